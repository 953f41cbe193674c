//! `lodlab view` (and `lodlab` alone): the front end of the viewer ([`crate::app::viewer`]).

use crate::app::cli::ViewArgs;
use crate::app::viewer;
use std::process::ExitCode;

/// `lodlab view` (and `lodlab` alone): the viewer.
pub fn command(a: ViewArgs, inputs: &crate::runtime::spec::BakeInputs) -> anyhow::Result<ExitCode> {
    let options = viewer::ViewOptions::from_args(a, inputs);
    super::first_run::first_run_note(
        options.spec.cache_dir.as_deref(),
        options.screenshot.is_some(),
    );
    viewer::run(options)
}

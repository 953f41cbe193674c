//! `lodlab view` (and `lodlab` alone): the front end of the viewer ([`crate::app::viewer`]).

use crate::app::cli::ViewArgs;
use crate::app::viewer;
use crate::scene::LodMethod;
use std::process::ExitCode;

/// `lodlab view` (and `lodlab` alone): the viewer.
pub fn command(a: ViewArgs) -> anyhow::Result<ExitCode> {
    let spec = a.scene.spec();
    super::first_run::first_run_note(spec.cache_dir.as_deref(), a.screenshot.is_some());
    viewer::run(viewer::ViewOptions {
        spec,
        width: a.size.0,
        height: a.size.1,
        samples: a.msaa,
        screenshot: a.screenshot,
        frames: a.frames,
        lod: a.lod.shot_lod(LodMethod::AS_IS),
    })
}

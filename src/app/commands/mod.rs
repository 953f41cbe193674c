//! The commands: each one's work, and its front end (`command`), which takes the command's
//! parsed arguments ([`crate::app::cli`]) and prints what it found. [`run`] sends the parsed
//! command line to its command.

pub mod bake;
pub mod bench;
pub mod doctor;
pub mod export;
pub mod first_run;
pub mod gen_assets;
pub mod record;
pub mod report;
pub mod shot;
pub mod soak;
pub mod study;
pub mod tree_report;
pub mod view;
pub mod web;

use crate::app::cli::{Cli, Command};
use std::process::ExitCode;

/// Runs the command `cli` names (the viewer where it names none), after setting what the
/// global options set for every command: the import's limits, extra clips, level budgets.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    crate::import::validate::set_limits(cli.import_limits());
    crate::import::set_extra_clips(cli.clips.clone());
    crate::runtime::levels::set_level_budgets(cli.levels.as_ref().and_then(|l| l.budgets()));
    match cli.command {
        Some(Command::Shot(a)) => shot::command(a),
        Some(Command::GenAssets(a)) => gen_assets::command(a),
        Some(Command::Bake(a)) => bake::command(a),
        Some(Command::Report(a)) => report::command(a),
        Some(Command::Export(a)) => export::command(a),
        Some(Command::Bench(a)) => bench::command(a),
        Some(Command::Record(a)) => record::command(a),
        Some(Command::Soak(a)) => soak::command(a),
        Some(Command::Study(a)) => study::command(a.command),
        Some(Command::View(a)) => view::command(a),
        Some(Command::Doctor(a)) => doctor::command(a),
        Some(Command::Web(a)) => web::command(a),
        None => view::command(cli.view),
    }
}

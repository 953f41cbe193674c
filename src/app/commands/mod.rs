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

/// Runs the command `cli` names (the viewer where it names none), handing it what the global
/// options say for every command: the import's limits and extra clips, the level budgets.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    let inputs = cli.bake_inputs();
    match cli.command {
        Some(Command::Shot(a)) => shot::command(a, &inputs),
        Some(Command::GenAssets(a)) => gen_assets::command(a, &inputs.import.limits),
        Some(Command::Bake(a)) => bake::command(a, &inputs),
        Some(Command::Report(a)) => report::command(a, &inputs),
        Some(Command::Export(a)) => export::command(a, &inputs),
        Some(Command::Bench(a)) => bench::command(a, &inputs),
        Some(Command::Record(a)) => record::command(a, &inputs),
        Some(Command::Soak(a)) => soak::command(a, &inputs),
        Some(Command::Study(a)) => study::command(a.command, &inputs),
        Some(Command::View(a)) => view::command(a, &inputs),
        Some(Command::Doctor(a)) => doctor::command(a, &inputs.import.limits),
        Some(Command::Web(a)) => web::command(a, &inputs),
        None => view::command(cli.view, &inputs),
    }
}

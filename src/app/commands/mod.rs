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
/// options say for every command: the import's limits and extra clips, the level budgets. A
/// global option the command does not read is refused, in one line: accepted and ignored, it
/// would let a user believe it did something (`doctor --clips FILE` read no file).
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    refuse_unread_options(&cli)?;
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

/// Which of the global options a command reads: the import limits (`--limit`,
/// `--allow-outside-files`), extra clips (`--clips`), level budgets (`--levels`). Its name
/// for the error where it does not read them.
fn global_options_read(command: &Option<Command>) -> (&'static str, [bool; 4]) {
    use crate::app::cli::StudyCommand;
    const ALL: [bool; 4] = [true; 4];
    match command {
        // Every command that loads models, and `web`, which refuses clips and budgets outside
        // its view words with its own tip.
        None
        | Some(Command::View(_))
        | Some(Command::Shot(_))
        | Some(Command::Bake(_))
        | Some(Command::Export(_))
        | Some(Command::Report(_))
        | Some(Command::Bench(_))
        | Some(Command::Record(_))
        | Some(Command::Soak(_))
        | Some(Command::Web(_)) => ("", ALL),
        Some(Command::Study(a)) => match &a.command {
            StudyCommand::Make { .. } | StudyCommand::Web { .. } | StudyCommand::Proxy { .. } => {
                ("", ALL)
            }
            StudyCommand::Run { .. } => ("study run", [false; 4]),
            StudyCommand::Analyze { .. } => ("study analyze", [false; 4]),
        },
        // It lists the limits in force; it reads no model.
        Some(Command::Doctor(_)) => ("doctor", [true, true, false, false]),
        // It reads back what it wrote under the limits; the files are its own.
        Some(Command::GenAssets(_)) => ("gen-assets", [true, false, false, false]),
    }
}

/// Fails, naming the option and the command, where the command line sets a global option the
/// command does not read (see [`global_options_read`]).
fn refuse_unread_options(cli: &Cli) -> anyhow::Result<()> {
    let (name, reads) = global_options_read(&cli.command);
    let set = [
        ("--limit", !cli.limits.is_empty()),
        ("--allow-outside-files", cli.allow_outside_files),
        ("--clips", !cli.clips.is_empty()),
        ("--levels", cli.levels.is_some()),
    ];
    for ((option, given), read) in set.into_iter().zip(reads) {
        if given && !read {
            anyhow::bail!(
                "{option}: `lodlab {name}` reads no models of yours, so {option} would change nothing"
            );
        }
    }
    Ok(())
}

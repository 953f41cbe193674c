//! `lodlab study make|run|proxy|analyze`: the front end of the user studies
//! ([`crate::app::study`]).

use crate::app::cli::StudyCommand;
use crate::app::study;
use std::process::ExitCode;

/// `lodlab study make|run|analyze`.
pub fn command(command: StudyCommand) -> anyhow::Result<ExitCode> {
    match command {
        StudyCommand::Make {
            plan,
            out,
            cache,
            msaa,
            shard,
            merge,
        } => {
            let options = study::MakeOptions {
                plan: plan.clone(),
                out: out.clone(),
                cache_dir: cache,
                samples: msaa,
                progress: true,
                merge,
            };
            if let Some(shard) = shard {
                let made = study::make::make_shard(&options, shard)?;
                println!(
                    "{}: shard {shard}: {} of the study's {} clips ({} rendered now); when \
                     every shard is done, merge them with: {}",
                    out.display(),
                    made.record.clips.len(),
                    made.total,
                    made.rendered,
                    crate::app::cli::command_line::shell_line(&[
                        "lodlab".into(),
                        "study".into(),
                        "make".into(),
                        "--plan".into(),
                        plan.to_string_lossy().into_owned(),
                        "--out".into(),
                        out.to_string_lossy().into_owned(),
                        "--merge".into(),
                    ])
                );
                return Ok(ExitCode::SUCCESS);
            }
            let m = study::make(&options)?;
            let trials = study::session::plan_session(&m, &m.participants[0]).len();
            println!(
                "{}: {} clips, {} conditions, {} participants with {trials} trials each",
                out.display(),
                m.clips.len(),
                m.conditions.len(),
                m.participants.len()
            );
            Ok(ExitCode::SUCCESS)
        }
        StudyCommand::Run {
            dir,
            participant,
            fullscreen,
            size,
            script,
        } => {
            let mut session = study::session::Session::open(&dir, &participant)?;
            if let Some(script) = script {
                let answers: Vec<u8> = script
                    .split(',')
                    .map(|a| match a.trim() {
                        "1" => Ok(1),
                        "2" => Ok(2),
                        other => Err(anyhow::anyhow!(
                            "--script: '{other}' is not an answer (1 or 2)"
                        )),
                    })
                    .collect::<anyhow::Result<_>>()?;
                let given = study::session::run_scripted(&mut session, &answers)?;
                println!(
                    "{participant}: {given} answer(s) recorded; {} of {} answered",
                    session.answered(),
                    session.total()
                );
                return Ok(ExitCode::SUCCESS);
            }
            study::window::run(
                session,
                study::window::RunOptions {
                    fullscreen,
                    width: size.0,
                    height: size.1,
                },
            )
        }
        StudyCommand::Proxy { dir, cache, msaa } => {
            let p = study::proxy::run(&study::proxy::ProxyOptions {
                dir,
                cache_dir: cache,
                samples: msaa,
                progress: true,
            })?;
            print!("{}", study::proxy::markdown(&p));
            Ok(ExitCode::SUCCESS)
        }
        StudyCommand::Analyze { dir } => {
            let a = study::analyze::run(&dir)?;
            print!("{}", study::analyze::markdown(&a));
            Ok(ExitCode::SUCCESS)
        }
    }
}

//! `lodlab study make|web|run|proxy|analyze`: the front end of the user studies
//! ([`crate::app::study`]).

use crate::app::cli::StudyCommand;
use crate::app::study;
use std::process::ExitCode;

/// `lodlab study make|web|run|proxy|analyze`.
pub fn command(
    command: StudyCommand,
    inputs: &crate::runtime::spec::BakeInputs,
) -> anyhow::Result<ExitCode> {
    match command {
        StudyCommand::Make {
            plan,
            plan_flag,
            out,
            cache,
            msaa,
            shard,
            merge,
        } => make(
            the_plan(plan, plan_flag)?,
            out,
            cache,
            msaa,
            shard,
            merge,
            inputs,
        ),
        StudyCommand::Web {
            plan,
            plan_flag,
            out,
            cache,
            msaa,
            post,
        } => web(the_plan(plan, plan_flag)?, out, cache, msaa, post, inputs),
        StudyCommand::Run {
            dir,
            participant,
            fullscreen,
            size,
            script,
        } => run(dir, participant, fullscreen, size, script),
        StudyCommand::Proxy { dir, cache, msaa } => {
            let p = study::proxy::run(&study::proxy::ProxyOptions {
                dir,
                rendering: study::make::ClipRendering {
                    cache_dir: cache,
                    samples: msaa,
                    progress: true,
                    inputs: inputs.clone(),
                },
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

/// The plan, given as `study make PLAN` or `study make --plan PLAN` (and `web` alike).
fn the_plan(
    plan: Option<std::path::PathBuf>,
    flag: Option<std::path::PathBuf>,
) -> anyhow::Result<std::path::PathBuf> {
    plan.or(flag)
        .ok_or_else(|| anyhow::anyhow!("a study needs its plan: lodlab study make PLAN --out DIR"))
}

/// `study make`: the whole study, or with `--shard` one job's share of its clips.
fn make(
    plan: std::path::PathBuf,
    out: std::path::PathBuf,
    cache: Option<std::path::PathBuf>,
    msaa: u32,
    shard: Option<crate::app::shard::Shard>,
    merge: bool,
    inputs: &crate::runtime::spec::BakeInputs,
) -> anyhow::Result<ExitCode> {
    let options = study::MakeOptions {
        plan: plan.clone(),
        out: out.clone(),
        rendering: study::make::ClipRendering {
            cache_dir: cache,
            samples: msaa,
            progress: true,
            inputs: inputs.clone(),
        },
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
            crate::app::cli::command_line::shell_line(&merge_command(
                &plan,
                &out,
                options.rendering.cache_dir.as_deref(),
                msaa
            ))
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

/// `study web`: the study made, and written as a site that runs online.
fn web(
    plan: std::path::PathBuf,
    out: std::path::PathBuf,
    cache: Option<std::path::PathBuf>,
    msaa: u32,
    post: Option<String>,
    inputs: &crate::runtime::spec::BakeInputs,
) -> anyhow::Result<ExitCode> {
    study::web::check_post_url(post.as_deref())?;
    let m = study::make(&study::MakeOptions {
        plan,
        out: out.clone(),
        rendering: study::make::ClipRendering {
            cache_dir: cache,
            samples: msaa,
            progress: true,
            inputs: inputs.clone(),
        },
        merge: false,
    })?;
    let (site, _) = study::web::write_site(&out, &m, post.as_deref())?;
    let first = m.participants.first().map_or("P01", String::as_str);
    println!(
        "{}: a static site for {} participants, holding only what their browsers fetch (the \
         page, its script and data, the clips); put that folder on any web server (or try it \
         with `python3 -m http.server -d {}`), never the study folder {} (it holds the \
         reference frames, the image metrics' verdict and the answers), and send each \
         participant their link, index.html?participant={first}; copy the answers-ID.csv \
         files they send back into {} and run `lodlab study analyze {}`",
        site.display(),
        m.participants.len(),
        site.display(),
        out.display(),
        out.display(),
        out.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// `study run`: a participant's session in a window, or answered by a script.
fn run(
    dir: std::path::PathBuf,
    participant: String,
    fullscreen: bool,
    size: (u32, u32),
    script: Option<String>,
) -> anyhow::Result<ExitCode> {
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

/// The `study make … --merge` that merges the shards a `--shard` run is one of: the same plan,
/// folder, cache and `--msaa`.
fn merge_command(
    plan: &std::path::Path,
    out: &std::path::Path,
    cache: Option<&std::path::Path>,
    msaa: u32,
) -> Vec<String> {
    let mut words: Vec<String> = ["lodlab", "study", "make", "--plan"]
        .into_iter()
        .map(String::from)
        .collect();
    words.push(plan.to_string_lossy().into_owned());
    words.push("--out".into());
    words.push(out.to_string_lossy().into_owned());
    if let Some(cache) = cache {
        words.push("--cache".into());
        words.push(cache.to_string_lossy().into_owned());
    }
    words.extend(["--msaa".into(), msaa.to_string(), "--merge".into()]);
    words
}

//! The `lodlab` command line: parses the arguments (`lodlab::app::cli`) and runs each command's
//! front end.

use clap::Parser;
use lodlab::app::cli::{
    BakeArgs, BenchArgs, Cli, Command, ExportArgs, GenAssetsArgs, RecordArgs, ReportArgs, ShotArgs,
    SoakArgs, StudyCommand, ViewArgs,
};
use lodlab::app::shot::{self, ShotOptions};
use lodlab::atomic::write as write_atomic;
use lodlab::runtime::headless::ShotLod;
use lodlab::scene::{LodMethod, SceneKind};
use std::process::ExitCode;

fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Some(Command::Shot(a)) => shot(a),
        Some(Command::GenAssets(a)) => gen_assets(a),
        Some(Command::Bake(a)) => bake(a),
        Some(Command::Report(a)) => report(a),
        Some(Command::Export(a)) => export(a),
        Some(Command::Bench(a)) => bench(a),
        Some(Command::Record(a)) => record(a),
        Some(Command::Soak(a)) => soak(a),
        Some(Command::Study(a)) => study(a.command),
        Some(Command::View(a)) => view(a),
        None => view(cli.view),
    }
}

/// `lodlab shot`: one PNG and a JSON line of figures.
fn shot(a: ShotArgs) -> anyhow::Result<ExitCode> {
    let report = shot::run(&ShotOptions {
        spec: a.scene.spec(),
        out: a.out,
        width: a.size.0,
        height: a.size.1,
        time: a.time,
        samples: a.msaa,
        camera: a.camera,
        timed_frames: a.frames,
        calibrate: a.calibrate,
        lod: a.lod.shot_lod(LodMethod::None),
    })?;
    println!("{}", serde_json::to_string(&report)?);
    Ok(ExitCode::SUCCESS)
}

/// `lodlab soak`: frames through every setting, memory read as they go; exit 1 on growth.
fn soak(a: SoakArgs) -> anyhow::Result<ExitCode> {
    let o = lodlab::app::soak::SoakOptions {
        vary: a.vary,
        spec: a.scene.spec(),
        frames: a.frames,
        phase_frames: a.phase_frames,
        every: a.every,
        width: a.size.0,
        height: a.size.1,
        samples: a.msaa,
        max_growth_mb: a.max_growth_mb as f64,
        csv: a.csv,
    };
    let r = lodlab::app::soak::run(&o)?;
    let growth = r.growth_mb.map_or(
        "not measured (fewer than two readings after the first cycle)".into(),
        |g| format!("{g:+.1} MB"),
    );
    let gpu = match r.gpu_steady {
        Some(true) => "the same at every reading after the first cycle",
        Some(false) => "NOT the same at every reading after the first cycle",
        None => "not compared (readings not aligned with the cycle, or no figures)",
    };
    println!(
        "lodlab soak: {} frames in {:.0} s; resident growth after the first cycle {growth}; GPU memory {gpu}",
        a.frames, r.seconds
    );
    if r.growth_mb.is_some_and(|g| g > o.max_growth_mb) || r.gpu_steady == Some(false) {
        eprintln!(
            "error: memory grew (limit {} MB resident, GPU figures must repeat)",
            o.max_growth_mb
        );
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

/// `lodlab gen-assets`: the built-in models as .glb files.
fn gen_assets(a: GenAssetsArgs) -> anyhow::Result<ExitCode> {
    let dir = a.out.unwrap_or_else(lodlab::assets::assets_dir);
    for w in lodlab::app::gen_assets::run(&dir, &a.only)? {
        println!("{}", serde_json::to_string(&w)?);
    }
    Ok(ExitCode::SUCCESS)
}

/// `lodlab bake`: levels of detail baked or fetched from the cache, as a table.
fn bake(a: BakeArgs) -> anyhow::Result<ExitCode> {
    if !(a.first_error.is_finite() && a.first_error > 0.0) {
        anyhow::bail!("--first-error must be a positive number of pixels");
    }
    let results = lodlab::app::bake::run(&lodlab::app::bake::BakeOptions {
        models: a.models.into_iter().chain(a.model_flags).collect(),
        methods: dedup(a.methods),
        tolerance_px: a.first_error,
        // `--triangles`, or the budgets `--levels triangles:…` gave every command.
        budgets: a.triangles.or_else(lodlab::runtime::levels::level_budgets),
        cache_dir: a.cache,
    })?;
    for warning in lodlab::app::bake::budget_warnings(&results) {
        eprintln!("warning: {warning}");
    }
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&lodlab::app::bake::summary(&results))?
        );
    } else {
        print!("{}", lodlab::app::bake::table(&results));
    }
    Ok(ExitCode::SUCCESS)
}

/// `lodlab export`: a character's levels as glTF files.
fn export(a: ExportArgs) -> anyhow::Result<ExitCode> {
    let Some(model) = a.model.or(a.model_flag) else {
        anyhow::bail!("export needs a model: lodlab export --model NAME|PATH --out DIR");
    };
    let exported = lodlab::app::export::run(&lodlab::app::export::ExportOptions {
        model,
        method: a.method,
        out: a.out,
        tolerance_px: a.tolerance,
        cache_dir: a.cache,
    })?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&exported)?);
    } else {
        print!("{}", lodlab::app::export::table(&exported));
    }
    Ok(ExitCode::SUCCESS)
}

/// `lodlab report`: a tree's billboard-cloud report or a character's error curves.
fn report(a: ReportArgs) -> anyhow::Result<ExitCode> {
    let Some(name) = a.model.or(a.model_flag) else {
        anyhow::bail!("report needs a model: lodlab report --model NAME|PATH --out DIR");
    };
    // A tree (a model whose foliage cuts leaves out with alpha) gets the billboard-cloud
    // report; a character the simplification report.
    let model = lodlab::import::load_model(&name)?;
    if lodlab::bake::foliage::billboard::foliage(&model).is_ok() {
        let r = lodlab::app::tree_report::run(&model, &a.out)?;
        let last = r.levels.last().map_or(0, |l| l.billboards);
        println!(
            "{}: {} leaves, {} levels down to {last} billboards in {:.2} s; wrote {}",
            r.model,
            r.leaves,
            r.levels.len(),
            r.chain_seconds,
            a.out.display()
        );
        return Ok(ExitCode::SUCCESS);
    }
    let report = lodlab::app::report::run(&lodlab::app::report::data::ReportOptions {
        model: name,
        out: a.out.clone(),
        baseline_meshopt: a.baseline.is_some(),
        progress: true,
    })?;
    let c = &report.comparison;
    let pct = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{:.0}%", x * 100.0));
    let floors: Vec<String> = report
        .methods
        .iter()
        .filter_map(|(m, r)| Some(format!("{m} {}", r.levels.last()?.triangles)))
        .collect();
    println!(
        "{}: AS <= rest-pose on {} of the curve ({} down to the coarsest level; {} within the \
         noise, {} at the median, where the same mesh reordered scores {}; AS/rest-pose {} at \
         the median), AS+IS <= AS on {} (its lighting at most {} AS's at equal influences); \
         coarsest levels {} of {} triangles; errors by {}; wrote {}",
        report.model,
        pct(c.as_le_rest_pose),
        pct(c.as_le_rest_pose_at_levels),
        pct(c.as_le_rest_pose_within_noise),
        c.noise
            .map_or("-".into(), |n| format!("±{:.1}%", n * 100.0)),
        pct(c.reordered_le_rest_pose),
        c.as_over_rest_pose
            .map_or("-".into(), |r| format!("{r:.2}")),
        pct(c.as_is_le_as),
        c.as_is_lighting_over_as
            .map_or("-".into(), |r| format!("{r:.2}x")),
        floors.join(", "),
        report.triangles,
        report.correspondence.describe(),
        a.out.display()
    );
    if let Some(still) = report.stillness() {
        println!("{}: {still}", report.model);
    }
    Ok(ExitCode::SUCCESS)
}

/// `lodlab bench`: frame times of the methods, as a Markdown table (and JSON).
fn bench(a: BenchArgs) -> anyhow::Result<ExitCode> {
    use lodlab::app::bench;
    bench::check_outputs(&[&a.json, &a.markdown])?;
    let report = bench::run(&bench::BenchOptions {
        spec: a.scene.spec(),
        methods: dedup(a.methods),
        policy: a.policy.policy(),
        foliage: a.foliage.view(),
        normal_maps: !a.no_normal_maps,
        width: a.size.0,
        height: a.size.1,
        samples: a.msaa,
        seconds: a.seconds,
        warmup: a.warmup,
        frames: a.frames.map(|f| f as usize),
        path: a.path,
        path_seconds: a.path_seconds,
        progress: true,
    })?;
    let table = bench::markdown(&report);
    print!("{table}");
    if let Some(p) = &a.json {
        write_atomic(p, serde_json::to_string_pretty(&report)?.as_bytes())?;
    }
    if let Some(p) = &a.markdown {
        write_atomic(p, table.as_bytes())?;
    }
    Ok(ExitCode::SUCCESS)
}

/// `lodlab record`: a study clip as MP4.
fn record(a: RecordArgs) -> anyhow::Result<ExitCode> {
    let report = lodlab::app::record::run(&lodlab::app::record::RecordOptions {
        spec: a.scene.spec_or(SceneKind::Study),
        lod: ShotLod {
            method: a.method,
            policy: a.policy.policy(),
            debug: a.debug_view,
            foliage: a.foliage.view(),
            ..Default::default()
        },
        width: a.size.0,
        height: a.size.1,
        samples: a.msaa,
        fps: a.fps,
        seconds: a.seconds,
        path: a.path,
        out: a.out,
        frames_dir: a.frames_dir,
        progress: true,
    })?;
    println!("{}", serde_json::to_string(&report)?);
    Ok(ExitCode::SUCCESS)
}

/// `lodlab study make|run|analyze`.
fn study(command: StudyCommand) -> anyhow::Result<ExitCode> {
    use lodlab::app::study;
    match command {
        StudyCommand::Make {
            plan,
            out,
            cache,
            msaa,
        } => {
            let m = study::make(&study::MakeOptions {
                plan,
                out: out.clone(),
                cache_dir: cache,
                samples: msaa,
                progress: true,
            })?;
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

/// `lodlab view` (and `lodlab` alone): the viewer.
fn view(a: ViewArgs) -> anyhow::Result<ExitCode> {
    lodlab::app::viewer::run(lodlab::app::viewer::ViewOptions {
        spec: a.scene.spec(),
        width: a.size.0,
        height: a.size.1,
        samples: a.msaa,
        screenshot: a.screenshot,
        frames: a.frames,
        lod: a.lod.shot_lod(LodMethod::AS_IS),
    })
}

fn main() -> ExitCode {
    quiet_device_select();
    // Diagnostics (`RUST_LOG=debug`: the bake and the cache's decisions) go to stderr beside
    // the user-facing lines, which stay plain `eprintln!`s.
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn"))
        .format_timestamp(None)
        .init();
    let cli = Cli::parse();
    lodlab::import::validate::set_limits(cli.import_limits());
    lodlab::import::set_extra_clips(cli.clips.clone());
    lodlab::runtime::levels::set_level_budgets(cli.levels.as_ref().and_then(|l| l.budgets()));
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            // One line: the whole context chain joined.
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}

/// Mesa's device-select Vulkan layer looks for a Wayland compositor whenever a Vulkan instance
/// is made, and where `XDG_RUNTIME_DIR` is unset or no folder (containers, ssh sessions)
/// libwayland prints "error: XDG_RUNTIME_DIR is invalid or not set in the environment." four
/// times: lines on stderr that read as lodlab's own errors, on every command. There is no
/// compositor to find there, so the layer is switched off (its `NODEVICE_SELECT`) unless the
/// user set it up or chose a device through it. What the layer does besides is put the boot
/// display's GPU first; on a headless machine with several, `WGPU_ADAPTER_NAME` or
/// `WGPU_POWER_PREF` choose (see `render::gpu`).
fn quiet_device_select() {
    let runtime_dir = std::env::var_os("XDG_RUNTIME_DIR");
    let no_compositor = runtime_dir.is_none_or(|d| !std::path::Path::new(&d).is_dir());
    let chosen = ["NODEVICE_SELECT", "MESA_VK_DEVICE_SELECT", "DRI_PRIME"]
        .iter()
        .any(|v| std::env::var_os(v).is_some());
    if no_compositor && !chosen {
        // SAFETY: the first statement of main, before any thread is started.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}

/// A list of choices in the order given, each once.
fn dedup<T: PartialEq>(list: Vec<T>) -> Vec<T> {
    let mut out = Vec::with_capacity(list.len());
    for x in list {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}

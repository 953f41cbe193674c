//! `lodlab bench`: frame times of several level-of-detail methods on one scene, headless, along
//! a fixed camera path, measured in one process.
//!
//! How it measures, and why:
//! - Every measured frame is a point of the camera path ([`CameraPath`]) at a path time fixed in
//!   advance, and shows what a viewer running at 60 Hz would show there: selection runs over
//!   the second before it at 60 steps, from a clean state. So the frames are the same on every
//!   machine and for every method, however slowly they render, and transitions are caught in
//!   the middle as a viewer sees them.
//! - Methods are measured interleaved in short blocks (A B C D A B C D …), so that a drift of the
//!   machine (another process, the clock, the temperature) spreads over all of them instead of
//!   favouring whichever ran first.
//! - Each frame is drawn twice: skinned as the method draws it, then the very same triangles
//!   by the trivial unskinned shader (the calibration). A method's efficiency is its triangles
//!   per second over the calibration's on the same triangles: 1 means skinning and shading
//!   cost nothing beyond raw triangle drawing. It is a ratio measured in one run, comparable
//!   across machines.
//! - The time of a frame is the GPU time of its render pass from timestamp queries where the
//!   adapter has them, otherwise the wall time from submit to completion.

use crate::app::cli::BenchArgs;
use crate::atomic::write as write_atomic;
use std::process::ExitCode;

use super::shot::histogram;
use crate::app::progress::Progress;
use crate::atomic::check_target;
use crate::bake::gpu_data::drawable::LevelKind;
use crate::measure::statistics::{medians, percentile};
use crate::render::CharacterShader;
use crate::render::timer::{FrameTimer, Pass, overdraw_median, pass_medians};
use crate::runtime::headless::{Headless, ShotLod};
use crate::runtime::spec::SceneSpec;
use crate::scene::camera_path::PathKind;
use crate::scene::foliage::FoliageView;
use crate::scene::{CameraPath, LodMethod, LodPolicy};
use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

mod coverage;
mod frame;
mod markdown;
use coverage::COVERAGE_VIEWS;
use frame::{Bench, Samples, path_time};
pub use markdown::markdown;

/// Frames per method when the budget allows fewer: below this a median means little.
pub const MIN_FRAMES: usize = 6;
/// Frames per method at most, however many --seconds would fit.
const MAX_FRAMES: usize = 3600;
/// At most this many frames of one method in a row.
const MAX_BLOCK: usize = 5;

/// The version of [`BenchReport`]'s JSON: bumped whenever a field changes meaning or goes.
/// 2: `schema_version`, `warmup_seconds`, `measured_seconds` and each method's `frame_ms`.
/// 3: `announced_seconds` is all that follows the warm-up (the coverage's other views and the
/// measuring), beside `rest_seconds`, what that took.
pub const BENCH_SCHEMA_VERSION: u32 = 3;

/// What `--json` writes.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BenchReport {
    /// [`BENCH_SCHEMA_VERSION`] of the writer (absent, so 0, before version 2).
    #[serde(default)]
    pub schema_version: u32,
    /// Wall seconds the warm-up took, and the measuring after it (every method and its
    /// calibration): what the run really cost, whatever `--seconds` asked.
    #[serde(default)]
    pub warmup_seconds: f64,
    #[serde(default)]
    pub measured_seconds: f64,
    /// Wall seconds of the fragment and level-kind coverage, between the warm-up and the
    /// measuring (0 with `--no-coverage`).
    #[serde(default)]
    pub coverage_seconds: f64,
    /// What the bench said, once warm, the rest would take: the coverage's views after its
    /// first (taken during the warm-up) and the measuring.
    #[serde(default)]
    pub announced_seconds: f64,
    /// What the rest took.
    #[serde(default)]
    pub rest_seconds: f64,
    pub adapter: String,
    pub driver: String,
    pub backend: String,
    pub size: [u32; 2],
    pub msaa: u32,
    pub scene: String,
    /// Instances in the scene (characters and trees), before culling.
    pub instances: usize,
    /// "gpu timestamps" or "wall clock".
    pub timing: String,
    pub frames_per_method: usize,
    pub path: PathKind,
    pub path_seconds: f32,
    pub transition: String,
    pub drive: String,
    pub tolerance_px: f32,
    /// Coarse levels were lit through their normal maps.
    #[serde(default)]
    pub normal_maps: bool,
    pub calibration: Calibration,
    pub methods: BTreeMap<String, MethodFigures>,
    /// The methods in the order they were given (`methods` is keyed by name).
    pub order: Vec<String>,
}

/// The machine's raw throughput: the trivial unskinned shader on the frames of the method that
/// draws the most triangles (full detail where `none` is measured).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Calibration {
    pub triangles_per_second: f64,
    pub method: String,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MethodFigures {
    pub median_ms: f64,
    pub p5_ms: f64,
    pub p95_ms: f64,
    /// 1000 / median_ms.
    pub fps: f64,
    /// Means per frame over the path.
    pub triangles: u64,
    pub vertices: u64,
    pub influences: u64,
    /// Triangles per second over the calibration's on the same triangles.
    pub efficiency: f64,
    /// Median frame time of the same triangles drawn by the trivial unskinned shader.
    pub calibration_ms: f64,
    /// Mean instances per level of detail, finest first.
    pub lod_histogram: Vec<u32>,
    /// Mean instances in a transition per frame.
    pub in_transition: f64,
    /// Median GPU milliseconds of each pass drawn (see [`Pass`]), by pass name; empty without
    /// timestamp queries.
    #[serde(default)]
    pub passes: BTreeMap<String, f64>,
    /// Median fragments shaded per pixel over all passes, where the adapter counts them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub overdraw: Option<f64>,
    /// Every frame's time, milliseconds, in the order measured (blocks of frames along the
    /// path, interleaved with the other methods').
    #[serde(default)]
    pub frame_ms: Vec<f64>,
    /// Median CPU milliseconds a frame takes to select every instance's level and to encode
    /// and upload the instances (wall time on the submitting thread).
    #[serde(default)]
    pub cpu_ms: f64,
    /// Each pass's fragments against the pixels it covers, by pass name, where the adapter
    /// counts fragments.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub fragments_by_pass: BTreeMap<String, PassFragments>,
    /// Mean instances per frame by what their level shows ([`LevelKind`]'s names), the kinds
    /// drawn only.
    #[serde(default)]
    pub instances_by_kind: BTreeMap<String, f64>,
    /// Each level kind's instances drawn alone (no other kind hiding them), medians over
    /// [`COVERAGE_VIEWS`] views: GPU ms of its pass and fragments per pixel of the view.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub cost_by_kind: BTreeMap<String, [f64; 2]>,
}

/// A pass's fragments over [`COVERAGE_VIEWS`] views along the path, taken together (see
/// [`over_views`]).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct PassFragments {
    /// Fragments shaded per pixel of the whole view.
    pub per_pixel: f64,
    /// Fragments shaded per pixel the pass covers, drawn alone: how many times over it shades
    /// its own pixels.
    pub per_covered_pixel: f64,
    /// The share of the view it covers.
    pub covered: f64,
}

/// Pass `i`'s fragments over the views that have it, taken together: fragments and covered
/// pixels summed over the views, so that per pixel covered is per pixel of the view over the
/// share covered. (Medians of each figure over the views did not agree with one another where
/// the views differed: a forest of 16 trees read 32 fragments a pixel over 30% of the view and
/// 70 per pixel covered.)
fn over_views(views: &[[Option<[f64; 3]>; Pass::COUNT]], i: usize) -> Option<PassFragments> {
    let present: Vec<[f64; 3]> = views.iter().filter_map(|v| v[i]).collect();
    if present.is_empty() {
        return None;
    }
    let n = present.len() as f64;
    // Each view holds fragments and covered pixels over the view's pixels, alike for all.
    let fragments: f64 = present.iter().map(|v| v[0]).sum();
    let covered: f64 = present.iter().map(|v| v[2]).sum();
    Some(PassFragments {
        per_pixel: fragments / n,
        per_covered_pixel: fragments / covered.max(f64::MIN_POSITIVE),
        covered: covered / n,
    })
}

pub fn run(o: &BenchArgs, inputs: &crate::runtime::spec::BakeInputs) -> Result<BenchReport> {
    // Measured in the order given, each once, interleaved.
    let order = crate::app::cli::values::dedup(o.methods.clone());
    let (policy, foliage, normal_maps) = (o.policy.policy(), o.foliage.view(), !o.no_normal_maps);
    let (width, height) = o.size;
    let spec = o.scene.spec(inputs);
    check_inputs(o, &order)?;
    let (mut bench, msaa) = set_up(o, &spec, &order, policy, foliage, normal_maps)?;
    let path = bench.path;

    // Warm-up: round after round of every method, at the path's points the measuring takes
    // first, until the time is up. Then the coverage's frames, a round of every method at
    // each of its views, and its first view drawn pass by pass (see [`coverage`]). The
    // rounds after the first (which pays for first uses) estimate what a round of the
    // measuring costs, and the coverage's first view what its others do: with both known it
    // says how long the rest will take, the coverage's other views and last the measuring,
    // which stops when its time is up, so it takes what it said.
    let warm = Instant::now();
    let coverage = !o.no_coverage;
    say_what_follows(o);
    let mut rounds = warm_up(&mut bench, &order, warm, o.warmup)?;
    let warmup_seconds = warm.elapsed().as_secs_f64();
    let mut samples: Vec<Samples> = order.iter().map(|_| Samples::default()).collect();
    let covering = Instant::now();
    let cover = match coverage {
        true => coverage::Coverage::frames(&mut bench, &order)?,
        false => None,
    };
    let coverage_left = match &cover {
        Some(c) => {
            let (seconds, count) = c.rounds();
            rounds = (rounds.0 + seconds, rounds.1 + count);
            c.first_view(&mut bench, &order, &mut samples)?
        }
        None => 0.0,
    };
    let round_seconds = rounds.0 / rounds.1.max(1) as f64;
    let plan = match o.frames {
        Some(f) => Plan::Frames(f as usize),
        None => Plan::Seconds(o.seconds as f64),
    };
    let (measuring_announced, measuring_line) = plan.announce(round_seconds, &order);
    let announced = coverage_left + measuring_announced;
    eprintln!(
        "lodlab: bench: about {announced:.0} s more: {}{measuring_line}",
        match &cover {
            Some(_) => format!(
                "the other {} coverage views a method, about {coverage_left:.0} s, then ",
                COVERAGE_VIEWS - 1
            ),
            None => String::new(),
        }
    );
    let rest = Instant::now();
    if let Some(c) = cover {
        c.other_views(&mut bench, &order, &mut samples)?;
    }
    let coverage_seconds = if coverage {
        covering.elapsed().as_secs_f64()
    } else {
        0.0
    };
    let bar = Progress::new(true, "bench", 1000);
    let measuring = Instant::now();
    measure(&mut bench, &order, plan, round_seconds, &mut samples, &bar)?;
    bar.finish();
    let measured_seconds = measuring.elapsed().as_secs_f64();
    let rest_seconds = rest.elapsed().as_secs_f64();
    let n = samples[0].skinned.len();

    let methods = method_figures(&samples, &order, n, width, height);
    let calibration = calibration(&order, &methods);
    let gpu = &bench.gpu;
    Ok(BenchReport {
        schema_version: BENCH_SCHEMA_VERSION,
        warmup_seconds,
        measured_seconds,
        coverage_seconds,
        announced_seconds: announced,
        rest_seconds,
        adapter: gpu.info.name.clone(),
        driver: format!("{} {}", gpu.info.driver, gpu.info.driver_info)
            .trim()
            .to_string(),
        backend: gpu.backend_name(),
        size: [width, height],
        msaa,
        scene: spec.scene.to_string(),
        instances: bench.world.crowd.agents.len(),
        timing: if bench.timer.is_some() {
            "gpu timestamps"
        } else {
            "wall clock"
        }
        .into(),
        frames_per_method: n,
        path: o.path,
        path_seconds: path.duration(),
        transition: policy.transition.name().into(),
        drive: policy.drive.name().into(),
        tolerance_px: policy.tolerance_px,
        normal_maps,
        calibration,
        methods,
        order: order.iter().map(|m| m.name().to_string()).collect(),
    })
}

/// The bench's first line once loaded: the warm-up, the coverage and the measuring, in order.
fn say_what_follows(o: &BenchArgs) {
    eprintln!(
        "lodlab: bench: warming up for {} s{}, then {}; how long it takes is said once warm",
        o.warmup,
        if !o.no_coverage {
            format!(
                ", then fragments and level kinds at {COVERAGE_VIEWS} views a method \
                 (--no-coverage leaves them out)"
            )
        } else {
            String::new()
        },
        match o.frames {
            Some(f) => format!("measuring {f} frames of each method"),
            None => format!("measuring for {} s", o.seconds),
        }
    );
}

/// Input checks, before anything is loaded: there is a method to measure, and the measuring
/// and warm-up times make sense.
fn check_inputs(o: &BenchArgs, order: &[LodMethod]) -> Result<()> {
    if order.is_empty() {
        bail!("no method to measure");
    }
    if !(o.seconds.is_finite() && o.seconds > 0.0 && o.warmup.is_finite() && o.warmup >= 0.0) {
        bail!("--seconds must be positive and --warmup not negative");
    }
    Ok(())
}

/// Set-up: loads the scene and shows it once by every method (so that every method's levels
/// are baked and on the GPU before any timing), then takes the scene apart into a [`Bench`]
/// along the camera path from the scene's home view. Returns it with the samples per pixel.
fn set_up(
    o: &BenchArgs,
    spec: &SceneSpec,
    order: &[LodMethod],
    policy: LodPolicy,
    foliage: FoliageView,
    normal_maps: bool,
) -> Result<(Bench, u32)> {
    let (width, height) = o.size;
    let mut scene = Headless::new(spec, width, height, o.msaa, &crate::measure::GpuMeasurer)?;
    for &method in order {
        scene.show(&ShotLod {
            method,
            policy,
            foliage,
            normal_maps,
            ..Default::default()
        })?;
    }
    let Headless {
        gpu,
        target,
        world,
        samples: msaa,
        ..
    } = scene;
    let home = world.camera;
    let path = CameraPath::new(o.path, &home, o.path_seconds);
    let timer = FrameTimer::new(&gpu);
    let bench = Bench {
        gpu,
        world,
        target,
        timer,
        path,
        fov_y: home.fov_y,
        size: [width, height],
    };
    Ok((bench, msaa))
}

/// How long the measuring runs: `--frames` of each method, or `--seconds` of them all (at
/// least [`MIN_FRAMES`] of each, at most [`MAX_FRAMES`]).
#[derive(Clone, Copy)]
enum Plan {
    Frames(usize),
    Seconds(f64),
}

impl Plan {
    /// The seconds the measuring will take, as said before it starts, and the line saying
    /// it; `round_seconds` is what one frame of every method costs.
    fn announce(self, round_seconds: f64, order: &[LodMethod]) -> (f64, String) {
        let methods = format!(
            "{} method{}",
            order.len(),
            if order.len() == 1 { "" } else { "s" }
        );
        match self {
            Plan::Frames(n) => {
                let t = n as f64 * round_seconds;
                (
                    t,
                    format!("measuring {n} frames of each of {methods}, about {t:.0} s"),
                )
            }
            Plan::Seconds(seconds) => {
                let fit = (seconds / round_seconds.max(1e-9)).floor() as usize;
                if fit >= MIN_FRAMES {
                    (
                        seconds,
                        format!(
                            "measuring {methods} for {seconds} s (about {} frames of each)",
                            fit.min(MAX_FRAMES)
                        ),
                    )
                } else {
                    let t = MIN_FRAMES as f64 * round_seconds;
                    (
                        t,
                        format!(
                            "measuring {MIN_FRAMES} frames of each of {methods}, about {t:.0} s: \
                             --seconds {seconds} fits {fit}, and a median needs {MIN_FRAMES}"
                        ),
                    )
                }
            }
        }
    }
}

/// Warm-up: rounds of every method, skinned then calibration, at the path's golden-ratio
/// points in turn (the frames a measuring by time takes first), until `warmup` seconds have
/// passed since `warm` (at least one round). Returns the wall seconds of the rounds after the
/// first where there are more (the first pays for first uses: buffers grown, caches filled),
/// selection, encoding and waiting included, and how many they are: with the coverage's
/// rounds, they size the measuring's blocks and what the bench announces.
fn warm_up(
    bench: &mut Bench,
    order: &[LodMethod],
    warm: Instant,
    warmup: f32,
) -> Result<(f64, usize)> {
    let path = bench.path;
    let mut k = 0;
    let mut first = 0.0;
    loop {
        for &m in order {
            bench.show(m, golden_time(&path, k));
            bench.time(CharacterShader::Skinned)?;
            bench.time(CharacterShader::Plain)?;
        }
        k += 1;
        if k == 1 {
            first = warm.elapsed().as_secs_f64();
        }
        if warm.elapsed().as_secs_f32() >= warmup {
            break;
        }
    }
    let all = warm.elapsed().as_secs_f64();
    Ok(match k {
        1 => (all, 1),
        _ => (all - first, k - 1),
    })
}

/// The measuring loop: frames of every method along the path, methods interleaved in blocks
/// (see the module's notes), each frame timed skinned and then by the calibration shader, with
/// its statistics summed into `samples` (in `order`), until `plan` is met. Frame `i` of every
/// method is the same point of the path ([`measured_time`]). A block is a quarter of the
/// frames expected (at most [`MAX_BLOCK`]), one frame once the time left is less than a
/// cycle of blocks, so that the time is kept to within half a frame of each method.
fn measure(
    bench: &mut Bench,
    order: &[LodMethod],
    plan: Plan,
    round_seconds: f64,
    samples: &mut [Samples],
    bar: &Progress,
) -> Result<()> {
    let path = bench.path;
    let expected = match plan {
        Plan::Frames(n) => n,
        Plan::Seconds(t) => ((t / round_seconds.max(1e-9)) as usize).clamp(MIN_FRAMES, MAX_FRAMES),
    };
    let start = Instant::now();
    let mut done = 0;
    loop {
        let elapsed = start.elapsed().as_secs_f64();
        let (left, fraction) = match plan {
            Plan::Frames(n) => (n - done, done as f32 / n as f32),
            Plan::Seconds(t) if done < MIN_FRAMES => {
                (MIN_FRAMES - done, (elapsed / t).min(0.99) as f32)
            }
            Plan::Seconds(t) if elapsed < t && done < MAX_FRAMES => {
                let per_frame = elapsed / done.max(1) as f64;
                // Rounded: the measuring ends within half a round of the time asked.
                let fits = ((t - elapsed) / per_frame.max(1e-9)).round() as usize;
                (fits.min(MAX_FRAMES - done), (elapsed / t) as f32)
            }
            Plan::Seconds(_) => (0, 1.0),
        };
        bar.set_fraction(fraction);
        if left == 0 {
            return Ok(());
        }
        let block = (expected / 4).clamp(1, MAX_BLOCK).min(left);
        for (s, &m) in samples.iter_mut().zip(order) {
            bar.set_stage(m.name());
            for i in done..done + block {
                let (stats, cpu_ms) = bench.show(m, measured_time(&path, i, plan));
                let (ms, passes) = bench.time(CharacterShader::Skinned)?;
                s.skinned.push(ms);
                s.cpu.push(cpu_ms);
                if let Some(p) = passes {
                    s.passes.push(p);
                }
                s.plain.push(bench.time(CharacterShader::Plain)?.0);
                s.triangles += stats.triangles;
                s.vertices += stats.vertices;
                s.influences += stats.influences;
                s.in_transition += stats.in_transition;
                for (sum, &c) in s.levels.iter_mut().zip(&stats.levels) {
                    *sum += c as u64;
                }
                for (sum, &c) in s.kinds.iter_mut().zip(&stats.kinds) {
                    *sum += c as u64;
                }
            }
        }
        done += block;
    }
}

/// The path time of measured frame `i`: with `--frames N`, N points evenly along the path;
/// with `--seconds`, where the count is not known in advance, the golden-ratio sequence,
/// whose every prefix is spread evenly along it (so the frames are the same points on every
/// machine, however many are measured).
fn measured_time(path: &CameraPath, i: usize, plan: Plan) -> f32 {
    match plan {
        Plan::Frames(n) => path_time(path, i, n),
        Plan::Seconds(_) => golden_time(path, i),
    }
}

/// Path time `i` of the golden-ratio sequence: every prefix spread evenly along the path.
fn golden_time(path: &CameraPath, i: usize) -> f32 {
    let phi = 0.618_033_988_749_895_f64;
    (path.duration() as f64 * ((i as f64 + 0.5) * phi).fract()) as f32
}

/// Each method's figures from its samples, keyed by name for the report.
fn method_figures(
    samples: &[Samples],
    order: &[LodMethod],
    n: usize,
    width: u32,
    height: u32,
) -> BTreeMap<String, MethodFigures> {
    let mut methods = BTreeMap::new();
    for (s, m) in samples.iter().zip(order) {
        methods.insert(m.name().to_string(), figures(s, n, width, height));
    }
    methods
}

/// The calibration: the trivial shader's throughput on the frames of the method that draws
/// the most triangles (of equals, the last in `order`, as `max_by_key` picks).
fn calibration(order: &[LodMethod], methods: &BTreeMap<String, MethodFigures>) -> Calibration {
    let (cal_method, cal) = order
        .iter()
        .map(|m| (m.name(), &methods[m.name()]))
        .max_by_key(|(_, f)| f.triangles)
        .expect("at least one method");
    Calibration {
        triangles_per_second: cal.triangles as f64 / (cal.calibration_ms * 1e-3).max(1e-9),
        method: cal_method.to_string(),
    }
}

fn figures(s: &Samples, n: usize, width: u32, height: u32) -> MethodFigures {
    let n = n.max(1) as u64;
    let median_ms = percentile(&s.skinned, 0.5);
    let calibration_ms = percentile(&s.plain, 0.5);
    let mean_levels: Vec<u32> = s
        .levels
        .iter()
        .map(|&c| (c as f64 / n as f64).round() as u32)
        .collect();
    MethodFigures {
        median_ms,
        p5_ms: percentile(&s.skinned, 0.05),
        p95_ms: percentile(&s.skinned, 0.95),
        fps: 1e3 / median_ms.max(1e-9),
        triangles: s.triangles / n,
        vertices: s.vertices / n,
        influences: s.influences / n,
        efficiency: calibration_ms / median_ms.max(1e-9),
        calibration_ms,
        lod_histogram: histogram(&mean_levels),
        in_transition: s.in_transition as f64 / n as f64,
        passes: pass_medians(&s.passes),
        overdraw: overdraw_median(&s.passes, width, height),
        frame_ms: s.skinned.clone(),
        cpu_ms: percentile(&s.cpu, 0.5),
        fragments_by_pass: Pass::ALL
            .into_iter()
            .filter_map(|p| {
                let figures = over_views(&s.coverage, p as usize)?;
                Some((p.name().to_string(), figures))
            })
            .collect(),
        instances_by_kind: LevelKind::ALL
            .into_iter()
            .filter(|&k| s.kinds[k as usize] > 0)
            .map(|k| (k.name().to_string(), s.kinds[k as usize] as f64 / n as f64))
            .collect(),
        cost_by_kind: LevelKind::ALL
            .into_iter()
            .filter_map(|k| Some((k.name().to_string(), medians(&s.kind_costs, k as usize)?)))
            .collect(),
    }
}

/// Checks that the output files can be written, before any measuring.
pub fn check_outputs(paths: &[&Option<PathBuf>]) -> Result<()> {
    for p in paths.iter().filter_map(|p| p.as_ref()) {
        check_target(p)?;
    }
    Ok(())
}

/// `lodlab bench`: frame times of the methods, as a Markdown table (and JSON).
pub fn command(
    a: BenchArgs,
    inputs: &crate::runtime::spec::BakeInputs,
) -> anyhow::Result<ExitCode> {
    check_outputs(&[&crate::app::json::json_file(&a.json).cloned(), &a.markdown])?;
    let report = run(&a, inputs)?;
    let table = markdown(&report);
    crate::app::json::emit(&a.json, &report, &table)?;
    if let Some(p) = &a.markdown {
        write_atomic(p, table.as_bytes())?;
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_interpolate_between_ranks() {
        let v = [5.0, 1.0, 3.0, 2.0, 4.0];
        assert_eq!(percentile(&v, 0.5), 3.0);
        assert_eq!(percentile(&v, 0.0), 1.0);
        assert_eq!(percentile(&v, 1.0), 5.0);
        assert!((percentile(&v, 0.05) - 1.2).abs() < 1e-12);
        assert!((percentile(&v, 0.95) - 4.8).abs() < 1e-12);
        assert_eq!(percentile(&[2.0, 4.0], 0.5), 3.0);
        assert_eq!(percentile(&[], 0.5), 0.0);
    }
}

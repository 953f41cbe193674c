//! `lodlab report`: the evidence about a model's levels of detail. Error curves for every
//! method (Merry et al. Figure 7), bake timings (Table 1), each level's error and how far its
//! silhouette strays where the renderer switches to it, and optionally meshoptimizer as the
//! baseline a user would otherwise reach for.
//!
//! Each level's lighting is measured too: its colour error against full detail lit by its own
//! vertex normals and through its normal map ([`crate::measure::shading_error`]).
//!
//! The curves measure through the texture where the model's texture coordinates are a
//! parameterisation, else by closest points ([`Probe::for_model`]); the report says which.
//! Each method is baked in several tie orders (`--orders`), its curve the median with a band
//! from the lowest to the highest, and methods are compared only where their bands separate
//! ([`bands`]).

use crate::app::cli::ReportArgs;
use std::process::ExitCode;

pub mod bands;
pub mod compare;
pub mod data;
pub mod markdown;
pub mod plot;

use crate::app::commands::report::compare::compare;
use crate::app::commands::report::data::{
    CURVE_POINTS, CurvePoint, LevelReport, MethodReport, Report, ReportOptions, SAMPLES,
    SHADING_PX, SILHOUETTE_POSES, SILHOUETTE_TOLERANCES, motion,
};
use crate::app::commands::report::markdown::{docs_row, timings_markdown};
use crate::app::commands::report::plot::plot;
use crate::app::progress::Progress;
use crate::bake::character::lod::{Replay, SharedBake, SkinnedLods, meshopt};
use crate::bake::character::lod_error::{MeshError, Probe};
use crate::bake::character::simplify::{Method, Sequence, pose_samples};
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use anyhow::Result;
use std::collections::BTreeMap;

/// Runs the whole report and writes `timings.md`, `report.json` and `error.png` into `out`,
/// `timings.md` first, so it is there even if drawing the plot fails.
pub fn run(opts: &ReportOptions) -> Result<Report> {
    let model = &opts.model;
    crate::atomic::make_folder(&opts.out)?;
    let base = AnimationSpaceMesh::from_skinned(&model.mesh, &model.skeleton).optimized_for_gpu();
    let probe = Probe::for_model(model, &base, SAMPLES);
    let lod_opts = crate::runtime::levels::runtime_options(model, opts.budgets.as_deref());
    let poses = pose_samples(model, SILHOUETTE_POSES);

    // The lighting needs a GPU adapter (lavapipe will do); without one the rest stands.
    let gpu = crate::render::Gpu::headless()
        .map_err(|e| log::warn!("no GPU adapter, so no shading errors: {e:#}"))
        .ok();
    let full = crate::bake::gpu_data::drawable::Drawable::new(model).map_err(anyhow::Error::msg)?;
    let mut methods = BTreeMap::new();
    let mut sequences: Vec<(Method, Sequence)> = Vec::new();
    let measuring = Measuring {
        probe: &probe,
        base: &base,
        poses: &poses,
        gpu: gpu.as_ref(),
        full: &full,
        lod_opts: &lod_opts,
        // The other tie orders' bakes share the preparation, `P` and each order's first
        // pricing.
        shared: SharedBake::default(),
    };
    for method in Method::PAPERS {
        let (report, sequence) = measure_method(opts, &measuring, method)?;
        methods.insert(method.name().to_string(), report);
        sequences.push((method, sequence));
    }
    if opts.baseline_meshopt {
        let triangles: Vec<u32> = methods["rest-pose"]
            .curve
            .iter()
            .map(|p| p.triangles)
            .collect();
        let mut meshopt = meshopt_curve(&probe, model, &base, &triangles, opts.orders);
        // Its levels as the viewer bakes them, with their silhouettes: where they end says
        // where meshoptimizer stops short of the floor.
        let (lods, _) = crate::bake::character::lod::cached::load_or_bake(
            &opts.cache,
            model,
            &opts.source,
            Method::Meshopt,
            &lod_opts,
            &|_| {},
        );
        meshopt.levels = level_reports(&lods, &poses);
        meshopt.shading = level_shading(&measuring, model, &lods)?;
        methods.insert("meshopt".into(), meshopt);
    }
    let comparison = compare(&methods);
    let moved = motion(model);
    let report = Report {
        model: model.name.clone(),
        vertices: model.mesh.vertex_count(),
        triangles: model.mesh.triangle_count(),
        bones: model.skeleton.bone_count(),
        methods,
        comparison,
        correspondence: probe.correspondence(),
        samples: SAMPLES,
        frames: probe.frame_count(),
        units: "scene units (metres)".into(),
        silhouette_tolerances: SILHOUETTE_TOLERANCES.to_vec(),
        motion: moved.0,
        motion_share: moved.1,
        orders: opts.orders,
    };
    crate::atomic::write(
        &opts.out.join("timings.md"),
        timings_markdown(&report, model, &sequences, &lod_opts).as_bytes(),
    )?;
    crate::atomic::write(
        &opts.out.join("report.json"),
        crate::app::json::pretty(&report)?.as_bytes(),
    )?;
    crate::atomic::write(&opts.out.join("docs-row.md"), docs_row(&report).as_bytes())?;
    plot(&report, &opts.out.join("error.png"))?;
    Ok(report)
}

/// What every method's measuring shares: the surface samples, the animation-space mesh, the
/// poses of the silhouettes, the adapter for the lighting (if any), full detail drawn, the
/// options the levels are cut by, what the bakes in other tie orders share.
struct Measuring<'a> {
    probe: &'a Probe<'a>,
    base: &'a AnimationSpaceMesh,
    poses: &'a [Vec<glam::Affine3A>],
    gpu: Option<&'a crate::render::Gpu>,
    full: &'a crate::bake::gpu_data::drawable::Drawable,
    lod_opts: &'a crate::bake::character::lod::LodOptions,
    shared: SharedBake<'a>,
}

/// One method's levels, from the cache or baked, and measured: its error curve, each level's
/// silhouettes and lighting. Returns its report and its collapse sequence.
fn measure_method(
    opts: &ReportOptions,
    m: &Measuring<'_>,
    method: Method,
) -> Result<(MethodReport, Sequence)> {
    let model = &opts.model;
    let bar = bar(opts.progress, &format!("{} {method}", model.name));
    let progress = |f: f32| bar.set_fraction(f);
    let (lods, origin) = crate::bake::character::lod::cached::load_or_bake(
        &opts.cache,
        model,
        &opts.source,
        method,
        m.lod_opts,
        &progress,
    );
    if let crate::bake::cache::Origin::Baked { warning: Some(w) } = &origin {
        log::warn!("{w}");
    }
    let read = origin == crate::bake::cache::Origin::Cache;
    let clock = std::time::Instant::now();
    // Order 0 is the levels' own sequence; the others are baked here.
    let mut others = Vec::new();
    for order in 1..opts.orders {
        bar.set_stage(&format!("tie order {} of {}", order + 1, opts.orders));
        others.push(m.shared.sequence(model, m.base, method, order, &progress));
    }
    bar.set_stage("measuring");
    let all: Vec<&Sequence> = std::iter::once(&lods.sequence).chain(&others).collect();
    let curve = measure_in_orders(m.probe, m.base, &all);
    let measured = clock.elapsed().as_secs_f64();
    bar.set_stage("silhouettes");
    let levels = level_reports(&lods, m.poses);
    bar.set_stage("lighting");
    let shading = level_shading(m, model, &lods)?;
    log::debug!(
        "{} by {method}: bake {:.2} s, error curve {measured:.2} s, silhouettes {:.2} s",
        model.name,
        lods.bake_seconds,
        clock.elapsed().as_secs_f64() - measured
    );
    // The bake, then what was measured of it, in the order they ran.
    let measured_all = clock.elapsed().as_secs_f64();
    bar.finish_with(if read {
        format!(
            "read from the cache (baked in {:.2} s when made), measured in {measured_all:.1} s",
            lods.bake_seconds
        )
    } else {
        format!(
            "baked in {:.2} s, measured in {measured_all:.1} s",
            lods.bake_seconds
        )
    });
    let report = MethodReport {
        bake_seconds: lods.bake_seconds,
        orders_seconds: measured,
        cache_hit_rate: match method {
            Method::InfluenceSimplification => lods.sequence.stats.cache_hit_rate(),
            _ => None,
        },
        band: bands::band_width(&curve),
        curve,
        levels,
        shading,
    };
    Ok((report, lods.sequence))
}

/// Each level's lighting against full detail's, [`SHADING_PX`] high (none without an adapter).
fn level_shading(
    m: &Measuring<'_>,
    model: &crate::model::Model,
    lods: &SkinnedLods,
) -> Result<Vec<crate::measure::shading_error::LevelShading>> {
    let Some(gpu) = m.gpu else {
        return Ok(Vec::new());
    };
    let which: Vec<usize> = (1..lods.levels.len()).collect();
    crate::measure::shading_error::shading_errors(
        gpu,
        model,
        m.full,
        &lods.levels,
        &which,
        SHADING_PX,
    )
}

/// Every level of `lods` with its silhouette distances at [`SILHOUETTE_TOLERANCES`] (full
/// detail, level 0, has none).
fn level_reports(lods: &SkinnedLods, poses: &[Vec<glam::Affine3A>]) -> Vec<LevelReport> {
    let full = &lods.levels[0].mesh;
    lods.levels
        .iter()
        .enumerate()
        .map(|(k, l)| {
            use crate::bake::character::silhouette::{MAX_SIDE, distance};
            let distances: Vec<_> = if k == 0 {
                Vec::new()
            } else {
                SILHOUETTE_TOLERANCES
                    .iter()
                    .map(|&tau| distance(full, &l.mesh, l.error, tau, poses, MAX_SIDE))
                    .collect()
            };
            LevelReport {
                triangles: l.triangles() as u32,
                influences: l.influences() as u32,
                error: l.error,
                bound: l.bound,
                silhouette_px: distances.iter().map(|d| d.px).collect(),
                silhouette_resolution_px: distances.iter().map(|d| d.pixel).collect(),
            }
        })
        .collect()
}

/// A method's progress: a bar in a terminal, a line every few seconds elsewhere.
fn bar(show: bool, prefix: &str) -> Progress {
    Progress::new(show, prefix, 1000)
}

/// The error along a sequence at [`CURVE_POINTS`] prefixes spaced evenly in log(influences).
pub fn measure_sequence(
    probe: &Probe,
    base: &AnimationSpaceMesh,
    seq: &Sequence,
) -> Vec<CurvePoint> {
    measure_in_orders(probe, base, &[seq])
}

/// The error along each of `sequences` (one method in several tie orders) at the same
/// [`CURVE_POINTS`] influence counts, spaced evenly in log(influences) from full detail to the
/// farthest any of them reaches, made into one curve with its band ([`bands::banded`]).
pub fn measure_in_orders(
    probe: &Probe,
    base: &AnimationSpaceMesh,
    sequences: &[&Sequence],
) -> Vec<CurvePoint> {
    let Some(first) = sequences.first() else {
        return Vec::new();
    };
    let full = first.influences_after(0).max(1) as f64;
    let last = sequences
        .iter()
        .map(|s| s.influences_after(s.steps.len()).max(1))
        .min()
        .unwrap_or(1) as f64;
    let targets: Vec<f64> = (0..CURVE_POINTS)
        .map(|j| {
            let t = j as f64 / (CURVE_POINTS - 1) as f64;
            (full.ln() + t * (last.ln() - full.ln())).exp()
        })
        .collect();
    let per_order: Vec<Vec<Option<CurvePoint>>> = sequences
        .iter()
        .map(|seq| measure_at(probe, base, seq, &targets))
        .collect();
    bands::banded(&per_order)
}

/// The error of `seq` at the first prefix at or below each of `targets` influences; `None`
/// for those it stops short of. One step can pass several targets: they share its point.
fn measure_at(
    probe: &Probe,
    base: &AnimationSpaceMesh,
    seq: &Sequence,
    targets: &[f64],
) -> Vec<Option<CurvePoint>> {
    let mut replay = Replay::new(base, seq);
    let mut taken: Option<(usize, CurvePoint)> = None;
    targets
        .iter()
        .map(|&target| {
            let from = taken.as_ref().map_or(0, |t| t.0);
            let p = (from..=seq.steps.len())
                .find(|&p| seq.influences_after(p) as f64 <= target + 0.5)?;
            if let Some((q, point)) = &taken
                && *q == p
            {
                return Some(point.clone());
            }
            replay.advance_to(seq, p);
            let tris: Vec<[u32; 3]> = replay.triangles().collect();
            let MeshError { rms, max } = probe.measure(&tris, |r| replay.influences_of(r));
            let point = CurvePoint {
                influences: seq.influences_after(p),
                triangles: seq.triangles_after(p),
                rms_error: rms,
                rms_low: rms,
                rms_high: rms,
                max_error: max,
                orders: 1,
            };
            taken = Some((p, point.clone()));
            Some(point)
        })
        .collect()
}

/// meshoptimizer's simplifier on the rest pose, to each triangle count, handed the mesh as its
/// levels are ([`meshopt::Input`]: seams welded, skin seams locked, normals of weight 0.5,
/// small parts pruned unless that passes the count). Its ties go by the order it is handed
/// vertices and triangles in, which this project does not control: its band is over `orders`
/// listings of the mesh (the first as the file has it, then shuffles of it).
fn meshopt_curve(
    probe: &Probe,
    model: &crate::model::Model,
    base: &AnimationSpaceMesh,
    triangles: &[u32],
    orders: u32,
) -> MethodReport {
    let input = meshopt::Input::new(model, base);
    let clock = std::time::Instant::now();
    let mut seconds = 0.0;
    let per_order: Vec<Vec<Option<CurvePoint>>> = (0..orders)
        .map(|order| {
            let listing = Listing::new(base, order);
            let (curve, s) = listing.meshopt_points(probe, base, &input, triangles);
            if order == 0 {
                seconds = s;
            }
            curve
        })
        .collect();
    let curve = bands::banded(&per_order);
    MethodReport {
        // One call to the coarsest target: what building a level costs.
        bake_seconds: seconds,
        orders_seconds: clock.elapsed().as_secs_f64(),
        cache_hit_rate: None,
        band: bands::band_width(&curve),
        curve,
        levels: Vec::new(),
        shading: Vec::new(),
    }
}

/// The full-detail mesh as meshoptimizer is handed it in one order: vertex `v` listed as
/// `new[v]`, and the triangles.
struct Listing {
    old: Vec<u32>,
    indices: Vec<u32>,
}

impl Listing {
    /// Order 0 as it is; order k the vertices and triangles shuffled by seed k, each
    /// triangle's corners rotated.
    fn new(base: &AnimationSpaceMesh, order: u32) -> Listing {
        let n = base.vertex_count() as u32;
        let mut old: Vec<u32> = (0..n).collect();
        let mut triangles: Vec<[u32; 3]> = base
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        if order > 0 {
            let mut rng = fastrand::Rng::with_seed(u64::from(order));
            rng.shuffle(&mut old);
            rng.shuffle(&mut triangles);
            for t in &mut triangles {
                t.rotate_left(rng.usize(0..3));
            }
        }
        let mut new = vec![0u32; n as usize];
        for (k, &v) in old.iter().enumerate() {
            new[v as usize] = k as u32;
        }
        let indices = triangles
            .iter()
            .flatten()
            .map(|&v| new[v as usize])
            .collect();
        Listing { old, indices }
    }

    /// meshoptimizer's levels at each of `triangles` in this listing, measured by `probe` in
    /// the original's numbering; and the seconds of the coarsest call. The points end where
    /// no level keeps the count (the floor rule of [`meshopt::Input::simplify`]).
    fn meshopt_points(
        &self,
        probe: &Probe,
        base: &AnimationSpaceMesh,
        input: &meshopt::Input,
        triangles: &[u32],
    ) -> (Vec<Option<CurvePoint>>, f64) {
        let input = input.listed(&self.old);
        let full = base.triangle_count() as u32;
        let mut seconds = 0.0;
        let mut curve = Vec::new();
        for &target in triangles {
            let start = std::time::Instant::now();
            let indices = if target >= full {
                Some(self.indices.clone())
            } else {
                input.simplify(&self.indices, target, f32::MAX)
            };
            seconds = start.elapsed().as_secs_f64();
            let Some(indices) = indices else {
                // Said once, of the file's own order.
                if self.old.iter().enumerate().all(|(k, &v)| k as u32 == v) {
                    eprintln!(
                        "note: meshopt keeps no level of {target} triangles (pruned or not); its \
                         curve ends there"
                    );
                }
                curve.push(None);
                break;
            };
            let tris: Vec<[u32; 3]> = indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]].map(|v| self.old[v as usize]))
                .collect();
            let mut used = vec![false; base.vertex_count()];
            tris.iter().flatten().for_each(|&v| used[v as usize] = true);
            let influences = (0..base.vertex_count())
                .filter(|&v| used[v])
                .map(|v| base.influences_of(v).len() as u32)
                .sum();
            let MeshError { rms, max } = probe.measure(&tris, |r| base.influences_of(r as usize));
            curve.push(Some(CurvePoint {
                influences,
                triangles: tris.len() as u32,
                rms_error: rms,
                rms_low: rms,
                rms_high: rms,
                max_error: max,
                orders: 1,
            }));
        }
        curve.resize(triangles.len(), None);
        (curve, seconds)
    }
}

/// `lodlab report`: a tree's billboard-cloud report or a character's error curves.
pub fn command(
    a: ReportArgs,
    inputs: &crate::runtime::spec::BakeInputs,
) -> anyhow::Result<ExitCode> {
    let Some(name) = a.model.or(a.model_flag) else {
        anyhow::bail!("report needs a model: lodlab report --model NAME|PATH --out DIR");
    };
    // A tree (`bake::foliage::classify`: cut-out foliage swaying in place) gets the
    // billboard-cloud report; a character, cut-out parts or not, the simplification report.
    let imported = crate::import::import(&name, &inputs.import)?;
    let model = imported.model;
    if crate::bake::foliage::billboard::is_tree(&model) {
        let size = a.size.map_or(
            crate::app::commands::tree_report::data::METRIC_SIZE,
            |(w, h)| [w, h],
        );
        let r = crate::app::commands::tree_report::run(&model, &a.out, size)?;
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
    if a.size.is_some() {
        anyhow::bail!(
            "{name}: a character; --size sets the picture size of a tree's colour metric, and a character's report renders none"
        );
    }
    let report = run(&data::ReportOptions {
        model,
        budgets: inputs.level_budgets.clone(),
        out: a.out.clone(),
        baseline_meshopt: a.baseline.is_some(),
        orders: a.orders,
        progress: true,
        cache: crate::bake::cache::LodCache::new(a.cache.clone()),
        source: imported.source_hash,
    })?;
    print!("{}", summary(&report, &a.out));
    Ok(ExitCode::SUCCESS)
}

/// What a character's report found, a line a finding: the methods compared where their bands
/// separate and where, the floors, the correspondence, stillness and where the files are.
fn summary(report: &Report, out: &std::path::Path) -> String {
    let c = &report.comparison;
    let pct = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{:.0}%", x * 100.0));
    let floors: Vec<String> = report
        .methods
        .iter()
        .filter_map(|(m, r)| Some(format!("{m} {}", r.levels.last()?.triangles)))
        .collect();
    let bands: Vec<String> = report
        .methods
        .iter()
        .filter_map(|(m, r)| Some(format!("{m} ±{:.0}%", r.band? * 50.0)))
        .collect();
    let mut s = format!(
        "{}: {} tie orders a method; median band {}\n",
        report.model,
        report.orders,
        bands.join(", ")
    );
    for (pair, sep) in &c.separations {
        let first = pair.split(' ').next().unwrap_or(pair);
        s += &format!(
            "  {pair}: bands apart on {} of the curve, {first} better on {} of that; by influences:\n",
            pct(Some(sep.better + sep.worse)),
            pct(sep.better_where_separate()),
        );
        s += &wrapped(&sep.runs(), "    ", 150);
    }
    s += &format!(
        "  AS better than rest-pose on {} of the points where they separate down to the \
         coarsest level; AS/rest-pose error at the median: {}\n",
        pct(c.as_le_rest_pose_at_levels),
        c.as_over_rest_pose
            .map_or("-".into(), |r| format!("{r:.2}"))
    );
    if let Some(line) = markdown::meshopt_floor(report) {
        s += &format!("  {line}\n");
    }
    s += &format!(
        "  AS+IS's lighting at most {} AS's at equal influences\n",
        c.as_is_lighting_over_as
            .map_or("-".into(), |r| format!("{r:.2}x"))
    );
    s += &format!(
        "  coarsest levels: {} of {} triangles; errors by {}\n",
        floors.join(", "),
        report.triangles,
        report.correspondence.describe()
    );
    if let Some(still) = report.stillness() {
        s += &format!("  {still}\n");
    }
    s += &format!("wrote {}\n", out.display());
    s
}

/// `text` broken after its commas into lines of at most `width` characters, each indented.
fn wrapped(text: &str, indent: &str, width: usize) -> String {
    let mut lines: Vec<String> = Vec::new();
    for piece in text.split_inclusive(", ") {
        match lines.last_mut() {
            Some(l) if l.chars().count() + piece.chars().count() <= width => l.push_str(piece),
            _ => lines.push(format!("{indent}{piece}")),
        }
    }
    lines
        .iter()
        .map(|l| format!("{}\n", l.trim_end()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::compare::{lighting_at, lighting_over};
    use super::*;
    use crate::app::plotting::log_label;

    #[test]
    fn log_axis_labels_keep_two_significant_digits() {
        let labels: Vec<String> = [0.00123, 0.05, 0.5, 1.0, 3.16, 40.0]
            .into_iter()
            .map(log_label)
            .collect();
        assert_eq!(labels, ["0.0012", "0.050", "0.50", "1.0", "3.2", "40"]);
    }
    /// A method's report of its levels' colour errors only, each level with as many
    /// influences as triangles.
    fn lit(levels: &[(u32, f32)]) -> MethodReport {
        let level = |&(triangles, _): &(u32, f32)| LevelReport {
            triangles,
            influences: triangles,
            error: 0.0,
            bound: 0.0,
            silhouette_px: Vec::new(),
            silhouette_resolution_px: Vec::new(),
        };
        let shading = |(k, &(triangles, e)): (usize, &(u32, f32))| {
            crate::measure::shading_error::LevelShading {
                level: k,
                triangles: triangles as usize,
                px: SHADING_PX,
                vertex_normals: e,
                normal_maps: e,
                mapped: false,
                worst_tile_vertex_normals: e,
                worst_tile_normal_maps: e,
                recoloured: 0.0,
            }
        };
        MethodReport {
            bake_seconds: 0.0,
            orders_seconds: 0.0,
            cache_hit_rate: None,
            band: None,
            curve: Vec::new(),
            levels: levels.iter().map(level).collect(),
            shading: levels.iter().enumerate().skip(1).map(shading).collect(),
        }
    }

    #[test]
    fn as_is_lighting_is_read_against_as_at_equal_influences() {
        // AS+IS's level 1 is coarser than AS's (fewer influences at one index): at its own
        // count AS's error, between its levels 1 and 2, is about its own.
        let as_ = lit(&[(1000, 0.0), (900, 0.002), (500, 0.010)]);
        let is = lit(&[(1000, 0.0), (600, 0.008), (400, 0.02)]);
        let at_600 = lighting_at(&as_, 600.0).unwrap();
        assert!(at_600 > 0.002 && at_600 < 0.010, "{at_600}");
        // Level 2 (400) is past AS's coarsest level: no reference, not counted.
        assert!(lighting_at(&as_, 400.0).is_none());
        let r = lighting_over(&is, &as_).unwrap();
        assert!((r - 0.008 / at_600).abs() < 1e-6, "{r}");
        // Errors too small to see compare to nothing.
        let faint_as = lit(&[(1000, 0.0), (900, 0.00001), (500, 0.0005)]);
        let faint_is = lit(&[(1000, 0.0), (600, 0.0008)]);
        assert!(lighting_over(&faint_is, &faint_as).is_none());
        // Where one of them shows, it counts.
        assert!(lighting_over(&is, &faint_as).unwrap() > 20.0);
    }
}

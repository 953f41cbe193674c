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

use crate::bake::character::lod::{LodOptions, Replay, SkinnedLods, bake_lods, progressive_mesh};
use crate::bake::character::lod_error::{Correspondence, MeshError, Probe};
use crate::bake::character::simplify::{Method, Sequence, SimplifyInput, pose_samples};
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use crate::import::load_model;
use crate::model::{Model, SkinnedMesh};
use anyhow::{Context, Result};
use indicatif::ProgressBar;
use plotters::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Points per curve, spaced evenly in log(influences) from full detail to the coarsest mesh.
pub const CURVE_POINTS: usize = 40;
/// Errors below this (in scene units) are rounding, not simplification: full detail.
const NEGLIGIBLE: f64 = 1e-9;
/// Surface samples the error is averaged over.
pub const SAMPLES: usize = 6000;
/// Tolerances in pixels at which every level's silhouette is compared with full detail.
pub const SILHOUETTE_TOLERANCES: [f32; 3] = [1.5, 4.0, 8.0];
/// Poses (spread over the clips) the silhouettes are compared in, each from
/// [`crate::bake::character::silhouette::VIEWS`].
const SILHOUETTE_POSES: usize = 3;

#[derive(Clone, Debug)]
pub struct ReportOptions {
    pub model: String,
    pub out: PathBuf,
    pub baseline_meshopt: bool,
    pub progress: bool,
}

#[derive(Clone, Debug, Serialize)]
pub struct CurvePoint {
    pub influences: u32,
    pub triangles: u32,
    pub rms_error: f64,
    pub max_error: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct MethodReport {
    /// Wall time of the whole bake: the simplification and cutting the levels.
    pub bake_seconds: f64,
    pub cache_hit_rate: Option<f64>,
    pub curve: Vec<CurvePoint>,
    /// The levels the viewer uses (empty for the meshopt baseline).
    pub levels: Vec<LevelReport>,
    /// Every level but full detail's colour error against full detail, lit by its vertex
    /// normals and through its normal map, [`SHADING_PX`] high (empty for the meshopt
    /// baseline, or where no GPU adapter could draw them).
    pub shading: Vec<crate::measure::shading_error::LevelShading>,
}

/// The character's height on screen, pixels, at which every level's lighting is compared with
/// full detail's: close enough for a level's shading to show.
pub const SHADING_PX: f32 = 400.0;

/// One level of detail as the viewer bakes it, and how its silhouette compares.
#[derive(Clone, Debug, Serialize)]
pub struct LevelReport {
    pub triangles: u32,
    pub influences: u32,
    /// The level's error (what the renderer projects), and the memoryless bound under it, in
    /// scene units.
    pub error: f32,
    pub bound: f32,
    /// The largest silhouette distance from full detail in pixels where the renderer switches
    /// to this level, at each of [`SILHOUETTE_TOLERANCES`].
    pub silhouette_px: Vec<f32>,
    /// How many of those pixels one drawn pixel spanned at each tolerance: 1 unless the
    /// drawing had to be capped at [`crate::bake::character::silhouette::MAX_SIDE`] pixels, as for a
    /// level whose error is tiny. A distance of about one drawn pixel is the measurement's
    /// resolution, not the level's.
    pub silhouette_resolution_px: Vec<f32>,
}

/// How the methods compare at equal influence counts (Merry et al.'s Figure 7 read at equal influences).
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// Fraction of the AS curve (where the rest-pose curve covers it) with AS ≤ rest-pose.
    pub as_le_rest_pose: Option<f64>,
    /// Fraction of the AS+IS curve (where the AS curve covers it) with AS+IS ≤ AS.
    pub as_is_le_as: Option<f64>,
    /// Fraction of the meshopt curve with meshopt ≤ rest-pose.
    pub meshopt_le_rest_pose: Option<f64>,
    /// What two equal methods score against each other: the fraction of the curve of
    /// rest-pose baked on the same mesh in another order ([`reordered`]) that lies at or
    /// under rest-pose's. Where steps of nearly equal cost abound, which comes first is
    /// decided by order and rounding, and the fraction strays far from 100% (or 50%) for
    /// that alone: read `as_le_rest_pose` against it.
    pub reordered_le_rest_pose: Option<f64>,
    /// The noise band: the median of |rest-pose reordered / rest-pose − 1| over its curve.
    pub noise: Option<f64>,
    /// Fraction of the AS curve no further above rest-pose than the reordered rest-pose strays
    /// from it there: AS ≤ rest-pose × (1 + band), the band the local one of [`local_band`]
    /// (the largest deviation of the nearest reordered points, at least `noise`).
    pub as_le_rest_pose_within_noise: Option<f64>,
    /// `as_le_rest_pose` over the part of the curve the viewer's levels span: down to the
    /// coarsest level of AS or rest-pose, not on to the end of the sequence.
    pub as_le_rest_pose_at_levels: Option<f64>,
    /// The median of AS / rest-pose over the AS curve: below 1 where AS is better on most
    /// of it, by how much.
    pub as_over_rest_pose: Option<f64>,
    /// The largest ratio, over AS+IS's levels, of a level's colour error (by vertex normals,
    /// through the renderer) to AS's at the same total influences ([`lighting_at`]), where
    /// either shows at least [`VISIBLE_COLOUR`]; `None` where nothing was drawn or no level
    /// reaches that. Levels of one index are cut at one error, and AS+IS's then hold fewer
    /// influences and triangles: equal cost compares the lighting, equal indices the budget.
    pub as_is_lighting_over_as: Option<f64>,
    /// The fewest total influences each method reaches.
    pub min_influences: BTreeMap<String, u32>,
}

#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub model: String,
    pub vertices: usize,
    pub triangles: usize,
    pub bones: usize,
    pub methods: BTreeMap<String, MethodReport>,
    pub comparison: Comparison,
    /// How the error was measured: which points correspond, over how many samples and frames.
    pub correspondence: Correspondence,
    pub samples: usize,
    pub frames: usize,
    pub units: String,
    /// The tolerances of every level's `silhouette_px`.
    pub silhouette_tolerances: Vec<f32>,
    /// How far the clips move the character: the farthest any vertex gets from its rest-pose
    /// place over the frames measured, scene units, and as a share of its height.
    pub motion: f64,
    pub motion_share: f64,
    /// Rest-pose's curve on the same mesh in another order ([`reordered`]): the noise
    /// reference of [`Comparison`], drawn in `error.png` beside the methods.
    pub reordered_rest_pose: Vec<CurvePoint>,
}

/// Clips that move no vertex further than this share of the height from the rest pose give
/// `P` the rest pose's own blocks: AS then measures what rest-pose does.
pub const STILL: f64 = 0.01;

impl Report {
    /// The line a report says about its clips where they barely move the character.
    pub fn stillness(&self) -> Option<String> {
        (self.motion_share < STILL).then(|| {
            format!(
                "its clips barely move it (no vertex more than {:.1} mm, {:.2}% of its height, \
                 from its rest pose): AS measures what rest-pose measures, and their curves \
                 differ only by the order of equal steps",
                self.motion * 1e3,
                self.motion_share * 100.0
            )
        })
    }
}

/// How far `model`'s clips take its vertices from the rest pose (see [`Report::motion`]).
fn motion(model: &Model) -> (f64, f64) {
    let skel = &model.skeleton;
    // The bind pose, where the rest-pose metric measures (`Σ Ĝ_i p_i = v̂`), in scene space.
    let rest: Vec<glam::Vec3> = model
        .mesh
        .positions
        .iter()
        .map(|&p| skel.root_transform.transform_point3(p))
        .collect();
    let mut far = 0.0f64;
    for g in crate::bake::character::lod_error::animation_frames(model) {
        let posed = crate::anim::linear_blend_skinning(&model.mesh, skel, &g);
        for (a, b) in rest.iter().zip(&posed) {
            far = far.max(a.distance(*b) as f64);
        }
    }
    let height = crate::bake::character::lod::model_height(model) as f64;
    (far, far / height.max(1e-9))
}

/// Runs the whole report and writes `timings.md`, `report.json` and `error.png` into `out`,
/// `timings.md` first, so it is there even if drawing the plot fails.
pub fn run(opts: &ReportOptions) -> Result<Report> {
    let model = load_model(&opts.model)?;
    crate::atomic::make_folder(&opts.out)?;
    let base = AnimationSpaceMesh::from_skinned(&model.mesh, &model.skeleton).optimized_for_gpu();
    let probe = Probe::for_model(&model, &base, SAMPLES);
    let lod_opts = crate::runtime::levels::runtime_options(&model);
    let poses = pose_samples(&model, SILHOUETTE_POSES);

    // The lighting needs a GPU adapter (lavapipe will do); without one the rest stands.
    let gpu = crate::render::Gpu::headless()
        .map_err(|e| log::warn!("no GPU adapter, so no shading errors: {e:#}"))
        .ok();
    let full =
        crate::bake::gpu_data::drawable::CharacterBake::new(&model).map_err(anyhow::Error::msg)?;
    let mut methods = BTreeMap::new();
    let mut sequences: Vec<(Method, Sequence)> = Vec::new();
    for method in Method::ALL {
        let bar = bar(opts.progress, &format!("{} {method}", model.name));
        let progress = |f: f32| bar.set_position((f.clamp(0.0, 1.0) * 1000.0) as u64);
        let lods = bake_lods(&model, method, &lod_opts, &progress);
        bar.set_message("measuring");
        let clock = std::time::Instant::now();
        let curve = measure_sequence(&probe, &base, &lods.sequence);
        let measured = clock.elapsed().as_secs_f64();
        bar.set_message("silhouettes");
        let levels = level_reports(&lods, &poses);
        bar.set_message("lighting");
        let shading = match &gpu {
            Some(gpu) => {
                let which: Vec<usize> = (1..lods.levels.len()).collect();
                crate::measure::shading_error::shading_errors(
                    gpu,
                    &model,
                    &full,
                    &lods.levels,
                    &which,
                    SHADING_PX,
                )?
            }
            None => Vec::new(),
        };
        log::debug!(
            "{} by {method}: bake {:.2} s, error curve {measured:.2} s, silhouettes {:.2} s",
            model.name,
            lods.bake_seconds,
            clock.elapsed().as_secs_f64() - measured
        );
        bar.finish_with_message(format!("{:.2} s", lods.bake_seconds));
        methods.insert(
            method.name().to_string(),
            MethodReport {
                bake_seconds: lods.bake_seconds,
                cache_hit_rate: match method {
                    Method::InfluenceSimplification => lods.sequence.stats.cache_hit_rate(),
                    _ => None,
                },
                curve,
                levels,
                shading,
            },
        );
        sequences.push((method, lods.sequence));
    }
    if opts.baseline_meshopt {
        let triangles: Vec<u32> = methods["rest-pose"]
            .curve
            .iter()
            .map(|p| p.triangles)
            .collect();
        let rest_bones = SimplifyInput::rest_bones(&model.skeleton);
        methods.insert(
            "meshopt".into(),
            meshopt_curve(&probe, &base, &rest_bones, &triangles),
        );
    }

    // Rest-pose once more on the same mesh in another order: how far two equal methods'
    // curves stray apart, what the comparison of two methods is read against.
    let twin = reordered_rest_pose(&model);
    let comparison = compare(&methods, &twin);
    let moved = motion(&model);
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
        reordered_rest_pose: twin.curve,
    };
    crate::atomic::write(
        &opts.out.join("timings.md"),
        timings_markdown(&report, &model, &sequences, &lod_opts).as_bytes(),
    )?;
    crate::atomic::write(
        &opts.out.join("report.json"),
        serde_json::to_string_pretty(&report)?.as_bytes(),
    )?;
    plot(&report, &opts.out.join("error.png"))?;
    Ok(report)
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

fn bar(show: bool, prefix: &str) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(1000);
    bar.set_style(super::bake::bar_style());
    bar.set_prefix(prefix.to_string());
    bar
}

/// The error along a sequence at [`CURVE_POINTS`] prefixes spaced evenly in log(influences).
pub fn measure_sequence(
    probe: &Probe,
    base: &AnimationSpaceMesh,
    seq: &Sequence,
) -> Vec<CurvePoint> {
    let first = seq.influences_after(0).max(1) as f64;
    let last = seq.influences_after(seq.steps.len()).max(1) as f64;
    let mut prefixes: Vec<usize> = (0..CURVE_POINTS)
        .map(|j| {
            let t = j as f64 / (CURVE_POINTS - 1) as f64;
            let target = (first.ln() + t * (last.ln() - first.ln())).exp();
            // The first prefix at or below the target influence count.
            (0..=seq.steps.len())
                .find(|&p| seq.influences_after(p) as f64 <= target + 0.5)
                .unwrap_or(seq.steps.len())
        })
        .collect();
    prefixes.dedup();
    let mut replay = Replay::new(base, seq);
    prefixes
        .into_iter()
        .map(|p| {
            replay.advance_to(seq, p);
            let tris: Vec<[u32; 3]> = replay.triangles().collect();
            let MeshError { rms, max } = probe.measure(&tris, |r| replay.influences_of(r));
            CurvePoint {
                influences: seq.influences_after(p),
                triangles: seq.triangles_after(p),
                rms_error: rms,
                max_error: max,
            }
        })
        .collect()
}

/// meshoptimizer's simplifier on the rest pose, to each triangle count, set up as gltfpack
/// sets it up for a skinned mesh (its `simplifyMesh`): normals as attributes of weight 0.5,
/// texture seams kept by meshoptimizer's own topology, small parts pruned, triangles kept
/// regular.
fn meshopt_curve(
    probe: &Probe,
    base: &AnimationSpaceMesh,
    rest_bones: &[glam::Affine3A],
    triangles: &[u32],
) -> MethodReport {
    let positions: Vec<[f32; 3]> = base
        .rest_positions(rest_bones)
        .iter()
        .map(|p| p.to_array())
        .collect();
    let normals: Vec<f32> = (0..base.vertex_count())
        .flat_map(|v| {
            let n: glam::Vec3 = base
                .influences_of(v)
                .iter()
                .map(|i| rest_bones[i.bone as usize].matrix3 * i.n)
                .sum();
            n.normalize_or_zero().to_array()
        })
        .collect();
    let locks = vec![false; base.vertex_count()];
    let adapter = meshopt::VertexDataAdapter::new(bytemuck::cast_slice(&positions), 12, 0)
        .expect("tightly packed positions");
    let options = meshopt::SimplifyOptions::Prune | meshopt::SimplifyOptions::Regularize;
    let mut curve = Vec::new();
    let mut seconds = 0.0;
    let full = base.triangle_count() as u32;
    for &target in triangles {
        let start = std::time::Instant::now();
        let indices = if target >= full {
            base.indices.clone()
        } else {
            meshopt::simplify_with_attributes_and_locks(
                &base.indices,
                &adapter,
                &normals,
                &[0.5; 3],
                12,
                &locks,
                target as usize * 3,
                f32::MAX,
                options,
                None,
            )
        };
        seconds = start.elapsed().as_secs_f64();
        let tris: Vec<[u32; 3]> = indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        if tris.is_empty() {
            // Component pruning removed every part: nothing is left to measure, and no
            // smaller target keeps anything either.
            eprintln!(
                "note: meshopt keeps no triangle at a target of {target}; its curve ends there"
            );
            break;
        }
        let mut used = vec![false; base.vertex_count()];
        tris.iter().flatten().for_each(|&v| used[v as usize] = true);
        let influences = (0..base.vertex_count())
            .filter(|&v| used[v])
            .map(|v| base.influences_of(v).len() as u32)
            .sum();
        let MeshError { rms, max } = probe.measure(&tris, |r| base.influences_of(r as usize));
        curve.push(CurvePoint {
            influences,
            triangles: tris.len() as u32,
            rms_error: rms,
            max_error: max,
        });
    }
    MethodReport {
        // One call to the coarsest target: what building a level costs.
        bake_seconds: seconds,
        cache_hit_rate: None,
        curve,
        levels: Vec::new(),
        shading: Vec::new(),
    }
}

/// `y` of a curve at `x`, interpolated linearly in log–log; `None` outside its range.
fn interpolate(curve: &[(f64, f64)], x: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = curve.iter().copied().filter(|p| p.1 > NEGLIGIBLE).collect();
    between(pts, x, |a, b, t| (a.ln() + t * (b.ln() - a.ln())).exp())
}

/// `y` at `x` from the two points of `pts` either side of it, `blend(y_a, y_b, t)` with `t`
/// where `x` lies between their `x` in log scale; the point's own `y` where `x` is one; `None`
/// outside their range.
fn between(mut pts: Vec<(f64, f64)>, x: f64, blend: impl Fn(f64, f64, f64) -> f64) -> Option<f64> {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let i = pts.partition_point(|p| p.0 < x);
    if i < pts.len() && pts[i].0 == x {
        return Some(pts[i].1);
    }
    if i == 0 || i == pts.len() {
        return None;
    }
    let (a, b) = (pts[i - 1], pts[i]);
    let t = (x.ln() - a.0.ln()) / (b.0.ln() - a.0.ln());
    Some(blend(a.1, b.1, t))
}

fn points(r: &MethodReport) -> Vec<(f64, f64)> {
    r.curve
        .iter()
        .map(|p| (p.influences as f64, p.rms_error))
        .collect()
}

/// `(influences, a / b)` at each of `a`'s points with error within `b`'s range.
fn ratios_at(a: &MethodReport, b: &MethodReport) -> Vec<(f64, f64)> {
    let reference = points(b);
    a.curve
        .iter()
        .filter(|p| p.rms_error > NEGLIGIBLE)
        .filter_map(|p| {
            let x = p.influences as f64;
            Some((x, p.rms_error / interpolate(&reference, x)?))
        })
        .collect()
}

/// `a / b` at each of `a`'s points with error within `b`'s range.
fn ratios(a: &MethodReport, b: &MethodReport) -> Vec<f64> {
    ratios_at(a, b).into_iter().map(|(_, r)| r).collect()
}

/// Fraction of `a`'s points (with error, within `b`'s range) where `a ≤ b × (1 + slack)`,
/// `slack` given at the point's influence count.
fn fraction_below(a: &MethodReport, b: &MethodReport, slack: impl Fn(f64) -> f64) -> Option<f64> {
    let r = ratios_at(a, b);
    let below = r
        .iter()
        .filter(|&&(x, ratio)| ratio <= (1.0 + slack(x)) * (1.0 + 1e-9))
        .count();
    (!r.is_empty()).then(|| below as f64 / r.len() as f64)
}

/// Reordered points either side of a point that its local noise band looks at.
const BAND_NEIGHBOURS: usize = 1;

/// The noise band at `x` influences: the largest |reordered / rest-pose − 1| at the reordered
/// point nearest `x` in log(influences) and at [`BAND_NEIGHBOURS`] points either side of it,
/// and no less than the median band. The noise is not even along a curve: where steps of
/// equal cost are many (chart and material borders at the coarse end), equal methods part by
/// half and more, so one band for the whole curve would call that a method's loss.
/// `sorted`: `(influences, deviation)` in order of influences.
fn local_band(sorted: &[(f64, f64)], median: f64, x: f64) -> f64 {
    let distance = |d: &(f64, f64)| (d.0.ln() - x.ln()).abs();
    let Some(nearest) =
        (0..sorted.len()).min_by(|&i, &j| distance(&sorted[i]).total_cmp(&distance(&sorted[j])))
    else {
        return median;
    };
    let from = nearest.saturating_sub(BAND_NEIGHBOURS);
    let to = (nearest + BAND_NEIGHBOURS + 1).min(sorted.len());
    sorted[from..to].iter().map(|d| d.1).fold(median, f64::max)
}

/// Colour errors (0 to 1) below this are invisible: a quarter of one 8-bit step over the
/// figure. Ratios of two such errors say nothing.
pub const VISIBLE_COLOUR: f64 = 1e-3;

/// The total influences of the level a lighting row measures.
fn influences_of(m: &MethodReport, s: &crate::measure::shading_error::LevelShading) -> Option<f64> {
    Some(m.levels.get(s.level)?.influences as f64)
}

/// `m`'s colour error by vertex normals at `influences` in all, interpolated between its
/// levels (linearly in the error, in log(influences)), full detail counting as exact; `None`
/// outside the levels' range or where no lighting was measured. Influences are the paper's
/// measure of a level's cost (Merry et al. §5, Figure 7): an AS+IS level that drops
/// influences and keeps every triangle is compared with the AS level as cheap as it.
fn lighting_at(m: &MethodReport, influences: f64) -> Option<f64> {
    let full = m.levels.first()?.influences as f64;
    let pts: Vec<(f64, f64)> = std::iter::once((full, 0.0))
        .chain(
            m.shading
                .iter()
                .filter_map(|s| Some((influences_of(m, s)?, s.vertex_normals as f64))),
        )
        .collect();
    if pts.len() < 2 {
        return None;
    }
    between(pts, influences, |a, b, t| a + t * (b - a))
}

/// See [`Comparison::as_is_lighting_over_as`].
fn lighting_over(is: &MethodReport, as_: &MethodReport) -> Option<f64> {
    is.shading
        .iter()
        .filter_map(|s| {
            let own = s.vertex_normals as f64;
            let reference = lighting_at(as_, influences_of(is, s)?)?;
            (own.max(reference) >= VISIBLE_COLOUR).then(|| own / reference.max(1e-6))
        })
        .reduce(f64::max)
}

/// `a`'s curve down to the coarsest level `a` or `b` has: where the viewer shows levels. What
/// lies beyond is the extreme simplification that no level reaches (Merry et al. find AS worse
/// than rest-pose there).
fn down_to_levels(a: &MethodReport, b: &MethodReport) -> MethodReport {
    let floor = |m: &MethodReport| m.levels.last().map_or(0, |l| l.influences);
    let lowest = floor(a).max(floor(b));
    MethodReport {
        curve: a
            .curve
            .iter()
            .filter(|p| p.influences >= lowest)
            .cloned()
            .collect(),
        levels: Vec::new(),
        shading: Vec::new(),
        ..*a
    }
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    (!v.is_empty()).then(|| v[v.len() / 2])
}

/// `model` with its vertices in reverse order and each triangle's corners rotated: the same
/// surface, the same skin, so a method baked on it differs from the original only where
/// steps of equal cost are taken in another order.
pub fn reordered(model: &Model) -> Model {
    let src = &model.mesh;
    let n = src.vertex_count() as u32;
    let mut mesh = SkinnedMesh::empty();
    for v in (0..n as usize).rev() {
        mesh.copy_vertex_from(src, v);
    }
    mesh.indices = src
        .indices
        .chunks_exact(3)
        .rev()
        .flat_map(|t| [t[1], t[2], t[0]])
        .map(|v| n - 1 - v)
        .collect();
    Model {
        mesh,
        ..model.clone()
    }
}

/// Rest-pose's error curve on [`reordered`] `model`, for the noise band.
fn reordered_rest_pose(model: &Model) -> MethodReport {
    let twin = reordered(model);
    let (base, sequence, seconds) = progressive_mesh(&twin, Method::RestPose, &|_| {});
    let probe = Probe::for_model(&twin, &base, SAMPLES);
    MethodReport {
        bake_seconds: seconds,
        cache_hit_rate: None,
        curve: measure_sequence(&probe, &base, &sequence),
        levels: Vec::new(),
        shading: Vec::new(),
    }
}

fn compare(methods: &BTreeMap<String, MethodReport>, twin: &MethodReport) -> Comparison {
    let get = |n: &str| methods.get(n);
    let pair = |a: &str, b: &str| match (get(a), get(b)) {
        (Some(a), Some(b)) => fraction_below(a, b, |_| 0.0),
        _ => None,
    };
    let rest = get("rest-pose");
    // |reordered / rest-pose − 1| along the curve, in order of influences.
    let deviations: Vec<(f64, f64)> = rest.map_or(Vec::new(), |r| {
        let mut d: Vec<(f64, f64)> = ratios_at(twin, r)
            .into_iter()
            .map(|(x, q)| (x, (q - 1.0).abs()))
            .collect();
        d.sort_by(|a, b| a.0.total_cmp(&b.0));
        d
    });
    let noise = median(deviations.iter().map(|d| d.1).collect());
    let as_rest = get("as").zip(rest);
    Comparison {
        as_le_rest_pose: pair("as", "rest-pose"),
        as_is_le_as: pair("as+is", "as"),
        meshopt_le_rest_pose: pair("meshopt", "rest-pose"),
        reordered_le_rest_pose: rest.and_then(|r| fraction_below(twin, r, |_| 0.0)),
        noise,
        as_le_rest_pose_within_noise: as_rest
            .zip(noise)
            .and_then(|((a, r), n)| fraction_below(a, r, |x| local_band(&deviations, n, x))),
        as_over_rest_pose: as_rest.and_then(|(a, r)| median(ratios(a, r))),
        as_is_lighting_over_as: get("as+is")
            .zip(get("as"))
            .and_then(|(i, a)| lighting_over(i, a)),
        as_le_rest_pose_at_levels: as_rest
            .and_then(|(a, r)| fraction_below(&down_to_levels(a, r), r, |_| 0.0)),
        min_influences: methods
            .iter()
            .map(|(k, v)| {
                let min = v.curve.iter().map(|p| p.influences).min().unwrap_or(0);
                (k.clone(), min)
            })
            .collect(),
    }
}

/// A named, coloured line of (x, y) points.
type Series = (&'static str, RGBColor, Vec<(f64, f64)>);

/// Figure 7 redrawn: each method's RMS error divided by rest-pose's at the same influence
/// count, against total influences, both on log scales.
pub fn plot(report: &Report, path: &Path) -> Result<()> {
    register_font();
    let (w, h) = (1000u32, 640u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    let rest = points(&report.methods["rest-pose"]);
    // The noise reference first, under the methods: where two equal methods' curves part,
    // no difference is a method's.
    let noise = (
        "rest-pose, reordered",
        RGBColor(175, 175, 175),
        &report.reordered_rest_pose,
    );
    let series: Vec<Series> = std::iter::once(noise)
        .chain(
            [
                ("rest-pose", RGBColor(40, 40, 40)),
                ("as", RGBColor(30, 100, 220)),
                ("as+is", RGBColor(220, 50, 40)),
                ("meshopt", RGBColor(40, 160, 70)),
            ]
            .into_iter()
            .filter_map(|(name, colour)| Some((name, colour, &report.methods.get(name)?.curve))),
        )
        .map(|(name, colour, curve)| {
            let pts: Vec<(f64, f64)> = curve
                .iter()
                .filter(|p| p.rms_error > NEGLIGIBLE)
                .filter_map(|p| {
                    let r = interpolate(&rest, p.influences as f64)?;
                    Some((p.influences as f64, p.rms_error / r))
                })
                .collect();
            (name, colour, pts)
        })
        .collect();
    // Both axes are drawn as log10 of the value on a linear axis, labelled with the value:
    // plotters' own log axes leave a narrow range (a few hundred influences) unlabelled.
    let series: Vec<Series> = series
        .into_iter()
        .map(|(n, c, pts)| {
            (
                n,
                c,
                pts.iter().map(|&(x, y)| (x.log10(), y.log10())).collect(),
            )
        })
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in series.iter().flat_map(|s| s.2.iter()) {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 >= x1 {
        (x0, x1) = (0.0, 1.0);
    }
    let pad = 0.03 * (x1 - x0);
    let (x0, x1) = (x0 - pad, x1 + pad);
    let (y0, y1) = ((y0.min(-0.3) - 0.1).max(-4.0), (y1.max(0.3) + 0.1).min(4.0));
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "{}: RMS error relative to rest-pose simplification",
                    report.model
                ),
                ("sans-serif", 26),
            )
            .margin(20)
            .x_label_area_size(55)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(plot_error)?;
        chart
            .configure_mesh()
            .x_desc("total influences (log scale)")
            .x_labels(10)
            .x_label_formatter(&|x| format!("{:.0}", 10f64.powf(*x)))
            .y_desc("RMS error / rest-pose RMS error (log scale)")
            .y_labels(12)
            .y_label_formatter(&|y| log_label(10f64.powf(*y)))
            .label_style(("sans-serif", 16))
            .axis_desc_style(("sans-serif", 19))
            .draw()
            .map_err(plot_error)?;
        for (name, colour, pts) in &series {
            let style = ShapeStyle::from(colour).stroke_width(2);
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), style))
                .map_err(plot_error)?
                .label(*name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
            chart
                .draw_series(
                    pts.iter()
                        .map(|&p| Circle::new(p, 3, ShapeStyle::from(colour).filled())),
                )
                .map_err(plot_error)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(("sans-serif", 18))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    write_plot(path, w, h, buf)
}

/// A value on a log axis with two significant digits: 0.0012, 0.050, 0.50, 3.2, 40. (With two
/// decimals, every label under 0.01 read "0.00".)
pub(crate) fn log_label(v: f64) -> String {
    // NaN, infinities, zero and below: no log label; written as they are.
    if !v.is_finite() || v <= 0.0 {
        return format!("{v}");
    }
    if v >= 10.0 {
        return format!("{v:.0}");
    }
    let decimals = (1 - v.log10().floor() as i32).max(1) as usize;
    format!("{v:.decimals$}")
}

/// Writes a plot drawn into an RGB buffer `w`×`h` as a PNG.
pub(crate) fn write_plot(path: &Path, w: u32, h: u32, buf: Vec<u8>) -> Result<()> {
    let rgb = image::RgbImage::from_raw(w, h, buf).context("plot buffer size")?;
    crate::atomic::write_png(path, &image::DynamicImage::ImageRgb8(rgb).to_rgba8())
}

pub(crate) fn plot_error<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow::anyhow!("cannot draw the plot: {e}")
}

/// plotters draws text with fonts registered by name; lodlab brings its own (the one egui
/// ships), so plots look the same on every machine and need no system fonts.
pub(crate) fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}

/// Table 1 of the paper for this model, the levels with their silhouettes, and how the
/// methods compare.
fn timings_markdown(
    report: &Report,
    model: &Model,
    sequences: &[(Method, Sequence)],
    lod_opts: &LodOptions,
) -> String {
    let t = |n: &str| report.methods.get(n).map(|m| m.bake_seconds);
    let (rest, asm, asis) = (t("rest-pose"), t("as"), t("as+is"));
    let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => format!("{:.2}", a / b),
        _ => "–".into(),
    };
    let secs = |x: Option<f64>| x.map_or("–".into(), |x| format!("{x:.3}"));
    let is_stats = sequences
        .iter()
        .find(|(m, _)| *m == Method::InfluenceSimplification)
        .map(|(_, s)| &s.stats);
    let miss = is_stats
        .and_then(|s| s.cache_hit_rate())
        .map_or("–".into(), |h| format!("{:.4}%", (1.0 - h) * 100.0));
    let influences_per_vertex =
        model.mesh.influences.len() as f64 / model.mesh.vertex_count().max(1) as f64;
    let mut md = format!(
        "# Bake timings for {} (Table 1 of Merry et al.)\n\n\
         Memoryless simplification and cutting the levels (measuring each against full\n\
         detail), release build, one method at a time. 3D is simplification of the rest pose;\n\
         AS uses the L2,2 metric; AS+IS adds influence simplification. Cache miss rate:\n\
         influence-simplification factorisations not found in the {}-entry cache.\n\n\
         | Model | Vertices | Bones | Influences per vertex | 3D (s) | AS (s) | AS+IS (s) | AS/3D | AS+IS/3D | Cache miss rate |\n\
         |---|---|---|---|---|---|---|---|---|---|\n\
         | {} | {} | {} | {:.2} | {} | {} | {} | {} | {} | {} |\n",
        report.model,
        crate::bake::character::simplify::influence::CACHE_SIZE,
        report.model,
        report.vertices,
        report.bones,
        influences_per_vertex,
        secs(rest),
        secs(asm),
        secs(asis),
        ratio(asm, rest),
        ratio(asis, rest),
        miss
    );
    if let Some(m) = report.methods.get("meshopt") {
        md += &format!(
            "\nmeshoptimizer (`meshopt::simplify` on the rest pose) takes {:.3} s for one level at \
             the coarsest triangle count.\n",
            m.bake_seconds
        );
    }
    md += &levels_markdown(report, lod_opts);
    md += &shading_markdown(report);
    let c = &report.comparison;
    let pct = |x: Option<f64>| x.map_or("–".into(), |x| format!("{:.0}%", x * 100.0));
    md += &format!(
        "\n## Error at equal influence counts\n\n\
         Measured by {}, over {} surface samples and {} frames.\n\n\
         {}- AS ≤ rest-pose on {} of the AS curve ({} down to the coarsest level, not \
         beyond); within the noise (above rest-pose by no more than the reordered curve strays \
         from it nearby; that is {} at the median), on {}; AS / rest-pose {} at the median\n\
         - the same mesh in another order, baked by rest-pose, ≤ rest-pose on {} of its \
         curve: what two equal methods score, the fraction above is read against it\n\
         - AS+IS ≤ AS on {} of the AS+IS curve\n\
         - AS+IS's lighting (colour error by vertex normals) at most {} AS's at the same \
         total influences, over the levels where either shows {VISIBLE_COLOUR} or more\n\
         - meshopt ≤ rest-pose on {} of the meshopt curve\n\
         - fewest total influences reached: {}\n",
        report.correspondence.describe(),
        report.samples,
        report.frames,
        report
            .stillness()
            .map_or(String::new(), |s| format!("Note: {s}.\n\n")),
        pct(c.as_le_rest_pose),
        pct(c.as_le_rest_pose_at_levels),
        c.noise
            .map_or("–".into(), |n| format!("±{:.1}%", n * 100.0)),
        pct(c.as_le_rest_pose_within_noise),
        c.as_over_rest_pose
            .map_or("–".into(), |r| format!("{r:.2}")),
        pct(c.reordered_le_rest_pose),
        pct(c.as_is_le_as),
        c.as_is_lighting_over_as
            .map_or("–".into(), |r| format!("{r:.2}×")),
        pct(c.meshopt_le_rest_pose),
        c.min_influences
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    md
}

/// Every level's lighting against full detail's, per method: vertex normals against the
/// normal map.
fn shading_markdown(report: &Report) -> String {
    let mut md = format!(
        "\n## Lighting\n\n\
         Each level's colour error against full detail, {SHADING_PX} px high: the mean colour \
         difference (0 to 1) over the pixels either covers, divided by the pixels full detail \
         covers, from {} views 15° above the ground at {} times of the first clip. Both columns \
         draw the same triangles, lit by the level's own vertex normals or through its normal \
         map (full detail's normals baked on its texture coordinates); their difference is the \
         lighting alone. The worst tile is the same error over the {}-pixel tile where it is \
         largest (of those full detail mostly covers): where a mean hides a streak. Recoloured: \
         the share of the pixels both cover that show a colour full detail shows nowhere within \
         the level's error of them (a part's colour bleeding onto another's).\n",
        crate::measure::colour_error::METRIC_VIEWS,
        crate::measure::colour_error::METRIC_FRAMES,
        crate::measure::shading_error::TILE,
    );
    let measured: Vec<_> = report
        .methods
        .iter()
        .filter(|(_, m)| !m.shading.is_empty())
        .collect();
    if measured.is_empty() {
        md += "\nNot measured: no GPU adapter.\n";
    }
    for (name, m) in measured {
        md += &format!(
            "\n### {name}\n\n| LOD | triangles | vertex normals | normal map | change | worst tile, vertex normals | worst tile, normal map | recoloured |\n|---|---|---|---|---|---|---|---|\n"
        );
        for s in &m.shading {
            let change = if !s.mapped {
                "no map".to_string()
            } else if s.vertex_normals > 0.0 {
                format!("{:+.0}%", 100.0 * (s.normal_maps / s.vertex_normals - 1.0))
            } else {
                "–".to_string()
            };
            md += &format!(
                "| {} | {} | {:.5} | {:.5} | {change} | {:.4} | {:.4} | {:.2}% |\n",
                s.level,
                s.triangles,
                s.vertex_normals,
                s.normal_maps,
                s.worst_tile_vertex_normals,
                s.worst_tile_normal_maps,
                100.0 * s.recoloured
            );
        }
    }
    md
}

/// The levels the viewer bakes, per method: triangles, error, bound, and the silhouette
/// distance at each tolerance; the coarsest level's triangles against the source's.
fn levels_markdown(report: &Report, lod_opts: &LodOptions) -> String {
    let taus: Vec<String> = report
        .silhouette_tolerances
        .iter()
        .map(|t| format!("silhouette at {t} px"))
        .collect();
    let mut md = format!(
        "\n## Levels\n\n\
         As the viewer bakes them (LOD 1 within {:.2} mm, each level's error doubling; a \
         level's error is the larger of the memoryless bound and the distance measured from \
         full detail, closest points both ways, worst of {} poses). The silhouette columns are \
         the largest distance in pixels between the level's silhouette and full detail's where \
         the renderer switches to the level at that tolerance, over {} poses from {} \
         directions. Where a level's error is so small that drawing it at that scale would \
         exceed {} pixels, the drawing is capped, and the bracket says how many pixels one \
         drawn pixel spans: the measurement's resolution there.\n",
        lod_opts.base_error * 1000.0,
        crate::bake::character::lod::POSE_SAMPLES,
        SILHOUETTE_POSES,
        crate::bake::character::silhouette::VIEWS.len(),
        crate::bake::character::silhouette::MAX_SIDE,
    );
    for (name, m) in &report.methods {
        if m.levels.is_empty() {
            continue;
        }
        let coarsest = m.levels.last().map_or(0, |l| l.triangles);
        md += &format!(
            "\n### {name}: {} levels, the coarsest {} triangles ({:.1}% of {})\n\n\
             | LOD | triangles | influences | error (mm) | bound (mm) | {} |\n|---|---|---|---|---|{}\n",
            m.levels.len(),
            coarsest,
            100.0 * coarsest as f64 / report.triangles.max(1) as f64,
            report.triangles,
            taus.join(" | "),
            "---|".repeat(taus.len()),
        );
        for (k, l) in m.levels.iter().enumerate() {
            let sil: Vec<String> = if l.silhouette_px.is_empty() {
                vec!["–".into(); taus.len()]
            } else {
                l.silhouette_px
                    .iter()
                    .zip(&l.silhouette_resolution_px)
                    .map(|(d, pixel)| {
                        if *pixel > 1.01 {
                            format!("{d:.2} (1 px = {pixel:.1})")
                        } else {
                            format!("{d:.2}")
                        }
                    })
                    .collect()
            };
            md += &format!(
                "| {k} | {} | {} | {:.3} | {:.3} | {} |\n",
                l.triangles,
                l.influences,
                l.error * 1000.0,
                l.bound * 1000.0,
                sil.join(" | ")
            );
        }
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_axis_labels_keep_two_significant_digits() {
        let labels: Vec<String> = [0.00123, 0.05, 0.5, 1.0, 3.16, 40.0]
            .into_iter()
            .map(log_label)
            .collect();
        assert_eq!(labels, ["0.0012", "0.050", "0.50", "1.0", "3.2", "40"]);
    }
    #[test]
    fn the_noise_band_follows_the_reordered_curve_along_it() {
        // Equal methods part by 50% around 500 influences and by 1% elsewhere.
        let deviations: Vec<(f64, f64)> = [8000.0, 4000.0, 2000.0, 1000.0, 500.0, 250.0, 125.0]
            .into_iter()
            .map(|x| (x, if x == 500.0 { 0.5 } else { 0.01 }))
            .collect();
        let median = 0.02;
        assert_eq!(local_band(&deviations, median, 480.0), 0.5);
        // A neighbour of the spike sees it; two points off, the median is the band.
        assert_eq!(local_band(&deviations, median, 1000.0), 0.5);
        assert_eq!(local_band(&deviations, median, 4000.0), median);
        assert_eq!(local_band(&deviations, median, 130.0), median);
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
            cache_hit_rate: None,
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

    #[test]
    fn a_reordered_model_is_the_same_surface_and_skin() {
        let model = crate::generate::walker::lowpoly();
        let twin = reordered(&model);
        let corners = |m: &Model| {
            let mesh = &m.mesh;
            let mut tris: Vec<String> = mesh
                .indices
                .chunks_exact(3)
                .map(|t| {
                    // A triangle up to rotation, by its corners' positions and skins.
                    let c: Vec<String> = t
                        .iter()
                        .map(|&v| {
                            let v = v as usize;
                            format!("{:?}{:?}", mesh.positions[v], mesh.influences_of(v))
                        })
                        .collect();
                    let k = (0..3).min_by_key(|&k| &c[k]).unwrap();
                    format!("{}{}{}", c[k], c[(k + 1) % 3], c[(k + 2) % 3])
                })
                .collect();
            tris.sort();
            tris
        };
        assert_eq!(corners(&model), corners(&twin));
        // And not the same order: vertex 0 is the last one now.
        assert_eq!(
            twin.mesh.positions[0],
            *model.mesh.positions.last().unwrap()
        );
        assert_ne!(model.mesh.indices, twin.mesh.indices);
    }
}

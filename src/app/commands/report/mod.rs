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

use crate::app::cli::ReportArgs;
use std::process::ExitCode;

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
use crate::bake::character::lod::{Replay, SkinnedLods, progressive_mesh};
use crate::bake::character::lod_error::{MeshError, Probe};
use crate::bake::character::simplify::{Method, Sequence, SimplifyInput, pose_samples};
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use crate::model::{Model, SkinnedMesh};
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
    };
    for method in Method::ALL {
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
        let rest_bones = SimplifyInput::rest_bones(&model.skeleton);
        methods.insert(
            "meshopt".into(),
            meshopt_curve(&probe, &base, &rest_bones, &triangles),
        );
    }

    // Rest-pose once more on the same mesh in another order: how far two equal methods'
    // curves stray apart, what the comparison of two methods is read against.
    let twin = reordered_rest_pose(model);
    let comparison = compare(&methods, &twin);
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
        reordered_rest_pose: twin.curve,
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
/// options the levels are cut by.
struct Measuring<'a> {
    probe: &'a Probe<'a>,
    base: &'a AnimationSpaceMesh,
    poses: &'a [Vec<glam::Affine3A>],
    gpu: Option<&'a crate::render::Gpu>,
    full: &'a crate::bake::gpu_data::drawable::Drawable,
    lod_opts: &'a crate::bake::character::lod::LodOptions,
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
    bar.set_stage("measuring");
    let clock = std::time::Instant::now();
    let curve = measure_sequence(m.probe, m.base, &lods.sequence);
    let measured = clock.elapsed().as_secs_f64();
    bar.set_stage("silhouettes");
    let levels = level_reports(&lods, m.poses);
    bar.set_stage("lighting");
    let shading = match m.gpu {
        Some(gpu) => {
            let which: Vec<usize> = (1..lods.levels.len()).collect();
            crate::measure::shading_error::shading_errors(
                gpu,
                model,
                m.full,
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
        cache_hit_rate: match method {
            Method::InfluenceSimplification => lods.sequence.stats.cache_hit_rate(),
            _ => None,
        },
        curve,
        levels,
        shading,
    };
    Ok((report, lods.sequence))
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
        progress: true,
        cache: crate::bake::cache::LodCache::new(a.cache.clone()),
        source: imported.source_hash,
    })?;
    print!("{}", summary(&report, &a.out));
    Ok(ExitCode::SUCCESS)
}

/// What a character's report found, a line a finding: the methods compared along the curve
/// and at the levels, against the noise a reordered mesh shows, then the floors, the
/// correspondence, stillness and where the files are.
fn summary(report: &Report, out: &std::path::Path) -> String {
    let c = &report.comparison;
    let pct = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{:.0}%", x * 100.0));
    let floors: Vec<String> = report
        .methods
        .iter()
        .filter_map(|(m, r)| Some(format!("{m} {}", r.levels.last()?.triangles)))
        .collect();
    let mut s = format!(
        "{}: AS <= rest-pose on {} of the curve, {} of its levels\n",
        report.model,
        pct(c.as_le_rest_pose),
        pct(c.as_le_rest_pose_at_levels)
    );
    s += &format!(
        "  within the noise: {} (the same mesh reordered moves rest-pose's error {} at the median, and is at or under it on {} of the curve)\n",
        pct(c.as_le_rest_pose_within_noise),
        c.noise
            .map_or("-".into(), |n| format!("±{:.1}%", n * 100.0)),
        pct(c.reordered_le_rest_pose)
    );
    s += &format!(
        "  AS/rest-pose error at the median: {}\n",
        c.as_over_rest_pose
            .map_or("-".into(), |r| format!("{r:.2}"))
    );
    s += &format!(
        "  AS+IS <= AS on {} of the curve; its lighting at most {} AS's at equal influences\n",
        pct(c.as_is_le_as),
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

#[cfg(test)]
mod tests {
    use super::compare::{lighting_at, lighting_over, local_band};
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

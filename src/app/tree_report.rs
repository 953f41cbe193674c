//! `lodlab report TREE`: a tree's chain of billboard-cloud levels measured as in the
//! Bennett-Therkildsen, Carlsen & Schmid's thesis "Animated Billboard Clouds for Foliage
//! Simplification" (2007), (§5.1.3 §5.1.4 §8.4): per level ε, billboards, area, texture memory,
//! colour error, animation errors and bake time (`report.json`), colour error and billboard count
//! against ε (`colour-error.png`), every level side by side from one view (`levels.png`), and a few
//! leaves' trajectories against their billboards' (`motion.png`), and the thesis's figures
//! beside this tree's at the same billboard counts (`against-thesis.md`), and how each level
//! is lit beside the full tree under two suns, its billboards lit by their planes and per
//! texel through their atlases (`lighting.md`).
//!
//! Besides the chain (skeleton clouds, spectral ones, then clumps), the report measures the
//! skeleton-only chain's coarse levels (`skeleton_levels`, for comparison at equal billboard
//! counts) and the spectral levels rebuilt with each description type and as plain SCA
//! (`description_types`).

use super::plotting::{plot_error, register_font, write_plot};
use crate::atomic::write as write_atomic;
use crate::bake::foliage::billboard::chain::{
    ChainOptions, ChainStyle, CloudKind, TreeLevel, at_rest, cloud_level, tree_chain,
};
use crate::bake::foliage::billboard::cloud::CloudParams;
use crate::bake::foliage::billboard::{Foliage, Grouping, foliage, tree_height};
use crate::bake::foliage::spectral::cloud::SpectralParams;
use crate::bake::foliage::spectral::description::DescriptionType;
use crate::measure::colour_error::{at_switch, colour_error, colour_error_over};
use crate::model::Model;
use crate::render::Gpu;
use anyhow::{Result, anyhow};
use plotters::prelude::*;
use serde::Serialize;
use std::path::Path;

/// The colour metric's image size (thesis §5.1.3).
pub const METRIC_SIZE: [u32; 2] = [800, 600];

#[derive(Clone, Debug, Serialize)]
pub struct LevelReport {
    /// ε as a fraction of the tree's height.
    pub epsilon: f32,
    pub epsilon_m: f32,
    /// How leaves were grouped into clouds: "full tree", "per bone", "subtree below N forks".
    pub grouping: String,
    pub billboards: usize,
    /// Billboards drawn from any one view: all of a cloud's, one per clump of a clump level.
    pub drawn_billboards: usize,
    pub triangles: usize,
    /// Total billboard area, m².
    pub area: f32,
    pub texture_bytes: usize,
    pub colour_error: f32,
    /// The tree's height on screen where the level comes in (ε projects to the chain's
    /// tolerance), pixels (0 for the full tree).
    pub switch_px: f32,
    /// The colour error with the tree drawn that high (0 for the full tree).
    pub colour_error_at_switch: f32,
    /// The colour error at the metric's size, seen from as far off as where the level comes
    /// in (0 for the full tree; see [`crate::measure::colour_error::SwitchErrors`]).
    pub colour_error_from_switch: f32,
    /// Mean RMS distance over the loop between a leaf and its projection on its billboard,
    /// in tree heights (see [`crate::bake::foliage::spectral::metrics`]).
    pub anim_rms: f32,
    /// Mean dominating-axis spectral amplitude error (thesis §5.1.4), in [0, 1).
    pub anim_spectral: f32,
    pub bake_seconds: f64,
}

/// A spectral level rebuilt with one description type.
#[derive(Clone, Debug, Serialize)]
pub struct DescriptionReport {
    /// The chain level it stands in for.
    pub level: usize,
    pub description: String,
    /// Billboards follow their leaves' shared bone (§6.4); false: plain SCA.
    pub shared_bone: bool,
    pub epsilon: f32,
    pub clusters: usize,
    pub billboards: usize,
    pub anim_rms: f32,
    pub anim_spectral: f32,
    pub bake_seconds: f64,
}

/// The thesis's own set-up (§8.4): one static cloud for the whole crown, scored by the static
/// colour metric (one frame, the tree at rest), for comparison with its figures.
#[derive(Clone, Debug, Serialize)]
pub struct StaticCloudReport {
    /// ε as a fraction of the tree's height.
    pub epsilon: f32,
    pub billboards: usize,
    pub colour_error: f32,
}

#[derive(Clone, Debug, Serialize)]
pub struct TreeReport {
    pub model: String,
    pub leaves: usize,
    pub bones: usize,
    pub height_m: f32,
    pub levels: Vec<LevelReport>,
    /// Seconds to build the whole chain (clouds and atlases).
    pub chain_seconds: f64,
    pub metric: String,
    /// At the levels' ε: one static cloud for the whole crown, static colour metric.
    pub static_clouds: Vec<StaticCloudReport>,
    /// The skeleton-only chain's levels where it differs from the chain (coarser branch
    /// subtrees instead of spectral clouds).
    pub skeleton_levels: Vec<LevelReport>,
    /// The chain's spectral levels with each description type, and as plain SCA.
    pub description_types: Vec<DescriptionReport>,
    /// The thesis's figures (§8.4.1) beside this tree's at the same billboard counts.
    pub against_thesis: Vec<ThesisRow>,
    /// Each cloud level's lighting against the full tree's under two suns, billboards lit
    /// by their planes and through their atlases, the tree [`LIGHTING_PX`] pixels high.
    pub lighting: Vec<crate::measure::foliage_lighting::LevelLighting>,
}

/// How high the lighting comparison draws the tree, pixels.
pub const LIGHTING_PX: f32 = 240.0;

/// One of the thesis's results (§8.4.1, its 692-quad tree, one static cloud, view penalty
/// on, 800×600) and this tree's colour error at the same billboard count, read off its
/// levels (linear in log billboards between the two levels either side; None where no level
/// is that coarse or that fine).
#[derive(Clone, Debug, Serialize)]
pub struct ThesisRow {
    pub billboards: f32,
    pub thesis: f32,
    /// The chain, animated, at 800×600, its levels counted by the billboards a view draws.
    pub chain: Option<f32>,
    /// The same, its levels counted by all the billboards they hold (a clump level holds
    /// several to a clump).
    pub chain_by_held: Option<f32>,
    /// The chain, animated, each level at its switch size.
    pub chain_at_switch: Option<f32>,
    /// The chain, animated, at 800×600, each level seen from as far off as it comes in.
    pub chain_from_switch: Option<f32>,
    /// A level of the chain's coarse kind made at exactly this many billboards drawn (as many
    /// view-selected clumps), animated, at 800×600: close, and from as far off as it comes in.
    pub at_count: AtCount,
    /// One static cloud at rest, the thesis's own set-up.
    pub static_cloud: Option<f32>,
}

/// A clump level made at one of the thesis's billboard counts (see [`ThesisRow::at_count`]).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct AtCount {
    pub clumps: usize,
    /// Its ε bound ([`crate::bake::foliage::billboard::clumps::ClumpCloud::epsilon`]), in tree heights.
    pub epsilon: f32,
    pub close: f32,
    pub from_switch: f32,
}

/// The thesis's results to compare with: (billboards, colour error), §8.4.1: ε 4 gave 36.2
/// billboards and 0.310, ε 10 gave 5.73 and 0.440 (20 runs each).
pub const THESIS: [(f32, f32); 2] = [(36.2, 0.310), (5.73, 0.440)];

/// The error at `billboards` read off `(billboards, error)` points (see [`ThesisRow`]).
pub fn at_billboards(points: &[(usize, f32)], billboards: f32) -> Option<f32> {
    let mut p: Vec<(f32, f32)> = points
        .iter()
        .filter(|(n, _)| *n > 0)
        .map(|&(n, e)| ((n as f32).ln(), e))
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    let x = billboards.ln();
    p.windows(2).find(|w| w[0].0 <= x && x <= w[1].0).map(|w| {
        let t = if w[1].0 > w[0].0 {
            (x - w[0].0) / (w[1].0 - w[0].0)
        } else {
            0.0
        };
        w[0].1 + t * (w[1].1 - w[0].1)
    })
}

/// The table against the thesis, in Markdown.
pub fn thesis_table(report: &TreeReport) -> String {
    use std::fmt::Write as _;
    let cell = |e: Option<f32>| e.map_or("not reached".into(), |e| format!("{e:.3}"));
    let framing = crate::measure::colour_error::FRAMING;
    let mut out = format!(
        "{}: colour error against the thesis (§8.4.1: its 692-quad tree, one static cloud, \
         800×600). This tree's errors are read off its levels at the thesis's billboard counts: \
         the billboards a view draws (a clump level draws one of its planes per clump), or, \
         in the fourth column, all the billboards a level holds; and, beside them, a level of \
         exactly that many clumps made as the chain makes its coarse levels. Levels are seen \
         {framing} tree heights off (the thesis does not say from how far), or from \
         as far off as each comes in (the field of view narrowed to fill 800×600 alike), or \
         drawn as small as it is there.\n\n\
         | billboards | thesis | chain, animated, 800×600 | chain, animated, 800×600 from the switch distance | chain by billboards held | chain, animated, at switch size | that many clumps, animated, 800×600 | the same from its switch distance | one static cloud at rest, 800×600 |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        report.model
    );
    for r in &report.against_thesis {
        let _ = writeln!(
            out,
            "| {:.1} | {:.3} | {} | {} | {} | {} | {} | {} | {} |",
            r.billboards,
            r.thesis,
            cell(r.chain),
            cell(r.chain_from_switch),
            cell(r.chain_by_held),
            cell(r.chain_at_switch),
            cell(Some(r.at_count.close)),
            cell(Some(r.at_count.from_switch)),
            cell(r.static_cloud)
        );
    }
    out
}

/// `lighting.md`: every cloud level's lighting against the full tree's, per sun.
pub fn lighting_table(report: &TreeReport) -> String {
    use std::fmt::Write;
    let mut out = format!(
        "{}: each cloud level beside the full tree, {LIGHTING_PX:.0} px high, under two suns; \
         billboards lit by their planes (flat, as the thesis did) and per texel through their \
         atlases by the leaves' normals (both darkened by the crown's occlusion). Shading: the mean colour difference \
         over the pixels both cover; tone: the difference of the mean colours. Both 0..1, \
         lower is closer.\n\n\
         | level | billboards | sun | shading, flat | shading, atlas | tone, flat | tone, atlas |\n\
         |---:|---:|---|---:|---:|---:|---:|\n",
        report.model
    );
    for l in &report.lighting {
        let billboards = report.levels.get(l.level).map_or(0, |r| r.billboards);
        let _ = writeln!(
            out,
            "| L{} | {} | {} | {:.4} | {:.4} | {:.4} | {:.4} |",
            l.level, billboards, l.sun, l.flat.shading, l.atlas.shading, l.flat.tone, l.atlas.tone
        );
    }
    out
}

/// Builds the chain of `tree`, measures it and writes the three files into `out`.
pub fn run(tree: &Model, out: &Path) -> Result<TreeReport> {
    let f = foliage(tree).map_err(|e| anyhow!("{}: {e}", tree.name))?;
    crate::atomic::make_folder(out)?;
    let gpu = Gpu::headless()?;
    let raster = crate::render::atlas::AtlasRasterizer::new(&gpu);
    let h = tree_height(tree);
    let start = std::time::Instant::now();
    let opts = ChainOptions::default();
    let chain = tree_chain(&raster, tree, &f, &opts, &|_| {})?;
    let chain_seconds = start.elapsed().as_secs_f64();
    let mut levels = Vec::new();
    for (k, l) in chain.iter().enumerate() {
        levels.push(measure_level(&gpu, tree, k, l, "")?);
    }
    // The skeleton-only chain, where it parts from this one.
    let skeleton_opts = ChainOptions {
        style: ChainStyle::Skeleton,
        ..opts
    };
    let skeleton_chain = tree_chain(&raster, tree, &f, &skeleton_opts, &|_| {})?;
    let mut skeleton_levels = Vec::new();
    for (k, l) in skeleton_chain.iter().enumerate() {
        if chain.get(k).is_some_and(|c| c.kind == l.kind) {
            continue;
        }
        skeleton_levels.push(measure_level(&gpu, tree, k, l, "skeleton-only ")?);
    }
    let description_types = description_types(&raster, tree, &f, &chain, &opts)?;
    let static_clouds = static_clouds(&gpu, &raster, tree, &f, &chain)?;
    let clouds: Vec<(usize, &crate::bake::foliage::billboard::chain::CloudLevel)> = chain
        .iter()
        .enumerate()
        .filter(|(_, l)| l.cloud.billboards > 0 && l.cloud.impostor.is_none())
        .map(|(k, l)| (k, &l.cloud))
        .collect();
    let lighting =
        crate::measure::foliage_lighting::foliage_lighting(&gpu, tree, &clouds, LIGHTING_PX)?;
    let points = |f: &dyn Fn(&LevelReport) -> f32| -> Vec<(usize, f32)> {
        levels[1..]
            .iter()
            .map(|l| (l.drawn_billboards, f(l)))
            .collect()
    };
    let held: Vec<(usize, f32)> = levels[1..]
        .iter()
        .map(|l| (l.billboards, l.colour_error))
        .collect();
    let still: Vec<(usize, f32)> = static_clouds
        .iter()
        .map(|s| (s.billboards, s.colour_error))
        .collect();
    let at_counts = THESIS
        .iter()
        .map(|&(billboards, _)| clumps_at_count(&gpu, &raster, tree, &f, &opts, billboards))
        .collect::<Result<Vec<_>>>()?;
    let against_thesis = THESIS
        .iter()
        .zip(at_counts)
        .map(|(&(billboards, thesis), at_count)| ThesisRow {
            billboards,
            thesis,
            chain: at_billboards(&points(&|l| l.colour_error), billboards),
            chain_by_held: at_billboards(&held, billboards),
            chain_at_switch: at_billboards(&points(&|l| l.colour_error_at_switch), billboards),
            chain_from_switch: at_billboards(&points(&|l| l.colour_error_from_switch), billboards),
            at_count,
            static_cloud: at_billboards(&still, billboards),
        })
        .collect();
    let report = TreeReport {
        model: tree.name.clone(),
        leaves: f.leaves.len(),
        bones: tree.skeleton.bone_count(),
        height_m: h,
        levels,
        chain_seconds,
        metric: format!(
            "binary coverage masks at {}x{}, {} views round the tree at ground level, {} times over the loop; share of the full tree's covered pixels that differ",
            METRIC_SIZE[0],
            METRIC_SIZE[1],
            crate::measure::colour_error::METRIC_VIEWS,
            crate::measure::colour_error::METRIC_FRAMES
        ),
        static_clouds,
        skeleton_levels,
        description_types,
        against_thesis,
        lighting,
    };
    write_atomic(
        &out.join("report.json"),
        serde_json::to_string_pretty(&report)?.as_bytes(),
    )?;
    write_atomic(
        &out.join("against-thesis.md"),
        thesis_table(&report).as_bytes(),
    )?;
    write_atomic(&out.join("lighting.md"), lighting_table(&report).as_bytes())?;
    plot(&report, &out.join("colour-error.png"))?;
    contact_sheet(&gpu, &chain, &report, &out.join("levels.png"))?;
    // The finest spectral level against the skeleton-only level at the same ε.
    let spectral = chain
        .iter()
        .position(|l| matches!(l.kind, Some(CloudKind::Spectral(_))));
    let pair = spectral.map(|k| {
        (
            (k, &chain[k]),
            skeleton_chain
                .get(k)
                .or(skeleton_chain.last())
                .map(|l| (k.min(skeleton_chain.len() - 1), l)),
        )
    });
    motion_plot(&report, pair, &out.join("motion.png"))?;
    Ok(report)
}

/// A level of a chain with its colour error (said on stderr as it goes).
fn measure_level(
    gpu: &Gpu,
    tree: &Model,
    k: usize,
    l: &TreeLevel,
    what: &str,
) -> Result<LevelReport> {
    let h = tree_height(tree);
    // Where the level comes in, and its errors there (none for the full tree, level 0).
    let (error, switch_px, from_switch, at_switch) = if l.epsilon > 0.0 {
        let px = ChainOptions::default().tolerance_px * h / l.epsilon;
        let e = at_switch(gpu, tree, &l.cloud, METRIC_SIZE, px)?;
        (e.close, px, e.from_switch, e.at_switch)
    } else {
        let close = colour_error(gpu, tree, &l.cloud, METRIC_SIZE)?;
        (close, 0.0, 0.0, 0.0)
    };
    let anim = &l.cloud.animation;
    eprintln!(
        "lodlab: {} {what}L{k}: ε {:.4} h, {} billboards, colour error {:.3} ({:.3} from the switch distance, {:.3} at {:.0} px), animation error {:.4} h / {:.3}",
        tree.name,
        l.epsilon / h,
        l.cloud.billboards,
        error,
        from_switch,
        at_switch,
        switch_px,
        anim.rms,
        anim.spectral
    );
    Ok(LevelReport {
        epsilon: l.epsilon / h,
        epsilon_m: l.epsilon,
        grouping: CloudKind::name(l.kind.as_ref()),
        billboards: l.cloud.billboards,
        drawn_billboards: l.cloud.drawn_billboards(),
        triangles: l.cloud.model.mesh.triangle_count(),
        area: l.cloud.area,
        texture_bytes: l.cloud.texture_bytes,
        colour_error: error,
        switch_px,
        colour_error_at_switch: at_switch,
        colour_error_from_switch: from_switch,
        anim_rms: anim.rms,
        anim_spectral: anim.spectral,
        bake_seconds: l.bake_seconds,
    })
}

/// The chain's spectral levels baked again with every description type and the shared bone,
/// and with the chain's own type without it (thesis Ch. 4–5): their animation errors.
fn description_types(
    raster: &crate::render::atlas::AtlasRasterizer,
    tree: &Model,
    f: &Foliage,
    chain: &[TreeLevel],
    opts: &ChainOptions,
) -> Result<Vec<DescriptionReport>> {
    let h = tree_height(tree);
    let mut description_types = Vec::new();
    for (k, l) in chain.iter().enumerate() {
        let Some(CloudKind::Spectral(sp)) = l.kind else {
            continue;
        };
        let params = CloudParams {
            epsilon: l.epsilon,
            seed: opts.seed,
            ..Default::default()
        };
        let density = opts.atlas_density(l.epsilon, h, &CloudKind::Spectral(sp));
        // Every description type with the shared bone, and the chain's own without it.
        let variants = DescriptionType::ALL
            .map(|d| (d, true))
            .into_iter()
            .chain([(sp.kind, false)]);
        for (description, shared_bone) in variants {
            let start = std::time::Instant::now();
            let kind = CloudKind::Spectral(SpectralParams {
                kind: description,
                shared_bone,
                ..sp
            });
            // Only the motion is scored here: no occlusion needed.
            let cloud = cloud_level(raster, tree, f, &params, &kind, density, tree, None)?;
            description_types.push(DescriptionReport {
                level: k,
                description: description.name().into(),
                shared_bone,
                epsilon: l.epsilon / h,
                clusters: sp.clusters,
                billboards: cloud.billboards,
                anim_rms: cloud.animation.rms,
                anim_spectral: cloud.animation.spectral,
                bake_seconds: start.elapsed().as_secs_f64(),
            });
        }
    }
    Ok(description_types)
}

/// A level of `billboards` (rounded) view-selected clumps, as the chain makes its coarse
/// levels, measured close and from where it would come in (its ε bound projecting to the
/// chain's tolerance): the chain's method at the thesis's count itself, where the chain's
/// own levels straddle it.
fn clumps_at_count(
    gpu: &Gpu,
    raster: &crate::render::atlas::AtlasRasterizer,
    tree: &Model,
    f: &Foliage,
    opts: &ChainOptions,
    billboards: f32,
) -> Result<AtCount> {
    let h = tree_height(tree);
    let clumps = (billboards.round() as usize).max(1);
    let c = crate::bake::foliage::billboard::clumps::clump_cloud(
        tree,
        f,
        clumps,
        opts.clump_views,
        opts.seed,
    );
    let eps = c.epsilon().max(1e-4 * h);
    let params = CloudParams {
        epsilon: eps,
        seed: opts.seed,
        ..Default::default()
    };
    // Its atlas as sharp as the chain's sharpest, about two texels per pixel of the metric's
    // picture (the tree some 500 px high), as the thesis sized its textures for its pictures:
    // the chain's own clump levels carry 256 texels across the tree
    // (`ChainOptions::min_atlas_texels`), which the metric's close look still magnifies, so
    // this one scores their shapes alone.
    let density = crate::bake::foliage::billboard::atlas::AtlasDensity::for_level(
        800.0 / h,
        eps,
        opts.tolerance_px,
    );
    let wood = crate::bake::foliage::billboard::wood::WoodChain::new(tree).tree_at(tree, eps);
    let crown = crate::bake::foliage::billboard::occlusion::CrownDensity::of(tree);
    let kind = CloudKind::Clumps {
        clumps,
        views: opts.clump_views,
    };
    let level = cloud_level(
        raster,
        tree,
        f,
        &params,
        &kind,
        density,
        &wood,
        crown.as_ref(),
    )?;
    let px = opts.tolerance_px * h / eps;
    let e = at_switch(gpu, tree, &level, METRIC_SIZE, px)?;
    eprintln!(
        "lodlab: {} {clumps} clumps: ε {:.4} h, colour error {:.3} ({:.3} from the switch distance, {px:.0} px)",
        tree.name,
        eps / h,
        e.close,
        e.from_switch
    );
    Ok(AtCount {
        clumps: level.drawn_billboards(),
        epsilon: eps / h,
        close: e.close,
        from_switch: e.from_switch,
    })
}

/// The thesis's own set-up (§8.4) at every level's ε: one static cloud for the whole crown of
/// the tree at rest, scored by the static colour metric.
fn static_clouds(
    gpu: &Gpu,
    raster: &crate::render::atlas::AtlasRasterizer,
    tree: &Model,
    f: &Foliage,
    chain: &[TreeLevel],
) -> Result<Vec<StaticCloudReport>> {
    let h = tree_height(tree);
    let still = at_rest(tree);
    let crown = crate::bake::foliage::billboard::occlusion::CrownDensity::of(&still);
    let mut static_clouds = Vec::new();
    for l in &chain[1..] {
        // The thesis's algorithm as its stability runs set it (§8.4.1): view penalty on, no
        // increased density, and no crossed billboards.
        let params = CloudParams {
            epsilon: l.epsilon,
            crossing: false,
            increased_density: false,
            ..Default::default()
        };
        let whole = CloudKind::Skeleton(Grouping::Subtree { forks: 0 });
        let density = ChainOptions::default().atlas_density(l.epsilon, h, &whole);
        let cloud = cloud_level(
            raster,
            &still,
            f,
            &params,
            &whole,
            density,
            &still,
            crown.as_ref(),
        )?;
        let error = colour_error_over(gpu, &still, &cloud, METRIC_SIZE, 1)?;
        eprintln!(
            "lodlab: {} static whole-crown cloud: ε {:.4} h, {} billboards, colour error {:.3}",
            tree.name,
            l.epsilon / h,
            cloud.billboards,
            error
        );
        static_clouds.push(StaticCloudReport {
            epsilon: l.epsilon / h,
            billboards: cloud.billboards,
            colour_error: error,
        });
    }
    Ok(static_clouds)
}

/// A few leaves' sway over one loop (their x and z about their mean), against where their
/// billboards take them: a spectral level, and the skeleton-only level at the same ε.
type Shown<'a> = (usize, &'a TreeLevel);

fn motion_plot(
    report: &TreeReport,
    pair: Option<(Shown<'_>, Option<Shown<'_>>)>,
    path: &Path,
) -> Result<()> {
    register_font();
    let (w, h) = (1200u32, 900u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let Some(((sk, spectral), skeleton)) = pair else {
            root.titled(
                &format!("{}: no spectral level in the chain", report.model),
                ("sans-serif", 24),
            )
            .map_err(plot_error)?;
            root.present().map_err(plot_error)?;
            drop(root);
            return write_plot(path, w, h, buf);
        };
        let root = root
            .titled(
                &format!(
                    "{}: leaves' sway over one loop (x and z about the leaf's mean, m)",
                    report.model
                ),
                ("sans-serif", 22),
            )
            .map_err(plot_error)?;
        let traces = &spectral.cloud.animation.traces;
        let rows = traces.len().max(1);
        let cells = root.split_evenly((rows, 2));
        let black = RGBColor(20, 20, 20);
        let blue = RGBColor(30, 100, 220);
        let orange = RGBColor(230, 120, 20);
        for (i, trace) in traces.iter().enumerate() {
            let other = skeleton.and_then(|(_, l)| {
                l.cloud
                    .animation
                    .traces
                    .iter()
                    .find(|t| t.leaf == trace.leaf)
            });
            for (axis, name) in [(0usize, "x"), (2, "z")] {
                let mean = trace.original.iter().map(|p| p[axis]).sum::<f32>()
                    / trace.original.len().max(1) as f32;
                let curve = |t: &[glam::Vec3]| -> Vec<(f64, f64)> {
                    let n = t.len().max(1) as f64;
                    t.iter()
                        .enumerate()
                        .map(|(s, p)| (s as f64 / n, (p[axis] - mean) as f64))
                        .collect()
                };
                let mut curves = vec![(curve(&trace.original), black, "leaf".to_string())];
                curves.push((
                    curve(&trace.billboard),
                    blue,
                    format!("spectral L{sk} ({} billboards)", spectral.cloud.billboards),
                ));
                if let (Some(t), Some((k, l))) = (other, skeleton) {
                    curves.push((
                        curve(&t.billboard),
                        orange,
                        format!("skeleton L{k} ({} billboards)", l.cloud.billboards),
                    ));
                }
                let span = curves
                    .iter()
                    .flat_map(|(c, _, _)| c.iter().map(|p| p.1.abs()))
                    .fold(0.01f64, f64::max)
                    * 1.15;
                let mut chart = ChartBuilder::on(&cells[2 * i + axis / 2])
                    .caption(
                        format!("leaf {} along {name}", trace.leaf),
                        ("sans-serif", 17),
                    )
                    .margin(12)
                    .x_label_area_size(32)
                    .y_label_area_size(60)
                    .build_cartesian_2d(0.0..1.0, -span..span)
                    .map_err(plot_error)?;
                chart
                    .configure_mesh()
                    .x_desc("loop time")
                    .label_style(("sans-serif", 13))
                    .draw()
                    .map_err(plot_error)?;
                for (points, colour, label) in curves {
                    chart
                        .draw_series(LineSeries::new(points, colour.stroke_width(2)))
                        .map_err(plot_error)?
                        .label(label)
                        .legend(move |(x, y)| {
                            PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(2))
                        });
                }
                if i == 0 && axis == 0 {
                    chart
                        .configure_series_labels()
                        .position(SeriesLabelPosition::UpperRight)
                        .border_style(BLACK)
                        .background_style(WHITE.mix(0.9))
                        .label_font(("sans-serif", 13))
                        .draw()
                        .map_err(plot_error)?;
                }
            }
        }
        root.present().map_err(plot_error)?;
    }
    write_plot(path, w, h, buf)
}

/// Colour error (top) and billboard count (bottom, log scale) against ε.
fn plot(report: &TreeReport, path: &Path) -> Result<()> {
    register_font();
    let (w, h) = (1000u32, 800u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    let pts: Vec<&LevelReport> = report.levels.iter().skip(1).collect();
    let x1 = pts.iter().map(|l| l.epsilon).fold(0.01f32, f32::max) as f64 * 1.08;
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let (top, bottom) = root.split_vertically(h / 2);
        let colour = RGBColor(30, 100, 220);
        let mut chart = ChartBuilder::on(&top)
            .caption(
                format!("{}: colour error of its billboard clouds", report.model),
                ("sans-serif", 24),
            )
            .margin(18)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(
                0.0..x1,
                0.0..(pts
                    .iter()
                    .map(|l| l.colour_error)
                    .chain(report.static_clouds.iter().map(|l| l.colour_error))
                    .fold(0.05f32, f32::max) as f64
                    * 1.15),
            )
            .map_err(plot_error)?;
        chart
            .configure_mesh()
            .x_desc("ε (fraction of tree height)")
            .y_desc("colour error")
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 17))
            .draw()
            .map_err(plot_error)?;
        let chain_errors: Vec<(f64, f64)> = pts
            .iter()
            .map(|l| (l.epsilon as f64, l.colour_error as f64))
            .collect();
        let chain_label = "the chain (skeleton clouds, spectral, then clumps), animated";
        series(
            &mut chart,
            &chain_errors,
            colour,
            Marker::Circle,
            Some(chain_label),
        )?;
        let green = RGBColor(40, 160, 70);
        let still_errors: Vec<(f64, f64)> = report
            .static_clouds
            .iter()
            .map(|l| (l.epsilon as f64, l.colour_error as f64))
            .collect();
        let still_label = "one static cloud, at rest (thesis §8.4)";
        series(
            &mut chart,
            &still_errors,
            green,
            Marker::Triangle,
            Some(still_label),
        )?;
        let orange = RGBColor(230, 120, 20);
        let skeleton_errors: Vec<(f64, f64)> = report
            .skeleton_levels
            .iter()
            .map(|l| (l.epsilon as f64, l.colour_error as f64))
            .collect();
        series(
            &mut chart,
            &skeleton_errors,
            orange,
            Marker::Triangle,
            Some("skeleton clouds only (branch subtrees), animated"),
        )?;
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .border_style(BLACK)
            .background_style(WHITE.mix(0.9))
            .label_font(("sans-serif", 15))
            .draw()
            .map_err(plot_error)?;

        let red = RGBColor(220, 50, 40);
        let max_count = pts.iter().map(|l| l.billboards).max().unwrap_or(10).max(10) as f64;
        let mut chart = ChartBuilder::on(&bottom)
            .caption("billboards drawn from a view", ("sans-serif", 22))
            .margin(18)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..x1, 0.0..(max_count * 1.5).log10())
            .map_err(plot_error)?;
        chart
            .configure_mesh()
            .x_desc("ε (fraction of tree height)")
            .y_desc("billboards (log scale)")
            .y_label_formatter(&|y| format!("{:.0}", 10f64.powf(*y)))
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 17))
            .draw()
            .map_err(plot_error)?;
        let log_count = |n: usize| (n.max(1) as f64).log10();
        let chain_counts: Vec<(f64, f64)> = pts
            .iter()
            .map(|l| (l.epsilon as f64, log_count(l.drawn_billboards)))
            .collect();
        series(&mut chart, &chain_counts, red, Marker::Circle, None)?;
        let still_counts: Vec<(f64, f64)> = report
            .static_clouds
            .iter()
            .map(|l| (l.epsilon as f64, log_count(l.billboards)))
            .collect();
        series(&mut chart, &still_counts, green, Marker::Triangle, None)?;
        let skeleton_counts: Vec<(f64, f64)> = report
            .skeleton_levels
            .iter()
            .map(|l| (l.epsilon as f64, log_count(l.billboards)))
            .collect();
        series(&mut chart, &skeleton_counts, orange, Marker::Triangle, None)?;
        root.present().map_err(plot_error)?;
    }
    write_plot(path, w, h, buf)
}

/// How a series marks its points: the chain with circles, the thesis's set-up with triangles.
#[derive(Clone, Copy)]
enum Marker {
    Circle,
    Triangle,
}

type Chart<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// One series: a line through `points` (thicker for circles) and a marker on each, with a
/// legend entry when it has a label.
fn series(
    chart: &mut Chart<'_, '_>,
    points: &[(f64, f64)],
    colour: RGBColor,
    marker: Marker,
    label: Option<&str>,
) -> Result<()> {
    let width = match marker {
        Marker::Circle => 2,
        Marker::Triangle => 1,
    };
    chart
        .draw_series(LineSeries::new(
            points.iter().copied(),
            colour.stroke_width(width),
        ))
        .map_err(plot_error)?;
    let style = colour.filled();
    match marker {
        Marker::Circle => {
            let drawn = chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 4, style)))
                .map_err(plot_error)?;
            if let Some(label) = label {
                drawn
                    .label(label)
                    .legend(move |(x, y)| Circle::new((x + 10, y), 4, style));
            }
        }
        Marker::Triangle => {
            let drawn = chart
                .draw_series(points.iter().map(|&p| TriangleMarker::new(p, 5, style)))
                .map_err(plot_error)?;
            if let Some(label) = label {
                drawn
                    .label(label)
                    .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 5, style));
            }
        }
    }
    Ok(())
}

/// Every level from the same view, side by side, labelled.
fn contact_sheet(gpu: &Gpu, chain: &[TreeLevel], report: &TreeReport, path: &Path) -> Result<()> {
    use crate::render::targets::{OFFSCREEN_FORMAT, Offscreen};
    use crate::runtime::spec::Loaded;
    use crate::runtime::world::World;
    let (tw, th) = (300u32, 400u32);
    let columns = chain.len().min(6) as u32;
    let rows = (chain.len() as u32).div_ceil(columns);
    let mut sheet =
        image::RgbImage::from_pixel(tw * columns, th * rows, image::Rgb([255, 255, 255]));
    let target = Offscreen::new(gpu, tw, th, 4);
    for (k, l) in chain.iter().enumerate() {
        let bake = l
            .cloud
            .bake()
            .map_err(|e| anyhow!("{}: {e}", l.cloud.model.name))?;
        let loaded = Loaded::forest_of_bake(&l.cloud.model, bake, 1);
        let mut world = World::new(gpu, loaded, OFFSCREEN_FORMAT, 4)?;
        // The billboards as their atlases light them, whatever the adapter's default.
        world.renderer.atlas_lighting = true;
        let height = world.bakes[0].bounds.size().y;
        world.camera = crate::scene::Camera::new(
            glam::Vec3::new(0.0, height * 0.5, 0.0),
            30.0,
            6.0,
            height * 1.45,
        );
        world.prepare(gpu, [tw, th], 1.0, 0.0);
        world
            .renderer
            .render_to(gpu, &target.targets, &target.view)?;
        let tile = image::DynamicImage::ImageRgba8(target.read_rgba(gpu)?).to_rgb8();
        let (x, y) = ((k as u32 % columns) * tw, (k as u32 / columns) * th);
        image::imageops::replace(&mut sheet, &tile, x as i64, y as i64);
    }
    // Labels.
    register_font();
    let (w, h) = sheet.dimensions();
    let mut buf = sheet.into_raw();
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        for (k, l) in report.levels.iter().enumerate() {
            let (x, y) = ((k as u32 % columns) * tw, (k as u32 / columns) * th);
            let text = if k == 0 {
                format!("L0: {} leaves", report.leaves)
            } else {
                let drawn = if l.drawn_billboards < l.billboards {
                    format!("{} of {}", l.drawn_billboards, l.billboards)
                } else {
                    l.billboards.to_string()
                };
                format!(
                    "L{k}: ε {:.3} h · {drawn} billboards · {:.3}",
                    l.epsilon, l.colour_error
                )
            };
            root.draw(&Text::new(
                text,
                (x as i32 + 8, y as i32 + 8),
                ("sans-serif", 15).into_font().color(&BLACK),
            ))
            .map_err(plot_error)?;
        }
        root.present().map_err(plot_error)?;
    }
    write_plot(path, w, h, buf)
}

#[cfg(test)]
mod thesis_tests {
    use super::*;

    #[test]
    fn errors_are_read_off_the_levels_in_log_billboards() {
        let levels = [(100, 0.2), (10, 0.4), (1, 0.8)];
        assert!((at_billboards(&levels, 100.0).unwrap() - 0.2).abs() < 1e-6);
        // √1000 ≈ 31.6 lies halfway between 100 and 10 in log billboards.
        assert!((at_billboards(&levels, 1000f32.sqrt()).unwrap() - 0.3).abs() < 1e-5);
        assert!((at_billboards(&levels, 1.0).unwrap() - 0.8).abs() < 1e-6);
        assert_eq!(at_billboards(&levels, 200.0), None);
        assert_eq!(at_billboards(&levels[..1], 100.0), None);
    }
}

//! `lodlab report TREE`: a tree's chain of billboard-cloud levels measured as in the
//! Bennett-Therkildsen, Carlsen & Schmid's thesis "Animated Billboard Clouds for Foliage
//! Simplification" (2007), (§5.1.3 §5.1.4 §8.4): per level ε, billboards, area, texture memory,
//! colour error, animation errors and bake time (`report.json`), colour error and billboard count
//! against ε (`colour-error.png`), every level side by side from one view (`levels.png`), and a few
//! leaves' trajectories against their billboards' (`motion.png`), and the thesis's figures
//! beside this tree's at the same billboard counts (`against-thesis.md`), and how each level
//! is lit beside the full tree under two suns, its billboards lit as one and per
//! texel through their atlases (`lighting.md`), and the levels each size draws ordered by ε
//! and by measured error per cost (`orders.md`, `error-per-cost.png`,
//! `chains-error-per-cost.png`), and, for a tree of several cut-out materials told apart by
//! colour (leaves and flowers), each level's share of foliage pixels by material
//! (`materials.md`). `report.json` also says what wind the tree gets.
//!
//! Besides the chain (skeleton clouds, spectral ones, then clumps), the report measures the
//! skeleton-only chain's coarse levels (`skeleton_levels`, for comparison at equal billboard
//! counts) and the spectral levels rebuilt with each description type and as plain SCA
//! (`description_types`).

pub mod charts;
pub mod data;
pub mod orders;

use crate::app::commands::tree_report::charts::{contact_sheet, motion_plot, plot};
use crate::app::commands::tree_report::data::{
    AtCount, DescriptionReport, FULL_TREE_PX, LIGHTING_PX, LevelReport, StaticCloudReport, THESIS,
    ThesisRow, TreeReport, at_billboards, lighting_table, thesis_table,
};
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
use std::path::Path;

/// What every level is measured with: the adapter, its fragment counter and the size of the
/// colour metric's pictures.
struct Metric<'g> {
    gpu: &'g Gpu,
    overdraw: crate::measure::colour_error::GpuColourError<'g>,
    size: [u32; 2],
}

/// Builds the chain of `tree`, measures it with the colour metric's pictures `size` pixels
/// large ([`data::METRIC_SIZE`], the thesis's, unless asked otherwise) and writes the files into
/// `out`.
pub fn run(tree: &Model, out: &Path, size: [u32; 2]) -> Result<TreeReport> {
    let f = foliage(tree).map_err(|e| anyhow!("{}: {e}", tree.name))?;
    crate::atomic::make_folder(out)?;
    let gpu = Gpu::headless()?;
    let raster = crate::render::atlas::AtlasRasterizer::new(&gpu);
    let h = tree_height(tree);
    let start = std::time::Instant::now();
    let opts = ChainOptions::default();
    let chain = tree_chain(&raster, tree, &f, &opts, &|_| {})?;
    let chain_seconds = start.elapsed().as_secs_f64();
    // One measuring world for the tree, its levels swapped in one by one.
    let metric = Metric {
        gpu: &gpu,
        overdraw: crate::measure::colour_error::GpuColourError::new(&gpu),
        size,
    };
    let mut levels = Vec::new();
    for (k, l) in chain.iter().enumerate() {
        levels.push(measure_level(&metric, tree, k, l, "")?);
    }
    let (skeleton_chain, skeleton_levels) =
        skeleton_chain(&metric, &raster, tree, &f, &chain, &opts)?;
    let description_types = description_types(&raster, tree, &f, &chain, &opts)?;
    let static_clouds = static_clouds(&metric, &raster, tree, &f, &chain)?;
    let clouds: Vec<(usize, &crate::bake::foliage::billboard::chain::CloudLevel)> = chain
        .iter()
        .enumerate()
        .filter(|(_, l)| l.cloud.billboards > 0 && l.cloud.impostor.is_none())
        .map(|(k, l)| (k, &l.cloud))
        .collect();
    let lighting =
        crate::measure::foliage_lighting::foliage_lighting(&gpu, tree, &clouds, LIGHTING_PX)?;
    let colours = crate::measure::material_share::MaterialColours::of(tree);
    let material_shares = if colours.len() >= 2 {
        crate::measure::material_share::material_shares(&gpu, tree, &colours, &clouds, LIGHTING_PX)?
    } else {
        Vec::new()
    };
    for l in &material_shares {
        eprintln!(
            "lodlab: {} L{}: foliage pixels by material {} (full tree {})",
            tree.name,
            l.level,
            percentages(&colours.names, &l.shares),
            percentages(&colours.names, &l.full)
        );
    }
    let orders = orders::orders(&raster, &metric.overdraw, tree, &chain, &opts)?;
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
        .map(|&(billboards, _)| clumps_at_count(&metric, &raster, tree, &f, &opts, billboards))
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
            "binary coverage masks at {}x{}, {} views round the tree at ground level, {} times over the loop; of the pixels either covers, the share that differ (0 the same, 1 nothing in common)",
            size[0],
            size[1],
            crate::measure::colour_error::METRIC_VIEWS,
            crate::measure::colour_error::METRIC_FRAMES
        ),
        static_clouds,
        skeleton_levels,
        description_types,
        against_thesis,
        lighting,
        orders,
        wind: data::wind(tree),
        materials: colours.names.clone(),
        material_shares,
    };
    eprintln!("lodlab: {}: wind: {}", tree.name, report.wind);
    write_files(&gpu, &report, &chain, &skeleton_chain, out)?;
    Ok(report)
}

/// Writes the report's files into `out`: the JSON, the tables and the charts.
fn write_files(
    gpu: &Gpu,
    report: &TreeReport,
    chain: &[TreeLevel],
    skeleton_chain: &[TreeLevel],
    out: &Path,
) -> Result<()> {
    write_atomic(
        &out.join("report.json"),
        crate::app::json::pretty(report)?.as_bytes(),
    )?;
    write_atomic(
        &out.join("against-thesis.md"),
        thesis_table(report).as_bytes(),
    )?;
    write_atomic(&out.join("lighting.md"), lighting_table(report).as_bytes())?;
    if !report.material_shares.is_empty() {
        write_atomic(
            &out.join("materials.md"),
            data::materials_table(report).as_bytes(),
        )?;
    }
    write_atomic(
        &out.join("orders.md"),
        orders::orders_table(&report.orders).as_bytes(),
    )?;
    orders::orders_plot(&report.orders, &out.join("error-per-cost.png"))?;
    orders::chains_plot(&report.orders, &out.join("chains-error-per-cost.png"))?;
    plot(report, &out.join("colour-error.png"))?;
    contact_sheet(gpu, chain, report, &out.join("levels.png"))?;
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
    motion_plot(report, pair, &out.join("motion.png"))?;
    Ok(())
}

/// The skeleton-only chain of `tree`, and its levels measured where it parts from `chain`.
fn skeleton_chain(
    metric: &Metric<'_>,
    raster: &crate::render::atlas::AtlasRasterizer,
    tree: &Model,
    f: &Foliage,
    chain: &[TreeLevel],
    opts: &ChainOptions,
) -> Result<(Vec<TreeLevel>, Vec<LevelReport>)> {
    let skeleton_opts = ChainOptions {
        style: ChainStyle::Skeleton,
        ..*opts
    };
    let skeleton_chain = tree_chain(raster, tree, f, &skeleton_opts, &|_| {})?;
    let mut levels = Vec::new();
    for (k, l) in skeleton_chain.iter().enumerate() {
        if chain.get(k).is_some_and(|c| c.kind == l.kind) {
            continue;
        }
        levels.push(measure_level(metric, tree, k, l, "skeleton-only ")?);
    }
    Ok((skeleton_chain, levels))
}

/// "leaf 84.0%, blossom 16.0%".
fn percentages(names: &[String], shares: &[f32]) -> String {
    names
        .iter()
        .zip(shares)
        .map(|(n, s)| format!("{n} {:.1}%", 100.0 * s))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A level of a chain with its colour error and its fragments per covered pixel (measured
/// through `metric`), said on stderr as it goes.
fn measure_level(
    metric: &Metric<'_>,
    tree: &Model,
    k: usize,
    l: &TreeLevel,
    what: &str,
) -> Result<LevelReport> {
    let h = tree_height(tree);
    // Where the level comes in, and its errors there (none for the full tree, level 0).
    let (error, switch_px, from_switch, at_switch) = if l.epsilon > 0.0 {
        let px = ChainOptions::default().tolerance_px * h / l.epsilon;
        let e = at_switch(metric.gpu, tree, &l.cloud, metric.size, px)?;
        (e.close, px, e.from_switch, e.at_switch)
    } else {
        let close = colour_error(metric.gpu, tree, &l.cloud, metric.size)?;
        (close, 0.0, 0.0, 0.0)
    };
    let anim = &l.cloud.animation;
    let bake = l
        .cloud
        .bake()
        .map_err(|e| anyhow::anyhow!("{}: {e}", tree.name))?;
    let overdraw = metric
        .overdraw
        .fragments_per_covered_pixel(
            tree,
            &l.cloud.model,
            bake,
            if switch_px > 0.0 {
                switch_px
            } else {
                FULL_TREE_PX
            },
        )?
        .map(|f| f as f32);
    eprintln!(
        "lodlab: {} {what}L{k}: ε {:.4} h, {} billboards{}, colour error {:.3} ({:.3} from the switch distance, {:.3} at {:.0} px), animation error {:.4} h / {:.3}, {} fragments per pixel it covers",
        tree.name,
        l.epsilon / h,
        l.cloud.billboards,
        if l.cloud.drawn_area > 0.0 && l.cloud.area > 0.0 {
            format!(
                " ({:.0}% of their area drawn)",
                100.0 * l.cloud.drawn_area / l.cloud.area
            )
        } else {
            String::new()
        },
        error,
        from_switch,
        at_switch,
        switch_px,
        anim.rms,
        anim.spectral,
        overdraw.map_or("?".into(), |f| format!("{f:.1}"))
    );
    Ok(LevelReport {
        epsilon: l.epsilon / h,
        epsilon_m: l.epsilon,
        grouping: CloudKind::name(l.kind.as_ref()),
        billboards: l.cloud.billboards,
        drawn_billboards: l.cloud.drawn_billboards(),
        triangles: l.cloud.model.mesh.triangle_count(),
        area: l.cloud.area,
        drawn_area: l.cloud.drawn_area,
        fragments_per_covered_pixel: overdraw,
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
    metric: &Metric<'_>,
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
    let e = at_switch(metric.gpu, tree, &level, metric.size, px)?;
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
    metric: &Metric<'_>,
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
        let error = colour_error_over(metric.gpu, &still, &cloud, metric.size, 1)?;
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

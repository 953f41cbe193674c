//! What `lodlab report` measures of a tree, as plain data, and the tables it is compared by:
//! its chain's levels, the description types, static clouds, and the thesis's own figures.

use serde::Serialize;

/// The colour metric's image size (thesis §5.1.3).
pub const METRIC_SIZE: [u32; 2] = [800, 600];

/// The height, pixels, the full tree is drawn at for its fragments per covered pixel (it has
/// no switch size of its own): about as high as the metric's pictures show it.
pub const FULL_TREE_PX: f32 = 400.0;

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
    /// The area the billboards are drawn with, trimmed round their leaves, m².
    pub drawn_area: f32,
    /// Fragments the level shades per pixel it covers, drawn as high as where it comes in
    /// (the full tree: [`FULL_TREE_PX`] high), over the metric's views; None where the
    /// adapter cannot count fragments.
    pub fragments_per_covered_pixel: Option<f32>,
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
    /// as one (flat) and through their atlases, the tree [`LIGHTING_PX`] pixels high.
    pub lighting: Vec<crate::measure::foliage_lighting::LevelLighting>,
    /// The levels each switch size draws by ε and by error per cost.
    pub orders: super::orders::OrdersReport,
    /// What wind the tree gets (see [`wind`]).
    pub wind: String,
    /// The colours its foliage is told apart by (its cut-out materials, alike ones as one),
    /// and each cloud level's share of foliage pixels by them against the full tree's, the
    /// foliage [`LIGHTING_PX`] pixels high (empty where there is only one colour).
    pub materials: Vec<String>,
    pub material_shares: Vec<crate::measure::material_share::LevelShares>,
}

/// What wind `tree` gets, in words: lodlab plays a tree's own first clip, looped, and rigs
/// nothing; a tree without one (most files from public collections: a mesh and no skin)
/// stands still.
pub fn wind(tree: &crate::model::Model) -> String {
    let moving = tree.clips.iter().find(|c| !c.channels.is_empty());
    match moving {
        Some(c) => format!(
            "its own clip \"{}\" ({:.1} s, looped, on {} bone{}), its sway scaled by --wind",
            c.name,
            c.duration,
            tree.skeleton.bone_count(),
            if tree.skeleton.bone_count() == 1 {
                ""
            } else {
                "s"
            }
        ),
        None => "none: the file has no animation, and lodlab rigs no tree, so it stands still \
                 (its animation error is then only how far its leaves were moved onto their \
                 billboards)"
            .into(),
    }
}

/// `materials.md`: each cloud level's share of foliage pixels by material colour beside the
/// full tree's.
pub fn materials_table(report: &TreeReport) -> String {
    let mut out = format!(
        "# {}: foliage pixels by material\n\nEach cut-out material's share of the foliage's \
         pixels (told apart by colour; alike materials as one), the foliage {LIGHTING_PX} px \
         high from {} views round the tree. Worst: the largest relative difference of a \
         share from the full tree's.\n\n| level |",
        report.model,
        crate::measure::colour_error::METRIC_VIEWS
    );
    for name in &report.materials {
        out.push_str(&format!(" {name} |"));
    }
    out.push_str(" worst |\n|---|");
    out.push_str(&"---:|".repeat(report.materials.len() + 1));
    out.push('\n');
    if let Some(first) = report.material_shares.first() {
        out.push_str("| full tree |");
        for s in &first.full {
            out.push_str(&format!(" {:.1}% |", 100.0 * s));
        }
        out.push_str(" |\n");
    }
    for l in &report.material_shares {
        out.push_str(&format!("| L{} |", l.level));
        for s in &l.shares {
            out.push_str(&format!(" {:.1}% |", 100.0 * s));
        }
        out.push_str(&format!(" {:.0}% |\n", 100.0 * l.worst()));
    }
    out
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
         billboards lit as one (flat, by their leaves' mean normal) and per texel through their \
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_report_says_what_wind_a_tree_gets() {
        let mut tree = crate::generate::tree::sapling();
        let w = wind(&tree);
        assert!(w.starts_with("its own clip \"wind\""), "{w}");
        // A file of a mesh and no animation (most trees from public collections).
        for clip in &mut tree.clips {
            clip.channels.clear();
        }
        assert!(wind(&tree).starts_with("none: the file has no animation"));
        tree.clips.clear();
        assert!(wind(&tree).starts_with("none"));
    }
}

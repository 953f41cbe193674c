//! What `lodlab report` measures, as plain data: the options, each method's curve of error
//! against triangles and its levels, the comparisons between methods, and the report itself.

use crate::bake::character::lod_error::Correspondence;
use crate::model::Model;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Points per curve, spaced evenly in log(influences) from full detail to the coarsest mesh.
pub const CURVE_POINTS: usize = 40;
/// Errors below this (in scene units) are rounding, not simplification: full detail.
pub(crate) const NEGLIGIBLE: f64 = 1e-9;
/// Surface samples the error is averaged over.
pub const SAMPLES: usize = 6000;
/// Tolerances in pixels at which every level's silhouette is compared with full detail.
pub const SILHOUETTE_TOLERANCES: [f32; 3] = [1.5, 4.0, 8.0];
/// Poses (spread over the clips) the silhouettes are compared in, each from
/// [`crate::bake::character::silhouette::VIEWS`].
pub(crate) const SILHOUETTE_POSES: usize = 3;

#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// The character, as imported.
    pub model: crate::model::Model,
    /// Triangle budgets its levels are cut by (`--levels triangles:…`); `None`: by error.
    pub budgets: Option<Vec<u32>>,
    pub out: PathBuf,
    pub baseline_meshopt: bool,
    pub progress: bool,
    /// Where the levels are read from, and baked into where missing (`--cache`): a run
    /// after the first measures without baking again.
    pub cache: crate::bake::cache::LodCache,
    /// The hash of the model's source, the levels' cache key (`Imported::source_hash`).
    pub source: [u8; 32],
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
    /// rest-pose baked on the same mesh in another order ([`reordered`](crate::app::commands::report::reordered)) that lies at or
    /// under rest-pose's. Where steps of nearly equal cost abound, which comes first is
    /// decided by order and rounding, and the fraction strays far from 100% (or 50%) for
    /// that alone: read `as_le_rest_pose` against it.
    pub reordered_le_rest_pose: Option<f64>,
    /// The noise band: the median of |rest-pose reordered / rest-pose − 1| over its curve.
    pub noise: Option<f64>,
    /// Fraction of the AS curve no further above rest-pose than the reordered rest-pose strays
    /// from it there: AS ≤ rest-pose × (1 + band), the band the local one of [`local_band`](crate::app::commands::report::compare::local_band)
    /// (the largest deviation of the nearest reordered points, at least `noise`).
    pub as_le_rest_pose_within_noise: Option<f64>,
    /// `as_le_rest_pose` over the part of the curve the viewer's levels span: down to the
    /// coarsest level of AS or rest-pose, not on to the end of the sequence.
    pub as_le_rest_pose_at_levels: Option<f64>,
    /// The median of AS / rest-pose over the AS curve: below 1 where AS is better on most
    /// of it, by how much.
    pub as_over_rest_pose: Option<f64>,
    /// The largest ratio, over AS+IS's levels, of a level's colour error (by vertex normals,
    /// through the renderer) to AS's at the same total influences ([`lighting_at`](crate::app::commands::report::compare::lighting_at)), where
    /// either shows at least [`VISIBLE_COLOUR`](crate::app::commands::report::compare::VISIBLE_COLOUR); `None` where nothing was drawn or no level
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
    /// Rest-pose's curve on the same mesh in another order ([`reordered`](crate::app::commands::report::reordered)): the noise
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
                "its clips barely move it (at most {:.1} mm, {:.2}% of its height): AS measures \
                 what rest-pose does, their curves apart only by the order of equal steps",
                self.motion * 1e3,
                self.motion_share * 100.0
            )
        })
    }
}

/// How far `model`'s clips take its vertices from the rest pose (see [`Report::motion`]).
pub(crate) fn motion(model: &Model) -> (f64, f64) {
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

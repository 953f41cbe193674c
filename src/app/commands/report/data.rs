//! What `lodlab report` measures, as plain data: the options, each method's curve of error
//! against triangles and its levels, the comparisons between methods, and the report itself.

use crate::app::viewer::figures::thousands;
use crate::bake::character::lod_error::Correspondence;
use crate::model::Model;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Points per curve, spaced evenly in log(influences) from full detail to the coarsest mesh.
pub const CURVE_POINTS: usize = 40;
/// Tie orders each method is baked in (`--orders`): the band of every curve.
pub const ORDERS: u32 = crate::app::cli::REPORT_ORDERS;
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
    /// Tie orders each method is baked in ([`ORDERS`] by default): 1 draws no band.
    pub orders: u32,
    pub progress: bool,
    /// Where the levels are read from, and baked into where missing (`--cache`): a run
    /// after the first measures without baking again.
    pub cache: crate::bake::cache::LodCache,
    /// The hash of the model's source, the levels' cache key (`Imported::source_hash`).
    pub source: [u8; 32],
}

/// A point of a method's error curve: over the tie orders that reach it, the median RMS
/// error and the lowest and highest (the band), and the median largest error.
#[derive(Clone, Debug, Serialize)]
pub struct CurvePoint {
    pub influences: u32,
    pub triangles: u32,
    pub rms_error: f64,
    pub rms_low: f64,
    pub rms_high: f64,
    pub max_error: f64,
    /// The tie orders whose sequences reach this far.
    pub orders: u32,
}

#[derive(Clone, Debug, Serialize)]
pub struct MethodReport {
    /// Wall time of the whole bake: the simplification and cutting the levels.
    pub bake_seconds: f64,
    /// Wall time of the simplifications in the other tie orders, and measuring them.
    pub orders_seconds: f64,
    pub cache_hit_rate: Option<f64>,
    /// The median width of the curve's band: (highest − lowest) / median over the orders.
    pub band: Option<f64>,
    pub curve: Vec<CurvePoint>,
    /// The levels the viewer uses, with their silhouettes.
    pub levels: Vec<LevelReport>,
    /// Every level but full detail's colour error against full detail, lit by its vertex
    /// normals and through its normal map, [`SHADING_PX`] high (empty where no GPU adapter
    /// could draw them).
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

/// How the methods compare at equal influence counts (Merry et al.'s Figure 7 read at equal
/// influences), counting only the points where two methods' bands separate: where they
/// overlap, the tie orders alone part the curves as far ([`Separation`]).
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// Of the AS curve's points where its band and rest-pose's separate, the share where AS is
    /// better.
    pub as_le_rest_pose: Option<f64>,
    /// The same for AS+IS against AS.
    pub as_is_le_as: Option<f64>,
    /// The same for meshopt against rest-pose.
    pub meshopt_le_rest_pose: Option<f64>,
    /// `as_le_rest_pose` over the part of the curve the viewer's levels span: down to the
    /// coarsest level of AS or rest-pose, not on to the end of the sequence.
    pub as_le_rest_pose_at_levels: Option<f64>,
    /// Each pair ("as vs rest-pose", "as+is vs as", "meshopt vs rest-pose"): the shares of the
    /// first's curve better, indistinguishable and worse, and where.
    pub separations: BTreeMap<String, Separation>,
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
    /// Tie orders each method was baked in: its curve's band.
    pub orders: u32,
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
                 what rest-pose does, their curves apart only by the order of equal steps, \
                 within their bands",
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

/// How one method's band sits against another's at a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// Its highest order below the other's lowest.
    Better,
    /// The bands overlap: the tie orders alone part them as far.
    Indistinguishable,
    /// Its lowest order above the other's highest.
    Worse,
}

impl Verdict {
    pub(crate) fn word(self) -> &'static str {
        match self {
            Verdict::Better => "better",
            Verdict::Indistinguishable => "indistinguishable",
            Verdict::Worse => "worse",
        }
    }
}

/// A run of one verdict along the curve, from its first point's influence count to its last's.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Span {
    pub verdict: Verdict,
    pub from: u32,
    pub to: u32,
}

/// Method `a` against method `b` along `a`'s curve, where `b`'s reaches.
#[derive(Clone, Debug, Serialize)]
pub struct Separation {
    /// Shares of `a`'s points compared: better, indistinguishable, worse.
    pub better: f64,
    pub indistinguishable: f64,
    pub worse: f64,
    /// The verdicts in runs, from full detail down.
    pub spans: Vec<Span>,
    /// The runs in words: "as better than rest-pose from 7,645 to 2,500 influences,
    /// indistinguishable from 2,400 to 600, worse from 580 to 120".
    pub says: String,
}

impl Separation {
    /// The runs in short: "better 10,130–1,263, overlap 1,117–874, worse 773" (influences).
    pub fn runs(&self) -> String {
        self.spans
            .iter()
            .map(|s| {
                let word = match s.verdict {
                    Verdict::Better => "better",
                    Verdict::Indistinguishable => "overlap",
                    Verdict::Worse => "worse",
                };
                if s.from == s.to {
                    format!("{word} {}", thousands(u64::from(s.from)))
                } else {
                    format!(
                        "{word} {}–{}",
                        thousands(u64::from(s.from)),
                        thousands(u64::from(s.to))
                    )
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Of the points where the bands separate, the share where `a` is better; `None` where
    /// they never separate.
    pub fn better_where_separate(&self) -> Option<f64> {
        let separate = self.better + self.worse;
        (separate > 0.0).then(|| self.better / separate)
    }
}

//! Levels of detail as plain data: the options they are cut by, a level (its mesh, its error
//! bound and its geomorph map), and a model's levels by one method.

use crate::bake::character::simplify::{Method, Sequence};
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use crate::model::Model;
use serde::{Deserialize, Serialize};

/// Poses the simplifier checks every collapse in, and a level's error is measured over.
pub const POSE_SAMPLES: usize = 16;

/// How levels are cut from a sequence.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LodOptions {
    /// `e_1`, in scene units; `e_k = e_1 · 2^(k−1)`.
    pub base_error: f32,
    /// No level goes below this many triangles (unless the full-detail mesh has fewer).
    pub floor_triangles: u32,
    /// Cut by triangle budgets instead of errors: level k is the first prefix within
    /// `budgets[k−1]` triangles.
    pub budgets: Option<Vec<u32>>,
}

impl LodOptions {
    /// The tolerance a user gives in pixels, for a model whose height fills a 1000-pixel
    /// viewport: `e_1 = px · height / 1000`.
    pub fn from_pixels(px: f32, model_height: f32) -> LodOptions {
        LodOptions {
            base_error: px * model_height / 1000.0,
            floor_triangles: 100,
            budgets: None,
        }
    }
}

/// The model's rest-pose height in scene units.
pub fn model_height(model: &Model) -> f32 {
    let root = model.skeleton.root_transform;
    crate::model::Bounds::of(
        model
            .mesh
            .positions
            .iter()
            .map(|p| root.transform_point3(*p)),
    )
    .map_or(1.0, |b| b.size().y.max(1e-3))
}

/// The level options for a model from the command's options.
pub fn lod_options(model: &Model, tolerance_px: f32, budgets: Option<&[u32]>) -> LodOptions {
    let mut o = LodOptions::from_pixels(tolerance_px, model_height(model));
    o.budgets = budgets.map(<[u32]>::to_vec);
    o
}

/// One level of detail.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LodLevel {
    /// How many steps of the sequence it applies.
    pub prefix: u32,
    /// The level's error in scene units: the larger of `bound` and the measured distance
    /// from full detail (see the module comment). What the renderer projects to pixels.
    pub error: f32,
    /// The memoryless bound: the largest step cost so far.
    pub bound: f32,
    /// Vertices with their influences at this level and the triangles, in GPU-friendly order.
    pub mesh: AnimationSpaceMesh,
    /// For every vertex, which render vertex of the full-detail mesh it is.
    pub source: Vec<u32>,
    /// For every vertex, the vertex of the next coarser level it morphs into; empty on the
    /// coarsest level.
    pub geomorph: Vec<u32>,
}

impl LodLevel {
    pub fn triangles(&self) -> usize {
        self.mesh.triangle_count()
    }

    pub fn vertices(&self) -> usize {
        self.mesh.vertex_count()
    }

    pub fn influences(&self) -> usize {
        self.mesh.influences.len()
    }
}

/// The last prefix of `seq` with at least `opts.floor_triangles` triangles (or the full
/// detail's count if that is lower).
pub fn last_above_floor(seq: &Sequence, opts: &LodOptions) -> usize {
    let floor = opts.floor_triangles.min(seq.base_triangle_count());
    // Triangles never grow along the sequence: the search is binary.
    seq.steps.partition_point(|s| s.triangles >= floor)
}

/// The fewest triangles any level of `seq` can have under `opts`: budgets below it all
/// become the same level.
pub fn floor_triangles(seq: &Sequence, opts: &LodOptions) -> u32 {
    seq.triangles_after(last_above_floor(seq, opts))
}

/// A model's levels of detail by one method, with the sequence they were cut from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SkinnedLods {
    pub model: String,
    pub method: Method,
    pub options: LodOptions,
    pub levels: Vec<LodLevel>,
    pub sequence: Sequence,
    /// Wall time of the bake (estimating `P`, the simplification and cutting the levels), in
    /// seconds.
    pub bake_seconds: f64,
}

//! The simplifier's output: every step in order with its cost and the running maximum (the
//! memoryless bound of Merry et al. §4), from which levels and geomorphs are cut.

use super::input::Method;
use crate::bake::gpu_data::animation_space::AsInfluence;
use serde::{Deserialize, Serialize};

/// What one step of the sequence did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum StepKind {
    /// Half-edge collapse: every wedge `[from, to]` of the removed position goes to the wedge
    /// of the kept position in the same chart (render vertex indices).
    Collapse { wedges: Vec<[u32; 2]> },
    /// Influence simplification of one position: its render vertices (the wedges) take
    /// `influences` from now on, one list a wedge. The lists share their `p_i` (one point)
    /// and differ in their normals' `n_i`, as the wedges did (a hard edge stays hard).
    Influence {
        wedges: Vec<u32>,
        removed_bone: u32,
        influences: Vec<Vec<AsInfluence>>,
    },
    /// A whole connected part removed: its render vertices still in use, and the render vertex
    /// nearby (on another part) its geomorph shrinks it towards; `None` when nothing is left.
    Prune {
        wedges: Vec<u32>,
        anchor: Option<u32>,
    },
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Step {
    pub kind: StepKind,
    /// The memoryless deviation of this step alone, in scene units.
    pub cost: f32,
    /// The largest cost so far: the error bound quoted for the mesh after this step.
    pub max_cost: f32,
    /// Triangles and total influences (over used render vertices) after this step.
    pub triangles: u32,
    pub influences: u32,
}

/// A progressive mesh: the starting mesh and every simplification in order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sequence {
    pub method: Method,
    /// For every render vertex, the position it belongs to (see [`mesh::weld_positions`](super::mesh::weld_positions)).
    pub positions: Vec<u32>,
    /// The triangles the sequence starts from: the input without triangles that repeat a
    /// position or duplicate another.
    pub base_triangles: Vec<[u32; 3]>,
    pub base_influences: u32,
    pub steps: Vec<Step>,
    pub stats: Stats,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    pub dropped_triangles: u32,
    /// Positions that never move: complex or locked kinds.
    pub locked_positions: u32,
    /// Some triangles have texture coordinates usable as a parameterisation (the others use
    /// the geometric correspondence).
    pub texture_parameterisation: bool,
    /// Connected parts at the start, and how many were removed whole.
    pub parts: u32,
    pub pruned_parts: u32,
    /// Influence-simplification factor cache (§6.3).
    pub cache_hits: u64,
    pub cache_misses: u64,
    /// Collapse candidates evaluated, and re-checked when popped.
    pub evaluations: u64,
}

impl Stats {
    pub fn cache_hit_rate(&self) -> Option<f64> {
        let total = self.cache_hits + self.cache_misses;
        (total > 0).then(|| self.cache_hits as f64 / total as f64)
    }
}

impl Sequence {
    pub fn base_triangle_count(&self) -> u32 {
        self.base_triangles.len() as u32
    }

    /// Triangles after the first `prefix` steps.
    pub fn triangles_after(&self, prefix: usize) -> u32 {
        match prefix {
            0 => self.base_triangle_count(),
            n => self.steps[n - 1].triangles,
        }
    }

    pub fn influences_after(&self, prefix: usize) -> u32 {
        match prefix {
            0 => self.base_influences,
            n => self.steps[n - 1].influences,
        }
    }

    /// The error bound after the first `prefix` steps.
    pub fn error_after(&self, prefix: usize) -> f32 {
        match prefix {
            0 => 0.0,
            n => self.steps[n - 1].max_cost,
        }
    }
}

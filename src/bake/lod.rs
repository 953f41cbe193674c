//! Discrete levels of detail cut from a progressive mesh, with geomorph maps between them.
//!
//! A [`Sequence`] is every simplification in order. Level k is the longest prefix whose error
//! bound stays within `e_k`, with `e_k` doubling from a base tolerance (or the first prefix
//! within a triangle budget), down to a floor of about a hundred triangles. Each level holds
//! its render vertices with their animation-space influences *at that level* (influence
//! simplification changes them), its triangles, and a geomorph map: for every vertex, the
//! vertex of the next coarser level it ends up as, following the half-edge collapses in
//! between (Houle & Poulin §5.1). A renderer can then morph any vertex of level k towards level
//! k+1 with `v = (1−t)·Σ G_i p_i(fine) + t·Σ G_j p_j(coarse)` (Merry et al. §6.4).

use super::animation_space::{AnimationSpaceMesh, AsInfluence};
use super::simplify::expectation::ExpectationMatrix;
use super::simplify::mesh::Mesh;
use super::simplify::{Method, Sequence, SimplifyInput, StepKind, influences64, simplify};
use crate::model::Model;
use serde::{Deserialize, Serialize};

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

/// One level of detail.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LodLevel {
    /// How many steps of the sequence it applies.
    pub prefix: u32,
    /// The error bound (largest step cost so far), in scene units.
    pub error: f32,
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

/// The prefixes of `seq` that become levels, finest first (always starting with 0).
pub fn choose_prefixes(seq: &Sequence, opts: &LodOptions) -> Vec<usize> {
    let steps = seq.steps.len();
    let floor = opts.floor_triangles.min(seq.base_triangle_count());
    // Triangles never grow along the sequence and the error bound never falls, so both
    // searches are binary.
    let last_above_floor = seq.steps.partition_point(|s| s.triangles >= floor);
    let mut out = vec![0usize];
    let push = |p: usize, out: &mut Vec<usize>| {
        if p > *out.last().unwrap() {
            out.push(p);
        }
    };
    match &opts.budgets {
        Some(budgets) => {
            let mut budgets = budgets.clone();
            budgets.sort_unstable_by(|a, b| b.cmp(a));
            for b in budgets {
                let first = seq.steps.partition_point(|s| s.triangles > b) + 1;
                push(first.min(steps).min(last_above_floor), &mut out);
            }
        }
        None => {
            let mut e = opts.base_error.max(f32::MIN_POSITIVE);
            loop {
                let within = seq.steps.partition_point(|s| s.max_cost <= e);
                let p = within.min(last_above_floor);
                push(p, &mut out);
                if p >= last_above_floor || !e.is_finite() {
                    break;
                }
                e *= 2.0;
            }
        }
    }
    out
}

/// Replays a sequence step by step on the full-detail mesh.
pub struct Replay<'a> {
    base: &'a AnimationSpaceMesh,
    seq: &'a Sequence,
    mesh: Mesh,
    /// Influences of every render vertex as of the steps applied.
    influences: Vec<Vec<AsInfluence>>,
    /// Where each render vertex went when its position collapsed.
    collapsed_to: Vec<u32>,
    applied: usize,
}

impl<'a> Replay<'a> {
    pub fn new(base: &'a AnimationSpaceMesh, seq: &'a Sequence) -> Replay<'a> {
        let mesh = Mesh::new(&base.indices, &influences64(base));
        let n = base.vertex_count();
        Replay {
            base,
            seq,
            mesh,
            influences: (0..n).map(|v| base.influences_of(v).to_vec()).collect(),
            collapsed_to: vec![u32::MAX; n],
            applied: 0,
        }
    }

    /// Applies steps until `prefix` of them are applied (never goes back).
    pub fn advance_to(&mut self, prefix: usize) {
        while self.applied < prefix.min(self.seq.steps.len()) {
            match &self.seq.steps[self.applied].kind {
                StepKind::Collapse { wedges } => {
                    let u1 = self.mesh.pos(wedges[0][0]);
                    let u2 = self.mesh.pos(wedges[0][1]);
                    self.mesh.collapse(u1, u2, wedges);
                    for &[from, to] in wedges {
                        self.collapsed_to[from as usize] = to;
                    }
                }
                StepKind::Influence {
                    wedges, influences, ..
                } => {
                    for &w in wedges {
                        self.influences[w as usize] = influences.clone();
                    }
                }
            }
            self.applied += 1;
        }
    }

    /// The current triangles, as render vertices of the full-detail mesh.
    pub fn triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.mesh
            .tris
            .iter()
            .zip(&self.mesh.tri_alive)
            .filter(|(_, a)| **a)
            .map(|(t, _)| *t)
    }

    pub fn influences_of(&self, r: u32) -> &[AsInfluence] {
        &self.influences[r as usize]
    }

    pub fn is_used(&self, r: u32) -> bool {
        self.mesh.refs[r as usize] > 0
    }

    /// The render vertex `r` has become: followed through the collapses applied so far.
    pub fn follow(&self, mut r: u32) -> u32 {
        while !self.is_used(r) && self.collapsed_to[r as usize] != u32::MAX {
            r = self.collapsed_to[r as usize];
        }
        r
    }

    /// The current mesh as a compact level: used vertices only, GPU order.
    fn snapshot(&self, prefix: usize) -> LodLevel {
        let n = self.base.vertex_count();
        let mut local = vec![u32::MAX; n];
        let mut used: Vec<u32> = Vec::new();
        let mut indices = Vec::with_capacity(self.mesh.alive_triangles * 3);
        for t in self.triangles() {
            for r in t {
                if local[r as usize] == u32::MAX {
                    local[r as usize] = used.len() as u32;
                    used.push(r);
                }
                indices.push(local[r as usize]);
            }
        }
        let mut compact = AnimationSpaceMesh {
            offsets: vec![0],
            influences: Vec::new(),
            uvs: used.iter().map(|&r| self.base.uvs[r as usize]).collect(),
            materials: used
                .iter()
                .map(|&r| self.base.materials[r as usize])
                .collect(),
            indices,
            spectral_rows: Vec::new(),
        };
        for &r in &used {
            compact.influences.extend_from_slice(self.influences_of(r));
            compact.offsets.push(compact.influences.len() as u32);
        }
        let (mesh, order) = compact.optimized_for_gpu_with_order();
        LodLevel {
            prefix: prefix as u32,
            error: self.seq.error_after(prefix),
            mesh,
            source: order.iter().map(|&i| used[i]).collect(),
            geomorph: Vec::new(),
        }
    }
}

/// Cuts the levels at `prefixes` (ascending) and links each to the next by its geomorph map.
pub fn extract(base: &AnimationSpaceMesh, seq: &Sequence, prefixes: &[usize]) -> Vec<LodLevel> {
    let mut replay = Replay::new(base, seq);
    let mut levels: Vec<LodLevel> = Vec::with_capacity(prefixes.len());
    for &prefix in prefixes {
        replay.advance_to(prefix);
        let level = replay.snapshot(prefix);
        if let Some(prev) = levels.last_mut() {
            let mut index = vec![u32::MAX; base.vertex_count()];
            for (i, &r) in level.source.iter().enumerate() {
                index[r as usize] = i as u32;
            }
            prev.geomorph = prev
                .source
                .iter()
                .map(|&r| {
                    let to = replay.follow(r);
                    match index[to as usize] {
                        u32::MAX => nearest_in_chart(base, &level, r),
                        i => i,
                    }
                })
                .collect();
        }
        levels.push(level);
    }
    levels
}

/// Fallback for a vertex whose collapse chain does not end in the next level (only possible
/// around degenerate input): the vertex of `level` nearest in texture space.
fn nearest_in_chart(base: &AnimationSpaceMesh, level: &LodLevel, r: u32) -> u32 {
    let uv = base.uvs[r as usize];
    (0..level.vertices())
        .min_by(|&a, &b| {
            let da = level.mesh.uvs[a].distance_squared(uv);
            let db = level.mesh.uvs[b].distance_squared(uv);
            da.total_cmp(&db)
        })
        .unwrap_or(0) as u32
}

/// A model's levels of detail by one method, with the sequence they were cut from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SkinnedLods {
    pub model: String,
    pub method: Method,
    pub options: LodOptions,
    pub levels: Vec<LodLevel>,
    pub sequence: Sequence,
    /// Wall time of the simplification (estimating `P` included), in seconds.
    pub bake_seconds: f64,
}

/// The full-detail mesh of `model` in animation space (GPU order) and its progressive mesh by
/// `method`, with the wall time the simplification took (estimating `P` included).
pub fn progressive_mesh(
    model: &Model,
    method: Method,
    progress: &dyn Fn(f32),
) -> (AnimationSpaceMesh, Sequence, f64) {
    let base = AnimationSpaceMesh::from_skinned(&model.mesh, &model.skeleton).optimized_for_gpu();
    let start = std::time::Instant::now();
    let expectation = match method {
        Method::RestPose => ExpectationMatrix::from_poses(0, std::iter::empty::<Vec<_>>()),
        _ => ExpectationMatrix::estimate(model),
    };
    let rest_bones = SimplifyInput::rest_bones(&model.skeleton);
    let input = SimplifyInput {
        mesh: &base,
        rest_bones: &rest_bones,
        expectation: &expectation,
    };
    let sequence = simplify(&input, method, progress);
    let seconds = start.elapsed().as_secs_f64();
    (base, sequence, seconds)
}

/// Builds the progressive mesh of `model` by `method` and cuts its levels.
pub fn bake_lods(
    model: &Model,
    method: Method,
    opts: &LodOptions,
    progress: &dyn Fn(f32),
) -> SkinnedLods {
    let (base, sequence, bake_seconds) = progressive_mesh(model, method, progress);
    let prefixes = choose_prefixes(&sequence, opts);
    let levels = extract(&base, &sequence, &prefixes);
    SkinnedLods {
        model: model.name.clone(),
        method,
        options: opts.clone(),
        levels,
        sequence,
        bake_seconds,
    }
}

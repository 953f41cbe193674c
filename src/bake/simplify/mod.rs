//! Progressive meshes of skinned characters, simplified in animation space.
//!
//! Implements, as one engine with three metrics:
//! - Merry, Marais & Gain, "Analytic simplification of animated characters" (2008), §4:
//!   progressive meshes by half-edge collapse ranked with the memoryless appearance-preserving
//!   deviation of Sander et al. (2001), measured with the L2,2 metric of animation space;
//! - the same paper, §5 and §5.1: influence simplification, interleaved with the collapses in
//!   one priority queue;
//! - and, as the baseline the paper compares against, the same collapses ranked by Euclidean
//!   deviation in the rest pose.
//!
//! Layout follows meshoptimizer's `simplifier.cpp`: flat arrays ([`mesh::Mesh`]), a table of
//! which vertex kinds may collapse onto which ([`mesh::CAN_COLLAPSE`]), and a lazily updated
//! binary heap. The output is a [`Sequence`]: every step in order with its cost and the running
//! maximum, from which [`crate::bake::lod`] cuts discrete levels and geomorph maps.

pub mod collapse;
pub mod expectation;
pub mod influence;
pub mod mesh;

use crate::bake::animation_space::{AnimationSpaceMesh, AsInfluence};
use collapse::{Context, Corner, Flattening, Parameterisation, Scratch};
use expectation::{ExpectationMatrix, quadratic};
use glam::{Affine3A, DVec2, DVec3, Vec3, Vec4};
use influence::{FactorCache, Influence64};
use mesh::{Kind, Mesh};
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};
use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

/// The three ways of ranking simplifications the paper compares.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
pub enum Method {
    /// Edge collapses ranked by Euclidean deviation in the rest pose ("3D" in Table 1).
    #[serde(rename = "rest-pose")]
    RestPose,
    /// Edge collapses ranked by the L2,2 deviation in animation space (§4).
    #[serde(rename = "as")]
    AnimationSpace,
    /// As `AnimationSpace`, with influence simplifications in the same queue (§5).
    #[serde(rename = "as+is")]
    InfluenceSimplification,
}

impl Method {
    pub const ALL: [Method; 3] = [
        Method::RestPose,
        Method::AnimationSpace,
        Method::InfluenceSimplification,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::RestPose => "rest-pose",
            Method::AnimationSpace => "as",
            Method::InfluenceSimplification => "as+is",
        }
    }

    pub fn parse(s: &str) -> Option<Method> {
        Method::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s.trim()))
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What one step of the sequence did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum StepKind {
    /// Half-edge collapse: every wedge `[from, to]` of the removed position goes to the wedge
    /// of the kept position in the same chart (render vertex indices).
    Collapse { wedges: Vec<[u32; 2]> },
    /// Influence simplification of one position: its render vertices (the wedges) all take
    /// `influences` from now on.
    Influence {
        wedges: Vec<u32>,
        removed_bone: u32,
        influences: Vec<AsInfluence>,
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
    pub texture_parameterisation: bool,
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

/// What the simplifier needs to know about a character.
pub struct SimplifyInput<'a> {
    pub mesh: &'a AnimationSpaceMesh,
    /// The rest-pose bone matrices `Ĝ_i` in scene space (the root transform applied), so the
    /// rest-pose metric measures in the same units as the L2,2 one.
    pub rest_bones: &'a [Affine3A],
    pub expectation: &'a ExpectationMatrix,
}

impl SimplifyInput<'_> {
    /// `Ĝ_i` for every bone of `skeleton`, in scene space.
    pub fn rest_bones(skeleton: &crate::model::Skeleton) -> Vec<Affine3A> {
        skeleton
            .inverse_bind
            .iter()
            .map(|inv| skeleton.root_transform * Affine3A::from_mat4(inv.inverse()))
            .collect()
    }
}

/// A queue entry. Ordered by cost, then kind and vertex so that runs are deterministic.
#[derive(Clone, Copy, Debug)]
struct Entry {
    cost: f64,
    influence: bool,
    vertex: u32,
    version: u32,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        self.cost
            .total_cmp(&other.cost)
            .then(self.influence.cmp(&other.influence))
            .then(self.vertex.cmp(&other.vertex))
            .then(self.version.cmp(&other.version))
    }
}

/// The deviation measure at a cell corner.
enum Metric<'a> {
    /// Euclidean distance between rest-pose positions.
    RestPose,
    /// `‖s‖²₂,₂ = sᵀPs`. A corner is a combination `s = Σ c_a p_a` of at most four positions,
    /// so `sᵀPs = Σ c_a c_b (p_aᵀ P p_b)`: the inner products of neighbouring positions are
    /// computed once and cached (stamped with each position's influence version), which keeps
    /// the animation-space metric a small overhead on the rest-pose one.
    AnimationSpace {
        pm: &'a ExpectationMatrix,
        gram: FxHashMap<(u32, u32), (u32, u32, f64)>,
    },
}

impl Metric<'_> {
    fn deviation2(
        &mut self,
        corner: &Corner,
        rest: &[DVec3],
        infl: &[Vec<Influence64>],
        version: &[u32],
    ) -> f64 {
        match self {
            Metric::RestPose => corner
                .iter()
                .map(|&(p, c)| rest[p as usize] * c)
                .sum::<DVec3>()
                .length_squared(),
            Metric::AnimationSpace { pm, gram } => {
                let mut sum = 0.0;
                for i in 0..4 {
                    let (a, ca) = corner[i];
                    if ca == 0.0 {
                        continue;
                    }
                    for &(b, cb) in &corner[i..] {
                        if cb == 0.0 {
                            continue;
                        }
                        let key = (a.min(b), a.max(b));
                        let stamp = (version[key.0 as usize], version[key.1 as usize]);
                        let g = match gram.get(&key) {
                            Some(&(va, vb, g)) if (va, vb) == stamp => g,
                            _ => {
                                let g = inner(pm, &infl[key.0 as usize], &infl[key.1 as usize]);
                                gram.insert(key, (stamp.0, stamp.1, g));
                                g
                            }
                        };
                        sum += if a == b {
                            ca * cb * g
                        } else {
                            2.0 * ca * cb * g
                        };
                    }
                }
                sum.max(0.0)
            }
        }
    }
}

/// Every vertex's influences in double precision, sorted by bone (the order [`Mesh::new`]
/// groups wedges by and the factor cache keys on).
pub fn influences64(am: &AnimationSpaceMesh) -> Vec<Vec<Influence64>> {
    (0..am.vertex_count())
        .map(|v| {
            let mut list: Vec<Influence64> = am
                .influences_of(v)
                .iter()
                .map(|i| Influence64 {
                    bone: i.bone,
                    p: i.p.to_array().map(f64::from),
                    n: i.n.to_array().map(f64::from),
                })
                .collect();
            list.sort_by_key(|i| i.bone);
            list
        })
        .collect()
}

/// `aᵀ P b` for two vertices' influences.
fn inner(pm: &ExpectationMatrix, a: &[Influence64], b: &[Influence64]) -> f64 {
    let mut sum = 0.0;
    for x in a {
        for y in b {
            sum += quadratic(pm.block(x.bone, y.bone), &x.p, &y.p);
        }
    }
    sum
}

/// The rest-pose position of a vertex: `Σ Ĝ_i p_i`.
fn rest_position(rest_bones: &[Affine3A], infl: &[Influence64]) -> DVec3 {
    infl.iter()
        .map(|i| {
            let g = &rest_bones[i.bone as usize];
            let m = g.matrix3.to_cols_array().map(|x| x as f64);
            let t = DVec3::from(Vec3::from(g.translation));
            DVec3::new(
                m[0] * i.p[0] + m[3] * i.p[1] + m[6] * i.p[2],
                m[1] * i.p[0] + m[4] * i.p[1] + m[7] * i.p[2],
                m[2] * i.p[0] + m[5] * i.p[1] + m[8] * i.p[2],
            ) + t * i.p[3]
        })
        .sum()
}

/// The simplifier's state.
struct Simplifier<'a> {
    method: Method,
    mesh: Mesh,
    uv: Vec<DVec2>,
    rest: Vec<DVec3>,
    rest_bones: &'a [Affine3A],
    infl: Vec<Vec<Influence64>>,
    version: Vec<u32>,
    param: Parameterisation,
    metric: Metric<'a>,
    pm: &'a ExpectationMatrix,
    cache: FactorCache,
    heap: BinaryHeap<Reverse<Entry>>,
    collapse_version: Vec<u32>,
    influence_version: Vec<u32>,
    target: Vec<u32>,
    scratch: Scratch,
    neighbours: Vec<u32>,
    influences: u64,
    stats: Stats,
}

/// Builds the whole progressive mesh of `input` by `method`. `progress` is told the fraction
/// of triangles removed so far, now and then.
pub fn simplify(input: &SimplifyInput, method: Method, progress: &dyn Fn(f32)) -> Sequence {
    let am = input.mesh;
    let n = am.vertex_count();
    let infl = influences64(am);
    let mesh = Mesh::new(&am.indices, &infl);
    let uv: Vec<DVec2> = am.uvs.iter().map(|u| u.as_dvec2()).collect();
    let rest: Vec<DVec3> = infl
        .iter()
        .map(|i| rest_position(input.rest_bones, i))
        .collect();

    // Texture coordinates are the parameterisation when most triangles have area in them.
    let with_area = mesh
        .tris
        .iter()
        .filter(|t| {
            let [a, b, c] = t.map(|r| uv[r as usize]);
            (b - a).perp_dot(c - a).abs() > 1e-14
        })
        .count();
    let param = if with_area * 2 > mesh.tris.len() {
        let (lo, hi) = uv.iter().fold(
            (DVec2::splat(f64::MAX), DVec2::splat(f64::MIN)),
            |(lo, hi), &u| (lo.min(u), hi.max(u)),
        );
        Parameterisation::Texture {
            tolerance: 1e-5 * (hi - lo).length().max(1e-6),
        }
    } else {
        Parameterisation::Flattening
    };

    let influences: u64 = (0..n)
        .filter(|&v| mesh.refs[v] > 0)
        .map(|v| infl[mesh.pos(v as u32) as usize].len() as u64)
        .sum();
    let stats = Stats {
        dropped_triangles: mesh.dropped_triangles as u32,
        locked_positions: (0..n)
            .filter(|&u| mesh.alive[u] && matches!(mesh.kind[u], Kind::Complex | Kind::Locked))
            .count() as u32,
        texture_parameterisation: matches!(param, Parameterisation::Texture { .. }),
        ..Stats::default()
    };
    let metric = match method {
        Method::RestPose => Metric::RestPose,
        _ => Metric::AnimationSpace {
            pm: input.expectation,
            gram: FxHashMap::default(),
        },
    };
    let base_triangles = mesh.tris.clone();
    let mut s = Simplifier {
        method,
        mesh,
        uv,
        rest,
        rest_bones: input.rest_bones,
        infl,
        version: vec![0; n],
        param,
        metric,
        pm: input.expectation,
        cache: FactorCache::default(),
        heap: BinaryHeap::new(),
        collapse_version: vec![0; n],
        influence_version: vec![0; n],
        target: vec![u32::MAX; n],
        scratch: Scratch::default(),
        neighbours: Vec::new(),
        influences,
        stats,
    };
    let base_influences = s.influences as u32;
    let steps = s.run(progress);
    s.stats.cache_hits = s.cache.hits;
    s.stats.cache_misses = s.cache.misses;
    Sequence {
        method,
        base_triangles,
        base_influences,
        steps,
        stats: s.stats,
    }
}

impl Simplifier<'_> {
    fn run(&mut self, progress: &dyn Fn(f32)) -> Vec<Step> {
        let n = self.mesh.position.len() as u32;
        for u in 0..n {
            if self.mesh.alive[u as usize] && self.mesh.pos(u) == u {
                self.evaluate_collapse(u);
                self.evaluate_influence(u);
            }
        }
        let start = self.mesh.alive_triangles.max(1) as f32;
        let mut steps = Vec::new();
        let mut max_cost = 0.0f32;
        while let Some(Reverse(e)) = self.heap.pop() {
            let u = e.vertex as usize;
            if !self.mesh.alive[u] {
                continue;
            }
            let kind = if e.influence {
                if e.version != self.influence_version[u] {
                    continue;
                }
                self.apply_influence(e.vertex)
            } else {
                if e.version != self.collapse_version[u] {
                    continue;
                }
                // Neighbourhoods two rings away may have changed the legality since this was
                // queued: check again before applying.
                let target = self.target[u];
                match self.collapse_cost(e.vertex, target) {
                    Some(c) if (c - e.cost).abs() <= 1e-9 * c.max(e.cost) + 1e-300 => {}
                    _ => {
                        self.evaluate_collapse(e.vertex);
                        continue;
                    }
                }
                self.apply_collapse(e.vertex, target)
            };
            let cost = e.cost as f32;
            max_cost = max_cost.max(cost);
            steps.push(Step {
                kind,
                cost,
                max_cost,
                triangles: self.mesh.alive_triangles as u32,
                influences: self.influences as u32,
            });
            if steps.len() % 512 == 0 {
                progress(1.0 - self.mesh.alive_triangles as f32 / start);
            }
            if self.mesh.alive_triangles == 0 {
                break;
            }
        }
        progress(1.0);
        steps
    }

    /// The cost (a distance) of the half-edge collapse `u1 → u2`, or `None` if illegal.
    fn collapse_cost(&mut self, u1: u32, u2: u32) -> Option<f64> {
        if u2 == u32::MAX || !self.mesh.alive[u2 as usize] {
            return None;
        }
        let flat = match self.param {
            Parameterisation::Flattening => Some(Flattening::new(&self.mesh, &self.rest, u1)?),
            Parameterisation::Texture { .. } => None,
        };
        self.cost_with(u1, u2, flat.as_ref())
    }

    fn cost_with(&mut self, u1: u32, u2: u32, flat: Option<&Flattening>) -> Option<f64> {
        self.stats.evaluations += 1;
        let ctx = Context {
            mesh: &self.mesh,
            uv: &self.uv,
            rest: &self.rest,
            param: self.param,
        };
        ctx.corners(u1, u2, flat, &mut self.scratch).ok()?;
        let mut worst = 0.0f64;
        for corner in &self.scratch.corners {
            let d = self
                .metric
                .deviation2(corner, &self.rest, &self.infl, &self.version);
            worst = worst.max(d);
        }
        Some(worst.sqrt())
    }

    /// Finds `u`'s cheapest legal collapse and queues it.
    fn evaluate_collapse(&mut self, u: u32) {
        let ui = u as usize;
        self.collapse_version[ui] += 1;
        self.target[ui] = u32::MAX;
        if !self.mesh.alive[ui] || matches!(self.mesh.kind[ui], Kind::Complex | Kind::Locked) {
            return;
        }
        let flat = match self.param {
            Parameterisation::Flattening => match Flattening::new(&self.mesh, &self.rest, u) {
                Some(f) => Some(f),
                None => return,
            },
            Parameterisation::Texture { .. } => None,
        };
        let mut neighbours = std::mem::take(&mut self.neighbours);
        self.mesh.neighbours(u, &mut neighbours);
        let mut best: Option<(f64, u32)> = None;
        for &u2 in &neighbours {
            if let Some(c) = self.cost_with(u, u2, flat.as_ref())
                && best.is_none_or(|(b, _)| c < b)
            {
                best = Some((c, u2));
            }
        }
        self.neighbours = neighbours;
        if let Some((cost, u2)) = best {
            self.target[ui] = u2;
            self.heap.push(Reverse(Entry {
                cost,
                influence: false,
                vertex: u,
                version: self.collapse_version[ui],
            }));
        }
    }

    /// Finds `u`'s cheapest influence removal (§5) and queues it.
    fn evaluate_influence(&mut self, u: u32) {
        let ui = u as usize;
        self.influence_version[ui] += 1;
        if self.method != Method::InfluenceSimplification || self.infl[ui].len() < 2 {
            return;
        }
        let best = self.best_removal(u).map(|(cost, _)| cost);
        if let Some(cost) = best {
            self.heap.push(Reverse(Entry {
                cost,
                influence: true,
                vertex: u,
                version: self.influence_version[ui],
            }));
        }
    }

    /// The cheapest influence of `u` to remove: its deviation and its index.
    fn best_removal(&mut self, u: u32) -> Option<(f64, usize)> {
        let infl = &self.infl[u as usize];
        let bones: Vec<u32> = infl.iter().map(|i| i.bone).collect();
        let mut best: Option<(f64, usize)> = None;
        for (k, inf) in infl.iter().enumerate() {
            if let Some(f) = self.cache.get(self.pm, &bones, k) {
                let c = f.deviation(&inf.p);
                if best.is_none_or(|(b, _)| c < b) {
                    best = Some((c, k));
                }
            }
        }
        best
    }

    fn apply_collapse(&mut self, u1: u32, u2: u32) -> StepKind {
        let map = self
            .mesh
            .wedge_map(u1, u2)
            .expect("checked by collapse_cost");
        let mut ring = Vec::new();
        self.mesh.neighbours(u1, &mut ring);
        let (_, released) = self.mesh.collapse(u1, u2, &map);
        for r in released {
            self.influences -= self.infl[self.mesh.pos(r) as usize].len() as u64;
        }
        self.influence_version[u1 as usize] += 1;
        self.collapse_version[u1 as usize] += 1;
        // Only fans that contained u1 changed (the ring of u1, u2 included).
        for x in ring {
            self.evaluate_collapse(x);
        }
        StepKind::Collapse { wedges: map }
    }

    fn apply_influence(&mut self, u: u32) -> StepKind {
        let ui = u as usize;
        let bones: Vec<u32> = self.infl[ui].iter().map(|i| i.bone).collect();
        let (_, k) = self.best_removal(u).expect("queued with a solvable factor");
        let factor = self
            .cache
            .get(self.pm, &bones, k)
            .expect("just solved")
            .clone();
        let next = factor.apply(&self.infl[ui], k);
        let removed_bone = bones[k];
        self.infl[ui] = next;
        self.rest[ui] = rest_position(self.rest_bones, &self.infl[ui]);
        self.version[ui] += 1;
        let wedges = self.mesh.wedges[ui].clone();
        self.influences -= wedges.len() as u64;
        // Figure 4: every collapse whose fan holds this vertex changes, and the vertex may
        // lose another influence.
        let mut ring = Vec::new();
        self.mesh.neighbours(u, &mut ring);
        self.evaluate_collapse(u);
        for x in ring {
            self.evaluate_collapse(x);
        }
        self.evaluate_influence(u);
        StepKind::Influence {
            wedges,
            removed_bone,
            influences: self.infl[ui]
                .iter()
                .map(|i| AsInfluence {
                    bone: i.bone,
                    p: Vec4::from_array(i.p.map(|x| x as f32)),
                    n: Vec3::from_array(i.n.map(|x| x as f32)),
                })
                .collect(),
        }
    }
}

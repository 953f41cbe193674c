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
//! Two steps the paper does not need on its own models, for the files users bring:
//! - which parameter space makes points correspond is chosen per chart and collapse (the
//!   texture where it is one, else a geometric map of the fan; see [`collapse`]), and no
//!   collapse may turn a triangle over, or thin it into a sliver, in any sampled pose;
//! - a small separate part (a rivet, a buckle) is removed whole once its size in the metric is
//!   the cheapest step left, instead of being crushed into shards: meshoptimizer's component
//!   pruning (`meshopt_SimplifyPrune`), priced as the part's diameter, since that is how far
//!   the surface moves when it goes.
//!
//! Layout follows meshoptimizer's `simplifier.cpp`: flat arrays ([`mesh::Mesh`]), a table of
//! which vertex kinds may collapse onto which ([`mesh::CAN_COLLAPSE`]), and a lazily updated
//! binary heap. The output is a [`Sequence`]: every step in order with its cost and the running
//! maximum, from which [`crate::bake::character::lod`] cuts discrete levels and geomorph maps.

pub mod collapse;
pub mod expectation;
pub mod influence;
pub mod mesh;
mod metric;
mod sequence;

pub use metric::influences64;
use metric::{Metric, rest_position};
pub use sequence::{Sequence, Stats, Step, StepKind};

use crate::bake::gpu_data::animation_space::{AnimationSpaceMesh, AsInfluence};
use collapse::{Context, Posed, Scratch};
use expectation::ExpectationMatrix;
use glam::{Affine3A, DVec2, DVec3, Vec3, Vec4};
use influence::{FactorCache, Influence64};
use mesh::{Kind, Mesh};
use rayon::prelude::*;
use rstar::RTree;
use rstar::primitives::GeomWithData;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;
use std::sync::{Mutex, OnceLock};

crate::choice! {
    /// The three ways of ranking simplifications the paper compares.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
    pub enum Method {
        /// Edge collapses ranked by Euclidean deviation in the rest pose ("3D" in Table 1).
        #[serde(rename = "rest-pose")]
        RestPose => "rest-pose",
        /// Edge collapses ranked by the L2,2 deviation in animation space (§4).
        #[serde(rename = "as")]
        AnimationSpace => "as",
        /// As `AnimationSpace`, with influence simplifications in the same queue (§5).
        #[serde(rename = "as+is")]
        InfluenceSimplification => "as+is",
    }
}

/// What the simplifier needs to know about a character.
pub struct SimplifyInput<'a> {
    pub mesh: &'a AnimationSpaceMesh,
    /// The rest-pose bone matrices `Ĝ_i` in scene space (the root transform applied), so the
    /// rest-pose metric measures in the same units as the L2,2 one.
    pub rest_bones: &'a [Affine3A],
    pub expectation: &'a ExpectationMatrix,
    /// Bone matrices of sampled poses (scene space): no collapse may turn a triangle over in
    /// any of them. See [`pose_samples`].
    pub poses: &'a [Vec<Affine3A>],
    /// Per material (as [`AnimationSpaceMesh::materials`] numbers them): it has a texture,
    /// so its texture coordinates say what colour a point shows. A texture sliding over the
    /// surface costs what it moves, and two wedges of one position that differ in material,
    /// or in texture coordinate on a textured one, show different colours: a chart torn
    /// between them costs the triangles it recolours (see [`collapse`]). A material missing
    /// here counts as untextured.
    pub textured: &'a [bool],
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

/// Poses sampled evenly over every clip of `model` (at least one, the rest pose for a model
/// without clips), `count` in all, in scene space: what the simplifier checks orientation in
/// and the level error is measured over.
pub fn pose_samples(model: &crate::model::Model, count: usize) -> Vec<Vec<Affine3A>> {
    let skel = &model.skeleton;
    if model.clips.is_empty() {
        return vec![crate::anim::bone_matrices(skel, None, 0.0)];
    }
    let per_clip = count.div_ceil(model.clips.len()).max(1);
    model
        .clips
        .iter()
        .flat_map(|clip| {
            (0..per_clip).map(move |k| {
                let t = clip.duration.max(0.0) * (k as f32 + 0.5) / per_clip as f32;
                crate::anim::bone_matrices(skel, Some(clip), t)
            })
        })
        .collect()
}

/// What a queue entry would do.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Action {
    Collapse,
    Influence,
    /// Remove connected part `vertex` whole.
    Prune,
}

/// A queue entry. Ordered by cost, then kind and vertex so that runs are deterministic.
#[derive(Clone, Copy, Debug)]
struct Entry {
    cost: f64,
    action: Action,
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
            .then(self.action.cmp(&other.action))
            .then(self.vertex.cmp(&other.vertex))
            .then(self.version.cmp(&other.version))
    }
}

/// A position in the index the pruning looks for anchors in.
type Located = GeomWithData<[f64; 3], u32>;

/// The simplifier's state.
struct Simplifier<'a> {
    method: Method,
    mesh: Mesh,
    uv: &'a [DVec2],
    /// Per triangle of `mesh`: its texture coordinates span area.
    uv_valid: &'a [bool],
    uv_tolerance: f64,
    /// Metres of surface per texture unit where a texture can slide; 0 for none.
    slide_scale: f64,
    /// Rest positions, influences and posed positions: the prepared ones until an influence
    /// removal changes them (AS+IS alone does), then the simplifier's own copy.
    rest: Cow<'a, [DVec3]>,
    /// Rest-pose normals, by render vertex.
    normals: &'a [DVec3],
    rest_bones: &'a [Affine3A],
    poses: &'a [Vec<Affine3A>],
    /// Per render vertex, its material; per material, whether it is textured.
    materials: &'a [u16],
    textured: &'a [bool],
    /// Positions in the sampled poses.
    posed: Cow<'a, Posed>,
    infl: Cow<'a, [Vec<Influence64>]>,
    metric: Metric<'a>,
    pm: &'a ExpectationMatrix,
    cache: FactorCache,
    heap: BinaryHeap<Reverse<Entry>>,
    collapse_version: Vec<u32>,
    influence_version: Vec<u32>,
    target: Vec<u32>,
    /// Positions whose fan changed since their queued collapse was priced: priced again
    /// when that entry comes out (see [`Self::apply_collapse`]).
    stale: Vec<bool>,
    /// Per position: the step (`stamp`) its fan last changed at, the step its collapse was
    /// last priced at, and whether a position of its fan has moved since (an influence
    /// removal). A queued collapse is checked again before it is applied only if something it
    /// depends on may have changed since it was priced (see [`Self::run`]).
    touched: Vec<u64>,
    priced_at: Vec<u64>,
    moved: Vec<bool>,
    /// Connected parts (positions) and each position's part.
    parts: &'a [Vec<u32>],
    part_of: &'a [u32],
    located: &'a RTree<Located>,
    /// The serial steps' scratch space.
    workspace: Workspace,
    /// Scratch spaces for the candidates priced in parallel, one per task at a time.
    workspaces: Mutex<Vec<Workspace>>,
    influences: u64,
    /// Steps applied: marks what the scratch space cached as stale.
    stamp: u64,
    stats: Stats,
    /// Every cost is rounded to a multiple of this before it is ranked: see [`Self::rank`].
    cost_grid: f64,
    /// Vertices priced whole (all their candidates), those of them priced because their
    /// entry came out stale, and queued collapses checked again before they were applied:
    /// for the debug log.
    priced: u64,
    repriced: u64,
    verified: u64,
    unchecked: u64,
}

/// The costs' grid as a share of the model's rest-pose diagonal: a fifth of a micrometre on a
/// character, a ten-thousandth of what one pixel of error is on a figure 1000 pixels tall.
/// Pose matrices are single precision, so `P` makes a rigid bone's lengths wrong by about
/// 10⁻⁸ of themselves: the grid is ten times that, so the two metrics' roundings of one cost
/// all but always land on the same step of it.
const COST_GRID: f64 = 1e-7;

/// Builds the whole progressive mesh of `input` by `method`. `progress` is told the fraction
/// of triangles removed so far, now and then.
pub fn simplify(
    input: &SimplifyInput,
    method: Method,
    progress: &(dyn Fn(f32) + Sync),
) -> Sequence {
    gathered(|feed| simplify_feeding(input, method, progress, feed))
}

/// What [`simplify_feeding`] hands over as it runs: the sequence in pieces, each once, so
/// that it is held in one place only (on a 2-million-triangle model a million steps, about
/// 100 MB).
pub enum Feed {
    /// The sequence before its first step: everything but the steps and the statistics.
    Start(Sequence),
    /// The next steps, in order, a batch at a time.
    Steps(Vec<Step>),
}

/// The whole sequence that `simplify` (a call of [`simplify_feeding`]) hands over to the
/// feed it is given, with the statistics it returns.
pub fn gathered(simplify: impl FnOnce(&mut (dyn FnMut(Feed) + Send)) -> Stats) -> Sequence {
    let mut sequence: Option<Sequence> = None;
    let stats = simplify(&mut |feed| match feed {
        Feed::Start(start) => sequence = Some(start),
        Feed::Steps(steps) => {
            if let Some(s) = &mut sequence {
                s.steps.extend(steps);
            }
        }
    });
    let mut sequence = sequence.expect("the simplifier hands over its start");
    sequence.stats = stats;
    sequence
}

/// Fewer vertices than this to price are priced on the calling thread.
const PARALLEL_PRICING: usize = 64;

/// Steps handed over at a time by [`simplify_feeding`].
const FEED_BATCH: usize = 64;

/// [`simplify`], handing the sequence to `feed` as it is built (and keeping none of it), so
/// that a caller can work on its first steps while the rest are found. Returns the
/// statistics, which the start handed over lacks.
pub fn simplify_feeding(
    input: &SimplifyInput,
    method: Method,
    progress: &(dyn Fn(f32) + Sync),
    feed: &mut (dyn FnMut(Feed) + Send),
) -> Stats {
    let prepared = Prepared::new(input.mesh, input.rest_bones, input.poses, input.textured);
    let start = OnceLock::new();
    simplify_prepared(&prepared, input.expectation, &start, method, progress, feed)
}

/// What the simplifier makes of a character before its first step, whatever the method: the
/// mesh's topology and kinds, its welded positions, texture charts, posed positions and
/// connected parts. On a 2-million-triangle model that is about five seconds and half a
/// gigabyte, which each of the three methods made again; a bake of several methods makes it
/// once and each method's simplifier starts from it ([`simplify_prepared`]).
pub struct Prepared {
    rest_bones: Vec<Affine3A>,
    poses: Vec<Vec<Affine3A>>,
    materials: Vec<u16>,
    textured: Vec<bool>,
    infl: Vec<Vec<Influence64>>,
    rest: Vec<DVec3>,
    normals: Vec<DVec3>,
    positions: Vec<u32>,
    mesh: Mesh,
    uv: Vec<DVec2>,
    charts: TextureCharts,
    posed: Posed,
    influences: u64,
    parts: Vec<Vec<u32>>,
    part_of: Vec<u32>,
    located: RTree<Located>,
    stats: Stats,
    diagonal: f64,
}

impl Prepared {
    /// Prepares `am` (a character's full-detail mesh) with its rest-pose bone matrices, sampled
    /// poses and which materials are textured (as [`SimplifyInput`] has them).
    pub fn new(
        am: &AnimationSpaceMesh,
        rest_bones: &[Affine3A],
        poses: &[Vec<Affine3A>],
        textured: &[bool],
    ) -> Prepared {
        let start = std::time::Instant::now();
        let n = am.vertex_count();
        let infl = influences64(am);
        let rest: Vec<DVec3> = infl.iter().map(|i| rest_position(rest_bones, i)).collect();
        let normals: Vec<DVec3> = (0..n)
            .map(|v| {
                am.influences_of(v)
                    .iter()
                    .map(|i| {
                        let m = rest_bones[i.bone as usize].matrix3;
                        (m * i.n).as_dvec3()
                    })
                    .sum::<DVec3>()
                    .normalize_or_zero()
            })
            .collect();
        let positions = mesh::weld_positions(&rest, &infl);
        let diagonal = rest
            .iter()
            .fold(None, |b: Option<(DVec3, DVec3)>, &p| {
                Some(b.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))))
            })
            .map_or(0.0, |(lo, hi)| (hi - lo).length());
        let mut mesh = Mesh::new(&am.indices, positions.clone());
        mesh.classify_all();
        let uv: Vec<DVec2> = am.uvs.iter().map(|u| u.as_dvec2()).collect();
        let charts = TextureCharts::measure(&mesh, &uv, &rest);
        let posed = Posed::new(n, poses.len(), |v, s| {
            rest_position(&poses[s], &infl[v]).as_vec3()
        });
        let influences: u64 = (0..n)
            .filter(|&v| mesh.refs[v] > 0)
            .map(|v| infl[mesh.pos(v as u32) as usize].len() as u64)
            .sum();
        let parts = mesh.components();
        let mut part_of = vec![u32::MAX; n];
        for (i, part) in parts.iter().enumerate() {
            for &u in part {
                part_of[u as usize] = i as u32;
            }
        }
        let located = RTree::bulk_load(
            parts
                .iter()
                .flatten()
                .map(|&u| Located::new(rest[u as usize].to_array(), u))
                .collect(),
        );
        let stats = Stats {
            dropped_triangles: mesh.dropped_triangles as u32,
            locked_positions: (0..n)
                .filter(|&u| mesh.alive[u] && matches!(mesh.kind[u], Kind::Complex | Kind::Locked))
                .count() as u32,
            texture_parameterisation: charts.valid.iter().any(|&v| v),
            parts: parts.len() as u32,
            ..Stats::default()
        };
        log::debug!(
            "the simplifier's preparation of {n} vertices took {:.2} s",
            start.elapsed().as_secs_f64()
        );
        Prepared {
            rest_bones: rest_bones.to_vec(),
            poses: poses.to_vec(),
            materials: am.materials.clone(),
            textured: textured.to_vec(),
            infl,
            rest,
            normals,
            positions,
            mesh,
            uv,
            charts,
            posed,
            influences,
            parts,
            part_of,
            located,
            stats,
            diagonal,
        }
    }
}

/// A vertex's cheapest legal collapse (its cost and target), and how many candidates were
/// priced to find it.
type Priced = (Option<(f64, u32)>, u64);

/// Every position's cheapest collapse in a prepared character at full detail, by one metric:
/// where a simplification starts, a quarter of its pricing on a large model. AS and AS+IS rank
/// by the same metric (influence removals are queued beside the collapses, and none has
/// happened yet), so a bake of both prices the full-detail mesh once. It holds for the
/// [`Prepared`] character, metric and expectation matrix it was made with, and for no other.
pub struct FirstPricing {
    found: Vec<Priced>,
}

/// [`simplify_feeding`] from a prepared character ([`Prepared`]), ranked by `method` with the
/// expectation matrix `expectation` (unused by the rest-pose method). `start` is the first
/// pricing of every position: made here if it is empty, and left for the other methods that
/// rank by the same metric (see [`FirstPricing`]).
pub fn simplify_prepared(
    prepared: &Prepared,
    expectation: &ExpectationMatrix,
    start: &OnceLock<FirstPricing>,
    method: Method,
    progress: &(dyn Fn(f32) + Sync),
    feed: &mut (dyn FnMut(Feed) + Send),
) -> Stats {
    let p = prepared;
    let n = p.infl.len();
    let metric = match method {
        Method::RestPose => Metric::RestPose,
        _ => Metric::AnimationSpace { pm: expectation },
    };
    let base_triangles = p.mesh.tris.clone();
    let mut s = Simplifier {
        method,
        mesh: p.mesh.clone(),
        uv: &p.uv,
        uv_valid: &p.charts.valid,
        uv_tolerance: p.charts.tolerance,
        slide_scale: if p.textured.iter().any(|&t| t) {
            p.charts.metres_per_unit
        } else {
            0.0
        },
        rest: Cow::Borrowed(&p.rest),
        normals: &p.normals,
        rest_bones: &p.rest_bones,
        poses: &p.poses,
        materials: &p.materials,
        textured: &p.textured,
        posed: Cow::Borrowed(&p.posed),
        infl: Cow::Borrowed(&p.infl),
        metric,
        pm: expectation,
        cache: FactorCache::default(),
        heap: BinaryHeap::new(),
        collapse_version: vec![0; n],
        influence_version: vec![0; n],
        target: vec![u32::MAX; n],
        stale: vec![false; n],
        touched: vec![0; n],
        priced_at: vec![0; n],
        moved: vec![false; n],
        parts: &p.parts,
        part_of: &p.part_of,
        located: &p.located,
        workspace: Workspace::default(),
        workspaces: Mutex::new(Vec::new()),
        influences: p.influences,
        stamp: 0,
        stats: p.stats.clone(),
        cost_grid: COST_GRID * p.diagonal.max(f64::MIN_POSITIVE),
        priced: 0,
        repriced: 0,
        verified: 0,
        unchecked: 0,
    };
    let triangles = base_triangles.len();
    feed(Feed::Start(Sequence {
        method,
        positions: p.positions.clone(),
        base_triangles,
        base_influences: p.influences as u32,
        steps: Vec::new(),
        stats: Stats::default(),
    }));
    // On a worker of rayon's pool, the candidates priced in parallel after each collapse
    // (see `evaluate_collapses`) cost a push onto the worker's own queue, which an idle
    // worker steals from; from any other thread, each would wake the pool and wait.
    let clock = std::time::Instant::now();
    let steps = rayon::scope(|_| s.run(start, progress, feed));
    log::debug!(
        "{method}: {steps} steps from {triangles} triangles in {:.2} s; {} vertices priced ({} \
         again when their entry came out stale), {} candidates, {} collapses checked again ({} applied unchecked)",
        clock.elapsed().as_secs_f64(),
        s.priced,
        s.repriced,
        s.stats.evaluations,
        s.verified,
        s.unchecked,
    );
    s.stats.cache_hits = s.cache.hits;
    s.stats.cache_misses = s.cache.misses;
    s.stats
}

/// Where a model's texture coordinates are a parameterisation.
struct TextureCharts {
    /// Per triangle: its texture coordinates span area, at least a thousandth of what the
    /// model's usual texel density gives a triangle of its size.
    valid: Vec<bool>,
    /// Metres of surface per texture unit: the median over triangles with texture area.
    metres_per_unit: f64,
    /// How far off its outline's line a chart outline vertex may lie and still slide along it.
    tolerance: f64,
}

impl TextureCharts {
    fn measure(mesh: &Mesh, uv: &[DVec2], rest: &[DVec3]) -> TextureCharts {
        let areas: Vec<(f64, f64)> = mesh
            .tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|r| uv[r as usize]);
                let [x, y, z] = t.map(|r| rest[mesh.pos(r) as usize]);
                (
                    0.5 * (b - a).perp_dot(c - a).abs(),
                    0.5 * (y - x).cross(z - x).length(),
                )
            })
            .collect();
        let mut scales: Vec<f64> = areas
            .iter()
            .filter(|(uv, xyz)| *uv > 0.0 && *xyz > 0.0)
            .map(|(uv, xyz)| (xyz / uv).sqrt())
            .collect();
        scales.sort_by(f64::total_cmp);
        let metres_per_unit = scales.get(scales.len() / 2).copied().unwrap_or(0.0);
        let valid = areas
            .iter()
            .map(|&(uv, xyz)| {
                metres_per_unit > 0.0 && uv * metres_per_unit * metres_per_unit >= 1e-3 * xyz
            })
            .collect();
        let (lo, hi) = uv.iter().fold(
            (DVec2::splat(f64::MAX), DVec2::splat(f64::MIN)),
            |(lo, hi), &u| (lo.min(u), hi.max(u)),
        );
        TextureCharts {
            valid,
            metres_per_unit,
            tolerance: 1e-5 * (hi - lo).length().max(1e-6),
        }
    }
}

impl Simplifier<'_> {
    fn run(
        &mut self,
        start: &OnceLock<FirstPricing>,
        progress: &(dyn Fn(f32) + Sync),
        feed: &mut (dyn FnMut(Feed) + Send),
    ) -> usize {
        let n = self.mesh.position.len() as u32;
        let positions: Vec<u32> = (0..n)
            .filter(|&u| self.mesh.alive[u as usize] && self.mesh.pos(u) == u)
            .collect();
        // Every position priced at full detail: shared with any other simplification from the
        // same start (see [`FirstPricing`]).
        let first = start.get_or_init(|| FirstPricing {
            found: self.price_in_parallel(&positions),
        });
        self.queue_priced(&positions, &first.found);
        for &u in &positions {
            self.evaluate_influence(u);
        }
        for part in 0..self.parts.len() as u32 {
            self.queue_prune(part);
        }
        let start = self.mesh.alive_triangles.max(1) as f32;
        let mut steps = 0;
        let mut batch = Vec::with_capacity(FEED_BATCH);
        let mut max_cost = 0.0f32;
        while let Some(Reverse(e)) = self.heap.pop() {
            let u = e.vertex as usize;
            let kind = match e.action {
                Action::Prune => {
                    // The last part left is the character: it stays.
                    if self.stats.pruned_parts + 1 >= self.stats.parts {
                        continue;
                    }
                    // The part's size can change as its positions collapse or lose influences:
                    // queue it again at its current cost if that moved.
                    match self.part_diameter(e.vertex) {
                        None => continue,
                        Some(c) if (c - e.cost).abs() > 1e-9 * c.max(e.cost) => {
                            self.heap.push(Reverse(Entry { cost: c, ..e }));
                            continue;
                        }
                        Some(_) => self.apply_prune(e.vertex),
                    }
                }
                Action::Influence => {
                    if !self.mesh.alive[u] || e.version != self.influence_version[u] {
                        continue;
                    }
                    self.apply_influence(e.vertex)
                }
                Action::Collapse => {
                    if !self.mesh.alive[u] || e.version != self.collapse_version[u] {
                        continue;
                    }
                    if self.stale[u] {
                        self.repriced += 1;
                        self.evaluate_collapse(e.vertex);
                        continue;
                    }
                    // The cost and legality of `u → target` depend on u's fan (unchanged:
                    // not stale), on the target's fan (the link condition reads whom it
                    // neighbours, the wedge map its wedges) and on where the fan's positions
                    // are. If the target's fan changed or a position moved since the collapse
                    // was priced, check it again before applying it; else it is what it was,
                    // and checking it again (a collapse in every step) found the same.
                    let target = self.target[u];
                    if self.moved[u] || self.touched[target as usize] > self.priced_at[u] {
                        self.verified += 1;
                        match self.collapse_cost(e.vertex, target) {
                            Some(c) if (c - e.cost).abs() <= 1e-9 * c.max(e.cost) + 1e-300 => {}
                            _ => {
                                self.evaluate_collapse(e.vertex);
                                continue;
                            }
                        }
                    } else {
                        self.unchecked += 1;
                    }
                    self.apply_collapse(e.vertex, target)
                }
            };
            let cost = e.cost as f32;
            max_cost = max_cost.max(cost);
            batch.push(Step {
                kind,
                cost,
                max_cost,
                triangles: self.mesh.alive_triangles as u32,
                influences: self.influences as u32,
            });
            steps += 1;
            if batch.len() == FEED_BATCH {
                feed(Feed::Steps(std::mem::replace(
                    &mut batch,
                    Vec::with_capacity(FEED_BATCH),
                )));
            }
            if steps % 512 == 0 {
                progress(1.0 - self.mesh.alive_triangles as f32 / start);
            }
            if self.mesh.alive_triangles == 0 {
                break;
            }
        }
        feed(Feed::Steps(batch));
        progress(1.0);
        steps
    }

    /// `cost` as it is ranked: rounded to the cost grid, 10⁻⁷ of the model's size.
    /// The metrics compute the same distance in different ways (the rest-pose one from
    /// positions, L2,2 through the blocks of `P`), and where they should agree (a clip that
    /// does not move, a part on one bone) their roundings differ: a free collapse inside a flat
    /// face costs 10⁻¹⁷ by one and 4·10⁻¹⁷ by the other, and mirror-image collapses that cost
    /// the same tie one way or the other. Ranked by the raw values, the two methods then took
    /// free and tied steps in different orders, and their greedy paths drifted apart (on the
    /// rigid robot, RMS errors 1.6 times apart at 320 triangles). On the grid, such costs are
    /// equal and ties go by vertex, the same way for both.
    fn rank(&self, cost: f64) -> f64 {
        (cost / self.cost_grid).round() * self.cost_grid
    }

    fn context(&self) -> Context<'_> {
        Context {
            stamp: self.stamp,
            mesh: &self.mesh,
            uv: self.uv,
            uv_valid: self.uv_valid,
            uv_tolerance: self.uv_tolerance,
            slide_scale: self.slide_scale,
            materials: self.materials,
            textured: self.textured,
            rest: &self.rest,
            normals: self.normals,
            posed: &self.posed,
        }
    }

    /// The cost (a distance) of the half-edge collapse `u1 → u2`, or `None` if illegal.
    fn collapse_cost(&mut self, u1: u32, u2: u32) -> Option<f64> {
        self.stats.evaluations += 1;
        let mut w = std::mem::take(&mut self.workspace);
        let cost = self.unoriented_cost(u1, u2, &mut w.scratch).filter(|_| {
            let ctx = self.context();
            self.mesh.neighbours(u1, &mut w.neighbours);
            ctx.check_link(u1, u2, &w.neighbours).is_ok() && ctx.check_orientation(u1, u2).is_ok()
        });
        self.workspace = w;
        cost
    }

    /// [`Self::collapse_cost`] without the link and orientation checks.
    fn unoriented_cost(&self, u1: u32, u2: u32, scratch: &mut Scratch) -> Option<f64> {
        if u2 == u32::MAX || !self.mesh.alive[u2 as usize] {
            return None;
        }
        self.context().corners(u1, u2, scratch).ok()?;
        let mut worst = 0.0f64;
        for corner in &scratch.corners {
            let d = self
                .metric
                .deviation2(&corner.terms, &self.rest, &self.infl);
            worst = worst.max(d + corner.texture * corner.texture);
        }
        Some(self.rank(worst.sqrt()))
    }

    /// `u`'s cheapest legal collapse, as its cost and target, and how many candidates were
    /// priced. Reads the simplifier only, so the candidates of many vertices can be priced at
    /// once.
    fn best_collapse(&self, u: u32, w: &mut Workspace) -> Priced {
        let ui = u as usize;
        if !self.mesh.alive[ui] || matches!(self.mesh.kind[ui], Kind::Complex | Kind::Locked) {
            return (None, 0);
        }
        self.mesh.neighbours(u, &mut w.neighbours);
        let mut costs: smallvec::SmallVec<[(f64, u32); 16]> = w
            .neighbours
            .iter()
            .filter_map(|&u2| Some((self.unoriented_cost(u, u2, &mut w.scratch)?, u2)))
            .collect();
        costs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let ctx = self.context();
        let best = costs.into_iter().find(|&(_, u2)| {
            ctx.check_link(u, u2, &w.neighbours).is_ok() && ctx.check_orientation(u, u2).is_ok()
        });
        (best, w.neighbours.len() as u64)
    }

    /// Finds `u`'s cheapest legal collapse and queues it.
    fn evaluate_collapse(&mut self, u: u32) {
        let mut w = std::mem::take(&mut self.workspace);
        let (best, evaluations) = self.best_collapse(u, &mut w);
        self.workspace = w;
        self.priced += 1;
        self.stats.evaluations += evaluations;
        self.queue_collapse(u, best);
    }

    /// [`Self::evaluate_collapse`] for each of `vertices`. Many are priced in parallel, since
    /// pricing reads the mesh only and is most of the work; they are queued in order, so the
    /// sequence is the same on any number of cores.
    fn evaluate_collapses(&mut self, vertices: &[u32]) {
        // A few vertices (what a collapse leaves with nothing queued) cost less priced here
        // than handed to the pool.
        if vertices.len() < PARALLEL_PRICING {
            for &u in vertices {
                self.evaluate_collapse(u);
            }
            return;
        }
        let found = self.price_in_parallel(vertices);
        self.queue_priced(vertices, &found);
    }

    /// [`Self::best_collapse`] of each of `vertices`, in parallel.
    fn price_in_parallel(&self, vertices: &[u32]) -> Vec<Priced> {
        vertices
            .par_iter()
            .map_init(
                || Pooled::take(&self.workspaces),
                |w, &u| self.best_collapse(u, &mut w.workspace),
            )
            .collect()
    }

    /// Queues the collapses `found` of `vertices` (as [`Self::best_collapse`] priced them), in
    /// order.
    fn queue_priced(&mut self, vertices: &[u32], found: &[Priced]) {
        for (&u, &(best, evaluations)) in vertices.iter().zip(found) {
            self.priced += 1;
            self.stats.evaluations += evaluations;
            self.queue_collapse(u, best);
        }
    }

    /// Queues `u`'s collapse `best` (found by [`Self::best_collapse`]), in place of any
    /// queued before.
    fn queue_collapse(&mut self, u: u32, best: Option<(f64, u32)>) {
        let ui = u as usize;
        self.stale[ui] = false;
        self.moved[ui] = false;
        self.priced_at[ui] = self.stamp;
        self.collapse_version[ui] += 1;
        self.target[ui] = u32::MAX;
        if let Some((cost, u2)) = best {
            self.target[ui] = u2;
            self.heap.push(Reverse(Entry {
                cost,
                action: Action::Collapse,
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
                action: Action::Influence,
                vertex: u,
                version: self.influence_version[ui],
            }));
        }
    }

    /// Queues the removal of part `part` at its current diameter.
    fn queue_prune(&mut self, part: u32) {
        if let Some(cost) = self.part_diameter(part) {
            self.heap.push(Reverse(Entry {
                cost,
                action: Action::Prune,
                vertex: part,
                version: 0,
            }));
        }
    }

    /// How far the surface moves when part `part` goes: its diameter in the metric (twice the
    /// largest distance of its positions from their mean). `None` once nothing of it is left.
    fn part_diameter(&self, part: u32) -> Option<f64> {
        let alive: Vec<u32> = self.parts[part as usize]
            .iter()
            .copied()
            .filter(|&u| self.mesh.alive[u as usize])
            .collect();
        if alive.is_empty() {
            return None;
        }
        let weight = 1.0 / alive.len() as f64;
        let radius2 = match self.metric {
            Metric::RestPose => {
                let centre: DVec3 =
                    alive.iter().map(|&u| self.rest[u as usize]).sum::<DVec3>() * weight;
                alive
                    .iter()
                    .map(|&u| self.rest[u as usize].distance_squared(centre))
                    .fold(0.0, f64::max)
            }
            Metric::AnimationSpace { pm, .. } => {
                let points: Vec<Vec<(u32, [f64; 4])>> = alive
                    .iter()
                    .map(|&u| {
                        self.infl[u as usize]
                            .iter()
                            .map(|i| (i.bone, i.p))
                            .collect()
                    })
                    .collect();
                pm.max_spread2(&points)
            }
        };
        Some(self.rank(2.0 * radius2.max(0.0).sqrt()))
    }

    /// The cheapest influence of `u` to remove: its deviation and its index.
    fn best_removal(&mut self, u: u32) -> Option<(f64, usize)> {
        let infl = &self.infl[u as usize];
        let bones: Vec<u32> = infl.iter().map(|i| i.bone).collect();
        let mut best: Option<(f64, usize)> = None;
        for (k, inf) in infl.iter().enumerate() {
            if let Some(f) = self.cache.get(self.pm, &bones, k) {
                let c = (f.deviation(&inf.p) / self.cost_grid).round() * self.cost_grid;
                if best.is_none_or(|(b, _)| c < b) {
                    best = Some((c, k));
                }
            }
        }
        best
    }

    fn apply_collapse(&mut self, u1: u32, u2: u32) -> StepKind {
        self.stamp += 1;
        let map: Vec<[u32; 2]> = self
            .context()
            .wedge_map(u1, u2)
            .expect("checked by collapse_cost")
            .into_iter()
            .map(|(pair, _)| pair)
            .collect();
        let corner = self.mesh.kind[u1 as usize] == Kind::Corner;
        let mut ring = Vec::new();
        self.mesh.neighbours(u1, &mut ring);
        let (_, released) = self.mesh.collapse(u1, u2, &map);
        for r in released {
            self.influences -= self.infl[self.mesh.pos(r) as usize].len() as u64;
        }
        self.influence_version[u1 as usize] += 1;
        self.collapse_version[u1 as usize] += 1;
        // A torn chart changes where the seams run round the vertices it reaches.
        if corner {
            for &x in &ring {
                self.mesh.reclassify(x);
            }
        }
        // Only fans that contained u1 changed (the ring of u1, u2 included). A ring vertex
        // with a collapse queued is priced again only when that entry comes out, and goes
        // back in at its new cost (straight out again if it is still the cheapest): a
        // memoryless cost mostly grows as the mesh around it coarsens, so the old cost is
        // where its turn comes at the earliest. Pricing the whole ring at once after every
        // collapse priced each vertex many times over before it came out (six ring vertices
        // a collapse, each pricing its six or so candidates): deferred, the rest-pose bake of
        // a 2-million-triangle model took 69 s instead of 94, with levels as close to the
        // model (errors at the same triangle budgets 2% lower on average over the built-in
        // characters; level by level they moved by -66% to +32%, as greedy paths do). A
        // vertex with nothing queued is priced now, since no entry would bring it out.
        let mut now = Vec::new();
        for &x in &ring {
            self.touched[x as usize] = self.stamp;
            if self.target[x as usize] == u32::MAX {
                now.push(x);
            } else {
                self.stale[x as usize] = true;
            }
        }
        self.evaluate_collapses(&now);
        StepKind::Collapse { wedges: map }
    }

    /// Removes part `part` whole. Its geomorph anchor is the nearest position left on another
    /// part, in the rest pose.
    fn apply_prune(&mut self, part: u32) -> StepKind {
        self.stamp += 1;
        let positions: Vec<u32> = self.parts[part as usize]
            .iter()
            .copied()
            .filter(|&u| self.mesh.alive[u as usize])
            .collect();
        let centre = positions
            .iter()
            .map(|&u| self.rest[u as usize])
            .sum::<DVec3>()
            / positions.len() as f64;
        let anchor = self
            .located
            .nearest_neighbor_iter(centre.to_array())
            .map(|l| l.data)
            .find(|&u| self.mesh.alive[u as usize] && self.part_of[u as usize] != part)
            .and_then(|u| self.mesh.wedges[u as usize].first().copied());
        let (_, released) = self.mesh.prune(&positions);
        for &r in &released {
            self.influences -= self.infl[self.mesh.pos(r) as usize].len() as u64;
        }
        for &u in &positions {
            self.collapse_version[u as usize] += 1;
            self.influence_version[u as usize] += 1;
        }
        self.stats.pruned_parts += 1;
        StepKind::Prune {
            wedges: released,
            anchor,
        }
    }

    fn apply_influence(&mut self, u: u32) -> StepKind {
        self.stamp += 1;
        let ui = u as usize;
        let bones: Vec<u32> = self.infl[ui].iter().map(|i| i.bone).collect();
        let (_, k) = self.best_removal(u).expect("queued with a solvable factor");
        let factor = self
            .cache
            .get(self.pm, &bones, k)
            .expect("just solved")
            .clone();
        let removed_bone = bones[k];
        // Every wedge keeps its own normal (a hard edge, a flat-shaded facet): the position's
        // `p_i` with the wedge's own `n_i`, both moved by the factor. Giving every wedge the
        // first one's normals smoothed a faceted model at its first level.
        let wedges = self.mesh.wedges[ui].to_vec();
        let mut moved: Vec<Vec<Influence64>> = Vec::with_capacity(wedges.len());
        for &w in &wedges {
            let own: Vec<Influence64> = self.infl[ui]
                .iter()
                .map(|i| Influence64 {
                    n: self.infl[w as usize]
                        .iter()
                        .find(|x| x.bone == i.bone)
                        .map_or([0.0; 3], |x| x.n),
                    ..*i
                })
                .collect();
            moved.push(factor.apply(&own, k));
        }
        let next = factor.apply(&self.infl[ui], k);
        for (&w, m) in wedges.iter().zip(&moved) {
            self.infl.to_mut()[w as usize] = m.clone();
        }
        let infl = self.infl.to_mut();
        infl[ui] = next;
        self.rest.to_mut()[ui] = rest_position(self.rest_bones, &infl[ui]);
        // Every collapse whose fan holds this position must be checked before it is applied.
        let mut ring = Vec::new();
        self.mesh.neighbours(u, &mut ring);
        self.moved[ui] = true;
        for &x in &ring {
            self.moved[x as usize] = true;
        }
        let posed: Vec<Vec3> = self
            .poses
            .iter()
            .map(|g| rest_position(g, &self.infl[ui]).as_vec3())
            .collect();
        self.posed.to_mut().set(ui, &posed);
        self.influences -= wedges.len() as u64;
        // Figure 4: every collapse whose fan holds this vertex changes. Their queue entries are
        // left as they are and checked when they come out (`run` recomputes a collapse's cost
        // before applying it and queues it again if it moved): an influence removal moves the
        // vertex by its own small cost, so the order barely changes, and re-evaluating every
        // fan at once would cost as much again as the collapses themselves. The vertex may
        // lose another influence.
        self.evaluate_influence(u);
        StepKind::Influence {
            wedges,
            removed_bone,
            influences: moved
                .iter()
                .map(|m| {
                    m.iter()
                        .map(|i| AsInfluence {
                            bone: i.bone,
                            p: Vec4::from_array(i.p.map(|x| x as f32)),
                            n: Vec3::from_array(i.n.map(|x| x as f32)),
                        })
                        .collect()
                })
                .collect(),
        }
    }
}

/// What pricing one vertex's candidates writes to: the collapse's scratch space and the
/// vertex's neighbours.
#[derive(Default)]
struct Workspace {
    scratch: Scratch,
    neighbours: Vec<u32>,
}

/// A [`Workspace`] taken from a pool for one parallel task, and put back when it ends, so
/// that scratch space is allocated once per thread rather than once per collapse.
struct Pooled<'p> {
    pool: &'p Mutex<Vec<Workspace>>,
    workspace: Workspace,
}

impl<'p> Pooled<'p> {
    fn take(pool: &'p Mutex<Vec<Workspace>>) -> Pooled<'p> {
        let workspace = pool
            .lock()
            .map(|mut p| p.pop())
            .ok()
            .flatten()
            .unwrap_or_default();
        Pooled { pool, workspace }
    }
}

impl Drop for Pooled<'_> {
    fn drop(&mut self) {
        if let Ok(mut pool) = self.pool.lock() {
            pool.push(std::mem::take(&mut self.workspace));
        }
    }
}

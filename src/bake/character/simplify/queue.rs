//! The greedy loop: a heap of candidate actions (half-edge collapses and influence
//! removals) ranked by cost, re-priced lazily when a neighbour changes, applied cheapest first
//! while the sequence is fed to its reader (Merry et al. §4.3, §5).

use super::collapse::{Context, Scratch};
use super::expectation::ExpectationMatrix;
use super::influence::{FactorCache, Influence64};
use super::input::Method;
use super::mesh::{Kind, Mesh};
use super::metric::{Metric, rest_position};
use super::posed::Posed;
use super::sequence::{Sequence, Stats, Step, StepKind};
use crate::bake::character::simplify::prepare::Located;
use crate::bake::gpu_data::animation_space::AsInfluence;
use glam::{Affine3A, DVec2, DVec3, Vec3, Vec4};
use rayon::prelude::*;
use rstar::RTree;
use std::borrow::Cow;
use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;
use std::sync::{Mutex, OnceLock};

/// What a queue entry would do.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Action {
    Collapse,
    Influence,
    /// Remove connected part `vertex` whole.
    Prune,
}

/// A queue entry. Ordered by cost, then kind, then (collapses) the shorter edge, then the tie
/// order's rank of its vertex (or part), never its index: equal costs go the same way whatever
/// order the file lists its vertices in (see [`Ties`](super::prepare::Ties)). Of free
/// collapses in a flat region, the shortest first keeps triangles even where the clips bend
/// the region later: ranked by position alone, the rest-pose method emptied the split tube's
/// straight runs end to end and cut 3 levels where it had cut 5.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Entry {
    pub(crate) cost: f64,
    pub(crate) action: Action,
    /// A collapse's edge length at rest (0 for other actions): of equal costs, the shorter
    /// edge goes first.
    pub(crate) length: f64,
    pub(crate) tie: u32,
    pub(crate) vertex: u32,
    pub(crate) version: u32,
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
            .then(self.length.total_cmp(&other.length))
            .then(self.tie.cmp(&other.tie))
            .then(self.vertex.cmp(&other.vertex))
            .then(self.version.cmp(&other.version))
    }
}

/// The simplifier's state.
pub(crate) struct Simplifier<'a> {
    pub(crate) method: Method,
    pub(crate) mesh: Mesh,
    pub(crate) uv: &'a [DVec2],
    /// Per triangle of `mesh`: its texture coordinates span area.
    pub(crate) uv_valid: &'a [bool],
    pub(crate) uv_tolerance: f64,
    /// Metres of surface per texture unit where a texture can slide; 0 for none.
    pub(crate) slide_scale: f64,
    /// Rest positions, influences and posed positions: the prepared ones until an influence
    /// removal changes them (AS+IS alone does), then the simplifier's own copy.
    pub(crate) rest: Cow<'a, [DVec3]>,
    /// Rest-pose normals, by render vertex.
    pub(crate) normals: &'a [DVec3],
    pub(crate) rest_bones: &'a [Affine3A],
    pub(crate) poses: &'a [Vec<Affine3A>],
    /// Per render vertex, its material; per material, whether it is textured.
    pub(crate) materials: &'a [u16],
    pub(crate) textured: &'a [bool],
    /// Positions in the sampled poses.
    pub(crate) posed: Cow<'a, Posed>,
    pub(crate) infl: Cow<'a, [Vec<Influence64>]>,
    pub(crate) metric: Metric<'a>,
    pub(crate) pm: &'a ExpectationMatrix,
    pub(crate) cache: FactorCache,
    pub(crate) heap: BinaryHeap<Reverse<Entry>>,
    pub(crate) collapse_version: Vec<u32>,
    pub(crate) influence_version: Vec<u32>,
    pub(crate) target: Vec<u32>,
    /// Positions whose fan changed since their queued collapse was priced: priced again
    /// when that entry comes out (see [`Self::apply_collapse`]).
    pub(crate) stale: Vec<bool>,
    /// Per position: the step (`stamp`) its fan last changed at, the step its collapse was
    /// last priced at, and whether a position of its fan has moved since (an influence
    /// removal). A queued collapse is checked again before it is applied only if something it
    /// depends on may have changed since it was priced (see [`Self::run`]).
    pub(crate) touched: Vec<u64>,
    pub(crate) priced_at: Vec<u64>,
    pub(crate) moved: Vec<bool>,
    /// Connected parts (positions) and each position's part.
    pub(crate) parts: &'a [Vec<u32>],
    pub(crate) part_of: &'a [u32],
    pub(crate) located: &'a RTree<Located>,
    /// The tie order: a rank per position ([`Ties`](super::prepare::Ties)).
    pub(crate) ties: &'a super::prepare::Ties,
    /// The serial steps' scratch space.
    pub(crate) workspace: Workspace,
    /// Scratch spaces for the candidates priced in parallel, one per task at a time.
    pub(crate) workspaces: Mutex<Vec<Workspace>>,
    pub(crate) influences: u64,
    /// Steps applied: marks what the scratch space cached as stale.
    pub(crate) stamp: u64,
    pub(crate) stats: Stats,
    /// Every cost is rounded to a multiple of this before it is ranked: see [`Self::rank`].
    pub(crate) cost_grid: f64,
    /// Vertices priced whole (all their candidates), those of them priced because their
    /// entry came out stale, and queued collapses checked again before they were applied:
    /// for the debug log.
    pub(crate) priced: u64,
    pub(crate) repriced: u64,
    pub(crate) verified: u64,
    pub(crate) unchecked: u64,
}

/// What [`simplify_feeding`](super::simplify_feeding) hands over as it runs: the sequence in pieces, each once, so
/// that it is held in one place only (on a 2-million-triangle model a million steps, about
/// 100 MB).
pub enum Feed {
    /// The sequence before its first step: everything but the steps and the statistics.
    Start(Sequence),
    /// The next steps, in order, a batch at a time.
    Steps(Vec<Step>),
}

/// Fewer vertices than this to price are priced on the calling thread.
pub(crate) const PARALLEL_PRICING: usize = 64;

/// Steps handed over at a time by [`simplify_feeding`](super::simplify_feeding).
pub(crate) const FEED_BATCH: usize = 64;

/// A vertex's cheapest legal collapse (its cost and target), and how many candidates were
/// priced to find it.
pub(crate) type Priced = (Option<(f64, u32)>, u64);

/// Every position's cheapest collapse in a prepared character at full detail, by one metric:
/// where a simplification starts, a quarter of its pricing on a large model. AS and AS+IS rank
/// by the same metric (influence removals are queued beside the collapses, and none has
/// happened yet), so a bake of both prices the full-detail mesh once. It holds for the
/// [`Prepared`](super::prepare::Prepared) character, metric and expectation matrix it was made with, and for no other.
pub struct FirstPricing {
    /// The tie order it was priced in: ties between targets of equal cost go by it.
    pub(crate) order: u32,
    pub(crate) found: Vec<Priced>,
}

impl Simplifier<'_> {
    pub(crate) fn run(
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
            order: self.ties.order,
            found: self.price_in_parallel(&positions),
        });
        assert_eq!(
            first.order, self.ties.order,
            "a first pricing is shared only by simplifications in one tie order"
        );
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
    pub(crate) fn rank(&self, cost: f64) -> f64 {
        (cost / self.cost_grid).round() * self.cost_grid
    }

    pub(crate) fn context(&self) -> Context<'_> {
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
    pub(crate) fn collapse_cost(&mut self, u1: u32, u2: u32) -> Option<f64> {
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
    pub(crate) fn unoriented_cost(&self, u1: u32, u2: u32, scratch: &mut Scratch) -> Option<f64> {
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
    pub(crate) fn best_collapse(&self, u: u32, w: &mut Workspace) -> Priced {
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
        let tie = |u: u32| self.ties.rank[u as usize];
        let length = |u2: u32| self.rest[ui].distance_squared(self.rest[u2 as usize]);
        costs.sort_by(|a, b| {
            a.0.total_cmp(&b.0)
                .then(length(a.1).total_cmp(&length(b.1)))
                .then(tie(a.1).cmp(&tie(b.1)))
        });
        let ctx = self.context();
        let best = costs.into_iter().find(|&(_, u2)| {
            ctx.check_link(u, u2, &w.neighbours).is_ok() && ctx.check_orientation(u, u2).is_ok()
        });
        (best, w.neighbours.len() as u64)
    }

    /// Finds `u`'s cheapest legal collapse and queues it.
    pub(crate) fn evaluate_collapse(&mut self, u: u32) {
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
    pub(crate) fn evaluate_collapses(&mut self, vertices: &[u32]) {
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
    pub(crate) fn price_in_parallel(&self, vertices: &[u32]) -> Vec<Priced> {
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
    pub(crate) fn queue_priced(&mut self, vertices: &[u32], found: &[Priced]) {
        for (&u, &(best, evaluations)) in vertices.iter().zip(found) {
            self.priced += 1;
            self.stats.evaluations += evaluations;
            self.queue_collapse(u, best);
        }
    }

    /// Queues `u`'s collapse `best` (found by [`Self::best_collapse`]), in place of any
    /// queued before.
    pub(crate) fn queue_collapse(&mut self, u: u32, best: Option<(f64, u32)>) {
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
                length: self.rest[ui].distance(self.rest[u2 as usize]),
                tie: self.ties.rank[ui],
                vertex: u,
                version: self.collapse_version[ui],
            }));
        }
    }

    /// Finds `u`'s cheapest influence removal (§5) and queues it.
    pub(crate) fn evaluate_influence(&mut self, u: u32) {
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
                length: 0.0,
                tie: self.ties.rank[ui],
                vertex: u,
                version: self.influence_version[ui],
            }));
        }
    }

    /// Queues the removal of part `part` at its current diameter.
    pub(crate) fn queue_prune(&mut self, part: u32) {
        if let Some(cost) = self.part_diameter(part) {
            // A part ranks as its first position does.
            let tie = self.parts[part as usize]
                .iter()
                .map(|&u| self.ties.rank[u as usize])
                .min()
                .unwrap_or(u32::MAX);
            self.heap.push(Reverse(Entry {
                cost,
                action: Action::Prune,
                length: 0.0,
                tie,
                vertex: part,
                version: 0,
            }));
        }
    }

    /// How far the surface moves when part `part` goes: its diameter in the metric (twice the
    /// largest distance of its positions from their mean). `None` once nothing of it is left.
    pub(crate) fn part_diameter(&self, part: u32) -> Option<f64> {
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
    pub(crate) fn best_removal(&mut self, u: u32) -> Option<(f64, usize)> {
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

    pub(crate) fn apply_collapse(&mut self, u1: u32, u2: u32) -> StepKind {
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
    pub(crate) fn apply_prune(&mut self, part: u32) -> StepKind {
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

    pub(crate) fn apply_influence(&mut self, u: u32) -> StepKind {
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
pub(crate) struct Workspace {
    pub(crate) scratch: Scratch,
    pub(crate) neighbours: Vec<u32>,
}

/// A [`Workspace`] taken from a pool for one parallel task, and put back when it ends, so
/// that scratch space is allocated once per thread rather than once per collapse.
pub(crate) struct Pooled<'p> {
    pub(crate) pool: &'p Mutex<Vec<Workspace>>,
    pub(crate) workspace: Workspace,
}

impl<'p> Pooled<'p> {
    pub(crate) fn take(pool: &'p Mutex<Vec<Workspace>>) -> Pooled<'p> {
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

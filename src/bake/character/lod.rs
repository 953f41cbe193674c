//! Discrete levels of detail cut from a progressive mesh, with geomorph maps between them.
//!
//! A [`Sequence`] is every simplification in order. Level k is the longest prefix whose error
//! stays within `e_k`, with `e_k` doubling from a base tolerance (or the first prefix within a
//! triangle budget), down to a floor of about a hundred triangles. "Error" is the true one:
//! the memoryless bound of the steps so far, or the measured distance from full detail if that
//! is larger ([`SurfaceProbe`]: closest points both ways, the worst of the sampled poses). The
//! memoryless bound alone can drift from the truth over many steps, and for the rest-pose
//! method it knows nothing of the animation; a level's error is what the renderer projects to
//! pixels, so it must not flatter. Each level holds
//! its render vertices with their animation-space influences *at that level* (influence
//! simplification changes them), its triangles, and a geomorph map: for every vertex, the
//! vertex of the next coarser level it ends up as, following the half-edge collapses in
//! between (Houle & Poulin §5.1). A renderer can then morph any vertex of level k towards level
//! k+1 with `v = (1−t)·Σ G_i p_i(fine) + t·Σ G_j p_j(coarse)` (Merry et al. §6.4).

use super::lod_error::SurfaceProbe;
use super::simplify::expectation::ExpectationMatrix;
use super::simplify::mesh::Mesh;
use super::simplify::{
    Feed, FirstPricing, Method, Prepared, Sequence, SimplifyInput, Stats, Step, StepKind, gathered,
    pose_samples, simplify_prepared,
};
use crate::bake::gpu_data::animation_space::{AnimationSpaceMesh, AsInfluence};
use crate::model::Model;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::sync::OnceLock;
use std::sync::mpsc::{self, Receiver};

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

/// The prefixes of `seq` that become levels by the memoryless bound alone, finest first
/// (always starting with 0).
pub fn choose_prefixes(seq: &Sequence, opts: &LodOptions) -> Vec<usize> {
    let steps = seq.steps.len();
    // The error bound never falls along the sequence: the search is binary.
    let last_above_floor = last_above_floor(seq, opts);
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
#[derive(Clone)]
pub struct Replay<'a> {
    base: &'a AnimationSpaceMesh,
    mesh: Mesh,
    /// Influences of the render vertices that an influence simplification changed, as of the
    /// steps applied; every other vertex has the base mesh's. Only the changes are held: the
    /// cut search clones a replay for each probe, and on a 2-million-triangle model a copy of
    /// every vertex's list was about 100 MB a clone.
    influences: rustc_hash::FxHashMap<u32, Vec<AsInfluence>>,
    /// Where each render vertex went when its position collapsed.
    collapsed_to: Vec<u32>,
    applied: usize,
}

impl<'a> Replay<'a> {
    /// The full-detail mesh `base` that `seq` (whose steps may still be coming, see
    /// [`GrowingSequence`]) starts from.
    pub fn new(base: &'a AnimationSpaceMesh, seq: &Sequence) -> Replay<'a> {
        let mesh = Mesh::new(&base.indices, seq.positions.clone());
        let n = base.vertex_count();
        Replay {
            base,
            mesh,
            influences: rustc_hash::FxHashMap::default(),
            collapsed_to: vec![u32::MAX; n],
            applied: 0,
        }
    }

    /// Applies steps of `seq` until `prefix` of them are applied (never goes back).
    pub fn advance_to(&mut self, seq: &Sequence, prefix: usize) {
        while self.applied < prefix.min(seq.steps.len()) {
            match &seq.steps[self.applied].kind {
                StepKind::Collapse { wedges } => {
                    let u1 = self.mesh.pos(wedges[0][0]);
                    let u2 = self.mesh.pos(wedges[0][1]);
                    let (_, released) = self.mesh.collapse(u1, u2, wedges);
                    for &[from, to] in wedges {
                        self.collapsed_to[from as usize] = to;
                    }
                    // A wedge of a position that stays (its chart's last triangles were on the
                    // collapsed edge) goes on as another wedge of that position: the same
                    // point, so a geomorph follows it there.
                    for r in released {
                        let p = self.mesh.pos(r) as usize;
                        if self.collapsed_to[r as usize] == u32::MAX
                            && self.mesh.alive[p]
                            && let Some(&w) = self.mesh.wedges[p].first()
                        {
                            self.collapsed_to[r as usize] = w;
                        }
                    }
                }
                StepKind::Influence {
                    wedges, influences, ..
                } => {
                    for (&w, list) in wedges.iter().zip(influences) {
                        self.influences.insert(w, list.clone());
                    }
                }
                StepKind::Prune { wedges, anchor } => {
                    let mut positions: Vec<u32> =
                        wedges.iter().map(|&w| self.mesh.pos(w)).collect();
                    positions.sort_unstable();
                    positions.dedup();
                    self.mesh.prune(&positions);
                    for &w in wedges {
                        self.collapsed_to[w as usize] = anchor.unwrap_or(u32::MAX);
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
        match self.influences.get(&r) {
            Some(list) => list,
            None => self.base.influences_of(r as usize),
        }
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

    /// How many steps are applied.
    pub fn applied(&self) -> usize {
        self.applied
    }

    /// The current mesh's distance from full detail, exact above `resolution` (see
    /// [`SurfaceProbe::measure`]).
    fn measure(&self, probe: &SurfaceProbe, resolution: f32) -> f32 {
        let start = std::time::Instant::now();
        let tris: Vec<[u32; 3]> = self.triangles().collect();
        let follow = |r: u32| self.follow(r);
        let max = probe
            .measure(
                &tris,
                |r| self.influences_of(r),
                Some(&follow),
                resolution as f64,
            )
            .max as f32;
        log::debug!(
            "measured {} triangles in {} frames: {max:.3e} in {:.2} s",
            tris.len(),
            probe.frame_count(),
            start.elapsed().as_secs_f64()
        );
        max
    }

    /// The current mesh as a compact level: used vertices only, GPU order.
    fn snapshot(&self, prefix: usize, error: f32, bound: f32) -> LodLevel {
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
            crown_occlusion: Vec::new(),
            view_windows: Vec::new(),
        };
        for &r in &used {
            compact.influences.extend_from_slice(self.influences_of(r));
            compact.offsets.push(compact.influences.len() as u32);
        }
        let (mesh, order) = compact.optimized_for_gpu_with_order();
        LodLevel {
            prefix: prefix as u32,
            error,
            bound,
            mesh,
            source: order.iter().map(|&i| used[i]).collect(),
            geomorph: Vec::new(),
        }
    }
}

/// Cuts the levels at `prefixes` (ascending) and links each to the next by its geomorph map.
/// Each level's error is its memoryless bound.
pub fn extract(base: &AnimationSpaceMesh, seq: &Sequence, prefixes: &[usize]) -> Vec<LodLevel> {
    let mut replay = Replay::new(base, seq);
    let mut chain = Chain::default();
    for &prefix in prefixes {
        replay.advance_to(seq, prefix);
        chain.push(&replay, seq, seq.error_after(prefix), 1.0);
    }
    chain.levels
}

/// Levels as they are cut, finest first, each linked to the next by its geomorph map.
#[derive(Default)]
struct Chain {
    levels: Vec<LodLevel>,
}

impl Chain {
    /// Adds the mesh `replay` has reached as the next level, with error `error`. A level whose
    /// next one is no less exact would never be drawn (the renderer shows the coarsest level
    /// within the tolerance): it is replaced. So is one whose next one's error is less than
    /// `min_growth` times its own: it would be drawn only over a sliver of distances, and a
    /// transition towards it would run on past it.
    fn push(&mut self, replay: &Replay, seq: &Sequence, error: f32, min_growth: f32) {
        let prefix = replay.applied();
        let level = replay.snapshot(prefix, error, seq.error_after(prefix));
        // A level whose every triangle has two corners at one point in every pose (influence
        // simplification can give two vertices at one rest point the same influences) would
        // show nothing: the coarsest level that draws stays the coarsest.
        if !self.levels.is_empty() && !level.mesh.draws() {
            return;
        }
        if self.levels.len() > 1
            && self
                .levels
                .last()
                .is_some_and(|l| l.error * min_growth >= error)
        {
            self.levels.pop();
        }
        if let Some(prev) = self.levels.last_mut() {
            let mut index = vec![u32::MAX; replay.base.vertex_count()];
            for (i, &r) in level.source.iter().enumerate() {
                index[r as usize] = i as u32;
            }
            prev.geomorph = prev
                .source
                .iter()
                .map(|&r| {
                    let to = replay.follow(r);
                    match index[to as usize] {
                        u32::MAX => nearest_in_chart(replay.base, &level, r),
                        i => i,
                    }
                })
                .collect();
        }
        self.levels.push(level);
    }
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

/// The levels of `seq` with their true errors (see the module comment).
///
/// By error, level k is cut at a prefix within `e_k`. The first guess is where the memoryless
/// bound reaches `e_k` divided by how far the last level's measured error exceeded its bound
/// (the two grow together), measured finely; if that is over `e_k`, the cut halves back from
/// there with quick measurements ([`CUT_PROBES`] in all), and the prefix found is measured
/// finely for its error. If no probe is within `e_k`, the coarsest within `2 e_k` stands, so
/// consecutive levels stay about a doubling apart; if none is within that either there is no
/// level at `e_k`. By budget, level k is the first prefix within each budget, measured. Errors
/// never fall from one level to the next.
pub fn cut_levels(
    base: &AnimationSpaceMesh,
    seq: &Sequence,
    opts: &LodOptions,
    probes: &LevelProbes,
) -> Vec<LodLevel> {
    cut_growing_levels(base, &mut GrowingSequence::complete(seq), opts, probes)
}

/// [`cut_levels`] of a sequence whose steps may still be coming: each question waits for the
/// steps that decide it, so the levels come out the same as from the whole sequence.
pub fn cut_growing_levels(
    base: &AnimationSpaceMesh,
    seq: &mut GrowingSequence,
    opts: &LodOptions,
    probes: &LevelProbes,
) -> Vec<LodLevel> {
    let mut at = Replay::new(base, seq.known());
    let mut chain = Chain::default();
    chain.push(&at, seq.known(), 0.0, 1.0);
    // Levels cut by error are about a doubling apart; one within a quarter of the next is a
    // near-duplicate. Levels cut by budget are what the user asked for: only exact duplicates
    // go.
    let min_growth = if opts.budgets.is_some() {
        1.0
    } else {
        MIN_ERROR_GROWTH
    };
    let push = |chain: &mut Chain, seq: &Sequence, at: &Replay, measured: f32| {
        let last = chain.levels.last().map_or(0.0, |l| l.error);
        let error = seq.error_after(at.applied()).max(measured).max(last);
        chain.push(at, seq, error, min_growth);
    };
    match &opts.budgets {
        Some(_) => {
            let seq = seq.whole();
            for &p in &choose_prefixes(seq, opts)[1..] {
                at.advance_to(seq, p);
                let resolution = RESOLUTION * seq.error_after(p);
                let measured = at.measure(&probes.label, resolution);
                push(&mut chain, seq, &at, measured);
            }
        }
        None => {
            let floor = opts.floor_triangles.min(seq.known().base_triangle_count());
            let mut ratio = 1.0f32;
            let mut e = opts.base_error.max(f32::MIN_POSITIVE);
            loop {
                let search = CutSearch { floor, probes };
                if let Some((found, measured)) = search.next_level(seq, &at, e, ratio) {
                    at = found;
                    let bound = seq.known().error_after(at.applied());
                    if bound > 0.0 {
                        ratio = (measured / bound).max(1.0);
                    }
                    push(&mut chain, seq.known(), &at, measured);
                }
                if seq.at_floor(at.applied(), floor) || !e.is_finite() {
                    break;
                }
                e *= 2.0;
            }
        }
    }
    chain.levels
}

/// A sequence as the simplifier hands it over, steps in batches down a channel (see
/// [`bake_lods`]), or whole. What [`cut_growing_levels`] asks of it waits for the steps that
/// decide the answer, so levels are cut while the simplifier runs on, and the cut's
/// measurements and the simplification share the machine's cores.
pub struct GrowingSequence<'s> {
    seq: Cow<'s, Sequence>,
    feed: Option<Receiver<Vec<Step>>>,
}

impl<'s> GrowingSequence<'s> {
    /// A sequence with all its steps.
    pub fn complete(seq: &'s Sequence) -> GrowingSequence<'s> {
        GrowingSequence {
            seq: Cow::Borrowed(seq),
            feed: None,
        }
    }

    /// `start` (everything but the steps), the steps to come from `feed` until it closes.
    pub fn fed(start: Sequence, feed: Receiver<Vec<Step>>) -> GrowingSequence<'static> {
        GrowingSequence {
            seq: Cow::Owned(start),
            feed: Some(feed),
        }
    }

    /// The steps received so far.
    pub fn known(&self) -> &Sequence {
        &self.seq
    }

    /// Receives steps until `enough` holds of those known, or there are no more.
    fn wait(&mut self, enough: impl Fn(&[Step]) -> bool) {
        while let Some(feed) = &self.feed {
            if enough(&self.seq.steps) {
                return;
            }
            match feed.recv() {
                Ok(steps) => self.seq.to_mut().steps.extend(steps),
                Err(_) => self.feed = None,
            }
        }
    }

    /// The whole sequence, once the last step has come.
    fn whole(&mut self) -> &Sequence {
        self.wait(|_| false);
        &self.seq
    }

    /// [`Self::whole`], owned.
    pub fn into_whole(mut self) -> Sequence {
        self.wait(|_| false);
        self.seq.into_owned()
    }

    /// How many steps keep the bound within `e`, no more than keep `floor` triangles. Bounds
    /// never fall along the sequence: the first step over `e` settles it.
    fn within(&mut self, e: f32, floor: u32) -> usize {
        self.wait(|steps| steps.last().is_some_and(|s| s.max_cost > e));
        let steps = &self.seq.steps;
        let p = steps.partition_point(|s| s.max_cost <= e);
        steps[..p].partition_point(|s| s.triangles >= floor)
    }

    /// Whether `prefix` steps reach the floor of `floor` triangles: the next step (if any)
    /// leaves fewer. Triangles never grow along the sequence.
    fn at_floor(&mut self, prefix: usize, floor: u32) -> bool {
        self.wait(|steps| steps.len() > prefix);
        self.seq
            .steps
            .get(prefix)
            .is_none_or(|s| s.triangles < floor)
    }
}

/// Levels cut by error whose errors grow by less than this from one to the next: the finer is
/// dropped (see [`Chain::push`]).
const MIN_ERROR_GROWTH: f32 = 1.25;

/// Measurements one level's cut may take (see [`cut_levels`]).
const CUT_PROBES: usize = 4;
/// A level's distance from full detail is measured exactly only above this share of the error
/// it is cut for: only the largest distances decide a cut and its error.
const RESOLUTION: f32 = 0.25;

/// The search for one level's cut (see [`cut_levels`]).
struct CutSearch<'p> {
    /// No level has fewer triangles than this (unless the full detail has).
    floor: u32,
    probes: &'p LevelProbes<'p>,
}

impl CutSearch<'_> {
    /// From `from` (the last level), the next level's prefix for error `e` and its finely
    /// measured error; `None` if there is none.
    fn next_level<'a>(
        &self,
        seq: &mut GrowingSequence,
        from: &Replay<'a>,
        e: f32,
        ratio: f32,
    ) -> Option<(Replay<'a>, f32)> {
        let lo = from.applied();
        let hi = seq.within(e, self.floor);
        if hi <= lo {
            return None;
        }
        // Within e's steps, so already known.
        let guess = seq.within(e / ratio, self.floor).clamp(lo + 1, hi);
        let seq = seq.known();
        let probe_at = |start: &Replay<'a>, prefix: usize, probe: &SurfaceProbe| {
            let mut r = start.clone();
            r.advance_to(seq, prefix);
            let m = r.measure(probe, RESOLUTION * e);
            (r, m)
        };
        let (first, m) = probe_at(from, guess, &self.probes.label);
        if m <= e {
            return Some((first, m));
        }
        drop(first);
        // Over e: the coarsest probe within 2e stands in if nothing within e turns up. It is
        // kept as its prefix and replayed again if it is needed: a replay of a 2-million-
        // triangle model is about 100 MB, and several methods cut their levels at once.
        let mut fallback = (m <= 2.0 * e).then_some((guess, Some(m)));
        let mut good: Option<Replay<'a>> = None;
        let mut bad = guess;
        for _ in 1..CUT_PROBES {
            let known = good.as_ref().map_or(lo, |g| g.applied());
            let candidate = known + (bad - known) / 2;
            if candidate <= known {
                break;
            }
            let (r, m) = probe_at(
                good.as_ref().unwrap_or(from),
                candidate,
                &self.probes.search,
            );
            if m <= e {
                good = Some(r);
            } else {
                bad = candidate;
                if m <= 2.0 * e && fallback.is_none() {
                    fallback = Some((candidate, None));
                }
            }
        }
        let (r, measured) = match good {
            Some(r) => (r, None),
            None => {
                let (prefix, measured) = fallback?;
                let mut r = from.clone();
                r.advance_to(seq, prefix);
                (r, measured)
            }
        };
        let m = measured.unwrap_or_else(|| r.measure(&self.probes.label, RESOLUTION * e));
        Some((r, m))
    }
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

/// The full-detail mesh of `model` in animation space (GPU order) and its progressive mesh by
/// `method`, with the wall time the simplification took (estimating `P` included).
pub fn progressive_mesh(
    model: &Model,
    method: Method,
    progress: &(dyn Fn(f32) + Sync),
) -> (AnimationSpaceMesh, Sequence, f64) {
    let base = full_detail(model);
    let start = std::time::Instant::now();
    let sequence =
        gathered(|feed| SharedBake::default().simplify(model, &base, method, progress, feed));
    let seconds = start.elapsed().as_secs_f64();
    (base, sequence, seconds)
}

/// `model`'s mesh in animation space, in GPU order: what every level is cut from.
pub fn full_detail(model: &Model) -> AnimationSpaceMesh {
    AnimationSpaceMesh::from_skinned(&model.mesh, &model.skeleton).optimized_for_gpu()
}

/// What the bakes of one model by several methods share, made by the first bake that needs
/// each (see [`bake_lods_sharing`]): the probes its levels are measured with, what the
/// simplifier prepares of its full detail ([`Prepared`]), the expectation matrix `P` and the
/// first pricing of every position in animation space ([`FirstPricing`]), which AS and AS+IS
/// share.
/// On a 2-million-triangle model the probes are about a gigabyte and several seconds, the
/// preparation five seconds and half a gigabyte, and the first pricing a quarter of a
/// method's simplification: three methods baking at once each made them again.
#[derive(Default)]
pub struct SharedBake<'a> {
    probes: OnceLock<LevelProbes<'a>>,
    prepared: OnceLock<Prepared>,
    expectation: OnceLock<ExpectationMatrix>,
    as_start: OnceLock<FirstPricing>,
}

impl<'a> SharedBake<'a> {
    /// The probes the levels of `model` (full detail `base`) are measured with.
    fn probes(&self, model: &Model, base: &'a AnimationSpaceMesh) -> &LevelProbes<'a> {
        self.probes.get_or_init(|| LevelProbes::new(model, base))
    }

    /// The progressive mesh of `base` (the full detail of `model`) by `method`, handed to
    /// `feed` as it is built, from what the bakes share; returns its statistics (see
    /// [`super::simplify::simplify_feeding`]).
    fn simplify(
        &self,
        model: &Model,
        base: &AnimationSpaceMesh,
        method: Method,
        progress: &(dyn Fn(f32) + Sync),
        feed: &mut (dyn FnMut(Feed) + Send),
    ) -> Stats {
        let prepared = self.prepared.get_or_init(|| prepare(model, base));
        match method {
            // No other method ranks by the rest pose: its first pricing is its own.
            Method::RestPose => {
                let none = ExpectationMatrix::from_poses(0, std::iter::empty::<Vec<_>>());
                let start = OnceLock::new();
                simplify_prepared(prepared, &none, &start, method, progress, feed)
            }
            Method::AnimationSpace | Method::InfluenceSimplification => {
                let pm = self
                    .expectation
                    .get_or_init(|| ExpectationMatrix::estimate(model));
                simplify_prepared(prepared, pm, &self.as_start, method, progress, feed)
            }
        }
    }
}

/// What the simplifier makes of `base` (the full detail of `model`) whatever the method
/// ([`Prepared`]).
fn prepare(model: &Model, base: &AnimationSpaceMesh) -> Prepared {
    let rest_bones = SimplifyInput::rest_bones(&model.skeleton);
    let poses = pose_samples(model, POSE_SAMPLES);
    let textured: Vec<bool> = model
        .materials
        .iter()
        .map(|m| m.texture.is_some())
        .collect();
    Prepared::new(base, &rest_bones, &poses, &textured)
}

/// Builds the progressive mesh of `model` by `method` and cuts its levels. The levels are cut
/// on a second thread as the steps come (see [`GrowingSequence`]): the same levels as cutting
/// the finished sequence, sooner where there are cores to spare.
pub fn bake_lods(
    model: &Model,
    method: Method,
    opts: &LodOptions,
    progress: &(dyn Fn(f32) + Sync),
) -> SkinnedLods {
    let start = std::time::Instant::now();
    let base = full_detail(model);
    let shared = SharedBake::default();
    let mut lods = bake_lods_sharing(model, &base, &shared, method, opts, progress);
    lods.bake_seconds = start.elapsed().as_secs_f64();
    lods
}

/// [`bake_lods`] of a model whose bakes by several methods share its full-detail mesh `base`
/// ([`full_detail`]) and `shared` ([`SharedBake`]): what one bake makes there the others
/// take, and a cutter waits for the probes while its simplifier goes on.
pub fn bake_lods_sharing<'a>(
    model: &Model,
    base: &'a AnimationSpaceMesh,
    shared: &SharedBake<'a>,
    method: Method,
    opts: &LodOptions,
    progress: &(dyn Fn(f32) + Sync),
) -> SkinnedLods {
    let start = std::time::Instant::now();
    let (sequence, levels) = std::thread::scope(|scope| {
        // Made inside the scope, so that a panicking simplifier drops them and the cutter,
        // seeing the channel close, ends before the scope joins it.
        let (start_tx, start_rx) = mpsc::channel::<Sequence>();
        let (steps_tx, steps_rx) = mpsc::channel::<Vec<Step>>();
        let cutter = scope.spawn(move || {
            let probes = shared.probes(model, base);
            // No start: the simplifier stopped before its first step (it panicked).
            let first = start_rx.recv().ok()?;
            let mut seq = GrowingSequence::fed(first, steps_rx);
            let levels = cut_growing_levels(base, &mut seq, opts, probes);
            // The cutter holds the only copy of the steps: the rest of them, if the floor
            // came before the end.
            Some((levels, seq.into_whole()))
        });
        // A closed channel means the cutter panicked: joining it below says so.
        let stats = shared.simplify(model, base, method, progress, &mut |feed| match feed {
            Feed::Start(first) => {
                let _ = start_tx.send(first);
            }
            Feed::Steps(steps) => {
                let _ = steps_tx.send(steps);
            }
        });
        drop(steps_tx);
        // A bake among others in a parallel loop runs on a pool worker: blocked here, it could
        // leave the cutter's measurements, which need the pool, with no worker to run them
        // (every worker waiting for its own cutter). So it keeps working while it waits.
        if rayon::current_thread_index().is_some() {
            while !cutter.is_finished() {
                if rayon::yield_now() != Some(rayon::Yield::Executed) {
                    std::thread::sleep(std::time::Duration::from_micros(200));
                }
            }
        }
        let (levels, mut sequence) = match cutter.join() {
            Ok(cut) => cut.expect("the simplifier hands over its start"),
            Err(panic) => std::panic::resume_unwind(panic),
        };
        sequence.stats = stats;
        (sequence, levels)
    });
    let bake_seconds = start.elapsed().as_secs_f64();
    log::debug!(
        "{} by {method}: {} steps, {} levels ({} triangles at the coarsest), {bake_seconds:.2} s",
        model.name,
        sequence.steps.len(),
        levels.len(),
        levels.last().map_or(0, LodLevel::triangles)
    );
    SkinnedLods {
        model: model.name.clone(),
        method,
        options: opts.clone(),
        levels,
        sequence,
        bake_seconds,
    }
}

/// The measurements [`cut_levels`] makes of `model`'s levels (full-detail mesh `base`): a
/// quick one while it looks for a cut, and a finer one for the error each level is given.
pub struct LevelProbes<'a> {
    pub search: SurfaceProbe<'a>,
    pub label: SurfaceProbe<'a>,
}

impl<'a> LevelProbes<'a> {
    pub fn new(model: &Model, base: &'a AnimationSpaceMesh) -> LevelProbes<'a> {
        let search =
            SurfaceProbe::new(model, base, 250, 250, pose_samples(model, 6)).with_candidates(3);
        let label = SurfaceProbe::sharing(&search, 800, 800, pose_samples(model, 10))
            .with_candidates(4)
            .every_vertex();
        LevelProbes { search, label }
    }
}

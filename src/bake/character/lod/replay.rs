//! Replaying a simplifier's collapse sequence: the mesh after any prefix of it, and the
//! chain of vertices each removed vertex collapsed into (Merry et al. §6.4's geomorphs follow
//! it).

use crate::bake::character::lod::levels::LodLevel;
use crate::bake::character::lod_error::SurfaceProbe;
use crate::bake::character::simplify::mesh::Mesh;
use crate::bake::character::simplify::{Sequence, Step, StepKind};
use crate::bake::gpu_data::animation_space::{AnimationSpaceMesh, AsInfluence};
use std::borrow::Cow;
use std::sync::mpsc::Receiver;

/// Replays a sequence step by step on the full-detail mesh.
#[derive(Clone)]
pub struct Replay<'a> {
    pub(crate) base: &'a AnimationSpaceMesh,
    pub(crate) mesh: Mesh,
    /// Influences of the render vertices that an influence simplification changed, as of the
    /// steps applied; every other vertex has the base mesh's. Only the changes are held: the
    /// cut search clones a replay for each probe, and on a 2-million-triangle model a copy of
    /// every vertex's list was about 100 MB a clone.
    pub(crate) influences: rustc_hash::FxHashMap<u32, Vec<AsInfluence>>,
    /// Where each render vertex went when its position collapsed.
    pub(crate) collapsed_to: Vec<u32>,
    pub(crate) applied: usize,
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
    pub(crate) fn measure(&self, probe: &SurfaceProbe, resolution: f32) -> f32 {
        let start = web_time::Instant::now();
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
    pub(crate) fn snapshot(&self, prefix: usize, error: f32, bound: f32) -> LodLevel {
        let mut level = compact_level(self.base, self.triangles(), |r| self.influences_of(r));
        level.prefix = prefix as u32;
        level.error = error;
        level.bound = bound;
        level
    }
}

/// A level made of `triangles` of `base`'s render vertices, each with `influences(r)`: only
/// the vertices used, in the order a GPU draws fastest, with their full-detail numbers
/// (`source`); no geomorph map yet, and its prefix, error and bound 0.
pub(crate) fn compact_level<'i>(
    base: &AnimationSpaceMesh,
    triangles: impl Iterator<Item = [u32; 3]>,
    influences: impl Fn(u32) -> &'i [AsInfluence],
) -> LodLevel {
    let n = base.vertex_count();
    let mut local = vec![u32::MAX; n];
    let mut used: Vec<u32> = Vec::new();
    let mut indices = Vec::new();
    for t in triangles {
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
        uvs: used.iter().map(|&r| base.uvs[r as usize]).collect(),
        materials: used.iter().map(|&r| base.materials[r as usize]).collect(),
        indices,
        spectral_rows: Vec::new(),
        crown_occlusion: Vec::new(),
        view_windows: Vec::new(),
    };
    for &r in &used {
        compact.influences.extend_from_slice(influences(r));
        compact.offsets.push(compact.influences.len() as u32);
    }
    let (mesh, order) = compact.optimized_for_gpu_with_order();
    LodLevel {
        prefix: 0,
        error: 0.0,
        bound: 0.0,
        mesh,
        source: order.iter().map(|&i| used[i]).collect(),
        geomorph: Vec::new(),
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
pub(crate) struct Chain {
    pub(crate) levels: Vec<LodLevel>,
}

impl Chain {
    /// Adds the mesh `replay` has reached as the next level, with error `error`. A level whose
    /// next one is no less exact would never be drawn (the renderer shows the coarsest level
    /// within the tolerance): it is replaced. So is one whose next one's error is less than
    /// `min_growth` times its own: it would be drawn only over a sliver of distances, and a
    /// transition towards it would run on past it.
    pub(crate) fn push(&mut self, replay: &Replay, seq: &Sequence, error: f32, min_growth: f32) {
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
pub(crate) fn nearest_in_chart(base: &AnimationSpaceMesh, level: &LodLevel, r: u32) -> u32 {
    let uv = base.uvs[r as usize];
    (0..level.vertices())
        .min_by(|&a, &b| {
            let da = level.mesh.uvs[a].distance_squared(uv);
            let db = level.mesh.uvs[b].distance_squared(uv);
            da.total_cmp(&db)
        })
        .unwrap_or(0) as u32
}

/// A sequence as the simplifier hands it over, steps in batches down a channel (see
/// [`bake_lods`](super::bake_lods)), or whole. What [`cut_growing_levels`](super::cut::cut_growing_levels) asks of it waits for the steps that
/// decide the answer, so levels are cut while the simplifier runs on, and the cut's
/// measurements and the simplification share the machine's cores.
pub struct GrowingSequence<'s> {
    pub(crate) seq: Cow<'s, Sequence>,
    pub(crate) feed: Option<Receiver<Vec<Step>>>,
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
    pub(crate) fn wait(&mut self, enough: impl Fn(&[Step]) -> bool) {
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
    pub(crate) fn whole(&mut self) -> &Sequence {
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
    pub(crate) fn within(&mut self, e: f32, floor: u32) -> usize {
        self.wait(|steps| steps.last().is_some_and(|s| s.max_cost > e));
        let steps = &self.seq.steps;
        let p = steps.partition_point(|s| s.max_cost <= e);
        steps[..p].partition_point(|s| s.triangles >= floor)
    }

    /// Whether `prefix` steps reach the floor of `floor` triangles: the next step (if any)
    /// leaves fewer. Triangles never grow along the sequence.
    pub(crate) fn at_floor(&mut self, prefix: usize, floor: u32) -> bool {
        self.wait(|steps| steps.len() > prefix);
        self.seq
            .steps
            .get(prefix)
            .is_none_or(|s| s.triangles < floor)
    }
}

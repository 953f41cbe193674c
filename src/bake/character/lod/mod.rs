//! Discrete levels of detail cut from a progressive mesh, with geomorph maps between them.
//!
//! A [`Sequence`] is every simplification in order. Level k is the longest prefix whose error
//! stays within `e_k`, with `e_k` doubling from a base tolerance (or the first prefix within a
//! triangle budget), down to a floor of about a hundred triangles. "Error" is the true one:
//! the memoryless bound of the steps so far, or the measured distance from full detail if that
//! is larger ([`SurfaceProbe`](crate::bake::character::lod_error::SurfaceProbe): closest points both ways, the worst of the sampled poses). The
//! memoryless bound alone can drift from the truth over many steps, and for the rest-pose
//! method it knows nothing of the animation; a level's error is what the renderer projects to
//! pixels, so it must not flatter. Each level holds
//! its render vertices with their animation-space influences *at that level* (influence
//! simplification changes them), its triangles, and a geomorph map: for every vertex, the
//! vertex of the next coarser level it ends up as, following the half-edge collapses in
//! between (Houle & Poulin §5.1). A renderer can then morph any vertex of level k towards level
//! k+1 with `v = (1−t)·Σ G_i p_i(fine) + t·Σ G_j p_j(coarse)` (Merry et al. §6.4).

pub mod cached;
pub mod cut;
pub mod levels;
// meshoptimizer is C++: the web build goes without it (its levels come from the desktop's bake).
#[cfg(not(target_arch = "wasm32"))]
pub mod meshopt;
pub mod replay;

use cut::cut_growing_levels;
pub use cut::{LevelProbes, choose_prefixes, cut_levels};
pub use levels::{
    LodLevel, LodOptions, POSE_SAMPLES, SkinnedLods, floor_triangles, lod_options, model_height,
};
use replay::GrowingSequence;
pub use replay::{Replay, extract};

use super::simplify::expectation::ExpectationMatrix;
use super::simplify::influences64;
use super::simplify::mesh::{Mesh, weld_positions};
use super::simplify::{
    Feed, FirstPricing, Method, Prepared, Sequence, SimplifyInput, Stats, Step, Ties, gathered,
    pose_samples, simplify_prepared,
};
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use crate::model::Model;
use std::collections::BTreeMap;
use std::sync::OnceLock;
use std::sync::mpsc::{self};
use std::sync::{Arc, Mutex};

/// The full-detail mesh of `model` in animation space (GPU order) and its progressive mesh by
/// `method`, with the wall time the simplification took (estimating `P` included).
pub fn progressive_mesh(
    model: &Model,
    method: Method,
    progress: &(dyn Fn(f32) + Sync),
) -> (AnimationSpaceMesh, Sequence, f64) {
    let base = full_detail(model);
    let start = web_time::Instant::now();
    let sequence = SharedBake::default().sequence(model, &base, method, 0, progress);
    let seconds = start.elapsed().as_secs_f64();
    (base, sequence, seconds)
}

/// `model`'s mesh in animation space, in GPU order: what every level is cut from.
pub fn full_detail(model: &Model) -> AnimationSpaceMesh {
    AnimationSpaceMesh::from_skinned(&model.mesh, &model.skeleton).optimized_for_gpu()
}

/// What the bakes of one model by several methods share, made by the first bake that needs
/// each (see [`bake_lods_sharing`]): the probes its levels are measured with, what the
/// simplifier prepares of its full detail ([`Prepared`]), the expectation matrix `P`, and per
/// tie order ([`Ties`]) the order itself and the first pricing of every position in animation
/// space ([`FirstPricing`]), which AS and AS+IS share.
/// On a 2-million-triangle model the probes are about a gigabyte and several seconds, the
/// preparation five seconds and half a gigabyte, and the first pricing a quarter of a
/// method's simplification: three methods baking at once each made them again. `report`'s
/// bakes in several tie orders share all but the last two.
#[derive(Default)]
pub struct SharedBake<'a> {
    probes: OnceLock<LevelProbes<'a>>,
    prepared: OnceLock<Prepared>,
    expectation: OnceLock<ExpectationMatrix>,
    by_order: Mutex<BTreeMap<u32, Arc<InOrder>>>,
}

/// What the bakes in one tie order share.
struct InOrder {
    ties: Ties,
    as_start: OnceLock<FirstPricing>,
}

impl<'a> SharedBake<'a> {
    /// The probes the levels of `model` (full detail `base`) are measured with.
    fn probes(&self, model: &Model, base: &'a AnimationSpaceMesh) -> &LevelProbes<'a> {
        self.probes.get_or_init(|| LevelProbes::new(model, base))
    }

    /// The progressive mesh of `base` (the full detail of `model`) by `method`, its ties
    /// broken in tie order `order` (0 is the order every level the viewer draws is baked in,
    /// see [`Ties`]), from what the bakes share.
    pub fn sequence(
        &self,
        model: &Model,
        base: &AnimationSpaceMesh,
        method: Method,
        order: u32,
        progress: &(dyn Fn(f32) + Sync),
    ) -> Sequence {
        gathered(|feed| self.simplify(model, base, method, order, progress, feed))
    }

    /// [`Self::sequence`], handed to `feed` as it is built; returns its statistics (see
    /// [`super::simplify::simplify_feeding`]).
    fn simplify(
        &self,
        model: &Model,
        base: &AnimationSpaceMesh,
        method: Method,
        order: u32,
        progress: &(dyn Fn(f32) + Sync),
        feed: &mut (dyn FnMut(Feed) + Send),
    ) -> Stats {
        // meshoptimizer hands back levels, not collapses: its sequence is the start alone, and
        // it needs nothing the simplifier prepares.
        if method == Method::Meshopt {
            feed(Feed::Start(no_steps(model, base, method)));
            return Stats::default();
        }
        let prepared = self.prepared.get_or_init(|| prepare(model, base));
        let in_order = Arc::clone(
            self.by_order
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .entry(order)
                .or_insert_with(|| {
                    Arc::new(InOrder {
                        ties: prepared.ties(order),
                        as_start: OnceLock::new(),
                    })
                }),
        );
        let ties = &in_order.ties;
        match method {
            // No other method ranks by the rest pose: its first pricing is its own.
            Method::RestPose => {
                let none = ExpectationMatrix::from_poses(0, std::iter::empty::<Vec<_>>());
                let start = OnceLock::new();
                simplify_prepared(prepared, ties, &none, &start, method, progress, feed)
            }
            // AS and AS+IS (meshopt has returned above).
            _ => {
                let pm = self
                    .expectation
                    .get_or_init(|| ExpectationMatrix::estimate(model));
                let start = &in_order.as_start;
                simplify_prepared(prepared, ties, pm, start, method, progress, feed)
            }
        }
    }
}

/// A sequence of no steps from `base` (the full detail of `model`): the full detail alone,
/// with its welded positions and its triangles as the simplifier would start from them. Only
/// the welding is done: the rest of a [`Prepared`] (posed positions, charts, parts) is half a
/// gigabyte and seconds on a 2-million-triangle model, which meshoptimizer's levels need none of.
fn no_steps(model: &Model, base: &AnimationSpaceMesh, method: Method) -> Sequence {
    let rest_bones = SimplifyInput::rest_bones(&model.skeleton);
    let infl = influences64(base);
    let rest: Vec<glam::DVec3> = base
        .rest_positions(&rest_bones)
        .iter()
        .map(|p| p.as_dvec3())
        .collect();
    let positions = weld_positions(&rest, &infl);
    let mesh = Mesh::new(&base.indices, positions.clone());
    let influences: usize = (0..positions.len())
        .filter(|&v| mesh.refs[v] > 0)
        .map(|v| infl[positions[v] as usize].len())
        .sum();
    Sequence {
        method,
        positions,
        base_triangles: mesh.tris,
        base_influences: influences as u32,
        steps: Vec::new(),
        stats: Stats::default(),
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
    let start = web_time::Instant::now();
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
    let start = web_time::Instant::now();
    if method == Method::Meshopt {
        #[cfg(not(target_arch = "wasm32"))]
        let (levels, stopped) =
            meshopt::meshopt_levels(model, base, opts, shared.probes(model, base), progress);
        // No meshoptimizer in the browser: full detail alone, said once.
        #[cfg(target_arch = "wasm32")]
        let (levels, stopped) = {
            log::warn!(
                "{}: meshoptimizer's levels are baked on the desktop",
                model.name
            );
            let level = replay::compact_level(
                base,
                base.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]),
                |r| base.influences_of(r as usize),
            );
            (vec![level], None::<u32>)
        };
        if let Some(left) = stopped {
            log::info!(
                "{}: meshoptimizer stops at {left} triangles, above the floor of {} (locked \
                 seams and borders it will not move)",
                model.name,
                opts.floor_triangles
            );
        }
        return SkinnedLods {
            model: model.name.clone(),
            method,
            options: opts.clone(),
            levels,
            sequence: no_steps(model, base, method),
            bake_seconds: start.elapsed().as_secs_f64(),
        };
    }
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
        let stats = shared.simplify(model, base, method, 0, progress, &mut |feed| match feed {
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

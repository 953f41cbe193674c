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
mod flatten;
pub mod influence;
mod input;
pub mod mesh;
mod metric;
mod posed;
mod prepare;
mod queue;
mod sequence;

pub use input::{Method, SimplifyInput, pose_samples};
use metric::Metric;
pub use metric::influences64;
pub use prepare::{Prepared, Ties};
pub use queue::{Feed, FirstPricing};
use queue::{Simplifier, Workspace};
pub use sequence::{Sequence, Stats, Step, StepKind};

use expectation::ExpectationMatrix;
use influence::FactorCache;
use std::borrow::Cow;
use std::collections::BinaryHeap;
use std::sync::{Mutex, OnceLock};

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
    let ties = prepared.ties(0);
    simplify_prepared(
        &prepared,
        &ties,
        input.expectation,
        &start,
        method,
        progress,
        feed,
    )
}

/// [`simplify_feeding`] from a prepared character ([`Prepared`]), ranked by `method` with the
/// expectation matrix `expectation` (unused by the rest-pose method), equal costs taken in
/// the tie order `ties` (made by [`Prepared::ties`]). `start` is the first pricing of every
/// position: made here if it is empty, and left for the other methods that rank by the same
/// metric in the same tie order (see [`FirstPricing`]).
pub fn simplify_prepared(
    prepared: &Prepared,
    ties: &Ties,
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
        ties,
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
    let clock = web_time::Instant::now();
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

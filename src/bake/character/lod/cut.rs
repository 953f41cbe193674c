//! Where a sequence is cut into levels: each level's error bound a fixed factor above the
//! last (or a triangle budget), the prefix found by probing its measured error.

use crate::bake::character::lod::levels::{LodLevel, LodOptions, last_above_floor};
use crate::bake::character::lod::replay::{Chain, GrowingSequence, Replay};
use crate::bake::character::lod_error::SurfaceProbe;
use crate::bake::character::simplify::{Sequence, pose_samples};
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use crate::model::Model;

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

/// Levels cut by error whose errors grow by less than this from one to the next: the finer is
/// dropped (see [`Chain::push`]).
pub(crate) const MIN_ERROR_GROWTH: f32 = 1.25;

/// Measurements one level's cut may take (see [`cut_levels`]).
pub(crate) const CUT_PROBES: usize = 4;
/// A level's distance from full detail is measured exactly only above this share of the error
/// it is cut for: only the largest distances decide a cut and its error.
pub(crate) const RESOLUTION: f32 = 0.25;

/// The search for one level's cut (see [`cut_levels`]).
pub(crate) struct CutSearch<'p> {
    /// No level has fewer triangles than this (unless the full detail has).
    pub(crate) floor: u32,
    pub(crate) probes: &'p LevelProbes<'p>,
}

impl CutSearch<'_> {
    /// From `from` (the last level), the next level's prefix for error `e` and its finely
    /// measured error; `None` if there is none.
    pub(crate) fn next_level<'a>(
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

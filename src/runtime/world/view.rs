//! The levels of detail a world shows and the user's run-time choices over them: methods
//! installed per model, the method and policy shown on each side, impostors in or out.

use crate::bake::foliage::billboard::chain::ChainOptions;
use crate::scene::foliage::FoliagePolicy;
use crate::scene::{Instance, LodDraw, LodMethod, LodModel, LodPolicy, LodTracker};

/// What levels of detail are shown and how: the user's choices and the per-instance state.
pub struct LodView {
    pub policy: LodPolicy,
    pub method: LodMethod,
    /// Compare mode: the right half of the view shows this method, the left half `method`.
    pub compare: Option<LodMethod>,
    /// What trees become under a simplified method, and how their chains are cut (its style
    /// follows the policy). Change both through [`World::set_foliage`].
    pub(super) foliage: FoliagePolicy,
    pub(super) chain: ChainOptions,
    /// Which models are trees.
    pub(super) trees: Vec<bool>,
    pub(super) trackers: [LodTracker; 2],
    pub(super) draws: [Vec<LodDraw>; 2],
    /// Per model, per method slot: what selection needs, once the levels are on the GPU.
    pub(super) models: Vec<[Option<LodModel>; LodMethod::COUNT]>,
    /// Whether far characters show as their animated impostors (where they have one).
    pub(super) impostors: bool,
    /// Per model and method slot: its impostor's placement in that method's chain, where it
    /// has one on the GPU.
    pub(super) impostor_errors:
        Vec<[Option<crate::bake::impostor::placement::Placement>; LodMethod::COUNT]>,
    /// The tolerance `with_impostors` was worked out for (see [`Placement::epsilon_at`]).
    ///
    /// [`Placement::epsilon_at`]: crate::bake::impostor::placement::Placement::epsilon_at
    pub(super) impostors_at: f32,
    /// `models` with each character's impostor appended as its last level (see
    /// [`with_impostor`]), for the simplified methods.
    pub(super) with_impostors: Vec<[Option<LodModel>; LodMethod::COUNT]>,
}

impl LodView {
    /// The methods the sides show, left (or only) first.
    pub fn methods(&self) -> impl Iterator<Item = LodMethod> + use<> {
        std::iter::once(self.method).chain(self.compare)
    }

    /// Forgets every instance's level and transition: the next frame snaps.
    pub fn reset(&mut self) {
        for t in &mut self.trackers {
            t.reset();
        }
    }

    /// Are the levels of `method` uploaded for every model (trees kept full need none)?
    pub fn has(&self, method: LodMethod) -> bool {
        method == LodMethod::None
            || self
                .models
                .iter()
                .zip(&self.trees)
                .all(|(m, &tree)| m[method.index()].is_some() || self.stays_full(tree))
    }

    pub(super) fn stays_full(&self, tree: bool) -> bool {
        tree && self.foliage == FoliagePolicy::Full
    }

    /// What selection uses for model `m` under the method in `slot`: its levels by that
    /// method where they are there (and, for a tree, where the policy is not to keep it
    /// full), else its full detail alone.
    pub(super) fn model(&self, m: usize, slot: usize) -> Option<&LodModel> {
        if let Some(with) = self.impostor_model(m, slot) {
            return Some(with);
        }
        let slots = self.models.get(m)?;
        let full = self.trees.get(m).is_some_and(|&t| self.stays_full(t));
        let chosen = if full { None } else { slots[slot].as_ref() };
        chosen.or(slots[0].as_ref())
    }

    /// Model `m`'s levels under the method in `slot` with its impostor last, where it is
    /// shown.
    pub(super) fn impostor_model(&self, m: usize, slot: usize) -> Option<&LodModel> {
        if !self.impostors {
            return None;
        }
        self.with_impostors.get(m)?[slot].as_ref()
    }

    /// The level at which model `m` shows its impostor under the method in `slot`, if it
    /// does.
    pub fn impostor_level(&self, m: usize, slot: usize) -> Option<u8> {
        self.impostor_model(m, slot)
            .map(|l| (l.errors.len() - 1) as u8)
    }

    /// The error bound of every level model `m` shows under the method in `slot` (its
    /// impostor last where it shows one), finest first.
    pub fn errors(&self, m: usize, slot: usize) -> Option<&[f32]> {
        self.model(m, slot).map(|l| l.errors.as_slice())
    }

    /// Whether far characters show as their animated impostors.
    pub fn impostors_shown(&self) -> bool {
        self.impostors
    }

    /// Rebuilds [`LodView::with_impostors`] after levels or impostors came, or the tolerance
    /// changed.
    pub(super) fn refresh_impostors(&mut self) {
        self.impostors_at = self.policy.tolerance_px;
        self.with_impostors = self
            .models
            .iter()
            .zip(&self.impostor_errors)
            .map(|(slots, errors)| {
                let mut with: [Option<LodModel>; LodMethod::COUNT] = Default::default();
                for (slot, levels) in slots.iter().enumerate().skip(1) {
                    let e = errors[slot]
                        .as_ref()
                        .and_then(|p| p.epsilon_at(self.policy.tolerance_px));
                    if let (Some(levels), Some(e)) = (levels, e) {
                        with[slot] = Some(with_impostor(levels, e));
                    }
                }
                with
            })
            .collect();
    }

    pub fn foliage(&self) -> FoliagePolicy {
        self.foliage
    }

    /// The chain options trees are wanted in.
    pub fn chain(&self) -> ChainOptions {
        self.chain
    }

    /// What the instances drew on each side in the last frame.
    pub fn draws(&self, side: usize) -> &[LodDraw] {
        &self.draws[side]
    }
}

/// `levels` with an impostor of error bound `error` as the last level: it stands for every
/// level whose error is not below its own, so the errors keep rising.
pub fn with_impostor(levels: &LodModel, error: f32) -> LodModel {
    let mut errors: Vec<f32> = levels
        .errors
        .iter()
        .copied()
        .take_while(|&e| e < error)
        .collect();
    errors.push(error);
    LodModel {
        errors,
        ..levels.clone()
    }
}

/// Pushes what instance `inst` draws when its draw `d` may involve its impostor at level
/// `far` (`shown`: the instance as its impostor's character): the impostor at that level, a
/// dissolve between it and the mesh level on the other side of a transition, or `d` itself.
pub(super) fn impostor_draws(
    inst: &Instance,
    shown: &Instance,
    d: LodDraw,
    far: u8,
    instances: &mut Vec<Instance>,
    draws: &mut Vec<LodDraw>,
) {
    let (from, to, p) = match d {
        LodDraw::Level(k) if k >= far => {
            instances.push(*shown);
            draws.push(LodDraw::Level(far));
            return;
        }
        LodDraw::Alpha { from, to, p } | LodDraw::Dither { from, to, p } => (from, to, p),
        LodDraw::Morph { fine, coarse, t } => (fine, coarse, t),
        _ => (0, 0, 0.0),
    };
    if from < far && to < far {
        instances.push(*inst);
        draws.push(d);
        return;
    }
    for (level, incoming) in [(from, false), (to, true)] {
        instances.push(if level >= far { *shown } else { *inst });
        draws.push(LodDraw::Dissolve {
            level: level.min(far),
            p,
            incoming,
        });
    }
}

//! The forest patches a world has installed and their state frame to frame: which agents
//! each stands for, how far each has come in, and what they add to a side's draws (the world's
//! side of them is `patches`).

use crate::bake::foliage::billboard::chain::CloudKind;
use crate::bake::foliage::patch::ForestPatches;
use crate::scene::{Instance, LodDraw, LodPolicy, ScreenProjection, Transition};
use glam::Vec3;

/// A layout's patches on the GPU and the state of each.
pub(super) struct InstalledPatches {
    pub(super) patches: Vec<PatchState>,
    /// Per agent of the crowd: the patch that stands for it.
    pub(super) of_agent: Vec<Option<u32>>,
    /// What was baked: where they come in, and the figures measured.
    pub(super) baked: ForestPatches,
}

pub(super) struct PatchState {
    pub(super) character: usize,
    pub(super) instance: Instance,
    /// The card's view sphere in the world: what selection projects its error from.
    pub(super) centre: Vec3,
    pub(super) radius: f32,
    /// Its error bound (see [`ForestPatches::epsilon`]).
    pub(super) epsilon: f32,
    /// 0: its trees are drawn; 1: the patch; between, a cross-dissolve under way.
    pub(super) fade: f32,
}

impl InstalledPatches {
    /// Per agent, how far its patch has come in (0 where it has none).
    pub(super) fn fades(&self) -> Vec<f32> {
        self.of_agent
            .iter()
            .map(|p| p.map_or(0.0, |k| self.patches[k as usize].fade))
            .collect()
    }

    /// Appends the patches that are drawn to a side's instances and draws: whole, or the
    /// incoming half of a dissolve.
    pub(super) fn draws(&self, instances: &mut Vec<Instance>, draws: &mut Vec<LodDraw>) {
        for p in self.patches.iter().filter(|p| p.fade > 0.0) {
            instances.push(p.instance);
            draws.push(if p.fade >= 1.0 {
                LodDraw::Level(0)
            } else {
                LodDraw::Dissolve {
                    level: 0,
                    p: p.fade,
                    incoming: true,
                }
            });
        }
    }

    /// Moves every patch towards being drawn or not, `dt` seconds on: drawn where its error
    /// projects within the tolerance (a patch not drawn yet waits until it is within the
    /// hysteresis's share of it, as a coarser level does).
    pub(super) fn select(&mut self, policy: &LodPolicy, screen: &ScreenProjection, dt: f32) {
        for p in &mut self.patches {
            let error = screen.projected(p.epsilon, screen.sphere_distance(p.centre, p.radius));
            let limit = if p.fade > 0.0 {
                policy.tolerance_px
            } else {
                policy.tolerance_px * (1.0 - policy.hysteresis)
            };
            let target = if error <= limit { 1.0 } else { 0.0 };
            p.fade = if policy.transition == Transition::Pop || policy.duration <= 0.0 {
                target
            } else {
                let step = dt / policy.duration;
                if target > p.fade {
                    (p.fade + step).min(1.0)
                } else {
                    (p.fade - step).max(0.0)
                }
            };
        }
    }
}

/// Whether a chain level is an impostor (what a patch is composed from).
pub(super) fn is_impostor(kind: &Option<CloudKind>) -> bool {
    matches!(kind, Some(CloudKind::Impostor { .. }))
}

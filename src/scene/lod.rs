//! Level-of-detail selection and transitions at run time: plain CPU arithmetic, run once per frame
//! for every instance before anything is drawn.
//!
//! Selection (Merry et al. §6.4): an instance shows the coarsest level whose error bound,
//! projected to the screen at the distance of its bounding sphere, stays within a tolerance in
//! pixels: `err · H / (2 · tan(fov/2) · d)`. Hysteresis makes a coarser level wait until it is
//! within `tolerance · (1 − h)`, so an instance standing at a threshold does not flicker between
//! two levels; a finer level is always taken as soon as the current one exceeds the tolerance.
//!
//! Transitions (Houle & Poulin §3, §5):
//! - `pop` changes level at once;
//! - `alpha` draws both levels and fades the incoming one in (their Figure 1);
//! - `morph` draws the finer level with every vertex moving towards its geomorph target,
//!   `t` = 0 being the finer level and `t` = 1 the coarser one.
//!
//! Alpha and morph are driven either by time (a transition runs for a duration once the choice
//! changes; a change back half-way reverses it) or by distance, in *morph zones* (Houle & Poulin
//! §5.3): level k+1 is blended in over a band of distances starting where it becomes good enough,
//! so `t` is a continuous function of distance and nothing changes at a threshold. The band sits
//! on the far side of the threshold, so what is drawn never exceeds the tolerance.

use super::crowd::Instance;
use crate::bake::character::simplify::Method;
use glam::Vec3;

/// Levels a histogram keeps apart; coarser ones are counted in the last bin.
pub const MAX_LEVELS: usize = 12;

/// Which levels of detail to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LodMethod {
    /// Full detail always.
    None,
    /// Levels from one of the simplification methods.
    Simplified(Method),
}

impl LodMethod {
    pub const ALL: [LodMethod; 5] = [
        LodMethod::None,
        LodMethod::Simplified(Method::RestPose),
        LodMethod::Simplified(Method::AnimationSpace),
        LodMethod::Simplified(Method::InfluenceSimplification),
        LodMethod::Simplified(Method::Meshopt),
    ];
    /// How many there are: the length of per-method tables.
    pub const COUNT: usize = Self::ALL.len();

    pub fn name(self) -> &'static str {
        match self {
            LodMethod::None => "none",
            LodMethod::Simplified(m) => m.name(),
        }
    }

    /// The finest simplified method: AS with influence simplification.
    pub const AS_IS: LodMethod = LodMethod::Simplified(Method::InfluenceSimplification);

    /// Position in [`LodMethod::ALL`]: a slot index for per-method tables.
    pub fn index(self) -> usize {
        Self::ALL.iter().position(|&m| m == self).unwrap_or(0)
    }
}

crate::choice! {
    /// How an instance goes from one level to another.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    pub enum Transition {
        Pop => "pop",
        /// Houle & Poulin's alpha blend (§3): one level opaque, the other blended over it.
        Alpha => "alpha",
        Morph => "morph",
        /// A screen-door cross-fade (as Bevy's dithered level changes): both levels opaque, each on
        /// its own share of the pixels. Each level is drawn once, so it costs less than the alpha
        /// blend where triangles are the limit; it looks grainy where the blend is smooth.
        Dither => "dither",
    }
}

crate::choice!(LodMethod);
crate::named_serde!(LodMethod, "a method");
crate::named_serde!(Transition, "a transition");
crate::named_serde!(Drive, "a transition drive");

crate::choice! {
    /// What drives an alpha, morph or dither transition.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    pub enum Drive {
        /// Runs for [`LodPolicy::duration`] seconds once the level changes.
        Time => "time",
        /// A function of distance over a band beyond each threshold (morph zones).
        Zone => "zone",
    }
}

/// The user's choices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodPolicy {
    /// Largest projected error allowed, pixels.
    pub tolerance_px: f32,
    /// Fraction `h` of the tolerance a coarser level must undercut before it is taken.
    pub hysteresis: f32,
    pub transition: Transition,
    pub drive: Drive,
    /// Seconds a time-driven transition takes.
    pub duration: f32,
    /// Width of a morph zone as a fraction of its threshold distance.
    pub zone_width: f32,
    /// Every instance shows this level (or its model's coarsest, if it has fewer), whatever its
    /// projected error: for looking at one level close up. A change of it still runs the
    /// transition.
    pub force_level: Option<u8>,
}

impl LodPolicy {
    /// The defaults, written once: the command line's (`cli::scene_args`) come from here.
    pub const DEFAULT: LodPolicy = LodPolicy {
        tolerance_px: 1.5,
        hysteresis: 0.2,
        transition: Transition::Morph,
        drive: Drive::Time,
        duration: 0.5,
        zone_width: 0.25,
        force_level: None,
    };
}

impl Default for LodPolicy {
    fn default() -> Self {
        LodPolicy::DEFAULT
    }
}

/// What selection needs to know about one model's levels.
#[derive(Clone, Debug, PartialEq)]
pub struct LodModel {
    /// Error bound of every level in scene units, finest (0) first, never decreasing.
    pub errors: Vec<f32>,
    /// Bounding sphere over the animation, model space.
    pub center: Vec3,
    pub radius: f32,
}

/// How scene-unit errors become pixels for one camera and viewport.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenProjection {
    pub eye: Vec3,
    /// `H / (2 · tan(fov/2))`: pixels covered by one scene unit at unit distance.
    pub pixels_per_unit: f32,
    /// Distances are clamped to at least this (the near plane).
    pub near: f32,
}

impl ScreenProjection {
    pub fn new(eye: Vec3, fov_y: f32, height_px: f32, near: f32) -> Self {
        ScreenProjection {
            eye,
            pixels_per_unit: height_px / (2.0 * (fov_y * 0.5).tan()),
            near: near.max(1e-4),
        }
    }

    /// Distance from the eye to the nearest point of a bounding sphere.
    pub fn sphere_distance(&self, center: Vec3, radius: f32) -> f32 {
        (center.distance(self.eye) - radius).max(self.near)
    }

    /// An error of `error` scene units seen `distance` away, in pixels.
    pub fn projected(&self, error: f32, distance: f32) -> f32 {
        error * self.pixels_per_unit / distance.max(self.near)
    }

    /// The distance beyond which `error` projects within `tolerance_px`.
    pub fn threshold(&self, error: f32, tolerance_px: f32) -> f32 {
        error * self.pixels_per_unit / tolerance_px.max(1e-6)
    }
}

/// The coarsest level whose error is within `limit` (level 0 if none is).
pub fn coarsest_within(errors: &[f32], limit: f32) -> usize {
    errors
        .partition_point(|&e| e <= limit)
        .saturating_sub(1)
        .min(errors.len().saturating_sub(1))
}

/// What to draw for one instance this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LodDraw {
    Level(u8),
    /// The finer level geomorphed towards the coarser: `t` = 0 is `fine`, 1 is `coarse`.
    Morph {
        fine: u8,
        coarse: u8,
        t: f32,
    },
    /// Both levels drawn, `to` fading in over `from` as `p` goes from 0 to 1.
    Alpha {
        from: u8,
        to: u8,
        p: f32,
    },
    /// Both levels drawn opaque on complementary pixels, `to` on the pixels whose fixed
    /// threshold lies below `p` (a dithered cross-fade, [`Transition::Dither`]).
    Dither {
        from: u8,
        to: u8,
        p: f32,
    },
    /// One half of a screen-door cross-dissolve between two models drawn as separate
    /// instances (a tree's billboard-cloud levels, which share no vertices to morph and whose
    /// overlapping leaves cannot be blended without sorting): every pixel shows either the
    /// outgoing model or the incoming one, the incoming one where a fixed per-pixel threshold
    /// lies below `p`. Drawn opaque; `level` is the level it stands for.
    Dissolve {
        level: u8,
        p: f32,
        incoming: bool,
    },
}

impl LodDraw {
    pub fn in_transition(&self) -> bool {
        !matches!(self, LodDraw::Level(_))
    }

    /// The level the instance mostly shows: for a histogram.
    pub fn nearest_level(&self) -> u8 {
        match *self {
            LodDraw::Level(k) => k,
            LodDraw::Morph { fine, coarse, t } => {
                if t < 0.5 {
                    fine
                } else {
                    coarse
                }
            }
            LodDraw::Alpha { from, to, p } | LodDraw::Dither { from, to, p } => {
                if p < 0.5 {
                    from
                } else {
                    to
                }
            }
            LodDraw::Dissolve { level, .. } => level,
        }
    }

    /// The transition parameter (0 when not in transition).
    pub fn t(&self) -> f32 {
        match *self {
            LodDraw::Level(_) => 0.0,
            LodDraw::Morph { t, .. } => t,
            LodDraw::Alpha { p, .. } | LodDraw::Dither { p, .. } | LodDraw::Dissolve { p, .. } => p,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Active {
    from: u8,
    to: u8,
    /// Progress, 0 to 1.
    p: f32,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct AgentLod {
    level: u8,
    active: Option<Active>,
    /// False until the first update: the first choice is taken without a transition.
    seen: bool,
}

/// Per-instance level and transition state, kept from frame to frame.
#[derive(Clone, Debug, Default)]
pub struct LodTracker {
    agents: Vec<AgentLod>,
}

impl LodTracker {
    /// Forget every state: the next update snaps each instance to its level (after the method,
    /// the crowd or the camera jumped).
    pub fn reset(&mut self) {
        self.agents.clear();
    }

    /// Chooses what every instance draws this frame, `dt` seconds after the last. `out[i]` is
    /// for `instances[i]`; the tracker keys its state by position, so the crowd must keep its
    /// order from frame to frame (it does: agents are laid out once).
    pub fn update(
        &mut self,
        policy: &LodPolicy,
        models: &[LodModel],
        instances: &[Instance],
        screen: &ScreenProjection,
        dt: f32,
        out: &mut Vec<LodDraw>,
    ) {
        self.update_with(policy, |m| models.get(m), instances, screen, dt, out);
    }

    /// [`LodTracker::update`] with the models looked up by `model_of(model index)`.
    pub fn update_with<'m>(
        &mut self,
        policy: &LodPolicy,
        model_of: impl Fn(usize) -> Option<&'m LodModel>,
        instances: &[Instance],
        screen: &ScreenProjection,
        dt: f32,
        out: &mut Vec<LodDraw>,
    ) {
        if self.agents.len() != instances.len() {
            self.agents.clear();
            self.agents.resize(instances.len(), AgentLod::default());
        }
        out.clear();
        let tol = policy.tolerance_px.max(1e-3);
        let h = policy.hysteresis.clamp(0.0, 0.9);
        for (inst, agent) in instances.iter().zip(&mut self.agents) {
            let Some(model) = model_of(inst.model).filter(|m| m.errors.len() > 1) else {
                *agent = AgentLod::default();
                out.push(LodDraw::Level(0));
                continue;
            };
            let last = (model.errors.len() - 1).min(u8::MAX as usize) as u8;
            let t = &inst.transform;
            let scale = t
                .matrix3
                .x_axis
                .length()
                .max(t.matrix3.y_axis.length())
                .max(t.matrix3.z_axis.length());
            let centre = t.transform_point3(model.center + inst.travel);
            let d = screen.sphere_distance(centre, model.radius * scale);
            // An error of e scene units is within `px` pixels here when e · scale ≤ limit(px).
            let limit = |px: f32| px * d / (screen.pixels_per_unit * scale.max(1e-6));
            let forced = policy.force_level.map(|f| f.min(last));
            let within = forced.unwrap_or_else(|| coarsest_within(&model.errors, limit(tol)) as u8);
            let draw = if forced.is_none()
                && policy.transition != Transition::Pop
                && policy.drive == Drive::Zone
            {
                *agent = AgentLod {
                    level: within,
                    active: None,
                    seen: true,
                };
                zone_draw(policy, model, screen, scale, d, within)
            } else {
                agent.level = agent.level.min(last);
                let current = agent.active.map_or(agent.level, |a| a.to).min(last);
                let desired = if forced.is_some() || within < current {
                    within
                } else {
                    (coarsest_within(&model.errors, limit(tol * (1.0 - h))) as u8).max(current)
                };
                if !agent.seen || policy.transition == Transition::Pop || policy.duration <= 0.0 {
                    *agent = AgentLod {
                        level: desired,
                        active: None,
                        seen: true,
                    };
                } else {
                    step_transition(agent, desired, dt / policy.duration, last);
                }
                match agent.active {
                    None => LodDraw::Level(agent.level),
                    Some(a) => transition_draw(policy.transition, a),
                }
            };
            out.push(draw);
        }
    }
}

/// Advances a time-driven transition by `dp` and starts, reverses or ends it as `desired` asks.
fn step_transition(agent: &mut AgentLod, desired: u8, dp: f32, last: u8) {
    if let Some(a) = &mut agent.active {
        a.from = a.from.min(last);
        a.to = a.to.min(last);
        if desired == a.from && desired != a.to {
            // Changed its mind half-way: run back from where it is.
            *a = Active {
                from: a.to,
                to: a.from,
                p: 1.0 - a.p,
            };
        }
        a.p += dp;
        if a.p >= 1.0 || a.from == a.to {
            agent.level = a.to;
            agent.active = None;
        }
    }
    if agent.active.is_none() && desired != agent.level {
        // A new transition shows exactly the old level on its first frame.
        agent.active = Some(Active {
            from: agent.level,
            to: desired,
            p: 0.0,
        });
    }
}

fn transition_draw(kind: Transition, a: Active) -> LodDraw {
    let p = a.p.clamp(0.0, 1.0);
    match kind {
        Transition::Alpha => LodDraw::Alpha {
            from: a.from,
            to: a.to,
            p,
        },
        Transition::Dither => LodDraw::Dither {
            from: a.from,
            to: a.to,
            p,
        },
        _ => {
            let (fine, coarse) = (a.from.min(a.to), a.from.max(a.to));
            let t = if a.to > a.from { p } else { 1.0 - p };
            LodDraw::Morph { fine, coarse, t }
        }
    }
}

/// Morph zones (Houle & Poulin §5.3): level `level` has just become good enough at its threshold
/// distance `D`; over `[D, D · (1 + w)]` (cut short at the next threshold) the instance goes
/// from `level − 1` to `level` as a function of distance alone.
fn zone_draw(
    policy: &LodPolicy,
    model: &LodModel,
    screen: &ScreenProjection,
    scale: f32,
    d: f32,
    level: u8,
) -> LodDraw {
    if level == 0 {
        return LodDraw::Level(0);
    }
    let k = level as usize;
    let tol = policy.tolerance_px.max(1e-3);
    let start = screen.threshold(model.errors[k] * scale, tol);
    let mut end = start * (1.0 + policy.zone_width.max(0.0));
    if let Some(&next) = model.errors.get(k + 1) {
        end = end.min(screen.threshold(next * scale, tol));
    }
    if d >= end || end <= start {
        return LodDraw::Level(level);
    }
    let t = ((d - start) / (end - start)).clamp(0.0, 1.0);
    transition_draw(
        policy.transition,
        Active {
            from: level - 1,
            to: level,
            p: t,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Affine3A, Vec4};

    fn model() -> LodModel {
        LodModel {
            errors: vec![0.0, 0.001, 0.002, 0.004, 0.008],
            center: Vec3::ZERO,
            radius: 0.0,
        }
    }

    fn at(z: f32) -> Instance {
        Instance {
            model: 0,
            transform: Affine3A::from_translation(Vec3::new(0.0, 0.0, -z)),
            clip: 0,
            time_offset: 0.0,
            speed: 1.0,
            wind: 1.0,
            tint: Vec4::ONE,
            fade: None,
            travel: Vec3::ZERO,
        }
    }

    fn screen() -> ScreenProjection {
        ScreenProjection::new(Vec3::ZERO, 60f32.to_radians(), 1000.0, 0.01)
    }

    #[test]
    fn a_forced_level_holds_at_every_distance_and_still_transitions() {
        let s = screen();
        let m = model();
        let mut tracker = LodTracker::default();
        let mut out = Vec::new();
        let mut run = |policy: &LodPolicy, z: f32, dt: f32, out: &mut Vec<LodDraw>| {
            tracker.update(policy, std::slice::from_ref(&m), &[at(z)], &s, dt, out);
            out[0]
        };
        let forced = |k, transition| LodPolicy {
            force_level: Some(k),
            transition,
            ..Default::default()
        };
        // Near and far alike; a level past the coarsest is the coarsest.
        for z in [0.1f32, 5.0, 500.0] {
            let draw = run(&forced(2, Transition::Pop), z, 0.0, &mut out);
            assert_eq!(draw, LodDraw::Level(2));
        }
        let draw = run(&forced(9, Transition::Pop), 0.1, 0.0, &mut out);
        assert_eq!(draw, LodDraw::Level(4));
        // Going from the coarsest back to level 1 morphs over the duration.
        let draw = run(&forced(1, Transition::Morph), 0.1, 0.1, &mut out);
        assert!(draw.in_transition(), "{draw:?}");
        let draw = run(&forced(1, Transition::Morph), 0.1, 1.0, &mut out);
        assert_eq!(draw, LodDraw::Level(1));
    }

    #[test]
    fn selection_follows_the_projected_error_formula() {
        let s = screen();
        let m = model();
        let policy = LodPolicy {
            transition: Transition::Pop,
            hysteresis: 0.0,
            ..Default::default()
        };
        for z in [0.5f32, 1.0, 2.0, 3.3, 5.0, 9.0, 20.0, 100.0] {
            let mut tracker = LodTracker::default();
            let mut out = Vec::new();
            tracker.update(
                &policy,
                std::slice::from_ref(&m),
                &[at(z)],
                &s,
                0.0,
                &mut out,
            );
            let LodDraw::Level(k) = out[0] else {
                panic!("pop never transitions")
            };
            // Reference: err · H / (2 tan(fov/2) d) ≤ tolerance, coarsest such level.
            let proj = |e: f32| e * 1000.0 / (2.0 * 30f32.to_radians().tan() * z);
            let expected = (0..m.errors.len())
                .rev()
                .find(|&k| proj(m.errors[k]) <= 1.5)
                .unwrap();
            assert_eq!(k as usize, expected, "at {z} m");
        }
    }

    #[test]
    fn hysteresis_stops_flicker_at_a_threshold() {
        let s = screen();
        let m = model();
        // The distance where level 2 becomes good enough.
        let d = s.threshold(m.errors[2], 1.5);
        let policy = LodPolicy {
            transition: Transition::Pop,
            ..Default::default()
        };
        let mut tracker = LodTracker::default();
        let mut out = Vec::new();
        let mut levels = Vec::new();
        // Wobbling by ±2% around the threshold, having come from nearer.
        tracker.update(
            &policy,
            std::slice::from_ref(&m),
            &[at(d * 0.9)],
            &s,
            0.0,
            &mut out,
        );
        for k in 0..100 {
            let z = d * (1.0 + 0.02 * (k as f32 * 0.7).sin());
            tracker.update(
                &policy,
                std::slice::from_ref(&m),
                &[at(z)],
                &s,
                1.0 / 60.0,
                &mut out,
            );
            levels.push(out[0]);
        }
        assert!(levels.iter().all(|l| *l == LodDraw::Level(1)), "{levels:?}");
        // Without hysteresis it flickers.
        let bare = LodPolicy {
            hysteresis: 0.0,
            ..policy
        };
        let mut tracker = LodTracker::default();
        let mut changes = 0;
        let mut prev = None;
        for k in 0..100 {
            let z = d * (1.0 + 0.02 * (k as f32 * 0.7).sin());
            tracker.update(
                &bare,
                std::slice::from_ref(&m),
                &[at(z)],
                &s,
                1.0 / 60.0,
                &mut out,
            );
            changes += (prev.is_some_and(|p| p != out[0])) as u32;
            prev = Some(out[0]);
        }
        assert!(changes > 10);
        // Far enough beyond the threshold, the coarser level is taken.
        tracker = LodTracker::default();
        tracker.update(
            &policy,
            std::slice::from_ref(&m),
            &[at(d * 0.9)],
            &s,
            0.0,
            &mut out,
        );
        tracker.update(
            &policy,
            std::slice::from_ref(&m),
            &[at(d * 1.3)],
            &s,
            0.0,
            &mut out,
        );
        assert_eq!(out[0], LodDraw::Level(2));
        // And it refines as soon as the tolerance is exceeded.
        tracker.update(
            &policy,
            std::slice::from_ref(&m),
            &[at(d * 0.99)],
            &s,
            0.0,
            &mut out,
        );
        assert_eq!(out[0], LodDraw::Level(1));
    }

    #[test]
    fn time_driven_morph_runs_reverses_and_ends() {
        let s = screen();
        let m = model();
        let d = s.threshold(m.errors[2], 1.5);
        let policy = LodPolicy::default();
        let dt = 1.0 / 60.0;
        let mut tracker = LodTracker::default();
        let mut out = Vec::new();
        let models = std::slice::from_ref(&m);
        tracker.update(&policy, models, &[at(d * 0.9)], &s, dt, &mut out);
        assert_eq!(out[0], LodDraw::Level(1));
        // Moving away: the morph to level 2 starts at t = 0 and rises by dt / duration.
        tracker.update(&policy, models, &[at(d * 1.3)], &s, dt, &mut out);
        assert_eq!(
            out[0],
            LodDraw::Morph {
                fine: 1,
                coarse: 2,
                t: 0.0
            }
        );
        for _ in 0..10 {
            tracker.update(&policy, models, &[at(d * 1.3)], &s, dt, &mut out);
        }
        let LodDraw::Morph { t, .. } = out[0] else {
            panic!("{:?}", out[0])
        };
        assert!((t - 10.0 * dt / 0.5).abs() < 1e-4);
        // Coming back: it reverses from where it is, with no jump.
        tracker.update(&policy, models, &[at(d * 0.9)], &s, dt, &mut out);
        let LodDraw::Morph { t: t2, .. } = out[0] else {
            panic!("{:?}", out[0])
        };
        assert!((t2 - (t - dt / 0.5)).abs() < 1e-4, "{t} then {t2}");
        for _ in 0..40 {
            tracker.update(&policy, models, &[at(d * 0.9)], &s, dt, &mut out);
        }
        assert_eq!(out[0], LodDraw::Level(1));
        // Alpha runs the same clock.
        let alpha = LodPolicy {
            transition: Transition::Alpha,
            ..policy
        };
        tracker.update(&alpha, models, &[at(d * 1.3)], &s, dt, &mut out);
        tracker.update(&alpha, models, &[at(d * 1.3)], &s, dt, &mut out);
        assert_eq!(
            out[0],
            LodDraw::Alpha {
                from: 1,
                to: 2,
                p: dt / 0.5
            }
        );
    }

    #[test]
    fn morph_zones_are_continuous_in_distance_and_within_tolerance() {
        let s = screen();
        let m = model();
        let policy = LodPolicy {
            drive: Drive::Zone,
            ..Default::default()
        };
        let mut tracker = LodTracker::default();
        let mut out = Vec::new();
        // The shown shape, as a continuous "level coordinate": fine + t · (coarse − fine).
        let coord = |d: &LodDraw| match *d {
            LodDraw::Level(k) => k as f32,
            LodDraw::Morph { fine, coarse, t } => fine as f32 + t * (coarse - fine) as f32,
            LodDraw::Alpha { .. } | LodDraw::Dither { .. } | LodDraw::Dissolve { .. } => {
                unreachable!()
            }
        };
        let mut prev: Option<f32> = None;
        let mut z = 0.3f32;
        let mut morphing = 0;
        while z < 200.0 {
            tracker.update(
                &policy,
                std::slice::from_ref(&m),
                &[at(z)],
                &s,
                0.0,
                &mut out,
            );
            let c = coord(&out[0]);
            morphing += out[0].in_transition() as u32;
            if let Some(p) = prev {
                assert!(c >= p - 1e-5, "level coordinate fell at {z}");
                assert!(c - p < 0.05, "jump from {p} to {c} at {z}");
            }
            // Never coarser than the tolerance allows: the upper level is within it.
            let upper = c.ceil() as usize;
            assert!(s.projected(m.errors[upper], z) <= 1.5 * 1.0001);
            prev = Some(c);
            z *= 1.002;
        }
        assert!(morphing > 100);
    }
}

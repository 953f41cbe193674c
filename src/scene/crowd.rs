//! The crowd: characters walking circular lanes round a central plaza, each with its own clip and
//! phase. Deterministic for a seed, so `lodlab shot` renders the same picture every time.
//!
//! Travelling characters share a lane only with characters of the same model and clip, so that
//! everyone on a lane moves at the same speed and nobody walks through anybody. Characters whose
//! clip stays on the spot (a wave, an idle) stand in the plaza.
//!
//! With a cross-fade time set ([`CrowdConfig::cross_fade`]), the walkers of a lane whose model
//! also has a clip played on the spot stop now and then to play it (a walker stops and waves):
//! their clip cross-fades into it, is held for one loop of it, and cross-fades back, and they
//! slow down and speed up with the walk's weight. A whole lane pauses together, so its spacing
//! holds.

use crate::model::Bounds;
use glam::{Affine3A, Vec2, Vec3, Vec3A, Vec4};

/// What the layout needs to know about a model.
#[derive(Clone, Debug, PartialEq)]
pub struct CrowdModel {
    /// Ground speed of every clip in metres per second (0: played on the spot).
    pub clip_speeds: Vec<f32>,
    /// Every clip's length in seconds.
    pub clip_durations: Vec<f32>,
    /// Animated bounds, model space.
    pub bounds: Bounds,
}

#[derive(Clone, Debug, PartialEq)]
pub struct CrowdConfig {
    pub count: usize,
    pub seed: u64,
    /// Per model, the clip every character of it plays; `None` (or a missing entry): a mix.
    pub clips: Vec<Option<usize>>,
    /// Seconds a clip cross-fade takes when walkers stop to play a clip on the spot; 0: they
    /// never stop.
    pub cross_fade: f32,
}

impl Default for CrowdConfig {
    fn default() -> Self {
        CrowdConfig {
            count: super::kind::DEFAULT_CHARACTERS,
            seed: 1,
            clips: Vec::new(),
            cross_fade: 0.0,
        }
    }
}

impl CrowdConfig {
    fn forced_clip(&self, model: usize, clip_count: usize) -> Option<usize> {
        self.clips
            .get(model)
            .copied()
            .flatten()
            .filter(|&c| c < clip_count)
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Path {
    /// Along a circle round the origin, counter-clockwise seen from above if `direction` is 1.
    Circle {
        radius: f32,
        angle: f32,
        direction: f32,
    },
    /// Standing at a point, facing `heading` (radians about +y, 0 facing +z).
    Still { position: Vec2, heading: f32 },
}

/// One member of the crowd.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agent {
    pub model: usize,
    pub clip: usize,
    /// Added to the animation time, seconds.
    pub phase: f32,
    /// Playback speed.
    pub speed: f32,
    /// Ground speed in metres per second at playback speed 1.
    pub ground_speed: f32,
    /// Wind strength: how far its animation moves it from rest (1: the clip as it is; trees
    /// get their own, so a forest does not sway in step).
    pub wind: f32,
    /// Uniform scale of the model (1 for characters; trees vary).
    pub scale: f32,
    pub tint: Vec4,
    pub path: Path,
    /// Stops now and then to play a clip on the spot (lane walkers; see [`Pause`]).
    pub pause: Option<Pause>,
}

/// A lane's walkers stopping to play a clip on the spot, over and over: each cycle walks for
/// `walk` seconds, cross-fades into the clip over `fade`, holds it for `hold`, and cross-fades
/// back over `fade`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pause {
    /// The clip played while stopped.
    pub clip: usize,
    /// Scene time at which a cycle begins.
    pub start: f32,
    pub walk: f32,
    pub fade: f32,
    pub hold: f32,
}

impl Pause {
    pub fn period(&self) -> f32 {
        self.walk + 2.0 * self.fade + self.hold
    }

    /// The cycle scene time `t` falls in (counted from `start`), and how far into it `t` is.
    fn cycle(&self, t: f32) -> (f32, f32) {
        let p = self.period().max(1e-3);
        let n = ((t - self.start) / p).floor();
        (n, t - self.start - n * p)
    }

    /// The stopped clip's weight at scene time `t`: 0 walking, rising linearly over the first
    /// fade, 1 while held, falling back over the second.
    pub fn weight(&self, t: f32) -> f32 {
        let (_, u) = self.cycle(t);
        let fade = self.fade.max(1e-6);
        let held = self.walk + self.fade;
        if u <= self.walk {
            0.0
        } else if u <= held {
            (u - self.walk) / fade
        } else if u <= held + self.hold {
            1.0
        } else {
            (1.0 - (u - held - self.hold) / fade).max(0.0)
        }
    }

    /// Seconds of walking up to scene time `t`, each weighted by the walk's weight 1 − w: how
    /// far a walker has got, in seconds at full speed (counted from `start`).
    pub fn walked(&self, t: f32) -> f32 {
        let (n, u) = self.cycle(t);
        let fade = self.fade.max(1e-6);
        let held = self.walk + self.fade;
        let within = if u <= self.walk {
            u
        } else if u <= held {
            let x = u - self.walk;
            self.walk + x - x * x / (2.0 * fade)
        } else if u <= held + self.hold {
            self.walk + 0.5 * fade
        } else {
            let x = u - held - self.hold;
            self.walk + 0.5 * fade + x * x / (2.0 * fade)
        };
        n * (self.walk + self.fade) + within
    }

    /// When the stopped clip began its current play (the start of the cycle's first fade).
    fn clip_start(&self, t: f32) -> f32 {
        let (n, _) = self.cycle(t);
        self.start + n * self.period() + self.walk
    }
}

/// A cross-fade from an instance's own clip to a second one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipFade {
    pub clip: u32,
    /// The second clip's animation time is `scene time · speed + time_offset`.
    pub time_offset: f32,
    pub speed: f32,
    /// 0: the instance's own clip alone; 1: the second alone.
    pub weight: f32,
}

/// One character on screen: what the renderer draws.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    pub model: usize,
    pub transform: Affine3A,
    pub clip: u32,
    /// Animation time is `scene time · speed + time_offset`.
    pub time_offset: f32,
    pub speed: f32,
    /// Wind strength (see [`Agent::wind`]).
    pub wind: f32,
    pub tint: Vec4,
    /// A cross-fade to a second clip under way, if any.
    pub fade: Option<ClipFade>,
    /// Where its clip has carried its body, model-local, against where the model stands at
    /// rest (root motion: see `bake::gpu_data::root_motion`; the world sets it each frame, zero
    /// for a character whose clips keep it in place). Its sphere, blob shadow and size on
    /// screen move with it.
    pub travel: Vec3,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Crowd {
    pub agents: Vec<Agent>,
    /// Radius of the outermost lane (or of the plaza if nobody travels), metres.
    pub radius: f32,
}

impl Agent {
    pub fn transform_at(&self, time: f32) -> Affine3A {
        // The heading as its sine and cosine: a lane's walkers face along the circle's
        // tangent, which gives them without an arc tangent (10,000 of these a frame).
        let (pos, (sin, cos)) = match self.path {
            Path::Still { position, heading } => (position, heading.sin_cos()),
            Path::Circle {
                radius,
                angle,
                direction,
            } => {
                let walked = self.pause.map_or(time, |p| p.walked(time));
                let travelled = self.ground_speed * self.speed * walked;
                let a = angle + direction * travelled / radius.max(1e-3);
                let (s, c) = a.sin_cos();
                let pos = Vec2::new(c, s) * radius;
                let tangent = Vec2::new(-s, c) * direction;
                (pos, (tangent.x, tangent.y))
            }
        };
        // A turn by the heading about +y (0 facing +z), scaled.
        let k = self.scale;
        Affine3A::from_cols(
            Vec3A::new(cos, 0.0, -sin) * k,
            Vec3A::new(0.0, k, 0.0),
            Vec3A::new(sin, 0.0, cos) * k,
            Vec3A::new(pos.x, 0.0, pos.y),
        )
    }

    pub fn instance_at(&self, time: f32) -> Instance {
        Instance {
            model: self.model,
            transform: self.transform_at(time),
            clip: self.clip as u32,
            time_offset: self.phase,
            speed: self.speed,
            wind: self.wind,
            tint: self.tint,
            fade: self.pause.and_then(|p| {
                let weight = p.weight(time);
                (weight > 0.0).then(|| ClipFade {
                    clip: p.clip as u32,
                    time_offset: -p.clip_start(time),
                    speed: 1.0,
                    weight,
                })
            }),
            travel: Vec3::ZERO,
        }
    }
}

impl Crowd {
    /// The crowd of `config.count` characters of `models`: who plays what, the standing
    /// ones on a plaza in the middle, the travelling ones on circular lanes round it, one
    /// (model, clip) group after another, slowest innermost. Deterministic in `config.seed`.
    pub fn layout(models: &[CrowdModel], config: &CrowdConfig) -> Crowd {
        if models.is_empty() || config.count == 0 {
            return Crowd::default();
        }
        if config.count == 1 {
            return Self::inspected(models, config);
        }
        let mut rng = fastrand::Rng::with_seed(config.seed);
        let cast = cast(models, config, &mut rng);
        let standing: Vec<usize> = (0..cast.len())
            .filter(|&i| models[cast[i].0].clip_speeds[cast[i].1] <= 0.0)
            .collect();
        let cell = plaza_cell(models);
        let plaza_radius = if standing.is_empty() {
            EMPTY_PLAZA_RADIUS
        } else {
            (standing.len() as f32 / std::f32::consts::PI).sqrt() * cell + cell
        };
        let mut agents = Vec::with_capacity(cast.len());
        plaza(&cast, &standing, cell, &mut rng, &mut agents);
        let outermost = lanes(models, config, &cast, plaza_radius, &mut rng, &mut agents);
        Crowd {
            agents,
            radius: outermost + 1.0,
        }
    }

    /// A single character, being inspected: it plays on the spot at the origin.
    fn inspected(models: &[CrowdModel], config: &CrowdConfig) -> Crowd {
        let clip = config
            .forced_clip(0, models[0].clip_speeds.len())
            .unwrap_or(0);
        Crowd {
            agents: vec![Agent {
                wind: 1.0,
                scale: 1.0,
                model: 0,
                clip,
                phase: 0.0,
                speed: 1.0,
                ground_speed: 0.0,
                tint: Vec4::ONE,
                path: Path::Still {
                    position: Vec2::ZERO,
                    heading: 0.0,
                },
                pause: None,
            }],
            radius: 1.0,
        }
    }

    /// The instances at scene time `time`, written into `out` (cleared first).
    pub fn instances_at(&self, time: f32, out: &mut Vec<Instance>) {
        out.clear();
        out.extend(self.agents.iter().map(|a| a.instance_at(time)));
    }
}

/// A standing character's cell on the plaza, in multiples of the largest model's footprint.
const PLAZA_SPACING: f32 = 1.8;
/// The plaza's radius, metres, where nobody stands on it.
const EMPTY_PLAZA_RADIUS: f32 = 6.0;
/// The golden angle, radians: consecutive characters of the plaza's spiral turn by it, so that
/// none lines up with another.
const GOLDEN_ANGLE: f32 = 2.399_963;
/// How tightly the spiral packs the plaza's cells.
const SPIRAL_PACKING: f32 = 0.56;
/// A plaza character's random offset from its place on the spiral, in cells.
const PLAZA_JITTER: f32 = 0.2;
/// The gap between the plaza and the first lane, metres.
const FIRST_LANE_GAP: f32 = 2.0;
/// A lane's width: its model's width (at least [`MIN_WIDTH`]) times this, plus [`LANE_MARGIN`].
const LANE_WIDTH: f32 = 2.5;
const MIN_WIDTH: f32 = 0.6;
const LANE_MARGIN: f32 = 0.6;
/// The shortest gap between two characters of a lane: their model's length times this, plus
/// [`SPACING_MARGIN`].
const SPACING: f32 = 1.6;
const SPACING_MARGIN: f32 = 0.4;
/// A lane holds one character per this many shortest gaps (it is filled to about a third).
const LANE_FILL: f32 = 3.0;
/// A lane's characters walk between 6 and 12 seconds before they stop together.
const PAUSE_WALK: f32 = 6.0;

/// Who plays what: models in turn, clips weighted towards travelling ones (or the clip the
/// configuration forces).
fn cast(
    models: &[CrowdModel],
    config: &CrowdConfig,
    rng: &mut fastrand::Rng,
) -> Vec<(usize, usize)> {
    let mut cast = Vec::with_capacity(config.count);
    for i in 0..config.count {
        let m = i % models.len();
        let speeds = &models[m].clip_speeds;
        let clip = match config.forced_clip(m, speeds.len()) {
            Some(c) => c,
            None => pick_clip(speeds, rng),
        };
        cast.push((m, clip));
    }
    cast
}

/// A model's footprint on the ground, width and length, metres (at least 0.3 each).
fn footprint(model: &CrowdModel) -> (f32, f32) {
    let s = model.bounds.size();
    (s.x.max(0.3), s.z.max(0.3))
}

/// A standing character's cell on the plaza, metres.
fn plaza_cell(models: &[CrowdModel]) -> f32 {
    models
        .iter()
        .map(|m| footprint(m).0.max(footprint(m).1))
        .fold(0.5f32, f32::max)
        * PLAZA_SPACING
}

/// A character's colour, a little lighter or darker and warmer or cooler than its model's.
fn tint(rng: &mut fastrand::Rng) -> Vec4 {
    let b = 0.85 + 0.25 * rng.f32();
    Vec4::new(
        b * (0.95 + 0.1 * rng.f32()),
        b * (0.95 + 0.1 * rng.f32()),
        b * (0.95 + 0.1 * rng.f32()),
        1.0,
    )
}

/// The plaza: the `standing` characters of `cast` on a jittered spiral of `cell`-sized
/// places, facing every way.
fn plaza(
    cast: &[(usize, usize)],
    standing: &[usize],
    cell: f32,
    rng: &mut fastrand::Rng,
    agents: &mut Vec<Agent>,
) {
    for (k, &i) in standing.iter().enumerate() {
        let (m, clip) = cast[i];
        let r = cell * (k as f32 + 0.5).sqrt() * SPIRAL_PACKING;
        let a = k as f32 * GOLDEN_ANGLE;
        let jitter = Vec2::new(rng.f32() - 0.5, rng.f32() - 0.5) * cell * PLAZA_JITTER;
        let position = Vec2::new(a.cos(), a.sin()) * r + jitter;
        agents.push(Agent {
            wind: 1.0,
            scale: 1.0,
            model: m,
            clip,
            phase: rng.f32() * 10.0,
            speed: 0.9 + 0.2 * rng.f32(),
            ground_speed: 0.0,
            tint: tint(rng),
            path: Path::Still {
                position,
                heading: rng.f32() * std::f32::consts::TAU,
            },
            pause: None,
        });
    }
}

/// The lanes: the travelling characters of `cast` in (model, clip) groups, slowest
/// innermost, each group on as many circular lanes beyond `plaza_radius` as it fills,
/// alternate lanes walking opposite ways. Returns the outermost lane's radius.
fn lanes(
    models: &[CrowdModel],
    config: &CrowdConfig,
    cast: &[(usize, usize)],
    plaza_radius: f32,
    rng: &mut fastrand::Rng,
    agents: &mut Vec<Agent>,
) -> f32 {
    let mut groups: Vec<(usize, usize, Vec<usize>)> = Vec::new();
    for (i, &(m, clip)) in cast.iter().enumerate() {
        if models[m].clip_speeds[clip] <= 0.0 {
            continue;
        }
        match groups.iter_mut().find(|g| g.0 == m && g.1 == clip) {
            Some(g) => g.2.push(i),
            None => groups.push((m, clip, vec![i])),
        }
    }
    groups.sort_by(|a, b| {
        let sa = models[a.0].clip_speeds[a.1];
        let sb = models[b.0].clip_speeds[b.1];
        sa.total_cmp(&sb).then(a.0.cmp(&b.0)).then(a.1.cmp(&b.1))
    });
    let mut radius = plaza_radius + FIRST_LANE_GAP;
    let mut lane_index = 0;
    let mut outermost = plaza_radius;
    for (m, clip, members) in groups {
        let (width, length) = footprint(&models[m]);
        let lane_gap = width.max(MIN_WIDTH) * LANE_WIDTH + LANE_MARGIN;
        // Lanes are filled to about a third, at random spacings no shorter than `min_gap`.
        let min_gap = length * SPACING + SPACING_MARGIN;
        let ground_speed = models[m].clip_speeds[clip];
        // Everyone on a lane plays at the same speed, so nobody catches anybody up.
        let speed = 0.95 + 0.1 * rng.f32();
        let pause = lane_pause(&models[m], config, rng);
        let mut left = members.as_slice();
        radius += lane_gap * 0.5;
        while !left.is_empty() {
            let circumference = std::f32::consts::TAU * radius;
            let capacity = ((circumference / min_gap / LANE_FILL).floor() as usize).max(1);
            let take = capacity.min(left.len());
            let direction = if lane_index % 2 == 0 { 1.0 } else { -1.0 };
            for (angle, _) in lane_angles(take, circumference, min_gap, rng)
                .into_iter()
                .zip(&left[..take])
            {
                agents.push(Agent {
                    wind: 1.0,
                    scale: 1.0,
                    model: m,
                    clip,
                    phase: rng.f32() * 10.0,
                    speed,
                    ground_speed,
                    tint: tint(rng),
                    path: Path::Circle {
                        radius,
                        angle,
                        direction,
                    },
                    pause,
                });
            }
            left = &left[take..];
            outermost = radius;
            radius += lane_gap;
            lane_index += 1;
        }
    }
    outermost
}

/// Where cross-fades are on, a lane of `model` stops together now and then to play the
/// model's first clip on the spot: its walk, fades and hold, started at a random point.
fn lane_pause(model: &CrowdModel, config: &CrowdConfig, rng: &mut fastrand::Rng) -> Option<Pause> {
    let on_the_spot = model.clip_speeds.iter().position(|&s| s <= 0.0);
    match (config.cross_fade > 0.0, on_the_spot) {
        (true, Some(clip)) => {
            let walk = PAUSE_WALK + PAUSE_WALK * rng.f32();
            let fade = config.cross_fade;
            let hold = model.clip_durations.get(clip).copied().unwrap_or(2.0);
            let period = walk + 2.0 * fade + hold;
            Some(Pause {
                clip,
                start: -rng.f32() * period,
                walk,
                fade,
                hold,
            })
        }
        _ => None,
    }
}

/// `count` angles round a circle of the given circumference, randomly spaced but never closer
/// than `min_gap` along it: the gaps get `min_gap` each plus a random share of the rest.
fn lane_angles(
    count: usize,
    circumference: f32,
    min_gap: f32,
    rng: &mut fastrand::Rng,
) -> Vec<f32> {
    let slack = (circumference - count as f32 * min_gap).max(0.0);
    let shares: Vec<f32> = (0..count).map(|_| 0.2 + rng.f32()).collect();
    let total: f32 = shares.iter().sum();
    let start = rng.f32() * std::f32::consts::TAU;
    let mut at = 0.0;
    shares
        .iter()
        .map(|share| {
            let a = start + at / circumference * std::f32::consts::TAU;
            at += min_gap + slack * share / total;
            a
        })
        .collect()
}

/// Travelling clips three times as likely as clips played on the spot.
fn pick_clip(speeds: &[f32], rng: &mut fastrand::Rng) -> usize {
    let weight = |s: f32| if s > 0.0 { 3 } else { 1 };
    let total: u32 = speeds.iter().map(|&s| weight(s)).sum();
    let mut r = rng.u32(0..total.max(1));
    for (i, &s) in speeds.iter().enumerate() {
        if r < weight(s) {
            return i;
        }
        r -= weight(s);
    }
    0
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn models() -> Vec<CrowdModel> {
        let b = |x: f32, y: f32, z: f32| Bounds {
            min: Vec3::new(-x / 2.0, 0.0, -z / 2.0),
            max: Vec3::new(x / 2.0, y, z / 2.0),
        };
        vec![
            CrowdModel {
                clip_speeds: vec![1.6, 8.0],
                clip_durations: vec![1.2, 0.55],
                bounds: b(0.7, 2.0, 2.4),
            },
            CrowdModel {
                clip_speeds: vec![1.3, 0.0],
                clip_durations: vec![1.1, 2.4],
                bounds: b(0.6, 1.8, 0.4),
            },
        ]
    }

    #[test]
    fn layout_is_deterministic_and_counts_right() {
        let cfg = CrowdConfig {
            count: 200,
            ..Default::default()
        };
        let a = Crowd::layout(&models(), &cfg);
        let b = Crowd::layout(&models(), &cfg);
        assert_eq!(a, b);
        assert_eq!(a.agents.len(), 200);
        assert_eq!(a.agents.iter().filter(|g| g.model == 0).count(), 100);
    }

    #[test]
    fn nobody_overlaps_over_time() {
        for cross_fade in [0.0, 0.6] {
            nobody_overlaps(cross_fade);
        }
    }

    fn nobody_overlaps(cross_fade: f32) {
        let crowd = Crowd::layout(
            &models(),
            &CrowdConfig {
                count: 300,
                cross_fade,
                ..Default::default()
            },
        );
        let mut inst = Vec::new();
        for t in [0.0, 3.7, 20.0, 31.3] {
            crowd.instances_at(t, &mut inst);
            for i in 0..inst.len() {
                for j in i + 1..inst.len() {
                    let d = Vec3::from(inst[i].transform.translation)
                        .distance(Vec3::from(inst[j].transform.translation));
                    assert!(d > 0.5, "agents {i} and {j} are {d} m apart at t={t}");
                }
            }
        }
    }

    #[test]
    fn travellers_face_their_direction_of_motion() {
        let crowd = Crowd::layout(
            &models(),
            &CrowdConfig {
                count: 20,
                clips: vec![Some(0), Some(0)],
                ..Default::default()
            },
        );
        for a in &crowd.agents {
            let p0 = Vec3::from(a.transform_at(1.0).translation);
            let p1 = Vec3::from(a.transform_at(1.01).translation);
            let facing = a.transform_at(1.0).transform_vector3(Vec3::Z);
            assert!((p1 - p0).normalize().dot(facing) > 0.99);
        }
    }

    #[test]
    fn a_pause_fades_in_holds_and_fades_out_continuously() {
        let p = Pause {
            clip: 1,
            start: -3.0,
            walk: 5.0,
            fade: 0.5,
            hold: 2.4,
        };
        let period = p.period();
        assert!((period - 8.4).abs() < 1e-6);
        // Walking, fading in, held, fading out, walking again.
        let at = |u: f32| p.start + period + u;
        assert_eq!(p.weight(at(2.0)), 0.0);
        assert!((p.weight(at(5.25)) - 0.5).abs() < 1e-4);
        assert_eq!(p.weight(at(6.5)), 1.0);
        assert!((p.weight(at(8.15)) - 0.5).abs() < 1e-4);
        // The weight and the distance walked never jump; the distance never goes back, stays
        // put while the clip is held, and grows by walk + fade a cycle.
        let mut last = (p.weight(-10.0), p.walked(-10.0));
        let step = 0.001;
        let mut t = -10.0 + step;
        while t < 20.0 {
            let now = (p.weight(t), p.walked(t));
            assert!(
                (now.0 - last.0).abs() <= step / p.fade + 1e-3,
                "weight jumps at {t}"
            );
            assert!(
                now.1 >= last.1 - 1e-4 && now.1 - last.1 <= step + 1e-3,
                "at {t}"
            );
            last = now;
            t += step;
        }
        assert!((p.walked(at(6.0)) - p.walked(at(7.0))).abs() < 1e-5);
        assert!((p.walked(at(1.0) + period) - p.walked(at(1.0)) - 5.5).abs() < 1e-3);
    }

    #[test]
    fn lane_walkers_stop_to_play_the_clip_on_the_spot_and_walk_on() {
        let crowd = Crowd::layout(
            &models(),
            &CrowdConfig {
                count: 40,
                clips: vec![Some(0), Some(0)],
                cross_fade: 0.6,
                ..Default::default()
            },
        );
        // Model 1 has a clip on the spot (clip 1), model 0 none: only model 1's walkers stop.
        for a in &crowd.agents {
            assert_eq!(a.pause.is_some(), a.model == 1, "{a:?}");
        }
        let a = crowd.agents.iter().find(|a| a.model == 1).unwrap();
        let p = a.pause.unwrap();
        let held = p.start + p.walk + p.fade + 0.5 * p.hold;
        let inst = a.instance_at(held);
        let fade = inst.fade.expect("a cross-fade while stopped");
        assert_eq!((fade.clip, fade.weight), (1, 1.0));
        // The clip on the spot began at the start of the fade: its time now is 0.6 + 1.2 s.
        assert!((held * fade.speed + fade.time_offset - (p.fade + 0.5 * p.hold)).abs() < 1e-3);
        // Standing still while held, walking again after.
        let here = Vec3::from(a.transform_at(held).translation);
        let later = Vec3::from(a.transform_at(held + 0.2).translation);
        assert!(here.distance(later) < 1e-4);
        let walking = p.start + p.period() + 1.0;
        assert!(a.instance_at(walking).fade.is_none());
        let moved = Vec3::from(a.transform_at(walking).translation)
            .distance(Vec3::from(a.transform_at(walking + 0.2).translation));
        assert!(moved > 0.2 * 1.3 * 0.9, "{moved}");
        // A lane pauses together: every walker of it shares the pause.
        for b in crowd.agents.iter().filter(|b| b.model == 1) {
            if let (Path::Circle { radius: r, .. }, Path::Circle { radius: s, .. }) =
                (a.path, b.path)
                && r == s
            {
                assert_eq!(b.pause, a.pause);
            }
        }
    }
}

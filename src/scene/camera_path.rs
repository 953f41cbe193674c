//! Camera paths: the camera as a pure function of time, so that a benchmark or a recorded clip
//! sees the same frames on every machine, however slowly it renders them.

use super::Camera;
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::f32::consts::TAU;

crate::choice! {
    own_values;
    /// The kinds of path, by the names the command line and the reports use.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
    #[serde(rename_all = "lowercase")]
    pub enum PathKind {
        /// Inwards, turning three quarters round the target (Merry et al. §6.2).
        Spiral => "spiral",
        /// One turn, swinging from near to far and back.
        Orbit => "orbit",
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraPath {
    /// Merry et al. §6.2: "an inward spiral to show a range of angles and distances". Over
    /// `duration` seconds the eye turns `turns` times round the target while its distance
    /// shrinks geometrically from `far` to `near` (a steady zoom to the eye) and it comes down
    /// from `pitch_far` to `pitch_near` (radians).
    Spiral {
        target: Vec3,
        start_yaw: f32,
        turns: f32,
        far: f32,
        near: f32,
        pitch_far: f32,
        pitch_near: f32,
        duration: f32,
    },
    /// A closed loop for benchmarks: one turn round the target every `period` seconds while
    /// the distance swings from `near` out to `far` and back, so that every level of detail is
    /// drawn in every stretch of the loop.
    Orbit {
        target: Vec3,
        start_yaw: f32,
        near: f32,
        far: f32,
        pitch_near: f32,
        pitch_far: f32,
        period: f32,
    },
}

impl CameraPath {
    /// A path of `kind` round the view `home` shows (a scene's default camera): from 1.6
    /// times its distance in to 0.3 times, over `seconds`.
    pub fn new(kind: PathKind, home: &Camera, seconds: f32) -> CameraPath {
        let seconds = seconds.max(1e-3);
        let far = home.distance * 1.6;
        let near = home.distance * 0.3;
        match kind {
            PathKind::Spiral => CameraPath::Spiral {
                target: home.target,
                start_yaw: home.yaw,
                turns: 0.75,
                far,
                near,
                pitch_far: 32f32.to_radians(),
                pitch_near: 8f32.to_radians(),
                duration: seconds,
            },
            PathKind::Orbit => CameraPath::Orbit {
                target: home.target,
                start_yaw: home.yaw,
                near,
                far,
                pitch_near: 10f32.to_radians(),
                pitch_far: 25f32.to_radians(),
                period: seconds,
            },
        }
    }

    /// Seconds the path lasts (a spiral) or takes to come round (an orbit).
    pub fn duration(&self) -> f32 {
        match *self {
            CameraPath::Spiral { duration, .. } => duration,
            CameraPath::Orbit { period, .. } => period,
        }
    }

    /// The camera at `t` seconds; `fov_y` from `home`'s. A spiral stays at its ends outside
    /// [0, duration]; an orbit repeats.
    pub fn at(&self, t: f32, fov_y: f32) -> Camera {
        let (target, yaw, pitch, distance) = match *self {
            CameraPath::Spiral {
                target,
                start_yaw,
                turns,
                far,
                near,
                pitch_far,
                pitch_near,
                duration,
            } => {
                let u = (t / duration).clamp(0.0, 1.0);
                (
                    target,
                    start_yaw + turns * TAU * u,
                    pitch_far + (pitch_near - pitch_far) * u,
                    far * (near / far).powf(u),
                )
            }
            CameraPath::Orbit {
                target,
                start_yaw,
                near,
                far,
                pitch_near,
                pitch_far,
                period,
            } => {
                let u = (t / period).rem_euclid(1.0);
                // 0 at the start and the end of the loop, 1 half-way round.
                let out = 0.5 - 0.5 * (TAU * u).cos();
                (
                    target,
                    start_yaw + TAU * u,
                    pitch_near + (pitch_far - pitch_near) * out,
                    near * (far / near).powf(out),
                )
            }
        };
        let mut camera = Camera::new(target, 0.0, 0.0, distance);
        camera.yaw = yaw.rem_euclid(TAU);
        camera.pitch = pitch;
        camera.fov_y = fov_y;
        camera
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn home() -> Camera {
        Camera::new(Vec3::new(1.0, 0.5, -2.0), 35.0, 14.0, 20.0)
    }

    #[test]
    fn the_spiral_closes_in_steadily_and_turns_round_the_target() {
        let home = home();
        let path = CameraPath::new(PathKind::Spiral, &home, 8.0);
        let at = |t: f32| path.at(t, home.fov_y);
        assert!((at(0.0).distance - 32.0).abs() < 1e-3);
        assert!((at(8.0).distance - 6.0).abs() < 1e-3);
        // Geometric: equal ratios over equal times, and always closer.
        let r1 = at(2.0).distance / at(0.0).distance;
        let r2 = at(6.0).distance / at(4.0).distance;
        assert!((r1 - r2).abs() < 1e-4);
        let mut last = at(0.0);
        for k in 1..=80 {
            let c = at(k as f32 * 0.1);
            assert!(c.distance < last.distance);
            assert!(c.pitch <= last.pitch);
            assert_eq!(c.target, home.target);
            // Smooth: no step longer than a few per cent of the distance.
            assert!(c.eye().distance(last.eye()) < 0.1 * last.distance);
            last = c;
        }
        // Three quarters of a turn: from the start, the eye ends up on another side.
        let start = at(0.0).eye() - home.target;
        let end = at(8.0).eye() - home.target;
        let turned = start.x.atan2(start.z) - end.x.atan2(end.z);
        assert!((turned.rem_euclid(TAU) - 0.25 * TAU).abs() < 1e-3);
        // It holds its ends.
        assert_eq!(at(-1.0), at(0.0));
        assert_eq!(at(9.0), at(8.0));
    }

    #[test]
    fn the_orbit_is_a_closed_loop_from_near_to_far() {
        let home = home();
        let path = CameraPath::new(PathKind::Orbit, &home, 10.0);
        let at = |t: f32| path.at(t, home.fov_y);
        assert!(at(0.0).eye().distance(at(10.0).eye()) < 1e-3);
        assert!(at(3.0).eye().distance(at(13.0).eye()) < 1e-3);
        assert!((at(0.0).distance - 6.0).abs() < 1e-3);
        assert!((at(5.0).distance - 32.0).abs() < 1e-3);
        for kind in [PathKind::Spiral, PathKind::Orbit] {
            let parsed: PathKind = crate::choice::parse(kind.name(), "a camera path").unwrap();
            assert_eq!(parsed, kind);
        }
        assert!(crate::choice::parse::<PathKind>("zigzag", "a camera path").is_err());
    }
}

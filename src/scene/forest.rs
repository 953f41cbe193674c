//! The forest: trees standing on a jittered grid, each turned and phased at random so that they
//! do not sway in step. Deterministic for a seed. The layout is a [`Crowd`] of agents that stand
//! still, so everything downstream (instances, selection, drawing) treats trees and characters
//! alike.

use super::crowd::{Agent, Crowd, CrowdModel, Path};
use glam::{Vec2, Vec4};

/// Lays out `count` trees of `models` (taken in turn).
pub fn layout(models: &[CrowdModel], count: usize, seed: u64) -> Crowd {
    if models.is_empty() || count == 0 {
        return Crowd::default();
    }
    let mut rng = fastrand::Rng::with_seed(seed);
    // Spacing: the widest crown, with a little air between neighbours.
    let crown = models
        .iter()
        .map(|m| m.bounds.size().x.max(m.bounds.size().z))
        .fold(1.0f32, f32::max);
    let spacing = crown * 1.05;
    let side = (count as f32).sqrt().ceil() as usize;
    let half = (side as f32 - 1.0) * 0.5;
    let mut agents = Vec::with_capacity(count);
    let mut radius = 0.0f32;
    for i in 0..count {
        let (gx, gz) = ((i % side) as f32 - half, (i / side) as f32 - half);
        let jitter = Vec2::new(rng.f32() - 0.5, rng.f32() - 0.5) * spacing * 0.3;
        let position = if count == 1 {
            Vec2::ZERO
        } else {
            Vec2::new(gx, gz) * spacing + jitter
        };
        radius = radius.max(position.length() + crown * 0.5);
        let m = i % models.len();
        // A slightly different green for every tree.
        let tint = Vec4::new(
            0.92 + 0.16 * rng.f32(),
            0.92 + 0.16 * rng.f32(),
            0.9 + 0.12 * rng.f32(),
            1.0,
        );
        agents.push(Agent {
            model: m,
            // Gusts differ from tree to tree: between 0.6 and 1.4 of the clip's sway.
            wind: if count == 1 {
                1.0
            } else {
                0.6 + 0.8 * rng.f32()
            },
            clip: 0,
            phase: if count == 1 { 0.0 } else { rng.f32() * 30.0 },
            speed: if count == 1 {
                1.0
            } else {
                0.9 + 0.2 * rng.f32()
            },
            ground_speed: 0.0,
            tint,
            path: Path::Still {
                position,
                heading: rng.f32() * std::f32::consts::TAU,
            },
        });
    }
    Crowd {
        agents,
        radius: radius.max(crown),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Bounds;
    use glam::Vec3;

    #[test]
    fn trees_stand_apart_and_the_layout_is_deterministic() {
        let m = CrowdModel {
            clip_speeds: vec![0.0],
            bounds: Bounds {
                min: Vec3::new(-2.0, 0.0, -2.0),
                max: Vec3::new(2.0, 8.0, 2.0),
            },
        };
        let a = layout(std::slice::from_ref(&m), 12, 3);
        assert_eq!(a, layout(std::slice::from_ref(&m), 12, 3));
        assert_eq!(a.agents.len(), 12);
        let at = |g: &Agent| match g.path {
            Path::Still { position, .. } => position,
            Path::Circle { .. } => panic!("trees do not walk"),
        };
        for (i, p) in a.agents.iter().enumerate() {
            for q in &a.agents[i + 1..] {
                assert!(at(p).distance(at(q)) > 4.0 * 0.7, "trees too close");
            }
        }
    }
}

//! The forest: trees standing on a jittered grid, each turned, scaled, phased and given its own
//! wind strength at random so that they do not sway in step. Deterministic for a seed. The
//! layout is a [`Crowd`] of agents that stand still, so everything downstream (instances,
//! selection, drawing) treats trees and characters alike. [`around`] lays a forest round a
//! clearing where a crowd walks (the mixed scene).

use super::crowd::{Agent, Crowd, CrowdModel, Path};
use glam::{Vec2, Vec4};

/// Lays out `count` trees of `models` (taken in turn).
pub fn layout(models: &[CrowdModel], count: usize, seed: u64) -> Crowd {
    around(models, count, seed, 0.0)
}

/// Lays out `count` trees of `models` (taken in turn) on the grid cells nearest the centre
/// whose trunks stand at least `clearing` from it (0: a square patch from the centre out).
pub fn around(models: &[CrowdModel], count: usize, seed: u64, clearing: f32) -> Crowd {
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
    let cells: Vec<Vec2> = if clearing <= 0.0 {
        // Row by row: a square patch.
        let side = (count as f32).sqrt().ceil() as usize;
        let half = (side as f32 - 1.0) * 0.5;
        (0..count)
            .map(|i| Vec2::new((i % side) as f32 - half, (i / side) as f32 - half) * spacing)
            .collect()
    } else {
        // The cells nearest the centre outside the clearing: a ring round it.
        let cleared = (clearing / spacing).ceil();
        let side = ((count as f32 + std::f32::consts::PI * cleared * cleared).sqrt() + 2.0).ceil()
            as usize
            * 2
            + 1;
        let half = (side as f32 - 1.0) * 0.5;
        let mut cells: Vec<Vec2> = (0..side * side)
            .map(|i| Vec2::new((i % side) as f32 - half, (i / side) as f32 - half) * spacing)
            .filter(|c| c.length() >= clearing)
            .collect();
        cells.sort_by(|a, b| a.length().total_cmp(&b.length()));
        cells.truncate(count);
        cells
    };
    let mut agents = Vec::with_capacity(count);
    let mut radius = 0.0f32;
    for (i, cell) in cells.into_iter().enumerate() {
        let jitter = Vec2::new(rng.f32() - 0.5, rng.f32() - 0.5) * spacing * 0.3;
        let position = if count == 1 && clearing <= 0.0 {
            Vec2::ZERO
        } else {
            cell + jitter
        };
        radius = radius.max(position.length() + crown * 0.5);
        let m = i % models.len();
        // A slightly different green for every tree; a lone tree its own colours, as a
        // measurement or another renderer's picture of it expects.
        let tint = Vec4::new(
            0.92 + 0.16 * rng.f32(),
            0.92 + 0.16 * rng.f32(),
            0.9 + 0.12 * rng.f32(),
            1.0,
        );
        let tint = if count == 1 { Vec4::ONE } else { tint };
        agents.push(Agent {
            model: m,
            // Gusts differ from tree to tree: between 0.6 and 1.4 of the clip's sway.
            wind: if count == 1 {
                1.0
            } else {
                0.6 + 0.8 * rng.f32()
            },
            // Sizes vary by about a quarter either way.
            scale: if count == 1 {
                1.0
            } else {
                0.8 + 0.45 * rng.f32()
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
                // A lone tree faces the way it was modelled, as a measurement expects to
                // find it (the draw is made all the same, so later trees keep their turns).
                heading: match rng.f32() * std::f32::consts::TAU {
                    _ if count == 1 => 0.0,
                    turn => turn,
                },
            },
            pause: None,
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

    /// Round a clearing, every trunk stands outside it, as many trees as asked, each with its
    /// own wind and size.
    #[test]
    fn a_forest_round_a_clearing_keeps_out_of_it() {
        let m = CrowdModel {
            clip_speeds: vec![0.0],
            clip_durations: vec![4.0],
            bounds: Bounds {
                min: Vec3::new(-2.0, 0.0, -2.0),
                max: Vec3::new(2.0, 8.0, 2.0),
            },
        };
        let f = around(std::slice::from_ref(&m), 200, 5, 30.0);
        assert_eq!(f.agents.len(), 200);
        for a in &f.agents {
            let Path::Still { position, .. } = a.path else {
                panic!("trees do not walk")
            };
            // Cells lie outside the clearing; jitter moves a trunk by under a third of a cell.
            assert!(position.length() > 30.0 - 4.2 * 0.3, "{position}");
            assert!((0.6..=1.4).contains(&a.wind) && (0.8..=1.25).contains(&a.scale));
        }
        let winds: std::collections::BTreeSet<u32> =
            f.agents.iter().map(|a| (a.wind * 1000.0) as u32).collect();
        assert!(winds.len() > 150, "winds vary tree to tree");
    }

    #[test]
    fn trees_stand_apart_and_the_layout_is_deterministic() {
        let m = CrowdModel {
            clip_speeds: vec![0.0],
            clip_durations: vec![4.0],
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

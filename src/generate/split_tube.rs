//! "split-tube": a test model with the properties of exported game assets that the demo
//! creatures lack. A tapered tail of 896 triangles on a chain of four joints, written the way
//! an exporter writes an indexed mesh:
//! - hard edges: four creases along its length, a crease between every three rings (armour
//!   segments), flat end caps; every position on one is split into one render vertex per side;
//! - a UV seam along its length, and texture coordinates only on a label band round the middle:
//!   everywhere else every corner has UV (0, 0), so most triangles have zero UV area;
//! - copies of a position differ by a rounding error in position and weights.
//!
//! So positions are split two to three ways, and nothing but welding by position within a
//! tolerance closes the surface. One clip, `swish`, waves the tail in a travelling wave.

use super::facets::{FacetBuilder, normalised};
use super::rig::{Chain, Pose, Rig, bake_clip, euler, wave};
use crate::model::{Material, Model};
use glam::{Vec2, Vec3};

const SIDES: usize = 16;
const RINGS: usize = 27;
const LENGTH: f32 = 1.6;
const RADIUS: f32 = 0.16;
/// Rings `LABEL.0..LABEL.1` carry real texture coordinates.
const LABEL: (usize, usize) = (11, 15);

pub fn split_tube() -> Model {
    let mut rig = Rig::default();
    let mut parent = None;
    let mut bones = Vec::new();
    for k in 0..4 {
        let b = rig.bone(
            &format!("tail{k}"),
            parent,
            Vec3::new(0.0, LENGTH * k as f32 / 4.0, 0.0),
        );
        bones.push(b);
        parent = Some(b);
    }
    let chain = Chain::new(&rig, &bones, Vec3::new(0.0, LENGTH, 0.0));

    let mut b = FacetBuilder::default();
    let rings: Vec<Vec<u32>> = (0..=RINGS)
        .map(|i| {
            let y = LENGTH * i as f32 / RINGS as f32;
            let r = RADIUS * (1.0 - 0.35 * y / LENGTH);
            let w = normalised(chain.weights(4.0 * y / LENGTH));
            (0..SIDES)
                .map(|j| {
                    let a = std::f32::consts::TAU * j as f32 / SIDES as f32;
                    b.point(Vec3::new(r * a.cos(), y, -r * a.sin()), w.clone())
                })
                .collect()
        })
        .collect();
    for i in 0..RINGS {
        let (v0, v1) = (i as f32 / RINGS as f32, (i + 1) as f32 / RINGS as f32);
        let label = (LABEL.0..LABEL.1).contains(&i);
        for j in 0..SIDES {
            let j1 = (j + 1) % SIDES;
            // The seam: the last column ends at u = 1, where the first starts at u = 0.
            let (u0, u1) = (j as f32 / SIDES as f32, (j + 1) as f32 / SIDES as f32);
            let uv = if label {
                [
                    Vec2::new(u0, v0),
                    Vec2::new(u1, v0),
                    Vec2::new(u1, v1),
                    Vec2::new(u0, v1),
                ]
            } else {
                [Vec2::ZERO; 4]
            };
            let group = (j / (SIDES / 4) + 4 * (i / 3)) as u32;
            b.quad(
                [rings[i][j], rings[i][j1], rings[i + 1][j1], rings[i + 1][j]],
                group,
                uv,
            );
        }
    }
    // Flat caps, each a fan round a centre point in a smoothing group of its own.
    for (end, ring, dir) in [(0usize, &rings[0], -1.0f32), (1, &rings[RINGS], 1.0)] {
        let y = if end == 0 { 0.0 } else { LENGTH };
        let centre = b.point(
            Vec3::new(0.0, y, 0.0),
            normalised(chain.weights(4.0 * y / LENGTH)),
        );
        let group = 1000 + end as u32;
        for j in 0..SIDES {
            let j1 = (j + 1) % SIDES;
            let tri = if dir > 0.0 {
                [centre, ring[j], ring[j1]]
            } else {
                [centre, ring[j1], ring[j]]
            };
            b.triangle(tri, group, [Vec2::ZERO; 3]);
        }
    }

    let clip = bake_clip("swish", 2.0, 0.0, &rig, bones[0], |phase| {
        let mut p = Pose::rest(rig.len());
        for (k, &bone) in bones.iter().enumerate().skip(1) {
            let swing = 32.0 * wave(phase, 1.0, -0.12 * k as f32);
            let nod = 14.0 * wave(phase, 2.0, -0.1 * k as f32);
            p.rotate(bone, euler(nod, 0.0, swing));
        }
        p
    });
    Model {
        name: "split-tube".into(),
        mesh: b.build(2e-7),
        skeleton: rig.skeleton(),
        clips: vec![clip],
        materials: vec![Material::opaque("scales", [0.45, 0.62, 0.38, 1.0], None)],
    }
}

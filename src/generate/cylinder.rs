//! The "cylinder" test model of Merry et al. (Figure 5): an open tube that bends in the middle.
//! Small, quick to simplify and with one joint whose bend the rest pose does not show, it is
//! what the simplifier's tests and benchmarks run on; `rings` and `sides` scale it to any size.

use super::rig::{Pose, Rig, bake_clip, euler, wave};
use crate::model::{Influence, Material, Model, SkinnedMesh};
use glam::{Vec2, Vec3};

/// Height and radius of the tube, in metres.
pub const HEIGHT: f32 = 2.0;
pub const RADIUS: f32 = 0.3;

/// A tube of `rings` × `sides` quads (at least 2 × 3) along +y, textured by one chart that wraps
/// around it (so one UV seam runs up its side) with open ends. Bone `base` holds the lower half,
/// bone `top` (its child, at mid height) the upper half, and the weights blend across the
/// middle fifth. One clip, `bend`, swings the top half through ±70° once a second.
pub fn bent_cylinder(rings: usize, sides: usize) -> Model {
    let (rings, sides) = (rings.max(2), sides.max(3));
    let mut rig = Rig::default();
    let base = rig.bone("base", None, Vec3::ZERO);
    rig.bone("top", Some(base), Vec3::new(0.0, HEIGHT / 2.0, 0.0));
    let mut mesh = SkinnedMesh::default();
    mesh.influence_offsets.push(0);
    for i in 0..=rings {
        let y = HEIGHT * i as f32 / rings as f32;
        let t = ((y / HEIGHT - 0.4) / 0.2).clamp(0.0, 1.0);
        let w = t * t * (3.0 - 2.0 * t);
        for j in 0..=sides {
            // The last column closes the tube at exactly the first one's position.
            let theta = std::f32::consts::TAU * (j % sides) as f32 / sides as f32;
            let (s, c) = theta.sin_cos();
            mesh.positions.push(Vec3::new(RADIUS * c, y, RADIUS * s));
            mesh.normals.push(Vec3::new(c, 0.0, s));
            mesh.uvs
                .push(Vec2::new(j as f32 / sides as f32, 1.0 - y / HEIGHT));
            mesh.materials.push(0);
            for (bone, weight) in [(0, 1.0 - w), (1, w)] {
                if weight > 0.0 {
                    mesh.influences.push(Influence { bone, weight });
                }
            }
            mesh.influence_offsets.push(mesh.influences.len() as u32);
        }
    }
    let row = (sides + 1) as u32;
    for i in 0..rings as u32 {
        for j in 0..sides as u32 {
            let a = i * row + j;
            let (b, c, d) = (a + 1, a + row + 1, a + row);
            // Counter-clockwise seen from outside.
            mesh.indices.extend([a, c, b, a, d, c]);
        }
    }
    let clip = bake_clip("bend", 1.0, 0.0, &rig, base, |phase| {
        let mut p = Pose::rest(2);
        p.rotate(1, euler(0.0, 0.0, 70.0 * wave(phase, 1.0, 0.0)));
        p
    });
    Model {
        name: "cylinder".into(),
        mesh,
        skeleton: rig.skeleton(),
        clips: vec![clip],
        materials: vec![Material::opaque("grey", [0.7, 0.7, 0.7, 1.0], None)],
    }
}

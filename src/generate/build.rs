//! Helpers shared by the creature definitions: body rings from a spine, limbs extruded along a
//! bone chain, nearest-point queries on chains.

use super::cage::{Cage, ExtrudeRing, Extrusion, FaceId, Ring, Weights};
use super::finish::{finish, paint};
use super::rig::{Chain, Rig};
use crate::model::{Clip, Material, Model};
use glam::{Vec2, Vec3};

/// Side of the square texture every creature is painted into.
const TEXTURE_SIZE: u32 = 512;

/// A colour function of (part, rest position, normal), as [`paint`] takes it.
pub type Painter = Box<dyn Fn(u32, Vec3, Vec3) -> Vec3>;

/// The last steps every creature shares: two levels of Catmull–Clark, the triangle mesh with its
/// atlas, the texture painted by the painter `coat` makes once it can see the finished surface
/// (to put eyes on it), and the model.
pub fn assemble(
    name: &str,
    material: &str,
    rig: &Rig,
    cage: Cage,
    clips: Vec<Clip>,
    coat: impl FnOnce(&[Vec3]) -> Painter,
) -> Model {
    assemble_subdivided(
        name,
        material,
        rig,
        cage.subdivide().subdivide(),
        clips,
        coat,
    )
}

/// [`assemble`] for a cage already subdivided as far as it should be.
pub fn assemble_subdivided(
    name: &str,
    material: &str,
    rig: &Rig,
    cage: Cage,
    clips: Vec<Clip>,
    coat: impl FnOnce(&[Vec3]) -> Painter,
) -> Model {
    let finished = finish(&cage, TEXTURE_SIZE);
    let painter = coat(&finished.mesh.positions);
    let texture = paint(&finished, TEXTURE_SIZE, &*painter);
    Model {
        name: name.into(),
        mesh: finished.mesh,
        skeleton: rig.skeleton(),
        clips,
        materials: vec![Material::opaque(material, [1.0; 4], Some(texture))],
    }
}

/// A cross-section of a body tube: centre, and half extents across (lateral) and up.
#[derive(Clone, Copy, Debug)]
pub struct Section {
    pub center: Vec3,
    pub half: Vec2,
}

pub const fn section(x: f32, y: f32, z: f32, half_lateral: f32, half_up: f32) -> Section {
    Section {
        center: Vec3::new(x, y, z),
        half: Vec2::new(half_lateral, half_up),
    }
}

/// An eight-sided cross-section, unit half extents: from the lower left corner round through
/// the left side, the top, the right side and back along the bottom. Suits an upright torso:
/// its caps split into left, middle and right quads for legs.
pub const OCTAGON: [Vec2; 8] = [
    Vec2::new(-0.55, -1.0),
    Vec2::new(-1.0, -0.42),
    Vec2::new(-1.0, 0.42),
    Vec2::new(-0.55, 1.0),
    Vec2::new(0.55, 1.0),
    Vec2::new(1.0, 0.42),
    Vec2::new(1.0, -0.42),
    Vec2::new(0.55, -1.0),
];

/// A ten-sided cross-section for a quadruped's barrel: nearly flat faces low on either side for
/// the legs to hang from, and sloping faces high on either side for the ears.
pub const DECAGON: [Vec2; 10] = [
    Vec2::new(-0.32, -1.0),
    Vec2::new(-0.8, -0.84),
    Vec2::new(-1.0, -0.25),
    Vec2::new(-0.92, 0.45),
    Vec2::new(-0.4, 1.0),
    Vec2::new(0.4, 1.0),
    Vec2::new(0.92, 0.45),
    Vec2::new(1.0, -0.25),
    Vec2::new(0.8, -0.84),
    Vec2::new(0.32, -1.0),
];

/// Rings of a body tube through `sections`, oriented by the path: the lateral axis stays
/// `lateral`, "up" is perpendicular to it and to the path. Weights come from the nearest point
/// of `chain`.
pub fn body_rings(
    sections: &[Section],
    profile: &[Vec2],
    lateral: Vec3,
    chain: &Chain,
) -> Vec<Ring> {
    let n = sections.len();
    (0..n)
        .map(|j| {
            let prev = sections[j.saturating_sub(1)].center;
            let next = sections[(j + 1).min(n - 1)].center;
            let t = (next - prev).normalize();
            let up = t.cross(lateral).normalize();
            let side = up.cross(t);
            let s = &sections[j];
            Ring {
                center: s.center,
                points: profile
                    .iter()
                    .map(|q| s.center + side * (q.x * s.half.x) + up * (q.y * s.half.y))
                    .collect(),
                weights: chain.weights(project(chain, s.center)),
            }
        })
        .collect()
}

/// Chain coordinate of the point of `chain` nearest to `p`.
pub fn project(chain: &Chain, p: Vec3) -> f32 {
    let mut best = (f32::MAX, 0.0);
    for i in 0..chain.bones.len() {
        let (a, b) = (chain.points[i], chain.points[i + 1]);
        let ab = b - a;
        let t = ((p - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
        let d = p.distance(a + ab * t);
        if d < best.0 {
            best = (d, i as f32 + t);
        }
    }
    best.1
}

/// One ring of a limb: where along the chain, and the half extents across (along `lateral`)
/// and the other way.
#[derive(Clone, Copy, Debug)]
pub struct LimbRing {
    pub s: f32,
    pub half: Vec2,
}

pub const fn limb(s: f32, half_lateral: f32, half_other: f32) -> LimbRing {
    LimbRing {
        s,
        half: Vec2::new(half_lateral, half_other),
    }
}

/// Extrudes `face` along `chain`, one ring per entry, weights following the chain.
pub fn extrude_limb(
    cage: &mut Cage,
    face: FaceId,
    chain: &Chain,
    rings: &[LimbRing],
    lateral: Vec3,
    part: u32,
    cap_part: u32,
) -> Extrusion {
    let rings: Vec<ExtrudeRing> = rings
        .iter()
        .map(|r| ExtrudeRing {
            center: chain.point(r.s),
            half: r.half,
            weights: chain.weights(r.s),
        })
        .collect();
    cage.extrude_along(face, &rings, lateral, part, cap_part)
}

/// Extrudes `face` through explicit centres, all rigidly on one set of weights.
pub fn extrude_rigid(
    cage: &mut Cage,
    face: FaceId,
    rings: &[(Vec3, Vec2)],
    weights: &Weights,
    lateral: Vec3,
    part: u32,
    cap_part: u32,
) -> Extrusion {
    let rings: Vec<ExtrudeRing> = rings
        .iter()
        .map(|&(center, half)| ExtrudeRing {
            center,
            half,
            weights: weights.clone(),
        })
        .collect();
    cage.extrude_along(face, &rings, lateral, part, cap_part)
}

/// The mesh vertex nearest to `target`: for placing painted details (eyes) on the surface.
pub fn nearest_surface_point(positions: &[Vec3], target: Vec3) -> Vec3 {
    positions
        .iter()
        .copied()
        .min_by(|a, b| a.distance(target).total_cmp(&b.distance(target)))
        .unwrap_or(target)
}

//! "robot": a file with the layout of a kit-bashed character from an asset store. 19 rigid,
//! flat-shaded parts (boxes and cylinders, every vertex on one bone) on 18 joints, written as 19
//! primitives of four meshes, each mesh bound to a skin of its own that lists a few of the
//! joints in its own order (the torso's, each arm's, the legs'); plain-coloured materials; a
//! morph target on the visor. Two primitives hold what exporters leave behind: triangles that
//! repeat a vertex (glTF-Validator's `ACCESSOR_INDEX_TRIANGLE_DEGENERATE`), triangles of no area
//! between distinct vertices, a triangle written twice, and vertices no triangle uses. One clip,
//! `walk`.
//!
//! Metres, facing +z, standing on y = 0, left side at +x.

use super::file::{DocMesh, DocPrimitive, DocSkin, Document};
use crate::generate::facets::FacetBuilder;
use crate::generate::rig::{Pose, Rig, bake_clip, bump, euler, rigid};
use crate::model::{Clip, Material, SkinnedMesh, Trs};
use glam::{Mat4, Quat, Vec2, Vec3};
use std::f32::consts::TAU;

/// Materials, by index.
const METAL: usize = 0;
const JOINT: usize = 1;
const PAINT: usize = 2;
const GLASS: usize = 3;

/// One part: its triangles, the bone it rides on, its material, and which skin's mesh it is in.
struct Part {
    mesh: SkinnedMesh,
    material: usize,
    skin: usize,
}

/// A box with hard edges round `centre`, turned by `turn`, every vertex on `bone`.
fn cuboid(centre: Vec3, half: Vec3, turn: Quat, bone: usize) -> SkinnedMesh {
    let mut b = FacetBuilder::default();
    let corner = |b: &mut FacetBuilder, s: [f32; 3]| {
        b.point(centre + turn * (Vec3::from(s) * half), rigid(bone))
    };
    let mut ids = [[[0u32; 2]; 2]; 2];
    for (x, plane) in ids.iter_mut().enumerate() {
        for (y, row) in plane.iter_mut().enumerate() {
            for (z, id) in row.iter_mut().enumerate() {
                let s = |k: usize| if k == 0 { -1.0 } else { 1.0 };
                *id = corner(&mut b, [s(x), s(y), s(z)]);
            }
        }
    }
    let v = |x: usize, y: usize, z: usize| ids[x][y][z];
    let faces = [
        [v(1, 0, 0), v(1, 1, 0), v(1, 1, 1), v(1, 0, 1)],
        [v(0, 0, 0), v(0, 0, 1), v(0, 1, 1), v(0, 1, 0)],
        [v(0, 1, 0), v(0, 1, 1), v(1, 1, 1), v(1, 1, 0)],
        [v(0, 0, 0), v(1, 0, 0), v(1, 0, 1), v(0, 0, 1)],
        [v(0, 0, 1), v(1, 0, 1), v(1, 1, 1), v(0, 1, 1)],
        [v(0, 0, 0), v(0, 1, 0), v(1, 1, 0), v(1, 0, 0)],
    ];
    for (g, f) in faces.into_iter().enumerate() {
        b.quad(f, g as u32, [Vec2::ZERO; 4]);
    }
    b.build(0.0)
}

/// A faceted cylinder from `a` to `b` of radius `r`, `sides` flat sides and flat caps.
fn cylinder(a: Vec3, b: Vec3, r: f32, sides: usize, bone: usize) -> SkinnedMesh {
    let mut f = FacetBuilder::default();
    let axis = (b - a).normalize();
    let turn = Quat::from_rotation_arc(Vec3::Y, axis);
    let ring = |f: &mut FacetBuilder, c: Vec3| -> Vec<u32> {
        (0..sides)
            .map(|j| {
                let t = TAU * j as f32 / sides as f32;
                f.point(
                    c + turn * Vec3::new(r * t.cos(), 0.0, -r * t.sin()),
                    rigid(bone),
                )
            })
            .collect()
    };
    let (lo, hi) = (ring(&mut f, a), ring(&mut f, b));
    let (ca, cb) = (f.point(a, rigid(bone)), f.point(b, rigid(bone)));
    for j in 0..sides {
        let j1 = (j + 1) % sides;
        f.quad([lo[j], lo[j1], hi[j1], hi[j]], j as u32, [Vec2::ZERO; 4]);
        f.triangle([cb, hi[j], hi[j1]], sides as u32, [Vec2::ZERO; 3]);
        f.triangle([ca, lo[j1], lo[j]], sides as u32 + 1, [Vec2::ZERO; 3]);
    }
    f.build(0.0)
}

/// What exporters leave in a primitive: every seventh triangle repeating a vertex, two
/// triangles of no area between distinct vertices (a vertex copied to where another is), one
/// triangle written twice, and three vertices no triangle uses.
fn leave_debris(mesh: &mut SkinnedMesh) {
    let triangles = mesh.triangle_count();
    for t in (0..triangles).step_by(7) {
        let i = 3 * t;
        mesh.indices[i + 1] = mesh.indices[i];
    }
    let (a, b) = (mesh.indices[3], mesh.indices[4]);
    for _ in 0..2 {
        let copy = mesh.copy_vertex_from(&mesh.clone(), a as usize);
        mesh.indices.extend_from_slice(&[a, copy, b]);
    }
    let first: Vec<u32> = mesh.indices[6..9].to_vec();
    mesh.indices.extend_from_slice(&first);
    for k in 0..3 {
        let v = mesh.copy_vertex_from(&mesh.clone(), k);
        mesh.positions[v as usize] += Vec3::new(0.3, 0.0, 0.0);
    }
}

/// The robot's joints: the rig, and the bones the parts, skins and clip refer to by name.
struct Bones {
    rig: Rig,
    root: usize,
    pelvis: usize,
    spine: usize,
    chest: usize,
    neck: usize,
    head: usize,
    /// Shoulder, elbow and wrist, left then right.
    arms: [[usize; 3]; 2],
    /// Hip, knee and ankle, left then right.
    legs: [[usize; 3]; 2],
}

/// The 18 joints: the spine up to the head, then each side's arm and leg (left first), in the
/// order that gives the bones the indices the file's first nodes have.
fn skeleton() -> Bones {
    let mut r = Rig::default();
    let root = r.bone("root", None, Vec3::ZERO);
    let pelvis = r.bone("pelvis", Some(root), Vec3::new(0.0, 0.95, 0.0));
    let spine = r.bone("spine", Some(pelvis), Vec3::new(0.0, 1.1, 0.0));
    let chest = r.bone("chest", Some(spine), Vec3::new(0.0, 1.28, 0.0));
    let neck = r.bone("neck", Some(chest), Vec3::new(0.0, 1.5, 0.0));
    let head = r.bone("head", Some(neck), Vec3::new(0.0, 1.58, 0.0));
    let mut arms = [[0usize; 3]; 2];
    let mut legs = [[0usize; 3]; 2];
    for (i, (side, x)) in [("l", 1.0f32), ("r", -1.0)].into_iter().enumerate() {
        let s = r.bone(
            &format!("shoulder_{side}"),
            Some(chest),
            Vec3::new(0.26 * x, 1.42, 0.0),
        );
        let e = r.bone(
            &format!("elbow_{side}"),
            Some(s),
            Vec3::new(0.29 * x, 1.14, 0.0),
        );
        let w = r.bone(
            &format!("wrist_{side}"),
            Some(e),
            Vec3::new(0.3 * x, 0.9, 0.0),
        );
        arms[i] = [s, e, w];
        let h = r.bone(
            &format!("hip_{side}"),
            Some(pelvis),
            Vec3::new(0.11 * x, 0.9, 0.0),
        );
        let k = r.bone(
            &format!("knee_{side}"),
            Some(h),
            Vec3::new(0.11 * x, 0.5, 0.0),
        );
        let a = r.bone(
            &format!("ankle_{side}"),
            Some(k),
            Vec3::new(0.11 * x, 0.1, 0.0),
        );
        legs[i] = [h, k, a];
    }
    Bones {
        rig: r,
        root,
        pelvis,
        spine,
        chest,
        neck,
        head,
        arms,
        legs,
    }
}

/// The four skins' joint lists (torso, left arm, right arm, legs), each in an order of its own
/// rather than the rig's, as kit-bashed files have them.
fn skins(b: &Bones) -> Vec<Vec<usize>> {
    let (arms, legs) = (b.arms, b.legs);
    // Skins: the torso's, each arm's (with the chest it hangs from), the legs' (with the
    // pelvis), each listing its joints in an order of its own.
    vec![
        vec![b.head, b.neck, b.chest, b.spine, b.pelvis, b.root],
        vec![b.chest, arms[0][0], arms[0][1], arms[0][2]],
        vec![arms[1][2], arms[1][1], arms[1][0], b.chest],
        vec![
            b.pelvis, legs[1][0], legs[1][1], legs[1][2], legs[0][0], legs[0][1], legs[0][2],
        ],
    ]
}

/// The torso mesh's seven parts, in primitive order: pelvis, spine, chest, neck, head, visor
/// (the sixth, which the morph target moves) and antenna.
fn torso_parts(b: &Bones) -> Vec<Part> {
    let (pelvis, spine, chest, neck, head) = (b.pelvis, b.spine, b.chest, b.neck, b.head);
    let id = Quat::IDENTITY;
    vec![
        Part {
            mesh: cuboid(
                Vec3::new(0.0, 0.97, 0.0),
                Vec3::new(0.17, 0.08, 0.11),
                id,
                pelvis,
            ),
            material: METAL,
            skin: 0,
        },
        Part {
            mesh: cylinder(
                Vec3::new(0.0, 1.04, 0.0),
                Vec3::new(0.0, 1.2, 0.0),
                0.1,
                10,
                spine,
            ),
            material: JOINT,
            skin: 0,
        },
        Part {
            mesh: cuboid(
                Vec3::new(0.0, 1.33, 0.0),
                Vec3::new(0.21, 0.15, 0.13),
                id,
                chest,
            ),
            material: PAINT,
            skin: 0,
        },
        Part {
            mesh: cylinder(
                Vec3::new(0.0, 1.47, 0.0),
                Vec3::new(0.0, 1.57, 0.0),
                0.045,
                8,
                neck,
            ),
            material: JOINT,
            skin: 0,
        },
        Part {
            mesh: cuboid(
                Vec3::new(0.0, 1.68, 0.0),
                Vec3::new(0.11, 0.1, 0.11),
                id,
                head,
            ),
            material: METAL,
            skin: 0,
        },
        Part {
            mesh: cuboid(
                Vec3::new(0.0, 1.7, 0.115),
                Vec3::new(0.085, 0.035, 0.012),
                Quat::from_rotation_x(0.1),
                head,
            ),
            material: GLASS,
            skin: 0,
        },
        Part {
            mesh: cylinder(
                Vec3::new(0.06, 1.78, 0.0),
                Vec3::new(0.07, 1.92, 0.0),
                0.008,
                6,
                head,
            ),
            material: PAINT,
            skin: 0,
        },
    ]
}

/// Each side's limbs (left, then right), appended to `parts`: upper arm, forearm and hand on
/// the side's arm skin, then thigh, shin and foot on the legs' skin.
fn push_limb_parts(parts: &mut Vec<Part>, b: &Bones) {
    let (r, arms, legs) = (&b.rig, b.arms, b.legs);
    let id = Quat::IDENTITY;
    for (i, x) in [1.0f32, -1.0].into_iter().enumerate() {
        let [s, e, w] = arms[i];
        let skin = 1 + i;
        let (shoulder, elbow, wrist) = (r.heads[s], r.heads[e], r.heads[w]);
        parts.push(Part {
            mesh: cylinder(shoulder, elbow, 0.05, 8, s),
            material: METAL,
            skin,
        });
        parts.push(Part {
            mesh: cuboid(
                (elbow + wrist) * 0.5,
                Vec3::new(0.045, 0.13, 0.045),
                Quat::from_rotation_arc(Vec3::Y, (elbow - wrist).normalize()),
                e,
            ),
            material: PAINT,
            skin,
        });
        parts.push(Part {
            mesh: cuboid(
                wrist + Vec3::new(0.005 * x, -0.07, 0.0),
                Vec3::new(0.03, 0.06, 0.045),
                id,
                w,
            ),
            material: JOINT,
            skin,
        });
        let [h, k, a] = legs[i];
        let (hip, knee, ankle) = (r.heads[h], r.heads[k], r.heads[a]);
        parts.push(Part {
            mesh: cylinder(hip, knee, 0.075, 10, h),
            material: METAL,
            skin: 3,
        });
        parts.push(Part {
            mesh: cuboid((knee + ankle) * 0.5, Vec3::new(0.06, 0.19, 0.06), id, k),
            material: PAINT,
            skin: 3,
        });
        parts.push(Part {
            mesh: cuboid(
                Vec3::new(0.11 * x, 0.045, 0.04),
                Vec3::new(0.055, 0.045, 0.11),
                id,
                a,
            ),
            material: JOINT,
            skin: 3,
        });
    }
}

/// All 19 parts (torso, then the limbs), with exporters' debris left in two of them.
fn parts(b: &Bones) -> Vec<Part> {
    let mut parts = torso_parts(b);
    push_limb_parts(&mut parts, b);
    // Debris in the chest's and the head's primitives.
    leave_debris(&mut parts[2].mesh);
    leave_debris(&mut parts[4].mesh);
    parts
}

/// One node per bone, as the file's first nodes, each translated from its parent.
fn push_bone_nodes(doc: &mut Document, r: &Rig) {
    // The rig's bones are the file's first nodes, in order, so the clip's channels name them.
    for b in 0..r.len() {
        let parent = r.parents[b];
        let offset = r.heads[b] - parent.map_or(Vec3::ZERO, |p| r.heads[p]);
        doc.node(
            &r.names[b],
            parent,
            Trs {
                translation: offset,
                ..Trs::IDENTITY
            },
        );
    }
}

/// For each skin, a mesh of the parts on it (their bones renumbered as places in the skin's
/// list), the skin itself, and a node carrying both.
fn push_skinned_meshes(doc: &mut Document, r: &Rig, skins: &[Vec<usize>], parts: &[Part]) {
    for (k, joints) in skins.iter().enumerate() {
        let primitives = parts
            .iter()
            .filter(|p| p.skin == k)
            .map(|p| {
                // The part's bone as a place in this skin's list.
                let mut mesh = p.mesh.clone();
                for inf in &mut mesh.influences {
                    inf.bone = joints
                        .iter()
                        .position(|&j| j == inf.bone as usize)
                        .expect("a part's bone is in its skin")
                        as u32;
                }
                DocPrimitive {
                    mesh,
                    material: Some(p.material),
                    targets: Vec::new(),
                }
            })
            .collect();
        let names = ["torso", "arm_l", "arm_r", "legs"];
        doc.meshes.push(DocMesh {
            name: names[k].into(),
            primitives,
        });
        doc.skins.push(DocSkin {
            joints: joints.clone(),
            inverse_bind: joints
                .iter()
                .map(|&j| Mat4::from_translation(-r.heads[j]))
                .collect(),
        });
        let node = doc.node(&format!("robot_{}", names[k]), None, Trs::IDENTITY);
        doc.nodes[node].mesh = Some(k);
        doc.nodes[node].skin = Some(k);
    }
}

/// The torso mesh's morph target: the visor lifts, every other primitive stays put.
fn add_visor_target(doc: &mut Document) {
    // The visor (the torso mesh's sixth primitive) slides up on its morph target; the mesh's
    // other primitives have the target too, as glTF asks, and it leaves them where they are.
    for (i, p) in doc.meshes[0].primitives.iter_mut().enumerate() {
        let lift = if i == 5 { 0.03 } else { 0.0 };
        p.targets = vec![vec![Vec3::new(0.0, lift, 0.0); p.mesh.vertex_count()]];
    }
}

/// The `walk` clip: legs and arms swinging half a cycle apart, the head turning, the root
/// bobbing twice a cycle.
fn walk(b: &Bones) -> Clip {
    let (r, root, head, arms, legs) = (&b.rig, b.root, b.head, b.arms, b.legs);
    bake_clip("walk", 1.2, 1.2, r, root, |ph| {
        let mut pose = Pose::rest(r.len());
        for i in 0..2 {
            let q = (ph + 0.5 * i as f32).rem_euclid(1.0);
            let [h, k, a] = legs[i];
            pose.rotate(h, euler(-22.0 * (TAU * q).cos(), 0.0, 0.0));
            pose.rotate(
                k,
                euler(
                    8.0 * bump(q, 0.1, 0.12) + 50.0 * bump(q, 0.72, 0.2),
                    0.0,
                    0.0,
                ),
            );
            pose.rotate(a, euler(-8.0 * bump(q, 0.57, 0.1), 0.0, 0.0));
            let [s, e, _] = arms[i];
            pose.rotate(s, euler(20.0 * (TAU * q).cos(), 0.0, 0.0));
            pose.rotate(e, euler(-20.0 - 15.0 * (TAU * q).cos(), 0.0, 0.0));
        }
        pose.rotate(head, euler(0.0, 12.0 * (TAU * ph).sin(), 0.0));
        pose.root_offset = Vec3::Y * (0.02 * (2.0 * TAU * ph).cos() - 0.015);
        pose
    })
}

/// The robot's file.
pub fn robot() -> Document {
    let bones = skeleton();
    let skins = skins(&bones);
    let parts = parts(&bones);

    let mut doc = Document {
        generator: "lodlab gen-assets (robot)".into(),
        materials: vec![
            Material::opaque("metal", [0.55, 0.57, 0.6, 1.0], None),
            Material::opaque("joint", [0.08, 0.08, 0.09, 1.0], None),
            Material::opaque("paint", [0.85, 0.38, 0.06, 1.0], None),
            Material::opaque("glass", [0.1, 0.35, 0.6, 1.0], None),
        ],
        ..Default::default()
    };
    push_bone_nodes(&mut doc, &bones.rig);
    push_skinned_meshes(&mut doc, &bones.rig, &skins, &parts);
    add_visor_target(&mut doc);

    doc.clips = vec![walk(&bones)];
    doc
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Influence;

    #[test]
    fn the_robot_has_the_layout_it_stands_for() {
        let doc = robot();
        let primitives: usize = doc.meshes.iter().map(|m| m.primitives.len()).sum();
        assert_eq!(primitives, 19);
        assert_eq!(doc.skins.len(), 4);
        assert_eq!(doc.nodes.iter().filter(|n| n.skin.is_some()).count(), 4);
        let debris: Vec<&SkinnedMesh> = doc
            .meshes
            .iter()
            .flat_map(|m| &m.primitives)
            .map(|p| &p.mesh)
            .filter(|m| {
                m.indices
                    .chunks_exact(3)
                    .any(|t| t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
            })
            .collect();
        assert_eq!(debris.len(), 2);
        for m in debris {
            // The three added vertices, and those only a now degenerate triangle used.
            let mut used = vec![false; m.vertex_count()];
            m.indices.iter().for_each(|&v| used[v as usize] = true);
            assert!(used.iter().filter(|u| !**u).count() >= 3);
            assert!(used[m.vertex_count() - 3..].iter().all(|u| !u));
        }
        // Every vertex on one bone.
        for p in doc.meshes.iter().flat_map(|m| &m.primitives) {
            assert!((0..p.mesh.vertex_count()).all(|v| p.mesh.influences_of(v)
                == [Influence {
                    bone: p.mesh.influences_of(v)[0].bone,
                    weight: 1.0
                }]));
        }
        assert_eq!(doc.meshes[0].primitives[5].targets.len(), 1);
    }
}

//! Valid glTF files of random *structure*, for the fuzzer
//! (`fuzz/fuzz_targets/valid_structure.rs`) and a test that runs every stage on a few hundred.
//! [`super::random`] varies the mesh on a fixed chain of bones; this varies what lies around
//! the mesh, as files from other tools lay it out:
//!
//! - node graphs: joints in any tree, an armature node above them (turned, scaled by 0.01 to
//!   100), plain nodes between joints, scales that are not uniform or that mirror;
//! - skins over any subset of the joints, several per file, bound in the rest pose or in a
//!   pose of their own (inverse bind matrices that are not the rest pose's inverse);
//! - rigid parts: unskinned meshes on a joint or a plain node, and one mesh drawn by several
//!   nodes in several places;
//! - clips of any channels on any nodes: translation, rotation and scale, with step, linear and
//!   cubic-spline keys, one key or several, clips of different lengths;
//! - materials: plain colours, small textures, masked, blended and double-sided ones.
//!
//! Every choice is a byte of the input, and the bytes run out into zeros, so any bytes make a
//! file, the same bytes the same file. Sizes stay small (at most 8 joints, 3 meshes of 2
//! primitives, 24 vertices and 32 triangles a primitive), so that a fuzzer runs import, bake
//! and export on each in milliseconds.

use super::Choices;
use super::file::{DocMesh, DocPrimitive, DocSkin, Document};
use crate::model::{
    AlphaMode, Channel, ChannelTarget, Clip, Influence, Interpolation, Material, Rgba8Image,
    SkinnedMesh, Trs,
};
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};

/// The file `bytes` describe (any bytes make one).
pub fn structure_file(bytes: &[u8]) -> Vec<u8> {
    structure_document(bytes).to_glb()
}

/// The document `bytes` describe.
pub fn structure_document(bytes: &[u8]) -> Document {
    let mut r = Choices::new(bytes);
    let mut doc = Document {
        generator: "lodlab random structure".into(),
        ..Default::default()
    };
    let armature = add_armature(&mut r, &mut doc);
    let joint_nodes = add_joints(&mut r, &mut doc, armature);
    let skins = add_skins(&mut r, &mut doc, &joint_nodes);
    let materials = add_materials(&mut r, &mut doc);
    add_meshes(&mut r, &mut doc, armature, &joint_nodes, skins, materials);
    add_clips(&mut r, &mut doc);
    doc
}

/// The armature node, now and then (else `None`): the root above the joints that exporters
/// turn and scale, so that importers must carry its transform into the skeleton.
fn add_armature(r: &mut Choices, doc: &mut Document) -> Option<usize> {
    // An armature node above the joints, now and then, turned and scaled as exporters leave
    // one (Blender's centimetre armatures scale by 0.01, some by 100).
    r.one_in(2).then(|| {
        let scale = [1.0, 0.01, 100.0, 0.1][r.within(0, 3)];
        let rest = Trs {
            translation: r.vec3(),
            rotation: if r.one_in(2) {
                Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2)
            } else {
                r.rotation()
            },
            scale: Vec3::splat(scale),
        };
        doc.node("armature", None, rest)
    })
}

/// The joints' nodes (1 to 8, returned in joint order): a tree under the armature (or the
/// scene), with plain nodes between some joints and their parents, to test joint hierarchies
/// that are not simple chains.
fn add_joints(r: &mut Choices, doc: &mut Document, armature: Option<usize>) -> Vec<usize> {
    // Joints in a tree, a plain node between a joint and its parent now and then.
    let joints = r.within(1, 8);
    let mut joint_nodes: Vec<usize> = Vec::with_capacity(joints);
    for j in 0..joints {
        let parent = if j == 0 {
            armature
        } else {
            Some(joint_nodes[r.within(0, j - 1)])
        };
        let parent = if j > 0 && r.one_in(5) {
            let rest = Trs {
                translation: r.vec3() * 0.2,
                rotation: r.rotation(),
                scale: Vec3::ONE,
            };
            Some(doc.node(&format!("between{j}"), parent, rest))
        } else {
            parent
        };
        let rest = Trs {
            translation: if j == 0 {
                r.vec3() * 0.1
            } else {
                r.vec3() * 0.5
            },
            rotation: if r.one_in(2) {
                Quat::IDENTITY
            } else {
                r.rotation()
            },
            scale: r.scale(),
        };
        joint_nodes.push(doc.node(&format!("joint{j}"), parent, rest));
    }
    joint_nodes
}

/// One or two skins over subsets of the joints, returning how many; the bind pose is the rest
/// pose or one a little off it, so inverse bind matrices cannot be assumed from the nodes.
fn add_skins(r: &mut Choices, doc: &mut Document, joint_nodes: &[usize]) -> usize {
    let joints = joint_nodes.len();
    let rest_world: Vec<Mat4> = joint_nodes.iter().map(|&n| doc.world(n)).collect();

    // Skins over subsets of the joints (in the joints' order), each bound in the rest pose or
    // in a pose a little off it.
    let skins = r.within(1, 2);
    for _ in 0..skins {
        let mut members: Vec<usize> = (0..joints).filter(|_| !r.one_in(3)).collect();
        if members.is_empty() {
            members.push(r.within(0, joints - 1));
        }
        let off_rest = r.one_in(3);
        let inverse_bind = members
            .iter()
            .map(|&j| {
                let bind = if off_rest {
                    rest_world[j] * Mat4::from_quat(Quat::from_rotation_z(r.signed() * 0.3))
                } else {
                    rest_world[j]
                };
                // Inverted as an affine map: its last row exactly (0, 0, 0, 1), as
                // glTF-Validator asks of an inverse bind matrix.
                Mat4::from(glam::Affine3A::from_mat4(bind).inverse())
            })
            .collect();
        doc.skins.push(DocSkin {
            joints: members.iter().map(|&j| joint_nodes[j]).collect(),
            inverse_bind,
        });
    }
    skins
}

/// Zero to three materials, returning how many: plain or textured colours, masked, blended or
/// double-sided, the kinds of material an importer must carry through.
fn add_materials(r: &mut Choices, doc: &mut Document) -> usize {
    // Materials first, so that primitives can name any of them.
    let materials = r.within(0, 3);
    for m in 0..materials {
        let colour = [
            r.byte() as f32 / 255.0,
            r.byte() as f32 / 255.0,
            r.byte() as f32 / 255.0,
            if r.one_in(3) {
                r.byte() as f32 / 255.0
            } else {
                1.0
            },
        ];
        let texture = r.one_in(3).then(|| {
            let (w, h) = (1u32 << r.within(0, 3), 1u32 << r.within(0, 3));
            let pixels = (0..w * h * 4).map(|_| r.byte()).collect();
            Rgba8Image {
                width: w,
                height: h,
                pixels,
            }
        });
        let mut material = Material::opaque(&format!("material{m}"), colour, texture);
        material.alpha_mode = match r.byte() % 6 {
            0 => AlphaMode::Mask,
            1 => AlphaMode::Blend,
            _ => AlphaMode::Opaque,
        };
        material.alpha_cutoff = 0.1 + 0.8 * (r.byte() as f32 / 255.0);
        material.double_sided = r.one_in(3);
        doc.materials.push(material);
    }
    materials
}

/// One to three meshes of one or two primitives, each with the node(s) that draw it: skinned
/// meshes on a node of their own, rigid parts on a joint, the armature or a second node too.
fn add_meshes(
    r: &mut Choices,
    doc: &mut Document,
    armature: Option<usize>,
    joint_nodes: &[usize],
    skins: usize,
    materials: usize,
) {
    let joints = joint_nodes.len();
    // Meshes: skinned on a skin, or rigid on a joint or a plain node of their own; one drawn
    // by a second node in another place now and then.
    let meshes = r.within(1, 3);
    for k in 0..meshes {
        let skin = (!r.one_in(4)).then(|| r.within(0, skins - 1));
        let mut primitives = Vec::new();
        for _ in 0..r.within(1, 2) {
            let material = (materials > 0 && !r.one_in(4)).then(|| r.within(0, materials - 1));
            let members = skin.map_or(0, |s| doc.skins[s].joints.len());
            // A textured material's primitive has texture coordinates (glTF asks for them).
            let textured = material.is_some_and(|m| doc.materials[m].texture.is_some());
            primitives.push(DocPrimitive {
                mesh: random_primitive(r, members, textured),
                material,
                targets: Vec::new(),
            });
        }
        doc.meshes.push(DocMesh {
            name: format!("mesh{k}"),
            primitives,
        });
        match skin {
            Some(s) => {
                // A skinned mesh's node does not move it (glTF): put it anywhere.
                let node = doc.node(&format!("skinned{k}"), None, Trs::IDENTITY);
                doc.nodes[node].mesh = Some(k);
                doc.nodes[node].skin = Some(s);
            }
            None => {
                let parent = if r.one_in(4) {
                    armature
                } else {
                    Some(joint_nodes[r.within(0, joints - 1)])
                };
                let rest = Trs {
                    translation: r.vec3() * 0.3,
                    rotation: r.rotation(),
                    scale: r.scale(),
                };
                let node = doc.node(&format!("part{k}"), parent, rest);
                doc.nodes[node].mesh = Some(k);
                if r.one_in(3) {
                    let rest = Trs {
                        translation: r.vec3(),
                        ..rest
                    };
                    let again = doc.node(&format!("part{k}again"), parent, rest);
                    doc.nodes[again].mesh = Some(k);
                }
            }
        }
    }
}

/// Zero to two clips of one to four channels on nodes that carry no mesh (joints, plain nodes,
/// the armature), each clip as long as its longest channel.
fn add_clips(r: &mut Choices, doc: &mut Document) {
    // Clips: channels on joints, plain nodes or the armature.
    let animated: Vec<usize> = (0..doc.nodes.len())
        .filter(|&n| doc.nodes[n].mesh.is_none())
        .collect();
    for c in 0..r.within(0, 2) {
        let mut channels: Vec<Channel> = Vec::new();
        for _ in 0..r.within(1, 4) {
            let node = animated[r.within(0, animated.len() - 1)] as u32;
            let target = match r.byte() % 3 {
                0 => ChannelTarget::Translation,
                1 => ChannelTarget::Rotation,
                _ => ChannelTarget::Scale,
            };
            // glTF allows one channel a node and property.
            if channels
                .iter()
                .any(|ch| ch.node == node && ch.target == target)
            {
                continue;
            }
            channels.push(random_channel(
                r,
                node,
                target,
                &doc.nodes[node as usize].rest,
            ));
        }
        let duration = channels
            .iter()
            .filter_map(|ch| ch.times.last().copied())
            .fold(0.0f32, f32::max);
        doc.clips.push(Clip {
            name: format!("clip{c}"),
            duration,
            channels,
            ground_speed: 0.0,
        });
    }
}

/// A primitive of 3 to 24 vertices in a box of 2 m, 1 to 32 triangles among them (any may be
/// degenerate or repeated), weights on `members` joints of its skin (none for a rigid part),
/// texture coordinates where `textured` (or by chance).
fn random_primitive(r: &mut Choices, members: usize, textured: bool) -> SkinnedMesh {
    let n = r.within(3, 24);
    let mut mesh = SkinnedMesh::empty();
    let textured = textured || r.one_in(2);
    for _ in 0..n {
        mesh.positions.push(r.vec3());
        mesh.normals.push(r.vec3().normalize_or(Vec3::Y));
        mesh.uvs.push(if textured {
            // Never exactly zero: a file without texture coordinates has all of them zero.
            Vec2::new(
                (r.byte() as f32 + 0.5) / 256.0,
                (r.byte() as f32 + 0.5) / 256.0,
            )
        } else {
            Vec2::ZERO
        });
        mesh.materials.push(0);
        if members > 0 {
            let count = r.within(1, members.min(5));
            let mut bones: Vec<u32> = (0..count)
                .map(|_| r.within(0, members - 1) as u32)
                .collect();
            bones.sort_unstable();
            bones.dedup();
            let raw: Vec<f32> = bones.iter().map(|_| 1.0 + r.byte() as f32).collect();
            let total: f32 = raw.iter().sum();
            for (&bone, w) in bones.iter().zip(&raw) {
                mesh.influences.push(Influence {
                    bone,
                    weight: w / total,
                });
            }
        }
        mesh.influence_offsets.push(mesh.influences.len() as u32);
    }
    for _ in 0..r.within(1, 32) {
        for _ in 0..3 {
            mesh.indices.push(r.within(0, n - 1) as u32);
        }
    }
    mesh
}

/// A channel of 1 to 5 keys over up to 3 s, near the node's rest value (`rest`).
fn random_channel(r: &mut Choices, node: u32, target: ChannelTarget, rest: &Trs) -> Channel {
    let interpolation = match r.byte() % 4 {
        0 => Interpolation::Step,
        1 => Interpolation::CubicSpline,
        _ => Interpolation::Linear,
    };
    // glTF: a cubic spline has at least two keys.
    let keys = r.within(
        if interpolation == Interpolation::CubicSpline {
            2
        } else {
            1
        },
        5,
    );
    let mut times = Vec::with_capacity(keys);
    let mut t = 0.0;
    for k in 0..keys {
        if k > 0 {
            t += 0.05 + r.byte() as f32 / 255.0 * 0.7;
        }
        times.push(t);
    }
    let mut value = || -> Vec4 {
        match target {
            ChannelTarget::Translation => (rest.translation + r.vec3() * 0.2).extend(0.0),
            ChannelTarget::Rotation => Vec4::from(rest.rotation * r.rotation()),
            ChannelTarget::Scale => (rest.scale * (1.0 + r.vec3() * 0.3)).extend(0.0),
        }
    };
    let values = if interpolation == Interpolation::CubicSpline {
        // In-tangent, value, out-tangent a key; tangents small, zero at the ends' outsides.
        (0..keys)
            .flat_map(|_| {
                let v = value();
                [v * 0.0, v, v * 0.0]
            })
            .collect()
    } else {
        (0..keys).map(|_| value()).collect()
    };
    Channel {
        node,
        target,
        interpolation,
        times,
        values,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn any_bytes_make_a_valid_file_and_the_same_bytes_the_same_file() {
        for seed in 0..200u64 {
            let mut rng = fastrand::Rng::with_seed(seed);
            let bytes: Vec<u8> = (0..rng.usize(0..900)).map(|_| rng.u8(..)).collect();
            let a = structure_file(&bytes);
            assert_eq!(a, structure_file(&bytes));
            assert!(gltf::Gltf::from_slice(&a).is_ok(), "seed {seed}");
        }
        assert!(gltf::Gltf::from_slice(&structure_file(&[])).is_ok());
    }
}

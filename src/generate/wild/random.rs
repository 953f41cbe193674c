//! Valid glTF files of random meshes, for the fuzzer (`fuzz/fuzz_targets/random_mesh.rs`) and
//! a test that runs every command on a few hundred of them. Random bytes make files the
//! importer rejects on their first byte; these pass glTF-Validator and still hold everything odd
//! a valid file may: points on a coarse grid (coincident vertices, triangles of no area, folds),
//! triangles repeating a vertex or another triangle, vertices no triangle uses, a fan of one
//! triangle, several primitives and skins of one to four bones, weights of any spread.

use super::Choices;
use super::file::{DocMesh, DocPrimitive, DocSkin, Document};
use crate::model::{
    Channel, ChannelTarget, Clip, Influence, Interpolation, Material, SkinnedMesh, Trs,
};
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};

/// The file `bytes` describe (any bytes make one).
pub fn random_file(bytes: &[u8]) -> Vec<u8> {
    random_document(bytes).to_glb()
}

/// The document `bytes` describe.
pub fn random_document(bytes: &[u8]) -> Document {
    let mut r = Choices::new(bytes);
    let bones = r.within(1, 4);
    let mut doc = Document {
        generator: "lodlab random mesh".into(),
        ..Default::default()
    };
    // A chain of bones up y.
    let mut parent = None;
    for b in 0..bones {
        let node = doc.node(
            &format!("bone{b}"),
            parent,
            Trs {
                translation: Vec3::new(0.0, if b == 0 { 0.0 } else { 0.5 }, 0.0),
                ..Trs::IDENTITY
            },
        );
        parent = Some(node);
    }
    let inverse_bind: Vec<Mat4> = (0..bones)
        .map(|b| Mat4::from_translation(Vec3::new(0.0, -0.5 * b as f32, 0.0)))
        .collect();
    let primitives = r.within(1, 3);
    let coloured = r.byte().is_multiple_of(2);
    for k in 0..primitives {
        let n = r.within(3, 48);
        let textured = r.byte().is_multiple_of(3);
        let mut mesh = SkinnedMesh::empty();
        for _ in 0..n {
            let p = Vec3::new(r.coordinate(), r.coordinate(), r.coordinate());
            mesh.positions.push(p);
            // Normals as a file may give them: any direction, zero length now and then.
            let q = Vec3::new(r.coordinate(), r.coordinate(), r.coordinate());
            mesh.normals.push(q.normalize_or_zero());
            mesh.uvs.push(if textured {
                Vec2::new(r.byte() as f32 / 255.0, r.byte() as f32 / 255.0)
            } else {
                Vec2::ZERO
            });
            mesh.materials.push(0);
            let first = r.within(0, bones - 1) as u32;
            let second = r.within(0, bones - 1) as u32;
            let w = r.byte() as f32 / 255.0;
            if second == first || w == 0.0 {
                mesh.influences.push(Influence {
                    bone: first,
                    weight: 1.0,
                });
            } else {
                let (a, b) = if first < second {
                    (first, second)
                } else {
                    (second, first)
                };
                mesh.influences.push(Influence {
                    bone: a,
                    weight: 1.0 - w * 0.5,
                });
                mesh.influences.push(Influence {
                    bone: b,
                    weight: w * 0.5,
                });
            }
            mesh.influence_offsets.push(mesh.influences.len() as u32);
        }
        let triangles = r.within(1, 64);
        for _ in 0..triangles {
            for _ in 0..3 {
                mesh.indices.push(r.within(0, n - 1) as u32);
            }
        }
        let material = coloured.then(|| {
            doc.materials.push(Material::opaque(
                &format!("colour{k}"),
                [
                    r.byte() as f32 / 255.0,
                    r.byte() as f32 / 255.0,
                    r.byte() as f32 / 255.0,
                    1.0,
                ],
                None,
            ));
            doc.materials.len() - 1
        });
        // A primitive bound to a skin of its own, or to the first.
        let skin = if k > 0 && r.byte().is_multiple_of(2) {
            k
        } else {
            0
        };
        if skin >= doc.skins.len() {
            doc.skins.push(DocSkin {
                joints: (0..bones).collect(),
                inverse_bind: inverse_bind.clone(),
            });
        }
        let skin = skin.min(doc.skins.len() - 1);
        doc.meshes.push(DocMesh {
            name: format!("mesh{k}"),
            primitives: vec![DocPrimitive {
                mesh,
                material,
                targets: Vec::new(),
            }],
        });
        let node = doc.node(&format!("part{k}"), None, Trs::IDENTITY);
        doc.nodes[node].mesh = Some(doc.meshes.len() - 1);
        doc.nodes[node].skin = Some(skin);
    }
    // A clip that bends the chain, or none.
    if r.byte().is_multiple_of(2) {
        let angle = r.coordinate();
        let times = vec![0.0, 0.5, 1.0];
        let bend = Quat::from_rotation_z(angle);
        doc.clips.push(Clip {
            name: "bend".into(),
            duration: 1.0,
            channels: vec![Channel {
                node: (bones - 1) as u32,
                target: ChannelTarget::Rotation,
                interpolation: Interpolation::Linear,
                times,
                values: vec![Vec4::W, Vec4::from(bend), Vec4::W],
            }],
            ground_speed: 0.0,
        });
    }
    doc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn any_bytes_make_a_file_and_the_same_bytes_the_same_file() {
        for seed in 0..50u64 {
            let mut rng = fastrand::Rng::with_seed(seed);
            let bytes: Vec<u8> = (0..rng.usize(0..600)).map(|_| rng.u8(..)).collect();
            let a = random_file(&bytes);
            assert_eq!(a, random_file(&bytes));
            assert!(gltf::Gltf::from_slice(&a).is_ok(), "seed {seed}");
        }
        // No bytes at all: a single degenerate triangle of one bone.
        assert!(gltf::Gltf::from_slice(&random_file(&[])).is_ok());
    }
}

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
    let inverse_bind = add_chain(&mut doc, bones);
    let primitives = r.within(1, 3);
    let coloured = r.byte().is_multiple_of(2);
    for k in 0..primitives {
        let mesh = random_mesh(&mut r, bones);
        add_part(&mut r, &mut doc, k, mesh, coloured, &inverse_bind);
    }
    add_bend_clip(&mut r, &mut doc, bones);
    doc
}

/// The skeleton: a chain of `bones` nodes up y, half a metre apart, as the file's first nodes;
/// returns their inverse bind matrices (the rest pose's), for every skin over the chain.
fn add_chain(doc: &mut Document, bones: usize) -> Vec<Mat4> {
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
    (0..bones)
        .map(|b| Mat4::from_translation(Vec3::new(0.0, -0.5 * b as f32, 0.0)))
        .collect()
}

/// A primitive's mesh: 3 to 48 vertices on a coarse grid (so they coincide and fold), normals
/// of any length, texture coordinates now and then, one or two bones a vertex, then 1 to 64
/// triangles among the vertices (any may repeat a vertex or another triangle).
fn random_mesh(r: &mut Choices, bones: usize) -> SkinnedMesh {
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
    mesh
}

/// Part `k`: `mesh` as a mesh of one primitive, with a plain colour of its own when the file
/// is `coloured`, bound to a skin of its own over the whole chain (whose inverse bind matrices
/// are `inverse_bind`) or to the first, on a node of its own.
fn add_part(
    r: &mut Choices,
    doc: &mut Document,
    k: usize,
    mesh: SkinnedMesh,
    coloured: bool,
    inverse_bind: &[Mat4],
) {
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
            joints: (0..inverse_bind.len()).collect(),
            inverse_bind: inverse_bind.to_vec(),
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

/// Now and then a clip, `bend`, that turns the chain's last bone about z and back, so that
/// the file has an animation for the commands that play one.
fn add_bend_clip(r: &mut Choices, doc: &mut Document, bones: usize) {
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

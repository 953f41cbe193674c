//! "knight": the armour's knight as a kit-bashing tool exports it. Every smoothing group of
//! every part, in bands a few centimetres high, is a material of its own, a plain colour and no
//! texture, written as a primitive of its own: several hundred materials, more than there may
//! be texture layers. Two parts carry no skin: a spear on a node under the right hand's joint,
//! and a cape on a node beside the skeleton's root, under the armature node above both. One
//! clip, `walk`.
//!
//! Metres, facing +z, standing on y = 0, left side at +x.

use super::file::{DocMesh, DocPrimitive, DocSkin, Document};
use crate::generate::armour::knight as knight_parts;
use crate::generate::facets::FacetBuilder;
use crate::model::{Material, SkinnedMesh, Trs};
use glam::{Mat4, Quat, Vec2, Vec3};
use std::collections::BTreeMap;
use std::f32::consts::TAU;

/// Height of one band of a part that is a material of its own.
const BAND: f32 = 0.03;

/// `mesh` split into one mesh per material (its own vertices, in order), by material.
fn by_material(mesh: &SkinnedMesh) -> Vec<(u16, SkinnedMesh)> {
    let mut materials: Vec<u16> = mesh.materials.clone();
    materials.sort_unstable();
    materials.dedup();
    materials
        .into_iter()
        .map(|m| {
            let mut part = SkinnedMesh::empty();
            part.copy_triangles_from(mesh, |t| mesh.materials[t[0] as usize] == m);
            part.materials.iter_mut().for_each(|x| *x = 0);
            (m, part)
        })
        .filter(|(_, p)| p.triangle_count() > 0)
        .collect()
}

/// An unskinned part (no influences) from a facet builder's triangles.
fn unskinned(b: &FacetBuilder) -> SkinnedMesh {
    let mut mesh = b.build(0.0);
    mesh.influences.clear();
    mesh.influence_offsets = vec![0; mesh.vertex_count() + 1];
    mesh
}

/// A faceted cylinder along y from `y0` to `y1` of radius `r` (to `r1` at the top), capped.
fn shaft(b: &mut FacetBuilder, y0: f32, y1: f32, r: f32, r1: f32, sides: usize) {
    let w = vec![(0u32, 1.0f32)];
    let ring = |b: &mut FacetBuilder, y: f32, r: f32| -> Vec<u32> {
        (0..sides)
            .map(|j| {
                let t = TAU * j as f32 / sides as f32;
                b.point(Vec3::new(r * t.cos(), y, -r * t.sin()), w.clone())
            })
            .collect()
    };
    let (lo, hi) = (ring(b, y0, r), ring(b, y1, r1.max(1e-4)));
    let (c0, c1) = (
        b.point(Vec3::new(0.0, y0, 0.0), w.clone()),
        b.point(Vec3::new(0.0, y1, 0.0), w.clone()),
    );
    for j in 0..sides {
        let j1 = (j + 1) % sides;
        b.quad([lo[j], lo[j1], hi[j1], hi[j]], 0, [Vec2::ZERO; 4]);
        b.triangle([c1, hi[j], hi[j1]], 1, [Vec2::ZERO; 3]);
        b.triangle([c0, lo[j1], lo[j]], 2, [Vec2::ZERO; 3]);
    }
}

/// The spear, in its node's frame: a shaft through the hand and a blade at its top.
fn spear() -> SkinnedMesh {
    let mut b = FacetBuilder::default();
    shaft(&mut b, -0.75, 0.95, 0.012, 0.012, 8);
    shaft(&mut b, 0.95, 1.13, 0.025, 0.0, 4);
    unskinned(&b)
}

/// The cape, in its node's frame: a curved sheet with a little thickness, hanging from the
/// shoulders behind the back.
fn cape() -> SkinnedMesh {
    let mut b = FacetBuilder::default();
    let (columns, rows) = (10, 8);
    let w = vec![(0u32, 1.0f32)];
    let sheet = |b: &mut FacetBuilder, depth: f32| -> Vec<Vec<u32>> {
        (0..=rows)
            .map(|i| {
                let v = i as f32 / rows as f32;
                (0..=columns)
                    .map(|j| {
                        let u = j as f32 / columns as f32 - 0.5;
                        let spread = 0.22 + 0.12 * v;
                        let x = 2.0 * u * spread;
                        let z = -0.03 * (1.0 - (2.0 * u).powi(2)) - 0.1 * v - depth;
                        b.point(Vec3::new(x, -0.95 * v, z), w.clone())
                    })
                    .collect()
            })
            .collect()
    };
    let (back, front) = (sheet(&mut b, 0.012), sheet(&mut b, 0.0));
    for i in 0..rows {
        for j in 0..columns {
            b.quad(
                [
                    back[i][j],
                    back[i + 1][j],
                    back[i + 1][j + 1],
                    back[i][j + 1],
                ],
                0,
                [Vec2::ZERO; 4],
            );
            b.quad(
                [
                    front[i][j],
                    front[i][j + 1],
                    front[i + 1][j + 1],
                    front[i + 1][j],
                ],
                1,
                [Vec2::ZERO; 4],
            );
        }
    }
    // The rim closes the sheet.
    let last = |s: &Vec<Vec<u32>>, i: usize, j: usize| s[i][j];
    for j in 0..columns {
        b.quad(
            [
                last(&back, 0, j),
                last(&back, 0, j + 1),
                last(&front, 0, j + 1),
                last(&front, 0, j),
            ],
            2,
            [Vec2::ZERO; 4],
        );
        b.quad(
            [
                last(&front, rows, j),
                last(&front, rows, j + 1),
                last(&back, rows, j + 1),
                last(&back, rows, j),
            ],
            2,
            [Vec2::ZERO; 4],
        );
    }
    for i in 0..rows {
        for (j, flip) in [(0usize, false), (columns, true)] {
            let q = [back[i][j], front[i][j], front[i + 1][j], back[i + 1][j]];
            let q = if flip { [q[0], q[3], q[2], q[1]] } else { q };
            b.quad(q, 3, [Vec2::ZERO; 4]);
        }
    }
    unskinned(&b)
}

/// The knight's file.
pub fn knight() -> Document {
    let k = knight_parts(1.0);
    // One material per (smoothing group, band): the part a kit-bashing tool gives a colour.
    let mut slot: BTreeMap<(u32, i32), u16> = BTreeMap::new();
    let facets = k.parts.triangle_count();
    let mut keys = Vec::with_capacity(facets);
    for i in 0..facets {
        let band = (k.parts.facet_centre(i).y / BAND).floor() as i32;
        keys.push(band);
    }
    let mesh = k.parts.build_coloured(0.0, |group, i| {
        let n = slot.len() as u16;
        *slot.entry((group, keys[i])).or_insert(n)
    });
    let mut rng = fastrand::Rng::with_seed(0x6b6e);
    let mut materials: Vec<Material> = (0..slot.len())
        .map(|m| {
            // Steel greys with a tint, every seventh a gilded trim.
            let base = if m % 7 == 3 {
                [0.75, 0.55, 0.18]
            } else {
                [0.58, 0.6, 0.64]
            };
            let c = base.map(|x| (x + (rng.f32() - 0.5) * 0.12).clamp(0.0, 1.0));
            Material::opaque(&format!("Material.{m:03}"), [c[0], c[1], c[2], 1.0], None)
        })
        .collect();
    let wood = materials.len();
    materials.push(Material::opaque("spear", [0.36, 0.22, 0.1, 1.0], None));
    let cloth = materials.len();
    materials.push(Material::opaque("cape", [0.55, 0.05, 0.06, 1.0], None));

    let mut doc = Document {
        generator: "lodlab gen-assets (knight)".into(),
        materials,
        ..Default::default()
    };
    let armature = doc.node("Armature", None, Trs::IDENTITY);
    let r = &k.rig;
    for b in 0..r.len() {
        let parent = r.parents[b];
        let offset = r.heads[b] - parent.map_or(Vec3::ZERO, |p| r.heads[p]);
        doc.node(
            &r.names[b],
            Some(parent.map_or(armature, |p| p + 1)),
            Trs {
                translation: offset,
                ..Trs::IDENTITY
            },
        );
    }
    doc.meshes.push(DocMesh {
        name: "Knight".into(),
        primitives: by_material(&mesh)
            .into_iter()
            .map(|(m, part)| DocPrimitive {
                mesh: part,
                material: Some(m as usize),
                targets: Vec::new(),
            })
            .collect(),
    });
    doc.skins.push(DocSkin {
        joints: (1..=r.len()).collect(),
        inverse_bind: r
            .heads
            .iter()
            .map(|h| Mat4::from_translation(-*h))
            .collect(),
    });
    let body = doc.node("Knight", None, Trs::IDENTITY);
    doc.nodes[body].mesh = Some(0);
    doc.nodes[body].skin = Some(0);
    for (name, parent, at, turn, mesh, material) in [
        (
            "Spear",
            k.hand_r + 1,
            Vec3::new(0.0, -0.07, 0.0),
            Quat::from_rotation_x(0.25),
            spear(),
            wood,
        ),
        (
            "Cape",
            armature,
            r.heads[k.chest] + Vec3::new(0.0, 0.17, -0.13),
            Quat::IDENTITY,
            cape(),
            cloth,
        ),
    ] {
        doc.meshes.push(DocMesh {
            name: name.into(),
            primitives: vec![DocPrimitive {
                mesh,
                material: Some(material),
                targets: Vec::new(),
            }],
        });
        let node = doc.node(
            name,
            Some(parent),
            Trs {
                translation: at,
                rotation: turn,
                scale: Vec3::ONE,
            },
        );
        doc.nodes[node].mesh = Some(doc.meshes.len() - 1);
    }
    let mut walk = k.walk.clone();
    for ch in &mut walk.channels {
        ch.node += 1;
    }
    doc.clips = vec![walk];
    doc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_knight_is_coloured_by_hundreds_of_plain_materials() {
        let doc = knight();
        assert!(
            doc.materials.len() > 300,
            "{} materials",
            doc.materials.len()
        );
        assert!(doc.materials.iter().all(|m| m.texture.is_none()));
        assert_eq!(doc.meshes[0].primitives.len(), doc.materials.len() - 2);
        // The props carry no skin: one under a joint, one beside the skeleton's root.
        let props: Vec<_> = doc
            .nodes
            .iter()
            .filter(|n| n.mesh.is_some() && n.skin.is_none())
            .collect();
        assert_eq!(props.len(), 2);
        assert!(props.iter().all(|p| p.parent.is_some()));
    }
}

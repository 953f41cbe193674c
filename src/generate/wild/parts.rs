//! A character exported as one mesh and one skin per part, every skin over the same joints:
//! how exporters write a character made of several objects (one skin a mesh), and what a
//! character from an asset store often is (a body, its clothes, its sword). With its parts in
//! spaces of their own, each part's vertices are moved by a transform of its own and its
//! skin's inverse bind matrices bring them back, as a sword bound in its hand's space is.

use super::file::{DocMesh, DocPrimitive, DocSkin, Document};
use crate::model::{Model, SkinnedMesh, Trs};
use glam::{Mat4, Quat, Vec3};

/// `model` (its skeleton, clips and materials) as a file of `parts` meshes, each with a skin
/// of its own listing every joint: the triangles in `parts` runs, each run a mesh of one
/// primitive a material. `own_spaces`: part k's vertices lie in a space of their own (moved,
/// turned and scaled by a transform `T_k`), its skin's inverse bind matrices `IBM_j · T_k`
/// undoing it, so that every part is skinned where the model's would be.
pub fn parts_on_one_skeleton(model: &Model, parts: usize, own_spaces: bool) -> Document {
    let parts = parts.clamp(1, model.mesh.triangle_count().max(1));
    let mut doc = Document {
        generator: format!("lodlab parts_on_one_skeleton ({parts} skins)"),
        materials: model.materials.clone(),
        clips: model.clips.clone(),
        ..Default::default()
    };
    // The skeleton's nodes, in order: clips' channels name them by these indices.
    for n in &model.skeleton.nodes {
        doc.node(&n.name, n.parent.map(|p| p as usize), n.rest);
    }
    let joints: Vec<usize> = model.skeleton.joints.iter().map(|&j| j as usize).collect();
    let triangles = model.mesh.triangle_count();
    for k in 0..parts {
        let run = (k * triangles / parts)..((k + 1) * triangles / parts);
        let space = if own_spaces {
            part_space(k)
        } else {
            Mat4::IDENTITY
        };
        // The model with this run's triangles only (its vertices all kept, for now).
        let src = SkinnedMesh {
            indices: model.mesh.indices[3 * run.start..3 * run.end].to_vec(),
            ..model.mesh.clone()
        };
        let primitives = (0..model.materials.len().max(1))
            .filter_map(|m| {
                let mut mesh = SkinnedMesh::empty();
                mesh.copy_triangles_from(&src, |t| src.materials[t[0] as usize] as usize == m);
                if mesh.indices.is_empty() {
                    return None;
                }
                into_space(&mut mesh, space.inverse());
                Some(DocPrimitive {
                    mesh,
                    material: (!model.materials.is_empty()).then_some(m),
                    targets: Vec::new(),
                })
            })
            .collect();
        doc.meshes.push(DocMesh {
            name: format!("part{k}"),
            primitives,
        });
        doc.skins.push(DocSkin {
            joints: joints.clone(),
            inverse_bind: model
                .skeleton
                .inverse_bind
                .iter()
                .map(|ibm| *ibm * space)
                .collect(),
        });
        let node = doc.node(&format!("{}_part{k}", model.name), None, Trs::IDENTITY);
        doc.nodes[node].mesh = Some(k);
        doc.nodes[node].skin = Some(k);
    }
    doc
}

/// Part k's own space: moved, turned about a tilted axis and scaled, differently a part.
fn part_space(k: usize) -> Mat4 {
    let k = k as f32;
    Mat4::from_scale_rotation_translation(
        Vec3::splat(1.0 + 0.25 * k),
        Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.4 * (k + 1.0)),
        Vec3::new(0.3 * k, -0.2 * k, 0.1),
    )
}

/// Moves a mesh's vertices by `m`: positions and normals.
fn into_space(mesh: &mut SkinnedMesh, m: Mat4) {
    let normals = glam::Mat3::from_mat4(m).inverse().transpose();
    for p in &mut mesh.positions {
        *p = m.transform_point3(*p);
    }
    for n in &mut mesh.normals {
        *n = (normals * *n).normalize_or(Vec3::Y);
    }
}

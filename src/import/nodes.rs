//! A glTF file's node graph: the hierarchy above a skin's joints, the inverse bind matrices,
//! where meshes stand in the scene, and the character brought into its bind space, upright and
//! of a plausible size.

use crate::model::{Bounds, Node, Skeleton, SkinnedMesh, Trs};
use glam::{Affine3A, Mat4, Quat, Vec3};

/// Models whose rest pose is taller than this, or shorter than [`MIN_PLAUSIBLE_HEIGHT`], are in
/// units other than metres (centimetres, say) and get scaled to [`DEFAULT_HEIGHT`]. Tall trees
/// are metric up to 40 m.
pub(crate) const MAX_PLAUSIBLE_HEIGHT: f32 = 40.0;
pub(crate) const MIN_PLAUSIBLE_HEIGHT: f32 = 0.1;
pub(crate) const DEFAULT_HEIGHT: f32 = 1.0;

/// The skeleton's nodes: the joints and all their ancestors, parents first, with their rest
/// transforms; and every glTF node's index among them (`u32::MAX` for the others). A rotation
/// that is not a unit quaternion (glTF asks for one) is normalised, with a line in `warnings`.
pub(crate) fn read_hierarchy(
    doc: &gltf::Document,
    joints: &[usize],
    warnings: &mut Vec<String>,
) -> Result<(Vec<Node>, Vec<u32>), String> {
    let node_count = doc.nodes().len();
    let mut parent = vec![None; node_count];
    for n in doc.nodes() {
        for c in n.children() {
            if parent[c.index()].is_some() {
                return Err(format!("node {} has two parents", c.index()));
            }
            parent[c.index()] = Some(n.index());
        }
    }
    // The joints and their ancestors; a walk up stops at a node already kept, so this is
    // linear in the nodes (the validator has ruled out cycles).
    let mut keep = vec![false; node_count];
    for &j in joints {
        let mut n = Some(j);
        while let Some(i) = n.filter(|&i| !keep[i]) {
            keep[i] = true;
            n = parent[i];
        }
    }
    // Depths, each from its parent's: parents first by walking down from the roots.
    let mut depth = vec![0usize; node_count];
    let mut stack: Vec<usize> = (0..node_count)
        .filter(|&i| keep[i] && parent[i].is_none())
        .collect();
    let gltf_nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut order: Vec<(usize, usize)> = Vec::new();
    while let Some(i) = stack.pop() {
        order.push((depth[i], i));
        for c in gltf_nodes[i].children() {
            if keep[c.index()] {
                depth[c.index()] = depth[i] + 1;
                stack.push(c.index());
            }
        }
    }
    order.sort();
    let mut remap = vec![u32::MAX; node_count];
    for (new, &(_, old)) in order.iter().enumerate() {
        remap[old] = new as u32;
    }
    let mut nodes = Vec::with_capacity(order.len());
    for &(_, old) in &order {
        let n = &gltf_nodes[old];
        match n.transform() {
            gltf::scene::Transform::Matrix { matrix } => {
                let m = Mat4::from_cols_array_2d(&matrix);
                if m.is_finite() && !crate::model::keeps_every_direction(&m) {
                    return Err(format!(
                        "node {old} has a singular matrix (it squashes space flat)"
                    ));
                }
            }
            gltf::scene::Transform::Decomposed { rotation, .. } => {
                if rotation.iter().all(|&c| c == 0.0) {
                    return Err(format!(
                        "node {old} has a rotation of length zero (not a quaternion)"
                    ));
                }
                let length = Quat::from_array(rotation).length();
                // glTF's validator allows a rounding error of about 5·10⁻⁴ in the length.
                if length.is_finite() && (length - 1.0).abs() > 1e-3 {
                    warnings.push(format!(
                        "node {old}'s rotation is a quaternion of length {length:.3}, not 1 as \
                         glTF asks; read as the rotation it stands for (normalised)"
                    ));
                }
            }
        }
        let (t, r, s) = n.transform().decomposed();
        let rest = Trs {
            translation: Vec3::from(t),
            rotation: Quat::from_array(r).normalize(),
            scale: Vec3::from(s),
        };
        if !(rest.translation.is_finite() && rest.rotation.is_finite() && rest.scale.is_finite()) {
            return Err(format!("node {old} has a non-finite transform"));
        }
        nodes.push(Node {
            name: n
                .name()
                .map(str::to_string)
                .unwrap_or_else(|| format!("node{old}")),
            parent: parent[old].map(|p| remap[p]),
            rest,
        });
    }

    Ok((nodes, remap))
}

/// The skin's inverse bind matrices (identities where the file has none), one per joint, each
/// finite and invertible.
pub(crate) fn read_inverse_bind(
    skin: &gltf::Skin,
    buffers: &[gltf::buffer::Data],
    joints: usize,
) -> Result<Vec<Mat4>, String> {
    let buffer = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
    let inverse_bind: Vec<Mat4> = match skin.reader(buffer).read_inverse_bind_matrices() {
        Some(it) => it.map(|m| Mat4::from_cols_array_2d(&m)).collect(),
        None => vec![Mat4::IDENTITY; joints],
    };
    if inverse_bind.len() < joints {
        return Err(format!(
            "skin {} has {} inverse bind matrices for {} joints",
            skin.index(),
            inverse_bind.len(),
            joints
        ));
    }
    let inverse_bind: Vec<Mat4> = inverse_bind[..joints].to_vec();
    // Judged against the matrix's own scale (see `keeps_every_direction`): gltfpack's
    // quantised skins scale by about 9·10⁻⁵, a determinant of about 10⁻¹².
    if let Some(i) = inverse_bind
        .iter()
        .position(|m| !crate::model::keeps_every_direction(m))
    {
        return Err(format!(
            "inverse bind matrix of joint {i} is not finite or not invertible"
        ));
    }

    Ok(inverse_bind)
}

/// Every node's parent, `None` for roots (the first parent where a file gives two).
pub(crate) fn node_parents(doc: &gltf::Document) -> Vec<Option<usize>> {
    let mut parent = vec![None; doc.nodes().len()];
    for n in doc.nodes() {
        for c in n.children() {
            parent[c.index()].get_or_insert(n.index());
        }
    }
    parent
}

/// Node `n`'s world transform in its rest pose (the validator has ruled out cycles).
pub(crate) fn world_of(doc: &gltf::Document, parents: &[Option<usize>], n: usize) -> Mat4 {
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut world = Mat4::IDENTITY;
    let mut at = Some(n);
    while let Some(i) = at {
        world = Mat4::from_cols_array_2d(&nodes[i].transform().matrix()) * world;
        at = parents[i];
    }
    world
}

/// Every node with a mesh in the scene (the default one, else the first, else every root),
/// with its world transform. Each node is visited once, however the hierarchy loops.
pub(crate) fn mesh_nodes_in_scene(doc: &gltf::Document) -> Vec<(gltf::Node<'_>, Mat4)> {
    let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut child = vec![false; doc.nodes().len()];
            for n in doc.nodes() {
                n.children().for_each(|c| child[c.index()] = true);
            }
            doc.nodes().filter(|n| !child[n.index()]).collect()
        }
    };
    let mut visited = vec![false; doc.nodes().len()];
    let mut stack: Vec<(gltf::Node, Mat4)> =
        roots.into_iter().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut out = Vec::new();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            continue;
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if node.mesh().is_some() {
            out.push((node.clone(), world));
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    out.sort_by_key(|(n, _)| n.index());
    out
}

/// Moves the mesh into the space its bind pose stands in, so that the rest pose is `Ĝ_i =
/// IBM_i⁻¹` (Merry et al. §2.1.1) in the skeleton's space and rest positions are where the
/// skinned character stands. glTF skins a vertex by `G_i · IBM_i · v̂` and leaves the space of
/// `v̂` to the exporter: Blender writes a rig's mesh in its armature's space, which the armature
/// node scales (0.01 from centimetres) and turns (Z up) on its way to the scene, so every joint
/// at rest has `G_i · IBM_i = A`, the armature's transform, and not the identity. Read as they
/// were, such a mesh's rest positions were a hundred times too large and lying down: the
/// rest-pose metric measured centimetres, a level's tolerance came from a height of 180
/// instead of 1.8, and the texture and torn-chart costs (from rest positions) outweighed the
/// L2,2 deviation (from the poses, in metres) a hundredfold. `A` is taken from the joint that
/// carries the most skin weight (where the rest pose is not quite the bind pose, the body's
/// main bone says best where the bound mesh stands); `v̂ ← A v̂` and `IBM_i ← IBM_i A⁻¹` leave
/// every posed vertex where it was.
pub(crate) fn into_bind_space(mesh: &mut SkinnedMesh, skeleton: &mut Skeleton) {
    let mut weight = vec![0.0f64; skeleton.bone_count()];
    for inf in &mesh.influences {
        weight[inf.bone as usize] += inf.weight as f64;
    }
    let Some(main) = (0..weight.len()).max_by(|&a, &b| weight[a].total_cmp(&weight[b])) else {
        return;
    };
    let rest = crate::anim::bone_matrices(skeleton, None, 0.0);
    let a = Mat4::from(rest[main]) * skeleton.inverse_bind[main];
    if a.abs_diff_eq(Mat4::IDENTITY, 1e-6) || !crate::model::keeps_every_direction(&a) {
        return;
    }
    let normal_matrix = glam::Mat3::from_mat4(a).inverse().transpose();
    for p in &mut mesh.positions {
        *p = a.transform_point3(*p);
    }
    for n in &mut mesh.normals {
        *n = (normal_matrix * *n).normalize_or(Vec3::Y);
    }
    let back = a.inverse();
    for ibm in &mut skeleton.inverse_bind {
        *ibm *= back;
    }
    log::info!(
        "the mesh is bound in a space of its own (the armature's, scale {:.3}): moved into \
         the skeleton's",
        Affine3A::from_mat4(a).matrix3.x_axis.length()
    );
}

/// Scene units: metres, standing on the ground, centred. A model of implausible height (in
/// other units) is scaled to a default height; clips' ground speeds follow the scale, and a
/// clip whose file gives none gets a guess from its name.
pub(crate) fn place_in_scene(
    mesh: &SkinnedMesh,
    skeleton: &mut Skeleton,
    clips: &mut [crate::model::Clip],
) -> Result<(), String> {
    let rest = crate::anim::linear_blend_skinning(
        mesh,
        skeleton,
        &crate::anim::bone_matrices(skeleton, None, 0.0),
    );
    let bounds = Bounds::of(rest.iter().copied()).ok_or("the skinned mesh has no vertices")?;
    let height = bounds.size().y.max(bounds.size().x).max(bounds.size().z);
    if !height.is_finite() || height <= 0.0 {
        return Err("the skinned mesh has zero size in its rest pose".into());
    }
    let scale = if (MIN_PLAUSIBLE_HEIGHT..=MAX_PLAUSIBLE_HEIGHT).contains(&bounds.size().y) {
        1.0
    } else {
        DEFAULT_HEIGHT / height
    };
    let anchor = Vec3::new(bounds.center().x, bounds.min.y, bounds.center().z);
    skeleton.root_transform =
        Affine3A::from_translation(-anchor * scale) * Affine3A::from_scale(Vec3::splat(scale));
    let scaled_height = bounds.size().y * scale;
    for clip in clips.iter_mut() {
        if clip.ground_speed < 0.0 {
            clip.ground_speed = guess_ground_speed(&clip.name, scaled_height);
        } else {
            clip.ground_speed *= scale;
        }
    }

    Ok(())
}

/// Travel speed for clips whose file does not say: a guess from the clip's name, in body
/// heights per second. A walk covers about 0.8 heights a second, a run about 2.5.
pub(crate) fn guess_ground_speed(name: &str, height: f32) -> f32 {
    let n = name.to_ascii_lowercase();
    let per_height = if ["gallop", "run", "sprint", "canter"]
        .iter()
        .any(|k| n.contains(k))
    {
        2.5
    } else if n.contains("trot") {
        1.6
    } else if n.contains("walk") {
        0.8
    } else {
        0.0
    };
    per_height * height
}

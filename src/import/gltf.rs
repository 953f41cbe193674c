//! glTF 2.0 import of one skinned character: `.glb`, and `.gltf` with embedded or external
//! buffers.
//!
//! What is read: the first skin that a mesh uses, every primitive of every mesh bound to it (merged
//! into one [`SkinnedMesh`]), all JOINTS_n / WEIGHTS_n sets (so any number of influences per
//! vertex), the node hierarchy above the joints, the inverse bind matrices, every animation clip
//! (translation, rotation and scale; STEP, LINEAR and CUBICSPLINE) and the base colour of each
//! material. Everything the renderer and the bakes rely on is validated here, so that a bad file
//! stops with one line naming the file and the problem instead of a panic further down.

use super::validate;
use crate::error::InputError;
use crate::geometry::weld::{compute_normals, weld_map};
use crate::model::{
    AlphaMode, Bounds, Channel, ChannelTarget, Clip, Influence, Interpolation, Material, Model,
    Node, Rgba8Image, Skeleton, SkinnedMesh, Trs,
};
use glam::{Affine3A, Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::animation::util::ReadOutputs;
use gltf::mesh::Mode;
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::Path;

/// Models whose rest pose is taller than this, or shorter than [`MIN_PLAUSIBLE_HEIGHT`], are in
/// units other than metres (centimetres, say) and get scaled to [`DEFAULT_HEIGHT`]. Tall trees
/// are metric up to 40 m.
const MAX_PLAUSIBLE_HEIGHT: f32 = 40.0;
const MIN_PLAUSIBLE_HEIGHT: f32 = 0.1;
const DEFAULT_HEIGHT: f32 = 1.0;

/// The largest translation or scale a clip's key may hold: 10⁹ is a million kilometres in
/// metres, ten thousand in centimetres.
const MAX_KEY_VALUE: f32 = 1e9;

/// Loads a skinned model from a `.glb` or `.gltf` file.
pub fn load(path: &Path) -> Result<Model, InputError> {
    let fail = |p: String| InputError::new(path, p);
    let limits = validate::limits();
    let meta = std::fs::metadata(path).map_err(|e| fail(io_problem(&e)))?;
    validate::check_file(&meta, &limits).map_err(fail)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let read = std::fs::read(path).map_err(|e| fail(io_problem(&e)))?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "model".into());
    let (model, warnings) = from_bytes(&name, read, base, &limits).map_err(fail)?;
    for w in warnings {
        log::warn!("{}: {w}", path.display());
    }
    Ok(model)
}

/// A model from the bytes of a `.glb` or `.gltf` whose external files lie in `base`, and the
/// warnings to show with it; the error is the problem, without the file's name. What [`load`]
/// runs once it has read the file, and what the fuzzer feeds (see `fuzz/`).
pub fn from_bytes(
    name: &str,
    read: Vec<u8>,
    base: &Path,
    limits: &validate::Limits,
) -> Result<(Model, Vec<String>), String> {
    let (doc, buffers) = read_document(read, base, limits)?;
    let images = super::sources::read_images(&doc, base, &buffers, limits)?;
    let mut warnings = Vec::new();
    let mut model = build(name, &doc, &buffers, &images, &mut warnings)?;
    // The skins' joints were counted before reading; an unskinned part riding on a node of
    // its own makes that node a bone too, and bones are what the animation texture and an
    // export hold.
    let bones = model.skeleton.joints.len();
    if bones > limits.joints {
        return Err(validate::over(
            format!(
                "its skins' joints and the nodes its unskinned parts ride on make {bones} bones"
            ),
            limits.joints,
            "joints",
        ));
    }
    let packed = super::palette::pack_plain_colours(&mut model);
    if packed > 0 {
        log::info!("{packed} plain-coloured materials share one palette texture");
    }
    Ok((model, warnings))
}

/// The document in the bytes of a `.glb` or `.gltf` and its buffers, every check of
/// [`validate`] passed before anything reads an attribute.
fn read_document(
    read: Vec<u8>,
    base: &Path,
    limits: &validate::Limits,
) -> Result<(gltf::Document, Vec<gltf::buffer::Data>), String> {
    validate::check_glb_header(&read)?;
    validate::check_raw(&read)?;
    let bytes = unpacked(&read, base, limits)?.unwrap_or(read);
    let bytes = validate::without_untargeted_channels(&bytes).unwrap_or(bytes);
    let gltf::Gltf {
        document: doc,
        blob,
    } = gltf::Gltf::from_slice(&bytes).map_err(|e| gltf_problem(&e, &bytes))?;
    super::sources::check_uris(&doc, base, limits)?;
    let buffers = super::sources::read_buffers(&doc, base, blob, limits)?;
    validate::check_document(&doc, &buffers, limits)?;
    Ok((doc, buffers))
}

/// Adds the clips of the glTF file `path` to `model`, bound by joint name: what a service
/// that sends a character and its animations as separate files on one skeleton sends (Mixamo
/// does). Every node the file animates must be a node of the model's skeleton of the same
/// name; the error names those that are not. Returns how many clips came.
pub fn add_clips(model: &mut Model, path: &Path) -> Result<usize, InputError> {
    let fail = |p: String| InputError::new(path, p);
    let limits = validate::limits();
    let meta = std::fs::metadata(path).map_err(|e| fail(io_problem(&e)))?;
    validate::check_file(&meta, &limits).map_err(fail)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let read = std::fs::read(path).map_err(|e| fail(io_problem(&e)))?;
    let (doc, buffers) = read_document(read, base, &limits).map_err(fail)?;
    let skeleton = &model.skeleton;
    let mut remap = vec![u32::MAX; doc.nodes().len()];
    for n in doc.nodes() {
        if let Some(i) = n
            .name()
            .and_then(|name| skeleton.nodes.iter().position(|s| s.name == name))
        {
            remap[n.index()] = i as u32;
        }
    }
    let mut unmatched: Vec<String> = Vec::new();
    for anim in doc.animations() {
        for ch in anim.channels() {
            let node = ch.target().node();
            let moves = ch.target().property() != gltf::animation::Property::MorphTargetWeights;
            let name = node
                .name()
                .map_or_else(|| format!("node {}", node.index()), str::to_string);
            if moves && remap[node.index()] == u32::MAX && !unmatched.contains(&name) {
                unmatched.push(name);
            }
        }
    }
    if !unmatched.is_empty() {
        let list = |names: &[String]| {
            let shown: Vec<&str> = names.iter().take(6).map(String::as_str).collect();
            let more = names.len().saturating_sub(shown.len());
            if more > 0 {
                format!("{} and {more} more", shown.join(", "))
            } else {
                shown.join(", ")
            }
        };
        let joints: Vec<String> = model
            .skeleton
            .joints
            .iter()
            .map(|&j| model.skeleton.nodes[j as usize].name.clone())
            .collect();
        return Err(fail(format!(
            "its clips animate {} joint(s) that {} does not have: {} (its joints are {})",
            unmatched.len(),
            model.name,
            list(&unmatched),
            list(&joints)
        )));
    }
    let buffer = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
    let mut clips = Vec::new();
    for anim in doc.animations() {
        if let Some(clip) = read_clip(&anim, buffer, &remap).map_err(fail)? {
            clips.push(clip);
        }
    }
    if clips.is_empty() {
        return Err(fail("has no clips to add".into()));
    }
    // Ground speeds into the model's scene units, as `place_in_scene` does for its own.
    let scale = model.skeleton.root_transform.matrix3.x_axis.length();
    let rest = crate::anim::linear_blend_skinning(
        &model.mesh,
        &model.skeleton,
        &crate::anim::bone_matrices(&model.skeleton, None, 0.0),
    );
    let height = Bounds::of(rest).map_or(1.0, |b| b.size().y);
    for clip in &mut clips {
        if clip.ground_speed < 0.0 {
            clip.ground_speed = guess_ground_speed(&clip.name, height);
        } else {
            clip.ground_speed *= scale;
        }
    }
    let count = clips.len();
    model.clips.extend(clips);
    Ok(count)
}

/// `path` rewritten by [`super::gltfpack::unpack`] where it uses `EXT_meshopt_compression` or
/// `KHR_mesh_quantization` (what gltfpack writes), else `None`: the gltf crate reads it as it is.
fn unpacked(
    bytes: &[u8],
    base: &Path,
    limits: &validate::Limits,
) -> Result<Option<Vec<u8>>, String> {
    // The extensions are named in the JSON: a `.glb`'s first chunk, or the whole `.gltf`.
    let json_part = match bytes.get(12..16) {
        Some(len) if bytes.starts_with(b"glTF") => {
            let n = u32::from_le_bytes([len[0], len[1], len[2], len[3]]) as usize;
            &bytes[20.min(bytes.len())..(20 + n).min(bytes.len())]
        }
        _ => bytes,
    };
    let mentions = |name: &[u8]| json_part.windows(name.len()).any(|w| w == name);
    if !(mentions(b"EXT_meshopt_compression") || mentions(b"KHR_mesh_quantization")) {
        return Ok(None);
    }
    let Ok((json, _)) = super::container::split(bytes) else {
        // Not glTF at all: the gltf crate says what is wrong with it.
        return Ok(None);
    };
    if !super::gltfpack::needs_unpacking(&json) {
        return Ok(None);
    }
    super::gltfpack::unpack(bytes, base, limits).map(Some)
}

fn io_problem(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        std::io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => format!("cannot read: {e}"),
    }
}

/// What is wrong, in one line, where the gltf crate refused `bytes`.
fn gltf_problem(e: &gltf::Error, bytes: &[u8]) -> String {
    match e {
        gltf::Error::Io(io) => format!("cannot read a file it refers to: {}", io_problem(io)),
        // Well-formed JSON that is not what glTF's schema asks (a string where a number
        // goes) is a glTF problem, not a JSON one.
        gltf::Error::Deserialize(d) if well_formed_json(bytes) => {
            format!("invalid glTF (its JSON does not follow the glTF schema: {d})")
        }
        gltf::Error::Deserialize(d) => format!("not a glTF file (invalid JSON: {d})"),
        gltf::Error::Binary(b) => format!("not a valid binary glTF (truncated or corrupt: {b})"),
        gltf::Error::Validation(errors) => {
            let first = errors
                .first()
                .map(|(path, err)| format!("{}: {err}", path))
                .unwrap_or_default();
            format!(
                "invalid glTF ({} problem{}; first: {first})",
                errors.len(),
                if errors.len() == 1 { "" } else { "s" }
            )
        }
        gltf::Error::BufferLength {
            buffer,
            expected,
            actual,
        } => format!("buffer {buffer} is truncated: expected {expected} bytes, found {actual}"),
        gltf::Error::Base64(b) => format!("a data: URI is not valid base64: {b}"),
        gltf::Error::MissingBlob => "refers to a binary chunk that is missing".into(),
        gltf::Error::Image(i) => format!("cannot decode an image: {i}"),
        other => format!("cannot load: {other}"),
    }
}

/// Whether the JSON of a `.gltf`, or of a `.glb`'s first chunk, parses as JSON.
fn well_formed_json(bytes: &[u8]) -> bool {
    let json: std::borrow::Cow<[u8]> = if bytes.starts_with(b"glTF") {
        match gltf::binary::Glb::from_slice(bytes) {
            Ok(glb) => glb.json,
            Err(_) => return false,
        }
    } else {
        bytes.into()
    };
    serde_json::from_slice::<serde_json::Value>(&json).is_ok()
}

/// Per-primitive vertex data before welding.
struct RawPrimitive {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Vec<Vec2>,
    influences: Vec<Vec<Influence>>,
    triangles: Vec<[u32; 3]>,
    indexed: bool,
}

fn build(
    name: &str,
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    images: &[Option<Rgba8Image>],
    warnings: &mut Vec<String>,
) -> Result<Model, String> {
    let buffer = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
    let lower_lods = msft_lod_lower_levels(doc);
    let shown = |n: &gltf::Node| n.mesh().is_some() && !lower_lods.contains(&n.index());
    let skinned: Vec<gltf::Node> = doc
        .nodes()
        .filter(|n| shown(n) && n.skin().is_some())
        .collect();
    if skinned.is_empty() {
        return build_rigid(name, doc, buffers, images, warnings);
    }
    // Every skin a mesh uses, in order of first use, their joints merged into one list of
    // bones: a joint another skin has already, with the same inverse bind matrix, is shared;
    // otherwise it is a bone of its own (bones may share a node).
    let mut skins: Vec<gltf::Skin> = Vec::new();
    for n in &skinned {
        let s = n.skin().expect("filtered on a skin");
        if !skins.iter().any(|k| k.index() == s.index()) {
            skins.push(s);
        }
    }
    let (mut bone_nodes, mut inverse_bind): (Vec<usize>, Vec<Mat4>) = (Vec::new(), Vec::new());
    let mut maps: Vec<Vec<u32>> = Vec::with_capacity(skins.len());
    for skin in &skins {
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        if joints.is_empty() {
            return Err(format!("skin {} has no joints", skin.index()));
        }
        let ibm = read_inverse_bind(skin, buffers, joints.len())?;
        let mut map = Vec::with_capacity(joints.len());
        for (&j, m) in joints.iter().zip(&ibm) {
            let same = |(&n, b): (&usize, &Mat4)| n == j && b.abs_diff_eq(*m, 1e-5);
            let bone = match bone_nodes.iter().zip(&inverse_bind).position(same) {
                Some(i) => i,
                None => {
                    bone_nodes.push(j);
                    inverse_bind.push(*m);
                    bone_nodes.len() - 1
                }
            };
            map.push(bone as u32);
        }
        maps.push(map);
    }
    // Unskinned parts ride rigidly on what carries them in the file: the nearest joint above
    // the node (a helmet on the head bone), else the node itself, which becomes a bone of its
    // own so that whatever animates it or the nodes above it moves the part (a cape on the
    // armature's node beside the skeleton's root, a prop standing in the scene).
    let parents = node_parents(doc);
    let skin_bones = bone_nodes.len();
    let mut props: Vec<(gltf::Node, Mat4, usize)> = Vec::new();
    for (node, world) in mesh_nodes_in_scene(doc) {
        if node.skin().is_some() || lower_lods.contains(&node.index()) {
            continue;
        }
        if !world.is_finite() {
            return Err(format!(
                "mesh node {} has a non-finite transform",
                node.index()
            ));
        }
        // The validator has ruled out cycles, so the walk up ends.
        let mut up = parents[node.index()];
        while let Some(p) = up.filter(|&p| !bone_nodes[..skin_bones].contains(&p)) {
            up = parents[p];
        }
        let carrier = match up {
            Some(joint) => joint,
            None if !crate::model::keeps_every_direction(&world) => {
                warnings.push(format!(
                    "mesh node {} is left out: its transform squashes it flat",
                    node.index()
                ));
                continue;
            }
            None => {
                if !bone_nodes.contains(&node.index()) {
                    bone_nodes.push(node.index());
                    inverse_bind.push(world.inverse());
                }
                node.index()
            }
        };
        props.push((node, world, carrier));
    }
    let (nodes, remap) = read_hierarchy(doc, &bone_nodes)?;
    let mut skeleton = Skeleton {
        nodes,
        joints: bone_nodes.iter().map(|&j| remap[j]).collect(),
        inverse_bind,
        root_transform: Affine3A::IDENTITY,
    };
    let mut bound: Vec<(gltf::Node, Binding)> = skinned
        .iter()
        .map(|n| {
            let s = n.skin().expect("filtered on a skin").index();
            let k = skins
                .iter()
                .position(|x| x.index() == s)
                .expect("collected above");
            (n.clone(), Binding::Skin(&maps[k]))
        })
        .collect();
    for (node, world, carrier) in props {
        // The carrier's first bone (a node may be a bone of two skins).
        let bone = bone_nodes
            .iter()
            .position(|&b| b == carrier)
            .expect("every carrier is a bone");
        // Into the bone's bind space: G_b · IBM_b · v̂ then puts the part where the node
        // carrying it puts it, whatever the bind matrices say.
        let carrier_world = world_of(doc, &parents, carrier);
        let bind = skeleton.inverse_bind[bone].inverse();
        let to_bind = bind * carrier_world.inverse() * world;
        bound.push((node, Binding::Rigid(to_bind, bone as u32)));
    }
    let (mut mesh, materials) = read_meshes(&bound, buffers, images, warnings)?;
    into_bind_space(&mut mesh, &mut skeleton);
    let mut clips = Vec::new();
    for anim in doc.animations() {
        if let Some(clip) = read_clip(&anim, buffer, &remap)? {
            clips.push(clip);
        }
    }
    place_in_scene(&mesh, &mut skeleton, &mut clips)?;
    Ok(Model {
        name: name.to_string(),
        mesh,
        skeleton,
        clips,
        materials,
    })
}

/// A file without a skinned mesh: a static prop. Every mesh of the scene, its node's world
/// transform baked in, becomes one character of one bone (at the origin, weight 1), which
/// simplifies and draws like any other; it has no clips.
fn build_rigid(
    name: &str,
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    images: &[Option<Rgba8Image>],
    warnings: &mut Vec<String>,
) -> Result<Model, String> {
    let lower_lods = msft_lod_lower_levels(doc);
    let bound: Vec<(gltf::Node, Binding)> = mesh_nodes_in_scene(doc)
        .into_iter()
        .filter(|(n, _)| !lower_lods.contains(&n.index()))
        .map(|(n, world)| (n, Binding::Rigid(world, 0)))
        .collect();
    if bound.is_empty() {
        return Err("has no mesh in its scene".into());
    }
    if bound
        .iter()
        .any(|(_, b)| matches!(b, Binding::Rigid(w, _) if !w.is_finite()))
    {
        return Err("a mesh node has a non-finite transform".into());
    }
    let (mesh, materials) = read_meshes(&bound, buffers, images, warnings)?;
    if doc.animations().len() > 0 {
        warnings.push("its animations move nodes of an unskinned mesh: it is drawn still".into());
    }
    let mut skeleton = Skeleton {
        nodes: vec![Node {
            name: "root".into(),
            parent: None,
            rest: Trs::IDENTITY,
        }],
        joints: vec![0],
        inverse_bind: vec![Mat4::IDENTITY],
        root_transform: Affine3A::IDENTITY,
    };
    let mut clips = Vec::new();
    place_in_scene(&mesh, &mut skeleton, &mut clips)?;
    Ok(Model {
        name: name.to_string(),
        mesh,
        skeleton,
        clips,
        materials,
    })
}

/// The skeleton's nodes: the joints and all their ancestors, parents first, with their rest
/// transforms; and every glTF node's index among them (`u32::MAX` for the others).
fn read_hierarchy(doc: &gltf::Document, joints: &[usize]) -> Result<(Vec<Node>, Vec<u32>), String> {
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
fn read_inverse_bind(
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

/// `KHR_texture_transform` baked into texture coordinates: uv′ = T·R·S·uv, T the offset, R
/// the rotation (counter-clockwise, in radians), S the scale, as the extension defines them.
/// gltfpack writes quantised texture coordinates with the transform that maps them back.
fn apply_texture_transform(uvs: &mut [Vec2], offset: [f32; 2], rotation: f32, scale: [f32; 2]) {
    let (sin, cos) = rotation.sin_cos();
    for uv in uvs {
        let (x, y) = (uv.x * scale[0], uv.y * scale[1]);
        *uv = Vec2::new(
            cos * x + sin * y + offset[0],
            -sin * x + cos * y + offset[1],
        );
    }
}

/// The nodes that `MSFT_lod` names as lower levels of detail of another node: a reader takes
/// the highest level only, as one without the extension would (lodlab makes its own levels).
fn msft_lod_lower_levels(doc: &gltf::Document) -> Vec<usize> {
    doc.nodes()
        .filter_map(|n| {
            n.extensions()?
                .get("MSFT_lod")?
                .get("ids")?
                .as_array()
                .cloned()
        })
        .flatten()
        .filter_map(|id| id.as_u64().map(|i| i as usize))
        .collect()
}

/// How the vertices of one mesh node are bound: to the skin whose joints `joints` maps into
/// the model's bones (joint j of the skin is bone `joints[j]`), or rigidly to one bone with a
/// transform baked in: bone 0 and the node's world transform for an unskinned prop; the
/// nearest joint above the node, and the transform into that bone's bind space, for a part
/// hanging from a skeleton (a helmet on the head bone).
enum Binding<'m> {
    Skin(&'m [u32]),
    Rigid(Mat4, u32),
}

impl Binding<'_> {
    /// A key equal for bindings that put a mesh in the same place: the same skin (a skinned
    /// mesh's node transform does not move it), or the same bone and transform.
    fn key(&self) -> BindingKey {
        match self {
            Binding::Skin(map) => BindingKey::Skin(map.as_ptr() as usize),
            Binding::Rigid(m, bone) => {
                BindingKey::Rigid(*bone, m.to_cols_array().map(|x| (x + 0.0).to_bits()))
            }
        }
    }
}

/// A primitive's vertex accessors: each attribute's name and accessor, sorted.
type VertexAccessors = Vec<(String, usize)>;

/// What a primitive draws and where: two equal ones draw the same triangles in one place.
#[derive(PartialEq, Eq, Hash)]
struct DrawnPrimitive {
    attributes: VertexAccessors,
    indices: Option<usize>,
    mode: u32,
    material: Option<usize>,
    place: BindingKey,
}

/// Where a binding puts a primitive, hashable: a skin (by its joint map, which the import
/// holds for as long as the meshes are read), or a bone and a transform.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum BindingKey {
    Skin(usize),
    Rigid(u32, [u32; 16]),
}

/// The meshes of `nodes` (a mesh that two nodes draw in one place once, in two places twice),
/// all their primitives merged into one mesh (normals
/// computed where a primitive has none), and the materials they use. Morph targets are left
/// out with one warning in `warnings`: the base shape is drawn.
fn read_meshes(
    nodes: &[(gltf::Node, Binding)],
    buffers: &[gltf::buffer::Data],
    images: &[Option<Rgba8Image>],
    warnings: &mut Vec<String>,
) -> Result<(SkinnedMesh, Vec<Material>), String> {
    let buffer = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
    let mut material_slots: BTreeMap<Option<usize>, u16> = BTreeMap::new();
    let mut materials: Vec<Material> = Vec::new();
    let mut mesh = SkinnedMesh::default();
    let mut needs_normals: Vec<bool> = Vec::new();
    // Where the vertices of each set of vertex accessors went (and how many), by where they
    // are drawn and in which material.
    let mut vertex_bases: HashMap<(VertexAccessors, BindingKey, u16), (u32, usize)> =
        HashMap::new();
    // Primitives read, by their accessors, mode and material and where they are drawn: one
    // drawn again in the same place (a mesh on a second node of the same skin, or of the same
    // transform; the same primitive listed again, over one accessor, thousands of times)
    // would only repeat every triangle exactly, on top of itself.
    let mut drawn: HashSet<DrawnPrimitive> = HashSet::new();
    let mut repeated = 0usize;
    let mut morphed = 0;
    for (node, binding) in nodes {
        let Some(m) = node.mesh() else { continue };
        for prim in m.primitives() {
            let mut attributes: VertexAccessors = prim
                .attributes()
                .map(|(s, a)| (s.to_string(), a.index()))
                .collect();
            attributes.sort();
            let this = DrawnPrimitive {
                attributes: attributes.clone(),
                indices: prim.indices().map(|a| a.index()),
                mode: prim.mode().as_gl_enum(),
                material: prim.material().index(),
                place: binding.key(),
            };
            if !drawn.insert(this) {
                repeated += 1;
                continue;
            }
            let label = format!("mesh {} primitive {}", m.index(), prim.index());
            if prim.morph_targets().len() > 0 {
                morphed += 1;
            }
            let material = prim.material();
            let slot = match material_slots.get(&material.index()) {
                Some(&s) => s,
                None => {
                    let s = u16::try_from(materials.len())
                        .map_err(|_| "more than 65535 materials".to_string())?;
                    materials.push(convert_material(&material, images)?);
                    material_slots.insert(material.index(), s);
                    s
                }
            };
            let base_colour = material.pbr_metallic_roughness().base_color_texture();
            let transform = base_colour.as_ref().and_then(|t| t.texture_transform());
            let uv_set = transform
                .as_ref()
                .and_then(|t| t.tex_coord())
                .or(base_colour.as_ref().map(|t| t.tex_coord()))
                .unwrap_or(0);
            let joints = match binding {
                Binding::Skin(map) => Some(map.len()),
                Binding::Rigid(..) => None,
            };
            let mut raw = read_primitive(&prim, buffer, uv_set, joints, &label)?;
            if let Some(t) = &transform {
                let finite = t.offset().iter().chain(&t.scale()).all(|v| v.is_finite())
                    && t.rotation().is_finite();
                if !finite {
                    return Err(format!(
                        "{label}: its material's KHR_texture_transform is not finite"
                    ));
                }
            }
            if let Some(t) = transform {
                apply_texture_transform(&mut raw.uvs, t.offset(), t.rotation(), t.scale());
            }
            match binding {
                Binding::Skin(map) => {
                    for inf in raw.influences.iter_mut().flatten() {
                        inf.bone = map[inf.bone as usize];
                    }
                }
                Binding::Rigid(world, bone) => {
                    for inf in raw.influences.iter_mut().flatten() {
                        inf.bone = *bone;
                    }
                    let normal_matrix = glam::Mat3::from_mat4(*world).inverse().transpose();
                    for p in &mut raw.positions {
                        *p = world.transform_point3(*p);
                    }
                    for n in raw.normals.iter_mut().flatten() {
                        *n = (normal_matrix * *n).normalize_or(Vec3::Y);
                    }
                    if world.determinant() < 0.0 {
                        // A mirroring transform turns the triangles inside out.
                        raw.triangles.iter_mut().for_each(|t| t.swap(1, 2));
                    }
                }
            }
            // Primitives over the same vertex accessors, drawn in one place in one material,
            // share their vertices: an exporter's layout (one vertex buffer, index buffers
            // per part).
            let key = (attributes, binding.key(), slot);
            let shared = vertex_bases.get(&key).copied();
            let base = append_primitive(&mut mesh, &mut needs_normals, raw, slot, shared);
            vertex_bases.entry(key).or_insert(base);
        }
    }
    if morphed > 0 {
        warnings.push(format!(
            "morph targets are left out on {morphed} primitive(s) (the base shape is drawn)"
        ));
    }
    if repeated > 0 {
        log::info!("{repeated} primitive(s) drawn again where they were already drawn read once");
    }
    if needs_normals.iter().any(|&n| n) {
        compute_normals(&mut mesh, &needs_normals);
    }
    // Degenerate and repeated triangles, and the vertices only they used (or none did), go
    // before anything counts vertices or builds animation space from them.
    let (triangles, vertices) = mesh.drop_unused();
    if triangles + vertices > 0 {
        log::info!(
            "{triangles} degenerate or repeated triangle(s) and {vertices} vertex(es) no \
             triangle uses left out"
        );
    }
    if mesh.triangle_count() == 0 {
        return Err("the skinned mesh has no triangles".into());
    }
    // Two corners at one point with one skin stay at one point in every pose: such a triangle
    // never covers a pixel, and animation space welds the two into one vertex. A mesh of
    // nothing else would bake to levels of no triangles (found by the `random_mesh` fuzzer).
    if !mesh.draws() {
        return Err(
            "the skinned mesh has no triangles that draw (each has two corners at one point)"
                .into(),
        );
    }

    Ok((mesh, materials))
}

/// Every node's parent, `None` for roots (the first parent where a file gives two).
fn node_parents(doc: &gltf::Document) -> Vec<Option<usize>> {
    let mut parent = vec![None; doc.nodes().len()];
    for n in doc.nodes() {
        for c in n.children() {
            parent[c.index()].get_or_insert(n.index());
        }
    }
    parent
}

/// Node `n`'s world transform in its rest pose (the validator has ruled out cycles).
fn world_of(doc: &gltf::Document, parents: &[Option<usize>], n: usize) -> Mat4 {
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
fn mesh_nodes_in_scene(doc: &gltf::Document) -> Vec<(gltf::Node<'_>, Mat4)> {
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
fn into_bind_space(mesh: &mut SkinnedMesh, skeleton: &mut Skeleton) {
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
fn place_in_scene(
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
fn guess_ground_speed(name: &str, height: f32) -> f32 {
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

/// The elements of vertex attribute `$accessor`, `$n` floats each, whatever its component
/// type: `KHR_mesh_quantization` (what gltfpack writes) allows signed and unsigned 8- and
/// 16-bit integers, normalised (mapped to [-1, 1] or [0, 1] as the glTF specification says)
/// or not (their values). `None` for a component type no attribute may have.
macro_rules! read_floats {
    ($accessor:expr, $buffer:expr, $n:literal) => {{
        use gltf::accessor::{DataType, Iter};
        let a = $accessor;
        let normalized = a.normalized();
        let convert = |c: f32, scale: f32| {
            if normalized { (c / scale).max(-1.0) } else { c }
        };
        match a.data_type() {
            DataType::F32 => Iter::<[f32; $n]>::new(a, $buffer).map(|it| it.collect::<Vec<_>>()),
            DataType::I8 => Iter::<[i8; $n]>::new(a, $buffer)
                .map(|it| it.map(|v| v.map(|c| convert(c as f32, 127.0))).collect()),
            DataType::U8 => Iter::<[u8; $n]>::new(a, $buffer)
                .map(|it| it.map(|v| v.map(|c| convert(c as f32, 255.0))).collect()),
            DataType::I16 => Iter::<[i16; $n]>::new(a, $buffer)
                .map(|it| it.map(|v| v.map(|c| convert(c as f32, 32767.0))).collect()),
            DataType::U16 => Iter::<[u16; $n]>::new(a, $buffer)
                .map(|it| it.map(|v| v.map(|c| convert(c as f32, 65535.0))).collect()),
            DataType::U32 => None,
        }
    }};
}

fn read_primitive<'a, 's, F>(
    prim: &'a gltf::Primitive<'a>,
    buffer: F,
    uv_set: u32,
    joint_count: Option<usize>,
    label: &str,
) -> Result<RawPrimitive, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let reader = prim.reader(buffer.clone());
    let attribute = |s: gltf::Semantic| prim.get(&s);
    let positions: Vec<Vec3> = attribute(gltf::Semantic::Positions)
        .and_then(|a| read_floats!(a, buffer.clone(), 3))
        .ok_or_else(|| format!("{label}: has no POSITION attribute"))?
        .into_iter()
        .map(Vec3::from)
        .collect();
    let n = positions.len();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("{label}: vertex {i} has a non-finite position"));
    }
    let normals: Option<Vec<Vec3>> = attribute(gltf::Semantic::Normals)
        .and_then(|a| read_floats!(a, buffer.clone(), 3))
        .map(|ns| {
            ns.into_iter()
                .map(|n| Vec3::from(n).normalize_or_zero())
                .collect()
        });
    if let Some(ns) = &normals {
        if ns.len() != n {
            return Err(format!("{label}: NORMAL count differs from POSITION count"));
        }
        if let Some(i) = ns.iter().position(|v| !v.is_finite()) {
            return Err(format!("{label}: vertex {i} has a non-finite normal"));
        }
    }
    let uvs: Vec<Vec2> = match attribute(gltf::Semantic::TexCoords(uv_set))
        .and_then(|a| read_floats!(a, buffer.clone(), 2))
    {
        Some(uvs) => uvs.into_iter().map(Vec2::from).collect(),
        None => vec![Vec2::ZERO; n],
    };
    if uvs.len() != n {
        return Err(format!(
            "{label}: TEXCOORD_{uv_set} count differs from POSITION count"
        ));
    }
    if let Some(i) = uvs.iter().position(|v| !v.is_finite()) {
        return Err(format!(
            "{label}: vertex {i} has a non-finite texture coordinate"
        ));
    }

    // Skin influences from every JOINTS_n / WEIGHTS_n pair; a rigid mesh (no skin) follows
    // bone 0 alone.
    let Some(joint_count) = joint_count else {
        let influences = vec![
            vec![Influence {
                bone: 0,
                weight: 1.0
            }];
            n
        ];
        return finish_primitive(prim, &reader, positions, normals, uvs, influences, label);
    };
    let mut influences: Vec<Vec<Influence>> = vec![Vec::new(); n];
    let mut set = 0;
    loop {
        let (j, w) = (reader.read_joints(set), reader.read_weights(set));
        let (j, w) = match (j, w) {
            (None, None) => break,
            (Some(j), Some(w)) => (j, w),
            _ => {
                return Err(format!(
                    "{label}: JOINTS_{set} and WEIGHTS_{set} must come together"
                ));
            }
        };
        let j: Vec<[u16; 4]> = j.into_u16().collect();
        let w: Vec<[f32; 4]> = w.into_f32().collect();
        if j.len() != n || w.len() != n {
            return Err(format!(
                "{label}: JOINTS_{set}/WEIGHTS_{set} count differs from POSITION count"
            ));
        }
        for v in 0..n {
            for k in 0..4 {
                let (bone, weight) = (j[v][k] as u32, w[v][k]);
                if weight.is_nan() {
                    return Err(format!("{label}: vertex {v} has a NaN weight"));
                }
                if !weight.is_finite() || weight < 0.0 {
                    return Err(format!(
                        "{label}: vertex {v} has an invalid weight {weight}"
                    ));
                }
                if weight == 0.0 {
                    continue;
                }
                if bone as usize >= joint_count {
                    return Err(format!(
                        "{label}: vertex {v} uses joint index {bone}, but the skin has only {joint_count} joints"
                    ));
                }
                match influences[v].iter_mut().find(|i| i.bone == bone) {
                    // Summed in f64 so that two huge weights of one joint stay finite.
                    Some(i) => {
                        i.weight = (i.weight as f64 + weight as f64).min(f32::MAX as f64) as f32
                    }
                    None => influences[v].push(Influence { bone, weight }),
                }
            }
        }
        set += 1;
    }
    if set == 0 {
        return Err(format!(
            "{label}: has no JOINTS_0/WEIGHTS_0 skin attributes"
        ));
    }
    for (v, inf) in influences.iter_mut().enumerate() {
        let total: f32 = inf.iter().map(|i| i.weight).sum();
        if total <= 0.0 {
            return Err(format!("{label}: vertex {v} has all-zero skin weights"));
        }
        if total.is_finite() {
            for i in inf.iter_mut() {
                i.weight /= total;
            }
        } else {
            // Weights near f32::MAX (3e38 + 3e38) overflow an f32 sum to infinity, which would
            // turn every weight to zero: normalise those in f64.
            let total: f64 = inf.iter().map(|i| i.weight as f64).sum();
            for i in inf.iter_mut() {
                i.weight = (i.weight as f64 / total) as f32;
            }
        }
        inf.sort_by_key(|i| i.bone);
    }
    finish_primitive(prim, &reader, positions, normals, uvs, influences, label)
}

/// A primitive's triangles (from its indices and mode) with its vertices read so far.
fn finish_primitive<'a, 's, F>(
    prim: &'a gltf::Primitive<'a>,
    reader: &gltf::mesh::Reader<'a, 's, F>,
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Vec<Vec2>,
    influences: Vec<Vec<Influence>>,
    label: &str,
) -> Result<RawPrimitive, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let n = positions.len();
    let indices: Option<Vec<u32>> = reader.read_indices().map(|i| i.into_u32().collect());
    let indexed = indices.is_some();
    let index_list: Vec<u32> = indices.unwrap_or_else(|| (0..n as u32).collect());
    if let Some(&bad) = index_list.iter().find(|&&i| i as usize >= n) {
        return Err(format!(
            "{label}: index {bad} is out of range ({n} vertices)"
        ));
    }
    let triangles: Vec<[u32; 3]> = match prim.mode() {
        Mode::Triangles => index_list
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
        Mode::TriangleStrip => (0..index_list.len().saturating_sub(2))
            .map(|i| {
                let (a, b, c) = (index_list[i], index_list[i + 1], index_list[i + 2]);
                if i % 2 == 0 { [a, b, c] } else { [b, a, c] }
            })
            .collect(),
        Mode::TriangleFan => (1..index_list.len().saturating_sub(1))
            .map(|i| [index_list[0], index_list[i], index_list[i + 1]])
            .collect(),
        other => {
            return Err(format!(
                "{label}: primitive mode {other:?} is not supported (triangles only)"
            ));
        }
    };
    Ok(RawPrimitive {
        positions,
        normals,
        uvs,
        influences,
        triangles,
        indexed,
    })
}

/// Merges unindexed vertices that share position, normal, UV and influences (see `weld`).
fn weld(raw: RawPrimitive) -> RawPrimitive {
    let rep = weld_map(&raw.positions, |a, b| {
        raw.uvs[a] == raw.uvs[b]
            && raw.influences[a] == raw.influences[b]
            && raw
                .normals
                .as_ref()
                .is_none_or(|n| n[a].normalize_or_zero().dot(n[b].normalize_or_zero()) > 0.9999)
    });
    let mut new_index = vec![u32::MAX; rep.len()];
    let mut kept = Vec::new();
    for (v, &r) in rep.iter().enumerate() {
        if r as usize == v {
            new_index[v] = kept.len() as u32;
            kept.push(v);
        }
    }
    let pick = |v: u32| new_index[rep[v as usize] as usize];
    RawPrimitive {
        positions: kept.iter().map(|&v| raw.positions[v]).collect(),
        normals: raw
            .normals
            .as_ref()
            .map(|n| kept.iter().map(|&v| n[v]).collect()),
        uvs: kept.iter().map(|&v| raw.uvs[v]).collect(),
        influences: kept.iter().map(|&v| raw.influences[v].clone()).collect(),
        triangles: raw.triangles.iter().map(|t| t.map(pick)).collect(),
        indexed: true,
    }
}

/// Appends a primitive's vertices and triangles; with `shared`, where the same vertices were
/// appended before (their first index and count), only its triangles, onto those. Returns
/// where its vertices are.
fn append_primitive(
    mesh: &mut SkinnedMesh,
    needs_normals: &mut Vec<bool>,
    raw: RawPrimitive,
    material: u16,
    shared: Option<(u32, usize)>,
) -> (u32, usize) {
    let raw = if raw.indexed { raw } else { weld(raw) };
    if let Some((base, count)) = shared
        && count == raw.positions.len()
    {
        for t in raw.triangles {
            mesh.indices.extend(t.iter().map(|&i| i + base));
        }
        return (base, count);
    }
    let base = mesh.positions.len() as u32;
    let has_normals = raw.normals.is_some();
    if mesh.influence_offsets.is_empty() {
        mesh.influence_offsets.push(0);
    }
    for v in 0..raw.positions.len() {
        mesh.positions.push(raw.positions[v]);
        mesh.normals.push(
            raw.normals
                .as_ref()
                .map(|n| n[v].normalize_or(Vec3::Y))
                .unwrap_or(Vec3::Y),
        );
        mesh.uvs.push(raw.uvs[v]);
        mesh.materials.push(material);
        mesh.influences.extend_from_slice(&raw.influences[v]);
        mesh.influence_offsets.push(mesh.influences.len() as u32);
        needs_normals.push(!has_normals);
    }
    // Triangles that welding (or the file) made degenerate go later, with the rest
    // (`SkinnedMesh::drop_unused`).
    let count = raw.positions.len();
    for t in raw.triangles {
        mesh.indices.extend(t.iter().map(|&i| i + base));
    }
    (base, count)
}

fn convert_material(
    material: &gltf::Material,
    images: &[Option<Rgba8Image>],
) -> Result<Material, String> {
    let pbr = material.pbr_metallic_roughness();
    let texture = match pbr.base_color_texture() {
        Some(info) => {
            let index = info.texture().source().index();
            let image = images
                .get(index)
                .and_then(Option::as_ref)
                .ok_or_else(|| format!("material refers to missing image {index}"))?;
            Some(image.clone())
        }
        None => None,
    };
    let base_color = pbr.base_color_factor();
    if base_color.iter().any(|c| !c.is_finite()) {
        return Err("a material has a non-finite base colour".into());
    }
    let alpha_cutoff = material.alpha_cutoff().unwrap_or(0.5);
    if !alpha_cutoff.is_finite() || alpha_cutoff < 0.0 {
        return Err(format!(
            "a material has an invalid alphaCutoff {alpha_cutoff}"
        ));
    }
    Ok(Material {
        name: material
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("material{}", material.index().unwrap_or(0))),
        base_color,
        texture,
        alpha_mode: match material.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask,
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        alpha_cutoff,
        double_sided: material.double_sided(),
    })
}

fn read_clip<'a, 's, F>(
    anim: &'a gltf::Animation<'a>,
    buffer: F,
    remap: &[u32],
) -> Result<Option<Clip>, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let name = anim
        .name()
        .map(str::to_string)
        .unwrap_or_else(|| format!("clip{}", anim.index()));
    let mut channels = Vec::new();
    for ch in anim.channels() {
        let node = ch.target().node().index();
        if remap[node] == u32::MAX {
            continue; // animates something that is not part of this skeleton
        }
        let target = match ch.target().property() {
            gltf::animation::Property::Translation => ChannelTarget::Translation,
            gltf::animation::Property::Rotation => ChannelTarget::Rotation,
            gltf::animation::Property::Scale => ChannelTarget::Scale,
            gltf::animation::Property::MorphTargetWeights => continue,
        };
        let interpolation = match ch.sampler().interpolation() {
            gltf::animation::Interpolation::Step => Interpolation::Step,
            gltf::animation::Interpolation::Linear => Interpolation::Linear,
            gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
        };
        let reader = ch.reader(buffer.clone());
        let times: Vec<f32> = reader
            .read_inputs()
            .ok_or_else(|| format!("clip '{name}': a channel has no key times"))?
            .collect();
        let values: Vec<Vec4> = match reader.read_outputs() {
            Some(ReadOutputs::Translations(it)) => it.map(|v| Vec3::from(v).extend(0.0)).collect(),
            Some(ReadOutputs::Scales(it)) => it.map(|v| Vec3::from(v).extend(0.0)).collect(),
            Some(ReadOutputs::Rotations(it)) => it.into_f32().map(Vec4::from).collect(),
            _ => return Err(format!("clip '{name}': a channel has no key values")),
        };
        if times.is_empty() {
            return Err(format!("clip '{name}': a channel has no keys"));
        }
        if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] <= w[0]) {
            return Err(format!(
                "clip '{name}': key times are not finite and strictly increasing"
            ));
        }
        let per_key = if interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        if values.len() != times.len() * per_key {
            return Err(format!(
                "clip '{name}': {} key values for {} key times",
                values.len(),
                times.len()
            ));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(format!("clip '{name}': a key value is not finite"));
        }
        // Finite but past any scene: a translation of 10³⁰ puts the character where no
        // camera framing can see it, or anything else, and squares to infinity in every
        // distance measured on it.
        if target != ChannelTarget::Rotation
            && let Some(v) = values
                .iter()
                .find(|v| v.abs().max_element() > MAX_KEY_VALUE)
        {
            return Err(format!(
                "clip '{name}': a {} key of {} is out of range (at most {MAX_KEY_VALUE:e} in \
                 the file's units)",
                if target == ChannelTarget::Translation {
                    "translation"
                } else {
                    "scale"
                },
                v.abs().max_element()
            ));
        }
        channels.push(Channel {
            node: remap[node],
            target,
            interpolation,
            times,
            values,
        });
    }
    if channels.is_empty() {
        return Ok(None);
    }
    let duration = channels
        .iter()
        .map(|c| *c.times.last().expect("non-empty"))
        .fold(0.0f32, f32::max);
    // `-1` marks "not given in the file": the caller guesses once the model's size is known.
    let ground_speed = anim
        .extras()
        .as_ref()
        .and_then(|raw| serde_json::from_str::<serde_json::Value>(raw.get()).ok())
        .and_then(|v| v.get("ground_speed").and_then(|s| s.as_f64()))
        .map(|s| s as f32)
        .filter(|s| s.is_finite() && *s >= 0.0)
        .unwrap_or(-1.0);
    Ok(Some(Clip {
        name,
        duration,
        channels,
        ground_speed,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_guess_uses_clip_names() {
        assert_eq!(guess_ground_speed("Survey", 1.0), 0.0);
        assert!(guess_ground_speed("Walk", 1.0) > 0.0);
        assert!(guess_ground_speed("Run", 1.0) > guess_ground_speed("Walk", 1.0));
    }
}

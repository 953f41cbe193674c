//! glTF 2.0 import of one skinned character: `.glb`, and `.gltf` with embedded or external
//! buffers.
//!
//! What is read: the first skin that a mesh uses, every primitive of every mesh bound to it (merged
//! into one [`SkinnedMesh`](crate::model::SkinnedMesh)), all JOINTS_n / WEIGHTS_n sets (so any number of influences per
//! vertex), the node hierarchy above the joints, the inverse bind matrices, every animation clip
//! (translation, rotation and scale; STEP, LINEAR and CUBICSPLINE) and the base colour of each
//! material. Everything the renderer and the bakes rely on is validated here, so that a bad file
//! stops with one line naming the file and the problem instead of a panic further down.

use super::validate;
use crate::error::InputError;
use crate::import::clips::read_clip;
use crate::import::nodes::{
    guess_ground_speed, into_bind_space, mesh_nodes_in_scene, node_parents, place_in_scene,
    read_hierarchy, read_inverse_bind, world_of,
};
use crate::import::primitives::{Binding, msft_lod_lower_levels, read_meshes};
use crate::model::{Bounds, Model, Node, Rgba8Image, Skeleton, Trs};
use glam::{Affine3A, Mat4};
use std::path::Path;

/// A model read from a file, and a digest of everything it was made from.
pub struct Read {
    pub model: Model,
    /// A hash of the bytes the import read: the file, every buffer (external ones included)
    /// and every image a material uses, decoded. What a bake of the model is cached under.
    pub digest: [u8; 32],
}

/// Loads a skinned model from a `.glb` or `.gltf` file within the default limits.
pub fn load(path: &Path) -> Result<Model, InputError> {
    read(path, &validate::Limits::default()).map(|r| r.model)
}

/// Reads a skinned model from a `.glb` or `.gltf` file, within `limits`.
pub fn read(path: &Path, limits: &validate::Limits) -> Result<Read, InputError> {
    let fail = |p: String| InputError::new(path, p);
    let meta = std::fs::metadata(path).map_err(|e| fail(io_problem(&e)))?;
    validate::check_file(&meta, limits).map_err(fail)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let read = std::fs::read(path).map_err(|e| fail(io_problem(&e)))?;
    let (read, warnings) = read_model(&model_name(path), read, base, limits).map_err(fail)?;
    for w in warnings {
        log::warn!("{}: {w}", path.display());
    }
    Ok(read)
}

/// Stems that say nothing of what a file holds: the names exporters give every file.
const GENERIC_STEMS: [&str; 5] = ["scene", "model", "untitled", "mesh", "export"];

/// What a model read from `path` is called: the file's stem, or, where that is a stem every
/// export has (Sketchfab publishes every model as `scene.gltf` in a folder named after it),
/// the folder's name.
pub fn model_name(path: &Path) -> String {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "model".into());
    if !GENERIC_STEMS.contains(&stem.to_ascii_lowercase().as_str()) {
        return stem;
    }
    // The folder as given, else as the file system has it (`scene.gltf` in the working one).
    let folder = match path.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(p) => std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf()),
        None => std::env::current_dir().unwrap_or_default(),
    };
    folder
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .filter(|n| !n.is_empty())
        .unwrap_or(stem)
}

/// Reads a built-in model from the copy built into the binary, within `limits`.
pub fn read_builtin(
    asset: &crate::assets::Builtin,
    limits: &validate::Limits,
) -> Result<Read, InputError> {
    let (read, warnings) = read_model(asset.name, asset.bytes.to_vec(), Path::new("."), limits)
        .map_err(|p| InputError::new(asset.label(), p))?;
    for w in warnings {
        log::warn!("{}: {w}", asset.label().display());
    }
    Ok(read)
}

/// A model from the bytes of a `.glb` or `.gltf` whose external files lie in `base`, and the
/// warnings to show with it; the error is the problem, without the file's name. What the
/// fuzzer feeds (see `fuzz/`).
pub fn from_bytes(
    name: &str,
    read: Vec<u8>,
    base: &Path,
    limits: &validate::Limits,
) -> Result<(Model, Vec<String>), String> {
    read_model(name, read, base, limits).map(|(r, w)| (r.model, w))
}

/// [`from_bytes`] with the digest of what it read.
fn read_model(
    name: &str,
    read: Vec<u8>,
    base: &Path,
    limits: &validate::Limits,
) -> Result<(Read, Vec<String>), String> {
    let mut digest = blake3::Hasher::new();
    digest.update(b"lodlab model");
    digest.update(&read);
    let (doc, buffers) = read_document(read, base, limits)?;
    let images = super::sources::read_images(&doc, base, &buffers, limits)?;
    digest_inputs(&mut digest, &buffers, &images);
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
    let digest = *digest.finalize().as_bytes();
    Ok((Read { model, digest }, warnings))
}

/// Adds to `digest` what a file's own bytes do not hold: its buffers (a `.gltf`'s external
/// ones) and the images its materials use, decoded (external ones too).
fn digest_inputs(
    digest: &mut blake3::Hasher,
    buffers: &[gltf::buffer::Data],
    images: &[Option<Rgba8Image>],
) {
    for b in buffers {
        digest.update(&(b.len() as u64).to_le_bytes());
        digest.update(b);
    }
    for image in images {
        match image {
            Some(i) => {
                digest.update(&[1]);
                digest.update(&i.width.to_le_bytes());
                digest.update(&i.height.to_le_bytes());
                digest.update(&i.pixels);
            }
            None => {
                digest.update(&[0]);
            }
        }
    }
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
/// name; the error names those that are not. Returns how many clips came, and a digest of
/// the bytes read (the file and its buffers).
pub fn add_clips(
    model: &mut Model,
    path: &Path,
    limits: &validate::Limits,
) -> Result<(usize, [u8; 32]), InputError> {
    let fail = |p: String| InputError::new(path, p);
    let meta = std::fs::metadata(path).map_err(|e| fail(io_problem(&e)))?;
    validate::check_file(&meta, limits).map_err(fail)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let read = std::fs::read(path).map_err(|e| fail(io_problem(&e)))?;
    clips_into(model, read, base, limits).map_err(fail)
}

/// [`add_clips`] from a model named on the command line: a built-in (`mocap-walk`) or a file.
pub fn add_clips_from(
    model: &mut Model,
    from: &crate::import::source::Source,
    limits: &validate::Limits,
) -> Result<(usize, [u8; 32]), InputError> {
    match from {
        crate::import::source::Source::File(path) => add_clips(model, path, limits),
        crate::import::source::Source::Builtin(b) => {
            clips_into(model, b.bytes.to_vec(), Path::new("."), limits)
                .map_err(|p| InputError::new(b.label(), p))
        }
    }
}

/// The clips of the glTF bytes `read` bound onto `model`'s skeleton by joint name; the error
/// is the problem, without the file's name.
fn clips_into(
    model: &mut Model,
    read: Vec<u8>,
    base: &Path,
    limits: &validate::Limits,
) -> Result<(usize, [u8; 32]), String> {
    let mut digest = blake3::Hasher::new();
    digest.update(b"lodlab clips");
    digest.update(&read);
    let (doc, buffers) = read_document(read, base, limits)?;
    digest_inputs(&mut digest, &buffers, &[]);
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
        return Err(format!(
            "its clips animate {} joint(s) that {} does not have: {} (its joints are {})",
            unmatched.len(),
            model.name,
            list(&unmatched),
            list(&joints)
        ));
    }
    let buffer = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
    let mut clips = Vec::new();
    for anim in doc.animations() {
        if let Some(clip) = read_clip(&anim, buffer, &remap)? {
            clips.push(clip);
        }
    }
    if clips.is_empty() {
        return Err("has no clips to add".into());
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
    Ok((count, *digest.finalize().as_bytes()))
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
    let skins = used_skins(&skinned);
    let SkinBones {
        mut bone_nodes,
        mut inverse_bind,
        maps,
        into,
    } = merge_skins(&skins, buffers)?;
    let parents = node_parents(doc);
    let props = rigid_parts(
        doc,
        &lower_lods,
        &parents,
        (&mut bone_nodes, &mut inverse_bind),
        warnings,
    )?;
    let (nodes, remap) = read_hierarchy(doc, &bone_nodes, warnings)?;
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
            (n.clone(), Binding::Skin(&maps[k], into[k]))
        })
        .collect();
    bound.extend(rigid_bindings(doc, &parents, &bone_nodes, &skeleton, props));
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

/// The bones of every skin a mesh uses, merged (see [`merge_skins`]).
struct SkinBones {
    /// Each bone's node, and its inverse bind matrix.
    bone_nodes: Vec<usize>,
    inverse_bind: Vec<Mat4>,
    /// Per skin, the bone of each of its joints.
    maps: Vec<Vec<u32>>,
    /// Per skin, the transform that takes its meshes' vertices into the space its bones are
    /// bound in (the identity for most skins).
    into: Vec<Mat4>,
}

/// Every skin the `skinned` nodes use, in order of first use.
fn used_skins<'a>(skinned: &[gltf::Node<'a>]) -> Vec<gltf::Skin<'a>> {
    let mut skins: Vec<gltf::Skin> = Vec::new();
    for n in skinned {
        let s = n.skin().expect("filtered on a skin");
        if !skins.iter().any(|k| k.index() == s.index()) {
            skins.push(s);
        }
    }
    skins
}

/// The joints of `skins` merged into one list of bones, one a node where the skins allow.
///
/// Every skin a mesh uses, in order of first use. A skin skins its vertex `v` by
/// `G_j · IBM_j · v`. A joint another skin has already, with the same inverse bind matrix, is
/// shared. Exporters often write a character as one mesh and skin per part, each part's
/// vertices in a space of its own (a sword bound in its hand's node), so that the same node
/// has, skin by skin, `IBM'_j = IBM_j · C` with one `C` for the whole skin: then the skin's
/// vertices are moved by `C` and its joints share the bones (`G_j · IBM_j · (C v) =
/// G_j · IBM'_j · v`). Only a skin bound in another pose (no one `C`) keeps bones of its own
/// on shared nodes.
fn merge_skins(skins: &[gltf::Skin], buffers: &[gltf::buffer::Data]) -> Result<SkinBones, String> {
    let (mut bone_nodes, mut inverse_bind): (Vec<usize>, Vec<Mat4>) = (Vec::new(), Vec::new());
    // The bones on each node.
    let mut on_node: std::collections::HashMap<usize, Vec<usize>> = Default::default();
    let mut maps: Vec<Vec<u32>> = Vec::with_capacity(skins.len());
    let mut into: Vec<Mat4> = Vec::with_capacity(skins.len());
    for skin in skins {
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        if joints.is_empty() {
            return Err(format!("skin {} has no joints", skin.index()));
        }
        let ibm = read_inverse_bind(skin, buffers, joints.len())?;
        let c = skin_space(&joints, &ibm, |j| {
            on_node.get(&j).map(|b| inverse_bind[b[0]])
        });
        let back = c.inverse();
        let mut map = Vec::with_capacity(joints.len());
        for (&j, m) in joints.iter().zip(&ibm) {
            let m = *m * back;
            let bones = on_node.entry(j).or_default();
            let bone = match bones.iter().find(|&&b| same_matrix(&inverse_bind[b], &m)) {
                Some(&b) => b,
                None => {
                    bone_nodes.push(j);
                    inverse_bind.push(m);
                    bones.push(bone_nodes.len() - 1);
                    bone_nodes.len() - 1
                }
            };
            map.push(bone as u32);
        }
        maps.push(map);
        into.push(c);
    }
    Ok(SkinBones {
        bone_nodes,
        inverse_bind,
        maps,
        into,
    })
}

/// `C` with `IBM'_j = bound(j) · C` for every joint `j` of a skin (`joints`, inverse bind
/// matrices `ibm`) whose node is bound already (`bound`): the space the skin's vertices are
/// in, seen from the shared bones'. The identity where no joint is bound yet or no one `C`
/// fits them all.
fn skin_space(joints: &[usize], ibm: &[Mat4], bound: impl Fn(usize) -> Option<Mat4>) -> Mat4 {
    let mut found: Option<Mat4> = None;
    for (&j, m) in joints.iter().zip(ibm) {
        let Some(b) = bound(j) else {
            continue;
        };
        let c = b.inverse() * *m;
        match found {
            None => found = Some(c),
            Some(f) if same_matrix(&f, &c) => {}
            Some(_) => return Mat4::IDENTITY,
        }
    }
    found
        .filter(|c| c.is_finite() && crate::model::keeps_every_direction(c))
        .unwrap_or(Mat4::IDENTITY)
}

/// Two matrices equal within rounding, relative to their size.
fn same_matrix(a: &Mat4, b: &Mat4) -> bool {
    let size = a
        .to_cols_array()
        .iter()
        .chain(&b.to_cols_array())
        .fold(1.0f32, |m, x| m.max(x.abs()));
    a.abs_diff_eq(*b, 1e-5 * size)
}

/// The unskinned mesh nodes of the scene, each with its world transform and the node that
/// carries it; a carrier that is no joint is added to `bones` (nodes and inverse bind
/// matrices, the skins' bones first).
///
/// Unskinned parts ride rigidly on what carries them in the file: the nearest joint above
/// the node (a helmet on the head bone), else the node itself, which becomes a bone of its
/// own so that whatever animates it or the nodes above it moves the part (a cape on the
/// armature's node beside the skeleton's root, a prop standing in the scene).
fn rigid_parts<'a>(
    doc: &'a gltf::Document,
    lower_lods: &[usize],
    parents: &[Option<usize>],
    bones: (&mut Vec<usize>, &mut Vec<Mat4>),
    warnings: &mut Vec<String>,
) -> Result<Vec<(gltf::Node<'a>, Mat4, usize)>, String> {
    let (bone_nodes, inverse_bind) = bones;
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
    Ok(props)
}

/// The unskinned parts `props` (node, world transform, carrier) bound rigidly to their
/// carriers' bones.
fn rigid_bindings<'a, 'm>(
    doc: &gltf::Document,
    parents: &[Option<usize>],
    bone_nodes: &[usize],
    skeleton: &Skeleton,
    props: Vec<(gltf::Node<'a>, Mat4, usize)>,
) -> Vec<(gltf::Node<'a>, Binding<'m>)> {
    let mut bound = Vec::with_capacity(props.len());
    for (node, world, carrier) in props {
        // The carrier's first bone (a node may be a bone of two skins).
        let bone = bone_nodes
            .iter()
            .position(|&b| b == carrier)
            .expect("every carrier is a bone");
        // Into the bone's bind space: G_b · IBM_b · v̂ then puts the part where the node
        // carrying it puts it, whatever the bind matrices say.
        let carrier_world = world_of(doc, parents, carrier);
        let bind = skeleton.inverse_bind[bone].inverse();
        let to_bind = bind * carrier_world.inverse() * world;
        bound.push((node, Binding::Rigid(to_bind, bone as u32)));
    }
    bound
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_with_a_generic_stem_is_named_by_its_folder() {
        let dir = tempfile::tempdir().unwrap();
        let folder = dir.path().join("red-kite");
        std::fs::create_dir(&folder).unwrap();
        assert_eq!(model_name(&folder.join("scene.gltf")), "red-kite");
        assert_eq!(model_name(&folder.join("Scene.glb")), "red-kite");
        assert_eq!(model_name(&folder.join("kite.glb")), "kite");
        // A folder given as `..` is named as the file system names it.
        let inner = folder.join("source");
        std::fs::create_dir(&inner).unwrap();
        assert_eq!(model_name(&inner.join("../untitled.glb")), "red-kite");
    }

    #[test]
    fn speed_guess_uses_clip_names() {
        assert_eq!(guess_ground_speed("Survey", 1.0), 0.0);
        assert!(guess_ground_speed("Walk", 1.0) > 0.0);
        assert!(guess_ground_speed("Run", 1.0) > guess_ground_speed("Walk", 1.0));
    }
}

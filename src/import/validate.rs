//! Checks of a glTF file before anything reads its data, against the limits on what a model
//! may ask for ([`Limits`]).
//!
//! The gltf crate checks that indices refer to things that exist; it does not check that the
//! bytes an accessor reads lie inside its buffer view, that a stride holds an element, or that
//! the node graph is a forest, and some of those reach assertions, endless walks or allocations
//! the size of what a 3 KB file claims. Everything here runs in time linear in the file, before
//! the importer reads any attribute, so that each problem is one line naming what is wrong.

pub use super::limits::Limits;

/// "…; the limit is N (--limit NAME=M raises it)".
pub(super) fn over(what: String, limit: impl std::fmt::Display, name: &str) -> String {
    format!("{what}; the limit is {limit} (--limit {name}=N raises it)")
}

/// The file itself: a regular file, not a device or a pipe that never ends, within the size
/// limit.
pub fn check_file(meta: &std::fs::Metadata, limits: &Limits) -> Result<(), String> {
    if meta.is_dir() {
        return Err("is a directory, not a glTF file".into());
    }
    if !meta.is_file() {
        return Err("is not a regular file (a device, pipe or socket)".into());
    }
    if meta.len() == 0 {
        return Err("is empty, not a glTF file".into());
    }
    if meta.len() > limits.file_mb << 20 {
        return Err(over(
            format!("is {} MiB", meta.len() >> 20),
            format!("{} MiB", limits.file_mb),
            "file-mb",
        ));
    }
    Ok(())
}

/// A binary glTF's header gives a length the file can hold: at least the header's own 12
/// bytes and no more than there are. (The gltf crate subtracts 12 from it unchecked: a length
/// under 12 overflows, which a debug build reports as a panic. Found by the fuzzer.)
pub fn check_glb_header(bytes: &[u8]) -> Result<(), String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let Some(field) = bytes.get(8..12) else {
        return Err(
            "not a valid binary glTF (truncated or corrupt: its header is cut short)".into(),
        );
    };
    let declared = u32::from_le_bytes(field.try_into().expect("4 bytes")) as u64;
    if declared < 12 || declared > bytes.len() as u64 {
        return Err(format!(
            "not a valid binary glTF (truncated or corrupt: its header gives a length of \
             {declared} bytes, the file has {})",
            bytes.len()
        ));
    }
    Ok(())
}

/// What the gltf crate reads unchecked, checked first on the raw JSON (each found by the
/// fuzzer as a panic): a POSITION attribute's accessor index, which its own validation looks up
/// before the index checks run, and an image's source, which it unwraps.
pub fn check_raw(bytes: &[u8]) -> Result<(), String> {
    use gltf::json::validation::Checked;
    let json: std::borrow::Cow<[u8]> = if bytes.starts_with(b"glTF") {
        match gltf::binary::Glb::from_slice(bytes) {
            Ok(glb) => glb.json,
            // The gltf crate says what is wrong with it.
            Err(_) => return Ok(()),
        }
    } else {
        bytes.into()
    };
    let Ok(root) = gltf::json::Root::from_slice(&json) else {
        return Ok(());
    };
    // The gltf crate unwraps these when asked for an image's source.
    for (i, image) in root.images.iter().enumerate() {
        match (&image.buffer_view, &image.uri, &image.mime_type) {
            (Some(_), _, None) => {
                return Err(format!(
                    "invalid glTF (image {i} lies in a buffer view but has no mimeType)"
                ));
            }
            (None, None, _) => {
                return Err(format!(
                    "invalid glTF (image {i} has neither a uri nor a bufferView)"
                ));
            }
            _ => {}
        }
    }
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (k, prim) in mesh.primitives.iter().enumerate() {
            let position = prim
                .attributes
                .get(&Checked::Valid(gltf::json::mesh::Semantic::Positions));
            if let Some(i) = position
                && i.value() >= root.accessors.len()
            {
                return Err(format!(
                    "invalid glTF (mesh {m} primitive {k}: POSITION refers to accessor {}, of {})",
                    i.value(),
                    root.accessors.len()
                ));
            }
        }
    }
    // The gltf crate unwraps a channel's target node when it is read, not when it validates.
    for (a, anim) in root.animations.iter().enumerate() {
        for (c, channel) in anim.channels.iter().enumerate() {
            let node = channel.target.node.value();
            if node >= root.nodes.len() {
                return Err(format!(
                    "invalid glTF (animation {a} channel {c} targets node {node}, of {})",
                    root.nodes.len()
                ));
            }
        }
    }
    Ok(())
}

/// The node graph is a forest: no node is its own child and no chain of children comes back
/// to where it started. (A node with two parents is the importer's to judge: it tolerates one
/// outside the skeleton.) Linear in the nodes.
fn check_nodes(doc: &gltf::Document, limits: &Limits) -> Result<(), String> {
    let count = doc.nodes().len();
    if count > limits.nodes {
        return Err(over(format!("has {count} nodes"), limits.nodes, "nodes"));
    }
    let mut parent = vec![None; count];
    for n in doc.nodes() {
        for c in n.children() {
            if c.index() == n.index() {
                return Err(format!("node {} is its own child", n.index()));
            }
            parent[c.index()].get_or_insert(n.index());
        }
    }
    // Walk up from every node; a walk that meets a node of its own walk has found a cycle.
    // 0: not seen, 1: on the current walk, 2: known to reach a root.
    let mut state = vec![0u8; count];
    for start in 0..count {
        let mut walk: Vec<usize> = Vec::new();
        let mut at = Some(start);
        while let Some(n) = at {
            match state[n] {
                2 => break,
                1 => {
                    let from = walk.iter().position(|&w| w == n).unwrap_or(0);
                    // Parents first, back to where it started.
                    let mut cycle: Vec<String> =
                        walk[from..].iter().rev().map(|w| w.to_string()).collect();
                    cycle.push(cycle[0].clone());
                    return Err(format!(
                        "nodes form a cycle ({}, each a child of the one before)",
                        cycle.join(" → ")
                    ));
                }
                _ => {
                    state[n] = 1;
                    walk.push(n);
                    at = parent[n];
                }
            }
        }
        for w in walk {
            state[w] = 2;
        }
    }
    Ok(())
}

/// Buffer views lie inside their buffers; strides are what glTF allows (4 to 252, a multiple
/// of 4).
fn check_views(doc: &gltf::Document, buffers: &[gltf::buffer::Data]) -> Result<(), String> {
    for v in doc.views() {
        let have = buffers.get(v.buffer().index()).map_or(0, |d| d.len()) as u64;
        let end = v.offset() as u64 + v.length() as u64;
        if end > have {
            return Err(format!(
                "buffer view {} (bytes {}..{end}) lies past the end of buffer {} ({have} bytes)",
                v.index(),
                v.offset(),
                v.buffer().index()
            ));
        }
        if let Some(stride) = v.stride()
            && (!(4..=252).contains(&stride) || !stride.is_multiple_of(4))
        {
            return Err(format!(
                "buffer view {} has byteStride {stride}: glTF allows 4 to 252, a multiple of 4",
                v.index()
            ));
        }
    }
    Ok(())
}

/// Every accessor reads inside its buffer view, element by element, at an aligned offset; its
/// sparse substitutions too.
fn check_accessors(doc: &gltf::Document, buffers: &[gltf::buffer::Data]) -> Result<(), String> {
    for a in doc.accessors() {
        let name = format!("accessor {}", a.index());
        let component = a.data_type().size() as u64;
        let size = a.size() as u64;
        let count = a.count() as u64;
        if count == 0 {
            return Err(format!("{name} has count 0"));
        }
        if let Some(view) = a.view() {
            let stride = view.stride().map_or(size, |s| s as u64);
            if stride < size {
                return Err(format!(
                    "buffer view {} has byteStride {stride}, less than the {size}-byte elements \
                     {name} reads",
                    view.index()
                ));
            }
            let offset = a.offset() as u64;
            if !offset.is_multiple_of(component)
                || !(view.offset() as u64).is_multiple_of(component)
            {
                return Err(format!(
                    "{name} starts at byte {} of buffer {}, not aligned to its {component}-byte \
                     components",
                    view.offset() as u64 + offset,
                    view.buffer().index()
                ));
            }
            let end = offset + stride * (count - 1) + size;
            if end > view.length() as u64 {
                return Err(format!(
                    "{name} ({count} elements of {size} bytes) reads past the end of buffer view \
                     {}: it needs {end} bytes, the view has {}",
                    view.index(),
                    view.length()
                ));
            }
        }
        if let Some(sparse) = a.sparse() {
            let n = sparse.count() as u64;
            let index_size = sparse.indices().index_type().size() as u64;
            let iv = sparse.indices().view();
            let vv = sparse.values().view();
            // glTF: "the referenced buffer view MUST NOT have its target or byteStride
            // properties defined" (the gltf crate would read such indices at the stride).
            for (part, view) in [("indices", &iv), ("values", &vv)] {
                if let Some(stride) = view.stride() {
                    return Err(format!(
                        "{name}'s sparse {part} are in buffer view {}, which has byteStride \
                         {stride}: glTF allows none there",
                        view.index()
                    ));
                }
            }
            let index_end = sparse.indices().offset() as u64 + n * index_size;
            let value_end = sparse.values().offset() as u64 + n * size;
            if index_end > iv.length() as u64 || value_end > vv.length() as u64 {
                return Err(format!(
                    "{name}'s sparse substitutions read past the end of their buffer views"
                ));
            }
            let data = &buffers[iv.buffer().index()][..];
            let start = iv.offset() + sparse.indices().offset();
            for k in 0..n as usize {
                let at = start + k * index_size as usize;
                let i = match index_size {
                    1 => data[at] as u64,
                    2 => u16::from_le_bytes([data[at], data[at + 1]]) as u64,
                    _ => u32::from_le_bytes([data[at], data[at + 1], data[at + 2], data[at + 3]])
                        as u64,
                };
                if i >= count {
                    return Err(format!(
                        "{name}'s sparse index {i} is past its {count} elements"
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Accessors have the types their use demands, so that no reader meets an element of the wrong
/// shape: vertex attributes as glTF (and `KHR_mesh_quantization`) allow them, indices as
/// unsigned scalars, inverse bind matrices as 4×4 floats, key times as float scalars.
fn check_types(doc: &gltf::Document) -> Result<(), String> {
    use gltf::Semantic as S;
    use gltf::accessor::{DataType as T, Dimensions as D};
    let allowed = |a: &gltf::Accessor, dims: &[D], types: &[T]| {
        dims.contains(&a.dimensions()) && types.contains(&a.data_type())
    };
    let ints = [T::I8, T::U8, T::I16, T::U16];
    let with_float = |t: &[T]| -> Vec<T> { t.iter().copied().chain([T::F32]).collect() };
    let quantized = doc.extensions_used().any(|e| e == "KHR_mesh_quantization");
    for mesh in doc.meshes() {
        for (k, prim) in mesh.primitives().enumerate() {
            let what = |name: &str| format!("mesh {} primitive {k}: {name}", mesh.index());
            for (semantic, a) in prim.attributes() {
                let ok = match &semantic {
                    S::Positions => allowed(&a, &[D::Vec3], &with_float(&ints)),
                    S::Normals => allowed(&a, &[D::Vec3], &with_float(&[T::I8, T::I16])),
                    S::TexCoords(_) => allowed(&a, &[D::Vec2], &with_float(&ints)),
                    S::Joints(_) => allowed(&a, &[D::Vec4], &[T::U8, T::U16]),
                    S::Weights(_) => allowed(&a, &[D::Vec4], &[T::F32, T::U8, T::U16]),
                    _ => true,
                };
                // Integers read as they are (not normalised to 0..1) are what
                // KHR_mesh_quantization adds; without it a texture coordinate of SHORT 1000
                // is a mistake, and tiles the texture a thousand times.
                let plain = matches!(semantic, S::Positions | S::Normals | S::TexCoords(_));
                if ok && plain && a.data_type() != T::F32 && !a.normalized() && !quantized {
                    return Err(format!(
                        "{} is {:?} of {:?} not normalised (accessor {}), which glTF allows \
                         only with KHR_mesh_quantization, not named in extensionsUsed",
                        what(&semantic.to_string()),
                        a.dimensions(),
                        a.data_type(),
                        a.index()
                    ));
                }
                if !ok {
                    return Err(format!(
                        "{} is a {:?} of {:?} (accessor {}), which glTF does not allow",
                        what(&semantic.to_string()),
                        a.dimensions(),
                        a.data_type(),
                        a.index()
                    ));
                }
            }
            if let Some(a) = prim.indices()
                && !allowed(&a, &[D::Scalar], &[T::U8, T::U16, T::U32])
            {
                return Err(format!(
                    "{} are {:?} of {:?} (accessor {}), not unsigned integers",
                    what("indices"),
                    a.dimensions(),
                    a.data_type(),
                    a.index()
                ));
            }
        }
    }
    for s in doc.skins() {
        if let Some(a) = s.inverse_bind_matrices()
            && !allowed(&a, &[D::Mat4], &[T::F32])
        {
            return Err(format!(
                "skin {}: inverse bind matrices are {:?} of {:?} (accessor {}), not 4×4 floats",
                s.index(),
                a.dimensions(),
                a.data_type(),
                a.index()
            ));
        }
    }
    for anim in doc.animations() {
        for (k, sampler) in anim.samplers().enumerate() {
            let input = sampler.input();
            if !allowed(&input, &[D::Scalar], &[T::F32]) {
                return Err(format!(
                    "animation {} sampler {k}: key times are {:?} of {:?}, not float scalars",
                    anim.index(),
                    input.dimensions(),
                    input.data_type()
                ));
            }
        }
        for ch in anim.channels() {
            use gltf::animation::Property as P;
            // The gltf crate lets an unknown path through and panics on reading it.
            let json = &doc.as_json().animations[anim.index()].channels[ch.index()];
            let gltf::json::validation::Checked::Valid(property) = json.target.path else {
                return Err(format!(
                    "animation {} channel {} animates a property glTF does not know",
                    anim.index(),
                    ch.index()
                ));
            };
            let out = ch.sampler().output();
            let ok = match property {
                // Integer translations and scales (KHR_mesh_quantization) are read by the gltf
                // crate as floats, which panics: only floats are taken.
                P::Translation | P::Scale => allowed(&out, &[D::Vec3], &[T::F32]),
                P::Rotation => allowed(&out, &[D::Vec4], &with_float(&ints)),
                P::MorphTargetWeights => allowed(&out, &[D::Scalar], &with_float(&ints)),
            };
            if !ok {
                return Err(format!(
                    "animation {} channel {}: its {:?} keys are {:?} of {:?} (accessor {})",
                    anim.index(),
                    ch.index(),
                    property,
                    out.dimensions(),
                    out.data_type(),
                    out.index()
                ));
            }
        }
    }
    Ok(())
}

/// The file without its animation channels that name no target node, which glTF allows ("the
/// channel should be ignored": an extension may target something else) and the gltf crate
/// refuses; `None` where there are none (or the JSON is not glTF, for the crate to say why).
pub fn without_untargeted_channels(bytes: &[u8]) -> Option<Vec<u8>> {
    if !bytes
        .windows(b"\"channels\"".len())
        .any(|w| w == b"\"channels\"")
    {
        return None;
    }
    let (mut json, bin) = super::container::split(bytes).ok()?;
    let mut dropped = 0;
    for anim in json.get_mut("animations")?.as_array_mut()? {
        if let Some(channels) = anim.get_mut("channels").and_then(|c| c.as_array_mut()) {
            let before = channels.len();
            channels.retain(|c| c.get("target").is_none_or(|t| t.get("node").is_some()));
            dropped += before - channels.len();
        }
    }
    if dropped == 0 {
        return None;
    }
    log::info!("{dropped} animation channel(s) without a target node ignored");
    if bytes.starts_with(b"glTF") {
        super::container::glb_of(&json, bin).ok()
    } else {
        serde_json::to_vec(&json).ok()
    }
}

/// Every attribute of a primitive has as many elements as its POSITION (glTF asks it): a
/// primitive of 10 vertices whose weights claim 2²⁸ is refused here, not read.
fn check_counts(doc: &gltf::Document) -> Result<(), String> {
    for mesh in doc.meshes() {
        for (k, prim) in mesh.primitives().enumerate() {
            let Some(position) = prim.get(&gltf::Semantic::Positions) else {
                continue;
            };
            for (semantic, a) in prim.attributes() {
                if a.count() != position.count() {
                    return Err(format!(
                        "mesh {} primitive {k}: {} has {} elements, POSITION has {}",
                        mesh.index(),
                        semantic.to_string(),
                        a.count(),
                        position.count()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// What the file expands to, from its declarations alone, before anything is read: vertices
/// and triangles of every primitive as often as nodes draw it (one primitive repeated 9,000
/// times, or a mesh on 5,000 nodes, is millions of triangles from a few kilobytes), and the
/// bytes of every accessor's elements (an accessor with no buffer view is all zeros, or a few
/// sparse values, however many elements it claims).
fn check_expansion(doc: &gltf::Document, limits: &Limits) -> Result<(), String> {
    use gltf::mesh::Mode;
    // Nodes drawing each mesh (an upper bound: nodes outside the scene count too).
    let mut draws = vec![0u64; doc.meshes().len()];
    for n in doc.nodes() {
        if let Some(m) = n.mesh() {
            draws[m.index()] += 1;
        }
    }
    let (mut vertices, mut triangles) = (0u64, 0u64);
    for mesh in doc.meshes() {
        let times = draws[mesh.index()];
        for prim in mesh.primitives() {
            let v = prim
                .get(&gltf::Semantic::Positions)
                .map_or(0, |a| a.count() as u64);
            let corners = prim.indices().map_or(v, |a| a.count() as u64);
            let t = match prim.mode() {
                Mode::Triangles => corners / 3,
                Mode::TriangleStrip | Mode::TriangleFan => corners.saturating_sub(2),
                _ => 0,
            };
            vertices = vertices.saturating_add(v.saturating_mul(times));
            triangles = triangles.saturating_add(t.saturating_mul(times));
        }
    }
    if vertices > limits.vertices {
        return Err(over(
            format!("its meshes draw {vertices} vertices"),
            limits.vertices,
            "vertices",
        ));
    }
    if triangles > limits.triangles {
        return Err(over(
            format!("its meshes draw {triangles} triangles"),
            limits.triangles,
            "triangles",
        ));
    }
    let bytes: u64 = doc
        .accessors()
        .map(|a| (a.count() as u64).saturating_mul(a.size() as u64))
        .fold(0, u64::saturating_add);
    if bytes > limits.decoded_mb.saturating_mul(1 << 20) {
        return Err(over(
            format!("its accessors hold {} MiB", bytes >> 20),
            format!("{} MiB", limits.decoded_mb),
            "decoded-mb",
        ));
    }
    Ok(())
}

/// How many skins may list one joint node, on average: a character split into a mesh and a
/// skin per part lists its shared joints once per part.
const MAX_SKINS_A_JOINT: usize = 64;

/// Skins, clips and materials within their limits.
fn check_sizes(
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    limits: &Limits,
) -> Result<(), String> {
    // Every joint node of every skin becomes a bone of one skeleton: skins over the same
    // nodes (a character exported as one mesh and skin per part) share their bones, so the
    // nodes are what it costs. (Bones the merge cannot share, one node bound two ways, are
    // counted again once the skeleton is built.) The lists themselves are bounded too: their
    // entries are what the merge walks.
    let mut nodes: Vec<usize> = doc
        .skins()
        .flat_map(|s| s.joints().map(|j| j.index()))
        .collect();
    let entries = nodes.len();
    nodes.sort_unstable();
    nodes.dedup();
    let joints = nodes.len();
    let skins = doc.skins().len();
    if joints > limits.joints {
        return Err(over(
            if skins == 1 {
                format!("its skin has {joints} joints")
            } else {
                format!("its {skins} skins have {joints} joint nodes together")
            },
            limits.joints,
            "joints",
        ));
    }
    if entries > limits.joints.saturating_mul(MAX_SKINS_A_JOINT) {
        return Err(over(
            format!(
                "its {skins} skins list {entries} joints, more than {MAX_SKINS_A_JOINT} a node"
            ),
            limits.joints,
            "joints",
        ));
    }
    // The animation texture holds every frame of every clip: a key at t = 10⁶ s in a 3 KB file
    // would ask for gigabytes of it. (Accessors are checked by now, so reading is safe.)
    let data = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
    let mut total = 0.0f32;
    for anim in doc.animations() {
        let last = anim
            .channels()
            .filter_map(|ch| ch.reader(data).read_inputs())
            .map(|times| times.filter(|t| t.is_finite()).fold(0.0f32, f32::max))
            .fold(0.0f32, f32::max);
        if last > limits.clip_seconds {
            let name = anim
                .name()
                .map_or_else(|| format!("clip{}", anim.index()), str::to_string);
            return Err(over(
                format!("clip '{name}' is {last} s long"),
                format!("{} s", limits.clip_seconds),
                "clip-seconds",
            ));
        }
        total += last;
        if total > limits.clips_seconds {
            return Err(over(
                format!(
                    "its first {} clips are {total} s long together",
                    anim.index() + 1
                ),
                format!("{} s", limits.clips_seconds),
                "clips-seconds",
            ));
        }
    }
    // Plain colours go into one palette texture on import: only textured materials take a
    // texture layer each.
    let materials = doc
        .materials()
        .filter(|m| m.pbr_metallic_roughness().base_color_texture().is_some())
        .count();
    if materials > limits.materials {
        return Err(over(
            format!("has {materials} textured materials"),
            limits.materials,
            "materials",
        ));
    }
    Ok(())
}

/// Everything about the document that can be checked against its buffers before they are
/// read: the node graph, views, accessors and sizes.
pub fn check_document(
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    limits: &Limits,
) -> Result<(), String> {
    check_nodes(doc, limits)?;
    check_views(doc, buffers)?;
    check_accessors(doc, buffers)?;
    check_types(doc)?;
    check_counts(doc)?;
    check_expansion(doc, limits)?;
    check_sizes(doc, buffers, limits)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_are_raised_by_name() {
        let mut l = Limits::default();
        l.set("joints=4096").unwrap();
        l.set(" clip-seconds = 3600").unwrap();
        assert_eq!(l.joints, 4096);
        assert_eq!(l.clip_seconds, 3600.0);
        assert!(
            l.set("bones=3")
                .unwrap_err()
                .contains("joints, clip-seconds")
        );
        assert!(l.set("joints=-1").is_err());
        assert!(l.set("joints=0").is_err());
        assert!(l.set("joints").is_err());
    }
}

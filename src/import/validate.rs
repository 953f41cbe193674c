//! Checks of a glTF file before anything reads its data, and the limits on what a model may
//! ask for.
//!
//! The gltf crate checks that indices refer to things that exist; it does not check that the
//! bytes an accessor reads lie inside its buffer view, that a stride holds an element, or that
//! the node graph is a forest, and some of those reach assertions, endless walks or allocations
//! the size of what a 3 KB file claims. Everything here runs in time linear in the file, before
//! the importer reads any attribute, so that each problem is one line naming what is wrong.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::RwLock;

/// What one model may ask for. Each bound keeps a small hostile file from taking the machine's
/// memory or minutes of baking; a real model past one can raise it (`--limit NAME=VALUE`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Size of the file and of each file it refers to, in MiB.
    pub file_mb: u64,
    /// Nodes in the file.
    pub nodes: usize,
    /// Joints of one skin (and bones of the merged skeleton).
    pub joints: usize,
    /// Length of one clip in seconds (the animation texture holds 30 frames a second of it).
    pub clip_seconds: f32,
    /// Textured materials (each is a layer of the material texture array at every level of
    /// detail; plain colours share one, see [`super::palette`]).
    pub materials: usize,
    /// Width or height of one texture image, in texels.
    pub texture_side: u32,
}

impl Limits {
    pub const DEFAULT: Limits = Limits {
        file_mb: 1024,
        nodes: 100_000,
        joints: 1024,
        clip_seconds: 600.0,
        materials: 256,
        texture_side: 8192,
    };

    /// The names `--limit` takes, with what each bounds.
    pub const NAMES: [(&'static str, &'static str); 6] = [
        (
            "file-mb",
            "size of a model file and of each file it refers to, MiB",
        ),
        ("nodes", "nodes in a file"),
        ("joints", "joints of a skin"),
        ("clip-seconds", "length of a clip"),
        ("materials", "textured materials of a model"),
        ("texture-side", "width or height of a texture image"),
    ];

    /// Applies one `NAME=VALUE` (see [`Limits::NAMES`]).
    pub fn set(&mut self, assignment: &str) -> Result<(), String> {
        let names = || {
            Self::NAMES
                .iter()
                .map(|(n, _)| *n)
                .collect::<Vec<_>>()
                .join(", ")
        };
        let (name, value) = assignment
            .split_once('=')
            .ok_or_else(|| format!("'{assignment}' is not NAME=VALUE (names: {})", names()))?;
        let number = || -> Result<u64, String> {
            value
                .trim()
                .parse::<u64>()
                .ok()
                .filter(|&v| v > 0)
                .ok_or_else(|| format!("limit {name}: '{value}' is not a positive whole number"))
        };
        match name.trim() {
            "file-mb" => self.file_mb = number()?,
            "nodes" => self.nodes = number()? as usize,
            "joints" => self.joints = number()? as usize,
            "clip-seconds" => self.clip_seconds = number()? as f32,
            "materials" => self.materials = number()? as usize,
            "texture-side" => self.texture_side = number()?.min(u32::MAX as u64) as u32,
            other => return Err(format!("no limit named '{other}' (names: {})", names())),
        }
        Ok(())
    }
}

impl Default for Limits {
    fn default() -> Self {
        Limits::DEFAULT
    }
}

static LIMITS: RwLock<Limits> = RwLock::new(Limits::DEFAULT);

/// The limits every import checks (the defaults, or what `--limit` set).
pub fn limits() -> Limits {
    *LIMITS.read().unwrap_or_else(|e| e.into_inner())
}

/// Sets the limits for the rest of the process (the command line's `--limit`).
pub fn set_limits(limits: Limits) {
    *LIMITS.write().unwrap_or_else(|e| e.into_inner()) = limits;
}

/// "…; the limit is N (--limit NAME=M raises it)".
fn over(what: String, limit: impl std::fmt::Display, name: &str) -> String {
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
    Ok(())
}

/// `%XX` escapes of a relative URI decoded, as glTF asks; `None` where they do not make UTF-8.
fn percent_decoded(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// The file an external URI names, relative to `base`; `Ok(None)` for a `data:` URI.
fn external_file(uri: &str, base: &Path) -> Result<Option<PathBuf>, String> {
    if uri.starts_with("data:") {
        return Ok(None);
    }
    let path = if let Some(rest) = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
    {
        PathBuf::from(rest)
    } else if uri.contains(':') {
        return Err(format!(
            "refers to '{uri}', a kind of URI lodlab cannot read"
        ));
    } else {
        let decoded = percent_decoded(uri)
            .ok_or_else(|| format!("refers to '{uri}', which is not a valid URI"))?;
        base.join(decoded)
    };
    Ok(Some(path))
}

/// Every file the document refers to (buffers and images) is a regular file within the size
/// limit, so that reading it ends; a missing one is named.
pub fn check_sources(doc: &gltf::Document, base: &Path, limits: &Limits) -> Result<(), String> {
    let buffers = doc.buffers().filter_map(|b| match b.source() {
        gltf::buffer::Source::Uri(u) => Some((format!("buffer {}", b.index()), u)),
        gltf::buffer::Source::Bin => None,
    });
    let images = doc.images().filter_map(|i| match i.source() {
        gltf::image::Source::Uri { uri, .. } => Some((format!("image {}", i.index()), uri)),
        gltf::image::Source::View { .. } => None,
    });
    for (what, uri) in buffers.chain(images) {
        let Some(path) = external_file(uri, base).map_err(|e| format!("{what} {e}"))? else {
            continue;
        };
        let meta = std::fs::metadata(&path)
            .map_err(|_| format!("{what} refers to {uri}, which cannot be read"))?;
        if !meta.is_file() {
            return Err(format!(
                "{what} refers to {}, which is not a regular file",
                path.display()
            ));
        }
        if meta.len() > limits.file_mb << 20 {
            return Err(over(
                format!(
                    "{what} refers to {}, {} MiB",
                    path.display(),
                    meta.len() >> 20
                ),
                format!("{} MiB", limits.file_mb),
                "file-mb",
            ));
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

/// Skins, clips and materials within their limits.
fn check_sizes(
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    limits: &Limits,
) -> Result<(), String> {
    for s in doc.skins() {
        let joints = s.joints().len();
        if joints > limits.joints {
            return Err(over(
                format!("skin {} has {joints} joints", s.index()),
                limits.joints,
                "joints",
            ));
        }
    }
    // The animation texture holds every frame of every clip: a key at t = 10⁶ s in a 3 KB file
    // would ask for gigabytes of it. (Accessors are checked by now, so reading is safe.)
    let data = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
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
    check_sizes(doc, buffers, limits)
}

/// The images decoded, each checked against the texture limit from its header before its
/// texels are allocated.
pub fn import_images(
    doc: &gltf::Document,
    base: &Path,
    buffers: &[gltf::buffer::Data],
    limits: &Limits,
) -> Result<Vec<gltf::image::Data>, String> {
    for image in doc.images() {
        let what = format!("image {}", image.index());
        let header: std::borrow::Cow<[u8]> = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let data = &buffers[view.buffer().index()];
                data[view.offset()..view.offset() + view.length()].into()
            }
            gltf::image::Source::Uri { uri, .. } => match external_file(uri, base) {
                Ok(Some(path)) => {
                    let mut head = Vec::new();
                    std::fs::File::open(&path)
                        .and_then(|f| f.take(1 << 16).read_to_end(&mut head))
                        .map_err(|e| format!("{what}: cannot read {}: {e}", path.display()))?;
                    head.into()
                }
                // A data URI's image is inside the file, bounded by its size; the decoder's
                // own allocation limit holds it.
                _ => continue,
            },
        };
        let reader = image::ImageReader::new(std::io::Cursor::new(&header[..]))
            .with_guessed_format()
            .map_err(|e| format!("{what} cannot be read: {e}"))?;
        // A header too short to say is left to the decoder, which says why.
        if let Ok((w, h)) = reader.into_dimensions()
            && w.max(h) > limits.texture_side
        {
            return Err(over(
                format!("{what} is {w}×{h} texels"),
                limits.texture_side,
                "texture-side",
            ));
        }
    }
    doc.images()
        .map(|image| {
            gltf::image::Data::from_source(image.source(), Some(base), buffers).map_err(|e| match e
            {
                gltf::Error::Image(i) => format!("image {} cannot be decoded: {i}", image.index()),
                e => format!("image {} cannot be read: {e}", image.index()),
            })
        })
        .collect()
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

    #[test]
    fn uris_are_percent_decoded_or_refused() {
        assert_eq!(percent_decoded("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decoded("%ff%fe"), None);
        assert_eq!(percent_decoded("cut%2"), None);
        let base = Path::new("/models");
        assert_eq!(
            external_file("tex%20ture.png", base).unwrap(),
            Some(PathBuf::from("/models/tex ture.png"))
        );
        assert_eq!(external_file("data:,abc", base).unwrap(), None);
        assert!(external_file("http://example.com/x.bin", base).is_err());
    }
}

//! The bytes behind a glTF document: its buffers and images, from the binary chunk, `data:`
//! URIs or files beside it, read within the limits of [`super::validate::Limits`].
//!
//! A viewer that opens files from strangers (drag and drop) must not be a way to read other
//! files: by default a URI names a relative path inside the model's folder, after symbolic
//! links are followed, and a regular file, not a pipe that never ends or a device that never
//! stops. A file's size is checked before it is read, and it is read no further than the
//! limit; a buffer shorter than its `byteLength` is refused before it is padded. An image's
//! size is read from its header (wherever the header puts it: a JPEG's frame may come after
//! megabytes of EXIF) before its texels are allocated, and an image is decoded once however
//! many materials use it.

use super::validate::{Limits, over};
use crate::model::Rgba8Image;
use base64::Engine;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

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

/// What a URI names: the bytes of a `data:` URI, or a file.
enum Named {
    Data(Vec<u8>),
    File(PathBuf),
}

/// What `uri` names, relative to `base` (the model's folder), under the folder policy of
/// `limits`.
fn resolve(uri: &str, base: &Path, limits: &Limits) -> Result<Named, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (kind, payload) = rest
            .split_once(',')
            .ok_or_else(|| "has a data: URI without a comma".to_string())?;
        if !kind.ends_with(";base64") {
            return Err("has a data: URI that is not base64 (glTF wants base64)".into());
        }
        return base64::engine::general_purpose::STANDARD
            .decode(payload.trim())
            .map(Named::Data)
            .map_err(|e| format!("has a data: URI that is not valid base64: {e}"));
    }
    let outside = |why: &str| {
        format!(
            "refers to '{uri}', outside the model's folder ({why}); --allow-outside-files \
             reads it"
        )
    };
    let path = if let Some(rest) = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
    {
        if !limits.outside_files {
            return Err(outside("a file: URI"));
        }
        PathBuf::from(
            percent_decoded(rest)
                .ok_or_else(|| format!("refers to '{uri}', which is not a valid URI"))?,
        )
    } else if uri.contains(':') {
        return Err(format!(
            "refers to '{uri}', a kind of URI lodlab cannot read"
        ));
    } else {
        let decoded = percent_decoded(uri)
            .ok_or_else(|| format!("refers to '{uri}', which is not a valid URI"))?;
        let relative = Path::new(&decoded);
        if !limits.outside_files {
            if relative.is_absolute() {
                return Err(outside("an absolute path"));
            }
            if relative.components().any(|c| c == Component::ParentDir) {
                return Err(outside("it climbs out with '..'"));
            }
        }
        base.join(relative)
    };
    if !limits.outside_files {
        // Symbolic links followed: where the file really is must lie in the real folder.
        let real = std::fs::canonicalize(&path)
            .map_err(|e| format!("refers to {uri}, which cannot be read: {}", io(&e)))?;
        let home = std::fs::canonicalize(if base.as_os_str().is_empty() {
            Path::new(".")
        } else {
            base
        })
        .map_err(|e| format!("its folder cannot be read: {}", io(&e)))?;
        if !real.starts_with(&home) {
            return Err(outside("a symbolic link leads out of it"));
        }
    }
    Ok(Named::File(path))
}

fn io(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        std::io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => e.to_string(),
    }
}

/// A regular file read whole (the error says what is wrong with it, without its name), its size
/// checked against `file-mb` before reading, and read no
/// further than that (a file that grows while it is read is cut there and refused).
pub fn read_regular(path: &Path, limits: &Limits) -> Result<Vec<u8>, String> {
    let cannot = |e: std::io::Error| format!("cannot be read: {}", io(&e));
    // Before opening: opening a FIFO blocks until something writes to it.
    let meta = std::fs::metadata(path).map_err(cannot)?;
    if !meta.is_file() {
        return Err("is not a regular file (a device, pipe, socket or folder)".into());
    }
    let most = limits.file_mb.saturating_mul(1 << 20);
    let too_big = |len: u64| {
        over(
            format!("is {} MiB", len >> 20),
            format!("{} MiB", limits.file_mb),
            "file-mb",
        )
    };
    if meta.len() > most {
        return Err(too_big(meta.len()));
    }
    let file = std::fs::File::open(path).map_err(cannot)?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(most + 1)
        .read_to_end(&mut bytes)
        .map_err(cannot)?;
    if bytes.len() as u64 > most {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

/// The bytes a URI names.
pub fn read_uri(uri: &str, base: &Path, limits: &Limits) -> Result<Vec<u8>, String> {
    match resolve(uri, base, limits)? {
        Named::Data(bytes) => Ok(bytes),
        Named::File(path) => read_regular(&path, limits)
            .map_err(|e| format!("refers to {}, which {e}", path.display())),
    }
}

/// Every file the document names is one the folder policy allows and a regular file, checked
/// before anything is read (so that a bad image is found before buffers are loaded).
pub fn check_uris(doc: &gltf::Document, base: &Path, limits: &Limits) -> Result<(), String> {
    let buffers = doc.buffers().filter_map(|b| match b.source() {
        gltf::buffer::Source::Uri(u) => Some((format!("buffer {}", b.index()), u)),
        gltf::buffer::Source::Bin => None,
    });
    let images = doc.images().filter_map(|i| match i.source() {
        gltf::image::Source::Uri { uri, .. } => Some((format!("image {}", i.index()), uri)),
        gltf::image::Source::View { .. } => None,
    });
    for (what, uri) in buffers.chain(images) {
        if uri.starts_with("data:") {
            continue;
        }
        if let Named::File(path) = resolve(uri, base, limits).map_err(|e| format!("{what} {e}"))? {
            let meta = std::fs::metadata(&path)
                .map_err(|e| format!("{what} refers to {uri}, which cannot be read: {}", io(&e)))?;
            if !meta.is_file() {
                return Err(format!(
                    "{what} refers to {}, which is not a regular file (a device, pipe, socket \
                     or folder)",
                    path.display()
                ));
            }
        }
    }
    Ok(())
}

/// The data of every buffer: the binary chunk, a `data:` URI or a file, each at least its
/// `byteLength` long (checked before the 4-byte padding glTF readers add).
pub fn read_buffers(
    doc: &gltf::Document,
    base: &Path,
    mut blob: Option<Vec<u8>>,
    limits: &Limits,
) -> Result<Vec<gltf::buffer::Data>, String> {
    let mut out = Vec::with_capacity(doc.buffers().len());
    for buffer in doc.buffers() {
        let what = format!("buffer {}", buffer.index());
        let mut data = match buffer.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| format!("{what} refers to a binary chunk that is missing"))?,
            gltf::buffer::Source::Uri(uri) => {
                read_uri(uri, base, limits).map_err(|e| format!("{what} {e}"))?
            }
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "{what} is truncated: expected {} bytes, found {}",
                buffer.length(),
                data.len()
            ));
        }
        while !data.len().is_multiple_of(4) {
            data.push(0);
        }
        out.push(gltf::buffer::Data(data));
    }
    Ok(out)
}

/// The image of every texture a material's base colour samples (`None` for images no such
/// material uses), decoded once each to RGBA8, their sizes checked from their headers against
/// `texture-side`, and their texels, once per material, against `texture-mb`, before any is
/// decoded.
pub fn read_images(
    doc: &gltf::Document,
    base: &Path,
    buffers: &[gltf::buffer::Data],
    limits: &Limits,
) -> Result<Vec<Option<Rgba8Image>>, String> {
    // How many textured materials use each image.
    let mut uses = vec![0u64; doc.images().len()];
    for m in doc.materials() {
        if let Some(info) = m.pbr_metallic_roughness().base_color_texture() {
            uses[info.texture().source().index()] += 1;
        }
    }
    let mut encoded: Vec<Option<Vec<u8>>> = Vec::with_capacity(uses.len());
    let mut texels = 0u64;
    for image in doc.images() {
        let i = image.index();
        let what = format!("image {i}");
        if uses[i] == 0 {
            encoded.push(None);
            continue;
        }
        let bytes = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let data = &buffers[view.buffer().index()];
                data[view.offset()..view.offset() + view.length()].to_vec()
            }
            gltf::image::Source::Uri { uri, .. } => {
                read_uri(uri, base, limits).map_err(|e| format!("{what} {e}"))?
            }
        };
        let (w, h) = reader(&bytes)
            .and_then(|r| r.into_dimensions().map_err(|e| e.to_string()))
            .map_err(|e| format!("{what} cannot be read: {e}"))?;
        if w.max(h) > limits.texture_side {
            return Err(over(
                format!("{what} is {w}×{h} texels"),
                limits.texture_side,
                "texture-side",
            ));
        }
        texels += w as u64 * h as u64 * uses[i];
        encoded.push(Some(bytes));
    }
    let most = limits.texture_mb.saturating_mul(1 << 20);
    if texels.saturating_mul(4) > most {
        return Err(over(
            format!(
                "its textured materials' images decode to {} MiB",
                texels.saturating_mul(4) >> 20
            ),
            format!("{} MiB", limits.texture_mb),
            "texture-mb",
        ));
    }
    encoded
        .into_iter()
        .enumerate()
        .map(|(i, bytes)| {
            bytes
                .map(|b| decode(&b, limits).map_err(|e| format!("image {i} {e}")))
                .transpose()
        })
        .collect()
}

fn reader(bytes: &[u8]) -> Result<image::ImageReader<std::io::Cursor<&[u8]>>, String> {
    image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())
}

/// One image decoded to RGBA8, the decoder held to the limits too (a header that lies about
/// the size is caught where the decoder allocates).
fn decode(bytes: &[u8], limits: &Limits) -> Result<Rgba8Image, String> {
    let mut r = reader(bytes).map_err(|e| format!("cannot be read: {e}"))?;
    if r.format().is_none() {
        return Err("is not a PNG or JPEG image".into());
    }
    let mut bounds = image::Limits::default();
    bounds.max_image_width = Some(limits.texture_side);
    bounds.max_image_height = Some(limits.texture_side);
    bounds.max_alloc = Some(limits.texture_mb.saturating_mul(1 << 20).max(1 << 20));
    r.limits(bounds);
    let img = r.decode().map_err(|e| format!("cannot be decoded: {e}"))?;
    let rgba = img.into_rgba8();
    if rgba.width() == 0 || rgba.height() == 0 {
        return Err("is empty".into());
    }
    Ok(Rgba8Image {
        width: rgba.width(),
        height: rgba.height(),
        pixels: rgba.into_raw(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris_are_percent_decoded_or_refused() {
        assert_eq!(percent_decoded("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decoded("%ff%fe"), None);
        assert_eq!(percent_decoded("cut%2"), None);
        let limits = Limits {
            outside_files: true,
            ..Limits::DEFAULT
        };
        let base = Path::new("/models");
        match resolve("tex%20ture.png", base, &limits).unwrap() {
            Named::File(p) => assert_eq!(p, PathBuf::from("/models/tex ture.png")),
            Named::Data(_) => panic!("a file"),
        }
        match resolve("data:application/octet-stream;base64,AAEC", base, &limits).unwrap() {
            Named::Data(d) => assert_eq!(d, vec![0, 1, 2]),
            Named::File(_) => panic!("data"),
        }
        assert!(resolve("http://example.com/x.bin", base, &limits).is_err());
    }

    #[test]
    fn only_files_inside_the_folder_by_default() {
        let dir = tempfile::tempdir().unwrap();
        let inside = dir.path().join("model");
        std::fs::create_dir(&inside).unwrap();
        std::fs::write(inside.join("a.bin"), [1u8; 8]).unwrap();
        std::fs::write(dir.path().join("b.bin"), [2u8; 8]).unwrap();
        std::os::unix::fs::symlink(dir.path().join("b.bin"), inside.join("out.bin")).unwrap();
        let strict = Limits::DEFAULT;
        let open = Limits {
            outside_files: true,
            ..Limits::DEFAULT
        };
        assert_eq!(read_uri("a.bin", &inside, &strict).unwrap(), vec![1u8; 8]);
        for uri in ["../b.bin", "out.bin", "/etc/passwd", "file:///etc/passwd"] {
            let e = read_uri(uri, &inside, &strict).unwrap_err();
            assert!(e.contains("outside the model's folder"), "{uri}: {e}");
        }
        assert_eq!(read_uri("../b.bin", &inside, &open).unwrap(), vec![2u8; 8]);
        assert_eq!(read_uri("out.bin", &inside, &open).unwrap(), vec![2u8; 8]);
        let e = read_uri("/dev/zero", &inside, &open).unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
    }
}

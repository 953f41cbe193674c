//! What gltfpack (meshoptimizer's glTF optimiser) writes, made readable: `EXT_meshopt_compression`
//! buffer views are decoded, and `KHR_mesh_quantization` is taken off the required extensions
//! (the importer reads quantised attributes itself, see `read_floats` in `super::gltf`).
//!
//! The gltf crate refuses a file whose `extensionsRequired` names an extension it does not
//! know, and cannot load a compressed view's fallback buffer (it has no data). So a file that
//! uses either extension is rewritten before the crate reads it: every buffer the file loads
//! (its binary chunk, data URIs, files beside it) and every decoded view go into one binary
//! chunk, the views are pointed into it, and the fallback buffers are dropped.
//!
//! `EXT_meshopt_compression` (Khronos glTF extension registry, vendor extensions): a view's
//! extension names the compressed bytes (`buffer`, `byteOffset`, `byteLength`), what they
//! decode to (`count` elements of `byteStride` bytes), the codec (`mode`: `ATTRIBUTES`,
//! `TRIANGLES` or `INDICES`) and a filter applied after it (`OCTAHEDRAL`, `QUATERNION`,
//! `EXPONENTIAL` or none). The meshopt crate's bindings decode them.

use super::container::{glb, split};
use super::validate::{Limits, over};
use serde_json::Value;
use std::path::Path;

const MESHOPT: &str = "EXT_meshopt_compression";
const QUANTIZATION: &str = "KHR_mesh_quantization";

/// Whether the document (its JSON) uses an extension this module unpacks.
pub fn needs_unpacking(json: &Value) -> bool {
    let names = |key: &str| {
        json.get(key)
            .and_then(Value::as_array)
            .is_some_and(|a| a.iter().any(|e| e == MESHOPT || e == QUANTIZATION))
    };
    names("extensionsUsed") || names("extensionsRequired")
}

fn is_fallback(buffer: &Value) -> bool {
    buffer["extensions"][MESHOPT]["fallback"] == true
}

fn field(v: &Value, key: &str, what: &str) -> Result<usize, String> {
    v.get(key)
        .and_then(Value::as_u64)
        .map(|x| x as usize)
        .ok_or_else(|| format!("{what} has no valid {key}"))
}

/// Decodes one compressed view (its `EXT_meshopt_compression` object `ext`) from `data`, the
/// bytes of the buffer it names.
/// The web build has no meshoptimizer (C++) to decode with.
#[cfg(target_arch = "wasm32")]
fn decode(_: &Value, _: &[u8], what: &str) -> Result<Vec<u8>, String> {
    Err(format!(
        "{what}: EXT_meshopt_compression needs meshoptimizer, which the web build does not have"
    ))
}

#[cfg(not(target_arch = "wasm32"))]
fn decode(ext: &Value, data: &[u8], what: &str) -> Result<Vec<u8>, String> {
    let offset = ext.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
    let length = field(ext, "byteLength", what)?;
    let stride = field(ext, "byteStride", what)?;
    let count = field(ext, "count", what)?;
    let src = offset
        .checked_add(length)
        .and_then(|end| data.get(offset..end))
        .ok_or_else(|| format!("{what}: compressed bytes lie past the end of their buffer"))?;
    let size = count
        .checked_mul(stride)
        .filter(|&s| s <= 1 << 30 && stride > 0 && stride <= 256)
        .ok_or_else(|| format!("{what}: {count} elements of {stride} bytes is out of range"))?;
    let mut out = vec![0u8; size];
    let mode = ext.get("mode").and_then(Value::as_str).unwrap_or("");
    // SAFETY: `out` holds exactly `count` elements of `stride` bytes, the size every decoder
    // below is told; the decoders read `src` within its length and check its contents.
    let code = unsafe {
        let dst = out.as_mut_ptr().cast();
        match mode {
            "ATTRIBUTES" if stride.is_multiple_of(4) => meshopt::ffi::meshopt_decodeVertexBuffer(
                dst,
                count,
                stride,
                src.as_ptr(),
                src.len(),
            ),
            "TRIANGLES" if stride == 2 || stride == 4 => {
                meshopt::ffi::meshopt_decodeIndexBuffer(dst, count, stride, src.as_ptr(), src.len())
            }
            "INDICES" if stride == 2 || stride == 4 => meshopt::ffi::meshopt_decodeIndexSequence(
                dst,
                count,
                stride,
                src.as_ptr(),
                src.len(),
            ),
            _ => {
                return Err(format!(
                    "{what}: mode {mode:?} with byteStride {stride} is not valid"
                ));
            }
        }
    };
    if code != 0 {
        return Err(format!(
            "{what}: the compressed data is corrupt (meshopt error {code})"
        ));
    }
    let filter = ext.get("filter").and_then(Value::as_str).unwrap_or("NONE");
    // SAFETY: as above; each filter rewrites `count` elements of `stride` bytes in place, and
    // the strides are the ones the extension allows each filter.
    unsafe {
        let buf = out.as_mut_ptr().cast();
        match (filter, stride) {
            ("NONE", _) => {}
            ("OCTAHEDRAL", 4 | 8) => meshopt::ffi::meshopt_decodeFilterOct(buf, count, stride),
            ("QUATERNION", 8) => meshopt::ffi::meshopt_decodeFilterQuat(buf, count, stride),
            ("EXPONENTIAL", s) if s.is_multiple_of(4) => {
                meshopt::ffi::meshopt_decodeFilterExp(buf, count, stride)
            }
            _ => {
                return Err(format!(
                    "{what}: filter {filter:?} with byteStride {stride} is not valid"
                ));
            }
        }
    }
    Ok(out)
}

/// `bytes` (a `.glb` or `.gltf` at `base`'s folder) rewritten as a `.glb` that the gltf crate
/// reads: compressed views decoded, every buffer in one binary chunk, the two extensions off
/// the required list. Images the file names by URI stay where they are (read from `base`).
///
/// Its buffers are read as every import reads them ([`super::sources::read_buffers`]: inside
/// the model's folder, regular files, within `file-mb`), and what the views decode to counts
/// against `decoded-mb` before each is decoded (200 views may all name one small stream).
pub fn unpack(bytes: &[u8], base: &Path, limits: &Limits) -> Result<Vec<u8>, String> {
    let (mut json, bin) = split(bytes)?;
    if !json.is_object() {
        return Err("its JSON is not an object".into());
    }
    let buffers: Vec<Value> = json["buffers"].as_array().cloned().unwrap_or_default();
    // Load every buffer with data through the gltf crate (binary chunk, data URIs, files):
    // a document of the buffers alone, the fallback buffers left out.
    let kept: Vec<usize> = (0..buffers.len())
        .filter(|&i| !is_fallback(&buffers[i]))
        .collect();
    let only_buffers = serde_json::json!({
        "asset": { "version": "2.0" },
        "buffers": kept.iter().map(|&i| buffers[i].clone()).collect::<Vec<_>>(),
    });
    let loaded = if kept.is_empty() {
        Vec::new()
    } else {
        let shell = glb(&only_buffers, bin.unwrap_or_default())?;
        let doc = gltf::Gltf::from_slice_without_validation(&shell)
            .map_err(|e| format!("its buffers cannot be read ({e})"))?;
        super::sources::check_uris(&doc.document, base, limits)?;
        super::sources::read_buffers(&doc.document, base, doc.blob, limits)?
    };
    let mut data: Vec<Option<&[u8]>> = vec![None; buffers.len()];
    for (k, &i) in kept.iter().enumerate() {
        data[i] = loaded.get(k).map(|d| &d.0[..]);
    }
    // One chunk: each kept buffer, then each decoded view, every start 4-byte aligned.
    let mut chunk: Vec<u8> = Vec::new();
    let mut start = vec![0usize; buffers.len()];
    for &i in &kept {
        while !chunk.len().is_multiple_of(4) {
            chunk.push(0);
        }
        start[i] = chunk.len();
        chunk.extend_from_slice(data[i].unwrap_or_default());
    }
    // What every compressed view decodes to, together, before any is decoded: 200 views may
    // all name one small stream.
    let most = limits.decoded_mb.saturating_mul(1 << 20);
    let mut decoded_bytes = 0u64;
    for (v, view) in json
        .get("bufferViews")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .enumerate()
    {
        if let Some(ext) = view.get("extensions").and_then(|e| e.get(MESHOPT)) {
            let what = format!("bufferViews[{v}]");
            let claimed =
                (field(ext, "count", &what)? as u64)
                    .saturating_mul(field(ext, "byteStride", &what)? as u64);
            decoded_bytes = decoded_bytes.saturating_add(claimed);
        }
    }
    if decoded_bytes > most {
        return Err(over(
            format!("its compressed views decode to {} MiB", decoded_bytes >> 20),
            format!("{} MiB", limits.decoded_mb),
            "decoded-mb",
        ));
    }
    if let Some(views) = json.get_mut("bufferViews").and_then(Value::as_array_mut) {
        for (v, view) in views.iter_mut().enumerate() {
            let what = format!("bufferViews[{v}]");
            if !view.is_object() {
                return Err(format!("{what} is not an object"));
            }
            if let Some(ext) = view["extensions"].get(MESHOPT).cloned() {
                let b = field(&ext, "buffer", &what)?;
                let src = data
                    .get(b)
                    .copied()
                    .flatten()
                    .ok_or_else(|| format!("{what}: its compressed buffer {b} has no data"))?;
                let decoded = decode(&ext, src, &what)?;
                while !chunk.len().is_multiple_of(4) {
                    chunk.push(0);
                }
                view["buffer"] = 0.into();
                view["byteOffset"] = chunk.len().into();
                view["byteLength"] = decoded.len().into();
                chunk.extend_from_slice(&decoded);
                if let Some(e) = view["extensions"].as_object_mut() {
                    e.remove(MESHOPT);
                }
            } else {
                let b = field(view, "buffer", &what)?;
                if data.get(b).copied().flatten().is_none() {
                    return Err(format!("{what} refers to buffer {b}, which has no data"));
                }
                let offset = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
                view["buffer"] = 0.into();
                view["byteOffset"] = (start[b] + offset).into();
            }
        }
    }
    while chunk.is_empty() || !chunk.len().is_multiple_of(4) {
        chunk.push(0);
    }
    json["buffers"] = serde_json::json!([{ "byteLength": chunk.len() }]);
    for key in ["extensionsUsed", "extensionsRequired"] {
        // `get_mut`, not indexing: indexing a missing key inserts a null, which the gltf
        // crate then refuses as a list that is not one.
        // KHR_mesh_quantization stays in extensionsUsed: the importer reads quantised
        // attributes itself, and allows unnormalised integers only where it is named.
        if let Some(list) = json.get_mut(key).and_then(Value::as_array_mut) {
            list.retain(|e| e != MESHOPT && (e != QUANTIZATION || key == "extensionsUsed"));
        }
    }
    glb(&json, chunk)
}

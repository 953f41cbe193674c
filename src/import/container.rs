//! The glTF container: a `.glb`'s JSON and binary chunks taken apart and put back together,
//! for the passes that rewrite a file's JSON before the gltf crate reads it (unpacking
//! gltfpack's extensions, dropping untargeted animation channels).

use serde_json::Value;
use std::borrow::Cow;

/// The JSON chunk and the binary chunk of a `.glb`, or the whole file as JSON.
pub fn split(bytes: &[u8]) -> Result<(Value, Option<Vec<u8>>), String> {
    if bytes.starts_with(b"glTF") {
        let glb = gltf::binary::Glb::from_slice(bytes).map_err(|e| format!("invalid GLB ({e})"))?;
        let json = serde_json::from_slice(&glb.json).map_err(|e| format!("invalid JSON ({e})"))?;
        Ok((json, glb.bin.map(Cow::into_owned)))
    } else {
        let json = serde_json::from_slice(bytes).map_err(|e| format!("invalid JSON ({e})"))?;
        Ok((json, None))
    }
}

/// A `.glb` of `json` and the binary chunk `bin`.
pub fn glb(json: &Value, bin: Vec<u8>) -> Result<Vec<u8>, String> {
    glb_of(json, Some(bin))
}

/// A `.glb` of `json` and a binary chunk, if any.
pub fn glb_of(json: &Value, bin: Option<Vec<u8>>) -> Result<Vec<u8>, String> {
    let mut j = serde_json::to_vec(json).map_err(|e| e.to_string())?;
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let length = 12 + 8 + j.len() + bin.as_ref().map_or(0, |b| 8 + b.len());
    gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: u32::try_from(length).map_err(|_| "larger than 4 GB".to_string())?,
        },
        json: Cow::Owned(j),
        bin: bin.map(Cow::Owned),
    }
    .to_vec()
    .map_err(|e| e.to_string())
}

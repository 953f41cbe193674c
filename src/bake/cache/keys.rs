//! Every version and key of the bake cache, in one place. A cache file's name and header carry
//! a key: a hash of what the bake was made from (the source file's bytes, the options) and of
//! the versions of the code that made it. Bump a version here whenever what it covers changes
//! its output, and every file it made is looked for under another key and rebuilt.

use crate::bake::character::lod::LodOptions;
use crate::bake::character::simplify::Method;
use crate::bake::character::simplify::expectation::MIN_SAMPLES;
use serde::Serialize;

/// The cache file's encoding and the progressive-mesh levels' bake.
pub const FORMAT_VERSION: u32 = 10;
/// A tree's chain of billboard-cloud levels and its impostor
/// (`bake::foliage::billboard::chain`).
pub const CHAIN_VERSION: u32 = 28;
/// Which of a tree's levels each size draws when ordered by cost
/// (`bake::foliage::billboard::chain::order`).
pub const ORDER_VERSION: u32 = 3;
/// A layout's forest patches (`bake::foliage::patch`).
pub const PATCH_VERSION: u32 = 4;
/// A character's animated impostor (`bake::impostor::animated`).
pub const IMPOSTOR_VERSION: u32 = 5;
/// Where a character's impostor joins a method's chain (`bake::impostor::placement`, as the
/// runtime places it).
pub const PLACEMENT_VERSION: u32 = 4;

/// How a method is spelled in cache file names: its name with '+' spelled '-'
/// (`rest-pose`, `as`, `as-is`).
pub fn file_kind(method: Method) -> String {
    method.name().replace('+', "-")
}

/// The cache key of a bake: the source's hash, the method, the parameters and the format.
pub fn levels_key(source: &[u8; 32], method: Method, options: &LodOptions) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    h.update(b"lodlab skinned lods");
    h.update(&FORMAT_VERSION.to_le_bytes());
    h.update(&(MIN_SAMPLES as u64).to_le_bytes());
    h.update(source);
    h.update(method.name().as_bytes());
    // Every field, so that no two option sets share a key.
    h.update(&options.base_error.to_bits().to_le_bytes());
    h.update(&options.floor_triangles.to_le_bytes());
    let budgets = options.budgets.as_deref();
    h.update(&[budgets.is_some() as u8]);
    h.update(&(budgets.map_or(0, <[u32]>::len) as u64).to_le_bytes());
    for t in budgets.unwrap_or_default() {
        h.update(&t.to_le_bytes());
    }
    *h.finalize().as_bytes()
}

/// A hash of a model's source: the file's bytes, the files `--clips` adds clips from
/// ([`crate::import::extra_clips`]), and for a `.gltf` the external files its buffers and
/// images name (those that exist; a missing one fails the import anyway).
///
/// Files are read as the import reads them ([`crate::import::sources::read_regular`]): regular
/// files within the limits and the folder policy, so that a FIFO or `/dev/zero` named by a
/// buffer does not hang the hash before the import can refuse it.
pub fn source_hash(path: &std::path::Path) -> std::io::Result<[u8; 32]> {
    source_hash_of(&crate::import::Source::File(path.to_path_buf()))
}

/// [`source_hash`] of a model named on the command line: a built-in's bytes, or a file's.
pub fn source_hash_of(source: &crate::import::Source) -> std::io::Result<[u8; 32]> {
    let limits = crate::import::validate::limits();
    let read = |s: &crate::import::Source| {
        s.read(&limits)
            .map_err(|e| std::io::Error::other(format!("{}: {e}", s.label().display())))
    };
    let bytes = read(source)?;
    let mut h = blake3::Hasher::new();
    h.update(&bytes);
    // Clips added from other files (`--clips`) change what the metric is estimated from.
    for file in crate::import::extra_clips() {
        let file = crate::import::source(&file.to_string_lossy());
        h.update(b"clips");
        h.update(&read(&file)?);
    }
    if let Ok(json) = serde_json::from_slice::<serde_json::Value>(&bytes) {
        let dir = source.folder();
        for list in ["buffers", "images"] {
            for item in json[list].as_array().into_iter().flatten() {
                if let Some(uri) = item["uri"].as_str().filter(|u| !u.starts_with("data:"))
                    && let Ok(extra) = crate::import::sources::read_uri(uri, dir, &limits)
                {
                    h.update(uri.as_bytes());
                    h.update(&extra);
                }
            }
        }
    }
    Ok(*h.finalize().as_bytes())
}

/// The key of a tree's chain: its source's hash, the chain options (`options`, encoded as the
/// cache encodes) and the versions.
pub fn chain_key(source: &[u8; 32], options: &impl Serialize) -> Result<[u8; 32], String> {
    let mut h = blake3::Hasher::new();
    h.update(b"lodlab tree chain");
    h.update(&FORMAT_VERSION.to_le_bytes());
    h.update(&CHAIN_VERSION.to_le_bytes());
    h.update(source);
    // Options that failed to encode must not share a key with others: no fallback.
    h.update(&postcard::to_stdvec(options).map_err(|e| format!("encoding chain options: {e}"))?);
    Ok(*h.finalize().as_bytes())
}

/// The key of a tree's cost order: its chain's key, the order's version and the options.
pub fn order_key(source: &[u8; 32], options: &impl Serialize) -> Result<[u8; 32], String> {
    let mut h = blake3::Hasher::new();
    h.update(b"lodlab tree order");
    h.update(&chain_key(source, options)?);
    h.update(&ORDER_VERSION.to_le_bytes());
    Ok(*h.finalize().as_bytes())
}

/// The key of a character's animated impostor: its source's hash, its views, frames and cell
/// size, and the versions.
pub fn impostor_key(source: &[u8; 32], views: u32, frames: u32, cell: u32) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    h.update(b"lodlab animated impostor");
    h.update(&FORMAT_VERSION.to_le_bytes());
    h.update(&IMPOSTOR_VERSION.to_le_bytes());
    h.update(source);
    for n in [views, frames, cell] {
        h.update(&n.to_le_bytes());
    }
    *h.finalize().as_bytes()
}

/// The key of an impostor's placement in one method's levels: the levels' key, the
/// impostor's, the pixel tolerance it was placed for and the version.
pub fn placement_key(levels: &[u8; 32], impostor: &[u8; 32], tolerance_px: f32) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    h.update(b"lodlab impostor placement");
    h.update(&PLACEMENT_VERSION.to_le_bytes());
    h.update(levels);
    h.update(impostor);
    h.update(&tolerance_px.to_le_bytes());
    *h.finalize().as_bytes()
}

/// The key of a layout's forest patches: every tree model's chain key, the trees as they
/// stand (`layout`, encoded as the cache encodes), the tolerance they are placed for and the
/// versions.
pub fn patch_key(
    chains: &[[u8; 32]],
    layout: &impl Serialize,
    tolerance_px: f32,
) -> Result<[u8; 32], String> {
    let mut h = blake3::Hasher::new();
    h.update(b"lodlab forest patches");
    h.update(&FORMAT_VERSION.to_le_bytes());
    h.update(&PATCH_VERSION.to_le_bytes());
    for c in chains {
        h.update(c);
    }
    h.update(&postcard::to_stdvec(layout).map_err(|e| format!("encoding the layout: {e}"))?);
    h.update(&tolerance_px.to_le_bytes());
    Ok(*h.finalize().as_bytes())
}

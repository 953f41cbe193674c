//! Every version and key of the bake cache, in one place. A cache file's name and header carry
//! a key: a hash of what the bake was made from (the source file's bytes, the options) and of
//! the versions of the code that made it. Bump a version here whenever what it covers changes
//! its output, and every file it made is looked for under another key and rebuilt.

use serde::Serialize;

/// The cache file's encoding and the progressive-mesh levels' bake.
pub const FORMAT_VERSION: u32 = 12;
/// A tree's chain of billboard-cloud levels and its impostor
/// (`bake::foliage::billboard::chain`).
pub const CHAIN_VERSION: u32 = 28;
/// Which of a tree's levels each size draws when ordered by cost
/// (`bake::foliage::billboard::chain::order`).
pub const ORDER_VERSION: u32 = 3;
/// A layout's forest patches (`bake::foliage::patch`).
pub const PATCH_VERSION: u32 = 4;
/// A character's animated impostor (`bake::impostor::animated`).
pub const IMPOSTOR_VERSION: u32 = 7;
/// Where a character's impostor joins a method's chain (`bake::impostor::placement`, as the
/// runtime places it).
pub const PLACEMENT_VERSION: u32 = 5;

/// What a cache file holds: the word its file names carry and the version of the code that
/// makes it, in one place, so that a kind is neither misspelt nor versioned apart from its
/// name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CacheKind {
    /// A character's progressive-mesh levels by one method (the method's name, '+' spelled
    /// '-': `rest-pose`, `as`, `as-is`).
    Levels(&'static str),
    /// A tree's chain of billboard-cloud levels and its impostor.
    Clouds,
    /// Which of a tree's levels each size draws when ordered by cost.
    Order,
    /// A character's animated impostor.
    Impostor,
    /// Where a character's impostor joins a method's chain.
    Placement,
    /// A layout's forest patches.
    Patches,
}

impl CacheKind {
    /// The word in its files' names.
    pub fn name(self) -> String {
        match self {
            CacheKind::Levels(method) => method.replace('+', "-"),
            CacheKind::Clouds => "clouds".into(),
            CacheKind::Order => "order".into(),
            CacheKind::Impostor => "impostor".into(),
            CacheKind::Placement => "placement".into(),
            CacheKind::Patches => "patches".into(),
        }
    }

    /// The version of what makes it, which its keys hold.
    pub fn version(self) -> u32 {
        match self {
            CacheKind::Levels(_) => FORMAT_VERSION,
            CacheKind::Clouds => CHAIN_VERSION,
            CacheKind::Order => ORDER_VERSION,
            CacheKind::Impostor => IMPOSTOR_VERSION,
            CacheKind::Placement => PLACEMENT_VERSION,
            CacheKind::Patches => PATCH_VERSION,
        }
    }
}

/// The key of a tree's chain: its source's hash, the chain options (`options`, encoded as the
/// cache encodes) and the versions.
pub fn chain_key(source: &[u8; 32], options: &impl Serialize) -> Result<[u8; 32], String> {
    let mut h = blake3::Hasher::new();
    h.update(b"lodlab tree chain");
    h.update(&FORMAT_VERSION.to_le_bytes());
    h.update(&CacheKind::Clouds.version().to_le_bytes());
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
    h.update(&CacheKind::Order.version().to_le_bytes());
    Ok(*h.finalize().as_bytes())
}

/// The key of a character's animated impostor: its source's hash, its views, frames and cell
/// size, and the versions.
pub fn impostor_key(source: &[u8; 32], views: u32, frames: u32, cell: u32) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    h.update(b"lodlab animated impostor");
    h.update(&FORMAT_VERSION.to_le_bytes());
    h.update(&CacheKind::Impostor.version().to_le_bytes());
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
    h.update(&CacheKind::Placement.version().to_le_bytes());
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
    h.update(&CacheKind::Patches.version().to_le_bytes());
    for c in chains {
        h.update(c);
    }
    h.update(&postcard::to_stdvec(layout).map_err(|e| format!("encoding the layout: {e}"))?);
    h.update(&tolerance_px.to_le_bytes());
    Ok(*h.finalize().as_bytes())
}

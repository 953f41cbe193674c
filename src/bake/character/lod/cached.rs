//! A character's levels through the cache: the cache stores them, and they are baked here on
//! a miss ([`load_or_bake`]). Their key and file name are made here too, so that the cache
//! knows nothing of characters.

use super::{LodOptions, SkinnedLods, bake_lods};
use crate::bake::cache::keys::CacheKind;
use crate::bake::cache::{LodCache, Origin};
use crate::bake::character::simplify::Method;
use crate::bake::character::simplify::expectation::MIN_SAMPLES;
use crate::model::Model;
use std::path::PathBuf;

/// The cache key of a bake: the source's hash, the method, the parameters and the format.
pub fn levels_key(source: &[u8; 32], method: Method, options: &LodOptions) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    h.update(b"lodlab skinned lods");
    h.update(&CacheKind::Levels(method.name()).version().to_le_bytes());
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

/// The cache file of `model`'s levels by `method` under `key`.
pub fn levels_path(cache: &LodCache, model: &str, method: Method, key: &[u8; 32]) -> PathBuf {
    cache.file(model, CacheKind::Levels(method.name()), key)
}

/// The cache file of `model`'s levels by `method` with `options` (its source hashing to
/// `source`), and the key inside it.
pub fn levels_file(
    cache: &LodCache,
    model: &str,
    source: &[u8; 32],
    method: Method,
    options: &LodOptions,
) -> (PathBuf, [u8; 32]) {
    let key = levels_key(source, method, options);
    (levels_path(cache, model, method, &key), key)
}

/// `model`'s levels by `method` from `cache` if a good file is there, else baked now and
/// stored.
pub fn load_or_bake(
    cache: &LodCache,
    model: &Model,
    source: &[u8; 32],
    method: Method,
    options: &LodOptions,
    progress: &(dyn Fn(f32) + Sync),
) -> (SkinnedLods, Origin) {
    let (path, key) = levels_file(cache, &model.name, source, method, options);
    let Ok(found) = cache.load_or_build(&path, &key, || {
        Ok::<_, std::convert::Infallible>(bake_lods(model, method, options, progress))
    });
    found
}

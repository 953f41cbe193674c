//! Cache files held in memory rather than on a disk, and the record of what was read.
//!
//! - The web build has no file system: its page fetches the cache files `lodlab web` put
//!   beside it and hands them in with [`preload`]; [`LodCache::load`](super::LodCache::load)
//!   looks a file up here, by its name, before the disk.
//! - `lodlab web` learns which files a scene reads by building it with [`record_reads`] on,
//!   then copies those ([`take_reads`]): exactly what the page will ask for.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, RwLock};

static PRELOADED: RwLock<BTreeMap<String, Arc<[u8]>>> = RwLock::new(BTreeMap::new());
static READS: Mutex<Option<BTreeSet<PathBuf>>> = Mutex::new(None);

/// Holds `bytes` as the cache file named `name` (its file name, no folder) for the rest of
/// the process.
pub fn preload(name: &str, bytes: Vec<u8>) {
    PRELOADED
        .write()
        .unwrap_or_else(|e| e.into_inner())
        .insert(name.to_string(), bytes.into());
}

/// The preloaded bytes of the cache file at `path` (by its name), if any.
pub(super) fn preloaded(path: &Path) -> Option<Arc<[u8]>> {
    let name = path.file_name()?.to_str()?;
    PRELOADED
        .read()
        .unwrap_or_else(|e| e.into_inner())
        .get(name)
        .cloned()
}

/// From now on, notes every cache file read with a good bake in it, or written.
pub fn record_reads() {
    *READS.lock().unwrap_or_else(|e| e.into_inner()) = Some(BTreeSet::new());
}

/// The files read since [`record_reads`], in name order; recording stops.
pub fn take_reads() -> Vec<PathBuf> {
    READS
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .take()
        .map(|s| s.into_iter().collect())
        .unwrap_or_default()
}

pub(super) fn note_read(path: &Path) {
    if let Some(set) = READS.lock().unwrap_or_else(|e| e.into_inner()).as_mut() {
        set.insert(path.to_path_buf());
    }
}

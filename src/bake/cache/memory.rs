//! Cache files held in memory rather than on a disk, and the record of what was read: a part
//! of one [`LodCache`](super::LodCache), shared by its clones.
//!
//! - The web build has no file system: its page fetches the cache files `lodlab web` put
//!   beside it and hands them to the scene's cache with [`MemoryFiles::preload`];
//!   [`LodCache::load`](super::LodCache::load) looks a file up here, by its name, before the
//!   disk.
//! - `lodlab web` learns which files a scene reads by building it over a cache with
//!   [`MemoryFiles::record_reads`] on, then copies those ([`MemoryFiles::take_reads`]):
//!   exactly what the page will ask for.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, RwLock};

/// A cache's files in memory and its record of reads (see the module's documentation).
#[derive(Debug, Default)]
pub struct MemoryFiles {
    preloaded: RwLock<BTreeMap<String, Arc<[u8]>>>,
    reads: Mutex<Option<BTreeSet<PathBuf>>>,
}

impl MemoryFiles {
    /// Holds `bytes` as the cache file named `name` (its file name, no folder).
    pub fn preload(&self, name: &str, bytes: Vec<u8>) {
        self.preloaded
            .write()
            .unwrap_or_else(|e| e.into_inner())
            .insert(name.to_string(), bytes.into());
    }

    /// The preloaded bytes of the cache file at `path` (by its name), if any.
    pub(super) fn preloaded(&self, path: &Path) -> Option<Arc<[u8]>> {
        let name = path.file_name()?.to_str()?;
        self.preloaded
            .read()
            .unwrap_or_else(|e| e.into_inner())
            .get(name)
            .cloned()
    }

    /// From now on, notes every cache file read with a good bake in it, or written.
    pub fn record_reads(&self) {
        *self.reads.lock().unwrap_or_else(|e| e.into_inner()) = Some(BTreeSet::new());
    }

    /// The files read since [`Self::record_reads`], in name order; recording stops.
    pub fn take_reads(&self) -> Vec<PathBuf> {
        self.reads
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
            .map(|s| s.into_iter().collect())
            .unwrap_or_default()
    }

    pub(super) fn note_read(&self, path: &Path) {
        if let Some(set) = self
            .reads
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .as_mut()
        {
            set.insert(path.to_path_buf());
        }
    }
}

//! The on-disk cache of level-of-detail bakes, so the viewer starts fast.
//!
//! A store: one file per bake (a character's progressive-mesh levels, a tree's chain of
//! billboard-cloud levels, an impostor, …). The cache knows no bake; each subject asks it for
//! its entry and bakes on a miss itself ([`LodCache::load_or_build`]). Its name carries a key: a hash of the source
//! file's bytes (and of the external buffers a `.gltf` names), the bake parameters and
//! [`FORMAT_VERSION`]. A changed model or parameter therefore looks for another file. Inside,
//! a header repeats the version and the key and holds a hash of the payload, so a file from
//! another version, cut short or damaged is recognised, reported in one line and rebuilt,
//! never trusted.
//!
//! Layout: `LODLABLC` | format version (u32 LE) | key (32 bytes) | payload hash (32 bytes) |
//! payload length (u64 LE) | payload (postcard-encoded, then LZ4-compressed: billboard-cloud
//! atlases are mostly empty texels).

pub mod keys;
pub mod memory;

use keys::FORMAT_VERSION;
use serde::Serialize;
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"LODLABLC";
const HEADER: usize = 8 + 4 + 32 + 32 + 8;

/// Where cached bakes live: a folder, and the files held in memory before it (see
/// [`memory`]; shared by a cache's clones).
#[derive(Clone, Debug)]
pub struct LodCache {
    pub dir: PathBuf,
    pub memory: std::sync::Arc<memory::MemoryFiles>,
}

/// What looking a bake up found.
#[derive(Debug)]
pub enum Lookup<T> {
    Hit(Box<T>),
    Miss,
    /// A file was there but cannot be used; the reason is one line.
    Unusable(String),
}

impl LodCache {
    /// `dir`, or the platform cache folder's `lodlab/` (`$XDG_CACHE_HOME/lodlab`,
    /// `~/.cache/lodlab` on Linux), or the system temporary folder if there is none.
    pub fn new(dir: Option<PathBuf>) -> LodCache {
        let dir = dir.unwrap_or_else(|| {
            dirs::cache_dir()
                .unwrap_or_else(|| {
                    // A page has no folders: its files are all preloaded (see `memory`).
                    if cfg!(target_arch = "wasm32") {
                        PathBuf::new()
                    } else {
                        std::env::temp_dir()
                    }
                })
                .join("lodlab")
        });
        LodCache {
            dir,
            memory: Default::default(),
        }
    }

    /// The cache file for a bake of `kind` of a model, under `key`.
    pub fn file(&self, model: &str, kind: keys::CacheKind, key: &[u8; 32]) -> PathBuf {
        let kind = kind.name();
        let name: String = model
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .take(40)
            .collect();
        let hex: String = key[..8].iter().map(|b| format!("{b:02x}")).collect();
        self.dir.join(format!("{name}-{kind}-{hex}.lods"))
    }

    /// Whether a file for the bake at `path` is there (preloaded, or on the disk); whether it
    /// is good is found out when it is read.
    pub fn has(&self, path: &Path) -> bool {
        self.memory.preloaded(path).is_some() || path.is_file()
    }

    /// Reads a cached bake, checking its version, key and integrity: from memory where the
    /// file was preloaded (see [`memory`]), else from the disk.
    pub fn load<T: DeserializeOwned>(&self, path: &Path, key: &[u8; 32]) -> Lookup<T> {
        let found = match self.memory.preloaded(path) {
            Some(bytes) => decode(&bytes, key),
            None => self.load_file(path, key),
        };
        if matches!(found, Lookup::Hit(_)) {
            self.memory.note_read(path);
        }
        found
    }

    fn load_file<T: DeserializeOwned>(&self, path: &Path, key: &[u8; 32]) -> Lookup<T> {
        // Only a regular file, and no more of it than a cache file can hold: a FIFO would
        // block the read for ever, a link to /dev/zero fill the memory.
        let meta = match std::fs::metadata(path) {
            Ok(m) => m,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Lookup::Miss,
            Err(e) => return Lookup::Unusable(format!("cannot read it ({e})")),
        };
        if !meta.is_file() {
            return Lookup::Unusable("not a regular file (a device, pipe or folder)".into());
        }
        let most = (MAX_UNPACKED + HEADER) as u64;
        if meta.len() > most {
            return Lookup::Unusable(format!(
                "{} MiB, more than a cache file holds",
                meta.len() >> 20
            ));
        }
        let mut bytes = Vec::with_capacity(meta.len() as usize);
        let read = std::fs::File::open(path).and_then(|f| {
            std::io::Read::read_to_end(&mut std::io::Read::take(f, most), &mut bytes)
        });
        if let Err(e) = read {
            return Lookup::Unusable(format!("cannot read it ({e})"));
        }
        decode(&bytes, key)
    }

    /// Writes a bake atomically (see [`crate::atomic`]).
    pub fn store<T: Serialize>(
        &self,
        path: &Path,
        key: &[u8; 32],
        value: &T,
    ) -> anyhow::Result<()> {
        std::fs::create_dir_all(&self.dir)
            .map_err(|e| anyhow::anyhow!("{}: cannot create: {e}", self.dir.display()))?;
        let payload = postcard::to_stdvec(value)
            .map_err(|e| anyhow::anyhow!("{}: cannot encode: {e}", path.display()))?;
        let payload = lz4_flex::compress_prepend_size(&payload);
        crate::atomic::write(path, &encode(key, &payload))?;
        self.memory.note_read(path);
        Ok(())
    }
}

/// The most a cache file's payload may unpack to: its own length prefix is not trusted with
/// more (a damaged one would ask for gigabytes).
const MAX_UNPACKED: usize = 1 << 31;

/// A cache file's bytes decoded: its magic, version, key, length and checksum checked before
/// the payload is unpacked and decoded. What a fuzzer feeds (see `fuzz/`).
pub fn decode<T: DeserializeOwned>(bytes: &[u8], key: &[u8; 32]) -> Lookup<T> {
    if bytes.len() < HEADER || &bytes[..8] != MAGIC {
        return Lookup::Unusable("not a lodlab cache file".into());
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version != FORMAT_VERSION {
        return Lookup::Unusable(format!(
            "written in cache format {version}, this lodlab uses {FORMAT_VERSION}"
        ));
    }
    if &bytes[12..44] != key {
        return Lookup::Unusable("made from another source or other parameters".into());
    }
    let len = u64::from_le_bytes(bytes[76..84].try_into().expect("8 bytes"));
    let payload = &bytes[HEADER..];
    if payload.len() as u64 != len {
        return Lookup::Unusable(format!(
            "truncated: {} of {len} payload bytes",
            payload.len()
        ));
    }
    if blake3::hash(payload).as_bytes() != &bytes[44..76] {
        return Lookup::Unusable("corrupt: its checksum does not match".into());
    }
    let unpacked = payload
        .get(..4)
        .map(|n| u32::from_le_bytes(n.try_into().expect("4 bytes")) as usize);
    // LZ4 expands at most 255 times.
    if unpacked.is_none_or(|n| n > MAX_UNPACKED || n > payload.len().saturating_mul(255)) {
        return Lookup::Unusable("corrupt: its unpacked size is impossible".into());
    }
    let Ok(payload) = lz4_flex::decompress_size_prepended(payload) else {
        return Lookup::Unusable("cannot decompress it".into());
    };
    match postcard::from_bytes::<T>(&payload) {
        Ok(value) => Lookup::Hit(Box::new(value)),
        Err(e) => Lookup::Unusable(format!("cannot decode it ({e})")),
    }
}

/// A cache file's bytes around `payload` (already compressed), as [`LodCache::store`] writes
/// them.
pub fn encode(key: &[u8; 32], payload: &[u8]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(HEADER + payload.len());
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    bytes.extend_from_slice(key);
    bytes.extend_from_slice(blake3::hash(payload).as_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(payload);
    bytes
}

/// Where a bake came from.
#[derive(Clone, Debug, PartialEq)]
pub enum Origin {
    Cache,
    /// Baked now; `warning` says why a cache file there was not used, or could not be written.
    Baked {
        warning: Option<String>,
    },
}

impl LodCache {
    /// What the file at `path` holds under `key` if it is good, else `build()`'s result,
    /// stored there. A file that cannot be used or written is a warning, never an error.
    pub fn load_or_build<T: Serialize + DeserializeOwned, E>(
        &self,
        path: &Path,
        key: &[u8; 32],
        build: impl FnOnce() -> Result<T, E>,
    ) -> Result<(T, Origin), E> {
        let mut warning = None;
        match self.load(path, key) {
            Lookup::Hit(value) => {
                log::debug!("{}: cache hit", path.display());
                return Ok((*value, Origin::Cache));
            }
            Lookup::Miss => log::debug!("{}: not in the cache; baking", path.display()),
            Lookup::Unusable(why) => {
                log::debug!("{}: unusable ({why}); baking", path.display());
                warning = Some(format!("{}: {why}; rebuilding it", path.display()));
            }
        }
        let start = web_time::Instant::now();
        let value = build()?;
        log::debug!(
            "{}: built in {:.2} s; storing it",
            path.display(),
            start.elapsed().as_secs_f64()
        );
        if let Err(e) = self.store(path, key, &value) {
            // The error names the file and the system's reason (a full disk, say).
            let w = format!("cannot write the cache: {e:#}");
            warning = Some(match warning {
                Some(first) => format!("{first}; {w}"),
                None => w,
            });
        }
        Ok((value, Origin::Baked { warning }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_payload_claiming_gigabytes_is_refused_before_it_is_unpacked() {
        let key = [7u8; 32];
        // A valid envelope (the checksum matches) around LZ4 data whose size prefix says 2 GiB.
        let mut payload = (u32::MAX / 2).to_le_bytes().to_vec();
        payload.extend_from_slice(&[0x10, b'a']);
        match decode::<Vec<u8>>(&encode(&key, &payload), &key) {
            Lookup::Unusable(why) => assert!(why.contains("impossible"), "{why}"),
            other => panic!("{other:?}"),
        }
        // A round trip still reads back.
        let value = vec![1u32, 2, 3];
        let packed = lz4_flex::compress_prepend_size(&postcard::to_stdvec(&value).unwrap());
        match decode::<Vec<u32>>(&encode(&key, &packed), &key) {
            Lookup::Hit(v) => assert_eq!(*v, value),
            other => panic!("{other:?}"),
        }
    }
}

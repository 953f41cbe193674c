//! Levels of detail for the front ends: baked on first use (or read from the cache), in parallel
//! over models, either at once (`shot`) or on a background thread while the viewer keeps drawing
//! (the panel shows the progress).

use crate::bake::cache::LodCache;
use crate::bake::lod::SkinnedLods;
use crate::bake::lod_pack::LodPack;
use crate::bake::simplify::Method;
use crate::model::Model;
use rayon::prelude::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError, channel};

/// A model as loaded, kept for baking its levels later.
#[derive(Clone, Debug)]
pub struct LevelSource {
    pub model: Model,
    /// Hash of its source file (the cache key).
    pub hash: [u8; 32],
}

/// The level options the front ends bake with: the defaults of `lodlab bake`, so that a
/// `lodlab bake MODEL` beforehand fills the same cache entries.
pub fn runtime_options(model: &Model) -> crate::bake::lod::LodOptions {
    super::bake::lod_options(model, DEFAULT_BAKE_TOLERANCE_PX, None)
}

/// `lodlab bake --tolerance` default: the error bound of LOD 1 in pixels.
pub const DEFAULT_BAKE_TOLERANCE_PX: f32 = 0.5;

/// What baking one model by a method gave: its packed levels, or nothing for a tree (trees get
/// billboard-cloud levels instead, see [`crate::app::tree_levels`]).
pub type Baked = Option<Result<LodPack, String>>;

/// Is this model a tree (foliage cut out with alpha)?
pub fn is_tree(model: &Model) -> bool {
    model
        .materials
        .iter()
        .any(crate::bake::billboard::is_cut_out)
}

/// The levels of every model by `method`, in model order, from the cache or baked now.
/// `progress(i, f)` reports model i's fraction done. Cache warnings go to `warn`.
pub fn bake_all(
    sources: &[LevelSource],
    method: Method,
    cache: &LodCache,
    progress: &(dyn Fn(usize, f32) + Sync),
    warn: &(dyn Fn(String) + Sync),
) -> Vec<Baked> {
    sources
        .par_iter()
        .enumerate()
        .map(|(i, s)| {
            if is_tree(&s.model) {
                progress(i, 1.0);
                return None;
            }
            let options = runtime_options(&s.model);
            let (lods, origin) =
                cache.load_or_bake(&s.model, &s.hash, method, &options, &|f| progress(i, f));
            if let crate::bake::cache::Origin::Baked { warning: Some(w) } = origin {
                warn(w);
            }
            progress(i, 1.0);
            Some(pack(&lods))
        })
        .collect()
}

fn pack(lods: &SkinnedLods) -> Result<LodPack, String> {
    LodPack::from_levels(&lods.levels).map_err(|e| format!("{} {}: {e}", lods.model, lods.method))
}

/// A bake running on its own thread.
pub struct BackgroundBake {
    pub method: Method,
    /// Per model, progress in thousandths.
    progress: Arc<Vec<AtomicU32>>,
    result: Receiver<Vec<Baked>>,
}

/// What polling a background bake found.
pub enum Poll {
    Running,
    Done(Vec<Baked>),
    /// The thread died without an answer.
    Failed,
}

impl BackgroundBake {
    pub fn start(sources: Vec<LevelSource>, method: Method, cache: LodCache) -> BackgroundBake {
        let progress: Arc<Vec<AtomicU32>> =
            Arc::new((0..sources.len()).map(|_| AtomicU32::new(0)).collect());
        let (tx, rx) = channel();
        let p = progress.clone();
        std::thread::spawn(move || {
            let report = |i: usize, f: f32| {
                p[i].store((f.clamp(0.0, 1.0) * 1000.0) as u32, Ordering::Relaxed);
            };
            let warn = |w: String| eprintln!("warning: {w}");
            let packs = bake_all(&sources, method, &cache, &report, &warn);
            let _ = tx.send(packs);
        });
        BackgroundBake {
            method,
            progress,
            result: rx,
        }
    }

    /// Fraction done over all models.
    pub fn fraction(&self) -> f32 {
        let n = self.progress.len().max(1) as f32;
        self.progress
            .iter()
            .map(|p| p.load(Ordering::Relaxed) as f32 / 1000.0)
            .sum::<f32>()
            / n
    }

    pub fn poll(&self) -> Poll {
        match self.result.try_recv() {
            Ok(packs) => Poll::Done(packs),
            Err(TryRecvError::Empty) => Poll::Running,
            Err(TryRecvError::Disconnected) => Poll::Failed,
        }
    }
}

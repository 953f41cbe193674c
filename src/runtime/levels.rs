//! Levels of detail for the front ends: baked on first use (or read from the cache), in parallel
//! over models, either at once (`shot`) or on a background thread while the viewer keeps drawing
//! (the panel shows the progress). Characters get progressive-mesh levels by a method; trees
//! get their billboard-cloud chain, the same for every method, built with the first one.

use crate::bake::CharacterBake;
use crate::bake::billboard::chain::{ChainOptions, load_or_build_chain};
use crate::bake::billboard::is_tree;
use crate::bake::cache::{LodCache, Origin};
use crate::bake::lod::SkinnedLods;
use crate::bake::lod_pack::LodPack;
use crate::bake::simplify::Method;
use crate::model::Model;
use crate::render::Gpu;
use crate::render::atlas::AtlasRasterizer;
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
    crate::bake::lod::lod_options(model, DEFAULT_BAKE_TOLERANCE_PX, None)
}

/// `lodlab bake --tolerance` default: the error bound of LOD 1 in pixels.
pub const DEFAULT_BAKE_TOLERANCE_PX: f32 = 0.5;

/// A model's levels as baked.
pub enum Levels {
    /// A character's progressive-mesh levels by one method.
    Pack(LodPack),
    /// A tree's billboard-cloud chain (level 0 the tree itself), with levels 1… baked for
    /// the GPU (on the baking thread: their atlases' mipmaps take a while).
    Tree {
        chain: Vec<crate::bake::billboard::chain::TreeLevel>,
        bakes: Vec<CharacterBake>,
    },
}

/// What baking one model by a method gave: its levels, or `None` for a model skipped (it had
/// what it needs).
pub type Baked = Option<Result<Levels, String>>;

/// The levels of every model, in model order, from the cache or baked now: characters' by
/// `method`, trees' chains cut by `chain`; models whose `skip` is set are left out.
/// `progress(i, f)` reports model i's fraction done. Cache warnings go to `warn`.
#[allow(clippy::too_many_arguments)]
pub fn bake_all(
    gpu: &Gpu,
    sources: &[LevelSource],
    skip: &[bool],
    method: Method,
    chain: &ChainOptions,
    cache: &LodCache,
    progress: &(dyn Fn(usize, f32) + Sync),
    warn: &(dyn Fn(String) + Sync),
) -> Vec<Baked> {
    sources
        .par_iter()
        .enumerate()
        .map(|(i, s)| {
            if skip.get(i).copied().unwrap_or(false) {
                progress(i, 1.0);
                return None;
            }
            let (levels, origin) = if is_tree(&s.model) {
                match tree_levels(gpu, cache, s, chain, &|f| progress(i, f)) {
                    Ok((levels, origin)) => (Ok(levels), origin),
                    Err(e) => (Err(format!("{}: {e:#}", s.model.name)), Origin::Cache),
                }
            } else {
                let options = runtime_options(&s.model);
                let (lods, origin) =
                    cache.load_or_bake(&s.model, &s.hash, method, &options, &|f| progress(i, f));
                (pack(&lods).map(Levels::Pack), origin)
            };
            if let Origin::Baked { warning: Some(w) } = origin {
                warn(w);
            }
            progress(i, 1.0);
            Some(levels)
        })
        .collect()
}

/// A tree's chain from the cache or built now, its levels 1… baked for the GPU.
fn tree_levels(
    gpu: &Gpu,
    cache: &LodCache,
    s: &LevelSource,
    opts: &ChainOptions,
    progress: &(dyn Fn(f32) + Sync),
) -> anyhow::Result<(Levels, Origin)> {
    let (chain, origin) = load_or_build_chain(
        &AtlasRasterizer::new(gpu),
        cache,
        &s.model,
        &s.hash,
        opts,
        progress,
    )?;
    let bakes = chain[1..]
        .par_iter()
        .map(|l| CharacterBake::with_motion(&l.cloud.model, l.cloud.motion.as_ref()))
        .collect::<Result<Vec<_>, String>>()
        .map_err(anyhow::Error::msg)?;
    Ok((Levels::Tree { chain, bakes }, origin))
}

fn pack(lods: &SkinnedLods) -> Result<LodPack, String> {
    LodPack::from_levels(&lods.levels).map_err(|e| format!("{} {}: {e}", lods.model, lods.method))
}

/// A bake running on its own thread.
pub struct BackgroundBake {
    pub method: Method,
    /// How the trees' chains it builds are cut.
    pub chain: ChainOptions,
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
    pub fn start(
        gpu: Gpu,
        sources: Vec<LevelSource>,
        skip: Vec<bool>,
        method: Method,
        chain: ChainOptions,
        cache: LodCache,
    ) -> BackgroundBake {
        let progress: Arc<Vec<AtomicU32>> =
            Arc::new((0..sources.len()).map(|_| AtomicU32::new(0)).collect());
        let (tx, rx) = channel();
        let p = progress.clone();
        std::thread::spawn(move || {
            let report = |i: usize, f: f32| {
                p[i].store((f.clamp(0.0, 1.0) * 1000.0) as u32, Ordering::Relaxed);
            };
            let warn = |w: String| eprintln!("warning: {w}");
            let packs = bake_all(
                &gpu, &sources, &skip, method, &chain, &cache, &report, &warn,
            );
            let _ = tx.send(packs);
        });
        BackgroundBake {
            method,
            chain,
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

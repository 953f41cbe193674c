//! Levels of detail for the front ends: baked on first use (or read from the cache), in parallel
//! over models, either at once (`shot`) or on a background thread while the viewer keeps drawing
//! (the panel shows the progress). Characters get progressive-mesh levels by a method; trees
//! get their billboard-cloud chain, the same for every method, built with the first one.

use crate::bake::cache::keys::CacheKind;
use crate::bake::cache::{LodCache, Origin};
use crate::bake::character::lod::LodLevel;
use crate::bake::character::lod::SkinnedLods;
use crate::bake::character::simplify::Method;
use crate::bake::foliage::billboard::chain::{
    ChainOptions, chain_file, load_or_build_chain, order_file,
};
use crate::bake::foliage::billboard::is_tree;
use crate::bake::gpu_data::drawable::Drawable;
use crate::bake::gpu_data::lod_pack::LodPack;
use crate::bake::gpu_products::{MeasureColour, MeasureImpostor};
use crate::bake::impostor::animated::{AnimatedImpostor, ImpostorOptions, load_or_bake_impostor};
use crate::bake::impostor::placement::{self, Placement};
use crate::model::Model;
use crate::render::Gpu;
use crate::render::atlas::AtlasRasterizer;
use rayon::prelude::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError, channel};

/// The measurements a bake of levels draws on the GPU: a tree chain's colour errors and a
/// character impostor's fit beside its levels. The `measure` layer makes them (its
/// `GpuMeasurer`); the front end hands them in.
pub trait Measurer: Sync {
    /// The colour seam of a tree chain's bake, drawing on `gpu`.
    fn colour<'g>(&self, gpu: &'g Gpu) -> Box<dyn MeasureColour + 'g>;

    /// What placing `impostor` among `levels` (finest first) of `model` measures; `full` is
    /// the model's full-detail bake.
    fn impostor<'a>(
        &self,
        gpu: &'a Gpu,
        model: &'a Model,
        full: &'a Drawable,
        levels: &'a [LodLevel],
        impostor: &'a AnimatedImpostor,
    ) -> anyhow::Result<Box<dyn MeasureImpostor + 'a>>;
}

/// A model as loaded, kept for baking its levels later.
#[derive(Clone, Debug)]
pub struct LevelSource {
    pub model: Model,
    /// Hash of its source file (the cache key).
    pub hash: [u8; 32],
    /// How a character's animated impostor is baked with its levels (`None`: it gets none;
    /// trees ignore it).
    pub impostor: Option<ImpostorOptions>,
    /// Triangle budgets its levels are cut by (`None`: by error; see [`runtime_options`]).
    pub budgets: Option<Vec<u32>>,
}

impl LevelSource {
    /// The options its levels are baked with ([`runtime_options`]).
    pub fn lod_options(&self) -> crate::bake::character::lod::LodOptions {
        runtime_options(&self.model, self.budgets.as_deref())
    }
}

/// The level options the front ends bake with: the defaults of `lodlab bake`, so that a
/// `lodlab bake MODEL` beforehand fills the same cache entries; or, where the command line
/// asked for levels by triangle count (`--levels triangles:N,N,…`: `budgets`), those of
/// `lodlab bake MODEL --triangles N,N,…`, whose cached cut they then read.
pub fn runtime_options(
    model: &Model,
    budgets: Option<&[u32]>,
) -> crate::bake::character::lod::LodOptions {
    crate::bake::character::lod::lod_options(model, DEFAULT_FIRST_ERROR_PX, budgets)
}

/// `lodlab bake --first-error` default: e₁, the error bound of LOD 1 in pixels.
pub const DEFAULT_FIRST_ERROR_PX: f32 = 0.5;

/// A model's levels as baked.
pub enum Levels {
    /// A character's progressive-mesh levels by one method, and its animated impostor where
    /// it has one (the same for every method, placed in each method's chain).
    Pack(Box<LodPack>, Option<ImpostorLevel>),
    /// A character's impostor placed in one method's chain, handed over after its levels
    /// (by [`BackgroundBake`]: its first bake takes longer than the levels); `None` where it
    /// could not be made.
    Impostor(Option<ImpostorLevel>),
    /// A tree's billboard-cloud chain (level 0 the tree itself), with levels 1… baked for
    /// the GPU (on the baking thread: their atlases' mipmaps take a while).
    Tree {
        chain: Vec<crate::bake::foliage::billboard::chain::TreeLevel>,
        bakes: Vec<Drawable>,
    },
}

/// A character's animated impostor and where it joins one method's chain.
pub struct ImpostorLevel {
    pub impostor: Box<AnimatedImpostor>,
    pub placement: Placement,
}

/// What baking one model by a method gave: its levels, or `None` for a model skipped (it had
/// what it needs).
pub type Baked = Option<Result<Levels, String>>;

/// What one call bakes every model's levels with: the device its pictures are drawn on and
/// how they are measured, the cache they are kept in, the method characters' levels are made
/// by and how trees' chains are cut.
#[derive(Clone, Copy)]
pub struct BakeJob<'a> {
    pub gpu: &'a Gpu,
    pub measure: &'a dyn Measurer,
    pub cache: &'a LodCache,
    pub method: Method,
    pub chain: &'a ChainOptions,
}

/// The levels of every model, in model order, from the cache or baked now as `job` says;
/// models whose `skip` is set are left out. `progress(i, f)` reports model i's fraction done.
/// Cache warnings go to `warn`.
pub fn bake_all(
    job: &BakeJob,
    sources: &[LevelSource],
    skip: &[bool],
    progress: &(dyn Fn(usize, f32) + Sync),
    warn: &(dyn Fn(String) + Sync),
) -> Vec<Baked> {
    let done = std::sync::Mutex::new((0..sources.len()).map(|_| None).collect::<Vec<Baked>>());
    // Impostors come after every model's levels (baking them beside the trees' chains made
    // the two fight over the CPU), each joining its character's levels.
    let deliver = |i: usize, baked: Baked| {
        if let Ok(mut d) = done.lock() {
            match (baked, &mut d[i]) {
                (Some(Ok(Levels::Impostor(level))), Some(Ok(Levels::Pack(_, impostor)))) => {
                    *impostor = level;
                }
                // Levels that failed keep their error.
                (Some(Ok(Levels::Impostor(_))), _) => {}
                (baked, slot) => *slot = baked,
            }
        }
    };
    bake_each(job, sources, skip, progress, warn, &deliver);
    done.into_inner().unwrap_or_default()
}

/// [`bake_all`], handing each model's levels to `deliver(i, levels)` as soon as they are
/// ready. Characters go first: their levels take a second or so, a tree's chain much longer,
/// and a viewer shows each as it comes. A character's impostor comes in a second delivery
/// ([`Levels::Impostor`], one for every character that asks for one; the mesh levels stand
/// without it where it fails) after every model's levels, so that its first bake holds back
/// neither its own levels nor the trees' chains.
pub fn bake_each(
    job: &BakeJob,
    sources: &[LevelSource],
    skip: &[bool],
    progress: &(dyn Fn(usize, f32) + Sync),
    warn: &(dyn Fn(String) + Sync),
    deliver: &(dyn Fn(usize, Baked) + Sync),
) {
    let (cache, method) = (job.cache, job.method);
    let mut order: Vec<usize> = (0..sources.len()).collect();
    order.sort_by_key(|&i| is_tree(&sources[i].model));
    // The characters' levels whose impostors are still to come.
    let later: std::sync::Mutex<Vec<(usize, SkinnedLods)>> = Default::default();
    order.par_iter().with_max_len(1).for_each(|&i| {
        let s = &sources[i];
        if skip.get(i).copied().unwrap_or(false) {
            progress(i, 1.0);
            deliver(i, None);
            return;
        }
        let (levels, origin) = if is_tree(&s.model) {
            match tree_levels(job, s, &|f| progress(i, f)) {
                Ok((levels, origin)) => (Ok(levels), origin),
                Err(e) => (Err(format!("{}: {e:#}", s.model.name)), Origin::Cache),
            }
        } else {
            let options = s.lod_options();
            // The levels are the share up to IMPOSTOR_PENDING; what comes after is the
            // impostor's (or, without one, the handing over).
            let (lods, origin) = crate::bake::character::lod::cached::load_or_bake(
                cache,
                &s.model,
                &s.hash,
                method,
                &options,
                &|f| progress(i, f.min(1.0) * IMPOSTOR_PENDING * 0.999),
            );
            if let Origin::Baked { warning: Some(w) } = &origin {
                warn(w.clone());
            }
            if s.impostor.is_some() {
                progress(i, IMPOSTOR_PENDING);
                deliver(
                    i,
                    Some(pack(&s.model, &lods).map(|p| Levels::Pack(Box::new(p), None))),
                );
                if let Ok(mut later) = later.lock() {
                    later.push((i, lods));
                }
                return;
            }
            (
                pack(&s.model, &lods).map(|p| Levels::Pack(Box::new(p), None)),
                Origin::Cache,
            )
        };
        if let Origin::Baked { warning: Some(w) } = origin {
            warn(w);
        }
        progress(i, 1.0);
        deliver(i, Some(levels));
    });
    // The impostors last, once every model's levels (the trees' chains included, which the
    // frame rate needs far more) are in.
    let later = later.into_inner().unwrap_or_default();
    later.par_iter().with_max_len(1).for_each(|(i, lods)| {
        let s = &sources[*i];
        let level = s.impostor.and_then(|options| {
            impostor_level(job, s, lods, &options, &|f| progress(*i, f), warn)
                .map_err(|e| warn(format!("{}: no impostor: {e:#}", s.model.name)))
                .ok()
        });
        progress(*i, 1.0);
        deliver(*i, Some(Ok(Levels::Impostor(level))));
    });
}

/// A character's progress once its levels are handed over and its impostor is to come (read
/// from the cache, or baked where the cache lacks it).
pub const IMPOSTOR_PENDING: f32 = 0.9;
/// A character's progress while its impostor's pages are drawn (a cache miss).
pub const IMPOSTOR_BAKING: f32 = 0.92;
/// A character's progress while where its impostor comes in is measured (a cache miss).
pub const IMPOSTOR_MEASURING: f32 = 0.96;

/// Character `s`'s animated impostor baked with `options` (from the cache or baked now) and
/// its placement in the chain `lods` (likewise), at the default pixel tolerance.
fn impostor_level(
    job: &BakeJob,
    s: &LevelSource,
    lods: &SkinnedLods,
    options: &ImpostorOptions,
    progress: &(dyn Fn(f32) + Sync),
    warn: &(dyn Fn(String) + Sync),
) -> anyhow::Result<ImpostorLevel> {
    let (gpu, measure, cache) = (job.gpu, job.measure, job.cache);
    let raster = AtlasRasterizer::new(gpu);
    // Said before the work, so that a progress line tells drawing pages from reading them.
    let impostor_key = crate::bake::impostor::animated::impostor_key(&s.hash, options);
    if s.hash == [0; 32]
        || !cache.has(&cache.file(&s.model.name, CacheKind::Impostor, &impostor_key))
    {
        progress(IMPOSTOR_BAKING);
    }
    // The full-detail bake, made only where the impostor or its placement is: a warm run
    // reads both from the cache.
    let full = std::sync::OnceLock::new();
    let full = || full.get_or_init(|| Drawable::new(&s.model));
    // The pages draw the body where it stands, moved back by its travel as the runtime moves
    // its sphere (see `bake::gpu_data::root_motion`).
    let travel = |c: usize, t: f32| {
        full()
            .as_ref()
            .map_or(glam::Vec3::ZERO, |f| f.travel_within(c, t))
    };
    let (impostor, origin) =
        load_or_bake_impostor(&raster, cache, &s.model, &s.hash, &travel, *options)?;
    if let Origin::Baked { warning: Some(w) } = origin {
        warn(w);
    }
    let tolerance = crate::scene::LodPolicy::default().tolerance_px;
    let place = || -> anyhow::Result<Placement> {
        progress(IMPOSTOR_MEASURING);
        let start = web_time::Instant::now();
        let full = full().as_ref().map_err(|e| anyhow::anyhow!("{e}"))?;
        let errors: Vec<f32> = lods.levels.iter().map(|l| l.error).collect();
        let height = full.bounds.size().y.max(1e-3);
        let placement = if errors.len() < 2 {
            // Full detail alone: nothing for the impostor to stand for (and no worlds to draw).
            Placement::none(tolerance)
        } else {
            let mut fit = measure.impostor(gpu, &s.model, full, &lods.levels, &impostor)?;
            placement::place(&errors, height, tolerance, 1, &mut *fit)?.0
        };
        log::debug!(
            "{} {}: impostor placed in {:.2} s; measured {:?}",
            s.model.name,
            lods.method,
            start.elapsed().as_secs_f64(),
            placement.measured,
        );
        Ok(placement)
    };
    let placement = if s.hash == [0; 32] {
        place()?
    } else {
        let (_, levels_key) = crate::bake::character::lod::cached::levels_file(
            cache,
            &s.model.name,
            &s.hash,
            lods.method,
            &lods.options,
        );
        let key = crate::bake::cache::keys::placement_key(&levels_key, &impostor_key, tolerance);
        let path = cache.file(&s.model.name, CacheKind::Placement, &key);
        let (placement, origin) = cache.load_or_build(&path, &key, place)?;
        if let Origin::Baked { warning: Some(w) } = origin {
            warn(w);
        }
        placement
    };
    // Said whether placed now or read from the cache: where the impostor comes in is what a
    // user looking at a crowd needs to know.
    let height = crate::bake::character::lod::model_height(&s.model);
    match (placement.epsilon, placement.largest_px(height)) {
        (Some(e), Some(px)) => {
            let replaces = lods.levels.iter().position(|l| l.error >= e);
            log::info!(
                "{} {}: the impostor comes in below {px:.0} px high (error {:.1} mm at \
                 {tolerance} px{}; never larger at a higher tolerance)",
                s.model.name,
                lods.method,
                e * 1e3,
                replaces.map_or(String::new(), |k| format!(", in place of level {k} and up"))
            )
        }
        _ => log::info!(
            "{} {}: no impostor (it beats none of the levels where they come in)",
            s.model.name,
            lods.method
        ),
    }
    Ok(ImpostorLevel {
        impostor: Box::new(impostor),
        placement,
    })
}

/// Whether the cache holds a file for `s`'s levels by `method` (a tree's chain cut as
/// `chain`): loading them then takes a second or two, not a bake. A damaged file is found out
/// when it is read, and rebuilt then.
pub fn cached(cache: &LodCache, s: &LevelSource, method: Method, chain: &ChainOptions) -> bool {
    let name = &s.model.name;
    let path = if is_tree(&s.model) {
        let order = match chain.order {
            crate::bake::foliage::billboard::chain::levels::FoliageOrder::Epsilon => None,
            crate::bake::foliage::billboard::chain::levels::FoliageOrder::Cost => {
                Some(order_file(cache, name, &s.hash, chain))
            }
        };
        match (chain_file(cache, name, &s.hash, chain), order) {
            (Ok((path, _)), None) => path,
            (Ok((path, _)), Some(Ok((order, _)))) if cache.has(&order) => path,
            _ => return false,
        }
    } else {
        crate::bake::character::lod::cached::levels_file(
            cache,
            name,
            &s.hash,
            method,
            &s.lod_options(),
        )
        .0
    };
    cache.has(&path)
}

/// A tree's chain from the cache or built now, its levels 1… baked for the GPU.
fn tree_levels(
    job: &BakeJob,
    s: &LevelSource,
    progress: &(dyn Fn(f32) + Sync),
) -> anyhow::Result<(Levels, Origin)> {
    let (gpu, opts) = (job.gpu, job.chain);
    let (chain, origin) = load_or_build_chain(
        &AtlasRasterizer::new(gpu),
        &*job.measure.colour(gpu),
        job.cache,
        &s.model,
        &s.hash,
        opts,
        progress,
    )?;
    let bakes = chain[1..]
        .par_iter()
        .map(|l| l.cloud.bake())
        .collect::<Result<Vec<_>, String>>()
        .map_err(anyhow::Error::msg)?;
    Ok((Levels::Tree { chain, bakes }, origin))
}

/// `lods` of `model` packed for the GPU, with normal maps for the coarse levels (see
/// [`crate::bake::character::normal_map`]).
fn pack(model: &Model, lods: &SkinnedLods) -> Result<LodPack, String> {
    mapped_pack(model, &lods.levels, &lods.levels)
        .map_err(|e| format!("{} {}: {e}", lods.model, lods.method))
}

/// `levels` (some of `chain`, whose first level is full detail) of `model` packed as the
/// runtime packs them, with their normal maps: [`pack`]'s levels, or one level alone for a
/// metric to draw.
pub(crate) fn mapped_pack(
    model: &Model,
    chain: &[crate::bake::character::lod::LodLevel],
    levels: &[crate::bake::character::lod::LodLevel],
) -> Result<LodPack, String> {
    let rest_bones = crate::bake::character::simplify::SimplifyInput::rest_bones(&model.skeleton);
    let full = &chain.first().ok_or("no levels")?.mesh;
    LodPack::with_normal_maps(
        levels,
        full,
        &rest_bones,
        &model.materials,
        crate::bake::character::normal_map::NORMAL_MAP_SIZE,
    )
}

/// A bake running on its own thread, handing over each model's levels as they are ready.
pub struct BackgroundBake {
    pub method: Method,
    /// How the trees' chains it builds are cut.
    pub chain: ChainOptions,
    /// Per model, progress in thousandths.
    progress: Arc<Vec<AtomicU32>>,
    /// Per model, its name and whether it is a tree; and whether this bake makes its levels.
    models: Vec<(String, bool, bool)>,
    result: Receiver<(usize, Baked)>,
    /// Models not handed over yet.
    pending: usize,
}

/// What polling a background bake found.
pub enum Poll {
    /// These models' levels are ready (maybe none yet); more are to come.
    Running(Vec<(usize, Baked)>),
    /// The last models' levels: the bake is over.
    Done(Vec<(usize, Baked)>),
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
        measure: &'static dyn Measurer,
    ) -> BackgroundBake {
        let progress: Arc<Vec<AtomicU32>> =
            Arc::new((0..sources.len()).map(|_| AtomicU32::new(0)).collect());
        let models = sources
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let making = !skip.get(i).copied().unwrap_or(false);
                (s.model.name.clone(), is_tree(&s.model), making)
            })
            .collect();
        let (tx, rx) = channel();
        let p = progress.clone();
        // One delivery a model, and a second for each character's impostor.
        let pending = sources.len()
            + sources
                .iter()
                .enumerate()
                .filter(|(i, s)| {
                    !skip.get(*i).copied().unwrap_or(false)
                        && !is_tree(&s.model)
                        && s.impostor.is_some()
                })
                .count();
        let work = move || {
            // The bake's draws (atlases, impostor views, colour measurements) go to a device
            // of its own, so that their read-backs do not wait behind the viewer's frames. (The
            // browser opens devices asynchronously only; the page bakes nothing anyway.)
            #[cfg(not(target_arch = "wasm32"))]
            let gpu = gpu.separate().unwrap_or_else(|e| {
                log::warn!("baking on the viewer's device: {e:#}");
                gpu
            });
            let report = |i: usize, f: f32| {
                p[i].store((f.clamp(0.0, 1.0) * 1000.0) as u32, Ordering::Relaxed);
            };
            let warn = |w: String| eprintln!("warning: {w}");
            let tx = std::sync::Mutex::new(tx);
            let deliver = |i: usize, baked: Baked| {
                if let Ok(tx) = tx.lock() {
                    let _ = tx.send((i, baked));
                }
            };
            let job = BakeJob {
                gpu: &gpu,
                measure,
                cache: &cache,
                method,
                chain: &chain,
            };
            bake_each(&job, &sources, &skip, &report, &warn, &deliver);
        };
        #[cfg(not(target_arch = "wasm32"))]
        std::thread::spawn(work);
        // A page has no threads for it: the levels, read from the page's data (never baked
        // there), are taken in before the next frame.
        #[cfg(target_arch = "wasm32")]
        work();
        BackgroundBake {
            method,
            chain,
            progress,
            models,
            result: rx,
            pending,
        }
    }

    /// Fraction done over the models it makes levels for.
    pub fn fraction(&self) -> f32 {
        let making: Vec<f32> = self
            .models
            .iter()
            .zip(self.progress.iter())
            .filter(|((_, _, making), _)| *making)
            .map(|(_, p)| p.load(Ordering::Relaxed) as f32 / 1000.0)
            .collect();
        making.iter().sum::<f32>() / making.len().max(1) as f32
    }

    /// What it is baking now, for a progress bar: `"as+is levels of walker · billboard clouds
    /// of broadleaf, conifer"`, the models begun and not finished (or, before any has begun,
    /// those to come).
    pub fn status(&self) -> String {
        let state: Vec<(&str, bool, u32)> = self
            .models
            .iter()
            .zip(self.progress.iter())
            .filter(|((_, _, making), _)| *making)
            .map(|((name, tree, _), p)| (name.as_str(), *tree, p.load(Ordering::Relaxed)))
            .filter(|&(_, _, p)| p < 1000)
            .collect();
        let begun: Vec<_> = state.iter().filter(|&&(_, _, p)| p > 0).copied().collect();
        let shown = if begun.is_empty() { state } else { begun };
        // A character whose levels are in and whose impostor is read or baked stands at
        // IMPOSTOR_PENDING or beyond.
        let pending = (IMPOSTOR_PENDING * 1000.0) as u32;
        let names = |trees: bool, impostor: bool| {
            shown
                .iter()
                .filter(|&&(_, t, p)| t == trees && (!trees && p >= pending) == impostor)
                .map(|&(n, _, _)| n)
                .collect::<Vec<_>>()
                .join(", ")
        };
        let (characters, impostors, trees) =
            (names(false, false), names(false, true), names(true, false));
        let mut parts = Vec::new();
        if !characters.is_empty() {
            parts.push(format!("{} levels of {characters}", self.method));
        }
        if !impostors.is_empty() {
            parts.push(format!("impostors of {impostors}"));
        }
        if !trees.is_empty() {
            parts.push(format!("billboard clouds of {trees}"));
        }
        if parts.is_empty() {
            format!("{} levels", self.method)
        } else {
            parts.join(" · ")
        }
    }

    pub fn poll(&mut self) -> Poll {
        let mut ready = Vec::new();
        loop {
            match self.result.try_recv() {
                Ok(item) => {
                    self.pending = self.pending.saturating_sub(1);
                    ready.push(item);
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) if self.pending > 0 => return Poll::Failed,
                Err(TryRecvError::Disconnected) => break,
            }
        }
        if self.pending == 0 {
            Poll::Done(ready)
        } else {
            Poll::Running(ready)
        }
    }
}

//! `lodlab bake`: build (or fetch from the cache) the levels of detail of models by several
//! methods at once, in parallel, and print them as a table.

use crate::bake::cache::{LodCache, Origin, source_hash};
use crate::bake::lod::{LodOptions, SkinnedLods};
use crate::bake::simplify::Method;
use crate::error::InputError;
use crate::import::{load_model, source_path};
use crate::model::{Bounds, Model};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::path::PathBuf;

#[derive(Clone, Debug)]
pub struct BakeOptions {
    pub models: Vec<String>,
    pub methods: Vec<Method>,
    /// `e_1` in pixels for a model filling 1000 pixels of height (see [`LodOptions`]).
    pub tolerance_px: f32,
    /// Cut levels by these triangle budgets instead.
    pub budgets: Option<Vec<u32>>,
    pub cache_dir: Option<PathBuf>,
}

/// One model's bake by one method.
#[derive(Debug)]
pub struct Baked {
    pub model: String,
    pub source_triangles: usize,
    pub bones: usize,
    pub lods: SkinnedLods,
    pub from_cache: bool,
}

/// The model's rest-pose height in scene units.
pub fn model_height(model: &Model) -> f32 {
    let root = model.skeleton.root_transform;
    Bounds::of(
        model
            .mesh
            .positions
            .iter()
            .map(|p| root.transform_point3(*p)),
    )
    .map_or(1.0, |b| b.size().y.max(1e-3))
}

/// The level options for a model from the command's options.
pub fn lod_options(model: &Model, tolerance_px: f32, budgets: Option<&[u32]>) -> LodOptions {
    let mut o = LodOptions::from_pixels(tolerance_px, model_height(model));
    o.budgets = budgets.map(<[u32]>::to_vec);
    o
}

/// Loads every model (failing on the first bad one before any work), then bakes every
/// (model, method) pair in parallel with one progress bar each.
pub fn run(opts: &BakeOptions) -> Result<Vec<Baked>, InputError> {
    let mut models = Vec::new();
    for name in &opts.models {
        let model = load_model(name)?;
        let path = source_path(name);
        let hash = source_hash(&path).map_err(|e| InputError::new(&path, e.to_string()))?;
        models.push((model, hash));
    }
    let cache = LodCache::new(opts.cache_dir.clone());
    let bars = MultiProgress::new();
    let style = bar_style();
    let jobs: Vec<(usize, Method, ProgressBar)> = models
        .iter()
        .enumerate()
        .flat_map(|(i, (m, _))| {
            let (bars, style) = (&bars, &style);
            opts.methods.iter().map(move |&method| {
                let bar = bars.add(ProgressBar::new(1000));
                bar.set_style(style.clone());
                bar.set_prefix(format!("{} {}", m.name, method));
                (i, method, bar)
            })
        })
        .collect();
    let results: Vec<Baked> = jobs
        .into_par_iter()
        .map(|(i, method, bar)| {
            let (model, hash) = &models[i];
            let options = lod_options(model, opts.tolerance_px, opts.budgets.as_deref());
            let progress = |f: f32| bar.set_position((f.clamp(0.0, 1.0) * 1000.0) as u64);
            let (lods, origin) = cache.load_or_bake(model, hash, method, &options, &progress);
            let from_cache = origin == Origin::Cache;
            if let Origin::Baked {
                warning: Some(w), ..
            } = &origin
            {
                bars.suspend(|| eprintln!("warning: {w}"));
            }
            bar.finish_with_message(if from_cache {
                "cached".to_string()
            } else {
                format!("{:.2} s", lods.bake_seconds)
            });
            Baked {
                model: model.name.clone(),
                source_triangles: model.mesh.triangle_count(),
                bones: model.skeleton.bone_count(),
                lods,
                from_cache,
            }
        })
        .collect();
    Ok(results)
}

/// The progress bar of one (model, method) job, shared by `bake` and `report`.
pub fn bar_style() -> ProgressStyle {
    ProgressStyle::with_template("{prefix:>18} [{bar:30}] {percent:>3}% {msg}")
        .expect("valid template")
        .progress_chars("=> ")
}

/// The table `lodlab bake` prints: one block per model, one row per level and method.
pub fn table(results: &[Baked]) -> String {
    let mut out = String::new();
    let mut last_model = "";
    for b in results {
        if b.model != last_model {
            last_model = &b.model;
            out += &format!(
                "\n{} ({} triangles, {} bones)\n{:<10} {:>3} {:>9} {:>8} {:>10} {:>12} {:>8}\n",
                b.model,
                b.source_triangles,
                b.bones,
                "method",
                "LOD",
                "triangles",
                "vertices",
                "influences",
                "error (mm)",
                "bake (s)"
            );
        }
        for (k, level) in b.lods.levels.iter().enumerate() {
            let time = match (k, b.from_cache) {
                (0, false) => format!("{:.2}", b.lods.bake_seconds),
                (0, true) => "cached".to_string(),
                _ => String::new(),
            };
            out += &format!(
                "{:<10} {:>3} {:>9} {:>8} {:>10} {:>12.3} {:>8}\n",
                b.lods.method.name(),
                k,
                level.triangles(),
                level.vertices(),
                level.influences(),
                level.error * 1000.0,
                time
            );
        }
    }
    out
}

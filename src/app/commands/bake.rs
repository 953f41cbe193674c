//! `lodlab bake`: build (or fetch from the cache) the levels of detail of models by several
//! methods at once, in parallel, and print them as a table. A tree gets its chain of
//! billboard-cloud levels instead (the same for every method), as the viewer uses it.

use crate::app::cli::BakeArgs;
use std::process::ExitCode;

use crate::bake::cache::{LodCache, Origin};
use crate::bake::character::lod::{
    SharedBake, SkinnedLods, bake_lods_sharing, full_detail, lod_options,
};
use crate::bake::character::simplify::Method;
use crate::bake::foliage::billboard::is_tree;
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use crate::import::{Imported, import};
use crate::render::atlas::AtlasRasterizer;
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::sync::OnceLock;

/// One model's bake by one method.
#[derive(Debug)]
pub struct Baked {
    pub model: String,
    pub source_triangles: usize,
    pub bones: usize,
    pub lods: SkinnedLods,
    pub from_cache: bool,
}

/// One tree's chain of billboard-cloud levels.
pub struct TreeBaked {
    pub model: String,
    pub source_triangles: usize,
    pub bones: usize,
    pub height: f32,
    pub levels: Vec<crate::bake::foliage::billboard::chain::TreeLevel>,
    pub from_cache: bool,
    pub seconds: f64,
}

/// Everything a `lodlab bake` made, characters and trees.
pub struct BakeResults {
    pub characters: Vec<Baked>,
    pub trees: Vec<TreeBaked>,
}

/// One bake: a character by one method, or a tree's chain (`method` None), with its
/// progress bar and its line in [`ProgressLines`].
struct Job {
    model: usize,
    method: Option<Method>,
    bar: ProgressBar,
    line: usize,
}

/// What every job reads: the models with their sources' hashes, the cache, the GPU tree
/// chains render their atlases on, and what the methods' bakes of one character share.
struct Bakery<'a> {
    models: Vec<(crate::model::Model, [u8; 32])>,
    gpu: Option<crate::render::Gpu>,
    cache: LodCache,
    tolerance_px: f32,
    budgets: Option<Vec<u32>>,
    /// Each character's full-detail mesh and what its methods' bakes share, made by the
    /// first of them that misses the cache (see `bake_lods_sharing`).
    bases: &'a [OnceLock<AnimationSpaceMesh>],
    shared: Vec<SharedBake<'a>>,
    bars: &'a MultiProgress,
    lines: &'a ProgressLines,
}

/// Loads every model `a` names (failing on the first bad one before any work), then bakes
/// every (model, method) pair of the characters and the chain of every tree, in parallel,
/// with one progress bar each.
pub fn run(a: &BakeArgs, inputs: &crate::runtime::spec::BakeInputs) -> anyhow::Result<BakeResults> {
    if !(a.first_error.is_finite() && a.first_error > 0.0) {
        anyhow::bail!("--first-error must be a positive number of pixels");
    }
    let mut names: Vec<String> = a.models.iter().chain(&a.model_flags).cloned().collect();
    // A missing model is one line, as `export` and `report` say it (not clap's usage).
    if names.is_empty() {
        anyhow::bail!("bake needs a model: lodlab bake NAME|PATH [NAME|PATH ...]");
    }
    if let Some(shard) = a.shard {
        names = shard.share(&names);
        eprintln!(
            "shard {shard}: {}",
            if names.is_empty() {
                "no models (more shards than models)".to_string()
            } else {
                names.join(", ")
            }
        );
    }
    let mut models = Vec::new();
    for name in &names {
        let Imported { model, source_hash } = import(name, &inputs.import)?;
        models.push((model, source_hash));
    }
    // Tree chains render their atlases on the GPU.
    let gpu = if models.iter().any(|(m, _)| is_tree(m)) {
        Some(crate::render::Gpu::headless()?)
    } else {
        None
    };
    let (bars, lines) = (MultiProgress::new(), ProgressLines::new());
    let bases: Vec<OnceLock<AnimationSpaceMesh>> = models.iter().map(|_| OnceLock::new()).collect();
    let bakery = Bakery {
        bases: &bases,
        shared: models.iter().map(|_| SharedBake::default()).collect(),
        models,
        gpu,
        cache: LodCache::new(a.cache.clone()),
        tolerance_px: a.first_error,
        // `--triangles`, or the budgets `--levels triangles:…` gave every command.
        budgets: a.triangles.clone().or_else(|| inputs.level_budgets.clone()),
        bars: &bars,
        lines: &lines,
    };
    let jobs = bakery.jobs(&crate::app::cli::values::dedup(a.methods.clone()));
    let done = std::sync::atomic::AtomicBool::new(false);
    let results: Vec<anyhow::Result<Result<Baked, TreeBaked>>> = std::thread::scope(|scope| {
        scope.spawn(|| lines.print_until(&done));
        // Stops the lines however the jobs end (a panic included: the scope joins the
        // printer before it passes the panic on).
        struct Stop<'d>(&'d std::sync::atomic::AtomicBool);
        impl Drop for Stop<'_> {
            fn drop(&mut self) {
                self.0.store(true, std::sync::atomic::Ordering::Relaxed);
            }
        }
        let _stop = Stop(&done);
        let mut results: Vec<(usize, anyhow::Result<Result<Baked, TreeBaked>>)> = jobs
            .into_par_iter()
            .map(|(k, job)| (k, bakery.bake(job)))
            .collect();
        results.sort_by_key(|(k, _)| *k);
        results.into_iter().map(|(_, r)| r).collect()
    });
    let mut out = BakeResults {
        characters: Vec::new(),
        trees: Vec::new(),
    };
    for r in results {
        match r? {
            Ok(character) => out.characters.push(character),
            Err(tree) => out.trees.push(tree),
        }
    }
    Ok(out)
}

impl Bakery<'_> {
    /// The jobs: each character by each of `methods`, each tree once; numbered in that
    /// order (the results keep it) and listed in the order they run.
    fn jobs(&self, methods: &[Method]) -> Vec<(usize, Job)> {
        let style = bar_style();
        let mut jobs = Vec::new();
        for (i, (m, _)) in self.models.iter().enumerate() {
            let methods: Vec<Option<Method>> = if is_tree(m) {
                vec![None]
            } else {
                methods.iter().copied().map(Some).collect()
            };
            for method in methods {
                let bar = self.bars.add(ProgressBar::new(1000));
                bar.set_style(style.clone());
                let what = method.map_or("clouds".to_string(), |m| m.to_string());
                bar.set_prefix(format!("{} {what}", m.name));
                let line = self.lines.add(format!("{} {what}", m.name));
                jobs.push((
                    jobs.len(),
                    Job {
                        model: i,
                        method,
                        bar,
                        line,
                    },
                ));
            }
        }
        // Run dearest first (longest processing time first), so that the cheapest is the one
        // that starts when a core comes free and the last to end is not a long one started
        // late. AS+IS (influence removals besides the collapses) is the dearest; AS is as
        // dear on its own, but it starts from the first pricing AS+IS makes (see
        // `SharedBake`), a quarter of its work, so it runs after rest-pose.
        jobs.sort_by_key(|(_, job)| {
            let rank = match job.method {
                Some(Method::InfluenceSimplification) | None => 0,
                Some(Method::RestPose) => 1,
                Some(Method::AnimationSpace) => 2,
                // A few calls to meshoptimizer: the cheapest.
                Some(Method::Meshopt) => 3,
            };
            (job.model, rank)
        });
        jobs
    }

    /// Runs one job: a character's levels (`Ok`) or a tree's chain (`Err`).
    fn bake(&self, job: Job) -> anyhow::Result<Result<Baked, TreeBaked>> {
        let progress = |f: f32| {
            job.bar.set_position((f.clamp(0.0, 1.0) * 1000.0) as u64);
            self.lines.set(job.line, f);
        };
        // Whichever way the job ends.
        struct Finish<'l>(&'l ProgressLines, usize);
        impl Drop for Finish<'_> {
            fn drop(&mut self) {
                self.0.finish(self.1);
            }
        }
        let _finish = Finish(self.lines, job.line);
        match job.method {
            None => self.bake_tree(job.model, &job.bar, &progress).map(Err),
            Some(method) => Ok(Ok(
                self.bake_character(job.model, method, &job.bar, &progress)
            )),
        }
    }

    /// A tree's chain of billboard-cloud levels, baked or from the cache.
    fn bake_tree(
        &self,
        i: usize,
        bar: &ProgressBar,
        progress: &(dyn Fn(f32) + Sync),
    ) -> anyhow::Result<TreeBaked> {
        let (model, hash) = &self.models[i];
        let start = std::time::Instant::now();
        let gpu = self.gpu.as_ref().expect("a GPU when there are trees");
        let opts = crate::bake::foliage::billboard::chain::ChainOptions::default();
        let (levels, origin) = crate::bake::foliage::billboard::chain::load_or_build_chain(
            &AtlasRasterizer::new(gpu),
            &crate::measure::colour_error::GpuColourError::new(gpu),
            &self.cache,
            model,
            hash,
            &opts,
            progress,
        )
        .map_err(|e| anyhow::anyhow!("{}: {e:#}", model.name))?;
        self.warn(&origin);
        let from_cache = origin == Origin::Cache;
        let seconds = start.elapsed().as_secs_f64();
        bar.finish_with_message(if from_cache {
            "cached".to_string()
        } else {
            format!("{seconds:.2} s")
        });
        Ok(TreeBaked {
            model: model.name.clone(),
            source_triangles: model.mesh.triangle_count(),
            bones: model.skeleton.bone_count(),
            height: crate::bake::foliage::billboard::tree_height(model),
            levels,
            from_cache,
            seconds,
        })
    }

    /// A character's levels by `method`, baked or from the cache.
    fn bake_character(
        &self,
        i: usize,
        method: Method,
        bar: &ProgressBar,
        progress: &(dyn Fn(f32) + Sync),
    ) -> Baked {
        let (model, hash) = &self.models[i];
        let options = lod_options(model, self.tolerance_px, self.budgets.as_deref());
        let (path, key) = crate::bake::character::lod::cached::levels_file(
            &self.cache,
            &model.name,
            hash,
            method,
            &options,
        );
        let Ok((lods, origin)) = self.cache.load_or_build(&path, &key, || {
            let base = self.bases[i].get_or_init(|| full_detail(model));
            Ok::<_, std::convert::Infallible>(bake_lods_sharing(
                model,
                base,
                &self.shared[i],
                method,
                &options,
                progress,
            ))
        });
        self.warn(&origin);
        let from_cache = origin == Origin::Cache;
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
    }

    /// A bake's warning, printed above the bars.
    fn warn(&self, origin: &Origin) {
        if let Origin::Baked { warning: Some(w) } = origin {
            self.bars.suspend(|| eprintln!("warning: {w}"));
        }
    }
}

/// One line per (model, method) whose triangle budgets go below what the simplification
/// can reach: those budgets all give the coarsest level, so they name the floor.
pub fn budget_warnings(results: &BakeResults) -> Vec<String> {
    let mut out = Vec::new();
    for b in &results.characters {
        let Some(budgets) = &b.lods.options.budgets else {
            continue;
        };
        let floor = crate::bake::character::lod::floor_triangles(&b.lods.sequence, &b.lods.options);
        let under: Vec<String> = budgets
            .iter()
            .filter(|&&t| t < floor)
            .map(|t| t.to_string())
            .collect();
        if !under.is_empty() {
            out.push(format!(
                "{} ({}): budget{} {} below its floor of {floor} triangles; {} the coarsest level",
                b.model,
                b.lods.method,
                if under.len() > 1 { "s" } else { "" },
                under.join(", "),
                if under.len() > 1 {
                    "they all give"
                } else {
                    "it gives"
                },
            ));
        }
    }
    out
}

/// Progress where stderr is not a terminal (a log, CI, a pipe), which indicatif's bars leave
/// blank: every [`ProgressLines::EVERY`], one line for each job still running, saying how far
/// it has come, so that a long bake is seen to be working however long one of its stages goes
/// without news (measuring the last levels of a large model reports no fraction).
pub struct ProgressLines {
    on: bool,
    started: std::time::Instant,
    /// Each job's name, the fraction of its simplification done (`None` before the first
    /// report), and whether it has finished.
    jobs: std::sync::Mutex<Vec<(String, Option<f32>, bool)>>,
}

impl ProgressLines {
    pub const EVERY: std::time::Duration = std::time::Duration::from_secs(5);

    pub fn new() -> Self {
        use std::io::IsTerminal;
        ProgressLines {
            on: !std::io::stderr().is_terminal(),
            started: std::time::Instant::now(),
            jobs: std::sync::Mutex::new(Vec::new()),
        }
    }

    fn jobs(&self) -> std::sync::MutexGuard<'_, Vec<(String, Option<f32>, bool)>> {
        self.jobs.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// A job to report on; returns its number.
    pub fn add(&self, what: String) -> usize {
        let mut jobs = self.jobs();
        jobs.push((what, None, false));
        jobs.len() - 1
    }

    /// Job `job` has come to `f` (0 to 1) of its simplification.
    pub fn set(&self, job: usize, f: f32) {
        self.jobs()[job].1 = Some(f.clamp(0.0, 1.0));
    }

    pub fn finish(&self, job: usize) {
        self.jobs()[job].2 = true;
    }

    /// The lines for the jobs still running.
    fn lines(&self) -> Vec<String> {
        let seconds = self.started.elapsed().as_secs_f32();
        self.jobs()
            .iter()
            .filter(|(_, _, done)| !done)
            .map(|(what, f, _)| match f {
                None => format!("{what}: starting, after {seconds:.0} s"),
                Some(f) if *f >= 1.0 => {
                    format!("{what}: simplified; measuring its levels, after {seconds:.0} s")
                }
                Some(f) => format!(
                    "{what}: {:.0}% of the triangles simplified away, after {seconds:.0} s",
                    f * 100.0
                ),
            })
            .collect()
    }

    /// Prints the lines every [`Self::EVERY`] until `done` is set (nothing where stderr is a
    /// terminal: the bars show it there).
    pub fn print_until(&self, done: &std::sync::atomic::AtomicBool) {
        use std::sync::atomic::Ordering;
        let mut last = std::time::Instant::now();
        while self.on && !done.load(Ordering::Relaxed) {
            std::thread::sleep(std::time::Duration::from_millis(100));
            if last.elapsed() >= Self::EVERY {
                last = std::time::Instant::now();
                for line in self.lines() {
                    eprintln!("{line}");
                }
            }
        }
    }
}

impl Default for ProgressLines {
    fn default() -> Self {
        Self::new()
    }
}

/// The progress bar of one (model, method) job, shared by `bake` and `report`.
pub fn bar_style() -> ProgressStyle {
    ProgressStyle::with_template("{prefix:>18} [{bar:30}] {percent:>3}% {msg}")
        .expect("valid template")
        .progress_chars("=> ")
}

/// What `lodlab bake --json` prints: the table's figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Summary {
    pub characters: Vec<CharacterSummary>,
    pub trees: Vec<TreeSummary>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct CharacterSummary {
    pub model: String,
    pub method: String,
    pub source_triangles: usize,
    pub bones: usize,
    /// Seconds the bake took; `None` when it came from the cache.
    pub bake_seconds: Option<f64>,
    pub levels: Vec<LevelSummary>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct LevelSummary {
    pub triangles: usize,
    pub vertices: usize,
    pub influences: usize,
    /// The level's error bound, millimetres (scene units are metres).
    pub error_mm: f32,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct TreeSummary {
    pub model: String,
    pub source_triangles: usize,
    pub bones: usize,
    pub bake_seconds: Option<f64>,
    pub levels: Vec<CloudSummary>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct CloudSummary {
    /// ε as a share of the tree's height.
    pub epsilon: f32,
    pub kind: String,
    pub billboards: usize,
    pub triangles: usize,
    pub atlas_bytes: usize,
}

/// The figures of `results`, as `bake --json` prints them.
pub fn summary(results: &BakeResults) -> Summary {
    Summary {
        characters: results
            .characters
            .iter()
            .map(|b| CharacterSummary {
                model: b.model.clone(),
                method: b.lods.method.name().to_string(),
                source_triangles: b.source_triangles,
                bones: b.bones,
                bake_seconds: (!b.from_cache).then_some(b.lods.bake_seconds),
                levels: b
                    .lods
                    .levels
                    .iter()
                    .map(|l| LevelSummary {
                        triangles: l.triangles(),
                        vertices: l.vertices(),
                        influences: l.influences(),
                        error_mm: l.error * 1000.0,
                    })
                    .collect(),
            })
            .collect(),
        trees: results
            .trees
            .iter()
            .map(|t| TreeSummary {
                model: t.model.clone(),
                source_triangles: t.source_triangles,
                bones: t.bones,
                bake_seconds: (!t.from_cache).then_some(t.seconds),
                levels: t
                    .levels
                    .iter()
                    .map(|l| CloudSummary {
                        epsilon: l.epsilon / t.height,
                        kind: crate::bake::foliage::billboard::chain::CloudKind::name(
                            l.kind.as_ref(),
                        )
                        .to_string(),
                        billboards: l.cloud.billboards,
                        triangles: l.cloud.model.mesh.triangle_count(),
                        atlas_bytes: l.cloud.texture_bytes,
                    })
                    .collect(),
            })
            .collect(),
    }
}

/// The table `lodlab bake` prints: one block per model, one row per level and method (per
/// level for a tree).
pub fn table(results: &BakeResults) -> String {
    let mut out = character_table(&results.characters);
    for t in &results.trees {
        out += &format!(
            "\n{} ({} triangles, {} bones): billboard clouds\n{:<5} {:>9} {:<32} {:>10} {:>9} {:>10} {:>8}\n",
            t.model,
            t.source_triangles,
            t.bones,
            "level",
            "ε (× h)",
            "grouping",
            "billboards",
            "triangles",
            "atlas (KB)",
            "bake (s)"
        );
        for (k, l) in t.levels.iter().enumerate() {
            let time = match (k, t.from_cache) {
                (0, false) => format!("{:.2}", t.seconds),
                (0, true) => "cached".to_string(),
                _ => String::new(),
            };
            out += &format!(
                "{:<5} {:>9.3} {:<32} {:>10} {:>9} {:>10} {:>8}\n",
                k,
                l.epsilon / t.height,
                crate::bake::foliage::billboard::chain::CloudKind::name(l.kind.as_ref()),
                l.cloud.billboards,
                l.cloud.model.mesh.triangle_count(),
                l.cloud.texture_bytes / 1024,
                time
            );
        }
    }
    out
}

fn character_table(results: &[Baked]) -> String {
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

/// `lodlab bake`: levels of detail baked or fetched from the cache, as a table.
pub fn command(a: BakeArgs, inputs: &crate::runtime::spec::BakeInputs) -> anyhow::Result<ExitCode> {
    if let Some(file) = crate::app::json::json_file(&a.json) {
        crate::atomic::check_target(file)?;
    }
    let results = run(&a, inputs)?;
    for warning in budget_warnings(&results) {
        eprintln!("warning: {warning}");
    }
    crate::app::json::emit(&a.json, &summary(&results), &table(&results))?;
    Ok(ExitCode::SUCCESS)
}

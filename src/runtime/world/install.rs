//! Levels of detail installed in a world: each model's levels by a method and its impostor
//! handed to the renderer, a tree's chains kept and shown by the foliage policy, and the
//! summaries the panel and the reports print of what is installed.

use super::{
    CHAINS_KEPT_PER_TREE, InstalledChain, InstalledImpostor, LevelSummary, NormalMapInfo, World,
    lod_model,
};
use crate::bake::character::simplify::Method;
use crate::bake::foliage::billboard::chain::{ChainOptions, TreeLevel};
use crate::bake::gpu_data::drawable::Drawable;
use crate::render::Gpu;
use crate::runtime::levels::{Baked, Levels, Measurer, bake_all};
use crate::scene::foliage::{FoliagePolicy, FoliageView};
use crate::scene::{LodMethod, LodModel};
use anyhow::{Result, bail};

impl World {
    /// Per model, whether it already has what showing `method` needs, so that a bake may
    /// leave it out (for [`bake_all`]): a character its levels by the method, a tree its chain
    /// cut as [`LodView::chain`](super::LodView::chain) says (or nothing, where the policy keeps trees full).
    pub fn has_levels(&self, method: Method) -> Vec<bool> {
        let slot = LodMethod::Simplified(method).index();
        (0..self.bakes.len())
            .map(|m| {
                if self.lod.trees[m] {
                    self.lod.foliage == FoliagePolicy::Full || self.shown_chain(m).is_some()
                } else {
                    self.lod.models[m][slot].is_some()
                }
            })
            .collect()
    }

    /// The simplified method to bake next for what the view shows, if anything is missing.
    pub fn missing_levels(&self) -> Option<Method> {
        self.lod.methods().find_map(|m| match m {
            LodMethod::Simplified(s) if self.has_levels(s).contains(&false) => Some(s),
            _ => None,
        })
    }

    /// The installed chain of tree `m` cut as wanted now, if there is one.
    fn shown_chain(&self, m: usize) -> Option<usize> {
        self.chains
            .iter()
            .position(|c| c.model == m && c.opts == self.lod.chain)
    }

    /// Sets what trees become and how their chains are cut. Trees whose chain for the new
    /// options is on the GPU switch to it at once; the others keep what they show until it is
    /// installed ([`World::missing_levels`] asks for it). Every instance's level is reset.
    pub fn set_foliage(&mut self, policy: FoliagePolicy, chain: ChainOptions) {
        let mut chain = chain;
        chain.style = policy.chain_style().unwrap_or(self.lod.chain.style);
        if policy == self.lod.foliage && chain == self.lod.chain {
            return;
        }
        self.lod.foliage = policy;
        self.lod.chain = chain;
        for m in 0..self.bakes.len() {
            if let Some(c) = self.shown_chain(m) {
                self.show_chain(c);
            }
        }
        // Patches stand for the impostors of the chains shown before.
        self.drop_patches();
        self.lod.reset();
    }

    /// Shows the trees as `foliage` says: their level policy and chains (see
    /// [`World::set_foliage`]), wind, outlines, tint and depth pre-pass.
    pub fn apply_foliage(&mut self, foliage: &FoliageView) {
        self.set_foliage(foliage.policy, foliage.chain);
        self.renderer.wind = foliage.wind;
        self.renderer.outlines = foliage.outlines;
        self.renderer.foliage_tint = foliage.tint;
        self.renderer.foliage_prepass = foliage.prepass;
        if let Some(on) = foliage.atlas_lighting {
            self.renderer.atlas_lighting = on;
        }
    }

    /// Uploads the levels of `method` for every model (`packs` in model order, trees' chains
    /// cut as `chain` among them) and makes them available to selection.
    pub fn install_levels(
        &mut self,
        gpu: &Gpu,
        method: Method,
        chain: &ChainOptions,
        packs: impl IntoIterator<Item = (usize, Baked)>,
    ) -> Result<()> {
        let slot = LodMethod::Simplified(method).index();
        for (m, pack) in packs {
            match pack.transpose().map_err(anyhow::Error::msg)? {
                None => {}
                Some(Levels::Pack(pack, impostor)) => {
                    self.renderer.add_levels(gpu, m, slot, &pack)?;
                    let info = pack.normal_maps.as_ref().map(|n| NormalMapInfo {
                        levels: pack.levels.iter().filter(|l| l.normal_mapped).count(),
                        bytes: n.bytes() as u64,
                        unmapped: n.unmapped_reason(),
                    });
                    let of_model = &mut self.normal_maps[m];
                    if of_model.len() <= slot {
                        of_model.resize(slot + 1, None);
                    }
                    of_model[slot] = info;
                    self.lod.models[m][slot] = Some(lod_model(&self.bakes[m], &pack));
                    self.lod.impostor_errors[m][slot] = None;
                    if let Some(level) = impostor {
                        self.install_impostor(gpu, m, &level.impostor)?;
                        self.lod.impostor_errors[m][slot] = Some(level.placement.clone());
                    }
                }
                Some(Levels::Impostor(level)) => {
                    self.lod.impostor_errors[m][slot] = None;
                    if let Some(level) = level {
                        self.install_impostor(gpu, m, &level.impostor)?;
                        self.lod.impostor_errors[m][slot] = Some(level.placement.clone());
                    }
                }
                Some(Levels::Tree {
                    chain: levels,
                    bakes,
                }) => self.install_tree_levels(gpu, m, chain, &levels, &bakes)?,
            }
        }
        self.lod.refresh_impostors();
        self.lod.reset();
        // A chain's decoding and its atlases' mipmaps leave hundreds of MB freed on the heap.
        crate::render::memory::return_freed_memory();
        Ok(())
    }

    /// Uploads character `m`'s animated impostor (once: it serves every method) as a
    /// character of its own.
    fn install_impostor(
        &mut self,
        gpu: &Gpu,
        m: usize,
        impostor: &crate::bake::impostor::animated::AnimatedImpostor,
    ) -> Result<()> {
        if self.impostors[m].as_ref().map(|i| i.options) == Some(impostor.options) {
            return Ok(());
        }
        let bake = impostor
            .bake(&self.bakes[m])
            .map_err(|e| anyhow::anyhow!("{}: {e}", impostor.model.name))?;
        let bytes = bake.materials.mips.iter().map(|l| l.len() as u64).sum();
        let character = match &self.impostors[m] {
            Some(old) => self.renderer.replace_character(gpu, old.character, &bake)?,
            None => self.renderer.add_character(gpu, &bake)?,
        };
        self.impostors[m] = Some(InstalledImpostor {
            character,
            options: impostor.options,
            bytes,
        });
        Ok(())
    }

    /// Shows far characters as their animated impostors, or not; every instance's level is
    /// reset.
    pub fn show_impostors(&mut self, shown: bool) {
        if self.lod.impostors != shown {
            self.lod.impostors = shown;
            self.lod.reset();
        }
    }

    /// The characters' animated impostors in a line, for the panel: each one's options,
    /// texture size and the level it comes in at under the method shown, or why there are
    /// none.
    pub fn impostor_summary(&self) -> String {
        let slot = self.lod.method.index();
        let mut parts = Vec::new();
        for (m, installed) in self.impostors.iter().enumerate() {
            let Some(i) = installed else { continue };
            let at = match (self.lod.impostor_level(m, slot), slot) {
                _ if !self.lod.impostors => "hidden".to_string(),
                (_, 0) => "full detail shows".to_string(),
                (Some(k), _) => format!("from level {k}"),
                (None, _) => "beats no level".to_string(),
            };
            parts.push(format!(
                "{} {} {:.1} MB, {at}",
                self.bakes[m].name,
                i.options,
                i.bytes as f64 / 1e6
            ));
        }
        match (parts.is_empty(), self.spec.impostors) {
            (false, _) => format!("impostors: {}", parts.join(" · ")),
            (true, Some(options)) => format!("impostors {options}: baked with a method's levels"),
            (true, None) => "impostors: off (--impostors)".into(),
        }
    }

    /// The characters' normal maps under the method shown, in a line for the panel: levels
    /// lit through one and megabytes, or why a model's levels keep their vertex normals.
    pub fn normal_map_summary(&self) -> String {
        if !self.renderer.normal_maps {
            return "normal maps: off, vertex normals (--no-normal-maps)".into();
        }
        let slot = self.lod.method.index();
        let parts: Vec<String> = self
            .normal_maps
            .iter()
            .enumerate()
            .filter_map(|(m, infos)| {
                let info = infos.get(slot).copied().flatten()?;
                let name = &self.bakes[m].name;
                Some(match info.unmapped {
                    Some(problem) => format!("{name}: vertex normals, {problem}"),
                    None => format!(
                        "{name} {} levels {:.1} MB",
                        info.levels,
                        info.bytes as f64 / 1e6
                    ),
                })
            })
            .collect();
        if parts.is_empty() {
            "normal maps: none (full detail or trees shown)".into()
        } else {
            format!("normal maps: {}", parts.join(" · "))
        }
    }

    /// Per model and method slot, its levels' normal maps as uploaded.
    pub fn normal_maps(&self, m: usize, slot: usize) -> Option<NormalMapInfo> {
        self.normal_maps.get(m)?.get(slot).copied().flatten()
    }

    /// Per model, its animated impostor where it has one on the GPU.
    pub fn impostors(&self) -> &[Option<InstalledImpostor>] {
        &self.impostors
    }

    /// Whether every level the view asks for and lacks is in the cache: then
    /// [`World::ensure_levels`] only reads them (a second or two for the default scene), and a
    /// viewer may as well wait for that instead of drawing its first frames at full detail.
    pub fn levels_cached(&self) -> bool {
        let cache = self.cache();
        self.lod.methods().all(|m| {
            let LodMethod::Simplified(method) = m else {
                return true;
            };
            let has = self.has_levels(method);
            self.sources.iter().zip(has).all(|(s, has)| {
                has || crate::runtime::levels::cached(&cache, s, method, &self.lod.chain)
            })
        })
    }

    /// Bakes (or reads from the cache) and uploads the levels of every method the view shows
    /// that is not there yet, and the trees' chains as wanted, waiting for them.
    pub fn ensure_levels(&mut self, gpu: &Gpu, measure: &dyn Measurer) -> Result<()> {
        while let Some(m) = self.missing_levels() {
            let warn = |w: String| eprintln!("warning: {w}");
            let skip = self.has_levels(m);
            let chain = self.lod.chain;
            let cache = self.cache();
            let names: Vec<&str> = self.sources.iter().map(|s| s.model.name.as_str()).collect();
            let trees = self
                .sources
                .iter()
                .map(|s| crate::bake::foliage::billboard::is_tree(&s.model))
                .collect();
            let what = format!("{m} levels");
            let progress = BakeProgress::new(&names, trees, &skip, &what);
            let job = crate::runtime::levels::BakeJob {
                gpu,
                measure,
                cache: &cache,
                method: m,
                chain: &chain,
            };
            let packs = with_clock(&progress, || {
                bake_all(
                    &job,
                    &self.sources,
                    &skip,
                    &|i, f| progress.report(i, f),
                    &warn,
                )
            });
            // A model that failed is reported by install_levels; none is retried for ever.
            self.install_levels(gpu, m, &chain, packs.into_iter().enumerate())?;
            if self.missing_levels() == Some(m) {
                bail!("{m}: levels are still missing after baking them");
            }
        }
        Ok(())
    }

    /// Uploads every level of tree `m`'s billboard-cloud chain, cut as `opts` (`bakes`: levels
    /// 1…), as a character of its own, and shows it if it is the chain wanted (or the tree
    /// shows none yet). The tree then switches between its levels with the same selection and
    /// transitions as the characters under every simplified method, its ε as the level error
    /// (an alpha or morph transition becomes a cross-dissolve, see [`LodDraw::Dissolve`]).
    /// The tree's oldest chains beyond [`CHAINS_KEPT_PER_TREE`] are let go.
    fn install_tree_levels(
        &mut self,
        gpu: &Gpu,
        m: usize,
        opts: &ChainOptions,
        chain: &[TreeLevel],
        bakes: &[Drawable],
    ) -> Result<()> {
        let mut characters = vec![m];
        for bake in bakes {
            let c = match self.free_characters.pop() {
                Some(c) => self.renderer.replace_character(gpu, c, bake)?,
                None => self.renderer.add_character(gpu, bake)?,
            };
            characters.push(c);
        }
        // A chain cut the same way again replaces the old one, whose characters are reused.
        if let Some(old) = self
            .chains
            .iter()
            .position(|c| c.model == m && c.opts == *opts)
        {
            let old = self.chains.remove(old);
            if self.tree_levels[m].as_ref() == Some(&old.characters) {
                self.tree_levels[m] = None;
            }
            self.free_characters.extend(&old.characters[1..]);
        }
        self.chains.push(InstalledChain {
            model: m,
            opts: *opts,
            characters,
            levels: chain.iter().map(LevelSummary::of).collect(),
            impostor: chain
                .iter()
                .rev()
                .find(|l| super::patch_state::is_impostor(&l.kind))
                .map(|l| Box::new(l.cloud.clone())),
        });
        if *opts == self.lod.chain || self.tree_levels[m].is_none() {
            self.show_chain(self.chains.len() - 1);
        }
        // Let the oldest chains of this tree go, never the shown one.
        let shown = self.tree_levels[m].clone();
        while self.chains.iter().filter(|c| c.model == m).count() > CHAINS_KEPT_PER_TREE {
            let Some(old) = self
                .chains
                .iter()
                .position(|c| c.model == m && Some(&c.characters) != shown.as_ref())
            else {
                break;
            };
            let gone = self.chains.remove(old);
            self.free_characters.extend(&gone.characters[1..]);
        }
        Ok(())
    }

    /// Shows installed chain `c` for its tree: selection switches along its levels (forest
    /// patches made from another chain's impostor are let go).
    fn show_chain(&mut self, c: usize) {
        if self.tree_levels[self.chains[c].model].as_ref() != Some(&self.chains[c].characters) {
            self.drop_patches();
        }
        let chain = &self.chains[c];
        let m = chain.model;
        let errors: Vec<f32> = chain.levels.iter().map(|l| l.epsilon).collect();
        let b = &self.bakes[m];
        for method in LodMethod::ALL.into_iter().skip(1) {
            self.lod.models[m][method.index()] = Some(LodModel {
                errors: errors.clone(),
                center: b.bounds.center(),
                radius: b.bounds.diagonal() * 0.5,
            });
        }
        self.tree_levels[m] = Some(chain.characters.clone());
    }

    /// The chain each tree shows: its name, whether it is cut as wanted now, and its levels.
    pub fn shown_chains(&self) -> Vec<(String, bool, &[LevelSummary])> {
        self.chains
            .iter()
            .filter(|c| self.tree_levels[c.model].as_ref() == Some(&c.characters))
            .map(|c| {
                (
                    self.bakes[c.model].name.clone(),
                    c.opts == self.lod.chain,
                    c.levels.as_slice(),
                )
            })
            .collect()
    }
}

/// Progress of a bake the caller waits for, on stderr every few seconds (a line each, so that
/// it reads the same in a terminal and in a log), saying what each model waits on: reading the
/// cache, baking its levels, drawing its impostor's pages, measuring where the impostor comes
/// in. A cold `shot` or `view --screenshot` would otherwise wait a minute in silence, and a
/// warm one read "baking" while it only read files.
struct BakeProgress<'a> {
    what: &'a str,
    names: &'a [&'a str],
    /// Which models are trees (their chains report no impostor stages).
    trees: Vec<bool>,
    start: web_time::Instant,
    /// When the last line was said, and each model's share done (never going back: a model's
    /// impostor reports from 0 again after its levels).
    state: std::sync::Mutex<(web_time::Instant, Vec<f32>)>,
}

impl<'a> BakeProgress<'a> {
    /// Seconds between lines, and before the first: a bake from the cache says nothing.
    const EVERY: f32 = 5.0;

    fn new(
        names: &'a [&'a str],
        trees: Vec<bool>,
        skip: &[bool],
        what: &'a str,
    ) -> BakeProgress<'a> {
        let done = skip.iter().map(|&s| if s { 1.0 } else { 0.0 }).collect();
        let now = web_time::Instant::now();
        BakeProgress {
            what,
            names,
            trees,
            start: now,
            state: std::sync::Mutex::new((now, done)),
        }
    }

    /// Model `i` is `fraction` done (see [`crate::runtime::levels::IMPOSTOR_PENDING`] and
    /// the stages after it).
    fn report(&self, i: usize, fraction: f32) {
        if let Ok(mut state) = self.state.lock()
            && let Some(d) = state.1.get_mut(i)
        {
            *d = d.max(fraction.clamp(0.0, 1.0));
        }
        self.tick();
    }

    /// Says where the bake stands, where [`Self::EVERY`] seconds have passed since the last
    /// line (or the start). Called on every report and by a clock between them.
    fn tick(&self) {
        if let Some(line) = self.due_line() {
            eprintln!("{line}");
        }
    }

    /// The line [`Self::tick`] says, where one is due.
    fn due_line(&self) -> Option<String> {
        let Ok(mut state) = self.state.lock() else {
            return None;
        };
        let (last, done) = &mut *state;
        if last.elapsed().as_secs_f32() < Self::EVERY {
            return None;
        }
        *last = web_time::Instant::now();
        let open: Vec<(String, bool)> = self
            .names
            .iter()
            .zip(done.iter())
            .zip(&self.trees)
            .filter(|&((_, &d), _)| d < 1.0)
            .map(|((n, &d), &tree)| stage(n, d, tree))
            .collect();
        let writes = open.iter().any(|(_, w)| *w);
        let open = if open.is_empty() {
            "finishing".to_string()
        } else {
            open.into_iter()
                .map(|(s, _)| s)
                .collect::<Vec<_>>()
                .join(", ")
        };
        Some(format!(
            "lodlab: {} for {:.0} s: {open}{}",
            self.what,
            self.start.elapsed().as_secs_f32(),
            if writes {
                " (kept in the cache for next time)"
            } else {
                ""
            }
        ))
    }
}

/// `work` run while a clock says `progress` every [`BakeProgress::EVERY`] seconds, whether the
/// work reports or not (a step of a bake can run for tens of seconds between reports). The web
/// build has no threads to keep a clock on: its lines come with the reports.
fn with_clock<T: Send>(progress: &BakeProgress, work: impl FnOnce() -> T) -> T {
    #[cfg(target_arch = "wasm32")]
    {
        let _ = progress;
        work()
    }
    #[cfg(not(target_arch = "wasm32"))]
    {
        use std::sync::mpsc::RecvTimeoutError;
        // The clock stops the moment the work ends (its sender dropped), not at its next
        // tick: a bake read from the cache in milliseconds waits for nothing.
        let (stop, stopped) = std::sync::mpsc::channel::<()>();
        std::thread::scope(|scope| {
            scope.spawn(move || {
                while let Err(RecvTimeoutError::Timeout) =
                    stopped.recv_timeout(std::time::Duration::from_millis(250))
                {
                    progress.tick();
                }
            });
            let out = work();
            drop(stop);
            out
        })
    }
}

/// What model `name` (a tree or not), `d` done, waits on, in words, and whether that work
/// writes the cache (see [`crate::runtime::levels::IMPOSTOR_PENDING`]): a model that has
/// reported nothing yet is reading the cache (a miss reports its first share within a second).
fn stage(name: &str, d: f32, tree: bool) -> (String, bool) {
    use crate::runtime::levels::{IMPOSTOR_BAKING, IMPOSTOR_MEASURING, IMPOSTOR_PENDING};
    match d {
        d if tree && d > 0.0 => (
            format!(
                "baking {name}'s billboard clouds {:.0}%",
                (d * 100.0).min(99.0)
            ),
            true,
        ),
        d if d >= IMPOSTOR_MEASURING => {
            (format!("measuring where {name}'s impostor comes in"), true)
        }
        d if d >= IMPOSTOR_BAKING => (format!("drawing {name}'s impostor"), true),
        d if d >= IMPOSTOR_PENDING => (format!("reading {name}'s impostor"), false),
        // Never 100% while it is still at work: measuring the levels follows simplifying.
        d if d > 0.0 => (
            format!(
                "baking {name} {:.0}%",
                (d / IMPOSTOR_PENDING * 100.0).min(99.0)
            ),
            true,
        ),
        _ => (format!("reading {name}"), false),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runtime::levels::{IMPOSTOR_BAKING, IMPOSTOR_MEASURING, IMPOSTOR_PENDING};

    /// The progress line says what each model waits on, and that the cache is written only
    /// where something is made: a warm run reads.
    #[test]
    fn a_progress_line_tells_reading_from_baking() {
        let names = ["walker", "horse", "broadleaf"];
        let p = BakeProgress::new(
            &names,
            vec![false, false, true],
            &[false; 3],
            "as+is levels",
        );
        let due = || {
            if let Ok(mut s) = p.state.lock() {
                s.0 = web_time::Instant::now() - std::time::Duration::from_secs(6);
            }
            p.due_line().unwrap()
        };
        assert!(p.due_line().is_none(), "nothing is said before 5 s");
        let line = due();
        assert!(
            line.contains("reading walker, reading horse, reading broadleaf"),
            "{line}"
        );
        assert!(!line.contains("cache for next time"), "{line}");
        p.report(0, IMPOSTOR_PENDING);
        p.report(1, 0.45);
        p.report(2, 0.3);
        let line = due();
        assert!(line.contains("reading walker's impostor"), "{line}");
        assert!(line.contains("baking horse 50%"), "{line}");
        assert!(
            line.contains("baking broadleaf's billboard clouds 30%"),
            "{line}"
        );
        assert!(
            line.ends_with("(kept in the cache for next time)"),
            "{line}"
        );
        p.report(0, IMPOSTOR_BAKING);
        assert!(due().contains("drawing walker's impostor"));
        p.report(0, IMPOSTOR_MEASURING);
        assert!(due().contains("measuring where walker's impostor comes in"));
        for i in 0..3 {
            p.report(i, 1.0);
        }
        assert!(due().contains(": finishing"));
    }
}

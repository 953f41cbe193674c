//! A world: the renderer with the scene's characters and trees, the crowd, the camera, and the
//! levels of detail installed with their run-time choices.

use super::levels::{Baked, LevelSource, Levels, Measurer, bake_all};
use super::spec::{Loaded, SceneSpec, default_camera, layout_crowd};
use crate::bake::cache::LodCache;
use crate::bake::character::simplify::Method;
use crate::bake::foliage::billboard::chain::{ChainOptions, CloudKind, TreeLevel};
use crate::bake::gpu_data::drawable::CharacterBake;
use crate::bake::gpu_data::lod_pack::LodPack;
use crate::render::{FrameStats, FrameView, Gpu, Region, SceneRenderer, Side};
use crate::scene::foliage::{FoliagePolicy, FoliageView};
use crate::scene::{
    Camera, Crowd, Instance, LodDraw, LodMethod, LodModel, LodPolicy, LodTracker, ScreenProjection,
};
use anyhow::{Result, bail};

/// A loaded scene: the renderer with its characters, the crowd, a camera, and the levels of
/// detail with their run-time choices.
pub struct World {
    pub spec: SceneSpec,
    pub bakes: Vec<CharacterBake>,
    pub sources: Vec<LevelSource>,
    pub crowd: Crowd,
    pub camera: Camera,
    pub renderer: SceneRenderer,
    pub lod: LodView,
    instances: Vec<Instance>,
    /// Per model: for a tree whose billboard-cloud chain is shown, the renderer's character of
    /// every level (level 0 the tree itself).
    tree_levels: Vec<Option<Vec<usize>>>,
    /// Every tree chain on the GPU, the shown ones and a few earlier ones (switching back to
    /// them is instant).
    chains: Vec<InstalledChain>,
    /// Renderer characters of chains let go, to be reused.
    free_characters: Vec<usize>,
    /// The instances and draws of a frame with trees turned into their level's character,
    /// and far characters into their impostors.
    drawn: [(Vec<Instance>, Vec<LodDraw>); 2],
    /// Per model: a character's animated impostor on the GPU, its last level under every
    /// simplified method.
    impostors: Vec<Option<InstalledImpostor>>,
    /// Per model and method slot: its levels' normal maps as uploaded.
    normal_maps: Vec<Vec<Option<NormalMapInfo>>>,
}

/// A set of levels' normal maps, as the panel reports them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalMapInfo {
    /// Levels lit through a map.
    pub levels: usize,
    /// Bytes of the maps with their mipmaps.
    pub bytes: u64,
    /// Why no level has one, where none has.
    pub unmapped: Option<crate::bake::character::normal_map::UvProblem>,
}

/// A character's animated impostor on the GPU.
#[derive(Clone, Debug, PartialEq)]
pub struct InstalledImpostor {
    /// The renderer's character that draws it.
    pub character: usize,
    pub options: crate::bake::impostor::animated::ImpostorOptions,
    /// Bytes of its pages with their mipmaps, as uploaded.
    pub bytes: u64,
}

/// Chains kept on the GPU per tree, the shown one included.
const CHAINS_KEPT_PER_TREE: usize = 3;

/// A tree's billboard-cloud chain on the GPU.
struct InstalledChain {
    model: usize,
    /// How it was cut.
    opts: ChainOptions,
    /// The renderer's character of every level (level 0 the tree itself).
    characters: Vec<usize>,
    levels: Vec<LevelSummary>,
}

/// One level of a tree's chain, as the foliage panel lists it.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelSummary {
    /// ε in scene units (0: the full tree).
    pub epsilon: f32,
    /// What it is, in a word: full, skeleton or spectral.
    pub kind: &'static str,
    pub billboards: usize,
    pub triangles: usize,
    /// RMS animation error, in tree heights.
    pub anim_rms: f32,
}

impl LevelSummary {
    fn of(level: &TreeLevel) -> LevelSummary {
        LevelSummary {
            epsilon: level.epsilon,
            kind: match level.kind {
                None => "full",
                Some(CloudKind::Skeleton(_)) => "skeleton",
                Some(CloudKind::Spectral(_)) => "spectral",
                Some(CloudKind::Clumps { .. }) => "clumps",
                Some(CloudKind::Impostor { .. }) => "impostor",
            },
            billboards: level.cloud.billboards,
            triangles: level.cloud.model.mesh.triangle_count(),
            anim_rms: level.cloud.animation.rms,
        }
    }
}

/// What levels of detail are shown and how: the user's choices and the per-instance state.
pub struct LodView {
    pub policy: LodPolicy,
    pub method: LodMethod,
    /// Compare mode: the right half of the view shows this method, the left half `method`.
    pub compare: Option<LodMethod>,
    /// What trees become under a simplified method, and how their chains are cut (its style
    /// follows the policy). Change both through [`World::set_foliage`].
    foliage: FoliagePolicy,
    chain: ChainOptions,
    /// Which models are trees.
    trees: Vec<bool>,
    trackers: [LodTracker; 2],
    draws: [Vec<LodDraw>; 2],
    /// Per model, per method slot: what selection needs, once the levels are on the GPU.
    models: Vec<[Option<LodModel>; 4]>,
    /// Whether far characters show as their animated impostors (where they have one).
    impostors: bool,
    /// Per model and method slot: its impostor's placement in that method's chain, where it
    /// has one on the GPU.
    impostor_errors: Vec<[Option<crate::bake::impostor::placement::Placement>; 4]>,
    /// The tolerance `with_impostors` was worked out for (see [`Placement::epsilon_at`]).
    ///
    /// [`Placement::epsilon_at`]: crate::bake::impostor::placement::Placement::epsilon_at
    impostors_at: f32,
    /// `models` with each character's impostor appended as its last level (see
    /// [`with_impostor`]), for the simplified methods.
    with_impostors: Vec<[Option<LodModel>; 4]>,
}

impl LodView {
    /// The methods the sides show, left (or only) first.
    pub fn methods(&self) -> impl Iterator<Item = LodMethod> + use<> {
        std::iter::once(self.method).chain(self.compare)
    }

    /// Forgets every instance's level and transition: the next frame snaps.
    pub fn reset(&mut self) {
        for t in &mut self.trackers {
            t.reset();
        }
    }

    /// Are the levels of `method` uploaded for every model (trees kept full need none)?
    pub fn has(&self, method: LodMethod) -> bool {
        method == LodMethod::None
            || self
                .models
                .iter()
                .zip(&self.trees)
                .all(|(m, &tree)| m[method.index()].is_some() || self.stays_full(tree))
    }

    fn stays_full(&self, tree: bool) -> bool {
        tree && self.foliage == FoliagePolicy::Full
    }

    /// What selection uses for model `m` under the method in `slot`: its levels by that
    /// method where they are there (and, for a tree, where the policy is not to keep it
    /// full), else its full detail alone.
    fn model(&self, m: usize, slot: usize) -> Option<&LodModel> {
        if let Some(with) = self.impostor_model(m, slot) {
            return Some(with);
        }
        let slots = self.models.get(m)?;
        let full = self.trees.get(m).is_some_and(|&t| self.stays_full(t));
        let chosen = if full { None } else { slots[slot].as_ref() };
        chosen.or(slots[0].as_ref())
    }

    /// Model `m`'s levels under the method in `slot` with its impostor last, where it is
    /// shown.
    fn impostor_model(&self, m: usize, slot: usize) -> Option<&LodModel> {
        if !self.impostors {
            return None;
        }
        self.with_impostors.get(m)?[slot].as_ref()
    }

    /// The level at which model `m` shows its impostor under the method in `slot`, if it
    /// does.
    pub fn impostor_level(&self, m: usize, slot: usize) -> Option<u8> {
        self.impostor_model(m, slot)
            .map(|l| (l.errors.len() - 1) as u8)
    }

    /// The error bound of every level model `m` shows under the method in `slot` (its
    /// impostor last where it shows one), finest first.
    pub fn errors(&self, m: usize, slot: usize) -> Option<&[f32]> {
        self.model(m, slot).map(|l| l.errors.as_slice())
    }

    /// Whether far characters show as their animated impostors.
    pub fn impostors_shown(&self) -> bool {
        self.impostors
    }

    /// Rebuilds [`LodView::with_impostors`] after levels or impostors came, or the tolerance
    /// changed.
    fn refresh_impostors(&mut self) {
        self.impostors_at = self.policy.tolerance_px;
        self.with_impostors = self
            .models
            .iter()
            .zip(&self.impostor_errors)
            .map(|(slots, errors)| {
                let mut with: [Option<LodModel>; 4] = Default::default();
                for (slot, levels) in slots.iter().enumerate().skip(1) {
                    let e = errors[slot]
                        .as_ref()
                        .and_then(|p| p.epsilon_at(self.policy.tolerance_px));
                    if let (Some(levels), Some(e)) = (levels, e) {
                        with[slot] = Some(with_impostor(levels, e));
                    }
                }
                with
            })
            .collect();
    }

    pub fn foliage(&self) -> FoliagePolicy {
        self.foliage
    }

    /// The chain options trees are wanted in.
    pub fn chain(&self) -> ChainOptions {
        self.chain
    }

    /// What the instances drew on each side in the last frame.
    pub fn draws(&self, side: usize) -> &[LodDraw] {
        &self.draws[side]
    }
}

impl World {
    pub fn new(
        gpu: &Gpu,
        loaded: Loaded,
        color_format: wgpu::TextureFormat,
        sample_count: u32,
    ) -> Result<World> {
        let Loaded {
            spec,
            bakes,
            sources,
        } = loaded;
        check_instance_count(gpu, &spec)?;
        let mut renderer = SceneRenderer::new(gpu, color_format, sample_count);
        for b in &bakes {
            renderer.add_character(gpu, b)?;
        }
        let crowd = layout_crowd(&spec, &bakes, None);
        let camera = default_camera(&crowd, &bakes);
        let n_models = bakes.len();
        let lod = LodView {
            policy: LodPolicy::default(),
            method: LodMethod::None,
            compare: None,
            foliage: FoliagePolicy::default(),
            chain: ChainOptions::default(),
            trees: bakes.iter().map(|b| b.alpha_tested).collect(),
            trackers: Default::default(),
            draws: Default::default(),
            models: bakes
                .iter()
                .map(|b| {
                    let mut slots: [Option<LodModel>; 4] = Default::default();
                    slots[0] = Some(lod_model(b, &LodPack::full_detail(b)));
                    slots
                })
                .collect(),
            impostors: true,
            impostor_errors: vec![Default::default(); n_models],
            impostors_at: f32::NAN,
            with_impostors: vec![Default::default(); n_models],
        };
        Ok(World {
            spec,
            bakes,
            sources,
            crowd,
            camera,
            renderer,
            tree_levels: vec![None; n_models],
            chains: Vec::new(),
            free_characters: Vec::new(),
            lod,
            instances: Vec::new(),
            drawn: Default::default(),
            impostors: vec![None; n_models],
            normal_maps: vec![Vec::new(); n_models],
        })
    }

    /// The level-of-detail cache this world bakes into.
    pub fn cache(&self) -> LodCache {
        LodCache::new(self.spec.cache_dir.clone())
    }

    /// Per model, whether it already has what showing `method` needs, so that a bake may
    /// leave it out (for [`bake_all`]): a character its levels by the method, a tree its chain
    /// cut as [`LodView::chain`] says (or nothing, where the policy keeps trees full).
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
        self.lod.reset();
    }

    /// Shows the trees as `foliage` says: their level policy and chains (see
    /// [`World::set_foliage`]), wind, outlines and tint.
    pub fn apply_foliage(&mut self, foliage: &FoliageView) {
        self.set_foliage(foliage.policy, foliage.chain);
        self.renderer.wind = foliage.wind;
        self.renderer.outlines = foliage.outlines;
        self.renderer.foliage_tint = foliage.tint;
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
            .bake(self.bakes[m].bounds)
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
            self.sources
                .iter()
                .zip(has)
                .all(|(s, has)| has || super::levels::cached(&cache, s, method, &self.lod.chain))
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
            let packs = bake_all(
                gpu,
                measure,
                &self.sources,
                &skip,
                m,
                &chain,
                &cache,
                &|_, _| {},
                &warn,
            );
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
        bakes: &[CharacterBake],
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

    /// Shows installed chain `c` for its tree: selection switches along its levels.
    fn show_chain(&mut self, c: usize) {
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

    /// Where memory goes, in bytes by kind: on the GPU (see [`GpuMemory`]), the frame's
    /// render targets (`targets`, the caller's), and the CPU's copies: the models as loaded
    /// (kept to bake their levels) and their bakes (kept for re-uploads and the crowd); then
    /// the process's resident size where the platform says it.
    pub fn memory(&self, targets: u64) -> Vec<(&'static str, u64)> {
        let mut rows: Vec<(&'static str, u64)> = self.renderer.memory().rows().to_vec();
        rows.push(("render targets", targets));
        rows.push((
            "models (CPU)",
            self.sources.iter().map(|s| s.model.heap_bytes()).sum(),
        ));
        rows.push((
            "bakes (CPU)",
            self.bakes.iter().map(CharacterBake::heap_bytes).sum(),
        ));
        if let Some(rss) = crate::render::memory::resident_bytes() {
            rows.push(("resident (process)", rss));
        }
        rows
    }

    /// Re-lays the crowd for a new count, clip or model choice without reloading anything:
    /// every character stays on the GPU.
    pub fn relayout(&mut self, only: Option<usize>, count: usize, clip: Option<String>) {
        self.spec.count = count;
        self.spec.clip = clip;
        self.crowd = layout_crowd(&self.spec, &self.bakes, only);
    }

    pub fn reset_camera(&mut self) {
        self.camera = default_camera(&self.crowd, &self.bakes);
    }

    /// Chooses every instance's level for a frame at scene time `time`, `dt` seconds of
    /// wall time after the last, seen in a view `height` pixels high.
    pub fn select(&mut self, height: u32, time: f32, dt: f32) {
        if self.lod.impostors_at != self.lod.policy.tolerance_px {
            self.lod.refresh_impostors();
        }
        self.crowd.instances_at(time, &mut self.instances);
        let screen = ScreenProjection::new(
            self.camera.eye(),
            self.camera.fov_y,
            height as f32,
            self.camera.near_far().0,
        );
        // The trackers and draws step out while selection reads the rest of the view.
        let mut trackers = std::mem::take(&mut self.lod.trackers);
        let mut draws = std::mem::take(&mut self.lod.draws);
        let lod = &self.lod;
        for (side, method) in lod.methods().enumerate() {
            let slot = method.index();
            trackers[side].update_with(
                &lod.policy,
                |m| lod.model(m, slot),
                &self.instances,
                &screen,
                dt,
                &mut draws[side],
            );
        }
        self.lod.trackers = trackers;
        self.lod.draws = draws;
    }

    /// Runs selection over the `seconds` before `time` at 60 frames per second, so that a
    /// single rendered frame shows the transitions a viewer would be in the middle of.
    pub fn settle(&mut self, height: u32, time: f32, seconds: f32) {
        let dt = 1.0 / 60.0;
        let frames = (seconds / dt).round() as usize;
        for k in (0..=frames).rev() {
            self.select(height, time - k as f32 * dt, dt);
        }
    }

    /// Uploads everything for a frame (after [`World::select`]) and returns what it will draw.
    pub fn upload(&mut self, gpu: &Gpu, aspect: f32, time: f32) -> FrameStats {
        let view = FrameView::from_camera(&self.camera, aspect, time);
        let lod = &self.lod;
        // Trees draw their level's own character (a billboard cloud) at full detail; between
        // two levels (an alpha or a morph transition) they cross-dissolve, the two levels'
        // characters drawn as two instances. Without tree levels the crowd goes to the
        // renderer as it is.
        // Far characters likewise draw their impostor's character: an instance at the
        // impostor's level is one instance of it; one changing between its coarsest mesh and
        // its impostor dissolves from one to the other on complementary pixels.
        let has_impostors = lod.impostors && self.impostors.iter().any(Option::is_some);
        let remap = self.tree_levels.iter().any(Option::is_some) || has_impostors;
        for (i, method) in lod.methods().enumerate().filter(|_| remap) {
            // Per model: its impostor's level under this side's method and its character.
            let slot = method.index();
            let far: Vec<Option<(u8, usize)>> = (0..self.impostors.len())
                .map(|m| {
                    let character = self.impostors[m].as_ref()?.character;
                    Some((lod.impostor_level(m, slot)?, character))
                })
                .collect();
            let (instances, draws) = &mut self.drawn[i];
            instances.clear();
            draws.clear();
            for (inst, d) in self.instances.iter().zip(&lod.draws[i]) {
                let Some(levels) = self.tree_levels.get(inst.model).and_then(Option::as_ref) else {
                    match far.get(inst.model).copied().flatten() {
                        Some((far, character)) => {
                            let shown = Instance {
                                model: character,
                                ..*inst
                            };
                            impostor_draws(inst, &shown, *d, far, instances, draws);
                        }
                        None => {
                            instances.push(*inst);
                            draws.push(*d);
                        }
                    }
                    continue;
                };
                let at = |k: u8| Instance {
                    model: levels[(k as usize).min(levels.len() - 1)],
                    ..*inst
                };
                match *d {
                    LodDraw::Level(k) | LodDraw::Dissolve { level: k, .. } => {
                        instances.push(at(k));
                        draws.push(LodDraw::Level(k));
                    }
                    LodDraw::Alpha { from, to, p }
                    | LodDraw::Dither { from, to, p }
                    | LodDraw::Morph {
                        fine: from,
                        coarse: to,
                        t: p,
                    } => {
                        for (level, incoming) in [(from, false), (to, true)] {
                            instances.push(at(level));
                            draws.push(LodDraw::Dissolve { level, p, incoming });
                        }
                    }
                }
            }
        }
        let drawn = &self.drawn;
        let instances = &self.instances;
        let side = |i: usize, m: LodMethod, region| Side {
            method: if lod.has(m) { m.index() } else { 0 },
            instances: if remap { &drawn[i].0 } else { instances },
            draws: if remap { &drawn[i].1 } else { &lod.draws[i] },
            region,
        };
        match lod.compare {
            None => self
                .renderer
                .prepare(gpu, &view, &[side(0, lod.method, Region::Full)]),
            Some(right) => self.renderer.prepare(
                gpu,
                &view,
                &[
                    side(0, lod.method, Region::Left),
                    side(1, right, Region::Right),
                ],
            ),
        }
    }

    /// Selection and upload for a frame `width`×`height` pixels, `dt` seconds after the last.
    pub fn prepare(&mut self, gpu: &Gpu, size: [u32; 2], time: f32, dt: f32) -> FrameStats {
        self.select(size[1], time, dt);
        self.upload(gpu, size[0] as f32 / size[1].max(1) as f32, time)
    }
}

/// Pushes what instance `inst` draws when its draw `d` may involve its impostor at level
/// `far` (`shown`: the instance as its impostor's character): the impostor at that level, a
/// dissolve between it and the mesh level on the other side of a transition, or `d` itself.
fn impostor_draws(
    inst: &Instance,
    shown: &Instance,
    d: LodDraw,
    far: u8,
    instances: &mut Vec<Instance>,
    draws: &mut Vec<LodDraw>,
) {
    let (from, to, p) = match d {
        LodDraw::Level(k) if k >= far => {
            instances.push(*shown);
            draws.push(LodDraw::Level(far));
            return;
        }
        LodDraw::Alpha { from, to, p } | LodDraw::Dither { from, to, p } => (from, to, p),
        LodDraw::Morph { fine, coarse, t } => (fine, coarse, t),
        _ => (0, 0, 0.0),
    };
    if from < far && to < far {
        instances.push(*inst);
        draws.push(d);
        return;
    }
    for (level, incoming) in [(from, false), (to, true)] {
        instances.push(if level >= far { *shown } else { *inst });
        draws.push(LodDraw::Dissolve {
            level: level.min(far),
            p,
            incoming,
        });
    }
}

/// `levels` with an impostor of error bound `error` as the last level: it stands for every
/// level whose error is not below its own, so the errors keep rising.
pub fn with_impostor(levels: &LodModel, error: f32) -> LodModel {
    let mut errors: Vec<f32> = levels
        .errors
        .iter()
        .copied()
        .take_while(|&e| e < error)
        .collect();
    errors.push(error);
    LodModel {
        errors,
        ..levels.clone()
    }
}

/// What selection needs to know about a character's levels.
fn lod_model(bake: &CharacterBake, pack: &LodPack) -> LodModel {
    LodModel {
        errors: pack.errors(),
        center: bake.bounds.center(),
        radius: bake.bounds.diagonal() * 0.5,
    }
}

/// Fails, in one line, where the scene's instances would not fit the device's instance buffer
/// (see [`SceneRenderer::max_instances`]), before any of them is laid out.
pub fn check_instance_count(gpu: &Gpu, spec: &SceneSpec) -> Result<()> {
    let max = SceneRenderer::max_instances(&gpu.device);
    let trees = if spec.scene == crate::scene::SceneKind::Mixed {
        spec.trees
    } else {
        0
    };
    let total = spec.count.saturating_add(trees);
    if total > max {
        bail!(
            "{total} instances (--count {}{}) are more than this adapter's buffers hold: at most {max} (max_buffer_size {} MiB)",
            spec.count,
            if trees > 0 {
                format!(", --trees {trees}")
            } else {
                String::new()
            },
            gpu.device.limits().max_buffer_size >> 20
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_character_changing_to_its_impostor_dissolves_between_the_two() {
        let inst = Instance {
            model: 0,
            transform: glam::Affine3A::IDENTITY,
            clip: 0,
            time_offset: 0.0,
            speed: 1.0,
            wind: 1.0,
            tint: glam::Vec4::ONE,
            fade: None,
        };
        let shown = Instance { model: 7, ..inst };
        let far = 5u8;
        let run = |d: LodDraw| {
            let (mut i, mut d2) = (Vec::new(), Vec::new());
            impostor_draws(&inst, &shown, d, far, &mut i, &mut d2);
            i.iter().map(|x| x.model).zip(d2).collect::<Vec<_>>()
        };
        // A mesh level stays the character; the impostor's level is its impostor.
        assert_eq!(run(LodDraw::Level(3)), vec![(0, LodDraw::Level(3))]);
        assert_eq!(run(LodDraw::Level(far)), vec![(7, LodDraw::Level(far))]);
        // Between two mesh levels nothing changes.
        let between = LodDraw::Alpha {
            from: 2,
            to: 3,
            p: 0.4,
        };
        assert_eq!(run(between), vec![(0, between)]);
        // Into the impostor (any transition): the mesh dissolves out as the impostor dissolves
        // in, on complementary pixels.
        for d in [
            LodDraw::Alpha {
                from: 4,
                to: far,
                p: 0.3,
            },
            LodDraw::Dither {
                from: 4,
                to: far,
                p: 0.3,
            },
            LodDraw::Morph {
                fine: 4,
                coarse: far,
                t: 0.3,
            },
        ] {
            assert_eq!(
                run(d),
                vec![
                    (
                        0,
                        LodDraw::Dissolve {
                            level: 4,
                            p: 0.3,
                            incoming: false
                        }
                    ),
                    (
                        7,
                        LodDraw::Dissolve {
                            level: far,
                            p: 0.3,
                            incoming: true
                        }
                    ),
                ]
            );
        }
        // And back out of it.
        let out = run(LodDraw::Alpha {
            from: far,
            to: 4,
            p: 0.6,
        });
        assert_eq!(out[0].0, 7);
        assert_eq!(
            out[1],
            (
                0,
                LodDraw::Dissolve {
                    level: 4,
                    p: 0.6,
                    incoming: true
                }
            )
        );
    }

    #[test]
    fn an_impostor_stands_for_the_levels_it_is_no_better_than() {
        let levels = LodModel {
            errors: vec![0.0, 1.0, 2.0, 4.0],
            center: glam::Vec3::ZERO,
            radius: 1.0,
        };
        assert_eq!(
            with_impostor(&levels, 8.0).errors,
            vec![0.0, 1.0, 2.0, 4.0, 8.0]
        );
        assert_eq!(with_impostor(&levels, 4.0).errors, vec![0.0, 1.0, 2.0, 4.0]);
        assert_eq!(with_impostor(&levels, 1.5).errors, vec![0.0, 1.0, 1.5]);
    }
}

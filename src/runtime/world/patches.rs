//! Forest patches in a world (see [`crate::bake::foliage::patch`]): composed for the world's
//! layout from its trees' impostors and placed by measuring a sample cell (or read from the
//! cache), uploaded as characters of their own, and drawn in place of their cells' trees
//! where selection finds a patch within the tolerance, as it finds any level. A cell going
//! to or from its patch cross-dissolves (its trees out, the card in, on complementary
//! pixels) over the transition's duration, or pops where transitions pop.

use super::World;
use super::patch_state::{InstalledPatches, PatchState};
use crate::bake::foliage::billboard::chain::{CloudKind, CloudLevel};
use crate::bake::foliage::patch::{
    self, CELL_TREES, ForestPatches, PATCH_GRID, PatchTree, PlacementInputs, TreeViews,
};
use crate::bake::gpu_data::drawable::LevelKind;
use crate::bake::gpu_products::MeasureColour;
use crate::render::Gpu;
use crate::scene::{Instance, LodMethod, ScreenProjection};
use anyhow::{Result, anyhow};
use glam::{Affine3A, Vec3, Vec4};
use rayon::prelude::*;

/// One tree as the cache key sees it.
#[derive(serde::Serialize)]
struct KeyedTree {
    model: u32,
    transform: [f32; 12],
    tint: [f32; 4],
    wind: f32,
    time_offset: f32,
    speed: f32,
}

impl World {
    /// Bakes (or reads from the cache) and uploads the patches of this world's layout, once;
    /// does nothing where the foliage policy keeps trees full or no tree shows an impostor.
    /// Patches are dropped when the layout changes ([`World::relayout`]).
    pub fn ensure_patches(&mut self, gpu: &Gpu, measure: &dyn MeasureColour) -> Result<()> {
        if self.patches.is_some() || self.lod.stays_full(true) {
            return Ok(());
        }
        let impostors: Vec<Option<&CloudLevel>> = (0..self.bakes.len())
            .map(|m| self.shown_impostor(m))
            .collect();
        if impostors.iter().all(Option::is_none) {
            return Ok(());
        }
        let mut trees = Vec::new();
        let mut agent_of = Vec::new();
        for (a, agent) in self.crowd.agents.iter().enumerate() {
            if impostors.get(agent.model).copied().flatten().is_some() {
                let i = agent.instance_at(0.0);
                trees.push(PatchTree {
                    model: i.model,
                    transform: i.transform,
                    tint: i.tint,
                    wind: i.wind,
                    time_offset: i.time_offset,
                    speed: i.speed,
                });
                agent_of.push(a);
            }
        }
        let baked = self.load_or_bake_patches(&trees, &impostors, measure)?;
        let installed = self.upload_patches(gpu, baked, &agent_of)?;
        self.patches = Some(installed);
        Ok(())
    }

    /// Tree `m`'s shown chain.
    fn shown(&self, m: usize) -> Option<&super::InstalledChain> {
        let shown = self.tree_levels.get(m)?.as_ref()?;
        self.chains
            .iter()
            .find(|c| c.model == m && &c.characters == shown)
    }

    /// The impostor level of tree `m`'s shown chain, if it has one.
    fn shown_impostor(&self, m: usize) -> Option<&CloudLevel> {
        self.shown(m)?.impostor.as_deref()
    }

    fn load_or_bake_patches(
        &self,
        trees: &[PatchTree],
        impostors: &[Option<&CloudLevel>],
        measure: &dyn MeasureColour,
    ) -> Result<ForestPatches> {
        let tolerance = self.lod.policy.tolerance_px;
        // Each tree's key of the chain it shows (the impostor the patches are made from).
        let chains: Vec<[u8; 32]> = (0..self.bakes.len())
            .filter_map(|m| Some((m, self.shown(m)?.opts)))
            .filter(|&(m, _)| impostors[m].is_some())
            .map(|(m, opts)| crate::bake::cache::keys::order_key(&self.sources[m].hash, &opts))
            .collect::<Result<_, String>>()
            .map_err(|e| anyhow!(e))?;
        let layout: Vec<KeyedTree> = trees
            .iter()
            .map(|t| KeyedTree {
                model: t.model as u32,
                transform: t.transform.to_cols_array(),
                tint: t.tint.to_array(),
                wind: t.wind,
                time_offset: t.time_offset,
                speed: t.speed,
            })
            .collect();
        let key = crate::bake::cache::keys::patch_key(&chains, &layout, tolerance)
            .map_err(|e| anyhow!(e))?;
        let cache = self.cache();
        let path = cache.file(
            &format!("{}-trees", trees.len()),
            crate::bake::cache::keys::CacheKind::Patches,
            &key,
        );
        let (baked, origin) = cache.load_or_build(&path, &key, || {
            self.bake_patches(trees, impostors, measure, tolerance)
        })?;
        if let crate::bake::cache::Origin::Baked {
            warning: Some(w), ..
        } = origin
        {
            eprintln!("warning: {w}");
        }
        Ok(baked)
    }

    /// Composes a patch for every cell of `trees` and places them by measuring the cell with
    /// the most trees.
    fn bake_patches(
        &self,
        trees: &[PatchTree],
        impostors: &[Option<&CloudLevel>],
        measure: &dyn MeasureColour,
        tolerance_px: f32,
    ) -> Result<ForestPatches> {
        let start = web_time::Instant::now();
        let views: Vec<Option<TreeViews>> = impostors
            .iter()
            .map(|l| l.and_then(TreeViews::of))
            .collect();
        // Cells a few crowns across: the widest crown with the layout's air between.
        let crown = (0..self.bakes.len())
            .filter(|&m| views[m].is_some())
            .map(|m| {
                let s = self.bakes[m].bounds.size();
                s.x.max(s.z)
            })
            .fold(1.0f32, f32::max);
        let cells = patch::cells(trees, CELL_TREES * crown * 1.05);
        let at_rest: Vec<crate::model::Model> = self
            .sources
            .iter()
            .map(|s| crate::bake::impostor::octahedral::at_rest(&s.model))
            .collect();
        let patches: Vec<patch::ForestPatch> = cells
            .par_iter()
            .map(|members| {
                let rep = commonest(trees, members);
                patch::compose(trees, members, &views, &at_rest[rep], PATCH_GRID)
            })
            .collect::<Result<_>>()?;
        log::debug!(
            "{} forest patches composed in {:.2} s",
            patches.len(),
            start.elapsed().as_secs_f64()
        );
        let Some(sample) = (0..patches.len()).max_by_key(|&k| patches[k].members.len()) else {
            return Ok(ForestPatches {
                patches,
                switch_px: None,
                tolerance_px,
                measured: Vec::new(),
            });
        };
        let p = &patches[sample];
        let members: Vec<usize> = p.members.iter().map(|&m| m as usize).collect();
        let rest: Vec<&crate::model::Model> = at_rest.iter().collect();
        let cell = patch::cell_model(
            &format!("forest cell {sample}"),
            trees,
            &members,
            &rest,
            Vec3::from(p.origin),
        );
        let inputs = PlacementInputs {
            cell: &cell,
            impostors: (0..self.bakes.len())
                .map(|m| impostors[m].map(|l| (&self.sources[m].model, l)))
                .collect(),
        };
        // From where the last of the sample's trees shows its impostor.
        let from_px = members
            .iter()
            .filter_map(|&i| self.impostor_switch_px(trees[i].model, tolerance_px))
            .fold(f32::INFINITY, f32::min);
        if !from_px.is_finite() {
            return Err(anyhow!("no tree of the forest shows an impostor"));
        }
        let (switch_px, measured) = patch::place(from_px, |px| {
            patch::errors_at(measure, p, trees, &inputs, px)
        })?;
        for m in &measured {
            log::debug!(
                "forest patch {sample} at {:.1} px: colour error {:.3}, its trees' impostors {:.3}",
                m.px,
                m.patch,
                m.trees
            );
        }
        Ok(ForestPatches {
            patches,
            switch_px,
            tolerance_px,
            measured: vec![(sample as u32, measured)],
        })
    }

    /// The tree's height in pixels below which model `m` shows its impostor, at
    /// `tolerance_px`.
    fn impostor_switch_px(&self, m: usize, tolerance_px: f32) -> Option<f32> {
        let last = self
            .shown(m)?
            .levels
            .last()
            .filter(|l| matches!(l.kind, Some(CloudKind::Impostor { .. })))?;
        let height = self.bakes[m].bounds.size().y;
        Some(tolerance_px * height / last.epsilon.max(1e-6))
    }

    fn upload_patches(
        &mut self,
        gpu: &Gpu,
        baked: ForestPatches,
        agent_of: &[usize],
    ) -> Result<InstalledPatches> {
        let mut patches: Vec<PatchState> = Vec::with_capacity(baked.patches.len());
        let mut of_agent = vec![None; self.crowd.agents.len()];
        for (k, p) in baked.patches.iter().enumerate() {
            let uploaded = p
                .level
                .bake()
                .map_err(|e| anyhow!("{}: {e}", p.level.model.name))
                .and_then(|bake| match self.free_characters.pop() {
                    Some(c) => self.renderer.replace_character(gpu, c, &bake),
                    None => self.renderer.add_character(gpu, &bake),
                });
            let character = match uploaded {
                Ok(c) => c,
                Err(e) => {
                    // The cards uploaded so far are reused later.
                    self.free_characters
                        .extend(patches.iter().map(|s| s.character));
                    return Err(e);
                }
            };
            self.renderer
                .set_level_kind(character, LevelKind::ForestPatch);
            let frame = p.level.impostor.expect("a patch is an impostor");
            let origin = Vec3::from(p.origin);
            for &m in &p.members {
                if let Some(&a) = agent_of.get(m as usize) {
                    of_agent[a] = Some(k as u32);
                }
            }
            patches.push(PatchState {
                character,
                instance: Instance {
                    model: character,
                    transform: Affine3A::from_translation(origin),
                    clip: 0,
                    time_offset: p.time_offset,
                    speed: p.speed,
                    wind: p.wind,
                    tint: Vec4::ONE,
                    fade: None,
                    travel: Vec3::ZERO,
                },
                centre: origin + Vec3::from(frame.centre),
                radius: frame.radius,
                epsilon: baked.epsilon(p.tree_height).unwrap_or(f32::INFINITY),
                fade: 0.0,
            });
        }
        Ok(InstalledPatches {
            patches,
            of_agent,
            baked,
        })
    }

    /// Lets the layout's patches go (their characters are reused).
    pub fn drop_patches(&mut self) {
        if let Some(p) = self.patches.take() {
            self.free_characters
                .extend(p.patches.iter().map(|s| s.character));
        }
    }

    /// Whether side `method` draws patches: a simplified method whose trees are not kept full.
    pub(super) fn shows_patches(&self, method: LodMethod) -> bool {
        self.patches.is_some() && method != LodMethod::None && !self.lod.stays_full(true)
    }

    /// Moves every patch towards being drawn or not, `dt` seconds on (see
    /// [`InstalledPatches::select`]).
    pub(super) fn select_patches(&mut self, screen: &ScreenProjection, dt: f32) {
        let policy = self.lod.policy;
        if let Some(p) = self.patches.as_mut() {
            p.select(&policy, screen, dt);
        }
    }

    /// The layout's patches, where they are baked: how many, where they come in (the trees'
    /// height in pixels at the tolerance they were placed for) and the sample's figures.
    pub fn patches(&self) -> Option<&ForestPatches> {
        self.patches.as_ref().map(|p| &p.baked)
    }
}

/// The model most of `members` are (the first of equals): the one a patch is skinned like.
fn commonest(trees: &[PatchTree], members: &[usize]) -> usize {
    let mut counts: std::collections::BTreeMap<usize, usize> = Default::default();
    for &i in members {
        *counts.entry(trees[i].model).or_default() += 1;
    }
    counts
        .into_iter()
        .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0)))
        .map_or(0, |(m, _)| m)
}

//! A world: the renderer with the scene's characters and trees, the crowd, the camera, and the
//! levels of detail installed with their run-time choices.

use super::levels::LevelSource;
use super::spec::{Loaded, SceneSpec, default_camera, layout_crowd};
use crate::bake::cache::LodCache;
use crate::bake::foliage::billboard::chain::{ChainOptions, CloudKind, TreeLevel};
use crate::bake::gpu_data::drawable::Drawable;
use crate::bake::gpu_data::lod_pack::LodPack;
use crate::render::{FrameStats, FrameView, Gpu, Region, SceneRenderer, Side};
use crate::scene::foliage::FoliagePolicy;
use crate::scene::{
    Camera, Crowd, Instance, LodDraw, LodMethod, LodModel, LodPolicy, ScreenProjection,
};
use anyhow::{Result, bail};

mod install;
mod patch_state;
mod patches;
pub mod selection;
mod view;

use view::impostor_draws;
pub use view::{LodView, with_impostor};

/// A loaded scene: the renderer with its characters, the crowd, a camera, and the levels of
/// detail with their run-time choices.
pub struct World {
    pub spec: SceneSpec,
    pub bakes: Vec<Drawable>,
    pub sources: Vec<LevelSource>,
    /// Where its levels are cached (see [`Loaded::cache`]).
    cache: LodCache,
    pub crowd: Crowd,
    pub camera: Camera,
    pub renderer: SceneRenderer,
    pub lod: LodView,
    /// An instance drawn brighter: the viewer's selection.
    pub highlight: Option<usize>,
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
    /// The layout's forest patches, once baked ([`World::ensure_patches`]).
    patches: Option<patch_state::InstalledPatches>,
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
    /// Its impostor level (what forest patches are composed from), if it has one.
    impostor: Option<Box<crate::bake::foliage::billboard::chain::CloudLevel>>,
}

/// One level of a tree's chain, as the foliage panel lists it.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelSummary {
    /// ε in scene units (0: the full tree).
    pub epsilon: f32,
    /// What it is (None: the full tree).
    pub kind: Option<CloudKind>,
    pub billboards: usize,
    pub triangles: usize,
    /// RMS animation error, in tree heights.
    pub anim_rms: f32,
}

impl LevelSummary {
    fn of(level: &TreeLevel) -> LevelSummary {
        LevelSummary {
            epsilon: level.epsilon,
            kind: level.kind,
            billboards: level.cloud.billboards,
            triangles: level.cloud.model.mesh.triangle_count(),
            anim_rms: level.cloud.animation.rms,
        }
    }
}

impl World {
    /// Whether the scene has trees (models with alpha-cut foliage).
    pub fn has_trees(&self) -> bool {
        self.lod.trees.iter().any(|&t| t)
    }

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
            cache,
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
            trees: bakes.iter().map(|b| b.kind.is_tree()).collect(),
            trackers: Default::default(),
            draws: Default::default(),
            models: bakes
                .iter()
                .map(|b| {
                    let mut slots: [Option<LodModel>; LodMethod::COUNT] = Default::default();
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
            cache,
            crowd,
            camera,
            renderer,
            tree_levels: vec![None; n_models],
            chains: Vec::new(),
            free_characters: Vec::new(),
            lod,
            highlight: None,
            instances: Vec::new(),
            drawn: Default::default(),
            impostors: vec![None; n_models],
            normal_maps: vec![Vec::new(); n_models],
            patches: None,
        })
    }

    /// The level-of-detail cache this world bakes into.
    pub fn cache(&self) -> LodCache {
        self.cache.clone()
    }

    /// Where memory goes, in bytes by kind: on the GPU (see [`GpuMemory`](crate::render::memory::GpuMemory)), the frame's
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
            self.bakes.iter().map(Drawable::heap_bytes).sum(),
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
        // Patches stand for the old layout's cells.
        self.drop_patches();
    }

    pub fn reset_camera(&mut self) {
        self.camera = self.home_camera();
    }

    /// The camera the scene starts with, and `shot` draws from without `--camera`.
    pub fn home_camera(&self) -> Camera {
        default_camera(&self.crowd, &self.bakes)
    }

    /// Chooses every instance's level for a frame at scene time `time`, `dt` seconds of
    /// wall time after the last, seen in a view `height` pixels high.
    pub fn select(&mut self, height: u32, time: f32, dt: f32) {
        if self.lod.impostors_at != self.lod.policy.tolerance_px {
            self.lod.refresh_impostors();
        }
        self.crowd.instances_at(time, &mut self.instances);
        for inst in &mut self.instances {
            inst.travel = travel_of(self.bakes.get(inst.model), inst, time);
        }
        if let Some(inst) = self.highlight.and_then(|h| self.instances.get_mut(h)) {
            // Brighter (a little warmer), whatever its own tint: it stands out without an
            // outline pass, at no cost.
            inst.tint *= glam::Vec4::new(1.8, 1.65, 1.2, 1.0);
        }
        let screen = ScreenProjection::new(
            self.camera.eye(),
            self.camera.fov_y,
            height as f32,
            self.camera.near_far().0,
        );
        self.renderer
            .set_tolerance(self.lod.policy.tolerance_px, height);
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
        self.select_patches(&screen, dt);
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
        let remap = self.remaps();
        if remap {
            for (i, method) in self.lod.methods().enumerate() {
                self.remap_side(i, method);
            }
        }
        let (lod, drawn, instances) = (&self.lod, &self.drawn, &self.instances);
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

    /// Whether instances reach the renderer through their models' levels: trees draw their
    /// level's own character (a billboard cloud, an impostor), far characters their
    /// impostor's. Without either the crowd goes to the renderer as it is.
    fn remaps(&self) -> bool {
        let has_impostors = self.lod.impostors && self.impostors.iter().any(Option::is_some);
        self.tree_levels.iter().any(Option::is_some) || has_impostors
    }

    /// Side `i`'s instances (drawn by `method`) as the renderer draws them, into
    /// `self.drawn[i]`: trees through their chains ([`tree_draws`]), characters at their
    /// impostor's level through its character ([`impostor_draws`]), trees whose forest patch
    /// has come in left to the patch.
    fn remap_side(&mut self, i: usize, method: LodMethod) {
        let lod = &self.lod;
        // Per model: its impostor's level under this side's method and its character.
        let slot = method.index();
        let far: Vec<Option<(u8, usize)>> = (0..self.impostors.len())
            .map(|m| {
                let character = self.impostors[m].as_ref()?.character;
                Some((lod.impostor_level(m, slot)?, character))
            })
            .collect();
        // Per agent: how far its forest patch has come in on this side.
        let fades = match &self.patches {
            Some(p) if self.shows_patches(method) => p.fades(),
            _ => Vec::new(),
        };
        let (instances, draws) = &mut self.drawn[i];
        instances.clear();
        draws.clear();
        for (a, (inst, d)) in self.instances.iter().zip(&lod.draws[i]).enumerate() {
            let fade = fades.get(a).copied().unwrap_or(0.0);
            if fade >= 1.0 {
                continue;
            }
            match self.tree_levels.get(inst.model).and_then(Option::as_ref) {
                Some(levels) => tree_draws(levels, inst, *d, fade, instances, draws),
                None => match far.get(inst.model).copied().flatten() {
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
                },
            }
        }
        if !fades.is_empty()
            && let Some(p) = &self.patches
        {
            p.draws(instances, draws);
        }
    }

    /// Selection and upload for a frame `width`×`height` pixels, `dt` seconds after the last.
    pub fn prepare(&mut self, gpu: &Gpu, size: [u32; 2], time: f32, dt: f32) -> FrameStats {
        self.select(size[1], time, dt);
        self.upload(gpu, size[0] as f32 / size[1].max(1) as f32, time)
    }
}

/// Tree instance `inst` drawn through its chain (`levels`: the renderer's character of each
/// level) for its selection `d`: its level's own character; between two levels (an alpha,
/// dither or morph transition) the two levels' characters cross-dissolving as two instances;
/// where its forest patch is coming in (`fade` > 0), the tree's outgoing half of that dissolve.
fn tree_draws(
    levels: &[usize],
    inst: &Instance,
    d: LodDraw,
    fade: f32,
    instances: &mut Vec<Instance>,
    draws: &mut Vec<LodDraw>,
) {
    let at = |k: u8| Instance {
        model: levels[(k as usize).min(levels.len() - 1)],
        ..*inst
    };
    if fade > 0.0 {
        let level = d.nearest_level();
        instances.push(at(level));
        draws.push(LodDraw::Dissolve {
            level,
            p: fade,
            incoming: false,
        });
        return;
    }
    match d {
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

/// What selection needs to know about a character's levels.
/// Where the clip of `inst` has carried the body of `bake`'s model at scene time `time`: see
/// [`Instance::travel`]. In a cross-fade, the clip that weighs more: an impostor shows that
/// clip's pages alone (`vs_animated_impostor`), and a mesh, whose poses blend, lies between
/// the two, which its sphere (the body's bounds) holds where the clips travel alike.
fn travel_of(bake: Option<&Drawable>, inst: &Instance, time: f32) -> glam::Vec3 {
    let Some(b) = bake.filter(|b| !b.travel.is_empty()) else {
        return glam::Vec3::ZERO;
    };
    match inst.fade {
        Some(f) if f.weight > 0.5 => b.travel_at(f.clip as usize, time * f.speed + f.time_offset),
        _ => b.travel_at(inst.clip as usize, time * inst.speed + inst.time_offset),
    }
}

fn lod_model(bake: &Drawable, pack: &LodPack) -> LodModel {
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
            travel: glam::Vec3::ZERO,
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

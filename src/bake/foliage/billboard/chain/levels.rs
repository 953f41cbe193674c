//! A tree's chain of levels as plain data: what each level is (a cloud, clumps or the
//! impostor), the level itself and how it is baked for the GPU, and the options the chain is
//! cut by.

use crate::bake::foliage::billboard::Grouping;
use crate::bake::foliage::billboard::atlas::AtlasDensity;
use crate::bake::foliage::billboard::wood::only_foliage;
use crate::bake::foliage::spectral::cloud::SpectralParams;
use crate::bake::foliage::spectral::description::DescriptionType;
use crate::bake::foliage::spectral::metrics::AnimationError;
use crate::bake::gpu_data::drawable::Drawable;
use crate::bake::gpu_data::spectra::{NO_ROW, SpectralMotion};
use crate::bake::impostor::octahedral::ImpostorFrame;
use crate::model::Model;
use anyhow::Result;
use serde::{Deserialize, Serialize};

crate::choice! {
    /// Which clouds a tree's chain is made of (the viewer's level policy, less "full").
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
    pub enum ChainStyle {
        /// Skeleton clouds while grouping by bones pays, then spectral clouds at a distance (the
        /// thesis's proposal §6.5 and Ch. 9: skeleton clouds near, spectral far), and view-selected
        /// clumps at the coarse end ([`ChainOptions::clumps_from`]).
        Automatic => "automatic",
        /// Skeleton clouds all the way: per bone with alike siblings merged, then coarser
        /// branch subtrees (the chain before spectral clouds existed).
        Skeleton => "skeleton",
        /// Spectral clouds from level 1 on.
        Spectral => "spectral",
    }
}

/// How a level's leaves become billboards.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum CloudKind {
    /// Skeleton clouds (thesis Ch. 7): clouds by bone groups, billboards skinned to a bone.
    Skeleton(Grouping),
    /// Spectral clouds (thesis Ch. 6): clouds by motion clusters, billboards skinned to their
    /// leaves' shared bone plus a spectral offset (§6.4).
    Spectral(SpectralParams),
    /// View-selected clump billboards ([`crate::bake::foliage::billboard::clumps`]): the crown in `clumps` clumps, each
    /// with `views` upright planes of which the renderer draws the one facing the viewer.
    Clumps { clumps: usize, views: usize },
    /// The far level after the coarsest cloud: the whole tree as an octahedral impostor of
    /// `frames` × `frames` views, one bending quad ([`crate::bake::impostor::octahedral`]).
    Impostor { frames: u32 },
}

impl CloudKind {
    /// What a level is, in a word (the foliage panel's column): full, skeleton, spectral,
    /// clumps or impostor.
    pub fn word(kind: Option<&CloudKind>) -> &'static str {
        match kind {
            None => "full",
            Some(CloudKind::Skeleton(_)) => "skeleton",
            Some(CloudKind::Spectral(_)) => "spectral",
            Some(CloudKind::Clumps { .. }) => "clumps",
            Some(CloudKind::Impostor { .. }) => "impostor",
        }
    }

    /// In words, for tables and reports.
    pub fn name(kind: Option<&CloudKind>) -> String {
        match kind {
            None => "full tree".into(),
            Some(CloudKind::Skeleton(Grouping::PerBone)) => "per bone".into(),
            Some(CloudKind::Skeleton(Grouping::Siblings)) => {
                "per bone, alike siblings merged".into()
            }
            Some(CloudKind::Skeleton(Grouping::Subtree { forks: 0 })) => "whole crown".into(),
            Some(CloudKind::Skeleton(Grouping::Subtree { forks })) => {
                format!("subtree below {forks} forks")
            }
            Some(CloudKind::Spectral(p)) => format!(
                "spectral, {} clusters, {}{}",
                p.clusters,
                p.kind.name(),
                if p.shared_bone { "" } else { ", plain SCA" }
            ),
            Some(CloudKind::Clumps { clumps, views }) => {
                format!("{clumps} clumps, {views} views each")
            }
            Some(CloudKind::Impostor { frames }) => {
                format!("octahedral impostor, {frames}×{frames} views")
            }
        }
    }
}

/// What one cloud level is.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CloudLevel {
    pub model: Model,
    /// A spectral cloud's billboard motion (None: billboards follow their bones only).
    pub motion: Option<SpectralMotion>,
    /// Clouds it was built as: bone groups, or motion clusters.
    pub groups: usize,
    /// How far its billboards' motion strays from the leaves' (0 for the full tree).
    pub animation: AnimationError,
    pub billboards: usize,
    /// Total billboard area, scene units²: their rectangles'.
    pub area: f32,
    /// The area its billboards are drawn with, scene units²: their outlines', trimmed round
    /// their leaves ([`crate::bake::foliage::billboard::trim`]); 0 in old caches and for
    /// levels without billboards.
    #[serde(default)]
    pub drawn_area: f32,
    /// Bytes of its atlas and its lighting (RGBA8 each, base level).
    pub texture_bytes: usize,
    /// An impostor's frame: how its quad is placed and its views are laid out (None for
    /// meshes and clouds).
    pub impostor: Option<ImpostorFrame>,
    /// A cloud's crown occlusion per vertex of `model` (0 on the billboards, whose atlas
    /// carries it per texel); empty for the full tree (its bake works it out) and impostors
    /// (their views carry it).
    #[serde(default)]
    pub occlusion: Vec<f32>,
    /// A clump level's view window per billboard, in billboard order (see [`crate::bake::foliage::billboard::clumps`]);
    /// empty where every billboard is drawn from every view.
    #[serde(default)]
    pub view_windows: Vec<f32>,
    /// Billboards to a clump, of which each view draws one (1, or 0 in old caches, for
    /// clouds, whose every billboard is drawn).
    #[serde(default)]
    pub views: usize,
    /// The vertices of each billboard, in billboard order (its outline's corners: 4 for the
    /// whole rectangle, up to [`crate::bake::foliage::billboard::trim::MAX_CORNERS`] where
    /// trimmed); empty for levels without billboards.
    #[serde(default)]
    pub corners: Vec<u32>,
}

crate::choice! {
    /// How a tree's chain orders its levels by screen size (see [`super::order`]).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
    pub enum FoliageOrder {
        /// Each level from where its ε projects to the tolerance (the thesis's chain).
        Epsilon => "epsilon",
        /// At each switch size the cheapest level no worse than the ε chain's there.
        #[default]
        Cost => "cost",
    }
}

/// How a tree's chain of levels is cut.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ChainOptions {
    /// ε of level 1, as a fraction of the tree's height.
    pub first_epsilon: f32,
    /// Each level's ε is the last one's times this (2: ε doubles level by level).
    pub epsilon_growth: f32,
    /// The chain ends at the first level with this many billboards or fewer.
    pub last_billboards: usize,
    /// Screen tolerance the levels are made for, pixels: an atlas gets about two texels per
    /// screen pixel at the distance where its ε projects to this (see [`Self::atlas_density`]).
    pub tolerance_px: f32,
    /// The fewest texels across the tree's height a clump level's atlas gets (see
    /// [`Self::atlas_density`]).
    pub min_atlas_texels: f32,
    pub style: ChainStyle,
    /// Spectral clouds: the description type their clustering and motion use, and the
    /// lines kept per axis (K).
    pub description: DescriptionType,
    pub bins: usize,
    /// Spectral clouds: billboards follow their leaves' shared bone (§6.4), or hang from the
    /// root with all the motion in their spectra (plain SCA §6.2).
    pub shared_bone: bool,
    /// Spectral clouds from level 1 start with this many motion clusters (halved level by
    /// level).
    pub first_clusters: usize,
    /// A level whose cloud has at most this many billboards is made of as many clumps instead,
    /// `clump_views` planes each, of which a view draws one ([`crate::bake::foliage::billboard::clumps`]): the same
    /// billboards drawn, closer to the leaves. 0: clouds all the way. Automatic chains only:
    /// the skeleton and spectral chains are the thesis's methods, kept as they are for
    /// comparison.
    pub clumps_from: usize,
    pub clump_views: usize,
    pub seed: u64,
    /// Which level each size draws: by ε alone, or the cheapest no worse (see
    /// [`super::order`]).
    pub order: FoliageOrder,
}

impl ChainOptions {
    /// How sharp the atlas of a level of ε `epsilon` on a tree `height` high, made as `kind`,
    /// is drawn: about two texels a screen pixel where the level comes in, but at least 8 a
    /// scene unit, nor more than 800 across the tree; a clump level's never fewer than
    /// [`Self::min_atlas_texels`] across it.
    /// Its gutter is as wide as that needs where the level comes in
    /// ([`AtlasDensity::for_level`]).
    ///
    /// A level is also looked at larger than where it comes in: forced in the viewer or by
    /// `shot --force-level` to compare levels by eye, in the report's contact sheet, or with
    /// the tolerance raised (the viewer's slider goes to 16 px, where a level comes in ten
    /// times larger). At two texels a pixel of a tree a few dozen pixels high the clump levels'
    /// leaves were a blur there, blotches of one shade (the sapling's 99-clump level had 75
    /// texels across its height, its 22-clump level 52). A clump level holds few billboards,
    /// so the floor costs it little atlas. The cloud levels keep the rule: sharper, an atlas is
    /// read at a deeper mip level where its level comes in, whose texels smooth the leaves'
    /// coverage where the tree's own leaves are sampled sharp, and the broadleaf's level 3
    /// (ε 0.02 h, 150 texels across) scored 0.288 against 0.270 at its 75 px with 256, which
    /// put its impostor in a level sooner, paler than the cloud, on a third of the default
    /// scene's broadleaves.
    pub fn atlas_density(&self, epsilon: f32, height: f32, kind: &CloudKind) -> AtlasDensity {
        let h = height.max(1e-6);
        let floor = match kind {
            CloudKind::Clumps { .. } => self.min_atlas_texels / h,
            _ => 0.0,
        };
        let texels = (2.0 * self.tolerance_px / epsilon.max(1e-9))
            .max(8.0)
            .max(floor)
            .min(800.0 / h);
        AtlasDensity::for_level(texels, epsilon, self.tolerance_px)
    }
}

impl Default for ChainOptions {
    fn default() -> Self {
        ChainOptions {
            first_epsilon: 0.005,
            epsilon_growth: 2.0,
            last_billboards: 10,
            tolerance_px: 1.5,
            min_atlas_texels: 256.0,
            style: ChainStyle::Automatic,
            description: DescriptionType::AxisPhase,
            bins: crate::bake::foliage::spectral::DEFAULT_BINS,
            shared_bone: true,
            first_clusters: 64,
            clumps_from: 128,
            clump_views: crate::bake::foliage::billboard::clumps::DEFAULT_VIEWS,
            seed: 1,
            order: FoliageOrder::Cost,
        }
    }
}

/// One level of a tree's chain.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TreeLevel {
    /// ε in scene units (0 for the full tree, level 0).
    pub epsilon: f32,
    /// How its leaves became billboards (None for the full tree).
    pub kind: Option<CloudKind>,
    pub cloud: CloudLevel,
    pub bake_seconds: f64,
}

impl CloudLevel {
    /// A level's foliage alone (wood left out), with its motion. `only_foliage` keeps the
    /// billboards' corners in order, and they were the model's last vertices, so their rows keep
    /// their order too.
    pub fn foliage(&self) -> (Model, Option<SpectralMotion>) {
        let model = only_foliage(&self.model);
        let motion = self.motion.as_ref().map(|m| SpectralMotion {
            spectra: m.spectra.clone(),
            vertex_rows: m
                .vertex_rows
                .iter()
                .copied()
                .filter(|&r| r != NO_ROW)
                .collect(),
        });
        debug_assert!(
            motion
                .as_ref()
                .is_none_or(|m| m.vertex_rows.len() == model.mesh.vertex_count())
        );
        (model, motion)
    }

    /// Its foliage alone ([`Self::foliage`]) baked for the GPU as the colour measures draw
    /// it: with its motion and view windows, and no crown occlusion (masks and colours
    /// compared alike, and a crown's worth of rays saved a measurement).
    pub fn foliage_bake(&self) -> Result<(Model, Drawable), String> {
        let (model, motion) = self.foliage();
        let bake = Drawable::tree_level(&model, motion.as_ref(), &[], &self.vertex_windows(&model))
            .map_err(|e| format!("{}: {e}", model.name))?;
        Ok((model, bake))
    }

    /// An octahedral impostor's card (`model`, framed by `frame`) as a level standing for
    /// `groups` trees: one billboard, its texture bytes counted from the model's materials.
    pub fn impostor(model: Model, frame: ImpostorFrame, groups: usize) -> CloudLevel {
        let texture_bytes = model
            .materials
            .iter()
            .filter_map(|m| m.texture.as_ref())
            .map(|t| t.pixels.len())
            .sum();
        CloudLevel {
            model,
            motion: None,
            groups,
            animation: AnimationError::default(),
            billboards: 1,
            area: 4.0 * frame.radius * frame.radius,
            drawn_area: 4.0 * frame.radius * frame.radius,
            texture_bytes,
            impostor: Some(frame),
            occlusion: Vec::new(),
            view_windows: Vec::new(),
            views: 1,
            corners: Vec::new(),
        }
    }

    /// The tree itself, leaves and all, as a level.
    pub fn full(tree: &Model) -> CloudLevel {
        CloudLevel {
            model: tree.clone(),
            motion: None,
            groups: 0,
            animation: AnimationError::default(),
            billboards: 0,
            area: 0.0,
            drawn_area: 0.0,
            texture_bytes: 0,
            impostor: None,
            occlusion: Vec::new(),
            view_windows: Vec::new(),
            views: 1,
            corners: Vec::new(),
        }
    }

    /// Billboards drawn from any one view: all of a cloud's, one per clump of a clump level.
    pub fn drawn_billboards(&self) -> usize {
        self.billboards / self.views.max(1)
    }

    /// Its view windows per vertex of `model` (the level's model, or its foliage alone): the
    /// billboards' corners are the last vertices, [`Self::corners`] to a billboard in order
    /// (four where it has none). Empty where the level has none.
    pub fn vertex_windows(&self, model: &Model) -> Vec<f32> {
        if self.view_windows.iter().all(|&w| w == 0.0) {
            return Vec::new();
        }
        let corners = |b: usize| self.corners.get(b).map_or(4, |&c| c as usize);
        let billboard_vertices: usize = (0..self.view_windows.len()).map(corners).sum();
        let n = model.mesh.vertex_count();
        let mut out = vec![0.0; n.saturating_sub(billboard_vertices)];
        for (b, &w) in self.view_windows.iter().enumerate() {
            out.extend(std::iter::repeat_n(w, corners(b)));
        }
        out.truncate(n);
        out
    }

    /// The level baked for the GPU: a mesh or cloud with its spectral motion, an impostor
    /// with its frame.
    pub fn bake(&self) -> Result<Drawable, String> {
        match self.impostor {
            Some(frame) => {
                // Its quad's vertices keep their order: the shader finds its rows by index.
                let mut bake = Drawable::in_order(&self.model)?;
                // The tree's bounds, not the card's, grown by how far the card sways (its
                // depth over the animation: at rest it has none).
                let [lo, hi] = frame.bounds.map(glam::Vec3::from);
                let sway = glam::Vec3::splat(bake.bounds.size().z);
                bake.bounds = crate::model::Bounds {
                    min: lo - sway,
                    max: hi + sway,
                };
                bake.kind = crate::bake::gpu_data::drawable::DrawKind::TreeImpostor(frame);
                Ok(bake)
            }
            None if self.billboards == 0 => {
                Drawable::with_motion(&self.model, self.motion.as_ref())
            }
            None => Drawable::tree_level(
                &self.model,
                self.motion.as_ref(),
                &self.occlusion,
                &self.vertex_windows(&self.model),
            ),
        }
    }
}

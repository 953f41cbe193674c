//! A tree's chain of levels of detail (thesis Ch. 7 and §6.5: Bennett-Therkildsen, Carlsen &
//! Schmid, "Animated billboard clouds", Aalborg University, 2007): the full tree, then its
//! foliage as billboard clouds of growing ε, end to end: the cloud, its atlas (drawn through
//! [`RasterizeAtlas`], then dilated), and the tree model that draws it; and the chain cached.

use super::atlas::{AtlasDensity, LeafCorner, atlas_triangles, layout, lighting_material};
use super::cloud::CloudParams;
use super::occlusion::CrownDensity;
use super::siblings::merge_siblings;
use super::wood::{WoodChain, only_foliage};
use super::{Foliage, Grouping, cloud_model, grouped_cloud, is_cut_out};
use crate::anim::skinning_over_loop;
use crate::bake::cache::{LodCache, Origin};
use crate::bake::foliage::spectral::cloud::{SpectralParams, lines_per_axis, spectral_cloud};
use crate::bake::foliage::spectral::description::DescriptionType;
use crate::bake::foliage::spectral::metrics::{AnimationError, animation_error, traced_leaves};
use crate::bake::gpu_data::drawable::CharacterBake;
use crate::bake::gpu_data::materials::{MaterialLayers, dilate};
use crate::bake::gpu_data::spectra::{NO_ROW, SpectraTexture, SpectralMotion};
use crate::bake::impostor::octahedral::{self, ImpostorFrame, ViewGrid};
use crate::bake::impostor::placement;
use crate::bake::seams::{MeasureColour, MeasureImpostor, RasterizeAtlas};
use crate::model::Model;
use anyhow::{Result, anyhow};
use serde::{Deserialize, Serialize};

/// Texels of dilated colour round every leaf in the atlas.
const DILATE_RINGS: u32 = 4;

/// How a level's leaves become billboards.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum CloudKind {
    /// Skeleton clouds (thesis Ch. 7): clouds by bone groups, billboards skinned to a bone.
    Skeleton(Grouping),
    /// Spectral clouds (thesis Ch. 6): clouds by motion clusters, billboards skinned to their
    /// leaves' shared bone plus a spectral offset (§6.4).
    Spectral(SpectralParams),
    /// View-selected clump billboards ([`super::clumps`]): the crown in `clumps` clumps, each
    /// with `views` upright planes of which the renderer draws the one facing the viewer.
    Clumps { clumps: usize, views: usize },
    /// The far level after the coarsest cloud: the whole tree as an octahedral impostor of
    /// `frames` × `frames` views, one bending quad ([`crate::bake::impostor::octahedral`]).
    Impostor { frames: u32 },
}

impl CloudKind {
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
    /// Total billboard area, scene units².
    pub area: f32,
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
    /// A clump level's view window per billboard, in billboard order (see [`super::clumps`]);
    /// empty where every billboard is drawn from every view.
    #[serde(default)]
    pub view_windows: Vec<f32>,
    /// Billboards to a clump, of which each view draws one (1, or 0 in old caches, for
    /// clouds, whose every billboard is drawn).
    #[serde(default)]
    pub views: usize,
}

/// The tree drawn with a billboard cloud of its foliage at `params`, made as `kind`, its atlas
/// drawn at `density` (texels per scene unit, and gutter). The wood is that of `wood` (the tree
/// itself, or the tree with its wood simplified). `crown` (the full tree's, where it has
/// leaves) darkens the wood and the atlas's texels inside the crown.
#[allow(clippy::too_many_arguments)]
pub fn cloud_level(
    raster: &dyn RasterizeAtlas,
    tree: &Model,
    foliage: &Foliage,
    params: &CloudParams,
    kind: &CloudKind,
    density: impl Into<AtlasDensity>,
    wood: &Model,
    crown: Option<&CrownDensity>,
) -> Result<CloudLevel> {
    let built = build_cloud(tree, foliage, params, kind)?;
    level_of_cloud(raster, tree, foliage, built, density.into(), wood, crown)
}

/// A cloud's billboards before its atlas and model are made: enough to count them, which is
/// all the chain needs to choose a level's kind.
struct BuiltCloud<'a> {
    /// The leaves it was built from: the tree's, or those rebound to merged siblings.
    foliage: std::borrow::Cow<'a, Foliage>,
    cloud: super::SkeletonCloud,
    /// A spectral cloud's lines per billboard, and lines per axis.
    lines: Option<(Vec<[Vec<crate::bake::gpu_data::spectra::Line>; 3]>, usize)>,
    /// The clouds or clumps it was built as.
    groups: usize,
    /// Billboards to a clump, of which a view draws one (1 for clouds).
    views: usize,
    /// How far a drawn leaf may lie off its billboard (the atlas's depth order is scaled to it).
    depth: f32,
}

/// The billboards of `foliage` at `params`, made as `kind`.
fn build_cloud<'a>(
    tree: &Model,
    foliage: &'a Foliage,
    params: &CloudParams,
    kind: &CloudKind,
) -> Result<BuiltCloud<'a>> {
    use std::borrow::Cow;
    Ok(match kind {
        CloudKind::Skeleton(grouping) => {
            let foliage = if *grouping == Grouping::Siblings {
                Cow::Owned(merge_siblings(tree, foliage, params.epsilon))
            } else {
                Cow::Borrowed(foliage)
            };
            let cloud = grouped_cloud(&tree.skeleton, &foliage, params, *grouping);
            let mut bones = cloud.bones.clone();
            bones.sort_unstable();
            bones.dedup();
            BuiltCloud {
                foliage,
                cloud,
                lines: None,
                groups: bones.len(),
                views: 1,
                depth: params.epsilon,
            }
        }
        CloudKind::Spectral(sp) => {
            let s = spectral_cloud(tree, foliage, params, sp);
            BuiltCloud {
                foliage: Cow::Borrowed(foliage),
                cloud: s.cloud,
                lines: Some((s.lines, lines_per_axis(sp))),
                groups: s.clusters,
                views: 1,
                depth: params.epsilon,
            }
        }
        CloudKind::Clumps { clumps, views } => {
            let c = super::clumps::clump_cloud(tree, foliage, *clumps, *views, params.seed);
            BuiltCloud {
                foliage: Cow::Borrowed(foliage),
                groups: c.clumps,
                views: c.views,
                depth: c.depth,
                cloud: c.cloud,
                lines: None,
            }
        }
        CloudKind::Impostor { .. } => {
            return Err(anyhow!(
                "an impostor is not a billboard cloud: see impostor_level"
            ));
        }
    })
}

/// The level that draws `built` (the tree's leaves `original`, perhaps rebound first): the
/// atlas, the model with `wood`, the motion, the animation error against `original`.
fn level_of_cloud(
    raster: &dyn RasterizeAtlas,
    tree: &Model,
    original: &Foliage,
    built: BuiltCloud<'_>,
    density: AtlasDensity,
    wood: &Model,
    crown: Option<&CrownDensity>,
) -> Result<CloudLevel> {
    let BuiltCloud {
        foliage,
        cloud,
        lines,
        groups,
        views,
        depth,
    } = built;
    let foliage = foliage.as_ref();
    let atlas_layout = layout(&cloud.billboards, density).map_err(|e| anyhow!(e))?;
    let mesh = &tree.mesh;
    let occlusion_at = |p: glam::Vec3| crown.map_or(0.0, |c| c.occlusion(p));
    // One occlusion a leaf, at its centre: leaves are small beside the crown's voxels. Found
    // once a leaf, not once a billboard drawing it: a clump level draws every leaf on four
    // planes, and the conifer's spent a second a level marching the same rays again.
    let leaf_occlusion: Vec<f32> = {
        use rayon::prelude::*;
        foliage
            .leaves
            .par_iter()
            .map(|l| occlusion_at(l.centre()))
            .collect()
    };
    let triangles = atlas_triangles(&cloud.billboards, &atlas_layout, depth, |leaf| {
        let occlusion = leaf_occlusion[leaf as usize];
        foliage.triangles[leaf as usize]
            .iter()
            .map(|&t| {
                let i = &mesh.indices[3 * t as usize..3 * t as usize + 3];
                [0, 1, 2].map(|k| {
                    let v = i[k] as usize;
                    LeafCorner {
                        position: mesh.positions[v],
                        uv: mesh.uvs[v],
                        normal: mesh.normals[v],
                        occlusion,
                    }
                })
            })
            .collect()
    });
    let leaf_material = tree
        .materials
        .iter()
        .find(|m| is_cut_out(m))
        .ok_or_else(|| anyhow!("{}: no foliage material", tree.name))?;
    let leaf = MaterialLayers::bake(std::slice::from_ref(leaf_material));
    let images = raster.rasterize(&atlas_layout, &triangles, &leaf)?;
    let (mut atlas, mut lighting) = (images.colour, images.lighting);
    dilate(&mut atlas.pixels, atlas.width, atlas.height, DILATE_RINGS);
    dilate(
        &mut lighting.pixels,
        lighting.width,
        lighting.height,
        DILATE_RINGS,
    );
    let texture_bytes = atlas.pixels.len() + lighting.pixels.len();
    let animation = animation_error(
        tree,
        original,
        &cloud,
        lines.as_ref().map(|(l, _)| l.as_slice()),
        &skinning_over_loop(tree, crate::bake::foliage::spectral::DEFAULT_SAMPLES),
        &traced_leaves(original),
    );
    let mut model = cloud_model(wood, &cloud, &atlas_layout, atlas);
    model.materials.push(lighting_material(lighting));
    let billboard_material = (model.materials.len() - 2) as u16;
    let occlusion = model
        .mesh
        .positions
        .iter()
        .zip(&model.mesh.materials)
        .map(|(&p, &m)| {
            if m == billboard_material {
                0.0
            } else {
                occlusion_at(p)
            }
        })
        .collect();
    // The billboards' corners are the model's last vertices, four per billboard in order.
    let motion = match lines {
        Some((lines, bins)) => {
            let spectra = SpectraTexture::new(&lines, bins).map_err(|e| anyhow!(e))?;
            let wood_vertices = model.mesh.vertex_count() - 4 * lines.len();
            let mut vertex_rows = vec![NO_ROW; wood_vertices];
            vertex_rows.extend((0..lines.len() as u32).flat_map(|b| [b; 4]));
            Some(SpectralMotion {
                spectra,
                vertex_rows,
            })
        }
        None => None,
    };
    Ok(CloudLevel {
        impostor: None,
        billboards: cloud.billboards.len(),
        groups,
        animation,
        area: cloud.total_area(),
        texture_bytes,
        model,
        motion,
        occlusion,
        view_windows: if cloud.billboards.iter().any(|b| b.view_window != 0.0) {
            cloud.billboards.iter().map(|b| b.view_window).collect()
        } else {
            Vec::new()
        },
        views,
    })
}

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
    /// `clump_views` planes each, of which a view draws one ([`super::clumps`]): the same
    /// billboards drawn, closer to the leaves. 0: clouds all the way. Automatic chains only:
    /// the skeleton and spectral chains are the thesis's methods, kept as they are for
    /// comparison.
    pub clumps_from: usize,
    pub clump_views: usize,
    pub seed: u64,
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
            clump_views: super::clumps::DEFAULT_VIEWS,
            seed: 1,
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

/// The groupings tried in turn, finest first.
const GROUPINGS: [Grouping; 5] = [
    Grouping::Siblings,
    Grouping::Subtree { forks: 3 },
    Grouping::Subtree { forks: 2 },
    Grouping::Subtree { forks: 1 },
    Grouping::Subtree { forks: 0 },
];

/// Levels must coarsen: ε grows by at least this factor from one to the next.
pub const MIN_EPSILON_GROWTH: f32 = 1.25;

/// The level-of-detail chain of a tree: L0 the full tree, then billboard clouds for ε growing by
/// `epsilon_growth` (doubling by default) from `first_epsilon`, each with the wood simplified to
/// the same error bound ([`WoodChain`]), until a level has at most `last_billboards` billboards.
///
/// Skeleton clouds are built per bone, sibling bones that move alike within ε sharing one
/// ([`Grouping::Siblings`]), while that pays. Where doubling ε would not cut the count by a
/// fifth, bones no longer make good groups: the [`ChainStyle::Skeleton`] chain then groups the
/// leaves by coarser branch subtrees (down to one cloud for the whole crown), the
/// [`ChainStyle::Automatic`] one goes on with spectral clouds of half as many motion clusters
/// as the last level had bone groups. Spectral clouds halve their cluster count level by level
/// (and again at the same ε where a level would not cut the count by a fifth).
///
/// At the coarse end of an automatic chain, from the first cloud of at most `clumps_from`
/// billboards, each level is made of as many view-selected clumps as its cloud has billboards ([`super::clumps`]): each
/// view draws as many billboards, and a clump's leaves lie nearer its planes (its ε bound,
/// [`super::clumps::ClumpCloud::epsilon`], is within the cloud's) and are never seen edge-on.
/// On the project's trees this lowers the colour error at 36 billboards drawn from 0.33–0.49
/// to 0.20–0.28 (the tree report's `against-thesis.md`).
///
/// `progress` hears the fraction done (estimated: about eight levels to a chain).
pub fn tree_chain(
    raster: &dyn RasterizeAtlas,
    tree: &Model,
    foliage: &Foliage,
    opts: &ChainOptions,
    progress: &(dyn Fn(f32) + Sync),
) -> Result<Vec<TreeLevel>> {
    let h = crate::bake::foliage::billboard::tree_height(tree);
    let mut levels = vec![full_tree(tree)];
    let wood = WoodChain::new(tree);
    let crown = CrownDensity::of(tree);
    let mut eps = opts.first_epsilon.max(1e-4) * h;
    let mut g = 0usize;
    // Motion clusters, once the chain has turned spectral.
    let mut clusters = (opts.style == ChainStyle::Spectral).then_some(opts.first_clusters.max(1));
    let mut previous = usize::MAX;
    let mut previous_groups = usize::MAX;
    for _ in 0..40 {
        let start = std::time::Instant::now();
        let params = CloudParams {
            epsilon: eps,
            seed: opts.seed,
            ..Default::default()
        };
        let kind = match clusters {
            Some(k) => CloudKind::Spectral(SpectralParams {
                kind: opts.description,
                clusters: k,
                bins: opts.bins,
                shared_bone: opts.shared_bone,
                seed: opts.seed,
                ..Default::default()
            }),
            None => CloudKind::Skeleton(GROUPINGS[g]),
        };
        // Counted before anything is drawn: a level that hardly improves on the last is
        // not made, and a coarse one is made as clumps instead.
        let built = build_cloud(tree, foliage, &params, &kind)?;
        let count = built.cloud.billboards.len();
        // A level that hardly improves on the last: group coarser at the same ε instead.
        if count as f32 > 0.8 * previous as f32 {
            match clusters {
                None if opts.style == ChainStyle::Automatic => {
                    clusters = Some((previous_groups / 2).max(1));
                    continue;
                }
                None if g + 1 < GROUPINGS.len() => {
                    g += 1;
                    continue;
                }
                Some(k) if k > 1 => {
                    clusters = Some(k / 2);
                    continue;
                }
                _ => {}
            }
        }
        previous_groups = built.groups;
        let clumps_here = opts.style == ChainStyle::Automatic && count <= opts.clumps_from;
        let (kind, built) = if clumps_here {
            let clumps = CloudKind::Clumps {
                clumps: count.max(1),
                views: opts.clump_views,
            };
            let built = build_cloud(tree, foliage, &params, &clumps)?;
            (clumps, built)
        } else {
            (kind, built)
        };
        let base = wood.tree_at(tree, eps);
        let density = opts.atlas_density(eps, h, &kind);
        let cloud = level_of_cloud(raster, tree, foliage, built, density, &base, crown.as_ref())?;
        levels.push(TreeLevel {
            epsilon: eps,
            kind: Some(kind),
            cloud,
            bake_seconds: start.elapsed().as_secs_f64(),
        });
        if count <= opts.last_billboards {
            break;
        }
        progress((levels.len() as f32 / 9.0).min(0.95));
        previous = count;
        clusters = clusters.map(|k| (k / 2).max(1));
        eps *= opts.epsilon_growth.max(MIN_EPSILON_GROWTH);
    }
    Ok(levels)
}

/// Level 0 of a tree's chain: the tree itself.
fn full_tree(tree: &Model) -> TreeLevel {
    TreeLevel {
        epsilon: 0.0,
        kind: None,
        cloud: CloudLevel::full(tree),
        bake_seconds: 0.0,
    }
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

    /// The tree itself, leaves and all, as a level.
    pub fn full(tree: &Model) -> CloudLevel {
        CloudLevel {
            model: tree.clone(),
            motion: None,
            groups: 0,
            animation: AnimationError::default(),
            billboards: 0,
            area: 0.0,
            texture_bytes: 0,
            impostor: None,
            occlusion: Vec::new(),
            view_windows: Vec::new(),
            views: 1,
        }
    }

    /// Billboards drawn from any one view: all of a cloud's, one per clump of a clump level.
    pub fn drawn_billboards(&self) -> usize {
        self.billboards / self.views.max(1)
    }

    /// Its view windows per vertex of `model` (the level's model, or its foliage alone): the
    /// billboards' corners are the last vertices, four to a billboard in order. Empty where
    /// the level has none.
    pub fn vertex_windows(&self, model: &Model) -> Vec<f32> {
        if self.view_windows.iter().all(|&w| w == 0.0) {
            return Vec::new();
        }
        let n = model.mesh.vertex_count();
        let mut out = vec![0.0; n.saturating_sub(4 * self.view_windows.len())];
        out.extend(self.view_windows.iter().flat_map(|&w| [w; 4]));
        out.truncate(n);
        out
    }

    /// The level baked for the GPU: a mesh or cloud with its spectral motion, an impostor
    /// with its frame.
    pub fn bake(&self) -> Result<CharacterBake, String> {
        match self.impostor {
            Some(frame) => {
                // Its quad's vertices keep their order: the shader finds its rows by index.
                let mut bake = CharacterBake::in_order(&self.model)?;
                // The tree's bounds, not the card's, grown by how far the card sways (its
                // depth over the animation: at rest it has none).
                let [lo, hi] = frame.bounds.map(glam::Vec3::from);
                let sway = glam::Vec3::splat(bake.bounds.size().z);
                bake.bounds = crate::model::Bounds {
                    min: lo - sway,
                    max: hi + sway,
                };
                bake.impostor = Some(frame);
                Ok(bake)
            }
            None if self.billboards == 0 => {
                CharacterBake::with_motion(&self.model, self.motion.as_ref())
            }
            None => CharacterBake::tree_level(
                &self.model,
                self.motion.as_ref(),
                &self.occlusion,
                &self.vertex_windows(&self.model),
            ),
        }
    }
}

/// The impostor after a chain's clouds: the tree's octahedral impostor, placed by the rule
/// characters' impostors follow ([`placement`]): it takes the place of the finest level k,
/// from the coarse end on and never level 1, where its colour error at k's switch size is no
/// worse than level k's own; or, beating none there, comes in further off than the coarsest
/// cloud. So the impostor's error at its switch size stays within the chain's own, and
/// selection treats it like any level.
///
/// Returns the impostor level and the index it goes in at (the levels from there on give way
/// to it), or `None` where it beats no cloud level (it is then not part of the chain).
pub fn impostor_level(
    raster: &dyn RasterizeAtlas,
    measure: &dyn MeasureColour,
    tree: &Model,
    chain: &[TreeLevel],
    opts: &ChainOptions,
) -> Result<Option<(TreeLevel, usize)>> {
    let start = std::time::Instant::now();
    let grid = ViewGrid {
        frames: octahedral::FRAMES,
        cell: octahedral::CELL,
    };
    let (model, frame) = octahedral::bake_impostor(raster, tree, grid)?;
    log::debug!(
        "{}: impostor views baked in {:.2} s",
        tree.name,
        start.elapsed().as_secs_f64()
    );
    let texture_bytes = model
        .materials
        .iter()
        .filter_map(|m| m.texture.as_ref())
        .map(|t| t.pixels.len())
        .sum();
    let level = CloudLevel {
        model,
        motion: None,
        groups: 1,
        animation: AnimationError::default(),
        billboards: 1,
        area: 4.0 * frame.radius * frame.radius,
        texture_bytes,
        impostor: Some(frame),
        occlusion: Vec::new(),
        view_windows: Vec::new(),
        views: 1,
    };
    let mut fit = TreeFit {
        measure,
        tree,
        impostor: &level,
        chain,
    };
    let errors: Vec<f32> = chain.iter().map(|l| l.epsilon).collect();
    let height = crate::bake::foliage::billboard::tree_height(tree);
    // Level 1 is the first cloud of the leaves, the finest step of foliage simplification the
    // chain has: the impostor stands only for coarser ones.
    let (placed, replaces) = placement::place(&errors, height, opts.tolerance_px, 2, &mut fit)?;
    for m in &placed.measured {
        log::debug!(
            "{}: at {:.1} px (level {}) the impostor's colour error is {:.3}, the level's {:.3}",
            tree.name,
            m.px,
            m.level,
            m.impostor,
            m.mesh
        );
    }
    log::debug!(
        "{}: impostor baked and placed in {:.2} s",
        tree.name,
        start.elapsed().as_secs_f64()
    );
    Ok(placed.epsilon.map(|epsilon| {
        let level = TreeLevel {
            epsilon,
            kind: Some(CloudKind::Impostor {
                frames: grid.frames,
            }),
            cloud: level,
            bake_seconds: start.elapsed().as_secs_f64(),
        };
        (level, replaces.unwrap_or(chain.len()))
    }))
}

/// A tree's impostor measured beside its chain's levels through the colour seam: each drawn
/// whole, wood and all, against the full tree.
struct TreeFit<'a> {
    measure: &'a dyn MeasureColour,
    tree: &'a Model,
    impostor: &'a CloudLevel,
    chain: &'a [TreeLevel],
}

impl TreeFit<'_> {
    fn error(&self, level: &CloudLevel, px: f32) -> Result<f32> {
        let bake = level
            .bake()
            .map_err(|e| anyhow!("{}: {e}", level.model.name))?;
        Ok(self
            .measure
            .colour_errors(self.tree, &level.model, bake, &[px])?[0])
    }
}

impl MeasureImpostor for TreeFit<'_> {
    fn errors(&mut self, level: usize, px: f32) -> Result<(f32, f32)> {
        Ok((
            self.error(self.impostor, px)?,
            self.error(&self.chain[level].cloud, px)?,
        ))
    }
}

/// The cache file of `tree`'s chain cut as `opts` (its source hashing to `source`), and the
/// key inside it.
pub fn chain_file(
    cache: &LodCache,
    tree: &str,
    source: &[u8; 32],
    opts: &ChainOptions,
) -> Result<(std::path::PathBuf, [u8; 32])> {
    let key = crate::bake::cache::keys::chain_key(source, opts).map_err(anyhow::Error::msg)?;
    Ok((cache.file(tree, "clouds", &key), key))
}

/// The chain of `tree` (whose source file hashes to `source`) from `cache` if a good one is
/// there, else built now and stored: its clouds, then its impostor (placed by `measure`). The
/// file holds levels 1… (level 0 is the tree). A tree with no source (all-zero hash: built in
/// memory) is built and not cached.
pub fn load_or_build_chain(
    raster: &dyn RasterizeAtlas,
    measure: &dyn MeasureColour,
    cache: &LodCache,
    tree: &Model,
    source: &[u8; 32],
    opts: &ChainOptions,
    progress: &(dyn Fn(f32) + Sync),
) -> Result<(Vec<TreeLevel>, Origin)> {
    let build = || -> Result<Vec<TreeLevel>> {
        let foliage = crate::bake::foliage::billboard::foliage(tree).map_err(anyhow::Error::msg)?;
        let mut chain = tree_chain(raster, tree, &foliage, opts, progress)?;
        if let Some((impostor, k)) = impostor_level(raster, measure, tree, &chain, opts)? {
            chain.truncate(k);
            chain.push(impostor);
        }
        chain.remove(0);
        Ok(chain)
    };
    let (coarse, origin) = if source == &[0; 32] {
        (build()?, Origin::Baked { warning: None })
    } else {
        let (path, key) = chain_file(cache, &tree.name, source, opts)?;
        cache.load_or_build(&path, &key, build)?
    };
    let mut levels = vec![full_tree(tree)];
    levels.extend(coarse);
    Ok((levels, origin))
}

/// The tree standing still in its rest pose: its clips keep their length but move nothing.
pub fn at_rest(tree: &Model) -> Model {
    let mut still = tree.clone();
    for clip in &mut still.clips {
        clip.channels.clear();
    }
    still
}

//! A tree's chain of levels of detail (thesis Ch. 7 and §6.5: Bennett-Therkildsen, Carlsen &
//! Schmid, "Animated billboard clouds", Aalborg University, 2007): the full tree, then its
//! foliage as billboard clouds of growing ε, end to end: the cloud, its atlas (drawn through
//! [`RasterizeAtlas`], then dilated), and the tree model that draws it; and the chain cached.

pub mod impostor;
pub mod levels;
pub mod order;

pub use impostor::impostor_level;
pub use levels::{ChainOptions, ChainStyle, CloudKind, CloudLevel, TreeLevel};

use super::atlas::{AtlasDensity, LeafCorner, atlas_triangles, layout, lighting_material};
use super::cloud::CloudParams;
use super::occlusion::CrownDensity;
use super::siblings::merge_siblings;
use super::wood::WoodChain;
use super::{Foliage, Grouping, SkeletonCloud, cloud_model, grouped_cloud, is_cut_out};
use crate::anim::skinning_over_loop;
use crate::bake::cache::keys::CacheKind;
use crate::bake::cache::{LodCache, Origin};
use crate::bake::foliage::spectral::cloud::{SpectralParams, lines_per_axis, spectral_cloud};
use crate::bake::foliage::spectral::metrics::{animation_error, traced_leaves};
use crate::bake::gpu_data::materials::{MaterialLayers, dilate, lit_atlas_material};
use crate::bake::gpu_data::spectra::{NO_ROW, SpectraTexture, SpectralMotion};
use crate::bake::gpu_products::{AtlasLayout, MeasureColour, RasterizeAtlas};
use crate::model::{Model, Rgba8Image};
use anyhow::{Result, anyhow};

/// Texels of dilated colour round every leaf in the atlas.
const DILATE_RINGS: u32 = 4;

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
    level_of_cloud(raster, tree, built, density.into(), wood, crown)
}

/// A cloud's billboards before its atlas and model are made: enough to count them, which is
/// all the chain needs to choose a level's kind.
struct BuiltCloud<'a> {
    /// The tree's leaves at this ε, each on its own bone: split at their bends where one
    /// plane does not hold them ([`super::bends`]).
    own: std::borrow::Cow<'a, Foliage>,
    /// The same leaves rebound to merged siblings, where the cloud was built from those.
    rebound: Option<Foliage>,
    cloud: SkeletonCloud,
    /// A spectral cloud's lines per billboard, and lines per axis.
    lines: Option<(Vec<[Vec<crate::bake::gpu_data::spectra::Line>; 3]>, usize)>,
    /// The clouds or clumps it was built as.
    groups: usize,
    /// Billboards to a clump, of which a view draws one (1 for clouds).
    views: usize,
    /// How far a drawn leaf may lie off its billboard (the atlas's depth order is scaled to it).
    depth: f32,
}

impl BuiltCloud<'_> {
    /// The leaves the cloud was built from (its billboards' leaf indices are theirs).
    fn foliage(&self) -> &Foliage {
        self.rebound.as_ref().unwrap_or(&self.own)
    }
}

/// The billboards of `foliage` at `params`, made as `kind`; leaves that no plane holds within
/// ε are split at their bends first ([`super::bends`]).
fn build_cloud<'a>(
    tree: &Model,
    foliage: &'a Foliage,
    params: &CloudParams,
    kind: &CloudKind,
) -> Result<BuiltCloud<'a>> {
    let own = super::bends::split_at_bends(foliage, &tree.mesh, params.epsilon);
    Ok(match kind {
        CloudKind::Skeleton(grouping) => {
            let rebound = (*grouping == Grouping::Siblings)
                .then(|| merge_siblings(tree, &own, params.epsilon));
            let cloud = grouped_cloud(
                &tree.skeleton,
                rebound.as_ref().unwrap_or(&own),
                params,
                *grouping,
            );
            let mut bones = cloud.bones.clone();
            bones.sort_unstable();
            bones.dedup();
            BuiltCloud {
                own,
                rebound,
                cloud,
                lines: None,
                groups: bones.len(),
                views: 1,
                depth: params.epsilon,
            }
        }
        CloudKind::Spectral(sp) => {
            let s = spectral_cloud(tree, &own, params, sp);
            BuiltCloud {
                own,
                rebound: None,
                cloud: s.cloud,
                lines: Some((s.lines, lines_per_axis(sp))),
                groups: s.clusters,
                views: 1,
                depth: params.epsilon,
            }
        }
        CloudKind::Clumps { clumps, views } => {
            let c = super::clumps::clump_cloud(tree, &own, *clumps, *views, params.seed);
            BuiltCloud {
                own,
                rebound: None,
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

/// The level that draws `built`: the atlas ([`draw_atlas`]), the model with `wood`, its
/// crown occlusion, the motion, the animation error against the leaves on their own bones.
fn level_of_cloud(
    raster: &dyn RasterizeAtlas,
    tree: &Model,
    built: BuiltCloud<'_>,
    density: AtlasDensity,
    wood: &Model,
    crown: Option<&CrownDensity>,
) -> Result<CloudLevel> {
    let drawn = draw_atlas(
        raster,
        tree,
        built.foliage(),
        &built.cloud,
        density,
        built.depth,
        crown,
    )?;
    let BuiltCloud {
        own,
        cloud,
        lines,
        groups,
        views,
        ..
    } = built;
    let texture_bytes = drawn.colour.pixels.len() + drawn.lighting.pixels.len();
    let animation = animation_error(
        tree,
        &own,
        &cloud,
        lines.as_ref().map(|(l, _)| l.as_slice()),
        &skinning_over_loop(tree, crate::bake::foliage::spectral::DEFAULT_SAMPLES),
        &traced_leaves(&own),
    );
    // Each billboard trimmed to its leaves where that pays (see [`super::trim`]), at the
    // texels a screen pixel holds where the level comes in (in the atlas as laid out, which
    // may be smaller than asked); its outline grown by as many, or by the gutter where that
    // is more: how far the mip level read there spreads a leaf's alpha.
    let per_pixel = density.texels_per_pixel * drawn.layout.texels_per_unit
        / density.texels_per_unit.max(1e-12);
    let margin = per_pixel.max(drawn.layout.gutter as f32);
    let outlines: Vec<super::trim::Outline> = drawn
        .layout
        .rects
        .iter()
        .map(|&rect| {
            super::trim::outline(
                &drawn.colour.pixels,
                drawn.colour.width,
                rect,
                margin,
                per_pixel,
            )
        })
        .collect();
    let corners: Vec<u32> = outlines.iter().map(|o| o.len() as u32).collect();
    let mut model = cloud_model(
        wood,
        &cloud,
        &drawn.layout,
        drawn.colour,
        &drawn.normals,
        &outlines,
    );
    model.materials.push(lighting_material(drawn.lighting));
    let occlusion = wood_occlusion(&model, crown);
    let motion = match lines {
        Some((lines, bins)) => Some(spectral_motion(&model, &lines, bins, &corners)?),
        None => None,
    };
    Ok(CloudLevel {
        impostor: None,
        billboards: cloud.billboards.len(),
        groups,
        animation,
        area: cloud.total_area(),
        drawn_area: cloud
            .billboards
            .iter()
            .zip(&outlines)
            .map(|(b, o)| b.area() * super::trim::share(o))
            .sum(),
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
        corners,
    })
}

/// A cloud's atlas (thesis §3.3): its layout at `density`, the leaves of `foliage` drawn into
/// it through `raster` (each darkened by the crown's occlusion at its centre), colour and
/// lighting dilated past the billboards' edges.
fn draw_atlas(
    raster: &dyn RasterizeAtlas,
    tree: &Model,
    foliage: &Foliage,
    cloud: &SkeletonCloud,
    density: AtlasDensity,
    depth: f32,
    crown: Option<&CrownDensity>,
) -> Result<DrawnAtlas> {
    let atlas_layout = layout(&cloud.billboards, density).map_err(|e| anyhow!(e))?;
    let mesh = &tree.mesh;
    // One occlusion a leaf, at its centre: leaves are small beside the crown's voxels. Found
    // once a leaf, not once a billboard drawing it: a clump level draws every leaf on four
    // planes, and the conifer's spent a second a level marching the same rays again.
    let leaf_occlusion: Vec<f32> = {
        use rayon::prelude::*;
        foliage
            .leaves
            .par_iter()
            .map(|l| crown.map_or(0.0, |c| c.occlusion(l.centre())))
            .collect()
    };
    // Every material of the tree is a layer of the atlas's leaf texture, as the renderer
    // makes them for the full tree (the same size, so the same texels and mip levels), and
    // each leaf is drawn with its own: leaves, needles and flowers all survive, each with its
    // texture, cutoff and colour.
    if !tree.materials.iter().any(is_cut_out) {
        return Err(anyhow!("{}: no foliage material", tree.name));
    }
    let layer_of = |v: usize| mesh.materials[v] as u32;
    let drawn = atlas_triangles(&cloud.billboards, &atlas_layout, depth, |leaf| {
        let occlusion = leaf_occlusion[leaf as usize];
        foliage.triangles[leaf as usize]
            .iter()
            .map(|&t| {
                let i = &mesh.indices[3 * t as usize..3 * t as usize + 3];
                // A triangle takes its first corner's material, as the renderer does.
                let layer = layer_of(i[0] as usize);
                [0, 1, 2].map(|k| {
                    let v = i[k] as usize;
                    LeafCorner {
                        position: mesh.positions[v],
                        uv: mesh.uvs[v],
                        normal: mesh.normals[v],
                        occlusion,
                        layer,
                    }
                })
            })
            .collect()
    });
    let leaf = MaterialLayers::bake(&tree.materials);
    let images = raster.rasterize(&atlas_layout, &drawn.vertices, &leaf)?;
    let (mut atlas, mut lighting) = (images.colour, images.lighting);
    dilate(&mut atlas.pixels, atlas.width, atlas.height, DILATE_RINGS);
    dilate(
        &mut lighting.pixels,
        lighting.width,
        lighting.height,
        DILATE_RINGS,
    );
    Ok(DrawnAtlas {
        layout: atlas_layout,
        colour: atlas,
        lighting,
        normals: drawn.normals,
    })
}

/// A cloud's atlas as [`draw_atlas`] draws it: where each billboard lies in it, its colour
/// and lighting images, and the normal each billboard is lit by (see
/// [`super::atlas::AtlasTriangles`]).
struct DrawnAtlas {
    layout: AtlasLayout,
    colour: Rgba8Image,
    lighting: Rgba8Image,
    normals: Vec<glam::Vec3>,
}

/// The crown's occlusion at each vertex of a cloud level's `model`: at the wood's vertices;
/// 0 on the billboards, whose atlas carries it per texel.
fn wood_occlusion(model: &Model, crown: Option<&CrownDensity>) -> Vec<f32> {
    let billboards = lit_atlas_material(&model.materials).map(|m| m as u16);
    model
        .mesh
        .positions
        .iter()
        .zip(&model.mesh.materials)
        .map(|(&p, &m)| match crown {
            Some(c) if Some(m) != billboards => c.occlusion(p),
            _ => 0.0,
        })
        .collect()
}

/// A spectral cloud's motion: its billboards' `lines` (`bins` a billboard and axis) as the
/// spectra texture, and each vertex of `model` pointed at its billboard's row. The
/// billboards' corners are the model's last vertices, `corners` of each billboard in order.
fn spectral_motion(
    model: &Model,
    lines: &[[Vec<crate::bake::gpu_data::spectra::Line>; 3]],
    bins: usize,
    corners: &[u32],
) -> Result<SpectralMotion> {
    let spectra = SpectraTexture::new(lines, bins).map_err(|e| anyhow!(e))?;
    let billboard_vertices: usize = corners.iter().map(|&c| c as usize).sum();
    if corners.len() != lines.len() || billboard_vertices > model.mesh.vertex_count() {
        return Err(anyhow!("spectral lines do not fit the cloud's billboards"));
    }
    let mut vertex_rows = vec![NO_ROW; model.mesh.vertex_count() - billboard_vertices];
    for (b, &c) in corners.iter().enumerate() {
        vertex_rows.extend(std::iter::repeat_n(b as u32, c as usize));
    }
    Ok(SpectralMotion {
        spectra,
        vertex_rows,
    })
}

/// The groupings tried in turn, finest first.
const GROUPINGS: [Grouping; 5] = [
    Grouping::Siblings,
    Grouping::Subtree { forks: 3 },
    Grouping::Subtree { forks: 2 },
    Grouping::Subtree { forks: 1 },
    Grouping::Subtree { forks: 0 },
];

/// A level is made of clumps only where each would stand for this many leaves on average
/// (leaves at the level's ε: a bent card split at its bends counts its pieces). A clump's upright planes show its leaves as seen from the side: a crown of
/// thousands of leaves in a hundred clumps keeps its look, but a tree of a hundred and fifty
/// needle cards, drooping nearly flat, made 93 clumps of one or two cards each at its finest
/// ε, every card pressed onto an upright plane (colour error 0.45, where its cloud of 93
/// billboards scores 0.09).
pub const MIN_LEAVES_PER_CLUMP: usize = 4;

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
        let start = web_time::Instant::now();
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
        let clumps_here = opts.style == ChainStyle::Automatic
            && count <= opts.clumps_from
            && built.own.leaves.len() >= MIN_LEAVES_PER_CLUMP * count;
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
        let cloud = level_of_cloud(raster, tree, built, density, &base, crown.as_ref())?;
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

/// The skeleton cloud that stands in for `level` (a spectral one) where nothing moves
/// billboards by their spectra: glTF skins by bones alone (`lodlab export`). The same ε, its
/// leaves grouped by the finest of the chain's groupings that makes no more billboards than
/// `level` has (else the coarsest), the atlas and wood as the chain makes them at that ε.
pub fn skeleton_stand_in(
    raster: &dyn RasterizeAtlas,
    tree: &Model,
    foliage: &Foliage,
    level: &TreeLevel,
    opts: &ChainOptions,
) -> Result<TreeLevel> {
    let start = web_time::Instant::now();
    let h = crate::bake::foliage::billboard::tree_height(tree);
    let params = CloudParams {
        epsilon: level.epsilon,
        seed: opts.seed,
        ..Default::default()
    };
    let mut chosen = None;
    for grouping in GROUPINGS {
        let kind = CloudKind::Skeleton(grouping);
        let built = build_cloud(tree, foliage, &params, &kind)?;
        let fits = built.cloud.billboards.len() <= level.cloud.billboards.max(1);
        chosen = Some((kind, built));
        if fits {
            break;
        }
    }
    let (kind, built) = chosen.expect("the chain has groupings");
    let wood = WoodChain::new(tree).tree_at(tree, level.epsilon);
    let density = opts.atlas_density(level.epsilon, h, &kind);
    let crown = CrownDensity::of(tree);
    let cloud = level_of_cloud(raster, tree, built, density, &wood, crown.as_ref())?;
    Ok(TreeLevel {
        epsilon: level.epsilon,
        kind: Some(kind),
        cloud,
        bake_seconds: start.elapsed().as_secs_f64(),
    })
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

/// The cache file of `tree`'s chain cut as `opts` (its source hashing to `source`), and the
/// key inside it: the same file for either order (see [`ChainBake`]).
pub fn chain_file(
    cache: &LodCache,
    tree: &str,
    source: &[u8; 32],
    opts: &ChainOptions,
) -> Result<(std::path::PathBuf, [u8; 32])> {
    let epsilon_opts = ChainOptions {
        order: order::FoliageOrder::Epsilon,
        ..*opts
    };
    let key =
        crate::bake::cache::keys::chain_key(source, &epsilon_opts).map_err(anyhow::Error::msg)?;
    Ok((cache.file(tree, CacheKind::Clouds, &key), key))
}

/// The cache file of the cost order's choices for `tree`'s chain cut as `opts`, and its key.
pub fn order_file(
    cache: &LodCache,
    tree: &str,
    source: &[u8; 32],
    opts: &ChainOptions,
) -> Result<(std::path::PathBuf, [u8; 32])> {
    let key = crate::bake::cache::keys::order_key(source, opts).map_err(anyhow::Error::msg)?;
    Ok((cache.file(tree, CacheKind::Order, &key), key))
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
    let (chains, origin) =
        load_or_build_chains(raster, measure, cache, tree, source, opts, progress)?;
    if opts.order == order::FoliageOrder::Epsilon {
        return Ok((chains.epsilon, origin));
    }
    let (choices, chosen) = load_or_choose(measure, cache, tree, source, opts, &chains)?;
    let origin = if origin == Origin::Cache {
        chosen
    } else {
        origin
    };
    Ok((order::chain_of(&chains, &choices), origin))
}

/// Every level of `tree`'s chain cut as `opts` and its ε chain (see [`order::Chains`]), from
/// `cache` or built now and stored: the same for either order.
pub fn load_or_build_chains(
    raster: &dyn RasterizeAtlas,
    measure: &dyn MeasureColour,
    cache: &LodCache,
    tree: &Model,
    source: &[u8; 32],
    opts: &ChainOptions,
    progress: &(dyn Fn(f32) + Sync),
) -> Result<(order::Chains, Origin)> {
    let build = || -> Result<ChainBake> {
        let foliage = crate::bake::foliage::billboard::foliage(tree).map_err(anyhow::Error::msg)?;
        let levels = tree_chain(raster, tree, &foliage, opts, progress)?;
        ChainBake::placing_impostor(raster, measure, tree, levels, opts)
    };
    let (bake, origin) = if source == &[0; 32] {
        (build()?, Origin::Baked { warning: None })
    } else {
        let (path, key) = chain_file(cache, &tree.name, source, opts)?;
        cache.load_or_build(&path, &key, build)?
    };
    Ok((bake.chains(full_tree(tree)), origin))
}

/// A tree's chain as it is cached: every level the bake made (levels 1…: the clouds, then
/// the impostor where it found a place), and where the ε order puts the impostor. The cost
/// order chooses among them all, clump levels past the impostor's place included.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct ChainBake {
    pub levels: Vec<TreeLevel>,
    /// The index (level 0 the tree) from which the impostor takes the ε chain's place: the
    /// levels from there on give way to it.
    pub impostor_from: Option<usize>,
}

impl ChainBake {
    /// The chain `levels` (level 0 the tree, as `tree_chain` makes it) with the tree's
    /// impostor placed after it (see [`impostor_level`]), where it finds a place.
    pub fn placing_impostor(
        raster: &dyn RasterizeAtlas,
        measure: &dyn MeasureColour,
        tree: &Model,
        mut levels: Vec<TreeLevel>,
        opts: &ChainOptions,
    ) -> Result<ChainBake> {
        let mut impostor_from = None;
        if let Some((impostor, k)) = impostor_level(raster, measure, tree, &levels, opts)? {
            impostor_from = Some(k);
            levels.push(impostor);
        }
        levels.remove(0);
        Ok(ChainBake {
            levels,
            impostor_from,
        })
    }

    /// With `full` as level 0: every level made and the ε chain.
    pub fn chains(self, full: TreeLevel) -> order::Chains {
        let mut candidates = vec![full];
        candidates.extend(self.levels);
        let last = candidates.len() - 1;
        let reference: Vec<usize> = match self.impostor_from {
            Some(k) => (0..k.min(last)).chain([last]).collect(),
            None => (0..=last).collect(),
        };
        order::Chains {
            epsilon: reference.iter().map(|&i| candidates[i].clone()).collect(),
            reference,
            candidates,
        }
    }
}

/// The cost order's choices (see [`order::by_cost`]) among `tree`'s levels for the stretches
/// of its ε chain (`chains`), cut as
/// `opts`, from `cache` if a good file is there, else measured now and stored (a tree with no
/// source is measured and not cached).
pub fn load_or_choose(
    measure: &dyn MeasureColour,
    cache: &LodCache,
    tree: &Model,
    source: &[u8; 32],
    opts: &ChainOptions,
    chains: &order::Chains,
) -> Result<(Vec<order::CostChoice>, Origin)> {
    let height = crate::bake::foliage::billboard::tree_height(tree);
    let choose = || order::by_cost(measure, tree, chains, height, opts.tolerance_px);
    if source == &[0; 32] {
        return Ok((choose()?, Origin::Baked { warning: None }));
    }
    let (path, key) = order_file(cache, &tree.name, source, opts)?;
    cache.load_or_build(&path, &key, choose)
}

/// The tree standing still in its rest pose: its clips keep their length but move nothing.
pub fn at_rest(tree: &Model) -> Model {
    let mut still = tree.clone();
    for clip in &mut still.clips {
        clip.channels.clear();
    }
    still
}

//! `lodlab export TREE`: a tree's chain of levels of detail as glTF, for engines that know
//! nothing of billboard clouds (issue: trees out to other engines). Level 0 is the tree as it
//! is; every cloud level (Bennett-Therkildsen et al. Ch. 7) is its wood and its billboards as
//! cards skinned with weight 1 to their bones, so an engine's own skinning sways them with the
//! tree's clips, cut out of the level's atlas (`alphaMode: MASK`), each card a fan over its
//! trimmed outline. The atlas's lighting (per texel the normal its leaf is lit by, in the
//! card's frame, [`billboard_frame`]) goes out as the atlas material's normal map, with each
//! card vertex's tangent, so that an ordinary PBR material lights the leaves as they face.
//!
//! What plain glTF cannot draw is said and stood in for or left out:
//! - a spectral level moves its cards by DFT spectra in lodlab's shader: it goes out as the
//!   skeleton cloud of the same ε ([`skeleton_stand_in`]);
//! - a clump level draws, of each clump's planes, the one facing the viewer: all its planes go
//!   out, crossed, as a classic crossed-card tree does;
//! - the octahedral impostor picks and blends its views per pixel: left out, with a line.
//!
//! [`billboard_frame`]: crate::bake::foliage::billboard::atlas::billboard_frame
//! [`skeleton_stand_in`]: crate::bake::foliage::billboard::chain::skeleton_stand_in

use super::exported::{ExportedLevel, coverage_hints, file_stem, switch_px};
use crate::bake::cache::{LodCache, Origin};
use crate::bake::foliage::billboard::atlas::billboard_frame;
use crate::bake::foliage::billboard::chain::{
    ChainOptions, CloudKind, TreeLevel, load_or_build_chain, order::FoliageOrder, skeleton_stand_in,
};
use crate::bake::gpu_data::materials::lit_atlas_material;
use crate::generate::glb::{Extra, to_glb_with, to_lod_glb_with};
use crate::model::{Material, Model, Rgba8Image};
use crate::render::atlas::AtlasRasterizer;
use anyhow::Result;
use std::path::Path;

/// One level of a tree as it goes out: the model drawn, what the file adds to it, and what
/// the level is in words.
pub struct TreeOut {
    pub model: Model,
    pub extra: Extra,
    pub epsilon: f32,
    pub kind: String,
    /// Its place in lodlab's chain by ε (`shot --foliage-order epsilon --force-level`).
    pub chain_level: usize,
}

/// What a tree's export wrote: its levels, the combined file, and the levels left out (a
/// line each, saying why).
pub struct TreeExport {
    pub levels: Vec<ExportedLevel>,
    pub lod_file: std::path::PathBuf,
    pub lod_bytes: usize,
    pub left_out: Vec<String>,
    pub from_cache: bool,
}

/// The chain of `tree` (source hash `hash`) as the viewer draws it by default, from `cache` or
/// baked now, each level as it goes out, and the levels left out.
pub fn tree_levels(
    tree: &Model,
    hash: &[u8; 32],
    cache: &LodCache,
) -> Result<(Vec<TreeOut>, Vec<String>, bool)> {
    let gpu = crate::render::Gpu::headless()?;
    let raster = AtlasRasterizer::new(&gpu);
    // The ε order: each level from where its ε projects to the tolerance, which is what a
    // coverage hint can say. (The viewer's default cost order leans on the impostor, which
    // cannot go out: a card oak's would leave the tree alone.)
    let opts = ChainOptions {
        order: FoliageOrder::Epsilon,
        ..ChainOptions::default()
    };
    let (chain, origin) = load_or_build_chain(
        &raster,
        &crate::measure::colour_error::GpuColourError::new(&gpu),
        cache,
        tree,
        hash,
        &opts,
        &|_| {},
    )
    .map_err(|e| anyhow::anyhow!("{}: {e:#}", tree.name))?;
    let mut foliage = None;
    let (mut out, mut left_out) = (Vec::new(), Vec::new());
    for (k, level) in chain.iter().enumerate() {
        let stood_in;
        let (level, kind) = match &level.kind {
            None => (level, "full tree".to_string()),
            Some(CloudKind::Impostor { .. }) => {
                left_out.push(format!(
                    "level {k} (octahedral impostor): left out, its views are picked and \
                     blended per pixel by lodlab's shader, which glTF has no way to say"
                ));
                continue;
            }
            Some(CloudKind::Spectral(_)) => {
                let f = match &foliage {
                    Some(f) => f,
                    None => foliage.insert(
                        crate::bake::foliage::billboard::foliage(tree)
                            .map_err(|e| anyhow::anyhow!("{}: {e}", tree.name))?,
                    ),
                };
                stood_in = skeleton_stand_in(&raster, tree, f, level, &opts)?;
                let kind = format!(
                    "{}, standing in for the spectral cloud of the same ε",
                    CloudKind::name(stood_in.kind.as_ref())
                );
                (&stood_in, kind)
            }
            Some(CloudKind::Clumps { .. }) => (
                level,
                format!(
                    "{}, every plane drawn (crossed)",
                    CloudKind::name(level.kind.as_ref())
                ),
            ),
            Some(kind @ CloudKind::Skeleton(_)) => (level, CloudKind::name(Some(kind))),
        };
        // A level of more triangles than a finer one kept would only cost more in an engine
        // (a card tree's first clouds, crossed clumps): the finer one draws on instead, as
        // lodlab's cost order keeps a tree lighter than its clouds.
        let finer = out
            .last()
            .map_or(usize::MAX, |o: &TreeOut| o.model.mesh.triangle_count());
        if level.cloud.model.mesh.triangle_count() >= finer {
            left_out.push(format!(
                "level {k} ({kind}): left out, {} triangles against the {finer} of a finer level",
                level.cloud.model.mesh.triangle_count()
            ));
            continue;
        }
        out.push(level_out(level, k, kind));
    }
    Ok((out, left_out, origin == Origin::Cache))
}

/// Level `level` (number `k` of its chain) as it goes out: the atlas's lighting taken off
/// the material list and put on the atlas as its normal map (linear), with a tangent for every
/// vertex, the card frame's for the billboards'.
fn level_out(level: &TreeLevel, k: usize, kind: String) -> TreeOut {
    let mut model = level.cloud.model.clone();
    let mut extra = Extra::default();
    if let Some(atlas) = lit_atlas_material(&model.materials) {
        // No triangle uses the lighting material; it is the last.
        let lighting = model.materials.remove(atlas + 1);
        extra.normal_maps = vec![None; model.materials.len()];
        extra.normal_maps[atlas] = lighting.texture.map(linear_normals);
        model.materials[atlas].name = format!("{} LOD{k} billboards", model.name);
        let mesh = &model.mesh;
        extra.tangents = vec![
            mesh.normals
                .iter()
                .map(|&n| billboard_frame(n.normalize_or(glam::Vec3::Z)).0.extend(1.0))
                .collect(),
        ];
    }
    TreeOut {
        model,
        extra,
        epsilon: level.epsilon,
        kind,
        chain_level: k,
    }
}

/// The lighting texture (stored sRGB-encoded for lodlab's sRGB material textures) as a glTF
/// normal map: linear, opaque.
fn linear_normals(mut image: Rgba8Image) -> Rgba8Image {
    for p in image.pixels.chunks_exact_mut(4) {
        for c in &mut p[..3] {
            *c = (crate::model::srgb_to_linear(*c) * 255.0).round() as u8;
        }
        p[3] = 255;
    }
    image
}

/// Writes `levels` of `tree` into `out`: one `.glb` a level, and all of them under `MSFT_lod`
/// with their coverage hints at `tolerance` pixels.
pub fn write_tree(
    tree: &Model,
    levels: &[TreeOut],
    out: &Path,
    tolerance: f32,
) -> Result<(Vec<ExportedLevel>, std::path::PathBuf, usize)> {
    let stem = file_stem(&tree.name);
    let height = crate::bake::foliage::billboard::tree_height(tree);
    let bounds = crate::model::Bounds::of(tree.mesh.positions.iter().copied())
        .ok_or_else(|| anyhow::anyhow!("{}: an empty mesh", tree.name))?;
    let aspect = bounds.size().x.max(bounds.size().z) / height.max(1e-6);
    let epsilons: Vec<f32> = levels.iter().map(|l| l.epsilon).collect();
    let hints = coverage_hints(&switch_px(&epsilons, tolerance, height), aspect);
    let generator = "lodlab export (billboard clouds)";
    let mut written = Vec::with_capacity(levels.len());
    for (k, level) in levels.iter().enumerate() {
        let bytes = to_glb_with(&level.model, &level.extra, generator);
        let file = out.join(format!("{stem}-clouds-lod{k}.glb"));
        crate::atomic::write(&file, &bytes)?;
        written.push(ExportedLevel {
            kind: Some(level.kind.clone()),
            chain_level: Some(level.chain_level),
            ..ExportedLevel::written(
                k,
                &level.model.mesh,
                (level.epsilon, hints[k]),
                file,
                bytes.len(),
            )
        });
    }
    let all = combined(levels);
    let meshes: Vec<&crate::model::SkinnedMesh> = all.meshes.iter().collect();
    let with_materials = Model {
        name: tree.name.clone(),
        mesh: crate::model::SkinnedMesh::empty(),
        skeleton: tree.skeleton.clone(),
        clips: tree.clips.clone(),
        materials: all.materials,
    };
    let bytes = to_lod_glb_with(&with_materials, &meshes, &hints, generator, &all.extra);
    let lod_file = out.join(format!("{stem}-clouds-lods.glb"));
    crate::atomic::write(&lod_file, &bytes)?;
    Ok((written, lod_file, bytes.len()))
}

/// Every level's mesh over one list of materials, with the normal maps and tangents that go
/// with them.
struct Combined {
    meshes: Vec<crate::model::SkinnedMesh>,
    materials: Vec<Material>,
    extra: Extra,
}

/// `levels` over one list of materials: a material (the wood's, a leaf's) that several
/// levels use is listed once.
fn combined(levels: &[TreeOut]) -> Combined {
    let mut all = Combined {
        meshes: Vec::with_capacity(levels.len()),
        materials: Vec::new(),
        extra: Extra::default(),
    };
    for level in levels {
        let remap: Vec<u16> = level
            .model
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let map = level.extra.normal_maps.get(i).cloned().flatten();
                let at = all
                    .materials
                    .iter()
                    .zip(&all.extra.normal_maps)
                    .position(|(have, have_map)| have == m && *have_map == map);
                at.unwrap_or_else(|| {
                    all.materials.push(m.clone());
                    all.extra.normal_maps.push(map);
                    all.materials.len() - 1
                }) as u16
            })
            .collect();
        let mut mesh = level.model.mesh.clone();
        for m in &mut mesh.materials {
            *m = remap.get(*m as usize).copied().unwrap_or(0);
        }
        // Levels without a normal map have no tangents; none of their primitives needs one.
        let tangents = level.extra.tangents.first().cloned().unwrap_or_default();
        all.extra.tangents.push(tangents);
        all.meshes.push(mesh);
    }
    all
}

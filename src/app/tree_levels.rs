//! A tree's foliage as a billboard cloud, end to end: the cloud (CPU), its atlas (rendered on
//! the GPU, then dilated), and the tree model that draws it.

use crate::bake::billboard::atlas::{atlas_triangles, dilate, layout};
use crate::bake::billboard::cloud::CloudParams;
use crate::bake::billboard::{Foliage, cloud_model, is_cut_out, skeleton_cloud};
use crate::bake::materials::MaterialLayers;
use crate::model::Model;
use crate::render::Gpu;
use crate::render::atlas::render_atlas;
use anyhow::{Result, anyhow};

/// Texels of dilated colour round every leaf in the atlas.
const DILATE_RINGS: u32 = 4;

/// The tree drawn with a skeleton billboard cloud of its foliage at `params`, with
/// `texels_per_unit` texels per scene unit in the atlas. Also returns the cloud's billboard
/// count and total area.
pub fn cloud_level(
    gpu: &Gpu,
    tree: &Model,
    foliage: &Foliage,
    params: &CloudParams,
    texels_per_unit: f32,
) -> Result<(Model, usize, f32)> {
    let cloud = skeleton_cloud(foliage, params);
    let atlas_layout = layout(&cloud.billboards, texels_per_unit).map_err(|e| anyhow!(e))?;
    let mesh = &tree.mesh;
    let triangles = atlas_triangles(&cloud.billboards, &atlas_layout, params.epsilon, |leaf| {
        foliage.triangles[leaf as usize]
            .iter()
            .map(|&t| {
                let i = &mesh.indices[3 * t as usize..3 * t as usize + 3];
                [0, 1, 2].map(|k| {
                    let v = i[k] as usize;
                    (mesh.positions[v], mesh.uvs[v])
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
    let mut atlas = render_atlas(gpu, &atlas_layout, &triangles, &leaf)?;
    dilate(&mut atlas.pixels, atlas.width, atlas.height, DILATE_RINGS);
    let (count, area) = (cloud.billboards.len(), cloud.total_area());
    Ok((cloud_model(tree, &cloud, &atlas_layout, atlas), count, area))
}

/// Views and frames of the colour metric (thesis §5.1.3): five views evenly round the tree at
/// ground level, at five times over the loop.
pub const METRIC_VIEWS: usize = 5;
pub const METRIC_FRAMES: usize = 5;

/// The colour error of `lod` against `original` (thesis §5.1.3): binary masks of where the
/// tree covers the image, at `size`, from [`METRIC_VIEWS`] views round it at ground level and
/// [`METRIC_FRAMES`] times of its loop; the share of the original's covered pixels that the
/// two masks disagree on, over all of them. 0 for identical trees.
pub fn colour_error(gpu: &Gpu, original: &Model, lod: &Model, size: [u32; 2]) -> Result<f32> {
    use crate::app::levels::LevelSource;
    use crate::app::world::{Loaded, SceneSpec, World};
    use crate::bake::CharacterBake;
    use crate::render::targets::{OFFSCREEN_FORMAT, Offscreen};
    let world_of = |m: &Model| -> Result<World> {
        let bake = CharacterBake::new(m).map_err(|e| anyhow!("{}: {e}", m.name))?;
        let loaded = Loaded {
            spec: SceneSpec {
                scene: "forest".into(),
                count: 1,
                ..Default::default()
            },
            bakes: vec![bake],
            sources: vec![LevelSource {
                model: m.clone(),
                hash: [0; 32],
            }],
        };
        let mut w = World::new(gpu, loaded, OFFSCREEN_FORMAT, 1)?;
        w.renderer.shadows = false;
        Ok(w)
    };
    let mut a = world_of(original)?;
    let mut b = world_of(lod)?;
    let target = Offscreen::new(gpu, size[0], size[1], 1);
    let bounds = a.bakes[0].bounds;
    let height = bounds.size().y.max(1e-3);
    let duration = original.clips.first().map_or(1.0, |c| c.duration);
    let (mut wrong, mut covered) = (0u64, 0u64);
    let shoot = |w: &mut World, camera: crate::scene::Camera, t: f32, empty: bool| {
        w.camera = camera;
        if empty {
            w.relayout(None, 0, None);
        }
        w.prepare(gpu, size, t, 0.0);
        w.renderer.render_to(gpu, &target.targets, &target.view);
        let img = target.read_rgba(gpu);
        if empty {
            w.relayout(None, 1, None);
        }
        img
    };
    for view in 0..METRIC_VIEWS {
        let yaw = 360.0 * view as f32 / METRIC_VIEWS as f32;
        // At ground level, far enough for the whole tree to fit with a margin.
        let camera = crate::scene::Camera::new(
            glam::Vec3::new(bounds.center().x, height * 0.5, bounds.center().z),
            yaw,
            0.0,
            height * 1.25,
        );
        let background = shoot(&mut a, camera, 0.0, true)?;
        for frame in 0..METRIC_FRAMES {
            let t = duration * frame as f32 / METRIC_FRAMES as f32;
            let ia = shoot(&mut a, camera, t, false)?;
            let ib = shoot(&mut b, camera, t, false)?;
            for ((p, q), bg) in ia.pixels().zip(ib.pixels()).zip(background.pixels()) {
                let on = |x: &image::Rgba<u8>| (0..3).any(|c| x[c].abs_diff(bg[c]) > 10);
                let (ma, mb) = (on(p), on(q));
                covered += ma as u64;
                wrong += (ma != mb) as u64;
            }
        }
    }
    Ok(wrong as f32 / covered.max(1) as f32)
}

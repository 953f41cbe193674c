//! What the normal maps buy: each coarse level's colour error against full detail, lit by its
//! own vertex normals and through its normal map (Merry, Marais & Gain, "Analytic simplification
//! of animated characters", light their coarse levels through tangent-space normal maps, §6.4;
//! see `bake::normal_map`).
//!
//! The error is the impostor placement's (see `impostor_placement`): the mean colour
//! difference over the pixels either picture covers, divided by the pixels full detail covers,
//! from five views round the character 15° above the ground at five times of its first clip.
//! Both pictures of a level show the same triangles, so the difference between the two errors
//! is the lighting alone.

use super::colour_error::{
    METRIC_FRAMES, METRIC_VIEWS, framing, metric_camera, metric_world, picture,
};
use super::impostor_placement::{PITCH_DEG, colour_off};
use super::levels::mapped_pack;
use super::spec::Loaded;
use crate::bake::CharacterBake;
use crate::bake::lod::LodLevel;
use crate::model::Model;
use crate::render::Gpu;
use crate::render::targets::Offscreen;
use anyhow::Result;
use serde::Serialize;

/// One level's colour errors against full detail at one size.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LevelShading {
    pub level: usize,
    pub triangles: usize,
    /// The character's height on screen, pixels.
    pub px: f32,
    /// Lit by its vertex normals.
    pub vertex_normals: f32,
    /// Lit through its normal map (the same as `vertex_normals` where it has none).
    pub normal_maps: f32,
    /// It has a normal map.
    pub mapped: bool,
}

/// The colour errors of levels `which` of `chain` (finest first, level 0 full detail) of
/// `model` (`full`: its full-detail bake) against full detail, `px` pixels high.
pub fn shading_errors(
    gpu: &Gpu,
    model: &Model,
    full: &CharacterBake,
    chain: &[LodLevel],
    which: &[usize],
    px: f32,
) -> Result<Vec<LevelShading>> {
    let mut full_world = metric_world(gpu, Loaded::forest_of_bake(model, full.clone(), 1))?;
    let mut level_world = metric_world(gpu, Loaded::forest_of_bake(model, full.clone(), 1))?;
    let (size, distance) = framing(px);
    let target = Offscreen::new(gpu, size[0], size[1], 1);
    let height = full.bounds.size().y.max(1e-3);
    let centre = full.bounds.center();
    let duration = model.clips.first().map_or(1.0, |c| c.duration);
    let mut out = Vec::with_capacity(which.len());
    for &k in which {
        let mut level = chain[k].clone();
        level.geomorph.clear();
        let pack = mapped_pack(model, chain, &[level]).map_err(anyhow::Error::msg)?;
        let mapped = pack.levels[0].normal_mapped;
        level_world.renderer.add_levels(gpu, 0, 0, &pack)?;
        let (mut covered, mut off_plain, mut off_mapped) = (0u64, 0.0f64, 0.0f64);
        for view in 0..METRIC_VIEWS {
            let yaw = 360.0 * view as f32 / METRIC_VIEWS as f32;
            let camera = metric_camera(centre, height, yaw, PITCH_DEG, distance);
            let background = picture(gpu, &mut full_world, &target, camera, 0.0, true)?;
            for frame in 0..METRIC_FRAMES {
                let t = duration * frame as f32 / METRIC_FRAMES as f32;
                let reference = picture(gpu, &mut full_world, &target, camera, t, false)?;
                level_world.renderer.normal_maps = false;
                let plain = picture(gpu, &mut level_world, &target, camera, t, false)?;
                level_world.renderer.normal_maps = true;
                let lit = picture(gpu, &mut level_world, &target, camera, t, false)?;
                let (n, off) = colour_off(&reference, &plain, &background);
                covered += n;
                off_plain += off;
                off_mapped += colour_off(&reference, &lit, &background).1;
            }
        }
        let n = covered.max(1) as f64;
        out.push(LevelShading {
            level: k,
            triangles: chain[k].triangles(),
            px,
            vertex_normals: (off_plain / n) as f32,
            normal_maps: (off_mapped / n) as f32,
            mapped,
        });
    }
    Ok(out)
}

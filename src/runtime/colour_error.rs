//! The colour error of a tree's level against the full tree (Bennett-Therkildsen, Carlsen &
//! Schmid's thesis "Animated Billboard Clouds for Foliage Simplification" (2007) §5.1.3), measured
//! by drawing both in worlds of their own.

use super::spec::Loaded;
use super::world::World;
use crate::bake::billboard::chain::CloudLevel;
use crate::bake::billboard::wood::only_foliage;
use crate::bake::spectral::texture::SpectralMotion;
use crate::model::Model;
use crate::render::Gpu;
use crate::render::targets::{OFFSCREEN_FORMAT, Offscreen};
use anyhow::Result;

/// Views and frames of the colour metric (thesis §5.1.3): five views evenly round the tree at
/// ground level, at five times over the loop.
pub const METRIC_VIEWS: usize = 5;
pub const METRIC_FRAMES: usize = 5;

/// The colour error of `lod` against `original` (thesis §5.1.3): binary masks of where the
/// foliage (the original's leaves, the level's billboards; wood left out) covers the image, at
/// `size`, from [`METRIC_VIEWS`] views round it at ground level and [`METRIC_FRAMES`] times of
/// its loop; the share of the original's foliage pixels that the two masks disagree on, over
/// all of them. 0 for identical trees.
pub fn colour_error(gpu: &Gpu, original: &Model, lod: &CloudLevel, size: [u32; 2]) -> Result<f32> {
    colour_error_over(gpu, original, lod, size, METRIC_FRAMES)
}

/// [`colour_error`] at `frames` times of the loop (1: the thesis's static colour metric).
pub fn colour_error_over(
    gpu: &Gpu,
    original: &Model,
    lod: &CloudLevel,
    size: [u32; 2],
    frames: usize,
) -> Result<f32> {
    let world_of = |m: &Model, motion: Option<&SpectralMotion>| -> Result<World> {
        let mut w = World::new(gpu, Loaded::forest_of(m, motion, 1)?, OFFSCREEN_FORMAT, 1)?;
        w.renderer.shadows = false;
        Ok(w)
    };
    let mut a = world_of(&only_foliage(original), None)?;
    let (lod_foliage, lod_motion) = lod.foliage();
    let mut b = world_of(&lod_foliage, lod_motion.as_ref())?;
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
        for frame in 0..frames.max(1) {
            let t = duration * frame as f32 / frames.max(1) as f32;
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

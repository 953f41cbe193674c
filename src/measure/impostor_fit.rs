//! A character's animated impostor measured beside its mesh levels, for the placement rule
//! of [`crate::bake::impostor::placement`] (the trees' rule too).
//!
//! The colour error of an image against full detail is the mean absolute difference of their
//! colours (0 to 1, over the three channels) over every pixel either covers, divided by the
//! pixels full detail covers: a missing or extra pixel counts its whole difference from the
//! background, a pixel shaded differently its difference. It is taken from five views round
//! the character, 15° above the ground, at five times of its first clip, framed as the trees'
//! colour metric frames a tree (`colour_error::framing`).

use super::colour_error::{
    METRIC_FRAMES, METRIC_VIEWS, framing, metric_camera, metric_world, picture,
};
use crate::bake::character::lod::LodLevel;
use crate::bake::gpu_data::drawable::Drawable;
use crate::bake::gpu_products::MeasureImpostor;
use crate::bake::impostor::animated::AnimatedImpostor;
use crate::model::Model;
use crate::render::Gpu;
use crate::render::targets::Offscreen;
use crate::runtime::levels::mapped_pack;
use crate::runtime::spec::Loaded;
use crate::runtime::world::World;
use anyhow::Result;

/// The views look down this many degrees, as a crowd's camera does.
pub(crate) const PITCH_DEG: f32 = 15.0;

/// The drawings the placement compares, each a world of its own: full detail, the impostor,
/// and full detail's world again with one mesh level of `levels` in place of its full-detail
/// set, lit through its normal map as the runtime draws it.
pub struct ImpostorFit<'a> {
    gpu: &'a Gpu,
    model: &'a Model,
    levels: &'a [LodLevel],
    full: World,
    impostor: World,
    level: World,
    /// The level `level` shows now.
    shown: Option<usize>,
    duration: f32,
    height: f32,
    centre: glam::Vec3,
    /// Where the first clip has carried the body at each frame measured (root motion; all
    /// zero for a character that stays put): the views follow it.
    travel: Vec<glam::Vec3>,
}

impl<'a> ImpostorFit<'a> {
    pub fn new(
        gpu: &'a Gpu,
        model: &'a Model,
        full: &Drawable,
        levels: &'a [LodLevel],
        impostor: &AnimatedImpostor,
    ) -> Result<Self> {
        let world = |loaded: Loaded| metric_world(gpu, loaded);
        let duration = model.clips.first().map_or(1.0, |c| c.duration);
        let impostor_bake = impostor
            .bake(full)
            .map_err(|e| anyhow::anyhow!("{}: {e}", impostor.model.name))?;
        Ok(ImpostorFit {
            gpu,
            model,
            levels,
            full: world(Loaded::forest_of_bake(model, full.clone(), 1))?,
            impostor: world(Loaded::forest_of_bake(&impostor.model, impostor_bake, 1))?,
            level: world(Loaded::forest_of_bake(model, full.clone(), 1))?,
            shown: None,
            duration,
            height: full.bounds.size().y.max(1e-3),
            centre: full.bounds.center(),
            travel: (0..METRIC_FRAMES)
                .map(|f| full.travel_at(0, duration * f as f32 / METRIC_FRAMES as f32))
                .collect(),
        })
    }

    /// Shows mesh level `k` in the level's world.
    fn show(&mut self, k: usize) -> Result<()> {
        if self.shown != Some(k) {
            let mut level = self.levels[k].clone();
            level.geomorph.clear();
            let pack =
                mapped_pack(self.model, self.levels, &[level]).map_err(anyhow::Error::msg)?;
            self.level.renderer.add_levels(self.gpu, 0, 0, &pack)?;
            self.shown = Some(k);
        }
        Ok(())
    }

    /// The colour errors of the impostor and of the level shown (0 where none is), both
    /// against full detail, at `px` pixels high; the impostor's clock `lag` seconds behind.
    fn colours(&mut self, px: f32, lag: f32) -> Result<(f32, f32)> {
        let gpu = self.gpu;
        let (size, distance) = framing(px);
        let target = Offscreen::new(gpu, size[0], size[1], 1);
        let shoot = |w: &mut World, camera, t, empty| picture(gpu, w, &target, camera, t, empty);
        let (mut covered, mut off_impostor, mut off_level) = (0u64, 0.0f64, 0.0f64);
        let still = self.travel.iter().all(|t| *t == glam::Vec3::ZERO);
        for view in 0..METRIC_VIEWS {
            let yaw = 360.0 * view as f32 / METRIC_VIEWS as f32;
            let at = |f: usize| self.centre + self.travel[f];
            let mut camera = metric_camera(at(0), self.height, yaw, PITCH_DEG, distance);
            let mut background = shoot(&mut self.full, camera, 0.0, true)?;
            for frame in 0..METRIC_FRAMES {
                let t = self.duration * frame as f32 / METRIC_FRAMES as f32;
                if !still && frame > 0 {
                    // Where the clip carries the body, the view goes with it.
                    camera = metric_camera(at(frame), self.height, yaw, PITCH_DEG, distance);
                    background = shoot(&mut self.full, camera, 0.0, true)?;
                }
                let full = shoot(&mut self.full, camera, t, false)?;
                let imp = shoot(&mut self.impostor, camera, t - lag, false)?;
                let lvl = match self.shown {
                    Some(_) => shoot(&mut self.level, camera, t, false)?,
                    None => full.clone(),
                };
                let (n, off) = colour_off(&full, &imp, &background);
                covered += n;
                off_impostor += off;
                off_level += colour_off(&full, &lvl, &background).1;
            }
        }
        let n = covered.max(1) as f64;
        Ok(((off_impostor / n) as f32, (off_level / n) as f32))
    }
}

/// The colour error's terms over one picture (see the module comment): the pixels `full`
/// covers, and the colour difference of `other` from `full` summed over the pixels either
/// covers, each a mean over the three channels in 0..1. A pixel is covered where it differs
/// from `background` (the same view with nothing in it).
pub(crate) fn colour_off(
    full: &image::RgbaImage,
    other: &image::RgbaImage,
    background: &image::RgbaImage,
) -> (u64, f64) {
    let (mut covered, mut off) = (0u64, 0.0f64);
    for ((a, b), bg) in full.pixels().zip(other.pixels()).zip(background.pixels()) {
        let on = |x: &image::Rgba<u8>| super::colour_error::covers(x, bg);
        covered += on(a) as u64;
        if on(a) || on(b) {
            off += (0..3).map(|i| a[i].abs_diff(b[i]) as f64).sum::<f64>() / (3.0 * 255.0);
        }
    }
    (covered, off)
}

impl MeasureImpostor for ImpostorFit<'_> {
    fn errors(&mut self, level: usize, px: f32) -> Result<(f32, f32)> {
        self.show(level)?;
        let (impostor, mesh) = self.colours(px, 0.0)?;
        log::debug!(
            "{}: at {px:.1} px the impostor's colour error is {impostor:.3}, level {level}'s {mesh:.3}",
            self.model.name
        );
        Ok((impostor, mesh))
    }
}

/// The colour error of `impostor` against full detail of `model` (`full`: its bake) at
/// `px` pixels high (see the module comment), its clock `lag` seconds behind full detail's.
pub fn impostor_error(
    gpu: &Gpu,
    model: &Model,
    full: &Drawable,
    impostor: &AnimatedImpostor,
    px: f32,
    lag: f32,
) -> Result<f32> {
    Ok(ImpostorFit::new(gpu, model, full, &[], impostor)?
        .colours(px, lag)?
        .0)
}

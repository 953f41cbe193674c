//! Where a character's animated impostor joins its chain under one method: measured, as the
//! trees' impostors are placed (see `bake::billboard::chain::impostor_level`), by its colour
//! error against full detail at the size where it would switch in, beside the mesh level it
//! would stand for at that size.
//!
//! Level k comes in where its error e_k projects to the pixel tolerance τ, at a height of
//! τ·H / e_k pixels for a character H high. Scanning from the coarsest level L towards the
//! finer ones, the impostor takes level k's place (and every coarser one's) while its colour
//! error at k's switch size is no worse than level k's own there. Where it does not beat even
//! level L at L's size, it may still come in further off: at half, a quarter or an eighth of
//! that size, with error 2, 4 or 8 e_L, if it beats level L there. Otherwise the chain keeps
//! no impostor. So selection treats it like any level, and its error where it shows stays
//! within what the chain's own levels show there.
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
use super::levels::mapped_pack;
use super::spec::Loaded;
use super::world::World;
use crate::bake::character::lod::LodLevel;
use crate::bake::gpu_data::drawable::CharacterBake;
use crate::bake::impostor::animated::AnimatedImpostor;
use crate::model::Model;
use crate::render::Gpu;
use crate::render::targets::Offscreen;
use anyhow::Result;
use serde::{Deserialize, Serialize};

/// One measurement of a placement: at `px` pixels high, the impostor's colour error and
/// mesh level `level`'s.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Measured {
    pub px: f32,
    pub level: usize,
    pub impostor: f32,
    pub mesh: f32,
}

/// Where the impostor comes in under one method.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Placement {
    /// Its error bound, scene units: the error of the level it takes the place of, or a
    /// multiple of the coarsest level's; `None` where it beats no level.
    pub epsilon: Option<f32>,
    /// The pixel tolerance it was placed for: with `epsilon`, it comes in at `tolerance_px ·
    /// H / epsilon` pixels high, the size its colour error was measured at.
    pub tolerance_px: f32,
    /// Every measurement, in the order taken.
    pub measured: Vec<Measured>,
}

impl Placement {
    /// The error bound selection gives the impostor at pixel tolerance `tolerance_px`: never
    /// below what makes it come in where it was measured. Selection takes a level where its
    /// error projects to the tolerance, so at a tolerance above the placement's the bound
    /// alone would bring the impostor in at a larger size than its error was measured at
    /// (at 8 px, five times the size placed at 1.5 px: a blurred figure 170 pixels high); the
    /// bound grows with the tolerance instead, so the impostor never shows larger than that.
    pub fn epsilon_at(&self, tolerance_px: f32) -> Option<f32> {
        self.epsilon
            .map(|e| e * (tolerance_px / self.tolerance_px.max(1e-6)).max(1.0))
    }

    /// The largest figure, in pixels high, the impostor is shown for, for a model `height`
    /// scene units high.
    pub fn largest_px(&self, height: f32) -> Option<f32> {
        self.epsilon
            .map(|e| self.tolerance_px * height / e.max(1e-9))
    }
}

/// The views look down this many degrees, as a crowd's camera does.
pub(crate) const PITCH_DEG: f32 = 15.0;

/// The drawings the placement compares, each a world of its own: full detail, the impostor,
/// and full detail's world again with one mesh level in place of its full-detail set, lit
/// through its normal map as the runtime draws it.
struct Worlds<'a> {
    gpu: &'a Gpu,
    model: &'a Model,
    full: World,
    impostor: World,
    level: World,
    /// The level `level` shows now.
    shown: Option<usize>,
    duration: f32,
    height: f32,
    centre: glam::Vec3,
}

impl<'a> Worlds<'a> {
    fn new(
        gpu: &'a Gpu,
        model: &'a Model,
        full: &CharacterBake,
        impostor: &AnimatedImpostor,
    ) -> Result<Self> {
        let world = |loaded: Loaded| metric_world(gpu, loaded);
        let impostor_bake = impostor
            .bake(full.bounds)
            .map_err(|e| anyhow::anyhow!("{}: {e}", impostor.model.name))?;
        Ok(Worlds {
            gpu,
            model,
            full: world(Loaded::forest_of_bake(model, full.clone(), 1))?,
            impostor: world(Loaded::forest_of_bake(&impostor.model, impostor_bake, 1))?,
            level: world(Loaded::forest_of_bake(model, full.clone(), 1))?,
            shown: None,
            duration: model.clips.first().map_or(1.0, |c| c.duration),
            height: full.bounds.size().y.max(1e-3),
            centre: full.bounds.center(),
        })
    }

    /// Shows mesh level `k` of `levels` in the level's world.
    fn show(&mut self, levels: &[LodLevel], k: usize) -> Result<()> {
        if self.shown != Some(k) {
            let mut level = levels[k].clone();
            level.geomorph.clear();
            let pack = mapped_pack(self.model, levels, &[level]).map_err(anyhow::Error::msg)?;
            self.level.renderer.add_levels(self.gpu, 0, 0, &pack)?;
            self.shown = Some(k);
        }
        Ok(())
    }

    /// The colour errors of the impostor and of the level shown (0 where none is), both
    /// against full detail, at `px` pixels high; the impostor's clock `lag` seconds behind.
    fn errors(&mut self, px: f32, lag: f32) -> Result<(f32, f32)> {
        let gpu = self.gpu;
        let (size, distance) = framing(px);
        let target = Offscreen::new(gpu, size[0], size[1], 1);
        let shoot = |w: &mut World, camera, t, empty| picture(gpu, w, &target, camera, t, empty);
        let (mut covered, mut off_impostor, mut off_level) = (0u64, 0.0f64, 0.0f64);
        for view in 0..METRIC_VIEWS {
            let yaw = 360.0 * view as f32 / METRIC_VIEWS as f32;
            let camera = metric_camera(self.centre, self.height, yaw, PITCH_DEG, distance);
            let background = shoot(&mut self.full, camera, 0.0, true)?;
            for frame in 0..METRIC_FRAMES {
                let t = self.duration * frame as f32 / METRIC_FRAMES as f32;
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

/// The colour error of `impostor` against full detail of `model` (`full`: its bake) at
/// `px` pixels high (see the module comment), its clock `lag` seconds behind full detail's.
pub fn impostor_error(
    gpu: &Gpu,
    model: &Model,
    full: &CharacterBake,
    impostor: &AnimatedImpostor,
    px: f32,
    lag: f32,
) -> Result<f32> {
    Ok(Worlds::new(gpu, model, full, impostor)?.errors(px, lag)?.0)
}

/// Places `impostor` in the chain `levels` (finest first) of `model` (`full`: its
/// full-detail bake), for selection at `tolerance_px` (see the module comment).
pub fn place_impostor(
    gpu: &Gpu,
    model: &Model,
    full: &CharacterBake,
    levels: &[LodLevel],
    impostor: &AnimatedImpostor,
    tolerance_px: f32,
) -> Result<Placement> {
    let mut placement = Placement {
        epsilon: None,
        tolerance_px,
        measured: Vec::new(),
    };
    let coarsest = levels.len().saturating_sub(1);
    if coarsest == 0 {
        return Ok(placement);
    }
    let mut worlds = Worlds::new(gpu, model, full, impostor)?;
    let h = worlds.height;
    let switch_px = |e: f32| tolerance_px * h / e.max(1e-6);
    let mut measure = |worlds: &mut Worlds, k: usize, px: f32| -> Result<bool> {
        worlds.show(levels, k)?;
        let (imp, mesh) = worlds.errors(px, 0.0)?;
        log::debug!(
            "{}: at {px:.1} px the impostor's colour error is {imp:.3}, level {k}'s {mesh:.3}",
            model.name
        );
        placement.measured.push(Measured {
            px,
            level: k,
            impostor: imp,
            mesh,
        });
        Ok(imp <= mesh)
    };
    let mut epsilon = None;
    for k in (1..=coarsest).rev() {
        if !measure(&mut worlds, k, switch_px(levels[k].error))? {
            break;
        }
        epsilon = Some(levels[k].error);
    }
    if epsilon.is_none() {
        let e = levels[coarsest].error;
        for scale in [2.0f32, 4.0, 8.0] {
            if measure(&mut worlds, coarsest, switch_px(e * scale))? {
                epsilon = Some(e * scale);
                break;
            }
        }
    }
    placement.epsilon = epsilon;
    Ok(placement)
}

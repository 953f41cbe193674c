//! What the normal maps buy: each coarse level's colour error against full detail, lit by its
//! own vertex normals and through its normal map (Merry, Marais & Gain, "Analytic simplification
//! of animated characters", light their coarse levels through tangent-space normal maps, §6.4;
//! see `bake::normal_map`).
//!
//! The error is the impostor placement's (see `impostor_fit`): the mean colour
//! difference over the pixels either picture covers, divided by the pixels full detail covers,
//! from five views round the character 15° above the ground at five times of its first clip.
//! Both pictures of a level show the same triangles, so the difference between the two errors
//! is the lighting alone.
//!
//! A mean over the picture can hide a streak: a normal map that darkens a few texels of a face
//! and brightens the rest scores as an improvement. So each error is also taken on its worst
//! [`TILE`]-pixel tile (among those full detail mostly covers). And a level that keeps its
//! shape but shows one part in another part's colour (a trim bleeding over a plate) is counted
//! apart, lighting aside: the share of the pixels both pictures cover that show a colour
//! (chromaticity, within [`RECOLOURED`]) full detail shows nowhere within the level's error of
//! them. A part's border that moved by the level's error is no bleed; a colour where full
//! detail has none near is.

use super::colour_error::{
    METRIC_FRAMES, METRIC_VIEWS, framing, metric_camera, metric_world, picture,
};
use super::impostor_fit::{PITCH_DEG, colour_off};
use crate::bake::character::lod::LodLevel;
use crate::bake::gpu_data::drawable::Drawable;
use crate::model::Model;
use crate::render::Gpu;
use crate::render::targets::Offscreen;
use crate::runtime::levels::mapped_pack;
use crate::runtime::spec::Loaded;
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
    /// The largest colour error over one [`TILE`]-pixel tile, lit by its vertex normals and
    /// through its normal map.
    pub worst_tile_vertex_normals: f32,
    pub worst_tile_normal_maps: f32,
    /// The share of the pixels both pictures cover that show another colour (see the module
    /// comment), lit by its vertex normals.
    pub recoloured: f32,
}

/// Tiles the worst local error is taken over are this many pixels on a side.
pub const TILE: u32 = 16;
/// A tile counts where full detail covers at least this share of it.
const TILE_COVERED: f32 = 0.5;
/// Chromaticities (r, g over r + g + b) differing by more than this, summed, are another
/// colour: the steel and gilt of the test knight differ by 0.1, a sunlit and a shaded side of
/// one colour by under 0.02.
pub const RECOLOURED: f32 = 0.04;
/// Pixels darker than this (r + g + b out of 765) have no chromaticity worth reading.
const DARK: u32 = 90;

/// One picture's terms: covered pixels, summed colour difference, the worst tile's error, and
/// the pixels both cover and those of them recoloured.
#[derive(Clone, Copy, Debug, Default)]
struct Terms {
    covered: u64,
    off: f64,
    worst_tile: f64,
    both: u64,
    recoloured: u64,
}

/// The terms of `other` against `full`, a colour looked for within `reach` pixels.
fn terms(
    full: &image::RgbaImage,
    other: &image::RgbaImage,
    background: &image::RgbaImage,
    reach: u32,
) -> Terms {
    let (covered, off) = colour_off(full, other, background);
    let (w, h) = full.dimensions();
    let on = |img: &image::RgbaImage, x: u32, y: u32| {
        super::colour_error::covers(img.get_pixel(x, y), background.get_pixel(x, y))
    };
    let mut t = Terms {
        covered,
        off,
        ..Terms::default()
    };
    let chroma = |p: &image::Rgba<u8>| {
        let sum = (p[0] as u32 + p[1] as u32 + p[2] as u32).max(1) as f32;
        (p[0] as f32 / sum, p[1] as f32 / sum, sum as u32)
    };
    for ty in (0..h).step_by(TILE as usize) {
        for tx in (0..w).step_by(TILE as usize) {
            let (mut n, mut sum, mut area) = (0u32, 0.0f64, 0u32);
            for y in ty..(ty + TILE).min(h) {
                for x in tx..(tx + TILE).min(w) {
                    area += 1;
                    let (a, b) = (full.get_pixel(x, y), other.get_pixel(x, y));
                    let (ina, inb) = (on(full, x, y), on(other, x, y));
                    n += ina as u32;
                    if ina || inb {
                        sum +=
                            (0..3).map(|i| a[i].abs_diff(b[i]) as f64).sum::<f64>() / (3.0 * 255.0);
                    }
                    if ina && inb {
                        let ((ar, ag, asum), (br, bg, bsum)) = (chroma(a), chroma(b));
                        if asum >= DARK && bsum >= DARK {
                            t.both += 1;
                            let like = |(r, g, sum): (f32, f32, u32)| {
                                sum >= DARK && (r - br).abs() + (g - bg).abs() <= RECOLOURED
                            };
                            if !like((ar, ag, asum)) {
                                let near =
                                    (y.saturating_sub(reach)..(y + reach + 1).min(h)).any(|v| {
                                        (x.saturating_sub(reach)..(x + reach + 1).min(w))
                                            .any(|u| like(chroma(full.get_pixel(u, v))))
                                    });
                                if !near {
                                    t.recoloured += 1;
                                }
                            }
                        }
                    }
                }
            }
            if n as f32 >= TILE_COVERED * area as f32 {
                t.worst_tile = t.worst_tile.max(sum / n as f64);
            }
        }
    }
    t
}

/// The colour errors of levels `which` of `chain` (finest first, level 0 full detail) of
/// `model` (`full`: its full-detail bake) against full detail, `px` pixels high.
pub fn shading_errors(
    gpu: &Gpu,
    model: &Model,
    full: &Drawable,
    chain: &[LodLevel],
    which: &[usize],
    px: f32,
) -> Result<Vec<LevelShading>> {
    let at: Vec<(usize, f32)> = which.iter().map(|&k| (k, px)).collect();
    shading_errors_at(gpu, model, full, chain, &at)
}

/// [`shading_errors`] with a size for each level: `(level, px)`.
pub fn shading_errors_at(
    gpu: &Gpu,
    model: &Model,
    full: &Drawable,
    chain: &[LodLevel],
    at: &[(usize, f32)],
) -> Result<Vec<LevelShading>> {
    let mut full_world = metric_world(gpu, Loaded::forest_of_bake(model, full.clone(), 1))?;
    let mut level_world = metric_world(gpu, Loaded::forest_of_bake(model, full.clone(), 1))?;
    let height = full.bounds.size().y.max(1e-3);
    let centre = full.bounds.center();
    let duration = model.clips.first().map_or(1.0, |c| c.duration);
    let mut out = Vec::with_capacity(at.len());
    for &(k, px) in at {
        let (size, distance) = framing(px);
        let target = Offscreen::new(gpu, size[0], size[1], 1);
        // The level's error at this size, in pixels: how far a part's border may have moved.
        let reach = (px * chain[k].error / height).ceil().clamp(1.0, 64.0) as u32;
        let mut level = chain[k].clone();
        level.geomorph.clear();
        let pack = mapped_pack(model, chain, &[level]).map_err(anyhow::Error::msg)?;
        let mapped = pack.levels[0].normal_mapped;
        level_world.renderer.add_levels(gpu, 0, 0, &pack)?;
        let (mut plain_terms, mut mapped_terms) = (Terms::default(), Terms::default());
        for view in 0..METRIC_VIEWS {
            let yaw = 360.0 * view as f32 / METRIC_VIEWS as f32;
            let mut camera = metric_camera(centre, height, yaw, PITCH_DEG, distance);
            let mut background = picture(gpu, &mut full_world, &target, camera, 0.0, true)?;
            for frame in 0..METRIC_FRAMES {
                let t = duration * frame as f32 / METRIC_FRAMES as f32;
                if !full.travel.is_empty() && frame > 0 {
                    // Where the clip carries the body (root motion), the view goes with it.
                    let at = centre + full.travel_at(0, t);
                    camera = metric_camera(at, height, yaw, PITCH_DEG, distance);
                    background = picture(gpu, &mut full_world, &target, camera, 0.0, true)?;
                }
                let reference = picture(gpu, &mut full_world, &target, camera, t, false)?;
                level_world.renderer.normal_maps = false;
                let plain = picture(gpu, &mut level_world, &target, camera, t, false)?;
                level_world.renderer.normal_maps = true;
                let lit = picture(gpu, &mut level_world, &target, camera, t, false)?;
                let (p, m) = (
                    terms(&reference, &plain, &background, reach),
                    terms(&reference, &lit, &background, reach),
                );
                for (sum, t) in [(&mut plain_terms, p), (&mut mapped_terms, m)] {
                    sum.covered += t.covered;
                    sum.off += t.off;
                    sum.worst_tile = sum.worst_tile.max(t.worst_tile);
                    sum.both += t.both;
                    sum.recoloured += t.recoloured;
                }
            }
        }
        let n = plain_terms.covered.max(1) as f64;
        out.push(LevelShading {
            level: k,
            triangles: chain[k].triangles(),
            px,
            vertex_normals: (plain_terms.off / n) as f32,
            normal_maps: (mapped_terms.off / n) as f32,
            mapped,
            worst_tile_vertex_normals: plain_terms.worst_tile as f32,
            worst_tile_normal_maps: mapped_terms.worst_tile as f32,
            recoloured: (plain_terms.recoloured as f64 / plain_terms.both.max(1) as f64) as f32,
        });
    }
    Ok(out)
}

//! Whether every cut-out material of a tree (leaves, needles, flowers) stays visible at each
//! of its levels: the share of the foliage's pixels drawn in each material's colour, full tree
//! against level.
//!
//! A billboard's atlas mixes its leaves' materials into one texture, so a level's pixels
//! cannot be traced back to materials by what drew them; they are told apart by colour. Each
//! material's colour is its texture's mean over the texels it keeps (alpha at or above its
//! cutoff) times its base colour factor, and each covered pixel of either picture counts for
//! the material whose chromaticity (r, g, b over their sum, linear) is nearest. Light tints
//! both pictures alike, so what moves a share is what the level draws. Materials closer in
//! chromaticity than [`ALIKE`] are counted as one (two greens cannot be told apart, and a
//! level that swapped one for the other would look the same).
//!
//! Foliage alone is drawn (wood left out, as the colour metric does), from the metric's
//! [`METRIC_VIEWS`] views round the tree at ground level, at two times of its loop.

use super::colour_error::{METRIC_VIEWS, covers, framing, metric_camera, metric_world, picture};
use crate::bake::foliage::billboard::chain::CloudLevel;
use crate::bake::foliage::billboard::is_cut_out;
use crate::model::{Material, Model, srgb_to_linear};
use crate::render::Gpu;
use crate::render::targets::Offscreen;
use crate::runtime::spec::Loaded;
use anyhow::Result;
use glam::Vec3;
use serde::Serialize;

/// Materials whose chromaticities lie closer than this are counted as one.
pub const ALIKE: f32 = 0.04;
/// Times of the loop each view is drawn at.
const FRAMES: usize = 2;

/// The colours a tree's foliage is told apart by: groups of its cut-out materials, each with
/// its chromaticity.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MaterialColours {
    /// Each group's material names, joined with " + " where several are alike.
    pub names: Vec<String>,
    #[serde(skip)]
    chroma: Vec<Vec3>,
}

impl MaterialColours {
    /// The cut-out materials of `tree`, grouped where alike (see the module comment).
    pub fn of(tree: &Model) -> MaterialColours {
        Self::of_materials(&tree.materials)
    }

    /// The cut-out ones of `materials`, grouped where alike.
    pub fn of_materials(materials: &[Material]) -> MaterialColours {
        let mut out = MaterialColours {
            names: Vec::new(),
            chroma: Vec::new(),
        };
        for m in materials.iter().filter(|m| is_cut_out(m)) {
            let c = chromaticity(mean_colour(m));
            match out.chroma.iter().position(|k| k.distance(c) < ALIKE) {
                Some(i) => out.names[i] = format!("{} + {}", out.names[i], m.name),
                None => {
                    out.names.push(m.name.clone());
                    out.chroma.push(c);
                }
            }
        }
        out
    }

    /// How many colours the foliage is told apart by.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// The group whose colour is nearest a pixel's (linear).
    fn nearest(&self, linear: Vec3) -> usize {
        let c = chromaticity(linear);
        (0..self.chroma.len())
            .min_by(|&a, &b| {
                self.chroma[a]
                    .distance_squared(c)
                    .total_cmp(&self.chroma[b].distance_squared(c))
            })
            .unwrap_or(0)
    }
}

/// (r, g, b) over their sum; grey where there is no light.
fn chromaticity(c: Vec3) -> Vec3 {
    let s = c.x + c.y + c.z;
    if s <= 1e-6 {
        Vec3::splat(1.0 / 3.0)
    } else {
        c / s
    }
}

/// A material's mean linear colour over the texels it keeps, times its base colour factor.
fn mean_colour(m: &Material) -> Vec3 {
    let factor = Vec3::new(m.base_color[0], m.base_color[1], m.base_color[2]);
    let Some(t) = &m.texture else {
        return factor;
    };
    let cutoff = (m.alpha_cutoff.clamp(0.0, 1.0) * 255.0) as u8;
    let (mut sum, mut n) = (Vec3::ZERO, 0u64);
    for p in t.pixels.chunks_exact(4).filter(|p| p[3] >= cutoff.max(1)) {
        sum += Vec3::new(
            srgb_to_linear(p[0]),
            srgb_to_linear(p[1]),
            srgb_to_linear(p[2]),
        );
        n += 1;
    }
    if n == 0 {
        factor
    } else {
        sum / n as f32 * factor
    }
}

/// The foliage's pixels by material colour, full tree and level (each share over that
/// picture's covered pixels).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LevelShares {
    pub level: usize,
    pub full: Vec<f32>,
    pub shares: Vec<f32>,
}

impl LevelShares {
    /// The largest relative difference of a material's share from the full tree's: 0.2 where
    /// some material covers a fifth more, or less, of the level's foliage than of the tree's.
    pub fn worst(&self) -> f32 {
        self.full
            .iter()
            .zip(&self.shares)
            .map(|(f, s)| (s - f).abs() / f.max(1e-6))
            .fold(0.0, f32::max)
    }
}

/// The shares of `levels` (index, level) of `tree` by the colours of `colours`, against the
/// full tree, the foliage drawn `px` pixels high (see the module comment).
pub fn material_shares(
    gpu: &Gpu,
    tree: &Model,
    colours: &MaterialColours,
    levels: &[(usize, &CloudLevel)],
    px: f32,
) -> Result<Vec<LevelShares>> {
    if levels.is_empty() || colours.is_empty() {
        return Ok(Vec::new());
    }
    let (leaves, bake) = CloudLevel::full(tree)
        .foliage_bake()
        .map_err(anyhow::Error::msg)?;
    let mut full = metric_world(gpu, Loaded::forest_of_bake(&leaves, bake, 1))?;
    let (size, distance) = framing(px);
    let target = Offscreen::new(gpu, size[0], size[1], 1);
    let bounds = full.bakes[0].bounds;
    let height = bounds.size().y.max(1e-3);
    let duration = tree.clips.first().map_or(1.0, |c| c.duration);
    let cameras: Vec<_> = (0..METRIC_VIEWS)
        .map(|view| {
            let yaw = 360.0 * view as f32 / METRIC_VIEWS as f32;
            metric_camera(bounds.center(), height, yaw, 0.0, distance)
        })
        .collect();
    let times: Vec<f32> = (0..FRAMES)
        .map(|f| duration * f as f32 / FRAMES as f32)
        .collect();
    // The full tree's pictures once, with their backgrounds.
    let mut backgrounds = Vec::new();
    let mut reference = vec![0u64; colours.len()];
    for &camera in &cameras {
        let background = picture(gpu, &mut full, &target, camera, 0.0, true)?;
        for &t in &times {
            let img = picture(gpu, &mut full, &target, camera, t, false)?;
            count(colours, &img, &background, &mut reference);
        }
        backgrounds.push(background);
    }
    // One world for the levels, its tree replaced level by level (a world builds every
    // pipeline).
    let (first, first_bake) = levels[0].1.foliage_bake().map_err(anyhow::Error::msg)?;
    let mut world = metric_world(gpu, Loaded::forest_of_bake(&first, first_bake, 1))?;
    let mut out = Vec::with_capacity(levels.len());
    for (i, &(k, level)) in levels.iter().enumerate() {
        if i > 0 {
            let (_, bake) = level.foliage_bake().map_err(anyhow::Error::msg)?;
            world.renderer.replace_character(gpu, 0, &bake)?;
            world.bakes[0] = bake;
        }
        let mut counts = vec![0u64; colours.len()];
        for (&camera, background) in cameras.iter().zip(&backgrounds) {
            for &t in &times {
                let img = picture(gpu, &mut world, &target, camera, t, false)?;
                count(colours, &img, background, &mut counts);
            }
        }
        out.push(LevelShares {
            level: k,
            full: shares(&reference),
            shares: shares(&counts),
        });
    }
    Ok(out)
}

/// Adds the covered pixels of `img` to `counts`, each to its nearest material colour.
fn count(
    colours: &MaterialColours,
    img: &image::RgbaImage,
    background: &image::RgbaImage,
    counts: &mut [u64],
) {
    for (p, bg) in img.pixels().zip(background.pixels()) {
        if covers(p, bg) {
            let linear = Vec3::new(
                srgb_to_linear(p[0]),
                srgb_to_linear(p[1]),
                srgb_to_linear(p[2]),
            );
            counts[colours.nearest(linear)] += 1;
        }
    }
}

fn shares(counts: &[u64]) -> Vec<f32> {
    let total = counts.iter().sum::<u64>().max(1) as f32;
    counts.iter().map(|&c| c as f32 / total).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Rgba8Image;

    fn plain(name: &str, rgb: [u8; 3], transparent_half: bool) -> Material {
        let mut pixels = Vec::new();
        for i in 0..16 {
            let a = if transparent_half && i % 2 == 0 {
                0
            } else {
                255
            };
            pixels.extend([rgb[0], rgb[1], rgb[2], a]);
        }
        Material::cut_out(
            name,
            [1.0; 4],
            Some(Rgba8Image {
                width: 4,
                height: 4,
                pixels,
            }),
        )
    }

    #[test]
    fn materials_are_told_apart_by_colour_and_alike_ones_counted_as_one() {
        let colours = MaterialColours::of_materials(&[
            Material::opaque("bark", [0.3, 0.2, 0.1, 1.0], None),
            plain("leaf", [40, 110, 30], true),
            plain("dark leaf", [30, 90, 24], true),
            plain("blossom", [230, 120, 170], true),
        ]);
        assert_eq!(colours.names, ["leaf + dark leaf", "blossom"]);
        // A dim pink pixel is a blossom's, a bright green one a leaf's.
        let lin = |r: u8, g: u8, b: u8| {
            Vec3::new(srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b))
        };
        assert_eq!(colours.nearest(lin(120, 60, 90)), 1);
        assert_eq!(colours.nearest(lin(90, 200, 80)), 0);
        let s = LevelShares {
            level: 1,
            full: vec![0.8, 0.2],
            shares: vec![0.85, 0.15],
        };
        assert!((s.worst() - 0.25).abs() < 1e-5);
    }
}

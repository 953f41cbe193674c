//! Base colours of all materials of a model as the layers of one texture array, mipmapped.
//!
//! glTF primitives of one skin may use different materials. Merging them into one model (one
//! draw) needs them in one place: every material becomes a layer of the same size holding
//! `texture × base colour factor` (a plain colour where there is no texture). The layer index goes
//! into each vertex's header in the vertex texture.

use crate::model::{AlphaMode, Material, MaterialRole, linear_to_srgb, srgb_to_linear};
use serde::{Deserialize, Serialize};

/// Layers are never larger than this on a side.
pub const MAX_LAYER_SIZE: u32 = 2048;
/// Layer size when no material has a texture.
const PLAIN_LAYER_SIZE: u32 = 4;

/// sRGB-encoded RGBA8 layers with their mip chains.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialLayers {
    pub width: u32,
    pub height: u32,
    pub layer_count: u32,
    /// `mips[level]` holds all layers of that level one after another.
    pub mips: Vec<Vec<u8>>,
    /// Per layer, whether its material cuts its shape out with alpha
    /// ([`Material::cuts_out`]): a character's triangles of such layers are drawn two-sided
    /// and alpha-tested (see [`super::lod_pack::PackedLevel::cut_indices`]).
    #[serde(default)]
    pub cut_out: Vec<bool>,
}

impl MaterialLayers {
    pub fn bake(materials: &[Material]) -> Self {
        let (mut width, mut height) = materials
            .iter()
            .filter_map(|m| m.texture.as_ref())
            .fold((0, 0), |(w, h), t| (w.max(t.width), h.max(t.height)));
        if width == 0 || height == 0 {
            (width, height) = (PLAIN_LAYER_SIZE, PLAIN_LAYER_SIZE);
        }
        let scale = (MAX_LAYER_SIZE as f32 / width.max(height) as f32).min(1.0);
        width = ((width as f32 * scale) as u32).max(1);
        height = ((height as f32 * scale) as u32).max(1);

        let mut levels: Vec<Vec<u8>> = Vec::new();
        let materials_or_default: Vec<Material> = if materials.is_empty() {
            vec![Material::opaque("default", [1.0; 4], None)]
        } else {
            materials.to_vec()
        };
        let mut layer_mips: Vec<Vec<Vec<u8>>> = Vec::new();
        for m in &materials_or_default {
            let base = layer_pixels(m, width, height);
            layer_mips.push(mip_chain(base, width, height));
        }
        let level_count = layer_mips[0].len();
        for level in 0..level_count {
            let mut all = Vec::new();
            for mips in &layer_mips {
                all.extend_from_slice(&mips[level]);
            }
            levels.push(all);
        }
        MaterialLayers {
            width,
            height,
            layer_count: materials_or_default.len() as u32,
            mips: levels,
            cut_out: materials_or_default
                .iter()
                .map(Material::cuts_out)
                .collect(),
        }
    }
}

/// One material's layer at the common size: texture (resized) times factor, in sRGB.
fn layer_pixels(m: &Material, width: u32, height: u32) -> Vec<u8> {
    let mut pixels = coloured_pixels(m, width, height);
    // The shaders cut out at one half: an opaque material's alpha goes to one, a mask's is
    // scaled so that its own cutoff lands on one half.
    match m.alpha_mode {
        AlphaMode::Opaque => pixels.chunks_exact_mut(4).for_each(|p| p[3] = 255),
        AlphaMode::Mask if m.alpha_cutoff != 0.5 => {
            let scale = 0.5 / m.alpha_cutoff.clamp(1.0 / 255.0, 1.0);
            for p in pixels.chunks_exact_mut(4) {
                p[3] = (p[3] as f32 * scale).round().min(255.0) as u8;
            }
        }
        _ => {}
    }
    pixels
}

/// The base colour texture (or factor) times the factor, `width` × `height`.
fn coloured_pixels(m: &Material, width: u32, height: u32) -> Vec<u8> {
    let f = m.base_color;
    match &m.texture {
        Some(tex) => {
            let img = image::RgbaImage::from_raw(tex.width, tex.height, tex.pixels.clone())
                .expect("importer checked the size");
            let img = if (tex.width, tex.height) == (width, height) {
                img
            } else {
                image::imageops::resize(&img, width, height, image::imageops::FilterType::Triangle)
            };
            if f == [1.0; 4] {
                return img.into_raw();
            }
            let lut: Vec<f32> = (0..=255u8).map(srgb_to_linear).collect();
            img.into_raw()
                .chunks_exact(4)
                .flat_map(|p| {
                    [
                        linear_to_srgb(lut[p[0] as usize] * f[0]),
                        linear_to_srgb(lut[p[1] as usize] * f[1]),
                        linear_to_srgb(lut[p[2] as usize] * f[2]),
                        (p[3] as f32 * f[3]).round().clamp(0.0, 255.0) as u8,
                    ]
                })
                .collect()
        }
        None => {
            let px = [
                linear_to_srgb(f[0]),
                linear_to_srgb(f[1]),
                linear_to_srgb(f[2]),
                (f[3] * 255.0).round().clamp(0.0, 255.0) as u8,
            ];
            px.repeat((width * height) as usize)
        }
    }
}

/// Alpha at or above this is inside a cut-out (foliage is alpha-tested at one half).
const CUTOFF: u8 = 128;
/// Rings of texels a cut-out's colour is dilated by at full size, and at each mip level.
const BASE_DILATION: u32 = 8;
const MIP_DILATION: u32 = 2;

/// Mip levels down to 1×1, each a 2×2 box average taken in linear light.
///
/// A layer with a cut-out (foliage) is treated as alpha-tested: colour is averaged weighted by
/// alpha, so the transparent surroundings do not darken the edges, and each level's alpha is
/// scaled so that the share of texels passing the alpha test stays that of the full-size
/// texture, so thin leaves and needles do not erode into nothing at a distance. Its colour is
/// dilated into the transparent texels round the shapes at every level (see [`dilate`]); where
/// a texel's four children are all transparent it takes their plain average, which carries the
/// dilated colour on down the chain.
fn mip_chain(mut base: Vec<u8>, width: u32, height: u32) -> Vec<Vec<u8>> {
    let lut: Vec<f32> = (0..=255u8).map(srgb_to_linear).collect();
    let cut_out = base.chunks_exact(4).any(|p| p[3] < CUTOFF);
    if cut_out {
        dilate(&mut base, width, height, BASE_DILATION);
    }
    let coverage = |px: &[u8]| {
        px.chunks_exact(4).filter(|p| p[3] >= CUTOFF).count() as f32 / (px.len() / 4) as f32
    };
    let target = coverage(&base);
    let mut chain = vec![base];
    let (mut w, mut h) = (width, height);
    while w > 1 || h > 1 {
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let prev = chain.last().expect("non-empty");
        let mut next = Vec::with_capacity((nw * nh * 4) as usize);
        for y in 0..nh {
            for x in 0..nw {
                let mut acc = [0.0f32; 4];
                let mut plain = [0.0f32; 3];
                let mut weight = 0.0f32;
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let sx = (2 * x + dx).min(w - 1);
                    let sy = (2 * y + dy).min(h - 1);
                    let i = ((sy * w + sx) * 4) as usize;
                    let a = if cut_out {
                        prev[i + 3] as f32 / 255.0
                    } else {
                        1.0
                    };
                    for c in 0..3 {
                        let v = lut[prev[i + c] as usize];
                        acc[c] += v * a;
                        plain[c] += v;
                    }
                    weight += a;
                    acc[3] += prev[i + 3] as f32;
                }
                let wsum = if !cut_out {
                    4.0
                } else if weight > 0.0 {
                    weight
                } else {
                    // All four transparent: their (dilated) colour, unweighted.
                    acc[..3].copy_from_slice(&plain);
                    4.0
                };
                next.extend_from_slice(&[
                    linear_to_srgb(acc[0] / wsum),
                    linear_to_srgb(acc[1] / wsum),
                    linear_to_srgb(acc[2] / wsum),
                    (acc[3] / 4.0).round() as u8,
                ]);
            }
        }
        if cut_out {
            preserve_coverage(&mut next, target);
            dilate(&mut next, nw, nh, MIP_DILATION);
        }
        chain.push(next);
        (w, h) = (nw, nh);
    }
    chain
}

/// Fills every transparent texel's colour with that of its nearest opaque neighbour (a few
/// rings out), keeping alpha 0, so that bilinear filtering and mipmaps never mix in black at a
/// leaf's edge: "dilated colour under alpha". Under alpha to coverage an edge fragment keeps
/// the colour it samples however little alpha it has, so an undilated edge shows whatever the
/// transparent texels hold (lit, a pale rim).
pub fn dilate(pixels: &mut [u8], width: u32, height: u32, rings: u32) {
    let (w, h) = (width as usize, height as usize);
    let mut filled: Vec<bool> = pixels.chunks_exact(4).map(|p| p[3] > 0).collect();
    let neighbours = |i: usize| {
        let (x, y) = (i % w, i / w);
        [
            (x > 0).then(|| i - 1),
            (x + 1 < w).then(|| i + 1),
            (y > 0).then(|| i - w),
            (y + 1 < h).then(|| i + w),
        ]
        .into_iter()
        .flatten()
    };
    // A ring at a time, breadth first: only the texels next to the ones filled so far are
    // visited, so a mostly empty atlas costs what its shapes' outlines cost.
    let mut ring: Vec<usize> = (0..w * h)
        .filter(|&i| !filled[i] && neighbours(i).any(|n| filled[n]))
        .collect();
    let mut updates: Vec<(usize, [u8; 3])> = Vec::new();
    for _ in 0..rings {
        if ring.is_empty() {
            break;
        }
        updates.clear();
        for &i in &ring {
            let mut acc = [0u32; 3];
            let mut n = 0;
            for j in neighbours(i).filter(|&j| filled[j]) {
                for c in 0..3 {
                    acc[c] += pixels[4 * j + c] as u32;
                }
                n += 1;
            }
            updates.push((i, acc.map(|a| (a / n.max(1)) as u8)));
        }
        for &(i, c) in &updates {
            pixels[4 * i..4 * i + 3].copy_from_slice(&c);
            filled[i] = true;
        }
        let mut next: Vec<usize> = ring
            .iter()
            .flat_map(|&i| neighbours(i))
            .filter(|&j| !filled[j])
            .collect();
        next.sort_unstable();
        next.dedup();
        ring = next;
    }
}

/// Scales a level's alpha so that the share of texels at or above [`CUTOFF`] is `target`
/// (Castaño's coverage-preserving mipmaps), by bisection on the scale.
pub(crate) fn preserve_coverage(level: &mut [u8], target: f32) {
    let mut histogram = [0u32; 256];
    for p in level.chunks_exact(4) {
        histogram[p[3] as usize] += 1;
    }
    let n = (level.len() / 4) as f32;
    let share = |scale: f32| {
        histogram
            .iter()
            .enumerate()
            .filter(|&(a, _)| (a as f32 * scale).min(255.0) >= CUTOFF as f32)
            .map(|(_, &c)| c)
            .sum::<u32>() as f32
            / n
    };
    let (mut lo, mut hi) = (0.0f32, 16.0f32);
    for _ in 0..24 {
        let mid = 0.5 * (lo + hi);
        if share(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let scaled: Vec<u8> = (0..256)
        .map(|a| (a as f32 * hi).round().min(255.0) as u8)
        .collect();
    for p in level.chunks_exact_mut(4) {
        p[3] = scaled[p[3] as usize];
    }
}

// A billboard cloud's atlas and its lighting are told apart from the model's own materials
// by their roles ([`MaterialRole`]), which only the cloud's bake
// (`bake::foliage::billboard::cloud_model`) gives; the names below are what a debugger or an
// exported file shows.

/// The name of a cloud model's atlas material ([`MaterialRole::BillboardAtlas`]).
pub const BILLBOARD_MATERIAL: &str = "billboards";

/// The name of the material after a cloud's atlas that holds its lighting
/// ([`MaterialRole::BillboardLighting`]): per texel, the normal the leaf drawn there is lit by
/// when seen from the billboard's front, in its billboard's
/// [`billboard_frame`](crate::bake::foliage::billboard::atlas::billboard_frame) (r, g, b along
/// t, b and n, as x/2 + 1/2). The crown's occlusion, which scales all of a leaf's light, is
/// multiplied into the atlas's colour. Stored sRGB-encoded, so that the renderer's sRGB
/// material texture hands the shader these values in linear form.
pub const BILLBOARD_LIGHTING: &str = "billboard lighting";

/// The index of `materials`' billboard atlas, if it has one.
pub fn billboard_atlas(materials: &[Material]) -> Option<usize> {
    materials
        .iter()
        .position(|m| m.role == MaterialRole::BillboardAtlas)
}

/// The index of `materials`' billboard atlas where the material after it holds its lighting.
pub fn lit_atlas_material(materials: &[Material]) -> Option<usize> {
    let atlas = billboard_atlas(materials)?;
    (materials.get(atlas + 1)?.role == MaterialRole::BillboardLighting).then_some(atlas)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Rgba8Image;

    /// A cut-out material of a square `size`² texture and a unit factor.
    fn textured(name: &str, size: u32, pixels: Vec<u8>) -> Material {
        let texture = Rgba8Image {
            width: size,
            height: size,
            pixels,
        };
        Material::cut_out(name, [1.0; 4], Some(texture))
    }

    #[test]
    fn factor_only_materials_make_plain_layers_with_mips() {
        let m = Material {
            ..Material::opaque("red", [1.0, 0.0, 0.0, 1.0], None)
        };
        let l = MaterialLayers::bake(&[m.clone(), m]);
        assert_eq!((l.width, l.height, l.layer_count), (4, 4, 2));
        assert_eq!(l.mips.len(), 3);
        assert_eq!(&l.mips[2], &[255, 0, 0, 255, 255, 0, 0, 255]);
    }

    #[test]
    fn cut_out_mips_keep_their_coverage() {
        // Small soft dots scattered at random, like distant leaves: a plain box filter fades
        // them below the cut-off within a few levels.
        let size = 128u32;
        let mut rng = fastrand::Rng::with_seed(5);
        let dots: Vec<(f32, f32, f32)> = (0..160)
            .map(|_| (rng.f32() * 128.0, rng.f32() * 128.0, 1.0 + 1.5 * rng.f32()))
            .collect();
        let mut pixels = Vec::new();
        for y in 0..size {
            for x in 0..size {
                let r = dots
                    .iter()
                    .map(|&(cx, cy, rad)| {
                        ((x as f32 + 0.5 - cx).hypot(y as f32 + 0.5 - cy) - rad).max(0.0)
                    })
                    .fold(f32::MAX, f32::min);
                let a = ((1.0 - r) * 255.0).clamp(0.0, 255.0) as u8;
                pixels.extend_from_slice(&[40, 120, 30, a]);
            }
        }
        let m = textured("needles", size, pixels);
        let l = MaterialLayers::bake(&[m]);
        let share = |px: &[u8]| {
            px.chunks_exact(4).filter(|p| p[3] >= CUTOFF).count() as f32 / (px.len() / 4) as f32
        };
        let base = share(&l.mips[0]);
        assert!(base > 0.1 && base < 0.5, "{base}");
        for level in 1..=3 {
            let s = share(&l.mips[level]);
            assert!(
                (s - base).abs() <= 0.05,
                "level {level}: {s} of texels pass, {base} at full size"
            );
            assert!(s > 0.0, "level {level}: the lines vanished");
            // Colour comes from the lines only, not from the black around them.
            let i = l.mips[level]
                .chunks_exact(4)
                .position(|p| p[3] > 0)
                .unwrap();
            assert!(l.mips[level][4 * i + 1] > 100, "darkened edge colour");
        }
    }

    #[test]
    fn dilation_fills_colour_but_keeps_alpha() {
        let mut px = vec![0u8; 4 * 4 * 4];
        px[(5 * 4)..(5 * 4 + 4)].copy_from_slice(&[200, 100, 50, 255]);
        dilate(&mut px, 4, 4, 2);
        assert_eq!(&px[(4 * 4)..(4 * 4 + 4)], &[200, 100, 50, 0]);
        assert_eq!(px[5 * 4 + 3], 255);
    }

    /// A leaf shape on black: every level's texels next to the shape carry the leaf's colour,
    /// not the black around it, so neither bilinear filtering nor alpha to coverage shows a
    /// dark or (lit) pale rim.
    #[test]
    fn cut_out_colour_is_dilated_at_every_level() {
        let size = 64u32;
        let mut pixels = Vec::new();
        for y in 0..size {
            for x in 0..size {
                let inside = (x as f32 - 31.5).hypot(y as f32 - 31.5) < 12.0;
                pixels.extend_from_slice(if inside {
                    &[60, 140, 30, 255]
                } else {
                    &[0, 0, 0, 0]
                });
            }
        }
        let m = textured("leaf", size, pixels);
        let l = MaterialLayers::bake(&[m]);
        for (level, px) in l.mips.iter().enumerate().take(5) {
            let w = size >> level;
            // The texel just outside the disc's right edge, on its middle row.
            let (r, y) = (12.0 / (1 << level) as f32, w / 2);
            let x = (w as f32 / 2.0 + r + 0.5) as u32;
            let i = ((y * w + x.min(w - 1)) * 4) as usize;
            assert!(
                px[i + 1] > 100 && px[i] < px[i + 1],
                "level {level}: edge texel {:?}",
                &px[i..i + 4]
            );
        }
    }

    #[test]
    fn textures_are_multiplied_by_the_factor() {
        let tex = Rgba8Image {
            width: 2,
            height: 2,
            pixels: vec![255; 16],
        };
        let m = Material::opaque("half", [0.5, 1.0, 1.0, 1.0], Some(tex));
        let l = MaterialLayers::bake(&[m]);
        assert_eq!(l.mips[0][0], linear_to_srgb(0.5));
        assert_eq!(l.mips[0][1], 255);
    }
}

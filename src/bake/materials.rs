//! Base colours of all materials of a model as the layers of one texture array, mipmapped.
//!
//! glTF primitives of one skin may use different materials. Merging them into one model (one
//! draw) needs them in one place: every material becomes a layer of the same size holding
//! `texture × base colour factor` (a plain colour where there is no texture). The layer index goes
//! into each vertex's header in the vertex texture.

use crate::model::Material;
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
            vec![Material {
                name: "default".into(),
                base_color: [1.0; 4],
                texture: None,
            }]
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
        }
    }
}

fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_to_srgb(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// One material's layer at the common size: texture (resized) times factor, in sRGB.
fn layer_pixels(m: &Material, width: u32, height: u32) -> Vec<u8> {
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

/// Mip levels down to 1×1, each a 2×2 box average taken in linear light.
fn mip_chain(base: Vec<u8>, width: u32, height: u32) -> Vec<Vec<u8>> {
    let lut: Vec<f32> = (0..=255u8).map(srgb_to_linear).collect();
    let mut chain = vec![base];
    let (mut w, mut h) = (width, height);
    while w > 1 || h > 1 {
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let prev = chain.last().expect("non-empty");
        let mut next = Vec::with_capacity((nw * nh * 4) as usize);
        for y in 0..nh {
            for x in 0..nw {
                let mut acc = [0.0f32; 4];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let sx = (2 * x + dx).min(w - 1);
                    let sy = (2 * y + dy).min(h - 1);
                    let i = ((sy * w + sx) * 4) as usize;
                    for c in 0..3 {
                        acc[c] += lut[prev[i + c] as usize];
                    }
                    acc[3] += prev[i + 3] as f32;
                }
                next.extend_from_slice(&[
                    linear_to_srgb(acc[0] / 4.0),
                    linear_to_srgb(acc[1] / 4.0),
                    linear_to_srgb(acc[2] / 4.0),
                    (acc[3] / 4.0).round() as u8,
                ]);
            }
        }
        chain.push(next);
        (w, h) = (nw, nh);
    }
    chain
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Rgba8Image;

    #[test]
    fn factor_only_materials_make_plain_layers_with_mips() {
        let m = Material {
            name: "red".into(),
            base_color: [1.0, 0.0, 0.0, 1.0],
            texture: None,
        };
        let l = MaterialLayers::bake(&[m.clone(), m]);
        assert_eq!((l.width, l.height, l.layer_count), (4, 4, 2));
        assert_eq!(l.mips.len(), 3);
        assert_eq!(&l.mips[2], &[255, 0, 0, 255, 255, 0, 0, 255]);
    }

    #[test]
    fn textures_are_multiplied_by_the_factor() {
        let tex = Rgba8Image {
            width: 2,
            height: 2,
            pixels: vec![255; 16],
        };
        let m = Material {
            name: "half".into(),
            base_color: [0.5, 1.0, 1.0, 1.0],
            texture: Some(tex),
        };
        let l = MaterialLayers::bake(&[m]);
        assert_eq!(l.mips[0][0], linear_to_srgb(0.5));
        assert_eq!(l.mips[0][1], 255);
    }
}

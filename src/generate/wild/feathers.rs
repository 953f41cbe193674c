//! A character with cut-out parts: feathers (cards of an alpha-cut texture) over a skinned,
//! animated body, every material alpha-blended, as an exporter writes a bird whose feathers
//! blend. The cards ride on the body's skin, so they move as the character does: the model
//! must stay a character (mesh levels, its feathers drawn with their alpha), not become a
//! tree's billboard clouds.

use crate::model::{AlphaMode, Material, Model, Rgba8Image};
use glam::{Vec2, Vec3};

/// The feathers' colour (sRGB): orange, which a billboard atlas of green leaves would lose.
pub const FEATHER_SRGB: [u8; 3] = [235, 120, 30];

/// `model` with `cards` feathers on its surface, spread evenly over its vertices: each a quad
/// hanging outwards and down from its vertex, a tenth of the model's height long, skinned as
/// that vertex is. Every material, the body's too, is made `BLEND` (the body's alpha stays one,
/// so only the feathers cut out).
pub fn feathered(model: &Model, cards: usize) -> Model {
    let mut out = model.clone();
    out.name = format!("{} with feathers", model.name);
    for m in &mut out.materials {
        m.alpha_mode = AlphaMode::Blend;
    }
    let feather = out.materials.len() as u16;
    out.materials.push(Material {
        alpha_mode: AlphaMode::Blend,
        double_sided: true,
        ..Material::opaque("feathers", [1.0; 4], Some(feather_texture()))
    });
    let mesh = &model.mesh;
    let n = mesh.vertex_count();
    let height = crate::model::Bounds::of(mesh.positions.iter().copied())
        .map_or(1.0, |b| b.size().max_element());
    let (length, width) = (0.1 * height, 0.04 * height);
    for k in 0..cards.min(n) {
        let v = k * n / cards.min(n).max(1);
        let at = mesh.positions[v];
        let normal = mesh.normals[v].normalize_or(Vec3::X);
        let side = normal.cross(Vec3::Y).normalize_or(Vec3::Z);
        let down = (0.6 * normal - 0.8 * Vec3::Y).normalize();
        let face = side.cross(down).normalize_or(normal);
        let corners = [
            (at - 0.5 * width * side, Vec2::new(0.0, 0.0)),
            (at + 0.5 * width * side, Vec2::new(1.0, 0.0)),
            (at + 0.5 * width * side + length * down, Vec2::new(1.0, 1.0)),
            (at - 0.5 * width * side + length * down, Vec2::new(0.0, 1.0)),
        ];
        let first = out.mesh.vertex_count() as u32;
        for (p, uv) in corners {
            out.mesh.positions.push(p);
            out.mesh.normals.push(face);
            out.mesh.uvs.push(uv);
            out.mesh.materials.push(feather);
            out.mesh.influences.extend_from_slice(mesh.influences_of(v));
            out.mesh
                .influence_offsets
                .push(out.mesh.influences.len() as u32);
        }
        out.mesh
            .indices
            .extend([0, 1, 2, 0, 2, 3].map(|i| first + i));
    }
    out
}

/// A feather: an orange vane (an ellipse, its alpha one) with a darker shaft, on a transparent
/// card (alpha zero round it), 32 × 64 texels.
pub fn feather_texture() -> Rgba8Image {
    let (w, h) = (32u32, 64u32);
    let mut pixels = Vec::with_capacity((4 * w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let u = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
            let v = (y as f32 + 0.5) / h as f32 * 2.0 - 1.0;
            let inside = u * u / 0.8 + v * v < 0.9;
            let shaft = u.abs() < 0.08;
            let [r, g, b] = FEATHER_SRGB;
            let rgb = if shaft {
                [r / 2, g / 2, b / 2]
            } else {
                [r, g, b]
            };
            pixels.extend(rgb);
            pixels.push(if inside { 255 } else { 0 });
        }
    }
    Rgba8Image {
        width: w,
        height: h,
        pixels,
    }
}

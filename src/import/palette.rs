//! Plain-coloured materials in one palette texture.
//!
//! Files from kit-bashing tools and asset stores often colour a character by material alone: a
//! knight of a thousand materials, each a base colour factor and no texture. lodlab draws a
//! character in one draw with its materials as the layers of one texture array, every layer
//! the size of the largest texture ([`crate::bake::gpu_data::materials`]), so each plain colour would
//! cost a whole layer, and a thousand of them more memory than any GPU lends. Here the plain,
//! solid ones become blocks of one palette texture, and each of their vertices takes the texture
//! coordinate of its block's centre: one layer for all of them, and the colour of every
//! corner kept where it was.
//!
//! A block is [`BLOCK`] texels on a side, so its centre keeps its own colour through the mip
//! levels a character is drawn with until it is a few dozen pixels high. The simplifier sees a
//! textured material whose charts each show one colour: a chart torn onto another colour's
//! wedge pays for what it recolours (`crate::bake::character::simplify::collapse`), as a material border
//! between the separate materials did.

use crate::model::{Material, Model, Rgba8Image, linear_to_srgb};
use glam::Vec2;

/// Texels on a side of one colour's block: 8 keeps a block's centre its own colour down to the
/// 8×-reduced mip level.
pub const BLOCK: u32 = 8;

/// The name of the palette material.
pub const PALETTE_MATERIAL: &str = "lodlab palette";

/// Replaces the plain, solid materials of `model` (no texture, nothing cut out) by one palette
/// material, where there are at least two of them; the others keep their order, the palette
/// comes after them. Returns how many materials went into the palette (0: none).
pub fn pack_plain_colours(model: &mut Model) -> usize {
    let plain: Vec<bool> = model
        .materials
        .iter()
        .map(|m| m.texture.is_none() && !m.cuts_out())
        .collect();
    let count = plain.iter().filter(|&&p| p).count();
    if count < 2 {
        return 0;
    }
    // One block per distinct colour (an opaque material's alpha is never read).
    let key = |m: &Material| [m.base_color[0], m.base_color[1], m.base_color[2]].map(f32::to_bits);
    let mut colours: Vec<[u32; 3]> = Vec::new();
    let mut block_of = vec![usize::MAX; model.materials.len()];
    for (i, m) in model.materials.iter().enumerate() {
        if plain[i] {
            let k = key(m);
            block_of[i] = match colours.iter().position(|&c| c == k) {
                Some(b) => b,
                None => {
                    colours.push(k);
                    colours.len() - 1
                }
            };
        }
    }
    let across = (colours.len() as f64).sqrt().ceil() as u32;
    let side = (across * BLOCK).next_power_of_two();
    let mut pixels = vec![255u8; (side * side * 4) as usize];
    for (b, c) in colours.iter().enumerate() {
        let (bx, by) = (b as u32 % across, b as u32 / across);
        let texel = c.map(|x| linear_to_srgb(f32::from_bits(x)));
        for y in by * BLOCK..(by + 1) * BLOCK {
            for x in bx * BLOCK..(bx + 1) * BLOCK {
                let i = ((y * side + x) * 4) as usize;
                pixels[i..i + 3].copy_from_slice(&texel);
            }
        }
    }
    let centre = |b: usize| {
        let (bx, by) = (b as u32 % across, b as u32 / across);
        Vec2::new(
            (bx * BLOCK) as f32 + 0.5 * BLOCK as f32,
            (by * BLOCK) as f32 + 0.5 * BLOCK as f32,
        ) / side as f32
    };

    let mut materials = Vec::with_capacity(model.materials.len() - count + 1);
    let mut new_index = vec![0u16; model.materials.len()];
    for (i, m) in model.materials.iter().enumerate() {
        if !plain[i] {
            new_index[i] = materials.len() as u16;
            materials.push(m.clone());
        }
    }
    let palette = materials.len() as u16;
    let mut material = Material::opaque(
        PALETTE_MATERIAL,
        [1.0; 4],
        Some(Rgba8Image {
            width: side,
            height: side,
            pixels,
        }),
    );
    material.double_sided = model
        .materials
        .iter()
        .zip(&plain)
        .any(|(m, &p)| p && m.double_sided);
    materials.push(material);
    let mesh = &mut model.mesh;
    for v in 0..mesh.vertex_count() {
        let old = mesh.materials[v] as usize;
        if plain.get(old).copied().unwrap_or(false) {
            mesh.uvs[v] = centre(block_of[old]);
            mesh.materials[v] = palette;
        } else {
            mesh.materials[v] = new_index.get(old).copied().unwrap_or(0);
        }
    }
    model.materials = materials;
    count
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Influence, Skeleton, SkinnedMesh};

    fn model(materials: Vec<Material>, of_vertex: Vec<u16>) -> Model {
        let n = of_vertex.len();
        let mut mesh = SkinnedMesh::empty();
        for (i, &m) in of_vertex.iter().enumerate() {
            mesh.positions.push(glam::Vec3::new(i as f32, 0.0, 0.0));
            mesh.normals.push(glam::Vec3::Y);
            mesh.uvs.push(Vec2::new(0.3, 0.7));
            mesh.materials.push(m);
            mesh.influences.push(Influence {
                bone: 0,
                weight: 1.0,
            });
            mesh.influence_offsets.push(mesh.influences.len() as u32);
        }
        mesh.indices = (0..n as u32).collect();
        Model {
            name: "m".into(),
            mesh,
            skeleton: Skeleton {
                nodes: Vec::new(),
                joints: vec![0],
                inverse_bind: vec![glam::Mat4::IDENTITY],
                root_transform: glam::Affine3A::IDENTITY,
            },
            clips: Vec::new(),
            materials,
        }
    }

    /// The colour the palette shows at a vertex's texture coordinate, in sRGB.
    fn colour_at(m: &Model, v: usize) -> [u8; 3] {
        let t = m.materials[m.mesh.materials[v] as usize]
            .texture
            .as_ref()
            .unwrap();
        let uv = m.mesh.uvs[v];
        let (x, y) = (
            (uv.x * t.width as f32) as u32,
            (uv.y * t.height as f32) as u32,
        );
        let i = ((y * t.width + x) * 4) as usize;
        [t.pixels[i], t.pixels[i + 1], t.pixels[i + 2]]
    }

    #[test]
    fn plain_colours_share_one_texture_and_keep_their_colour() {
        let textured = Material::opaque(
            "cloth",
            [1.0; 4],
            Some(Rgba8Image {
                width: 1,
                height: 1,
                pixels: vec![9, 9, 9, 255],
            }),
        );
        let leaf = Material::cut_out("leaf", [0.2, 0.5, 0.1, 0.3], None);
        let mut materials = vec![textured, leaf];
        // 300 plain colours, every third one repeated.
        for k in 0..300 {
            let c = (k - k % 3) as f32 / 300.0;
            materials.push(Material::opaque(
                &format!("c{k}"),
                [c, 1.0 - c, 0.5, 1.0],
                None,
            ));
        }
        let of_vertex: Vec<u16> = (0..302u16).chain([0, 1]).collect();
        let mut m = model(materials.clone(), of_vertex);
        assert_eq!(pack_plain_colours(&mut m), 300);
        // The textured and the cut-out materials stay as they were, in order, and the palette
        // comes after them.
        assert_eq!(m.materials.len(), 3);
        assert_eq!(m.materials[0], materials[0]);
        assert_eq!(m.materials[1], materials[1]);
        assert_eq!(m.materials[2].name, PALETTE_MATERIAL);
        assert_eq!(m.mesh.uvs[0], Vec2::new(0.3, 0.7));
        assert_eq!(m.mesh.materials[302], 0);
        assert_eq!(m.mesh.materials[303], 1);
        let t = m.materials[2].texture.as_ref().unwrap();
        // 100 distinct colours in blocks of 8: 10 × 10 blocks in 128 texels.
        assert_eq!((t.width, t.height), (128, 128));
        // Vertex v was of material v (the plain ones from 2).
        for (v, material) in materials.iter().enumerate().take(302).skip(2) {
            assert_eq!(m.mesh.materials[v], 2);
            let c = material.base_color;
            let want = [c[0], c[1], c[2]].map(linear_to_srgb);
            assert_eq!(colour_at(&m, v), want, "vertex {v}");
        }
    }

    #[test]
    fn a_single_plain_colour_is_left_alone() {
        let materials = vec![Material::opaque("steel", [0.6; 4], None)];
        let mut m = model(materials.clone(), vec![0, 0, 0]);
        assert_eq!(pack_plain_colours(&mut m), 0);
        assert_eq!(m.materials, materials);
    }
}

//! The texture atlas of a billboard cloud: where each billboard's texture goes (packed with
//! etagere), what is drawn into it (the billboard's leaves projected orthographically onto its
//! rectangle, as triangles in atlas pixels for the GPU to rasterise), and the clean-up after
//! the render (colour dilated into transparent texels, so filtering never pulls in black).
//!
//! The Bennett-Therkildsen, Carlsen & Schmid's thesis "Animated Billboard Clouds for Foliage
//! Simplification" (2007), recommended an atlas but did not build one (§3.5); its textures came out
//! dark and blurred. Here every billboard gets `texels_per_unit` texels per scene unit, a gutter
//! round it, and its leaves drawn unlit with their own texture's alpha as the cut-out.

use super::cloud::Billboard;
use glam::{Vec2, Vec3};

/// Texels of gutter round every billboard's rectangle in the atlas.
pub const GUTTER: u32 = 2;
/// The atlas never grows beyond this on a side: the largest material layer the renderer keeps
/// ([`crate::bake::materials::MAX_LAYER_SIZE`]).
pub const MAX_ATLAS: u32 = crate::bake::materials::MAX_LAYER_SIZE;

/// Where every billboard's texture lies in the atlas.
#[derive(Clone, Debug, PartialEq)]
pub struct AtlasLayout {
    pub width: u32,
    pub height: u32,
    /// Texels per scene unit actually used (less than asked for where the atlas would not
    /// fit otherwise).
    pub texels_per_unit: f32,
    /// Per billboard, the texels its rectangle maps onto: x, y, width, height (without the
    /// gutter).
    pub rects: Vec<[u32; 4]>,
}

impl AtlasLayout {
    /// Texture coordinates of a billboard's four corners, in the order of
    /// [`Billboard::corners`].
    pub fn corner_uvs(&self, b: usize) -> [Vec2; 4] {
        let [x, y, w, h] = self.rects[b];
        let (aw, ah) = (self.width as f32, self.height as f32);
        let (x0, y0) = (x as f32 / aw, y as f32 / ah);
        let (x1, y1) = ((x + w) as f32 / aw, (y + h) as f32 / ah);
        [
            Vec2::new(x0, y1),
            Vec2::new(x1, y1),
            Vec2::new(x1, y0),
            Vec2::new(x0, y0),
        ]
    }
}

/// Packs the billboards' rectangles, at `texels_per_unit`, into the smallest power-of-two
/// atlas that holds them (width first); where even [`MAX_ATLAS`]² does not, at a lower
/// density that fits.
pub fn layout(billboards: &[Billboard], texels_per_unit: f32) -> Result<AtlasLayout, String> {
    let mut density = texels_per_unit;
    for _ in 0..60 {
        if let Some(l) = layout_at(billboards, density) {
            return Ok(l);
        }
        density *= 0.9;
    }
    Err(format!(
        "{} billboards do not fit a {MAX_ATLAS}x{MAX_ATLAS} atlas",
        billboards.len()
    ))
}

fn layout_at(billboards: &[Billboard], texels_per_unit: f32) -> Option<AtlasLayout> {
    let sizes: Vec<[u32; 2]> = billboards
        .iter()
        .map(|b| {
            let w = (b.corners[1] - b.corners[0]).length() * texels_per_unit;
            let h = (b.corners[3] - b.corners[0]).length() * texels_per_unit;
            [
                (w.ceil() as u32).clamp(1, MAX_ATLAS / 2),
                (h.ceil() as u32).clamp(1, MAX_ATLAS / 2),
            ]
        })
        .collect();
    let area: u64 = sizes
        .iter()
        .map(|s| ((s[0] + 2 * GUTTER) * (s[1] + 2 * GUTTER)) as u64)
        .sum();
    let mut side = 64u32;
    while (side as u64 * side as u64) < area && side < MAX_ATLAS {
        side *= 2;
    }
    let mut height = (side / 2).max(1);
    loop {
        if let Some(rects) = try_pack(&sizes, side, height) {
            return Some(AtlasLayout {
                width: side,
                height,
                texels_per_unit,
                rects,
            });
        }
        if height < side {
            height *= 2;
        } else if side < MAX_ATLAS {
            side *= 2;
            height = side / 2;
        } else {
            return None;
        }
    }
}

fn try_pack(sizes: &[[u32; 2]], width: u32, height: u32) -> Option<Vec<[u32; 4]>> {
    let mut alloc = etagere::AtlasAllocator::new(etagere::size2(width as i32, height as i32));
    // Largest first packs tighter; the result is put back in billboard order.
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(sizes[i][0] * sizes[i][1]));
    let mut rects = vec![[0u32; 4]; sizes.len()];
    for i in order {
        let [w, h] = sizes[i];
        let a = alloc.allocate(etagere::size2(
            (w + 2 * GUTTER) as i32,
            (h + 2 * GUTTER) as i32,
        ))?;
        let min = a.rectangle.min;
        rects[i] = [min.x as u32 + GUTTER, min.y as u32 + GUTTER, w, h];
    }
    Some(rects)
}

/// A vertex of a leaf triangle as drawn into the atlas.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct AtlasVertex {
    /// Atlas pixels (x right, y down).
    pub pixel: [f32; 2],
    /// Depth in 0..1: leaves on the billboard's front side (along its normal) win.
    pub depth: f32,
    /// The leaf texture coordinate.
    pub uv: [f32; 2],
}

/// Every drawn leaf of every billboard as triangles in atlas pixels. `triangles_of(leaf)`
/// gives the leaf's triangles as (position, uv) corners.
pub fn atlas_triangles(
    billboards: &[Billboard],
    layout: &AtlasLayout,
    epsilon: f32,
    triangles_of: impl Fn(u32) -> Vec<[(Vec3, Vec2); 3]>,
) -> Vec<AtlasVertex> {
    let mut out = Vec::new();
    for (b, bb) in billboards.iter().enumerate() {
        let [x, y, w, h] = layout.rects[b];
        let origin = bb.corners[0];
        let eu = bb.corners[1] - bb.corners[0];
        let ev = bb.corners[3] - bb.corners[0];
        let (lu, lv) = (eu.length().max(1e-9), ev.length().max(1e-9));
        let (eu, ev) = (eu / lu, ev / lv);
        for &leaf in &bb.drawn {
            for tri in triangles_of(leaf) {
                for (p, uv) in tri {
                    let q = p - origin;
                    // Corner 0 is at the bottom-left of the atlas rectangle (v grows up the
                    // billboard, y grows down the atlas).
                    let s = q.dot(eu) / lu;
                    let t = q.dot(ev) / lv;
                    let d = bb.plane.distance(p);
                    out.push(AtlasVertex {
                        pixel: [x as f32 + s * w as f32, y as f32 + (1.0 - t) * h as f32],
                        depth: (0.5 - 0.49 * d / epsilon.max(1e-6)).clamp(0.0, 1.0),
                        uv: uv.to_array(),
                    });
                }
            }
        }
    }
    out
}

/// Divides alpha out of sRGB colour that was blended over transparent black (in linear light).
pub fn unpremultiply(pixels: &mut [u8]) {
    use crate::model::{linear_to_srgb, srgb_to_linear};
    for p in pixels.chunks_exact_mut(4) {
        let a = p[3] as f32 / 255.0;
        if a > 0.0 && a < 1.0 {
            for c in &mut p[..3] {
                *c = linear_to_srgb(srgb_to_linear(*c) / a);
            }
        }
    }
}

/// What draws an atlas: the one GPU-made part of a billboard cloud, behind a narrow seam so
/// that the bake stays plain CPU code (`render::atlas` implements it; a test may rasterise on
/// the CPU).
pub trait RasterizeAtlas {
    /// `vertices` (triangles in atlas pixels, see [`atlas_triangles`]) textured by layer 0 of
    /// `leaf`, mipmapped, into a `layout`-sized image, straight (not premultiplied) alpha,
    /// transparent where no leaf is.
    fn rasterize(
        &self,
        layout: &AtlasLayout,
        vertices: &[AtlasVertex],
        leaf: &crate::bake::materials::MaterialLayers,
    ) -> anyhow::Result<crate::model::Rgba8Image>;

    /// The views of an octahedral impostor ([`super::impostor::view_request`]): every
    /// triangle drawn from every view into its cell, textured by its layer of `materials`,
    /// depth-tested, cut out where a cut-out layer's alpha is below one half; unlit colour
    /// and the normal facing the eye, see [`super::impostor::ViewImages`].
    fn rasterize_views(
        &self,
        request: &super::impostor::ViewRequest,
        materials: &crate::bake::materials::MaterialLayers,
    ) -> anyhow::Result<super::impostor::ViewImages>;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::billboard::cloud::{CloudParams, Leaf, stochastic_cloud};

    #[test]
    fn packed_rectangles_do_not_overlap_and_fit() {
        let mut rng = fastrand::Rng::with_seed(2);
        let leaves: Vec<Leaf> = (0..300)
            .map(|_| {
                let c = Vec3::new(rng.f32() * 10.0, rng.f32() * 10.0, rng.f32() * 10.0);
                let s = 0.1 + rng.f32() * 0.5;
                Leaf::new(vec![
                    c,
                    c + Vec3::X * s,
                    c + Vec3::new(s, s * 0.7, 0.2),
                    c + Vec3::new(0.0, s * 0.7, 0.2),
                ])
            })
            .collect();
        let cloud = stochastic_cloud(&leaves, &CloudParams::default());
        let l = layout(&cloud, 40.0).unwrap();
        assert_eq!(l.rects.len(), cloud.len());
        for (i, a) in l.rects.iter().enumerate() {
            assert!(a[0] + a[2] + GUTTER <= l.width && a[1] + a[3] + GUTTER <= l.height);
            assert!(a[0] >= GUTTER && a[1] >= GUTTER);
            for b in &l.rects[i + 1..] {
                // Gutters included, no two rectangles share a texel.
                let sep_x = a[0] + a[2] + GUTTER <= b[0] - GUTTER.min(b[0])
                    || b[0] + b[2] + GUTTER <= a[0] - GUTTER.min(a[0]);
                let sep_y = a[1] + a[3] + GUTTER <= b[1] - GUTTER.min(b[1])
                    || b[1] + b[3] + GUTTER <= a[1] - GUTTER.min(a[1]);
                assert!(sep_x || sep_y, "{a:?} overlaps {b:?}");
            }
        }
    }
}

//! The texture atlas of a billboard cloud: where each billboard's texture goes (packed with
//! etagere), what is drawn into it (the billboard's leaves projected orthographically onto its
//! rectangle, as triangles in atlas pixels for the GPU to rasterise), and the clean-up after
//! the render (colour dilated into transparent texels, so filtering never pulls in black).
//!
//! Besides the colour, every texel keeps how the leaf drawn there is lit: its normal in the
//! billboard's frame, and the crown's occlusion at it ([`super::occlusion`]) darkens its
//! colour. The thesis lit a
//! billboard by its plane, so that a coarse cloud showed one shade per billboard; lit per texel,
//! a billboard shades like the leaves it replaces under any sun. The lighting is a second
//! image, stored as the material after the atlas ([`BILLBOARD_LIGHTING`]).
//!
//! Bennett-Therkildsen, Carlsen & Schmid's thesis "Animated Billboard Clouds for Foliage
//! Simplification" (2007), recommended an atlas but did not build one (§3.5); its textures came out
//! dark and blurred. Here every billboard gets `texels_per_unit` texels per scene unit, a gutter
//! round it, and its leaves drawn unlit with their own texture's alpha as the cut-out.

use super::cloud::Billboard;
use crate::bake::gpu_data::materials::BILLBOARD_LIGHTING;
use crate::bake::gpu_products::{AtlasLayout, AtlasVertex};
use glam::{Vec2, Vec3};

/// Texels of gutter round every billboard's rectangle in the atlas, at the least.
pub const GUTTER: u32 = 2;
/// The widest gutter [`AtlasDensity::for_level`] gives.
pub const MAX_GUTTER: u32 = 4;

/// How sharp a cloud's atlas is drawn, and how far apart its billboards lie in it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtlasDensity {
    /// Texels per scene unit.
    pub texels_per_unit: f32,
    /// Texels of gutter round every billboard's rectangle.
    pub gutter: u32,
    /// Atlas texels a screen pixel holds where the level comes in (as asked: the layout may
    /// shrink the atlas to fit).
    pub texels_per_pixel: f32,
}

/// A bare density gets the least gutter.
impl From<f32> for AtlasDensity {
    fn from(texels_per_unit: f32) -> Self {
        AtlasDensity {
            texels_per_unit,
            gutter: GUTTER,
            texels_per_pixel: GUTTER as f32,
        }
    }
}

impl AtlasDensity {
    /// `texels_per_unit` for a level of error `epsilon` that comes in where `epsilon`
    /// projects to `tolerance_px` pixels, with a gutter as wide as the atlas has texels a
    /// screen pixel there (a power of two, [`GUTTER`] to [`MAX_GUTTER`]).
    ///
    /// Where a level comes in, the GPU reads its atlas at the mip level log₂ of the texels a
    /// pixel, whose texels each average 2^k of the full-size texels on a side; a narrower
    /// gutter lets those at a billboard's edge average in its neighbour's leaves. An atlas
    /// drawn at two texels a pixel there needs the least gutter; a sharper one, made for
    /// looking closer, a wider one.
    pub fn for_level(texels_per_unit: f32, epsilon: f32, tolerance_px: f32) -> Self {
        let per_pixel = texels_per_unit * epsilon / tolerance_px.max(1e-6);
        // GUTTER and MAX_GUTTER are powers of two: rounding up stays between them.
        // (A float cast saturates, NaN to 0, so the clamp holds for any input.)
        let gutter = (per_pixel.ceil() as u32)
            .clamp(GUTTER, MAX_GUTTER)
            .next_power_of_two();
        AtlasDensity {
            texels_per_unit,
            gutter,
            texels_per_pixel: per_pixel.max(0.0),
        }
    }
}
/// The atlas never grows beyond this on a side: the largest material layer the renderer keeps
/// ([`crate::bake::gpu_data::materials::MAX_LAYER_SIZE`]).
pub const MAX_ATLAS: u32 = crate::bake::gpu_data::materials::MAX_LAYER_SIZE;

/// The frame a billboard's texels keep their leaves' normals in: t, b across the billboard,
/// made from its normal `n` alone, so that the vertex shader rebuilds it from the skinned
/// normal (`vs_foliage_lit` in shaders/character.wgsl mirrors this): t = (ref × n) / |ref × n|
/// with ref the model's up (+x for billboards lying within about 8° of flat), b = n × t. A
/// billboard turned about the up axis turns its frame with it exactly; a branch's sway tilts
/// it a little, and the frame follows to within that tilt.
pub fn billboard_frame(n: Vec3) -> (Vec3, Vec3) {
    let reference = if n.y.abs() < 0.99 { Vec3::Y } else { Vec3::X };
    let t = reference.cross(n).normalize_or(Vec3::X);
    (t, n.cross(t))
}

/// Packs the billboards' rectangles, at `density`, into the smallest power-of-two atlas that
/// holds them (width first); where even [`MAX_ATLAS`]² does not, at a lower density that fits.
pub fn layout(
    billboards: &[Billboard],
    density: impl Into<AtlasDensity>,
) -> Result<AtlasLayout, String> {
    let density = density.into();
    let gutter = density.gutter;
    let mut density = density.texels_per_unit;
    for _ in 0..60 {
        if let Some(l) = layout_at(billboards, density, gutter) {
            return Ok(l);
        }
        density *= 0.9;
    }
    Err(format!(
        "{} billboards do not fit a {MAX_ATLAS}x{MAX_ATLAS} atlas",
        billboards.len()
    ))
}

fn layout_at(billboards: &[Billboard], texels_per_unit: f32, gutter: u32) -> Option<AtlasLayout> {
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
        .map(|s| ((s[0] + 2 * gutter) * (s[1] + 2 * gutter)) as u64)
        .sum();
    let mut side = 64u32;
    while (side as u64 * side as u64) < area && side < MAX_ATLAS {
        side *= 2;
    }
    let mut height = (side / 2).max(1);
    loop {
        if let Some(rects) = try_pack(&sizes, side, height, gutter) {
            return Some(AtlasLayout {
                width: side,
                height,
                texels_per_unit,
                rects,
                gutter,
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

fn try_pack(sizes: &[[u32; 2]], width: u32, height: u32, gutter: u32) -> Option<Vec<[u32; 4]>> {
    let mut alloc = etagere::AtlasAllocator::new(etagere::size2(width as i32, height as i32));
    // Largest first packs tighter; the result is put back in billboard order.
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(sizes[i][0] * sizes[i][1]));
    let mut rects = vec![[0u32; 4]; sizes.len()];
    for i in order {
        let [w, h] = sizes[i];
        let a = alloc.allocate(etagere::size2(
            (w + 2 * gutter) as i32,
            (h + 2 * gutter) as i32,
        ))?;
        let min = a.rectangle.min;
        rects[i] = [min.x as u32 + gutter, min.y as u32 + gutter, w, h];
    }
    Some(rects)
}

/// One corner of a leaf triangle as the atlas draws it: where it is, its leaf-texture
/// coordinate, its normal, the crown's occlusion there and its material (its index among
/// the tree's materials, a layer of the atlas's leaf texture).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeafCorner {
    pub position: Vec3,
    pub uv: Vec2,
    pub normal: Vec3,
    pub occlusion: f32,
    pub layer: u32,
}

/// Which face of a leaf triangle a billboard of normal `n` shows (+1 its front, by the
/// triangle's winding, as the renderer finds it, not by its vertex normals, which a model may
/// point anywhere; −1 its back), and twice its area.
fn facing(tri: &[LeafCorner; 3], n: Vec3) -> (f32, f32) {
    let geometric = (tri[1].position - tri[0].position).cross(tri[2].position - tri[0].position);
    let turn = if geometric.dot(n) < 0.0 { -1.0 } else { 1.0 };
    (turn, geometric.length())
}

/// The normal billboard `bb` is lit by where it is lit as one (`--billboard-lighting flat`),
/// and whose frame its atlas keeps its texels' normals in: the mean of the normals its leaves'
/// triangles `tris` are lit by, each seen from the billboard's front (see [`facing`]),
/// weighted by area. A clump's planes (those with a view window) keep their plane's normal,
/// which their window is measured about.
///
/// The thesis lit a billboard by its plane. A leaf card is lit by its own vertex normals,
/// which artists often bend out from the crown's centre so that the crown shades like one
/// soft mass, or wind cards one way and point their normals the other: lit by their planes,
/// the clouds of such trees came out darker and flatter than the tree. The normal may point
/// behind the billboard's plane: the renderer lights a billboard's front face by it and its
/// back face by its negation, as it lights the leaves. Where the leaves' normals cancel out,
/// the plane's normal is kept.
fn shading_normal<'a>(bb: &Billboard, tris: impl Iterator<Item = &'a [LeafCorner; 3]>) -> Vec3 {
    let n = bb.plane.normal;
    if bb.view_window != 0.0 {
        return n;
    }
    let mut sum = Vec3::ZERO;
    for tri in tris {
        let (turn, area) = facing(tri, n);
        for c in tri {
            sum += c.normal.normalize_or_zero() * (turn * area);
        }
    }
    sum.normalize_or(n)
}

/// What the atlas draws: every drawn leaf of every billboard as triangles in atlas pixels,
/// and the normal each billboard is lit by (see [`shading_normal`]).
pub struct AtlasTriangles {
    pub vertices: Vec<AtlasVertex>,
    pub normals: Vec<Vec3>,
}

/// Every drawn leaf of every billboard as triangles in atlas pixels, each texel's normal in
/// the frame of its billboard's shading normal. `triangles_of(leaf)` gives the leaf's
/// triangles.
pub fn atlas_triangles(
    billboards: &[Billboard],
    layout: &AtlasLayout,
    epsilon: f32,
    triangles_of: impl Fn(u32) -> Vec<[LeafCorner; 3]>,
) -> AtlasTriangles {
    let mut out = Vec::new();
    let mut normals = Vec::with_capacity(billboards.len());
    for (b, bb) in billboards.iter().enumerate() {
        let [x, y, w, h] = layout.rects[b];
        let origin = bb.corners[0];
        let eu = bb.corners[1] - bb.corners[0];
        let ev = bb.corners[3] - bb.corners[0];
        let (lu, lv) = (eu.length().max(1e-9), ev.length().max(1e-9));
        let (eu, ev) = (eu / lu, ev / lv);
        let n = bb.plane.normal;
        // Back to front, as the billboard's front sees its leaves: the atlas blends each over
        // what is there, so the leaf nearest the front is drawn last and shows (a clump's
        // planes each hold all its leaves, one over another; drawn in the model's order, the
        // last material's leaves, a bush's flowers, covered the rest from every side).
        let mut tris: Vec<(f32, [LeafCorner; 3])> = bb
            .drawn
            .iter()
            .flat_map(|&leaf| triangles_of(leaf))
            .map(|tri| {
                let d = tri
                    .iter()
                    .map(|c| bb.plane.distance(c.position))
                    .sum::<f32>()
                    / 3.0;
                (d, tri)
            })
            .collect();
        tris.sort_by(|a, b| a.0.total_cmp(&b.0));
        let shading = shading_normal(bb, tris.iter().map(|(_, t)| t));
        normals.push(shading);
        let (ft, fb) = billboard_frame(shading);
        for (_, tri) in tris {
            // Foliage is two-sided, each face lit by the normal on its side: the billboard's
            // front shows the leaf's face turned towards it, and its back the other face, by
            // the negated normal.
            let (turn, _) = facing(&tri, n);
            for c in tri {
                let (p, uv) = (c.position, c.uv);
                let m = (c.normal * turn).normalize_or(n);
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
                    normal: [m.dot(ft), m.dot(fb), m.dot(shading)],
                    light: 1.0 - c.occlusion.clamp(0.0, 1.0),
                    layer: c.layer,
                });
            }
        }
    }
    AtlasTriangles {
        vertices: out,
        normals,
    }
}

/// The lighting image as the material after the atlas stores it: sRGB-encoded (the renderer
/// reads material layers as sRGB, and so gets the linear values back), opaque.
pub fn lighting_material(mut lighting: crate::model::Rgba8Image) -> crate::model::Material {
    use crate::model::linear_to_srgb;
    for p in lighting.pixels.chunks_exact_mut(4) {
        for c in &mut p[..3] {
            *c = linear_to_srgb(*c as f32 / 255.0);
        }
        p[3] = 255;
    }
    crate::model::Material::opaque(BILLBOARD_LIGHTING, [1.0; 4], Some(lighting))
        .with_role(crate::model::MaterialRole::BillboardLighting)
}

/// Divides alpha out of linear bytes that were blended over transparent black.
pub fn unpremultiply_linear(pixels: &mut [u8]) {
    for p in pixels.chunks_exact_mut(4) {
        let a = p[3] as f32 / 255.0;
        if a > 0.0 && a < 1.0 {
            for c in &mut p[..3] {
                *c = (*c as f32 / a).round().min(255.0) as u8;
            }
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::foliage::billboard::cloud::{CloudParams, Leaf, stochastic_cloud};
    use crate::bake::gpu_data::materials::{BILLBOARD_MATERIAL, lit_atlas_material};

    #[test]
    fn the_billboard_frame_is_orthonormal_and_turns_with_the_tree() {
        let mut rng = fastrand::Rng::with_seed(9);
        for _ in 0..200 {
            let n = Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5).normalize();
            let (t, b) = billboard_frame(n);
            assert!((t.length() - 1.0).abs() < 1e-4 && (b.length() - 1.0).abs() < 1e-4);
            assert!(t.dot(n).abs() < 1e-4 && b.dot(n).abs() < 1e-4 && t.dot(b).abs() < 1e-4);
            // Right-handed: t × b = n.
            assert!(t.cross(b).distance(n) < 1e-4);
            // A tree turned about its up axis turns every billboard's frame with it, so the
            // shader's frame of the turned normal is the turned frame.
            let r = glam::Quat::from_rotation_y(rng.f32() * std::f32::consts::TAU);
            let (t2, b2) = billboard_frame(r * n);
            assert!(
                t2.distance(r * t) < 1e-3 && b2.distance(r * b) < 1e-3,
                "{n}"
            );
        }
    }

    #[test]
    fn the_atlas_keeps_each_leaf_normal_in_the_billboard_frame_facing_its_front() {
        let (billboard, layout) = unit_billboard();
        // Leaf 0 tilted 30° about x, towards +y, wound to face the billboard's front; leaf 1
        // wound the other way (the billboard's front sees its back face) with the same vertex
        // normal, in the crown's heart.
        let tilted = Vec3::new(0.0, 0.5, 0.75f32.sqrt());
        let corner = |position, normal, occlusion| LeafCorner {
            position,
            uv: Vec2::ZERO,
            normal,
            occlusion,
            layer: 0,
        };
        let vertices = atlas_triangles(&[billboard], &layout, 0.1, |leaf| {
            let o = if leaf == 0 { 0.0 } else { 0.5 };
            let a = corner(Vec3::new(0.2, 0.2, 0.0), tilted, o);
            let b = corner(Vec3::new(0.8, 0.2, 0.0), tilted, o);
            let c = corner(Vec3::new(0.5, 0.8, 0.0), tilted, o);
            vec![if leaf == 0 { [a, b, c] } else { [b, a, c] }]
        })
        .vertices;
        assert_eq!(vertices.len(), 6);
        let (t, b) = billboard_frame(Vec3::Z);
        for (i, v) in vertices.iter().enumerate() {
            // Leaf 1's face towards the front is its back: lit by the negated normal.
            let m = if i < 3 { tilted } else { -tilted };
            let expected = [m.dot(t), m.dot(b), m.z];
            assert!(
                (0..3).all(|k| (v.normal[k] - expected[k]).abs() < 1e-5),
                "{:?} against {expected:?}",
                v.normal
            );
            assert_eq!(v.light, if i < 3 { 1.0 } else { 0.5 });
        }
        // A corner at (0.5, 0.8) of a billboard 32 texels across at texel (2, 2).
        assert_eq!(vertices[2].pixel, [2.0 + 16.0, 2.0 + 0.2 * 32.0]);
    }

    /// A unit billboard on the z = 0 plane facing +z, drawing leaves 0 and 1, and its place
    /// in a 64² atlas.
    fn unit_billboard() -> (Billboard, AtlasLayout) {
        let billboard = Billboard {
            plane: crate::bake::foliage::billboard::cloud::Plane {
                normal: Vec3::Z,
                offset: 0.0,
            },
            corners: [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            leaves: vec![0, 1],
            drawn: vec![0, 1],
            view_window: 0.0,
        };
        let layout = AtlasLayout {
            width: 64,
            height: 64,
            texels_per_unit: 32.0,
            rects: vec![[2, 2, 32, 32]],
            gutter: GUTTER,
        };
        (billboard, layout)
    }

    fn leaf(z: f32, normal: Vec3, layer: u32) -> Vec<[LeafCorner; 3]> {
        let c = |x: f32, y: f32| LeafCorner {
            position: Vec3::new(x, y, z),
            uv: Vec2::ZERO,
            normal,
            occlusion: 0.0,
            layer,
        };
        vec![[c(0.2, 0.2), c(0.8, 0.2), c(0.5, 0.8)]]
    }

    #[test]
    fn the_leaf_nearest_the_billboards_front_is_drawn_last_whatever_its_material() {
        let (billboard, layout) = unit_billboard();
        let vertices = atlas_triangles(&[billboard], &layout, 0.1, |l| {
            if l == 0 {
                leaf(0.05, Vec3::Z, 1)
            } else {
                leaf(-0.05, Vec3::Z, 0)
            }
        })
        .vertices;
        // Leaf 1, behind, first; leaf 0, in front (a flower over the leaves), last.
        assert_eq!(
            vertices.iter().map(|v| v.layer).collect::<Vec<_>>(),
            [0, 0, 0, 1, 1, 1]
        );
    }

    #[test]
    fn a_billboard_is_lit_by_its_leaves_normals_even_where_they_point_behind_it() {
        let (billboard, _) = unit_billboard();
        // Bent normals, tilted 60° off the plane towards +y: the mean is theirs.
        let bent = Vec3::new(0.0, 0.75f32.sqrt(), 0.5);
        let n = shading_normal(&billboard, leaf(0.0, bent, 0).iter());
        assert!(n.distance(bent) < 1e-5, "{n}");
        // Cards wound towards the billboard's front with normals pointing the other way (as
        // exported): lit as the renderer lights them, by those normals.
        let n = shading_normal(&billboard, leaf(0.0, -Vec3::Z, 0).iter());
        assert!(n.distance(-Vec3::Z) < 1e-5, "{n}");
        // Leaves whose normals cancel out: the plane's.
        let both = [leaf(0.0, Vec3::X, 0), leaf(0.0, -Vec3::X, 0)].concat();
        assert_eq!(shading_normal(&billboard, both.iter()), Vec3::Z);
        // A clump's plane keeps its own (its view window is measured about it).
        let clump = Billboard {
            view_window: 0.4,
            ..billboard
        };
        assert_eq!(shading_normal(&clump, leaf(0.0, bent, 0).iter()), Vec3::Z);
    }

    #[test]
    fn the_lighting_is_stored_so_that_the_renderer_reads_it_back() {
        use crate::model::srgb_to_linear;
        let lighting = crate::model::Rgba8Image {
            width: 2,
            height: 1,
            pixels: vec![128, 200, 77, 255, 0, 255, 255, 0],
        };
        let m = lighting_material(lighting);
        assert_eq!(m.name, BILLBOARD_LIGHTING);
        assert!(!m.cuts_out());
        let t = m.texture.clone().unwrap();
        // The sRGB material texture decodes each byte back to what was written, to within
        // the sRGB code's step.
        let written = [128u8, 200, 77, 0, 255, 255];
        let stored = [0, 1, 2, 4, 5, 6].map(|i| t.pixels[i]);
        for (s, w) in stored.into_iter().zip(written) {
            let back = srgb_to_linear(s);
            assert!((back - w as f32 / 255.0).abs() < 0.01, "{s} for {w}");
        }
        // Opaque: the colour layer's alpha cuts the billboard out, not this one's.
        assert_eq!([t.pixels[3], t.pixels[7]], [255, 255]);
        let atlas = crate::model::Material::cut_out(BILLBOARD_MATERIAL, [1.0; 4], None);
        let mut materials = vec![
            crate::model::Material::opaque("bark", [1.0; 4], None),
            atlas
                .clone()
                .with_role(crate::model::MaterialRole::BillboardAtlas),
            m.clone(),
        ];
        assert_eq!(lit_atlas_material(&materials), Some(1));
        assert_eq!(lit_atlas_material(&materials[..2]), None);
        // A file's materials that merely carry the names are surfaces.
        materials[1] = atlas;
        materials[2] = crate::model::Material {
            role: Default::default(),
            ..m
        };
        assert_eq!(lit_atlas_material(&materials), None);
    }

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
        for gutter in [GUTTER, 8] {
            let density = AtlasDensity {
                texels_per_unit: 40.0,
                gutter,
                texels_per_pixel: 2.0,
            };
            let l = layout(&cloud, density).unwrap();
            assert_eq!(l.rects.len(), cloud.len());
            assert_eq!(l.gutter, gutter);
            let g = gutter;
            for (i, a) in l.rects.iter().enumerate() {
                assert!(a[0] + a[2] + g <= l.width && a[1] + a[3] + g <= l.height);
                assert!(a[0] >= g && a[1] >= g);
                for b in &l.rects[i + 1..] {
                    // Gutters included, no two rectangles share a texel.
                    let sep_x = a[0] + a[2] + g <= b[0] - g.min(b[0])
                        || b[0] + b[2] + g <= a[0] - g.min(a[0]);
                    let sep_y = a[1] + a[3] + g <= b[1] - g.min(b[1])
                        || b[1] + b[3] + g <= a[1] - g.min(a[1]);
                    assert!(sep_x || sep_y, "{a:?} overlaps {b:?}");
                }
            }
        }
    }

    #[test]
    fn the_gutter_is_as_wide_as_the_texels_a_pixel_where_the_level_comes_in() {
        // ε 0.1 m at a 1.5 px tolerance: 1.5 px is 0.1 m there.
        let g = |texels_per_unit: f32| AtlasDensity::for_level(texels_per_unit, 0.1, 1.5).gutter;
        assert_eq!(g(30.0), GUTTER); // two texels a pixel: the chain's own rule
        assert_eq!(g(5.0), GUTTER); // blurrier still: never narrower
        assert_eq!(g(51.0), 4); // 3.4 texels a pixel
        assert_eq!(g(102.0), MAX_GUTTER); // 6.8: as wide as it goes
        assert_eq!(g(5000.0), MAX_GUTTER);
        assert_eq!(
            AtlasDensity::for_level(51.0, 0.1, 1.5).texels_per_unit,
            51.0
        );
    }
}

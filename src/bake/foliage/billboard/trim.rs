//! Cards trimmed to their leaves: each billboard drawn as a convex polygon of at most
//! [`MAX_CORNERS`] corners round the atlas texels its leaves cover, instead of its whole
//! rectangle.
//!
//! A billboard's rectangle bounds its leaves' projections; most of it is transparent, and
//! every transparent pixel is still rasterised, shaded and discarded. Emil Persson's particle
//! trimmer (and Unreal's SubUV cutout, Unity's tight sprite mesh) draws the tightest convex
//! polygon of a few corners round the texels above the cutoff instead; the gain is about the
//! share of the area trimmed ("Particle Trimming", Intel, 2013). Here:
//!
//! 1. the convex hull of the billboard's covered texels, each taken as its square grown by
//!    `margin` texels (as far as the mip level read where the level comes in spreads a
//!    leaf's alpha: the texels a screen pixel holds there, see
//!    [`super::atlas::AtlasDensity::for_level`]), clipped to the rectangle;
//! 2. reduced to [`MAX_CORNERS`] corners the way Persson's trimmer does: the edge whose two
//!    neighbours, extended until they meet, add the least area goes, until few enough are
//!    left (the polygon only grows, so it still covers every texel);
//! 3. kept only where it pays: it must save [`MIN_SAVED_SHARE`] of the rectangle and, where the
//!    level comes in, [`PIXELS_PER_EXTRA_CORNER`] screen pixels for each corner beyond four (a
//!    small card stays a quad: its extra vertices would cost more than its pixels).
//!
//! What it saves depends on the tree. A billboard of the built-in trees holds dozens of small
//! leaves spread over its whole rectangle: 20–40% of its texels are covered, but the gaps are
//! between the leaves, not round them, and the hull is nearly the rectangle (the broadleaf's
//! finest cloud is drawn with 89% of its area, its coarser ones whole). An artist's card tree
//! has billboards of one or a few cards at an angle: the bush's finest clouds are drawn with
//! 61–78% of their area.

use super::rect::convex_hull;
use glam::Vec2;

/// The most corners a trimmed billboard gets (Persson and three.js's diet-sprite find 4–8
/// enough).
pub const MAX_CORNERS: usize = 8;
/// The least share of its rectangle a trimmed outline must cut.
pub const MIN_SAVED_SHARE: f32 = 0.15;
/// Screen pixels (where the level comes in) an outline must save for each corner it adds.
/// Each corner beyond four adds a vertex and a triangle, which on lavapipe cost about what 9
/// fragments do (the cost order's `TRIANGLE_FRAGMENTS`), and a level is drawn from where it
/// comes in to about twice as far (ε doubles level by level), where its pixels are a
/// quarter: a pixel saved where it comes in is about half a pixel saved over its range. So
/// four times 9.
pub const PIXELS_PER_EXTRA_CORNER: f32 = 36.0;

/// A billboard's outline in its rectangle's own coordinates: s along its first side (corner
/// 0 to 1), t along its second (corner 0 to 3), both 0..1, counter-clockwise as its corners
/// are. The rectangle itself is `[(0,0), (1,0), (1,1), (0,1)]`.
pub type Outline = Vec<Vec2>;

/// The untrimmed outline: the whole rectangle.
pub fn whole() -> Outline {
    vec![
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
    ]
}

/// The outline to draw the billboard at atlas rectangle `rect` (x, y, width, height in
/// texels, y down; its corner 0 at the bottom left as [`crate::bake::gpu_products::AtlasLayout::corner_uvs`] maps it) of the RGBA
/// `atlas` `width` texels wide: trimmed round its texels of non-zero alpha grown by `margin`
/// texels, or the whole rectangle where trimming does not pay with `texels_per_pixel` atlas
/// texels to a screen pixel where the level comes in (or where nothing is covered).
pub fn outline(
    atlas: &[u8],
    width: u32,
    rect: [u32; 4],
    margin: f32,
    texels_per_pixel: f32,
) -> Outline {
    let [x0, y0, w, h] = rect;
    if w == 0 || h == 0 {
        return whole();
    }
    // Covered texels, row by row: the first and last in each row are all the hull needs.
    // Points in texels, u right, v up from the rectangle's bottom edge.
    let mut points: Vec<Vec2> = Vec::new();
    for row in 0..h {
        let y = y0 + row;
        let at = |x: u32| 4 * (y as usize * width as usize + x as usize) + 3;
        let covered = |x: &u32| atlas.get(at(*x)).is_some_and(|&a| a > 0);
        let (Some(first), Some(last)) =
            ((x0..x0 + w).find(covered), (x0..x0 + w).rev().find(covered))
        else {
            continue;
        };
        let (u0, u1) = (
            (first - x0) as f32 - margin,
            (last - x0 + 1) as f32 + margin,
        );
        let (v0, v1) = ((h - row - 1) as f32 - margin, (h - row) as f32 + margin);
        points.extend([
            Vec2::new(u0, v0),
            Vec2::new(u0, v1),
            Vec2::new(u1, v0),
            Vec2::new(u1, v1),
        ]);
    }
    if points.is_empty() {
        return whole();
    }
    let size = Vec2::new(w as f32, h as f32);
    // Growing corners out to where neighbouring edges meet can push them past the
    // rectangle, and clipping them back adds corners: reduce and clip again, a few times.
    let mut poly = clip_to_box(&convex_hull(&points), size);
    for _ in 0..4 {
        if poly.len() <= MAX_CORNERS {
            break;
        }
        poly = clip_to_box(&reduce(poly, MAX_CORNERS), size);
    }
    if poly.len() < 3 || poly.len() > MAX_CORNERS {
        return whole();
    }
    let rect_area = size.x * size.y;
    let saved = rect_area - area(&poly);
    let extra = poly.len().saturating_sub(4) as f32;
    let saved_pixels = saved / (texels_per_pixel * texels_per_pixel).max(1e-6);
    if saved < MIN_SAVED_SHARE * rect_area || saved_pixels < PIXELS_PER_EXTRA_CORNER * extra {
        return whole();
    }
    poly.into_iter().map(|p| p / size).collect()
}

/// The share of the rectangle an outline covers.
pub fn share(outline: &[Vec2]) -> f32 {
    area(outline)
}

/// Twice the signed area over two: the area of a counter-clockwise polygon.
fn area(poly: &[Vec2]) -> f32 {
    let n = poly.len();
    (0..n)
        .map(|i| poly[i].perp_dot(poly[(i + 1) % n]))
        .sum::<f32>()
        * 0.5
}

/// A convex counter-clockwise polygon clipped to the box [0, size] (Sutherland–Hodgman).
fn clip_to_box(poly: &[Vec2], size: Vec2) -> Vec<Vec2> {
    // Each edge of the box as (axis, bound, keep below).
    let edges = [
        (0, 0.0, false),
        (0, size.x, true),
        (1, 0.0, false),
        (1, size.y, true),
    ];
    let mut out: Vec<Vec2> = poly.to_vec();
    for (axis, bound, below) in edges {
        if out.is_empty() {
            break;
        }
        let inside = |p: Vec2| {
            if below {
                p[axis] <= bound
            } else {
                p[axis] >= bound
            }
        };
        let input = std::mem::take(&mut out);
        for i in 0..input.len() {
            let (a, b) = (input[i], input[(i + 1) % input.len()]);
            let (ia, ib) = (inside(a), inside(b));
            if ia {
                out.push(a);
            }
            if ia != ib {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                let mut p = a + (b - a) * t;
                p[axis] = bound;
                out.push(p);
            }
        }
    }
    out.dedup_by(|a, b| a.distance_squared(*b) < 1e-10);
    if out.len() > 1 && out[0].distance_squared(out[out.len() - 1]) < 1e-10 {
        out.pop();
    }
    out
}

/// A convex polygon grown to at most `corners` corners, containing it: Persson's trimmer
/// removes, one at a time, the edge whose neighbours extended to their meeting point add the
/// least area (edges whose neighbours do not meet beyond it cannot go).
fn reduce(mut poly: Vec<Vec2>, corners: usize) -> Vec<Vec2> {
    while poly.len() > corners {
        let n = poly.len();
        let mut best: Option<(f32, usize, Vec2)> = None;
        for i in 0..n {
            // Edge i runs from poly[i] to poly[i + 1]; its neighbours end at poly[i] and
            // start at poly[i + 1].
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let before = a - poly[(i + n - 1) % n];
            let after = poly[(i + 2) % n] - b;
            let denom = before.perp_dot(after);
            // The neighbours must turn towards each other by less than half a turn.
            if denom <= 1e-9 {
                continue;
            }
            let s = (b - a).perp_dot(after) / denom;
            if s < 0.0 {
                continue;
            }
            let meet = a + before * s;
            let added = 0.5 * (b - a).perp_dot(meet - a).abs();
            if best.is_none_or(|(area, _, _)| added < area) {
                best = Some((added, i, meet));
            }
        }
        let Some((_, i, meet)) = best else {
            break;
        };
        let n = poly.len();
        let j = (i + 1) % n;
        poly[i] = meet;
        poly.remove(j);
    }
    poly
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An RGBA atlas `w` × `h` covered where `covered(x, y)`.
    fn atlas(w: u32, h: u32, covered: impl Fn(u32, u32) -> bool) -> Vec<u8> {
        let mut px = vec![0u8; (4 * w * h) as usize];
        for y in 0..h {
            for x in 0..w {
                if covered(x, y) {
                    px[(4 * (y * w + x) + 3) as usize] = 255;
                }
            }
        }
        px
    }

    /// Is `p` inside (or on) the counter-clockwise convex polygon?
    fn inside(poly: &[Vec2], p: Vec2) -> bool {
        let n = poly.len();
        (0..n).all(|i| (poly[(i + 1) % n] - poly[i]).perp_dot(p - poly[i]) >= -1e-4)
    }

    #[test]
    fn a_disc_is_trimmed_to_a_few_corners_that_cover_every_texel() {
        // A disc of radius 20 in a 64 × 64 rectangle, inside a larger atlas at (8, 4).
        let (w, h) = (80, 72);
        let disc = |x: u32, y: u32| {
            let (dx, dy) = (x as f32 - 40.0 + 0.5, y as f32 - 36.0 + 0.5);
            dx * dx + dy * dy <= 400.0
        };
        let px = atlas(w, h, disc);
        let rect = [8, 4, 64, 64];
        let o = outline(&px, w, rect, 1.0, 2.0);
        assert!((4..=MAX_CORNERS).contains(&o.len()), "{} corners", o.len());
        assert!(area(&o) > 0.0, "counter-clockwise");
        // Every covered texel's centre (in s, t) lies inside.
        for y in 4..68 {
            for x in 8..72 {
                if disc(x, y) {
                    let s = (x - 8) as f32 + 0.5;
                    let t = (68 - y) as f32 - 0.5;
                    assert!(inside(&o, Vec2::new(s, t) / 64.0), "texel {x},{y} left out");
                }
            }
        }
        // The disc is π/4 of its square (and a third of the rectangle): an octagon round it
        // keeps well under the whole.
        let share = share(&o);
        assert!(share < 0.5, "share {share}");
        assert!(share > 0.3, "share {share}");
        for p in &o {
            assert!((0.0..=1.0).contains(&p.x) && (0.0..=1.0).contains(&p.y));
        }
    }

    #[test]
    fn a_card_full_to_its_edges_or_small_on_screen_stays_a_quad() {
        let (w, h) = (32, 32);
        let full = atlas(w, h, |_, _| true);
        assert_eq!(outline(&full, w, [0, 0, 32, 32], 1.0, 2.0), whole());
        // A corner triangle of 4 texels a side: little to save.
        let tiny = atlas(w, h, |x, y| x + y < 4);
        let o = outline(&tiny, w, [0, 0, 6, 6], 0.0, 8.0);
        assert_eq!(
            o,
            whole(),
            "at 8 texels a pixel the card is a pixel or two wide"
        );
        // Nothing covered at all.
        let empty = atlas(w, h, |_, _| false);
        assert_eq!(outline(&empty, w, [0, 0, 32, 32], 1.0, 1.0), whole());
    }

    #[test]
    fn a_diagonal_strip_keeps_its_corners_in_the_rectangles_frame() {
        // Covered along the diagonal from the rectangle's bottom left to its top right (atlas
        // y down): the outline is a band along s = t.
        let n = 48u32;
        let px = atlas(n, n, |x, y| (x as i32 - (n - 1 - y) as i32).abs() <= 2);
        let o = outline(&px, n, [0, 0, n, n], 0.0, 1.0);
        assert!(o.len() <= MAX_CORNERS);
        assert!(share(&o) < 0.35, "share {}", share(&o));
        assert!(inside(&o, Vec2::new(0.5, 0.5)));
        assert!(!inside(&o, Vec2::new(0.9, 0.1)));
        assert!(!inside(&o, Vec2::new(0.1, 0.9)));
    }

    #[test]
    fn reducing_a_polygon_only_grows_it() {
        let circle: Vec<Vec2> = (0..32)
            .map(|k| {
                let a = std::f32::consts::TAU * k as f32 / 32.0;
                Vec2::new(a.cos(), a.sin())
            })
            .collect();
        let r = reduce(circle.clone(), 6);
        assert_eq!(r.len(), 6);
        for p in &circle {
            assert!(inside(&r, *p));
        }
        assert!(area(&r) < 1.3 * area(&circle));
    }
}

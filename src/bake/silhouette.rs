//! How far a level's silhouette strays from full detail's, in pixels, where the renderer
//! switches to it: the check that a level's error is what it claims.
//!
//! The renderer shows level k from the distance where its error projects to the tolerance τ
//! pixels: there one metre covers `τ / e_k` pixels (`LodScreen::projected`), whatever the
//! viewport and field of view. So the level and full detail are drawn at that scale, from a
//! few directions and in a few poses, as coverage masks (a conservative rasteriser on the CPU,
//! which covers every pixel a triangle touches, so thin parts never alias away; orthographic:
//! at a switching distance the character spans a small angle), and compared by the symmetric
//! Hausdorff distance between the masks:
//! the furthest any covered pixel of one lies from a covered pixel of the other. A level
//! within its error stays within τ, up to a pixel of rasterisation.
//!
//! The distance transform is Felzenszwalb & Huttenlocher's, "Distance transforms of sampled
//! functions" (2012): exact squared Euclidean distances in two separable passes.

use super::animation_space::AnimationSpaceMesh;
use glam::{Affine3A, Quat, Vec2, Vec3};

/// A direction to look from: yaw about the vertical (0 looks along −z, at the front of a
/// character facing +z) and pitch above the horizon, in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub yaw: f32,
    pub pitch: f32,
}

/// Front, side, back three-quarter and from above: where silhouettes of a character differ.
pub const VIEWS: [View; 4] = [
    View {
        yaw: 0.0,
        pitch: 10.0,
    },
    View {
        yaw: 90.0,
        pitch: 10.0,
    },
    View {
        yaw: 210.0,
        pitch: 25.0,
    },
    View {
        yaw: -40.0,
        pitch: 60.0,
    },
];

/// What a report draws masks at most: a level so fine that full detail would span more
/// pixels at its switching distance is drawn at this size and its distance scaled up, which
/// can only overstate it.
pub const MAX_SIDE: u32 = 2048;

/// A coverage mask.
#[derive(Clone, Debug, PartialEq)]
pub struct Mask {
    pub width: u32,
    pub height: u32,
    pub covered: Vec<bool>,
}

impl Mask {
    pub fn count(&self) -> usize {
        self.covered.iter().filter(|&&c| c).count()
    }
}

/// Where a view puts points: screen x right, y down, in pixels.
#[derive(Clone, Copy, Debug)]
struct Projection {
    rotation: Quat,
    scale: f32,
    origin: Vec2,
}

impl Projection {
    fn new(view: View, scale: f32) -> Projection {
        // The camera's frame: turn the world so the camera looks along −z.
        let rotation = Quat::from_rotation_x(view.pitch.to_radians())
            * Quat::from_rotation_y(-view.yaw.to_radians());
        Projection {
            rotation,
            scale,
            origin: Vec2::ZERO,
        }
    }

    fn apply(&self, p: Vec3) -> Vec2 {
        let q = self.rotation * p;
        Vec2::new(q.x, -q.y) * self.scale - self.origin
    }
}

/// The mesh posed by bone matrices `g`, drawn by `projection` into a mask of `size`.
fn rasterise(
    mesh: &AnimationSpaceMesh,
    g: &[Affine3A],
    projection: &Projection,
    size: (u32, u32),
) -> Mask {
    let (positions, _) = mesh.evaluate(g);
    let screen: Vec<Vec2> = positions.iter().map(|&p| projection.apply(p)).collect();
    let (w, h) = size;
    let mut covered = vec![false; (w * h) as usize];
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| screen[i as usize]);
        let area = (b - a).perp_dot(c - a);
        if area == 0.0 || !area.is_finite() {
            continue;
        }
        // Conservative: every pixel the triangle touches, so that a part thinner than a pixel
        // (a ring seen edge-on, a sliver) still shows, in both masks alike.
        let lo = a.min(b).min(c);
        let hi = a.max(b).max(c);
        let x0 = lo.x.floor().max(0.0) as u32;
        let y0 = lo.y.floor().max(0.0) as u32;
        let x1 = (hi.x.floor() as i64).min(w as i64 - 1);
        let y1 = (hi.y.floor() as i64).min(h as i64 - 1);
        if x1 < x0 as i64 || y1 < y0 as i64 {
            continue;
        }
        // Both windings count: a silhouette has no back faces. An edge function reaches a
        // pixel's square when it is above minus half its extent along the edge's normal.
        let sign = area.signum();
        let edges = [(a, b), (b, c), (c, a)].map(|(p, q)| {
            let d = q - p;
            (p, d, 0.5 * (d.x.abs() + d.y.abs()))
        });
        for y in y0..=y1 as u32 {
            for x in x0..=x1 as u32 {
                let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                if edges
                    .iter()
                    .all(|&(o, d, slack)| d.perp_dot(p - o) * sign >= -slack)
                {
                    covered[(y * w + x) as usize] = true;
                }
            }
        }
    }
    Mask {
        width: w,
        height: h,
        covered,
    }
}

/// Squared Euclidean distance from every pixel to the nearest covered pixel of `mask`
/// (infinite everywhere if nothing is covered).
fn distance2(mask: &Mask) -> Vec<f32> {
    let (w, h) = (mask.width as usize, mask.height as usize);
    let mut d: Vec<f32> = mask
        .covered
        .iter()
        .map(|&c| if c { 0.0 } else { f32::INFINITY })
        .collect();
    let mut line = Vec::new();
    let mut out = Vec::new();
    for x in 0..w {
        line.clear();
        line.extend((0..h).map(|y| d[y * w + x]));
        transform_1d(&line, &mut out);
        for y in 0..h {
            d[y * w + x] = out[y];
        }
    }
    for y in 0..h {
        line.clear();
        line.extend_from_slice(&d[y * w..(y + 1) * w]);
        transform_1d(&line, &mut out);
        d[y * w..(y + 1) * w].copy_from_slice(&out);
    }
    d
}

/// The 1D squared distance transform of `f` (lower envelope of parabolas).
fn transform_1d(f: &[f32], out: &mut Vec<f32>) {
    let n = f.len();
    out.clear();
    out.resize(n, f32::INFINITY);
    let mut v = vec![0usize; n];
    let mut z = vec![0f32; n + 1];
    let mut k = 0usize;
    let first = match f.iter().position(|x| x.is_finite()) {
        Some(i) => i,
        None => return,
    };
    v[0] = first;
    z[0] = f32::NEG_INFINITY;
    z[1] = f32::INFINITY;
    for q in first + 1..n {
        if !f[q].is_finite() {
            continue;
        }
        // z[0] is −∞, so this stops at k = 0 at the latest.
        let s = loop {
            let p = v[k];
            let s = ((f[q] + (q * q) as f32) - (f[p] + (p * p) as f32)) / (2.0 * (q - p) as f32);
            if s <= z[k] {
                k -= 1;
            } else {
                break s;
            }
        };
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f32::INFINITY;
    }
    k = 0;
    for (q, slot) in out.iter_mut().enumerate() {
        while z[k + 1] < q as f32 {
            k += 1;
        }
        let p = v[k];
        let d = q as f32 - p as f32;
        *slot = d * d + f[p];
    }
}

/// The symmetric Hausdorff distance between two masks of one size, in pixels: the furthest a
/// covered pixel of either lies from the nearest covered pixel of the other.
pub fn hausdorff(a: &Mask, b: &Mask) -> f32 {
    let one_way = |from: &Mask, to: &Mask| {
        let d = distance2(to);
        from.covered
            .iter()
            .zip(&d)
            .filter(|(c, _)| **c)
            .map(|(_, &d)| d)
            .fold(0.0f32, f32::max)
    };
    one_way(a, b).max(one_way(b, a)).sqrt()
}

/// The masks of full detail and of a level, posed by `g`, seen from `view` at `scale` pixels
/// per metre (capped so that full detail spans at most `max_side` pixels), and the factor the
/// cap shrank the drawing by (1 when uncapped).
pub fn masks(
    full: &AnimationSpaceMesh,
    level: &AnimationSpaceMesh,
    g: &[Affine3A],
    view: View,
    scale: f32,
    max_side: u32,
) -> (Mask, Mask, f32) {
    let mut projection = Projection::new(view, 1.0);
    let (positions, _) = full.evaluate(g);
    let (mut lo, mut hi) = (Vec2::splat(f32::MAX), Vec2::splat(f32::MIN));
    for &p in &positions {
        let q = projection.apply(p);
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let extent = (hi - lo).max(Vec2::splat(1e-6));
    let cap = (max_side.max(16) as f32 - 8.0) / (extent.max_element() * scale);
    let shrink = cap.min(1.0);
    let scale = scale * shrink;
    // A margin round full detail's box for whatever the level puts outside it.
    let margin = 4.0 + 0.25 * extent.max_element() * scale;
    let size = (extent * scale + 2.0 * margin).ceil();
    let size = (
        (size.x as u32).clamp(1, max_side * 2),
        (size.y as u32).clamp(1, max_side * 2),
    );
    projection.scale = scale;
    projection.origin = lo * scale - Vec2::splat(margin);
    (
        rasterise(full, g, &projection, size),
        rasterise(level, g, &projection, size),
        shrink,
    )
}

/// A silhouette distance in pixels of the switching distance, and how many of those pixels
/// one drawn pixel spanned (1 unless the drawing was capped at its largest side): the
/// rasterisation's own uncertainty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Distance {
    pub px: f32,
    pub pixel: f32,
}

/// The silhouette distance of `level` from `full` where the renderer switches to it at
/// tolerance `tolerance_px`, where `level_error` metres cover `tolerance_px` pixels: the
/// worst over `poses` and [`VIEWS`], drawn no larger than `max_side` pixels.
pub fn distance(
    full: &AnimationSpaceMesh,
    level: &AnimationSpaceMesh,
    level_error: f32,
    tolerance_px: f32,
    poses: &[Vec<Affine3A>],
    max_side: u32,
) -> Distance {
    use rayon::prelude::*;
    let scale = tolerance_px / level_error.max(1e-9);
    poses
        .par_iter()
        .flat_map_iter(|g| VIEWS.iter().map(move |&v| (g, v)))
        .map(|(g, view)| {
            let (a, b, shrink) = masks(full, level, g, view, scale, max_side);
            Distance {
                px: hausdorff(&a, &b) / shrink,
                pixel: 1.0 / shrink,
            }
        })
        .reduce(
            || Distance {
                px: 0.0,
                pixel: 1.0,
            },
            |a, b| Distance {
                px: a.px.max(b.px),
                pixel: a.pixel.max(b.pixel),
            },
        )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask(w: u32, h: u32, on: &[(u32, u32)]) -> Mask {
        let mut covered = vec![false; (w * h) as usize];
        for &(x, y) in on {
            covered[(y * w + x) as usize] = true;
        }
        Mask {
            width: w,
            height: h,
            covered,
        }
    }

    #[test]
    fn distance_transform_is_exact() {
        let m = mask(7, 5, &[(1, 1), (5, 3)]);
        let d = distance2(&m);
        for y in 0..5u32 {
            for x in 0..7u32 {
                let want = [(1i32, 1i32), (5, 3)]
                    .iter()
                    .map(|&(a, b)| ((x as i32 - a).pow(2) + (y as i32 - b).pow(2)) as f32)
                    .fold(f32::INFINITY, f32::min);
                assert_eq!(d[(y * 7 + x) as usize], want, "at {x},{y}");
            }
        }
    }

    #[test]
    fn hausdorff_of_a_shifted_square() {
        let square = |dx: u32| {
            let on: Vec<(u32, u32)> = (2..6)
                .flat_map(|y| (2 + dx..6 + dx).map(move |x| (x, y)))
                .collect();
            mask(16, 8, &on)
        };
        assert_eq!(hausdorff(&square(0), &square(0)), 0.0);
        assert_eq!(hausdorff(&square(0), &square(3)), 3.0);
        // An extra island far away counts in full.
        let mut b = square(0);
        b.covered[7 * 16 + 15] = true;
        assert!((hausdorff(&square(0), &b) - (10f32.powi(2) + 2f32.powi(2)).sqrt()).abs() < 1e-4);
    }
}

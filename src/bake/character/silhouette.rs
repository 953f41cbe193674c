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

use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
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
        cover_triangle(
            &mut covered,
            w,
            [t[0], t[1], t[2]].map(|i| screen[i as usize]),
        );
    }
    Mask {
        width: w,
        height: h,
        covered,
    }
}

/// Marks every pixel of the `w`-wide mask `covered` that triangle `[a, b, c]` (in pixels)
/// touches: conservative, so that a part thinner than a pixel (a ring seen edge-on, a sliver)
/// still shows, in both masks alike.
fn cover_triangle(covered: &mut [bool], w: u32, [a, b, c]: [Vec2; 3]) {
    let h = covered.len() as u32 / w.max(1);
    let area = (b - a).perp_dot(c - a);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    let lo = a.min(b).min(c);
    let hi = a.max(b).max(c);
    let x0 = lo.x.floor().max(0.0) as u32;
    let y0 = lo.y.floor().max(0.0) as u32;
    let x1 = (hi.x.floor() as i64).min(w as i64 - 1);
    let y1 = (hi.y.floor() as i64).min(h as i64 - 1);
    if x1 < x0 as i64 || y1 < y0 as i64 {
        return;
    }
    // Both windings count: a silhouette has no back faces. An edge function reaches a
    // pixel's square when it is above minus half its extent along the edge's normal.
    let sign = area.signum();
    let edges = [(a, b), (b, c), (c, a)].map(|(p, q)| {
        let d = q - p;
        (p, d, 0.5 * (d.x.abs() + d.y.abs()))
    });
    for y in y0..=y1 as u32 {
        // The pixels of a row inside all three edges are one run: each edge, linear along
        // the row, bounds the pixel centres it lets in from one side. In f64, so that the
        // run is the test's up to rounding far below a pixel.
        let py = y as f64 + 0.5;
        let (mut lo, mut hi) = (x0 as f64 + 0.5, x1 as f64 + 0.5);
        for &(o, d, slack) in &edges {
            let (o, d) = (o.as_dvec2(), d.as_dvec2());
            // (d.x (py − o.y) − d.y (px − o.x)) · sign + slack ≥ 0, for px.
            let slope = -d.y * sign as f64;
            let at0 = (d.x * (py - o.y) + d.y * o.x) * sign as f64 + slack as f64;
            if slope > 0.0 {
                lo = lo.max(-at0 / slope);
            } else if slope < 0.0 {
                hi = hi.min(-at0 / slope);
            } else if at0 < 0.0 {
                hi = f64::NEG_INFINITY;
            }
        }
        // Pixel x's centre is x + 0.5.
        let xa = (lo - 0.5).ceil().max(x0 as f64);
        let xb = (hi - 0.5).floor().min(x1 as f64);
        if xa <= xb {
            let row = (y * w) as usize;
            covered[row + xa as usize..=row + xb as usize].fill(true);
        }
    }
}

/// Along every row, the squared distance to the nearest covered pixel of `mask` in that row
/// (infinite in a row with none): the first of the transform's two separable passes, which for
/// a binary image is two linear scans.
fn row_distances2(mask: &Mask) -> Vec<f32> {
    let w = mask.width as usize;
    let mut g = vec![f32::INFINITY; mask.covered.len()];
    for (row, out) in mask.covered.chunks_exact(w).zip(g.chunks_exact_mut(w)) {
        let mut last: Option<usize> = None;
        for (x, &c) in row.iter().enumerate() {
            if c {
                last = Some(x);
            }
            if let Some(l) = last {
                out[x] = ((x - l) * (x - l)) as f32;
            }
        }
        let mut next: Option<usize> = None;
        for x in (0..w).rev() {
            if row[x] {
                next = Some(x);
            }
            if let Some(n) = next {
                out[x] = out[x].min(((n - x) * (n - x)) as f32);
            }
        }
    }
    g
}

/// Scratch space of the 1D transform.
#[derive(Default)]
struct Envelope {
    v: Vec<usize>,
    z: Vec<f32>,
    out: Vec<f32>,
}

/// The second pass down columns `columns` of the row pass `g` (`w` wide): for each column in
/// turn, its exact squared Euclidean distances (top to bottom) handed to `visit`. Columns are
/// gathered sixteen at a time, so that reading them down the rows stays in cache.
fn column_distances2(g: &[f32], w: usize, columns: &[usize], mut visit: impl FnMut(usize, &[f32])) {
    const BLOCK: usize = 16;
    let h = g.len() / w.max(1);
    let mut lines = vec![0f32; BLOCK * h];
    let mut env = Envelope::default();
    for block in columns.chunks(BLOCK) {
        for y in 0..h {
            let row = &g[y * w..(y + 1) * w];
            for (k, &x) in block.iter().enumerate() {
                lines[k * h + y] = row[x];
            }
        }
        for (k, &x) in block.iter().enumerate() {
            transform_1d(&lines[k * h..(k + 1) * h], &mut env);
            visit(x, &env.out);
        }
    }
}

/// Squared Euclidean distance from every pixel to the nearest covered pixel of `mask`
/// (infinite everywhere if nothing is covered), row-major.
#[cfg(test)]
fn distance2(mask: &Mask) -> Vec<f32> {
    let w = mask.width as usize;
    let g = row_distances2(mask);
    let mut d = vec![0f32; g.len()];
    let all: Vec<usize> = (0..w).collect();
    column_distances2(&g, w, &all, |x, column| {
        for (y, &v) in column.iter().enumerate() {
            d[y * w + x] = v;
        }
    });
    d
}

/// The 1D squared distance transform of `f` (lower envelope of parabolas) into `env.out`.
fn transform_1d(f: &[f32], env: &mut Envelope) {
    let n = f.len();
    let Envelope { v, z, out } = env;
    out.clear();
    out.resize(n, f32::INFINITY);
    v.clear();
    v.resize(n, 0);
    z.clear();
    z.resize(n + 1, 0.0);
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

/// The largest squared distance from a covered pixel of `from` to the nearest covered pixel
/// of `to` (masks of one size). Only pixels `from` covers and `to` does not can be any
/// distance away, and they lie along the silhouettes' differences: the column pass runs only
/// down the columns that hold them.
fn one_way2(from: &Mask, to: &Mask) -> f32 {
    let w = from.width as usize;
    let apart = |i: usize| from.covered[i] && !to.covered[i];
    let mut wanted = vec![false; w];
    for i in (0..from.covered.len()).filter(|&i| apart(i)) {
        wanted[i % w] = true;
    }
    let columns: Vec<usize> = (0..w).filter(|&x| wanted[x]).collect();
    if columns.is_empty() {
        return 0.0;
    }
    let g = row_distances2(to);
    let mut worst = 0.0f32;
    column_distances2(&g, w, &columns, |x, column| {
        for (y, &d) in column.iter().enumerate() {
            if apart(y * w + x) {
                worst = worst.max(d);
            }
        }
    });
    worst
}

/// The symmetric Hausdorff distance between two masks of one size, in pixels: the furthest a
/// covered pixel of either lies from the nearest covered pixel of the other.
pub fn hausdorff(a: &Mask, b: &Mask) -> f32 {
    one_way2(a, b).max(one_way2(b, a)).sqrt()
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
    fn hausdorff_matches_brute_force_on_random_masks() {
        let mut rng = fastrand::Rng::with_seed(3);
        for _ in 0..40 {
            let (w, h) = (rng.u32(1..40), rng.u32(1..30));
            let random = |rng: &mut fastrand::Rng, share: f32| {
                let on: Vec<(u32, u32)> = (0..h)
                    .flat_map(|y| (0..w).map(move |x| (x, y)))
                    .filter(|_| rng.f32() < share)
                    .collect();
                mask(w, h, &on)
            };
            let a = random(&mut rng, 0.3);
            let b = random(&mut rng, 0.05);
            let pixels = |m: &Mask| -> Vec<(i64, i64)> {
                (0..m.covered.len())
                    .filter(|&i| m.covered[i])
                    .map(|i| ((i as u32 % w) as i64, (i as u32 / w) as i64))
                    .collect()
            };
            let one_way = |from: &Mask, to: &Mask| {
                let to = pixels(to);
                pixels(from)
                    .iter()
                    .map(|&(x, y)| {
                        to.iter()
                            .map(|&(u, v)| ((x - u).pow(2) + (y - v).pow(2)) as f32)
                            .fold(f32::INFINITY, f32::min)
                    })
                    .fold(0.0f32, f32::max)
            };
            let want = one_way(&a, &b).max(one_way(&b, &a)).sqrt();
            assert_eq!(hausdorff(&a, &b), want, "{w}x{h}");
        }
    }

    #[test]
    fn rows_of_a_triangle_are_the_pixels_its_edges_reach() {
        // Per pixel: inside all three edges, each pushed out by half the pixel's extent along
        // its normal.
        let mut rng = fastrand::Rng::with_seed(11);
        let (w, h) = (48u32, 40u32);
        for _ in 0..300 {
            let mut p = || Vec2::new(rng.f32() * 60.0 - 6.0, rng.f32() * 50.0 - 5.0);
            let tri = [p(), p(), p()];
            let mut covered = vec![false; (w * h) as usize];
            cover_triangle(&mut covered, w, tri);
            let [a, b, c] = tri.map(|v| v.as_dvec2());
            let sign = (b - a).perp_dot(c - a).signum();
            let (lo, hi) = (a.min(b).min(c).floor(), a.max(b).max(c).floor());
            for y in 0..h {
                for x in 0..w {
                    let q = glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    let inside = (x as f64) >= lo.x
                        && (x as f64) <= hi.x
                        && (y as f64) >= lo.y
                        && (y as f64) <= hi.y
                        && [(a, b), (b, c), (c, a)].iter().all(|&(o, e)| {
                            let d = e - o;
                            d.perp_dot(q - o) * sign >= -0.5 * (d.x.abs() + d.y.abs())
                        });
                    assert_eq!(covered[(y * w + x) as usize], inside, "{tri:?} at {x},{y}");
                }
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

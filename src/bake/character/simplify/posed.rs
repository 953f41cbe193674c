//! A collapse checked in the sampled poses (Merry et al. §4.3: no collapse may fold a
//! triangle over in any pose): the posed positions, each triangle's orientation and quality
//! before and after, and why a candidate is rejected.

use glam::{DVec3, Vec3};

/// Why a candidate was turned down, for statistics and tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rejection {
    Kind,
    NotAlongOutline,
    Wedges,
    Link,
    /// v1's own fan is degenerate or inconsistently oriented in parameter space.
    BadFan,
    ParameterFold,
    /// A triangle would turn over, in the rest pose or in a sampled pose.
    NormalFlip,
    /// A triangle would become a sliver, in the rest pose or in a sampled pose.
    Sliver,
    ChangesParameterArea,
    /// v1's fan has more than [`MAX_FAN`] triangles: it waits until its ring has thinned.
    Crowded,
}

/// The most triangles v1's fan may have for its collapse to be evaluated.
///
/// A collapse's cell corners are the crossings of v1's old edges with v2's new ones, about a
/// quarter of the fan's size squared, and every one is a term of the metric in every sampled
/// pose; the fan's evaluation is repeated whenever a collapse nearby changes it. A pole of a
/// finely segmented sphere (a rivet of a dense scan, 120 triangles round it) would cost 3,600
/// corners an evaluation, and on a 2-million-triangle model such fans took three quarters of
/// the bake. Turning them down costs nothing in quality: the collapse of so large a fan into
/// one of its ring's vertices makes a fan of slivers, never a cheap step, and each collapse
/// along the ring takes a triangle off the fan, so the vertex comes up again once its ring
/// has thinned. No fan of the models the figures in docs/levels.md come from is this large at full
/// detail.
pub const MAX_FAN: usize = 32;

impl Rejection {
    /// Rejections of the texture chart alone: the geometric correspondence may still take the
    /// collapse (at the price of the texture's slide).
    pub(crate) fn texture_only(self) -> bool {
        matches!(
            self,
            Rejection::BadFan | Rejection::ParameterFold | Rejection::ChangesParameterArea
        )
    }
}

/// Positions in the sampled poses, in single precision as the pose matrices that make them
/// are (on a 2-million-triangle model, 412 MB a method in double; only orientation and
/// slivers are read from them). Stored by coordinate in blocks of [`LANES`] poses (the last
/// pose repeated to fill the last block), so that [`Posed::check_triangle`] tests a block of
/// poses at once.
#[derive(Clone)]
pub struct Posed {
    /// Poses stored per position: the poses, rounded up to whole blocks.
    pub(crate) stride: usize,
    pub(crate) x: Vec<f32>,
    pub(crate) y: Vec<f32>,
    pub(crate) z: Vec<f32>,
}

/// Poses a block of [`Posed`] holds.
pub(crate) const LANES: usize = 8;

impl Posed {
    /// `positions` positions in `poses` poses, `point(u, s)` the position `u` in pose `s`.
    pub fn new(positions: usize, poses: usize, point: impl Fn(usize, usize) -> Vec3) -> Posed {
        // No poses, no blocks: only the rest pose is checked.
        let stride = poses.div_ceil(LANES) * LANES;
        let size = positions * stride;
        let mut posed = Posed {
            stride,
            x: Vec::with_capacity(size),
            y: Vec::with_capacity(size),
            z: Vec::with_capacity(size),
        };
        for u in 0..positions {
            for s in 0..stride {
                let p = point(u, s.min(poses - 1));
                posed.x.push(p.x);
                posed.y.push(p.y);
                posed.z.push(p.z);
            }
        }
        posed
    }

    /// Sets position `u` in every pose (`points` in pose order).
    pub fn set(&mut self, u: usize, points: &[Vec3]) {
        let Some(&last) = points.last() else {
            return;
        };
        for s in 0..self.stride {
            let p = points.get(s).copied().unwrap_or(last);
            let i = u * self.stride + s;
            (self.x[i], self.y[i], self.z[i]) = (p.x, p.y, p.z);
        }
    }

    pub(crate) fn get(&self, u: u32, s: usize) -> DVec3 {
        let i = u as usize * self.stride + s;
        DVec3::new(self.x[i] as f64, self.y[i] as f64, self.z[i] as f64)
    }

    /// [`check_triangle`] of `(x1, a, b)` becoming `(x2, a, b)` (positions) in every pose.
    ///
    /// Each block of poses is first tested in single precision with a margin: a triangle
    /// clearly facing the same way (its normals' dot product far above its rounding error,
    /// bounded by the edges' lengths) and clearly no sliver (1% off the bound) passes; only a
    /// pose that is not clear is tested as [`check_triangle`] tests it, in double precision,
    /// so the verdict is the same. Nearly every pose of nearly every triangle is clear, and
    /// these tests were a tenth of a bake.
    pub(crate) fn check_triangle(&self, x1: u32, x2: u32, a: u32, b: u32) -> Result<(), Rejection> {
        let stride = self.stride;
        let block = |c: &[f32], u: u32, at: usize| -> [f32; LANES] {
            let i = u as usize * stride + at;
            c[i..i + LANES].try_into().expect("a whole block")
        };
        for at in (0..stride).step_by(LANES) {
            let get = |u: u32| {
                (
                    block(&self.x, u, at),
                    block(&self.y, u, at),
                    block(&self.z, u, at),
                )
            };
            let (p1, p2, pa, pb) = (get(x1), get(x2), get(a), get(b));
            let mut clear = [false; LANES];
            for (k, clear) in clear.iter_mut().enumerate() {
                let sub =
                    |p: &([f32; LANES], [f32; LANES], [f32; LANES]),
                     q: &([f32; LANES], [f32; LANES], [f32; LANES])| {
                        [p.0[k] - q.0[k], p.1[k] - q.1[k], p.2[k] - q.2[k]]
                    };
                let cross = |u: [f32; 3], v: [f32; 3]| {
                    [
                        u[1] * v[2] - u[2] * v[1],
                        u[2] * v[0] - u[0] * v[2],
                        u[0] * v[1] - u[1] * v[0],
                    ]
                };
                let dot = |u: [f32; 3], v: [f32; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
                let (e1, e2) = (sub(&pa, &p1), sub(&pb, &p1));
                let (f1, f2) = (sub(&pa, &p2), sub(&pb, &p2));
                let g = sub(&pb, &pa);
                let (n_old, n_new) = (cross(e1, e2), cross(f1, f2));
                let d = dot(n_old, n_new);
                // |n| ≤ |u||v|, and single precision's error in d is a few 1e-7 of
                // |e1||e2||f1||f2|: a margin of 2e-5 of that is clear.
                let scale = dot(e1, e1) * dot(e2, e2) * dot(f1, f1) * dot(f2, f2);
                let facing = d > 0.0
                    && scale > f32::MIN_POSITIVE
                    && scale < f32::MAX
                    && d * d > 4e-10 * scale;
                let edges = dot(f1, f1) + dot(g, g) + dot(f2, f2);
                let bound = SLIVER as f32 * edges;
                let round = 12.0 * dot(n_new, n_new) > 1.01 * bound * bound;
                *clear = facing && round;
            }
            if clear.iter().all(|&c| c) {
                continue;
            }
            for (k, _) in clear.iter().enumerate().filter(|(_, c)| !**c) {
                let s = at + k;
                check_triangle(
                    self.get(x1, s),
                    self.get(x2, s),
                    self.get(a, s),
                    self.get(b, s),
                )?;
            }
        }
        Ok(())
    }
}

/// Triangle `(x1, a, b)` becoming `(x2, a, b)`: it must not turn over, nor become a sliver
/// (thinner than [`SLIVER`] and less than half as round as it was).
pub(crate) fn check_triangle(x1: DVec3, x2: DVec3, a: DVec3, b: DVec3) -> Result<(), Rejection> {
    let n_old = (a - x1).cross(b - x1);
    let n_new = (a - x2).cross(b - x2);
    if n_old.dot(n_new) <= 0.0 {
        return Err(Rejection::NormalFlip);
    }
    // quality(x2, a, b) < SLIVER without a square root, from the normal already at hand:
    // 2√3·|n| < SLIVER·Σ edge², squared. The old triangle's quality is needed only then.
    let edges = (a - x2).length_squared() + (b - a).length_squared() + (x2 - b).length_squared();
    let thin = 12.0 * n_new.length_squared() < (SLIVER * edges) * (SLIVER * edges);
    if thin && quality(x2, a, b) < 0.5 * quality(x1, a, b) {
        return Err(Rejection::Sliver);
    }
    Ok(())
}

/// How round a triangle is: `4√3 · area / Σ edge²`, 1 for an equilateral one, 0 for a
/// degenerate one.
pub fn quality(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let area2 = (b - a).cross(c - a).length();
    let edges = (b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared();
    if edges <= 0.0 {
        return 0.0;
    }
    2.0 * 3f64.sqrt() * area2 / edges
}

/// A triangle less round than this is a sliver (an aspect of about 50:1).
pub const SLIVER: f64 = 0.02;

//! Self-shadowing inside a crown, baked as one occlusion term per point: how much of the sky a
//! point deep in the foliage still sees through the leaves around it.
//!
//! The thesis (Bennett-Therkildsen, Carlsen & Schmid 2007) lit its billboards by their plane
//! alone, so a coarse cloud showed "the same shading on every billboard". Here the crown is a
//! participating medium, as trees made of particles were shaded by their depth in the crown
//! (Reeves & Blau, "Approximate and probabilistic algorithms for shading and rendering
//! structured particle systems", SIGGRAPH 1985): the full tree's leaf area is binned into a voxel grid, every voxel's extinction coefficient is
//! σ = G · leaf area / volume with G = ½ (randomly turned leaves), and a point's *exposure* is
//! the sky it sees, the mean over directions of the transmittance exp(−∫σ ds) towards the
//! outside. Exposures are scaled so that the crown's most open tenth sees the full sky, and
//! the term the shaders apply is the light lost, 1 − mix([`FLOOR`], 1, exposure).
//!
//! The same term lights every level: the full tree's leaves and wood per vertex, a billboard per
//! texel of its atlas (each texel taking the term of the leaf drawn there), an impostor per view
//! texel. It is a property of where a surface sits in the full crown, so every level of a chain
//! reads it off one [`CrownDensity`], made from the full tree.

use crate::model::Model;
use glam::Vec3;
use rayon::prelude::*;

/// The light a point in the crown's heart keeps: deep leaves are dark, never black (light
/// scattered through and between leaves, which the term leaves out).
pub const FLOOR: f32 = 0.3;
/// Voxels along the crown's longest side.
const CELLS: f32 = 28.0;
/// The projection of a randomly turned leaf onto a direction, per unit of its area
/// (Ross's G-function for a spherical leaf-angle distribution).
const G: f32 = 0.5;
/// Directions the exposure averages over (the whole sphere, the ground's bounce included:
/// leaves are lit from below too, more dimly, see [`sky_weight`]).
const DIRECTIONS: usize = 48;

/// The leaf area of a crown binned into voxels, as extinction coefficients.
#[derive(Clone, Debug)]
pub struct CrownDensity {
    origin: Vec3,
    cell: f32,
    dims: [usize; 3],
    /// σ per voxel, x fastest.
    sigma: Vec<f32>,
    /// The exposure the crown's most open points reach (its 90th percentile over the leaves).
    open: f32,
}

impl CrownDensity {
    /// The leaves (triangles of cut-out materials) of `tree` in its rest pose; `None` where it
    /// has none.
    pub fn of(tree: &Model) -> Option<CrownDensity> {
        let mesh = &tree.mesh;
        let cut: Vec<bool> = tree
            .materials
            .iter()
            .map(crate::model::Material::cuts_out)
            .collect();
        let leaf_triangles: Vec<[Vec3; 3]> = mesh
            .indices
            .chunks_exact(3)
            .filter(|t| {
                cut.get(mesh.materials[t[0] as usize] as usize)
                    .copied()
                    .unwrap_or(false)
            })
            .map(|t| [0, 1, 2].map(|k| mesh.positions[t[k] as usize]))
            .filter(|t| t.iter().all(|p| p.is_finite()))
            .collect();
        Self::from_triangles(&leaf_triangles)
    }

    /// The crown of these leaf triangles.
    pub fn from_triangles(triangles: &[[Vec3; 3]]) -> Option<CrownDensity> {
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for p in triangles.iter().flatten() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        if triangles.is_empty() || !(hi - lo).max_element().is_finite() {
            return None;
        }
        let cell = ((hi - lo).max_element() / CELLS).max(1e-4);
        // One empty voxel all round, so rays leave through open air.
        let origin = lo - Vec3::splat(cell);
        let dims = ((hi - lo) / cell).ceil().as_uvec3() + 3;
        let dims = [dims.x as usize, dims.y as usize, dims.z as usize];
        let mut area = vec![0.0f32; dims[0] * dims[1] * dims[2]];
        let mut density = CrownDensity {
            origin,
            cell,
            dims,
            sigma: Vec::new(),
            open: 1.0,
        };
        for t in triangles {
            let a = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
            // A leaf larger than a voxel spreads its area over the voxels it crosses.
            let longest = (t[1] - t[0])
                .length()
                .max((t[2] - t[1]).length())
                .max((t[0] - t[2]).length());
            let k = ((longest / cell).ceil() as usize).clamp(1, 16);
            let share = a / (k * k) as f32;
            for i in 0..k {
                for j in 0..k - i {
                    // Centroids of a k×k split of the triangle (the upright sub-triangles'
                    // centres, weighted as if all k² were).
                    let (u, v) = (
                        (i as f32 + 1.0 / 3.0) / k as f32,
                        (j as f32 + 1.0 / 3.0) / k as f32,
                    );
                    let p = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
                    let w = if i + j + 1 < k { 2.0 } else { 1.0 };
                    if let Some(c) = density.voxel(p) {
                        area[c] += share * w;
                    }
                }
            }
        }
        let volume = cell * cell * cell;
        density.sigma = area.iter().map(|a| G * a / volume).collect();
        // The percentile from at most a few thousand leaves spread through the list: a large
        // crown's own would cost as much again as lighting its vertices.
        let stride = (triangles.len() / 4096).max(1);
        let centres: Vec<Vec3> = triangles
            .iter()
            .step_by(stride)
            .map(|t| (t[0] + t[1] + t[2]) / 3.0)
            .collect();
        let mut raw: Vec<f32> = centres.par_iter().map(|&p| density.sky(p)).collect();
        raw.sort_unstable_by(f32::total_cmp);
        density.open = raw[(raw.len() * 9 / 10).min(raw.len() - 1)].max(1e-3);
        Some(density)
    }

    fn voxel(&self, p: Vec3) -> Option<usize> {
        let c = ((p - self.origin) / self.cell).floor();
        let [nx, ny, nz] = self.dims;
        if c.min_element() < 0.0
            || c.x >= nx as f32
            || c.y >= ny as f32
            || c.z >= nz as f32
            || !c.is_finite()
        {
            return None;
        }
        Some(c.x as usize + nx * (c.y as usize + ny * c.z as usize))
    }

    /// The weighted mean transmittance from `p` out of the crown over [`DIRECTIONS`]
    /// directions.
    fn sky(&self, p: Vec3) -> f32 {
        let step = 0.5 * self.cell;
        let (mut seen, mut total) = (0.0, 0.0);
        for d in 0..DIRECTIONS {
            let dir = fibonacci_direction(d, DIRECTIONS);
            let w = sky_weight(dir);
            // Half a voxel out first: the point's own leaf does not shade it.
            let mut q = p + dir * step;
            let mut depth = 0.0;
            while let Some(c) = self.voxel(q) {
                depth += self.sigma[c] * step;
                q += dir * step;
            }
            seen += w * (-depth).exp();
            total += w;
        }
        seen / total
    }

    /// How open `p` is: 1 on the crown's outside, towards 0 in its heart.
    pub fn exposure(&self, p: Vec3) -> f32 {
        if !p.is_finite() {
            return 1.0;
        }
        (self.sky(p) / self.open).clamp(0.0, 1.0)
    }

    /// The light lost at `p`, as the shaders take it: 1 − mix(FLOOR, 1, exposure).
    pub fn occlusion(&self, p: Vec3) -> f32 {
        (1.0 - FLOOR) * (1.0 - self.exposure(p))
    }

    /// [`Self::occlusion`] at every point.
    pub fn occlusions(&self, points: &[Vec3]) -> Vec<f32> {
        points.par_iter().map(|&p| self.occlusion(p)).collect()
    }
}

/// Sky above counts fully, the ground's bounce below a third.
fn sky_weight(dir: Vec3) -> f32 {
    if dir.y >= 0.0 { 1.0 } else { 1.0 / 3.0 }
}

/// Direction `i` of `n` spread evenly over the sphere (a Fibonacci lattice).
fn fibonacci_direction(i: usize, n: usize) -> Vec3 {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
    let r = (1.0 - y * y).max(0.0).sqrt();
    let phi = golden * i as f32;
    Vec3::new(r * phi.cos(), y, r * phi.sin())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ball of small random leaves, radius 1.
    fn ball(count: usize) -> Vec<[Vec3; 3]> {
        let mut rng = fastrand::Rng::with_seed(5);
        let mut out = Vec::new();
        while out.len() < count {
            let c = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0;
            if c.length() > 1.0 {
                continue;
            }
            let mut random = || Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0;
            let u = random().normalize_or(Vec3::X) * 0.1;
            let v = random().normalize_or(Vec3::Y) * 0.1;
            out.push([c, c + u, c + v]);
        }
        out
    }

    #[test]
    fn the_heart_of_a_crown_is_darker_than_its_outside() {
        let crown = CrownDensity::from_triangles(&ball(6000)).unwrap();
        let heart = crown.exposure(Vec3::ZERO);
        let side = crown.exposure(Vec3::new(0.95, 0.0, 0.0));
        let top = crown.exposure(Vec3::new(0.0, 0.95, 0.0));
        let outside = crown.exposure(Vec3::new(0.0, 3.0, 0.0));
        assert!(heart < 0.5, "heart {heart}");
        assert!(
            side > heart + 0.3 && top > heart + 0.3,
            "{side} {top} {heart}"
        );
        // The sky above counts for more than the ground below.
        let bottom = crown.exposure(Vec3::new(0.0, -0.95, 0.0));
        assert!(top > bottom, "top {top}, bottom {bottom}");
        assert_eq!(outside, 1.0);
        assert!((crown.occlusion(Vec3::ZERO) - (1.0 - FLOOR) * (1.0 - heart)).abs() < 1e-6);
    }

    #[test]
    fn sparse_foliage_hardly_shades_itself() {
        let sparse = CrownDensity::from_triangles(&ball(200)).unwrap();
        let dense = CrownDensity::from_triangles(&ball(8000)).unwrap();
        assert!(
            sparse.exposure(Vec3::ZERO) > 0.8,
            "{}",
            sparse.exposure(Vec3::ZERO)
        );
        assert!(dense.exposure(Vec3::ZERO) < sparse.exposure(Vec3::ZERO) - 0.3);
        assert!(CrownDensity::from_triangles(&[]).is_none());
    }

    #[test]
    fn the_lattice_covers_the_sphere_evenly() {
        let mean: Vec3 = (0..DIRECTIONS)
            .map(|i| fibonacci_direction(i, DIRECTIONS))
            .sum::<Vec3>()
            / DIRECTIONS as f32;
        assert!(mean.length() < 0.05, "{mean}");
        for i in 0..DIRECTIONS {
            assert!((fibonacci_direction(i, DIRECTIONS).length() - 1.0).abs() < 1e-5);
        }
    }
}

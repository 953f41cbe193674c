//! The view sphere of an octahedral impostor: the far level of a tree after its coarsest
//! billboard cloud, one quad showing the tree as seen from the nearest of a grid of directions
//! over the upper hemisphere (the views are baked into the cells of an atlas).
//!
//! The directions are laid out by the hemi-octahedral map (as in Ryan Brucks' octahedral
//! impostors and Shopf's "Mixed resolution rendering"): a unit vector with y ≥ 0 goes to the
//! octahedron |x| + |y| + |z| = 1, whose upper half, seen from above and turned by 45°, is
//! the square [−1, 1]². A regular `frames` × `frames` grid on the square then spreads the
//! views evenly enough over the hemisphere, its edge is the horizon, and any direction falls in
//! one grid cell: the renderer blends the three views of the cell's triangle it falls in,
//! weighted by its barycentric coordinates, so that turning round a tree never pops.
//!
//! Pure geometry: plain data in, plain data out. The bake draws the views through the atlas
//! seam ([`super::atlas::RasterizeAtlas`]); the shader mirrors [`hemi_oct_encode`].

use glam::{Vec2, Vec3};

/// The point of the square [−1, 1]² where the hemi-octahedral map puts direction `d`
/// (y up; a direction below the horizon is taken as its mirror above it).
pub fn hemi_oct_encode(d: Vec3) -> Vec2 {
    let d = Vec3::new(d.x, d.y.abs(), d.z);
    let p = Vec2::new(d.x, d.z) / (d.x.abs() + d.y + d.z.abs()).max(1e-12);
    Vec2::new(p.x + p.y, p.x - p.y)
}

/// The unit direction at point `s` of the square [−1, 1]² (the inverse of [`hemi_oct_encode`]).
pub fn hemi_oct_decode(s: Vec2) -> Vec3 {
    let p = Vec2::new(s.x + s.y, s.x - s.y) * 0.5;
    let y = 1.0 - p.x.abs() - p.y.abs();
    Vec3::new(p.x, y.max(0.0), p.y).normalize()
}

/// The views of an impostor: a `frames` × `frames` grid over the hemi-octahedral square, each
/// view drawn into a `cell` × `cell` texel cell of the atlas, row by row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ViewGrid {
    pub frames: u32,
    pub cell: u32,
}

impl ViewGrid {
    /// The direction from the tree towards the eye of view (i, j): grid points at the square's
    /// corners and edges look along the horizon, the middle one straight down.
    pub fn direction(&self, i: u32, j: u32) -> Vec3 {
        let n = (self.frames.max(2) - 1) as f32;
        hemi_oct_decode(Vec2::new(i as f32, j as f32) / n * 2.0 - Vec2::ONE)
    }

    /// The three views whose blend shows direction `d` and their weights (summing to 1): the
    /// corners of the half of the grid cell `d` falls in, by barycentric coordinates.
    pub fn blend(&self, d: Vec3) -> [((u32, u32), f32); 3] {
        let n = (self.frames.max(2) - 1) as f32;
        let g = ((hemi_oct_encode(d) + Vec2::ONE) * 0.5 * n).clamp(Vec2::ZERO, Vec2::splat(n));
        let base = g.floor().min(Vec2::splat(n - 1.0));
        let f = g - base;
        let (i, j) = (base.x as u32, base.y as u32);
        // Split the cell along its diagonal from (0, 0) to (1, 1).
        if f.x >= f.y {
            [
                ((i, j), 1.0 - f.x),
                ((i + 1, j), f.x - f.y),
                ((i + 1, j + 1), f.y),
            ]
        } else {
            [
                ((i, j), 1.0 - f.y),
                ((i, j + 1), f.y - f.x),
                ((i + 1, j + 1), f.x),
            ]
        }
    }

    /// The side of the square atlas that holds every view.
    pub fn atlas_size(&self) -> u32 {
        self.frames * self.cell
    }

    /// An orthographic view's axes for eye direction `d`: right and up on the screen, both
    /// unit and perpendicular to `d`. Up follows the world's up where it can (so a tree stands
    /// upright in its side views) and the world's −z when looking straight down.
    pub fn view_axes(d: Vec3) -> (Vec3, Vec3) {
        let d = d.normalize();
        let reference = if d.y > 0.999 { Vec3::NEG_Z } else { Vec3::Y };
        let right = reference.cross(d).normalize();
        let up = d.cross(right);
        (right, up)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_map_is_inverted_by_its_decode() {
        let mut rng = fastrand::Rng::with_seed(3);
        for _ in 0..2000 {
            let d = Vec3::new(rng.f32() * 2.0 - 1.0, rng.f32(), rng.f32() * 2.0 - 1.0);
            if d.length() < 1e-3 {
                continue;
            }
            let d = d.normalize();
            let s = hemi_oct_encode(d);
            assert!(s.x.abs() <= 1.0 + 1e-5 && s.y.abs() <= 1.0 + 1e-5, "{s}");
            let back = hemi_oct_decode(s);
            assert!(back.distance(d) < 1e-4, "{d} -> {s} -> {back}");
        }
        // Straight down onto the tree is the middle, the horizon the square's edge.
        assert!(hemi_oct_encode(Vec3::Y).length() < 1e-6);
        for d in [
            Vec3::X,
            Vec3::Z,
            Vec3::NEG_X,
            Vec3::new(1.0, 0.0, 1.0).normalize(),
        ] {
            let s = hemi_oct_encode(d);
            assert!((s.x.abs().max(s.y.abs()) - 1.0).abs() < 1e-5, "{d}: {s}");
        }
    }

    #[test]
    fn grid_views_cover_the_hemisphere_evenly_enough() {
        let grid = ViewGrid {
            frames: 8,
            cell: 64,
        };
        let views: Vec<Vec3> = (0..8)
            .flat_map(|j| (0..8).map(move |i| (i, j)))
            .map(|(i, j)| grid.direction(i, j))
            .collect();
        assert!(
            views
                .iter()
                .all(|v| v.y >= -1e-6 && (v.length() - 1.0).abs() < 1e-5)
        );
        // Every direction over the hemisphere has a view within 22°.
        let mut rng = fastrand::Rng::with_seed(4);
        let mut worst = 0.0f32;
        for _ in 0..4000 {
            let d = Vec3::new(rng.f32() * 2.0 - 1.0, rng.f32(), rng.f32() * 2.0 - 1.0);
            if d.length() < 1e-3 {
                continue;
            }
            let d = d.normalize();
            let nearest = views.iter().map(|v| v.dot(d)).fold(-1.0f32, f32::max);
            worst = worst.max(nearest.clamp(-1.0, 1.0).acos().to_degrees());
        }
        assert!(worst < 22.0, "{worst}°");
        assert_eq!(grid.atlas_size(), 512);
    }

    #[test]
    fn a_blend_uses_the_views_round_the_direction() {
        let grid = ViewGrid {
            frames: 6,
            cell: 32,
        };
        let mut rng = fastrand::Rng::with_seed(5);
        for _ in 0..1000 {
            let d = Vec3::new(rng.f32() * 2.0 - 1.0, rng.f32(), rng.f32() * 2.0 - 1.0);
            if d.length() < 1e-3 {
                continue;
            }
            let d = d.normalize();
            let blend = grid.blend(d);
            let sum: f32 = blend.iter().map(|(_, w)| w).sum();
            assert!((sum - 1.0).abs() < 1e-5);
            assert!(blend.iter().all(|&(_, w)| w >= -1e-5));
            // The heaviest view is close to the direction.
            let &((i, j), _) = blend.iter().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
            let angle = grid
                .direction(i, j)
                .dot(d)
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees();
            assert!(angle < 30.0, "{angle}°");
        }
        // A grid direction is its own view, alone.
        let at = grid.blend(grid.direction(2, 3));
        let own = at.iter().find(|((i, j), _)| (*i, *j) == (2, 3)).unwrap();
        assert!((own.1 - 1.0).abs() < 1e-3, "{at:?}");
    }

    #[test]
    fn view_axes_are_upright_and_orthonormal() {
        for d in [
            Vec3::X,
            Vec3::Y,
            Vec3::new(0.3, 0.5, -0.8).normalize(),
            Vec3::new(-1.0, 0.01, 0.0).normalize(),
        ] {
            let (r, u) = ViewGrid::view_axes(d);
            assert!((r.length() - 1.0).abs() < 1e-5 && (u.length() - 1.0).abs() < 1e-5);
            assert!(r.dot(u).abs() < 1e-5 && r.dot(d).abs() < 1e-5 && u.dot(d).abs() < 1e-5);
            if d.y < 0.99 {
                assert!(u.y > 0.0, "{d}: up {u}");
            }
        }
    }
}

//! The stochastic billboard cloud (Lacewell et al. 2006, as Bennett-Therkildsen, Carlsen & Schmid,
//! "Animated Billboard Clouds for Foliage Simplification", Aalborg University, 2007 use it in §3.3,
//! with the fixes its brief lists).
//!
//! A greedy, error-bounded clustering of leaves by coplanarity. Each round tries `S` random
//! planes, each through the three corners of a random seed leaf moved independently along its
//! normal by up to ε, and keeps the one of highest *density*: the summed *contribution*
//! (projected area, `area · |n_leaf · n_plane|`) of the leaves it is *valid* for (every corner
//! within ε of it), optionally weighted by the view penalty. Those leaves become one billboard
//! and leave the pool. The seed is always valid for its own plane, so every round removes at
//! least one leaf and the loop ends.
//!
//! Fixes of the thesis text: the best density is reset once per round (not per candidate); the
//! view-penalty factor is `1 − |φv − φn| / (π/2)` (the literal formula penalises the favoured
//! tilt), floored so a round always has a winner.
//!
//! One addition to the thesis (§3.4): the winning plane is refitted, by area-
//! weighted least squares, to the leaves it took, and the pool is searched again with the new
//! plane, for as long as that raises the density. A random plane through a small seed leaf
//! moved by up to ε is tilted by up to about 2ε over the leaf's size; the refit levels it, so a
//! large ε is not wasted on small leaves.

use super::rect::{Rect, min_area_rect};
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// A leaf as the builder sees it: a planar polygon (a quad, or a triangle), with its area and
/// unit normal.
#[derive(Clone, Debug, PartialEq)]
pub struct Leaf {
    pub corners: Vec<Vec3>,
    pub area: f32,
    pub normal: Vec3,
}

impl Leaf {
    /// From corners in order round the polygon (fan triangulated for area and normal).
    pub fn new(corners: Vec<Vec3>) -> Leaf {
        let mut n = Vec3::ZERO;
        for k in 1..corners.len().saturating_sub(1) {
            n += (corners[k] - corners[0]).cross(corners[k + 1] - corners[0]);
        }
        Leaf {
            area: 0.5 * n.length(),
            normal: n.normalize_or(Vec3::Y),
            corners,
        }
    }

    /// From its corners and its triangles (a strip, a fold, a crossed cluster): the area of
    /// its triangles summed and their normal averaged by area, each turned to agree with the
    /// first so that a card and its back face do not cancel out.
    pub fn from_triangles(corners: Vec<Vec3>, triangles: &[[Vec3; 3]]) -> Leaf {
        let mut n = Vec3::ZERO;
        for t in triangles {
            let c = (t[1] - t[0]).cross(t[2] - t[0]);
            n += if c.dot(n) < 0.0 { -c } else { c };
        }
        Leaf {
            area: 0.5 * n.length(),
            normal: n.normalize_or(Vec3::Y),
            corners,
        }
    }

    /// The leaf of `triangles` (indices into `mesh`'s triangles): its corners in order of
    /// first use, its area and normal from its triangles ([`Leaf::from_triangles`]).
    pub fn of_mesh(triangles: &[u32], mesh: &crate::model::SkinnedMesh) -> Leaf {
        let mut corners: Vec<u32> = Vec::new();
        let mut faces: Vec<[Vec3; 3]> = Vec::with_capacity(triangles.len());
        for &t in triangles {
            let i = &mesh.indices[3 * t as usize..3 * t as usize + 3];
            for &v in i {
                if !corners.contains(&v) {
                    corners.push(v);
                }
            }
            faces.push([0, 1, 2].map(|k| mesh.positions[i[k] as usize]));
        }
        Leaf::from_triangles(
            corners
                .iter()
                .map(|&v| mesh.positions[v as usize])
                .collect(),
            &faces,
        )
    }

    /// The mean of its corners.
    pub fn centre(&self) -> Vec3 {
        self.corners.iter().sum::<Vec3>() / self.corners.len().max(1) as f32
    }
}

/// A plane `normal · x = offset`, `normal` unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub normal: Vec3,
    pub offset: f32,
}

impl Plane {
    pub fn distance(&self, p: Vec3) -> f32 {
        self.normal.dot(p) - self.offset
    }

    /// Valid for a leaf: every corner within `epsilon`.
    pub fn valid_for(&self, leaf: &Leaf, epsilon: f32) -> bool {
        leaf.corners
            .iter()
            .all(|&c| self.distance(c).abs() <= epsilon)
    }

    /// Two unit axes spanning the plane.
    pub fn basis(&self) -> (Vec3, Vec3) {
        let a = if self.normal.y.abs() < 0.9 {
            Vec3::Y
        } else {
            Vec3::X
        };
        let u = a.cross(self.normal).normalize();
        (u, self.normal.cross(u))
    }
}

/// Parameters of a cloud.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CloudParams {
    /// Largest displacement of a leaf corner onto its billboard, scene units.
    pub epsilon: f32,
    /// Random candidate planes per round (`S`; 100 in every experiment of the thesis).
    pub samples: usize,
    /// Favour billboards whose normal makes this angle with the ground plane (radians; 0:
    /// vertical billboards, for trees seen from the ground). `None`: no penalty.
    pub view_angle: Option<f32>,
    /// Bake into each billboard every leaf valid for its plane, not only its own (thesis
    /// §3.6.2): denser textures, same planes and cost. On by default: on the project's trees
    /// it lowers the chain's colour error a little at every level (sapling, 22 billboards:
    /// 0.548 to 0.510).
    pub increased_density: bool,
    /// Cross a billboard whose leaves make a thick clump (see [`crossing`]) with an upright
    /// one at right angles: no view then sees only its edge.
    pub crossing: bool,
    pub seed: u64,
}

impl Default for CloudParams {
    fn default() -> Self {
        CloudParams {
            epsilon: 0.1,
            samples: 100,
            view_angle: Some(0.0),
            increased_density: true,
            crossing: true,
            seed: 1,
        }
    }
}

/// One billboard: its plane, its rectangle on the plane, and the leaves it shows.
#[derive(Clone, Debug, PartialEq)]
pub struct Billboard {
    pub plane: Plane,
    /// Corners in scene space, counter-clockwise seen from the side the normal points to.
    pub corners: [Vec3; 4],
    /// The leaves assigned to it (each leaf to exactly one billboard).
    pub leaves: Vec<u32>,
    /// The leaves its texture shows: `leaves`, plus, with increased density, every other leaf
    /// of the group valid for its plane.
    pub drawn: Vec<u32>,
    /// Drawn only from views within this angle (radians) of its normal, horizontally, either
    /// side: a clump billboard's view window ([`super::clumps`]; negative for the planes that
    /// take the other half of the cross-fade's screen door). 0: drawn from every view.
    pub view_window: f32,
}

impl Billboard {
    pub fn area(&self) -> f32 {
        (self.corners[1] - self.corners[0]).length() * (self.corners[3] - self.corners[0]).length()
    }
}

/// The view-penalty factor of a plane (thesis §3.6, corrected), floored at a small positive
/// value so that a round always has a winner.
fn view_factor(normal: Vec3, view_angle: f32) -> f32 {
    let phi_n = normal.y.abs().clamp(0.0, 1.0).asin();
    (1.0 - (view_angle - phi_n).abs() / std::f32::consts::FRAC_PI_2).max(0.05)
}

/// Builds the billboard cloud of `leaves`.
pub fn stochastic_cloud(leaves: &[Leaf], params: &CloudParams) -> Vec<Billboard> {
    let validity = Validity::new(leaves, params.epsilon);
    let valid = |plane: &Plane, i: u32| validity.valid(plane, i);
    let mut rng = fastrand::Rng::with_seed(params.seed);
    let mut pool: Vec<u32> = (0..leaves.len() as u32)
        .filter(|&i| leaves[i as usize].area > 0.0 && leaves[i as usize].corners.len() >= 3)
        .collect();
    let mut out: Vec<(Plane, Vec<u32>)> = Vec::new();
    while !pool.is_empty() {
        let (plane, best_density) = best_candidate(&validity, &pool, params, &mut rng);
        let plane = refit(&validity, &pool, plane, best_density, params.view_angle);
        let (taken, rest): (Vec<u32>, Vec<u32>) = pool.iter().partition(|&&i| valid(&plane, i));
        let taken = if taken.is_empty() {
            // Only possible through rounding at ε = 0: take the seed-most leaf alone on its own
            // plane so the loop always progresses.
            let i = pool[0];
            out.push((own_plane(&leaves[i as usize]), vec![i]));
            pool.remove(0);
            continue;
        } else {
            taken
        };
        pool = rest;
        let plane = settle(leaves, &taken, plane, validity.eps);
        out.push((plane, taken));
    }
    let shared = if params.crossing {
        cross_clumps(&mut out, leaves, &valid)
    } else {
        vec![None; out.len()]
    };
    out.into_iter()
        .zip(shared)
        .map(|((plane, taken), shared)| billboard(&validity, params, plane, taken, shared))
        .collect()
}

/// Which leaves are valid for a plane (every corner within ε of it), with what a quick
/// rejection of most of them needs.
struct Validity<'l> {
    leaves: &'l [Leaf],
    /// Each leaf's centre, and the largest distance of a corner from it.
    centres: Vec<Vec3>,
    radii: Vec<f32>,
    /// ε, as the parameter asks, plus rounding.
    eps: f32,
}

impl<'l> Validity<'l> {
    /// Validity within `epsilon` for `leaves`.
    fn new(leaves: &'l [Leaf], epsilon: f32) -> Validity<'l> {
        // ε = 0 still allows for rounding: a few ulps of the scene's size.
        let scale = leaves
            .iter()
            .flat_map(|l| l.corners.iter())
            .fold(1.0f32, |m, c| m.max(c.abs().max_element()));
        let eps = epsilon.max(0.0) + 4.0 * f32::EPSILON * scale;
        // Quick rejection: a leaf whose centre is farther than its radius + ε from a plane
        // cannot be valid for it.
        let centres: Vec<Vec3> = leaves.iter().map(Leaf::centre).collect();
        let radii: Vec<f32> = leaves
            .iter()
            .zip(&centres)
            .map(|(l, c)| l.corners.iter().map(|p| p.distance(*c)).fold(0.0, f32::max))
            .collect();
        Validity {
            leaves,
            centres,
            radii,
            eps,
        }
    }

    /// Whether `plane` is valid for leaf `i`.
    fn valid(&self, plane: &Plane, i: u32) -> bool {
        let i = i as usize;
        plane.distance(self.centres[i]).abs() <= self.radii[i] + self.eps
            && plane.valid_for(&self.leaves[i], self.eps)
    }

    /// A plane's density over the leaves of `pool`: the summed contribution (projected area)
    /// of those it is valid for, weighted by the view penalty where there is one.
    fn density(&self, pool: &[u32], plane: &Plane, view_angle: Option<f32>) -> f32 {
        let mut density: f32 = pool
            .iter()
            .filter(|&&i| self.valid(plane, i))
            .map(|&i| {
                let l = &self.leaves[i as usize];
                l.area * l.normal.dot(plane.normal).abs()
            })
            .sum();
        if let Some(phi_v) = view_angle {
            density *= view_factor(plane.normal, phi_v);
        }
        density
    }
}

/// One round's `S` random candidate planes, each through a seed leaf of `pool`: the densest,
/// with its density.
fn best_candidate(
    validity: &Validity,
    pool: &[u32],
    params: &CloudParams,
    rng: &mut fastrand::Rng,
) -> (Plane, f32) {
    let leaves = validity.leaves;
    // Candidates are drawn first (sequentially, from the seeded generator), then scored
    // in parallel: the result does not depend on the number of threads.
    let candidates: Vec<Plane> = (0..params.samples.max(1))
        .map(|_| {
            let seed = &leaves[pool[rng.usize(0..pool.len())] as usize];
            candidate_plane(seed, validity.eps, rng)
        })
        .collect();
    let scored: Vec<(f32, usize)> = candidates
        .par_iter()
        .enumerate()
        .map(|(k, plane)| (validity.density(pool, plane, params.view_angle), k))
        .collect();
    // The best candidate; ties go to the earliest (deterministic).
    let best = scored
        .iter()
        .fold((f32::NEG_INFINITY, 0usize), |b, &(d, k)| {
            if d > b.0 { (d, k) } else { b }
        })
        .1;
    (candidates[best], scored[best].0)
}

/// The winning plane refitted to the leaves it takes, for as long as that raises its
/// density (a few times at most; see the module comment): a random plane through a small
/// seed leaf is tilted, and the refit levels it.
fn refit(
    validity: &Validity,
    pool: &[u32],
    mut plane: Plane,
    mut best_density: f32,
    view_angle: Option<f32>,
) -> Plane {
    let valid = |plane: &Plane, i: u32| validity.valid(plane, i);
    for _ in 0..4 {
        let members: Vec<u32> = pool.iter().copied().filter(|&i| valid(&plane, i)).collect();
        let Some(refit) = fit_plane(members.iter().map(|&i| &validity.leaves[i as usize])) else {
            break;
        };
        if !members.iter().all(|&i| valid(&refit, i)) {
            break;
        }
        let density = validity.density(pool, &refit, view_angle);
        if density <= best_density * 1.000_01 {
            break;
        }
        (plane, best_density) = (refit, density);
    }
    plane
}

/// The plane a billboard's leaves `taken` (chosen on `plane`) lie nearest: their least-squares
/// plane, where every one of them stays within `eps` of it and it faces within 25° of
/// `plane` (a narrow bent strip lies nearest the plane that holds it edge-on, and the search's
/// plane, chosen by projected area, faces it); else `plane`.
///
/// The search scores planes by density under the view penalty, which favours upright planes
/// (thesis §3.6): a plane tilted up to the edge of ε from its leaves wins over their own, and
/// every corner moves by up to ε for nothing once the leaves are chosen. On a tree of drooping
/// needle cards, each card its own billboard, that tilted them by 1° (median) at ε = 0.002 of
/// the tree's height and raised the colour error from 0.024 to 0.060. The penalty still
/// decides which leaves go together; their billboard then lies where they are.
fn settle(leaves: &[Leaf], taken: &[u32], plane: Plane, eps: f32) -> Plane {
    let members = || taken.iter().map(|&i| &leaves[i as usize]);
    match fit_plane(members()) {
        Some(fit)
            if fit.normal.dot(plane.normal).abs() >= 0.9
                && members().all(|l| fit.valid_for(l, eps)) =>
        {
            // Keep the search's facing: the rectangle's winding and the atlas's front.
            if fit.normal.dot(plane.normal) < 0.0 {
                Plane {
                    normal: -fit.normal,
                    offset: -fit.offset,
                }
            } else {
                fit
            }
        }
        _ => plane,
    }
}

/// Crosses every billboard of `out` whose clump pays for it (see [`crossing`]), the crossing
/// planes appended: for each billboard, all the leaves of its clump where it is one of a
/// crossed pair.
///
/// Crossed pairs draw all their leaves on both planes, and size both to them.
fn cross_clumps(
    out: &mut Vec<(Plane, Vec<u32>)>,
    leaves: &[Leaf],
    valid: &dyn Fn(&Plane, u32) -> bool,
) -> Vec<Option<Vec<u32>>> {
    let mut shared: Vec<Option<Vec<u32>>> = vec![None; out.len()];
    for k in 0..out.len() {
        let (plane, taken) = &out[k];
        let Some((cross, stay, go)) = crossing(plane, taken, leaves, valid) else {
            continue;
        };
        let all = taken.clone();
        out[k].1 = stay;
        shared[k] = Some(all.clone());
        out.push((cross, go));
        shared.push(Some(all));
    }
    shared
}

/// The billboard on `plane` of the leaves `taken`: its rectangle, and the leaves its texture
/// shows (`shared`, all of a crossed pair's clump, where it is one).
fn billboard(
    validity: &Validity,
    params: &CloudParams,
    plane: Plane,
    taken: Vec<u32>,
    shared: Option<Vec<u32>>,
) -> Billboard {
    let leaves = validity.leaves;
    let valid = |plane: &Plane, i: u32| validity.valid(plane, i);
    // A crossed pair is sized to, and draws, all the leaves of its clump.
    let sized = shared.as_deref().unwrap_or(&taken);
    let corners = rectangle(&plane, sized.iter().map(|&i| &leaves[i as usize]));
    // Other leaves valid for the plane are drawn where they fall inside its rectangle
    // whole: its texture holds nothing outside it.
    let inside = |i: u32| {
        let (o, eu, ev) = (corners[0], corners[1] - corners[0], corners[3] - corners[0]);
        let slack = 1e-4;
        leaves[i as usize].corners.iter().all(|&c| {
            let s = (c - o).dot(eu) / eu.length_squared().max(f32::MIN_POSITIVE);
            let t = (c - o).dot(ev) / ev.length_squared().max(f32::MIN_POSITIVE);
            (-slack..=1.0 + slack).contains(&s) && (-slack..=1.0 + slack).contains(&t)
        })
    };
    let drawn = match shared {
        Some(all) => all,
        None if params.increased_density => {
            let mut drawn: Vec<u32> = (0..leaves.len() as u32)
                .filter(|&i| leaves[i as usize].area > 0.0 && valid(&plane, i) && inside(i))
                .collect();
            // Its own leaves always, rounding at the rectangle's edge notwithstanding.
            drawn.extend_from_slice(&taken);
            drawn.sort_unstable();
            drawn.dedup();
            drawn
        }
        None => taken.clone(),
    };
    Billboard {
        plane,
        corners,
        leaves: taken,
        drawn,
        view_window: 0.0,
    }
}

/// The billboard crossing one on `plane` that took the leaves `taken`, where one pays, and
/// how the leaves split between the two (each to the one it faces more squarely; both keep
/// some).
///
/// An addition to the thesis for the coarse end of a chain. A billboard shows its leaves as
/// they look along its normal; seen edge-on it shows nothing, while a clump of leaves looks
/// much the same from every side. Where ε exceeds a clump's depth one plane takes it whole,
/// and each of the metric's views round the tree (§5.1.3) then sees only |cos| of it. An
/// upright plane at right angles through the clump's centre, drawing the same leaves, keeps
/// at least half of it in every view (|cos θ| + |sin θ| ≥ 1).
///
/// It pays where the clump is thick: its leaves spread along the plane's normal at least half
/// as far as across the crossing plane (a flat layer looks like a line from the side, and a
/// crossing plane would show it as one), and the plane is not lying down (its normal's
/// horizontal part sets the crossing plane's facing). Every leaf must be within ε of it.
fn crossing(
    plane: &Plane,
    taken: &[u32],
    leaves: &[Leaf],
    valid: &dyn Fn(&Plane, u32) -> bool,
) -> Option<(Plane, Vec<u32>, Vec<u32>)> {
    let flat = Vec3::new(plane.normal.x, 0.0, plane.normal.z);
    if taken.len() < 2 || flat.length() < 0.5 {
        return None;
    }
    let normal = Vec3::Y.cross(flat).normalize();
    let area: f32 = taken.iter().map(|&i| leaves[i as usize].area).sum();
    let centre = taken
        .iter()
        .map(|&i| leaves[i as usize].centre() * leaves[i as usize].area)
        .sum::<Vec3>()
        / area.max(f32::MIN_POSITIVE);
    let cross = Plane {
        normal,
        offset: normal.dot(centre),
    };
    let spread = |n: Vec3| {
        let w = taken.iter().map(|&i| {
            let l = &leaves[i as usize];
            (l.area, n.dot(l.centre() - centre))
        });
        let (sum, sq) = w.fold((0.0, 0.0), |(s, q), (a, d)| (s + a, q + a * d * d));
        (sq / sum.max(f32::MIN_POSITIVE)).sqrt()
    };
    if spread(plane.normal) < 0.5 * spread(normal) || !taken.iter().all(|&i| valid(&cross, i)) {
        return None;
    }
    let (go, stay): (Vec<u32>, Vec<u32>) = taken.iter().partition(|&&i| {
        let n = leaves[i as usize].normal;
        n.dot(normal).abs() > n.dot(plane.normal).abs()
    });
    (!stay.is_empty() && !go.is_empty()).then_some((cross, stay, go))
}

/// The area-weighted least-squares plane of the leaves' corners: through their weighted
/// centroid, normal along the least-spread direction of their covariance.
fn fit_plane<'a>(leaves: impl Iterator<Item = &'a Leaf>) -> Option<Plane> {
    let mut points: Vec<(Vec3, f32)> = Vec::new();
    for l in leaves {
        let w = l.area / l.corners.len() as f32;
        points.extend(l.corners.iter().map(|&c| (c, w)));
    }
    let total: f32 = points.iter().map(|p| p.1).sum();
    if points.len() < 3 || total <= 0.0 {
        return None;
    }
    let centroid = points.iter().map(|(p, w)| *p * *w).sum::<Vec3>() / total;
    let mut cov = nalgebra::Matrix3::<f64>::zeros();
    for (p, w) in &points {
        let d = (*p - centroid).as_dvec3();
        let d = nalgebra::Vector3::new(d.x, d.y, d.z);
        cov += d * d.transpose() * (*w as f64);
    }
    let eig = cov.symmetric_eigen();
    let k = eig.eigenvalues.imin();
    let n = eig.eigenvectors.column(k);
    let normal = Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32).normalize_or_zero();
    if normal == Vec3::ZERO {
        return None;
    }
    Some(Plane {
        normal,
        offset: normal.dot(centroid),
    })
}

/// The plane of a leaf itself: a quad's or triangle's through its first corner, a larger
/// piece's (a run of a strip, see [`super::bends`]) fitted to its corners.
fn own_plane(leaf: &Leaf) -> Plane {
    if leaf.corners.len() > 4
        && let Some(p) = fit_plane(std::iter::once(leaf))
    {
        return p;
    }
    Plane {
        normal: leaf.normal,
        offset: leaf.normal.dot(leaf.corners[0]),
    }
}

/// A random plane through three corners of `seed`, each moved along its normal by up to ε. A
/// quad's fourth corner could then end up beyond ε; such a draw is retried, and after a few
/// tries the leaf's own plane is taken, so the seed is always valid for its candidate.
fn candidate_plane(seed: &Leaf, eps: f32, rng: &mut fastrand::Rng) -> Plane {
    let c = &seed.corners;
    let picks = spread_corners(c);
    for _ in 0..4 {
        let p: Vec<Vec3> = picks
            .iter()
            .map(|&k| c[k] + seed.normal * (rng.f32() * 2.0 - 1.0) * eps)
            .collect();
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        if n.length_squared() <= 1e-20 {
            continue;
        }
        let n = n.normalize();
        let plane = Plane {
            normal: n,
            offset: n.dot(p[0]),
        };
        if plane.valid_for(seed, eps * 1.0001) {
            return plane;
        }
    }
    own_plane(seed)
}

/// Three corners of a leaf to lay a plane through: a quad's or a triangle's first, second and
/// third; of a larger piece (whose corners in order of use may zigzag along a strip, so that
/// evenly spaced ones can fall on one edge) the first, the one farthest from it, and the one
/// farthest from the line through those two.
fn spread_corners(c: &[Vec3]) -> [usize; 3] {
    if c.len() <= 4 {
        return [0, c.len() / 3, 2 * c.len() / 3];
    }
    let far = |key: &dyn Fn(Vec3) -> f32| {
        (0..c.len())
            .max_by(|&a, &b| key(c[a]).total_cmp(&key(c[b])))
            .unwrap_or(0)
    };
    let b = far(&|p| p.distance_squared(c[0]));
    let axis = (c[b] - c[0]).normalize_or_zero();
    let third = far(&|p| (p - c[0]).reject_from_normalized(axis).length_squared());
    [0, b, third]
}

/// The least-area rectangle of the leaves' corners projected onto the plane, in scene space,
/// wound counter-clockwise about the plane normal.
pub(super) fn rectangle<'a>(plane: &Plane, leaves: impl Iterator<Item = &'a Leaf>) -> [Vec3; 4] {
    let (u, v) = plane.basis();
    let points: Vec<Vec2> = leaves
        .flat_map(|l| l.corners.iter())
        .map(|&p| Vec2::new(p.dot(u), p.dot(v)))
        .collect();
    let r: Rect = min_area_rect(&points);
    r.corners()
        .map(|q| u * q.x + v * q.y + plane.normal * plane.offset)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(c: Vec3, n: Vec3, size: f32) -> Leaf {
        let p = Plane {
            normal: n.normalize(),
            offset: 0.0,
        };
        let (u, v) = p.basis();
        let h = size * 0.5;
        Leaf::new(vec![
            c - u * h - v * h,
            c + u * h - v * h,
            c + u * h + v * h,
            c - u * h + v * h,
        ])
    }

    #[test]
    fn coplanar_leaves_share_one_billboard_and_scattered_ones_do_not() {
        // Two layers of leaves, 1 m apart, each exactly flat.
        let mut leaves = Vec::new();
        for k in 0..20 {
            let x = (k % 5) as f32;
            let z = (k / 5) as f32;
            leaves.push(quad(Vec3::new(x, 0.0, z), Vec3::Y, 0.3));
            leaves.push(quad(Vec3::new(x, 1.0, z), Vec3::Y, 0.3));
        }
        let params = CloudParams {
            epsilon: 0.05,
            view_angle: None,
            ..Default::default()
        };
        let cloud = stochastic_cloud(&leaves, &params);
        assert_eq!(cloud.len(), 2);
        assert!(cloud.iter().all(|b| b.leaves.len() == 20));
        // Layers 0.1 apart and ε = 0.6: one plane takes both.
        for l in leaves.iter_mut().skip(1).step_by(2) {
            for c in &mut l.corners {
                c.y -= 0.9;
            }
        }
        let big = stochastic_cloud(
            &leaves,
            &CloudParams {
                epsilon: 0.6,
                ..params
            },
        );
        assert_eq!(big.len(), 1);
        assert_eq!(big[0].leaves.len(), 40);
    }

    #[test]
    fn a_billboard_lies_on_its_leaves_not_tilted_upright_to_the_edge_of_epsilon() {
        // Cards drooping nearly flat, far apart: each its own billboard. The view penalty
        // would tilt each towards upright by as much as ε allows; settled, each lies on its
        // card.
        let leaves: Vec<Leaf> = (0..12)
            .map(|k| {
                let a = k as f32 * 0.5;
                quad(
                    Vec3::new(3.0 * a.cos(), k as f32, 3.0 * a.sin()),
                    Vec3::new(0.3 * a.cos(), 1.0, 0.3 * a.sin()),
                    1.0,
                )
            })
            .collect();
        let cloud = stochastic_cloud(
            &leaves,
            &CloudParams {
                epsilon: 0.05,
                ..Default::default()
            },
        );
        assert_eq!(cloud.len(), leaves.len());
        for b in &cloud {
            for &l in &b.leaves {
                for c in &leaves[l as usize].corners {
                    assert!(
                        b.plane.distance(*c).abs() < 1e-4,
                        "{}",
                        b.plane.distance(*c)
                    );
                }
            }
        }
    }

    #[test]
    fn the_view_penalty_prefers_upright_billboards() {
        assert!(view_factor(Vec3::X, 0.0) > 0.99);
        assert!(view_factor(Vec3::Y, 0.0) < 0.06);
        assert!(view_factor(Vec3::Y, std::f32::consts::FRAC_PI_2) > 0.99);
    }
}

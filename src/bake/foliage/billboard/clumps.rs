//! View-selected clump billboards: the coarse end of a tree's chain, where a billboard cloud
//! has too few planes left to keep its leaves near them.
//!
//! At a large ε the thesis's clouds (§3.3–3.7) run out of good planes: a handful of billboards
//! must stand for a crown, each leaf is pressed flat onto a plane far from it, and from any view
//! but the plane's own the leaves slide apart by their depth and shrink by foreshortening. The
//! thesis measures 0.44 colour error at about 6 billboards (§8.4.1), and the whole-crown clouds
//! of this project's trees do worse. Drawing every leaf of a clump on several crossed planes
//! (a "star") keeps each view covered, but then every view sees every plane at once and the
//! planes fill the crown's gaps.
//!
//! Here the crown is split into `clumps` clumps of leaves (k-means on their centres, weighted
//! by area), and each clump gets `views` upright planes through its centre, `π / views` apart
//! about the up axis. Every plane shows the whole clump, projected along its normal: the clump
//! as seen from that side, its silhouette included (the issue's "textures that cover the crown's
//! silhouette"). The renderer draws, per clump, only the plane that faces the viewer best: each
//! plane has a *view window*, the horizontal view directions within `π / (2·views)` of its
//! normal (either side), and the windows of one clump tile the circle, so from any view one
//! plane per clump is drawn, seen at most `π / (2·views)` off its normal. Near the edge of a
//! window the two neighbouring planes cross-fade through complementary halves of a screen door
//! (even planes keep one half of the pixels, odd planes the other: `views` is even), so
//! orbiting a tree does not pop.
//!
//! This is the billboard cloud's view penalty (§3.6) taken to its end: planes are not merely
//! favoured for facing the ground-level viewer, they are chosen per view. It is what SpeedTree's
//! 360° billboards do for a whole tree, applied clump by clump so that the crown keeps its
//! parallax and its branches their sway.
//!
//! The error is bounded like a cloud's: a leaf at depth d off its plane appears displaced by
//! d·sin θ from a view θ off the plane's normal, so a level whose clumps' leaves lie within
//! `depth` of their planes is within ε = depth · sin(π / (2·views)) of its leaves from every
//! ground-level view ([`ClumpCloud::epsilon`]). Views from high above see the upright planes
//! foreshortened, as they see every upright billboard of the thesis.

use super::cloud::{Billboard, Plane};
use super::{Foliage, SkeletonCloud};
use glam::Vec3;

/// Planes per clump by default: 45° apart, each seen at most 22.5° off its normal.
pub const DEFAULT_VIEWS: usize = 4;

/// Times over the loop at which a clump's bone is fitted to its leaves' motion.
const MOTION_SAMPLES: usize = 16;

/// The bone that carries a clump's leaves best: of every bone, the one whose motion moves the
/// leaves' centres least far from where their own bones take them, in the mean square over
/// `frames` (skinning matrices per time and bone). A clump straddling two branches hangs
/// from the trunk below them by the shared-bone rule, and would not sway at all; the fitted
/// bone sways as the clump does on average.
fn best_bone(
    frames: &[Vec<glam::Affine3A>],
    centres: &[Vec3],
    bones: &[u32],
    clump: &[u32],
) -> u32 {
    let count = frames.first().map_or(0, Vec::len);
    let error = |b: usize| -> f32 {
        let mut sum = 0.0;
        for f in frames {
            for &i in clump {
                let (c, own) = (centres[i as usize], bones[i as usize] as usize);
                let there = f.get(own).map_or(c, |m| m.transform_point3(c));
                sum += f[b].transform_point3(c).distance_squared(there);
            }
        }
        sum
    };
    (0..count)
        .map(|b| (b, error(b)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0, |(b, _)| b as u32)
}

/// Lloyd's iterations at most.
const ITERATIONS: usize = 30;

/// A clump cloud: its billboards, `views` to a clump in clump order, with their bones and view
/// windows, and the largest depth of a leaf off its clump's planes.
#[derive(Clone, Debug)]
pub struct ClumpCloud {
    pub cloud: SkeletonCloud,
    pub clumps: usize,
    pub views: usize,
    /// The largest distance of a leaf corner from its clump's centre, horizontally: the most a
    /// leaf lies off any of its clump's planes.
    pub depth: f32,
}

impl ClumpCloud {
    /// The screen displacement bound of the level, scene units: a leaf `depth` off a plane seen
    /// at most `π / (2·views)` off its normal.
    pub fn epsilon(&self) -> f32 {
        self.depth * half_window(self.views).sin()
    }

    /// Billboards drawn from any one view: one per clump.
    pub fn drawn_per_view(&self) -> usize {
        self.clumps
    }
}

/// Half the angle of a plane's view window with `views` planes to a clump.
pub fn half_window(views: usize) -> f32 {
    std::f32::consts::FRAC_PI_2 / views.max(1) as f32
}

/// The view window of plane `j` of a clump with `views` planes, as the renderer reads it (see
/// [`Billboard::view_window`]): the half angle, negative for odd planes, which take the other
/// half of the cross-fade's screen door.
fn window_of(j: usize, views: usize) -> f32 {
    let h = half_window(views);
    if j % 2 == 1 { -h } else { h }
}

/// The clump cloud of `foliage` with `clumps` clumps and `views` planes to a clump (rounded up
/// to an even number, at least 2, so that neighbouring planes take complementary halves of
/// the cross-fade). Each clump's planes are bound to the bone that moves its leaves best
/// ([`best_bone`]).
pub fn clump_cloud(
    tree: &crate::model::Model,
    foliage: &Foliage,
    clumps: usize,
    views: usize,
    seed: u64,
) -> ClumpCloud {
    let views = views.max(2).next_multiple_of(2);
    let frames = crate::anim::skinning_over_loop(tree, MOTION_SAMPLES);
    let leaves = &foliage.leaves;
    let centres: Vec<Vec3> = leaves.iter().map(|l| l.centre()).collect();
    let weights: Vec<f32> = leaves.iter().map(|l| l.area.max(1e-12)).collect();
    let of = k_means_restarted(
        &centres,
        &weights,
        clumps.clamp(1, leaves.len().max(1)),
        seed,
    );
    let k = of.iter().max().map_or(0, |&m| m as usize + 1);
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); k];
    for (i, &c) in of.iter().enumerate() {
        members[c as usize].push(i as u32);
    }
    members.retain(|m| !m.is_empty());
    let mut cloud = SkeletonCloud {
        billboards: Vec::new(),
        bones: Vec::new(),
    };
    let mut depth = 0.0f32;
    for (c, clump) in members.iter().enumerate() {
        let area: f32 = clump.iter().map(|&i| weights[i as usize]).sum();
        let centre = clump
            .iter()
            .map(|&i| centres[i as usize] * weights[i as usize])
            .sum::<Vec3>()
            / area;
        for &i in clump {
            for &p in &leaves[i as usize].corners {
                let d = p - centre;
                depth = depth.max(Vec3::new(d.x, 0.0, d.z).length());
            }
        }
        let bone = best_bone(&frames, &centres, &foliage.bones, clump);
        // Clumps turned by the golden angle one from the next, so that their windows' edges
        // (where a clump cross-fades) are spread round the tree rather than all at one view.
        let turn = c as f32 * 2.399_963;
        let normals: Vec<Vec3> = (0..views)
            .map(|j| {
                let a = turn + j as f32 * std::f32::consts::PI / views as f32;
                Vec3::new(a.cos(), 0.0, a.sin())
            })
            .collect();
        // Each leaf is counted once, on the plane it faces best (what the animation error
        // follows); every plane draws all of them.
        let mut taken: Vec<Vec<u32>> = vec![Vec::new(); views];
        for &i in clump {
            let n = leaves[i as usize].normal;
            let best = (0..views)
                .max_by(|&a, &b| n.dot(normals[a]).abs().total_cmp(&n.dot(normals[b]).abs()))
                .unwrap_or(0);
            taken[best].push(i);
        }
        for (j, (&normal, leaves_taken)) in normals.iter().zip(taken).enumerate() {
            let plane = Plane {
                normal,
                offset: normal.dot(centre),
            };
            let corners =
                super::cloud::rectangle(&plane, clump.iter().map(|&i| &leaves[i as usize]));
            cloud.billboards.push(Billboard {
                plane,
                corners,
                leaves: leaves_taken,
                drawn: clump.clone(),
                view_window: window_of(j, views),
            });
            cloud.bones.push(bone);
        }
    }
    ClumpCloud {
        cloud,
        clumps: members.len(),
        views,
        depth,
    }
}

/// Restarts of k-means, from different seeds, of which the tightest is kept.
const RESTARTS: u64 = 8;

/// [`k_means`] from [`RESTARTS`] seeds drawn from `seed`, keeping the clustering of least
/// weighted inertia (the sum of area times squared distance to the clump's centre). One
/// k-means run lands in a local minimum that depends on its seeding, and at a handful of
/// clumps that decides how a whole side of the crown is cut: on the sapling at 6 clumps, eight
/// seeds gave colour errors 0.384 to 0.421, and inertia ranked them (the tightest was the
/// best, the loosest, at over twice the inertia of the rest, the worst).
fn k_means_restarted(points: &[Vec3], weights: &[f32], k: usize, seed: u64) -> Vec<u32> {
    use rayon::prelude::*;
    (0..RESTARTS)
        .into_par_iter()
        .map(|r| {
            let of = k_means(
                points,
                weights,
                k,
                seed.wrapping_add(r.wrapping_mul(0x9E37_79B9)),
            );
            (inertia(points, weights, &of), r, of)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
        .map_or_else(Vec::new, |(_, _, of)| of)
}

/// The weighted inertia of the clustering `of`: Σ weight · |point − its cluster's centre|².
fn inertia(points: &[Vec3], weights: &[f32], of: &[u32]) -> f64 {
    let k = of.iter().max().map_or(0, |&m| m as usize + 1);
    let mut sum = vec![glam::DVec3::ZERO; k];
    let mut mass = vec![0.0f64; k];
    for ((p, &w), &c) in points.iter().zip(weights).zip(of) {
        sum[c as usize] += p.as_dvec3() * w as f64;
        mass[c as usize] += w as f64;
    }
    points
        .iter()
        .zip(weights)
        .zip(of)
        .map(|((p, &w), &c)| {
            let centre = sum[c as usize] / mass[c as usize].max(1e-300);
            w as f64 * p.as_dvec3().distance_squared(centre)
        })
        .sum()
}

/// Weighted k-means of `points` into at most `k` clusters (k-means++ seeding from `seed`, then
/// Lloyd's iterations); the cluster of every point.
fn k_means(points: &[Vec3], weights: &[f32], k: usize, seed: u64) -> Vec<u32> {
    if points.is_empty() {
        return Vec::new();
    }
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut centres = vec![points[rng.usize(..points.len())]];
    let mut nearest: Vec<f32> = points
        .iter()
        .map(|p| p.distance_squared(centres[0]))
        .collect();
    while centres.len() < k {
        let total: f32 = nearest.iter().zip(weights).map(|(d, w)| d * w).sum();
        if total <= 0.0 {
            break;
        }
        let mut pick = rng.f32() * total;
        let mut next = points.len() - 1;
        for (i, (d, w)) in nearest.iter().zip(weights).enumerate() {
            pick -= d * w;
            if pick <= 0.0 {
                next = i;
                break;
            }
        }
        let c = points[next];
        centres.push(c);
        for (n, p) in nearest.iter_mut().zip(points) {
            *n = n.min(p.distance_squared(c));
        }
    }
    let assign = |centres: &[Vec3]| -> Vec<u32> {
        points
            .iter()
            .map(|p| {
                (0..centres.len())
                    .min_by(|&a, &b| {
                        p.distance_squared(centres[a])
                            .total_cmp(&p.distance_squared(centres[b]))
                    })
                    .unwrap_or(0) as u32
            })
            .collect()
    };
    let mut of = assign(&centres);
    for _ in 0..ITERATIONS {
        let mut sum = vec![Vec3::ZERO; centres.len()];
        let mut mass = vec![0.0f32; centres.len()];
        for ((p, w), &c) in points.iter().zip(weights).zip(&of) {
            sum[c as usize] += *p * *w;
            mass[c as usize] += w;
        }
        for (c, (s, m)) in centres.iter_mut().zip(sum.iter().zip(&mass)) {
            if *m > 0.0 {
                *c = *s / *m;
            }
        }
        let next = assign(&centres);
        if next == of {
            break;
        }
        of = next;
    }
    of
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::foliage::billboard::cloud::Leaf;

    /// A tree of one bone and no mesh: what the clumps need of it is its skeleton.
    fn one_bone_tree() -> crate::model::Model {
        use crate::model::{Model, Node, Skeleton, SkinnedMesh, Trs};
        Model {
            name: "one bone".into(),
            mesh: SkinnedMesh::empty(),
            skeleton: Skeleton {
                nodes: vec![Node {
                    name: "root".into(),
                    parent: None,
                    rest: Trs::IDENTITY,
                }],
                joints: vec![0],
                inverse_bind: vec![glam::Mat4::IDENTITY],
                root_transform: glam::Affine3A::IDENTITY,
            },
            clips: Vec::new(),
            materials: Vec::new(),
        }
    }

    /// Leaves in `n` balls far apart along x, all on bone 0.
    fn balls(n: usize, per: usize) -> Foliage {
        let mut rng = fastrand::Rng::with_seed(3);
        let mut leaves = Vec::new();
        for b in 0..n {
            for _ in 0..per {
                let c = Vec3::new(10.0 * b as f32, 5.0, 0.0)
                    + Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5);
                let (u, v) = (Vec3::X * 0.1, Vec3::Y * 0.1);
                leaves.push(Leaf::new(vec![c, c + u, c + u + v, c + v]));
            }
        }
        let count = leaves.len();
        Foliage {
            leaves,
            bones: vec![0; count],
            triangles: vec![Vec::new(); count],
            rebound: 0,
        }
    }

    #[test]
    fn restarted_k_means_finds_balls_of_unequal_sizes_from_every_seed() {
        // Two big balls and three small ones, 10 apart: k-means++ from one seed now and then
        // puts two centres in a big ball and merges two small ones (the tighter clustering
        // is the balls: splitting a big ball saves about 160, merging two small ones costs
        // 600); the tightest of the restarts never does.
        let sizes = [400, 400, 12, 12, 12];
        let mut points = Vec::new();
        let mut ball = Vec::new();
        let mut rng = fastrand::Rng::with_seed(9);
        for (b, &per) in sizes.iter().enumerate() {
            let spread = if per > 100 { 2.0 } else { 0.3 };
            for _ in 0..per {
                let jitter = Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5;
                points.push(Vec3::new(10.0 * b as f32, 0.0, 0.0) + jitter * spread);
                ball.push(b);
            }
        }
        let weights = vec![1.0; points.len()];
        let finds_balls = |of: &[u32]| {
            let mut cluster_of_ball = vec![None; sizes.len()];
            for (&b, &c) in ball.iter().zip(of) {
                if *cluster_of_ball[b].get_or_insert(c) != c {
                    return false;
                }
            }
            let mut clusters: Vec<u32> = cluster_of_ball.into_iter().flatten().collect();
            clusters.sort_unstable();
            clusters.dedup();
            clusters.len() == sizes.len()
        };
        let single_misses = (0..20)
            .filter(|&seed| !finds_balls(&k_means(&points, &weights, 5, seed)))
            .count();
        for seed in 0..20 {
            let of = k_means_restarted(&points, &weights, 5, seed);
            assert!(finds_balls(&of), "seed {seed}");
            let single = k_means(&points, &weights, 5, seed);
            assert!(inertia(&points, &weights, &of) <= inertia(&points, &weights, &single));
        }
        // Otherwise the restarts would have nothing to fix here.
        assert!(single_misses > 0, "every single run found the balls");
    }

    #[test]
    fn clumps_follow_the_balls_and_each_gets_crossed_planes_with_tiling_windows() {
        let f = balls(3, 40);
        let c = clump_cloud(&one_bone_tree(), &f, 3, 4, 1);
        assert_eq!(c.clumps, 3);
        assert_eq!(c.cloud.billboards.len(), 12);
        for clump in c.cloud.billboards.chunks(4) {
            // One ball to a clump: all its leaves, on every plane.
            let xs: Vec<f32> = clump[0]
                .drawn
                .iter()
                .map(|&i| f.leaves[i as usize].centre().x)
                .collect();
            assert_eq!(xs.len(), 40);
            assert!(xs.iter().all(|x| (x - xs[0]).abs() < 2.0));
            assert!(clump.iter().all(|b| b.drawn == clump[0].drawn));
            // Upright planes 45° apart, windows of ±22.5°, alternating halves.
            for (j, b) in clump.iter().enumerate() {
                assert!(b.plane.normal.y.abs() < 1e-6);
                assert!((b.view_window.abs() - std::f32::consts::PI / 8.0).abs() < 1e-6);
                assert_eq!(b.view_window < 0.0, j % 2 == 1);
            }
            let a = clump[0].plane.normal.dot(clump[1].plane.normal);
            assert!((a - std::f32::consts::FRAC_PI_4.cos()).abs() < 1e-4);
            // Each leaf counted once over the clump's planes.
            let taken: usize = clump.iter().map(|b| b.leaves.len()).sum();
            assert_eq!(taken, 40);
        }
        // A ball's leaves lie within its radius of its planes (about 0.5·√2 and a leaf).
        assert!(c.depth > 0.3 && c.depth < 0.9, "{}", c.depth);
        assert!((c.epsilon() - c.depth * (std::f32::consts::PI / 8.0).sin()).abs() < 1e-6);
    }

    #[test]
    fn every_horizontal_view_falls_in_exactly_one_window_of_a_clump() {
        let f = balls(1, 30);
        for views in [2, 4, 6] {
            let c = clump_cloud(&one_bone_tree(), &f, 1, views, 1);
            for k in 0..360 {
                let a = (k as f32 + 0.37).to_radians();
                let v = Vec3::new(a.cos(), 0.0, a.sin());
                let inside = c
                    .cloud
                    .billboards
                    .iter()
                    .filter(|b| b.plane.normal.dot(v).abs().acos() < b.view_window.abs())
                    .count();
                assert_eq!(inside, 1, "{views} views, {k}°");
            }
        }
    }

    #[test]
    fn odd_view_counts_round_up_to_even() {
        let f = balls(1, 10);
        let c = clump_cloud(&one_bone_tree(), &f, 1, 3, 1);
        assert_eq!(c.views, 4);
        assert_eq!(c.cloud.billboards.len(), 4);
    }
}

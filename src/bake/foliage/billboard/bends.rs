//! Leaves that no plane holds within ε, split at their bends before a cloud is built.
//!
//! The thesis's leaves are flat polygons (§1.1: "foliage made of loose textured quads"), and
//! its builder (§3.3) moves every corner of a leaf at most ε onto a plane. Artists' cards are
//! often not flat: a palm frond is a strip of dozens of triangles folded along its rachis and
//! drooping along its length, a leaf cluster three cards crossed on a shared spine. Such a
//! piece is valid for no plane at a small ε, and a billboard of its own plane pressed it flat:
//! seen from the side a drooping frond came out short and bunched.
//!
//! So, at each level's ε, a leaf whose corners do not all lie within ε of one plane facing as
//! its triangles face on average is split into pieces that do: regions grown over its
//! triangles (two triangles are neighbours where they share a vertex), breadth first from the
//! first triangle not yet taken, a triangle joining while such a plane of the region keeps
//! every corner of the region within ε. (Not the least-squares plane: a narrow strip bent
//! along its length lies within ε of the plane that holds it edge-on, which would show it as
//! a line.) A strip then splits into runs along its length, a crossed cluster into its cards;
//! the pieces are leaves like any other, on the leaf's bone, and coarser levels (larger ε)
//! split them less or not at all.

use super::Foliage;
use super::cloud::Leaf;
use crate::model::SkinnedMesh;
use glam::{DVec3, Vec3};
use std::borrow::Cow;

/// `foliage` with every leaf that no plane holds within `epsilon` split into pieces that
/// one plane each does (see the module comment); borrowed where no leaf needed it.
pub fn split_at_bends<'a>(
    foliage: &'a Foliage,
    mesh: &SkinnedMesh,
    epsilon: f32,
) -> Cow<'a, Foliage> {
    let bent: Vec<bool> = foliage
        .leaves
        .iter()
        .map(|l| !flat_within(l, epsilon))
        .collect();
    if !bent.contains(&true) {
        return Cow::Borrowed(foliage);
    }
    let mut out = Foliage {
        leaves: Vec::with_capacity(foliage.leaves.len()),
        bones: Vec::with_capacity(foliage.leaves.len()),
        triangles: Vec::with_capacity(foliage.leaves.len()),
        rebound: foliage.rebound,
    };
    for (i, &bent) in bent.iter().enumerate() {
        let pieces = if bent {
            flat_pieces(&foliage.triangles[i], mesh, epsilon)
        } else {
            vec![foliage.triangles[i].clone()]
        };
        for piece in pieces {
            out.leaves.push(if bent {
                Leaf::of_mesh(&piece, mesh)
            } else {
                foliage.leaves[i].clone()
            });
            out.bones.push(foliage.bones[i]);
            out.triangles.push(piece);
        }
    }
    Cow::Owned(out)
}

/// Whether every corner of `leaf` lies within `epsilon` of one plane facing along its normal
/// (the area-weighted mean of its triangles').
pub fn flat_within(leaf: &Leaf, epsilon: f32) -> bool {
    spread_within(&leaf.corners, leaf.normal.as_dvec3(), epsilon)
}

/// Whether `points` lie within `epsilon` of one plane of normal `normal` (unit): their
/// distances along it span at most 2ε.
fn spread_within(points: &[Vec3], normal: DVec3, epsilon: f32) -> bool {
    let (lo, hi) = points.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
        let d = p.as_dvec3().dot(normal);
        (lo.min(d), hi.max(d))
    });
    // A little slack for rounding: a flat card is flat at ε = 0.
    let scale = points
        .iter()
        .fold(1.0f64, |m, p| m.max(p.abs().max_element() as f64));
    hi - lo <= 2.0 * epsilon.max(0.0) as f64 + 1e-6 * scale
}

/// `triangles` (one leaf, connected through shared vertices) in regions that one plane each
/// holds within `epsilon`: see the module comment.
fn flat_pieces(triangles: &[u32], mesh: &SkinnedMesh, epsilon: f32) -> Vec<Vec<u32>> {
    let corners = |t: u32| -> [u32; 3] {
        let i = &mesh.indices[3 * t as usize..3 * t as usize + 3];
        [i[0], i[1], i[2]]
    };
    // The leaf's triangles by vertex, for neighbours.
    let mut by_vertex: std::collections::HashMap<u32, Vec<usize>> = Default::default();
    for (k, &t) in triangles.iter().enumerate() {
        for v in corners(t) {
            by_vertex.entry(v).or_default().push(k);
        }
    }
    let face = |t: u32| {
        let [a, b, c] = corners(t).map(|v| mesh.positions[v as usize].as_dvec3());
        (b - a).cross(c - a)
    };
    let mut taken = vec![false; triangles.len()];
    let mut pieces = Vec::new();
    for seed in 0..triangles.len() {
        if taken[seed] {
            continue;
        }
        taken[seed] = true;
        let mut region = vec![seed];
        let mut vertices: Vec<u32> = corners(triangles[seed]).to_vec();
        let mut facing = Facing::default();
        facing.add(face(triangles[seed]));
        let mut queue = std::collections::VecDeque::from([seed]);
        // A triangle refused is tried again from each triangle of the region it touches, as
        // the region (and the way it faces) has grown since.
        while let Some(k) = queue.pop_front() {
            for v in corners(triangles[k]) {
                for &n in &by_vertex[&v] {
                    if taken[n] {
                        continue;
                    }
                    let new: Vec<u32> = corners(triangles[n])
                        .into_iter()
                        .filter(|c| !vertices.contains(c))
                        .collect();
                    let mut grown = facing;
                    grown.add(face(triangles[n]));
                    let points: Vec<Vec3> = vertices
                        .iter()
                        .chain(&new)
                        .map(|&c| mesh.positions[c as usize])
                        .collect();
                    if spread_within(&points, grown.normal(), epsilon) {
                        taken[n] = true;
                        region.push(n);
                        vertices.extend(new);
                        facing = grown;
                        queue.push_back(n);
                    }
                }
            }
        }
        region.sort_unstable();
        pieces.push(region.iter().map(|&k| triangles[k]).collect());
    }
    pieces
}

/// The way a region of triangles faces: their normals summed, each weighted by its area and
/// turned to agree with the sum so far (a card and its back face do not cancel out).
#[derive(Clone, Copy, Default)]
struct Facing {
    sum: DVec3,
}

impl Facing {
    /// Adds a triangle by its cross product (twice its area along its normal).
    fn add(&mut self, cross: DVec3) {
        self.sum += if cross.dot(self.sum) < 0.0 {
            -cross
        } else {
            cross
        };
    }

    fn normal(&self) -> DVec3 {
        self.sum.normalize_or(DVec3::Y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of `rows` quads, 0.1 wide, bent along its length into a quarter circle of
    /// radius 1 (in the y–z plane), as [`SkinnedMesh`] triangles (one leaf).
    fn bent_strip(rows: usize) -> SkinnedMesh {
        let mut mesh = SkinnedMesh::empty();
        for i in 0..=rows {
            let a = std::f32::consts::FRAC_PI_2 * i as f32 / rows as f32;
            for x in [-0.05, 0.05] {
                mesh.positions.push(Vec3::new(x, a.sin(), 1.0 - a.cos()));
                mesh.normals.push(Vec3::Z);
                mesh.uvs.push(glam::Vec2::ZERO);
                mesh.materials.push(0);
                mesh.influences.push(crate::model::Influence {
                    bone: 0,
                    weight: 1.0,
                });
                mesh.influence_offsets.push(mesh.influences.len() as u32);
            }
        }
        for i in 0..rows as u32 {
            let a = 2 * i;
            mesh.indices.extend([a, a + 1, a + 3, a, a + 3, a + 2]);
        }
        mesh
    }

    #[test]
    fn a_bent_strip_splits_into_runs_each_within_epsilon_and_a_flat_one_stays_whole() {
        let mesh = bent_strip(16);
        let tris: Vec<u32> = (0..32).collect();
        let leaf = Leaf::of_mesh(&tris, &mesh);
        let foliage = Foliage {
            leaves: vec![leaf],
            bones: vec![3],
            triangles: vec![tris],
            rebound: 0,
        };
        for eps in [0.005, 0.02, 0.08] {
            let split = split_at_bends(&foliage, &mesh, eps);
            let n = split.leaves.len();
            assert!(n > 1, "ε {eps}: {n} pieces");
            // Every triangle in exactly one piece, every piece flat within ε, on the bone.
            let mut all: Vec<u32> = split.triangles.concat();
            all.sort_unstable();
            assert_eq!(all, (0..32).collect::<Vec<u32>>());
            for (l, b) in split.leaves.iter().zip(&split.bones) {
                assert!(flat_within(l, eps), "ε {eps}");
                assert_eq!(*b, 3);
            }
            // Runs along the strip, not scraps: no more than twice the pieces the arc needs
            // (a chord of angle θ on radius 1 strays 1 − cos(θ/2) from its arc).
            let needed = (std::f32::consts::FRAC_PI_2 / (2.0 * (1.0 - eps).acos())).ceil();
            assert!(
                n as f32 <= 2.0 * needed + 1.0,
                "ε {eps}: {n} pieces, {needed} needed"
            );
        }
        // Coarser splits less; a wide ε holds the strip whole.
        let fine = split_at_bends(&foliage, &mesh, 0.005).leaves.len();
        let coarse = split_at_bends(&foliage, &mesh, 0.08).leaves.len();
        assert!(coarse < fine, "{coarse} < {fine}");
        assert!(matches!(
            split_at_bends(&foliage, &mesh, 0.5),
            Cow::Borrowed(_)
        ));
    }

    #[test]
    fn a_leaf_from_triangles_has_their_area_and_a_card_with_its_back_face_does_not_cancel() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let front = [[p[0], p[1], p[2]], [p[0], p[2], p[3]]];
        let leaf = Leaf::from_triangles(p.to_vec(), &front);
        assert!((leaf.area - 1.0).abs() < 1e-6);
        assert!(leaf.normal.distance(Vec3::Z) < 1e-6);
        // The same card written again wound the other way (a back face).
        let both = [front[0], front[1], [p[0], p[2], p[1]], [p[0], p[3], p[2]]];
        let leaf = Leaf::from_triangles(p.to_vec(), &both);
        assert!(leaf.normal.distance(Vec3::Z) < 1e-6, "{}", leaf.normal);
        assert!((leaf.area - 2.0).abs() < 1e-6);
    }
}

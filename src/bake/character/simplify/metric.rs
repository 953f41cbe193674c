//! The deviation the collapses are ranked by (Merry et al. §4): the L2,2 norm of animation
//! space through the expectation matrix `P`, or the Euclidean distance in the rest pose.

use super::expectation::{ExpectationMatrix, quadratic};
use super::influence::Influence64;
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use glam::{Affine3A, DVec3, Vec3};

/// The deviation measure at a cell corner.
pub(super) enum Metric<'a> {
    /// Euclidean distance between rest-pose positions.
    RestPose,
    /// `‖s‖²₂,₂ = sᵀPs`. A corner is a combination `s = Σ c_a p_a` of at most four positions,
    /// whose influences share a few bones: `s` is gathered per bone (`s_j = Σ c_a p_aj`) and
    /// `sᵀPs = Σ_jk s_jᵀ P_jk s_k` takes one 4×4 block of P per pair of those bones. That is
    /// cheaper than the inner products of the positions pairwise, and needs no cache (a cache
    /// of them, keyed by position pair, cost as much in memory traffic as it saved).
    AnimationSpace { pm: &'a ExpectationMatrix },
}

impl Metric<'_> {
    pub(super) fn deviation2(
        &self,
        corner: &[(u32, f64); 4],
        rest: &[DVec3],
        infl: &[Vec<Influence64>],
    ) -> f64 {
        match self {
            Metric::RestPose => corner
                .iter()
                .map(|&(p, c)| rest[p as usize] * c)
                .sum::<DVec3>()
                .length_squared(),
            Metric::AnimationSpace { pm } => {
                let mut gathered: smallvec::SmallVec<[(u32, [f64; 4]); 8]> =
                    smallvec::SmallVec::new();
                for &(a, c) in corner {
                    if c == 0.0 {
                        continue;
                    }
                    for x in &infl[a as usize] {
                        let add = x.p.map(|v| v * c);
                        match gathered.iter_mut().find(|(bone, _)| *bone == x.bone) {
                            Some((_, s)) => (0..4).for_each(|k| s[k] += add[k]),
                            None => gathered.push((x.bone, add)),
                        }
                    }
                }
                // P is symmetric: each pair of bones once, off-diagonal pairs twice.
                let mut sum = 0.0;
                for (i, (j, sj)) in gathered.iter().enumerate() {
                    sum += quadratic(&pm.block(*j, *j), sj, sj);
                    for (k, sk) in &gathered[i + 1..] {
                        sum += 2.0 * quadratic(&pm.block(*j, *k), sj, sk);
                    }
                }
                sum.max(0.0)
            }
        }
    }
}

/// Every vertex's influences in double precision, sorted by bone (the order [`Mesh::new`](super::mesh::Mesh::new)
/// groups wedges by and the factor cache keys on).
pub fn influences64(am: &AnimationSpaceMesh) -> Vec<Vec<Influence64>> {
    (0..am.vertex_count())
        .map(|v| {
            let mut list: Vec<Influence64> = am
                .influences_of(v)
                .iter()
                .map(|i| Influence64 {
                    bone: i.bone,
                    p: i.p.to_array().map(f64::from),
                    n: i.n.to_array().map(f64::from),
                })
                .collect();
            list.sort_by_key(|i| i.bone);
            list
        })
        .collect()
}

/// The rest-pose position of a vertex: `Σ Ĝ_i p_i`.
pub(super) fn rest_position(rest_bones: &[Affine3A], infl: &[Influence64]) -> DVec3 {
    infl.iter()
        .map(|i| {
            let g = &rest_bones[i.bone as usize];
            let m = g.matrix3.to_cols_array().map(|x| x as f64);
            let t = DVec3::from(Vec3::from(g.translation));
            DVec3::new(
                m[0] * i.p[0] + m[3] * i.p[1] + m[6] * i.p[2],
                m[1] * i.p[0] + m[4] * i.p[1] + m[7] * i.p[2],
                m[2] * i.p[0] + m[5] * i.p[1] + m[8] * i.p[2],
            ) + t * i.p[3]
        })
        .sum()
}

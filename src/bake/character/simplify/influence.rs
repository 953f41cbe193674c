//! Influence simplification (Merry, Marais & Gain §5): remove one bone's influence from a
//! vertex and move the remaining ones so that the vertex stays as close as possible to where
//! it was, in the L2,2 metric, over all poses.
//!
//! For a vertex `p` influenced by bones `1..k`, dropping bone `k` replaces `p` by `p + s` with
//! `s` influenced by at most those bones, `s_k = −p_k` (cancel the influence), `s̲ = 0` (the
//! homogeneous parts of `s` sum to zero, so `p + s` is still a point) and `sᵀP̃s` minimal, where
//! `P̃` is the 4k×4k part of the expectation matrix on those bones. With `r` the remaining
//! coordinates and `h` the vector picking their homogeneous parts, that is the equality
//! constrained least squares problem
//!
//! ```text
//!   minimise  s_rᵀ A s_r + 2 s_rᵀ B s_k     (A = P̃_rr, B = P̃_rk, s_k = −p_k)
//!   subject to hᵀ s_r = p_k.w
//! ```
//!
//! whose KKT system `[A h; hᵀ 0] [s_r; μ] = [B p_k; p_k.w]` has a right-hand side linear in
//! `p_k`. So the solution is `s_r = K p_k` for a 4(k−1)×4 matrix `K` that depends only on the
//! bones and which one goes, and the deviation is `‖s‖² = p_kᵀ Q p_k` with `Q = SᵀP̃S`,
//! `S = [K; −I]`. The paper diagonalises `P̃` and projects the origin onto the constraint
//! subspace; the KKT solve is the same minimiser, and caching `K` and `Q` keyed by the
//! influence set and the removed bone (§5, last paragraph) makes every later vertex with that
//! set cost a 4×4 product.
//!
//! `P̃` is singular when a bone never moves (its block has rank 3) or two bones always move
//! together. `A` is then regularised by a small multiple of its mean diagonal, which picks the
//! smallest correction among the equally good ones instead of an arbitrary huge one.
//!
//! Normals (`n_i`, vectors: no homogeneous part) get the same treatment through the 3×3 parts
//! of the blocks and no homogeneous constraint: `s_r = Kn n_k`, `Kn = A₃⁻¹ B₃`.

use super::expectation::ExpectationMatrix;
use lru::LruCache;
use nalgebra::{DMatrix, Matrix4};
use std::num::NonZeroUsize;

/// The paper caches the last 1024 influence sets (§6.3).
pub const CACHE_SIZE: usize = 1024;

/// The cached factorisation for one (influence set, removed bone).
#[derive(Clone, Debug)]
pub struct Factor {
    /// `s_r = K p_k`, 4(k−1)×4, rows in the order of the remaining bones.
    k: DMatrix<f64>,
    /// `‖s‖²₂,₂ = p_kᵀ Q p_k`.
    q: Matrix4<f64>,
    /// Normals: `s_r = Kn n_k`, 3(k−1)×3.
    kn: DMatrix<f64>,
}

/// One influence of a vertex during simplification, in double precision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Influence64 {
    pub bone: u32,
    pub p: [f64; 4],
    pub n: [f64; 3],
}

impl Factor {
    /// Solves the constrained problem for bones `bones` (any order) dropping `bones[removed]`.
    /// `None` if the system is singular even after regularisation.
    pub fn solve(pm: &ExpectationMatrix, bones: &[u32], removed: usize) -> Option<Factor> {
        let k = bones.len();
        if k < 2 || removed >= k {
            return None;
        }
        // Remaining bones first, the removed one last.
        let order: Vec<u32> = (0..k)
            .filter(|&i| i != removed)
            .chain([removed])
            .map(|i| bones[i])
            .collect();
        let n = 4 * k;
        let m = n - 4;
        let mut pt = DMatrix::<f64>::zeros(n, n);
        for (bi, &a) in order.iter().enumerate() {
            for (bj, &b) in order.iter().enumerate() {
                let blk = pm.block(a, b);
                for r in 0..4 {
                    for c in 0..4 {
                        pt[(4 * bi + r, 4 * bj + c)] = blk[r][c];
                    }
                }
            }
        }
        let mean_diag = (0..m).map(|i| pt[(i, i)]).sum::<f64>() / m as f64;
        let lambda = 1e-9 * mean_diag.max(1e-12);

        // Positions: KKT system [A + λI, h; hᵀ, 0] X = [B; e_wᵀ].
        let mut kkt = DMatrix::<f64>::zeros(m + 1, m + 1);
        let mut rhs = DMatrix::<f64>::zeros(m + 1, 4);
        for r in 0..m {
            for c in 0..m {
                kkt[(r, c)] = pt[(r, c)];
            }
            kkt[(r, r)] += lambda;
            if r % 4 == 3 {
                kkt[(r, m)] = 1.0;
                kkt[(m, r)] = 1.0;
            }
            for c in 0..4 {
                rhs[(r, c)] = pt[(r, m + c)];
            }
        }
        rhs[(m, 3)] = 1.0;
        let x = kkt.lu().solve(&rhs)?;
        let kmat = x.rows(0, m).into_owned();
        if kmat.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let mut s = DMatrix::<f64>::zeros(n, 4);
        s.rows_mut(0, m).copy_from(&kmat);
        for c in 0..4 {
            s[(m + c, c)] = -1.0;
        }
        let qd = s.transpose() * &pt * &s;
        let q = Matrix4::from_fn(|r, c| 0.5 * (qd[(r, c)] + qd[(c, r)]));

        // Normals: (A₃ + λI) Kn = B₃ on the 3×3 parts of the blocks.
        let m3 = 3 * (k - 1);
        let mut a3 = DMatrix::<f64>::zeros(m3, m3);
        let mut b3 = DMatrix::<f64>::zeros(m3, 3);
        for bi in 0..k - 1 {
            for r in 0..3 {
                for bj in 0..k - 1 {
                    for c in 0..3 {
                        a3[(3 * bi + r, 3 * bj + c)] = pt[(4 * bi + r, 4 * bj + c)];
                    }
                }
                a3[(3 * bi + r, 3 * bi + r)] += lambda;
                for c in 0..3 {
                    b3[(3 * bi + r, c)] = pt[(4 * bi + r, m + c)];
                }
            }
        }
        let kn = a3.lu().solve(&b3)?;
        if kn.iter().any(|v| !v.is_finite()) {
            return None;
        }
        Some(Factor { k: kmat, q, kn })
    }

    /// `‖s‖₂,₂` of removing an influence whose animation-space position is `p`.
    pub fn deviation(&self, p: &[f64; 4]) -> f64 {
        let v = nalgebra::Vector4::from_column_slice(p);
        (v.transpose() * self.q * v)[(0, 0)].max(0.0).sqrt()
    }

    /// The vertex after the removal: the remaining influences, moved.
    /// `influences[removed]` is the one that goes; the others keep their order.
    pub fn apply(&self, influences: &[Influence64], removed: usize) -> Vec<Influence64> {
        let pk = influences[removed].p;
        let nk = influences[removed].n;
        let mut out = Vec::with_capacity(influences.len() - 1);
        for (slot, inf) in influences
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != removed)
            .map(|(_, inf)| inf)
            .enumerate()
        {
            let mut next = *inf;
            for r in 0..4 {
                next.p[r] += (0..4)
                    .map(|c| self.k[(4 * slot + r, c)] * pk[c])
                    .sum::<f64>();
            }
            for r in 0..3 {
                next.n[r] += (0..3)
                    .map(|c| self.kn[(3 * slot + r, c)] * nk[c])
                    .sum::<f64>();
            }
            out.push(next);
        }
        out
    }
}

/// Factorisations of the last [`CACHE_SIZE`] (influence set, removed bone) pairs, least
/// recently used first out.
pub struct FactorCache {
    lru: LruCache<Vec<u32>, Option<Factor>>,
    pub hits: u64,
    pub misses: u64,
}

impl Default for FactorCache {
    fn default() -> Self {
        FactorCache {
            lru: LruCache::new(NonZeroUsize::new(CACHE_SIZE).expect("non-zero")),
            hits: 0,
            misses: 0,
        }
    }
}

impl FactorCache {
    /// The factor for dropping `bones[removed]`; `bones` must be in a canonical (sorted) order
    /// for the cache to recognise a set.
    pub fn get(
        &mut self,
        pm: &ExpectationMatrix,
        bones: &[u32],
        removed: usize,
    ) -> Option<&Factor> {
        let mut key = Vec::with_capacity(bones.len() + 1);
        key.extend_from_slice(bones);
        key.push(removed as u32);
        if self.lru.contains(&key) {
            self.hits += 1;
        } else {
            self.misses += 1;
            let factor = Factor::solve(pm, bones, removed);
            self.lru.put(key.clone(), factor);
        }
        self.lru.get(&key).and_then(|f| f.as_ref())
    }

    pub fn hit_rate(&self) -> Option<f64> {
        let total = self.hits + self.misses;
        (total > 0).then(|| self.hits as f64 / total as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Affine3A, Quat, Vec3};

    /// Three bones in a chain bending over many poses; the third sometimes lags the second.
    fn matrix() -> ExpectationMatrix {
        let poses: Vec<Vec<Affine3A>> = (0..64)
            .map(|i| {
                let a = (i as f32 * 0.37).sin() * 0.8;
                let b = (i as f32 * 0.23).cos() * 0.6;
                let g0 = Affine3A::IDENTITY;
                let g1 = Affine3A::from_rotation_translation(Quat::from_rotation_z(a), Vec3::Y);
                let g2 =
                    g1 * Affine3A::from_rotation_translation(Quat::from_rotation_x(b), Vec3::Y);
                vec![g0, g1, g2]
            })
            .collect();
        ExpectationMatrix::from_poses(3, &poses)
    }

    fn vertex() -> Vec<Influence64> {
        // p_i = w_i Ĝ_i⁻¹ v̂ for v̂ = (0.1, 1.2, 0.05), rest bones at y = 0, 1, 2.
        let v = [0.1, 1.2, 0.05];
        let w = [0.2, 0.5, 0.3];
        (0..3)
            .map(|i| Influence64 {
                bone: i as u32,
                p: [w[i] * v[0], w[i] * (v[1] - i as f64), w[i] * v[2], w[i]],
                n: [0.0, 0.0, w[i]],
            })
            .collect()
    }

    fn sparse(infl: &[Influence64]) -> Vec<(u32, [f64; 4])> {
        infl.iter().map(|i| (i.bone, i.p)).collect()
    }

    fn difference(a: &[Influence64], b: &[Influence64]) -> Vec<(u32, [f64; 4])> {
        let mut s = sparse(a);
        for (bone, p) in sparse(b) {
            match s.iter_mut().find(|(x, _)| *x == bone) {
                Some((_, q)) => (0..4).for_each(|c| q[c] -= p[c]),
                None => s.push((bone, p.map(|x| -x))),
            }
        }
        s
    }

    #[test]
    fn solution_keeps_constraints_and_beats_renormalised_weights() {
        let pm = matrix();
        let v = vertex();
        for removed in 0..3 {
            let bones: Vec<u32> = v.iter().map(|i| i.bone).collect();
            let f = Factor::solve(&pm, &bones, removed).expect("solvable");
            let next = f.apply(&v, removed);
            assert_eq!(next.len(), 2);
            assert!(next.iter().all(|i| i.bone != removed as u32));
            // Homogeneous parts still sum to one: the vertex is still a point.
            let w: f64 = next.iter().map(|i| i.p[3]).sum();
            assert!((w - 1.0).abs() < 1e-9, "homogeneous sum {w}");
            // The deviation the factor predicts is the one the vertex sees.
            let optimal = pm.norm2(&difference(&next, &v)).sqrt();
            let predicted = f.deviation(&v[removed].p);
            assert!(
                (optimal - predicted).abs() < 1e-7,
                "removing {removed}: {optimal} vs predicted {predicted}"
            );
            // The trivial removal: drop the weight and renormalise the rest.
            let wk = v[removed].p[3];
            let trivial: Vec<Influence64> = v
                .iter()
                .enumerate()
                .filter(|&(i, _)| i != removed)
                .map(|(_, i)| Influence64 {
                    p: i.p.map(|x| x / (1.0 - wk)),
                    ..*i
                })
                .collect();
            let naive = pm.norm2(&difference(&trivial, &v)).sqrt();
            assert!(
                optimal < naive,
                "removing bone {removed}: optimal {optimal} not below renormalised {naive}"
            );
        }
    }

    #[test]
    fn a_bone_that_never_moves_is_regularised() {
        // Bone 1 is fixed in every pose, and bone 2 moves exactly with bone 0: P is singular.
        let poses: Vec<Vec<Affine3A>> = (0..32)
            .map(|i| {
                let g = Affine3A::from_rotation_z(i as f32 * 0.1);
                vec![g, Affine3A::IDENTITY, g]
            })
            .collect();
        let pm = ExpectationMatrix::from_poses(3, &poses);
        let v = vertex();
        for removed in 0..3 {
            let f = Factor::solve(&pm, &[0, 1, 2], removed).expect("regularised");
            let next = f.apply(&v, removed);
            assert!(next.iter().all(|i| i.p.iter().all(|x| x.is_finite())));
            let w: f64 = next.iter().map(|i| i.p[3]).sum();
            assert!((w - 1.0).abs() < 1e-6);
        }
        // Bones 0 and 2 move together, so dropping 2 onto 0 is free.
        let f = Factor::solve(&pm, &[0, 1, 2], 2).unwrap();
        assert!(f.deviation(&v[2].p) < 1e-4, "{}", f.deviation(&v[2].p));
    }

    #[test]
    fn cache_counts_hits_and_misses() {
        let pm = matrix();
        let mut cache = FactorCache::default();
        for _ in 0..3 {
            assert!(cache.get(&pm, &[0, 1, 2], 1).is_some());
        }
        assert!(cache.get(&pm, &[0, 1], 0).is_some());
        assert_eq!((cache.hits, cache.misses), (2, 2));
        assert_eq!(cache.hit_rate(), Some(0.5));
    }
}

//! The expectation matrix `P = E[GᵀG]` of Merry, Marais & Gain §2.1.2, equation 3.
//!
//! `G = (G_1 … G_b)` is the 3×4b animation projection matrix of one pose, so `P` is a symmetric
//! 4b×4b matrix of 4×4 blocks `P_ij = E[G_iᵀ G_j]`, and the L2,2 norm of an animation-space
//! vector is `‖s‖²₂,₂ = sᵀPs`: the mean over poses of the squared distance `|Gs|²`. `P` depends
//! only on the distribution of poses, not on the mesh, so it is estimated once, here from
//! evenly resampled frames of every clip, and every metric evaluation after that costs the
//! same however many poses went in.

use crate::anim::bone_matrices;
use crate::model::Model;
use glam::Affine3A;
use serde::{Deserialize, Serialize};

/// Samples taken from the clips for the simplifier's metric: at least this many in all.
pub const MIN_SAMPLES: usize = 1024;

/// A 4×4 block of `P`, row-major.
pub type Block = [[f64; 4]; 4];

/// `P = E[GᵀG]`, stored as `bones × bones` blocks.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExpectationMatrix {
    pub bones: usize,
    /// `P_ij` at `blocks[i * bones + j]`.
    pub blocks: Vec<Block>,
    /// How many poses the estimate averages.
    pub samples: usize,
}

/// A sparse animation-space vector: one 4-vector per influencing bone.
pub type SparseAs = [(u32, [f64; 4])];

impl ExpectationMatrix {
    /// Estimates `P` from `MIN_SAMPLES` poses spread evenly over the clips of `model` (each clip
    /// weighted the same, sampled at the centres of equal time steps so a looping clip's end and
    /// start are not counted twice). A model without clips gets its rest pose.
    pub fn estimate(model: &Model) -> Self {
        let skel = &model.skeleton;
        if model.clips.is_empty() {
            return Self::from_poses(skel.bone_count(), [bone_matrices(skel, None, 0.0)]);
        }
        let per_clip = MIN_SAMPLES.div_ceil(model.clips.len());
        let poses = model.clips.iter().flat_map(|clip| {
            (0..per_clip).map(move |k| {
                let t = clip.duration.max(0.0) * (k as f32 + 0.5) / per_clip as f32;
                bone_matrices(skel, Some(clip), t)
            })
        });
        Self::from_poses(skel.bone_count(), poses)
    }

    /// The mean of `GᵀG` over the given poses (each a list of bone matrices `G_i`).
    pub fn from_poses<I>(bones: usize, poses: I) -> Self
    where
        I: IntoIterator,
        I::Item: AsRef<[Affine3A]>,
    {
        let mut blocks = vec![[[0.0f64; 4]; 4]; bones * bones];
        let mut samples = 0usize;
        let mut g = vec![[[0.0f64; 4]; 3]; bones];
        for pose in poses {
            let pose = pose.as_ref();
            for (gi, m) in g.iter_mut().zip(pose) {
                let c = m.matrix3.to_cols_array();
                let t = m.translation;
                // Row r of the 3×4 matrix [R | t].
                for (r, row) in gi.iter_mut().enumerate() {
                    *row = [c[r] as f64, c[3 + r] as f64, c[6 + r] as f64, t[r] as f64];
                }
            }
            // Only the upper triangle of blocks; the lower is its transpose.
            for i in 0..bones {
                for j in i..bones {
                    let b = &mut blocks[i * bones + j];
                    for (a, row_b) in b.iter_mut().enumerate() {
                        for (c, x) in row_b.iter_mut().enumerate() {
                            *x += g[i][0][a] * g[j][0][c]
                                + g[i][1][a] * g[j][1][c]
                                + g[i][2][a] * g[j][2][c];
                        }
                    }
                }
            }
            samples += 1;
        }
        let scale = 1.0 / samples.max(1) as f64;
        for i in 0..bones {
            for j in i..bones {
                let mut b = blocks[i * bones + j];
                for row in &mut b {
                    for x in row.iter_mut() {
                        *x *= scale;
                    }
                }
                blocks[i * bones + j] = b;
                blocks[j * bones + i] = transpose(&b);
            }
        }
        ExpectationMatrix {
            bones,
            blocks,
            samples,
        }
    }

    pub fn block(&self, i: u32, j: u32) -> &Block {
        &self.blocks[i as usize * self.bones + j as usize]
    }

    /// `aᵀ P b` for two sparse animation-space vectors.
    pub fn inner(&self, a: &SparseAs, b: &SparseAs) -> f64 {
        let mut sum = 0.0;
        for &(i, x) in a {
            for &(j, y) in b {
                sum += quadratic(self.block(i, j), &x, &y);
            }
        }
        sum
    }

    /// `‖s‖²₂,₂ = sᵀPs` (equation 3).
    pub fn norm2(&self, s: &SparseAs) -> f64 {
        self.inner(s, s).max(0.0)
    }
}

/// `xᵀ B y`.
pub fn quadratic(b: &Block, x: &[f64; 4], y: &[f64; 4]) -> f64 {
    let mut sum = 0.0;
    for r in 0..4 {
        sum += x[r] * (b[r][0] * y[0] + b[r][1] * y[1] + b[r][2] * y[2] + b[r][3] * y[3]);
    }
    sum
}

fn transpose(b: &Block) -> Block {
    let mut t = [[0.0; 4]; 4];
    for (r, row) in b.iter().enumerate() {
        for (c, x) in row.iter().enumerate() {
            t[c][r] = *x;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3};

    #[test]
    fn norm_is_mean_squared_distance_over_poses() {
        let poses = [
            vec![
                Affine3A::IDENTITY,
                Affine3A::from_translation(Vec3::new(1.0, 0.0, 0.0)),
            ],
            vec![
                Affine3A::from_rotation_translation(Quat::from_rotation_z(0.7), Vec3::Y),
                Affine3A::from_scale(Vec3::splat(2.0)),
            ],
        ];
        let p = ExpectationMatrix::from_poses(2, &poses);
        let s: Vec<(u32, [f64; 4])> = vec![(0, [0.3, -0.2, 0.1, 0.5]), (1, [0.1, 0.4, -0.3, -0.5])];
        let mean: f64 = poses
            .iter()
            .map(|g| {
                let v: Vec3 = s
                    .iter()
                    .map(|&(b, x)| {
                        let x = glam::Vec4::new(x[0] as f32, x[1] as f32, x[2] as f32, x[3] as f32);
                        crate::bake::animation_space::transform_homogeneous(&g[b as usize], x)
                    })
                    .sum();
                v.length_squared() as f64
            })
            .sum::<f64>()
            / 2.0;
        assert!(
            (p.norm2(&s) - mean).abs() < 1e-5,
            "{} vs {mean}",
            p.norm2(&s)
        );
        assert_eq!(p.samples, 2);
    }
}

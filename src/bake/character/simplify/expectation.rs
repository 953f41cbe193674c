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
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::sync::RwLock;

/// Samples taken from the clips for the simplifier's metric: at least this many in all.
pub const MIN_SAMPLES: usize = 1024;

/// Skeletons up to this many bones get every block of `P` up front: 128 bytes a pair, 8 MiB at
/// this size. Past it the whole matrix grows with bones² (a 5,000-joint skin asked for 3.2 GB
/// and minutes of sums), while a mesh only ever pairs bones that influence nearby positions, so
/// blocks are summed when first asked for and kept.
pub const DENSE_BONES: usize = 256;

/// A 4×4 block of `P`, row-major.
pub type Block = [[f64; 4]; 4];

/// `P = E[GᵀG]`: a symmetric 4b×4b matrix of 4×4 blocks.
#[derive(Debug)]
pub struct ExpectationMatrix {
    pub bones: usize,
    /// How many poses the estimate averages.
    pub samples: usize,
    store: Store,
}

#[derive(Debug)]
enum Store {
    /// `P_ij` at `[i * bones + j]`.
    Dense(Vec<Block>),
    /// The poses' rows, bone by bone (`rows[bone * samples + s]`: the 3×4 matrix `G_bone` of pose
    /// `s`, row-major), and the blocks summed from them so far, keyed by `(i, j)` with `i ≤ j`
    /// and spread over a few locks so the simplifier's parallel pricing rarely waits.
    Lazy {
        rows: Vec<[f32; 12]>,
        blocks: Box<[Shard]>,
    },
}

/// Some of the lazily summed blocks, behind one lock.
type Shard = RwLock<FxHashMap<(u32, u32), Block>>;

/// Locks the lazily summed blocks are spread over.
const SHARDS: usize = 16;

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
        Self::with_dense_limit(bones, poses, DENSE_BONES)
    }

    /// As [`Self::from_poses`], summing every block up front only if `bones ≤ dense_bones`.
    pub fn with_dense_limit<I>(bones: usize, poses: I, dense_bones: usize) -> Self
    where
        I: IntoIterator,
        I::Item: AsRef<[Affine3A]>,
    {
        // Pose-major while gathering; transposed to bone-major below.
        let mut gathered: Vec<[f32; 12]> = Vec::new();
        let mut samples = 0usize;
        for pose in poses {
            let pose = pose.as_ref();
            gathered.extend((0..bones).map(|b| rows_of(pose.get(b))));
            samples += 1;
        }
        let mut rows = vec![[0.0f32; 12]; gathered.len()];
        for s in 0..samples {
            for b in 0..bones {
                rows[b * samples + s] = gathered[s * bones + b];
            }
        }
        drop(gathered);
        let mut p = ExpectationMatrix {
            bones,
            samples,
            store: Store::Lazy {
                rows,
                blocks: (0..SHARDS).map(|_| RwLock::default()).collect(),
            },
        };
        if bones <= dense_bones {
            // Only the upper triangle is summed; the lower is its transpose.
            let upper: Vec<Vec<Block>> = (0..bones)
                .into_par_iter()
                .map(|i| (i..bones).map(|j| p.sum_block(i, j)).collect())
                .collect();
            let mut dense = vec![[[0.0f64; 4]; 4]; bones * bones];
            for (i, row) in upper.iter().enumerate() {
                for (j, b) in (i..bones).zip(row) {
                    dense[i * bones + j] = *b;
                    dense[j * bones + i] = transpose(b);
                }
            }
            p.store = Store::Dense(dense);
        }
        p
    }

    /// `E[G_iᵀ G_j]` from the stored rows.
    fn sum_block(&self, i: usize, j: usize) -> Block {
        let Store::Lazy { rows, .. } = &self.store else {
            unreachable!("blocks are summed before the rows are dropped")
        };
        let n = self.samples;
        let mut b = [[0.0f64; 4]; 4];
        for (gi, gj) in rows[i * n..(i + 1) * n]
            .iter()
            .zip(&rows[j * n..(j + 1) * n])
        {
            let gi = gi.map(f64::from);
            let gj = gj.map(f64::from);
            for (a, row) in b.iter_mut().enumerate() {
                for (c, x) in row.iter_mut().enumerate() {
                    *x += gi[a] * gj[c] + gi[4 + a] * gj[4 + c] + gi[8 + a] * gj[8 + c];
                }
            }
        }
        let scale = 1.0 / n.max(1) as f64;
        b.map(|row| row.map(|x| x * scale))
    }

    /// `P_ij`.
    pub fn block(&self, i: u32, j: u32) -> Block {
        match &self.store {
            Store::Dense(blocks) => blocks[i as usize * self.bones + j as usize],
            Store::Lazy { blocks, .. } => {
                let key = (i.min(j), i.max(j));
                let shard = &blocks[(key.0 as usize * 31 + key.1 as usize) % SHARDS];
                let upper = shard.read().unwrap().get(&key).copied();
                let upper = upper.unwrap_or_else(|| {
                    let b = self.sum_block(key.0 as usize, key.1 as usize);
                    shard.write().unwrap().insert(key, b);
                    b
                });
                if i <= j { upper } else { transpose(&upper) }
            }
        }
    }

    /// How many blocks are held: `bones²` when dense, else those asked for so far.
    pub fn blocks_held(&self) -> usize {
        match &self.store {
            Store::Dense(blocks) => blocks.len(),
            Store::Lazy { blocks, .. } => blocks.iter().map(|s| s.read().unwrap().len()).sum(),
        }
    }

    /// `aᵀ P b` for two sparse animation-space vectors.
    pub fn inner(&self, a: &SparseAs, b: &SparseAs) -> f64 {
        let mut sum = 0.0;
        for &(i, x) in a {
            for &(j, y) in b {
                sum += quadratic(&self.block(i, j), &x, &y);
            }
        }
        sum
    }

    /// `‖s‖²₂,₂ = sᵀPs` (equation 3).
    pub fn norm2(&self, s: &SparseAs) -> f64 {
        self.inner(s, s).max(0.0)
    }

    /// The largest `‖x − c‖²₂,₂` over `points`, `c` their mean. Through the blocks of `P` that
    /// pairs every bone of the points with every other, so on a lazily held `P` (a large
    /// skeleton, where a body part has hundreds of bones) it is summed over the poses instead:
    /// `‖x − c‖² = E[|Gx − Gc|²]`, and `Gc` is the mean of the posed points.
    pub fn max_spread2(&self, points: &[Vec<(u32, [f64; 4])>]) -> f64 {
        if points.is_empty() {
            return 0.0;
        }
        let weight = 1.0 / points.len() as f64;
        match &self.store {
            Store::Dense(_) => {
                let mut centre: Vec<(u32, [f64; 4])> = Vec::new();
                for x in points {
                    for &(bone, p) in x {
                        let p = p.map(|v| v * weight);
                        match centre.iter_mut().find(|c| c.0 == bone) {
                            Some(c) => (0..4).for_each(|k| c.1[k] += p[k]),
                            None => centre.push((bone, p)),
                        }
                    }
                }
                let cc = self.inner(&centre, &centre);
                points
                    .iter()
                    .map(|x| self.inner(x, x) - 2.0 * self.inner(x, &centre) + cc)
                    .fold(0.0, f64::max)
            }
            Store::Lazy { rows, .. } => {
                let n = self.samples;
                let posed = |x: &[(u32, [f64; 4])], s: usize| {
                    let mut y = [0.0f64; 3];
                    for &(bone, p) in x {
                        let g = rows[bone as usize * n + s].map(f64::from);
                        for (r, y) in y.iter_mut().enumerate() {
                            *y += g[4 * r] * p[0]
                                + g[4 * r + 1] * p[1]
                                + g[4 * r + 2] * p[2]
                                + g[4 * r + 3] * p[3];
                        }
                    }
                    y
                };
                let centres: Vec<[f64; 3]> = (0..n)
                    .into_par_iter()
                    .map(|s| {
                        let mut c = [0.0; 3];
                        for x in points {
                            let y = posed(x, s);
                            (0..3).for_each(|k| c[k] += y[k] * weight);
                        }
                        c
                    })
                    .collect();
                points
                    .par_iter()
                    .map(|x| {
                        let sum: f64 = (0..n)
                            .map(|s| {
                                let y = posed(x, s);
                                (0..3).map(|k| (y[k] - centres[s][k]).powi(2)).sum::<f64>()
                            })
                            .sum();
                        sum / n.max(1) as f64
                    })
                    .reduce(|| 0.0, f64::max)
            }
        }
    }
}

/// The 3×4 matrix `[R | t]` of a bone, row-major; a bone the pose lacks is zero.
fn rows_of(m: Option<&Affine3A>) -> [f32; 12] {
    let Some(m) = m else { return [0.0; 12] };
    let c = m.matrix3.to_cols_array();
    let t = m.translation;
    [
        c[0], c[3], c[6], t[0], c[1], c[4], c[7], t[1], c[2], c[5], c[8], t[2],
    ]
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
                        crate::bake::gpu_data::animation_space::transform_homogeneous(
                            &g[b as usize],
                            x,
                        )
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

    /// A large skeleton sums blocks only when asked, and they equal the ones summed up front.
    #[test]
    fn lazy_blocks_equal_dense_ones() {
        let bones = 40;
        let poses: Vec<Vec<Affine3A>> = (0..7)
            .map(|s| {
                (0..bones)
                    .map(|b| {
                        let a = (s * bones + b) as f32 * 0.37;
                        Affine3A::from_rotation_translation(
                            Quat::from_euler(glam::EulerRot::XYZ, a, a * 0.5, -a),
                            Vec3::new(a.sin(), b as f32 * 0.1, a.cos()),
                        )
                    })
                    .collect()
            })
            .collect();
        let dense = ExpectationMatrix::with_dense_limit(bones, &poses, bones);
        let lazy = ExpectationMatrix::with_dense_limit(bones, &poses, 0);
        assert_eq!(dense.blocks_held(), bones * bones);
        assert_eq!(lazy.blocks_held(), 0);
        for (i, j) in [(0, 0), (3, 17), (17, 3), (39, 38), (5, 5)] {
            assert_eq!(dense.block(i, j), lazy.block(i, j), "block ({i}, {j})");
        }
        // (3, 17) and (17, 3) share one stored block.
        assert_eq!(lazy.blocks_held(), 4);
        let s: Vec<(u32, [f64; 4])> = vec![(2, [0.3, -0.2, 0.1, 0.5]), (30, [0.1, 0.4, -0.3, 0.5])];
        assert_eq!(dense.norm2(&s), lazy.norm2(&s));

        // The spread of a part, through the blocks and through the poses.
        let points: Vec<Vec<(u32, [f64; 4])>> = (0..12u32)
            .map(|v| {
                let f = v as f64;
                vec![
                    (v * 3, [0.1 * f, -0.2, 0.3, 0.6]),
                    (v * 3 + 1, [0.2, 0.05 * f, -0.1, 0.4]),
                ]
            })
            .collect();
        let held = lazy.blocks_held();
        let (a, b) = (dense.max_spread2(&points), lazy.max_spread2(&points));
        assert!(a > 0.01 && (a - b).abs() < 1e-9 * a, "{a} vs {b}");
        assert_eq!(
            lazy.blocks_held(),
            held,
            "the poses, not the blocks, gave the spread"
        );
    }
}

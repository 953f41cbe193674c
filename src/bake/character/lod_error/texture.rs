//! The correspondence through the parameterisation (appearance-preserving simplification):
//! a point at texture coordinate `u` in chart `c` against the simplified mesh's point at the
//! same `u` in the same chart, its difference kept in animation space.

use super::MeshError;
use super::animation_frames;
use super::geometry::Surface;
use crate::bake::character::simplify::expectation::ExpectationMatrix;
use crate::bake::character::uv_grid::UvGrid;
use crate::bake::gpu_data::animation_space::{AnimationSpaceMesh, AsInfluence};
use crate::model::Model;
use glam::{Affine3A, DVec2, DVec3, Vec2};

/// A sparse animation-space vector: one 4-vector per bone.
type SparseVec = Vec<(u32, [f64; 4])>;

struct Sample {
    chart: u32,
    uv: DVec2,
    /// The original surface point in animation space, and in the rest pose.
    value: SparseVec,
    rest: DVec3,
}

/// Surface samples of the original mesh and the poses to measure them in.
pub struct ErrorProbe {
    samples: Vec<Sample>,
    chart: Vec<u32>,
    uvs: Vec<Vec2>,
    rest_bones: Vec<Affine3A>,
    frames_p: ExpectationMatrix,
    frames: Vec<Vec<Affine3A>>,
}

/// Samples whose worst frame is looked for when taking the maximum: the ones with the largest
/// RMS error over frames.
const MAX_CANDIDATES: usize = 64;

impl ErrorProbe {
    /// `count` samples of `base` (the full-detail mesh of `model`), from a fixed seed. Fails if
    /// the mesh has no texture coordinates to make points correspond through.
    pub fn new(model: &Model, base: &AnimationSpaceMesh, count: usize) -> Result<Self, String> {
        let n = base.vertex_count();
        // Charts: triangles joined through shared render vertices.
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(p: &mut [u32], mut x: u32) -> u32 {
            while p[x as usize] != x {
                p[x as usize] = p[p[x as usize] as usize];
                x = p[x as usize];
            }
            x
        }
        for t in base.indices.chunks_exact(3) {
            let a = find(&mut parent, t[0]);
            for &v in &t[1..] {
                let b = find(&mut parent, v);
                parent[b as usize] = a;
            }
        }
        let chart: Vec<u32> = (0..n as u32).map(|v| find(&mut parent, v)).collect();

        // Rest-pose areas, for area-weighted sampling; triangles flat in texture space have no
        // parameterisation to correspond through and are left out.
        let rest_bones =
            crate::bake::character::simplify::SimplifyInput::rest_bones(&model.skeleton);
        let rest = base.rest_positions(&rest_bones);
        let mut cumulative = Vec::with_capacity(base.triangle_count());
        let mut total = 0.0f64;
        let mut with_uv_area = 0usize;
        for t in base.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|v| v as usize);
            let uv_area = (base.uvs[b] - base.uvs[a]).perp_dot(base.uvs[c] - base.uvs[a]);
            if uv_area.abs() > 1e-12 {
                with_uv_area += 1;
                total += 0.5 * (rest[b] - rest[a]).cross(rest[c] - rest[a]).length() as f64;
            }
            cumulative.push(total);
        }
        if with_uv_area * 2 < base.triangle_count() || total <= 0.0 {
            return Err(
                "has no texture coordinates, so points of a simplified mesh cannot be matched \
                 to the original through the parameterisation"
                    .into(),
            );
        }
        let mut rng = fastrand::Rng::with_seed(0x10d1ab);
        let samples = (0..count)
            .map(|_| {
                let x = rng.f64() * total;
                let t = cumulative
                    .partition_point(|&c| c <= x)
                    .min(cumulative.len() - 1);
                let tri = &base.indices[3 * t..3 * t + 3];
                let (r1, r2) = (rng.f64().sqrt(), rng.f64());
                let w = [1.0 - r1, r1 * (1.0 - r2), r1 * r2];
                let mut uv = DVec2::ZERO;
                let mut value: SparseVec = Vec::new();
                for (k, &v) in tri.iter().enumerate() {
                    uv += base.uvs[v as usize].as_dvec2() * w[k];
                    accumulate(&mut value, base.influences_of(v as usize), w[k]);
                }
                Sample {
                    chart: chart[tri[0] as usize],
                    uv,
                    rest: rest_point(&rest_bones, &value),
                    value,
                }
            })
            .collect();

        let frames = animation_frames(model);
        let frames_p = ExpectationMatrix::from_poses(model.skeleton.bone_count(), &frames);
        Ok(ErrorProbe {
            samples,
            chart,
            uvs: base.uvs.clone(),
            rest_bones,
            frames_p,
            frames,
        })
    }

    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// The error of a simplified mesh given as triangles of the original's render vertices,
    /// each vertex with its (possibly simplified) influences.
    ///
    /// A sample whose chart the mesh has lost (a part pruned, a small island collapsed away)
    /// has nothing at its texture coordinate: it is matched to the mesh's closest point in the
    /// rest pose, where its pixels now fall. (It was matched to the first corner of the first
    /// triangle listed, a point anywhere on the body that moved with the order of the file.)
    pub fn measure<'a>(
        &self,
        triangles: &[[u32; 3]],
        influences: impl Fn(u32) -> &'a [AsInfluence],
    ) -> MeshError {
        let grid = UvGrid::new(triangles, &self.uvs);
        let surface = std::cell::OnceCell::new();
        let rest_of = |r: u32| {
            let mut value: SparseVec = Vec::new();
            accumulate(&mut value, influences(r), 1.0);
            rest_point(&self.rest_bones, &value)
        };
        let diffs = self
            .samples
            .iter()
            .map(|s| {
                let mut diff = s.value.clone();
                let located = grid
                    .locate(triangles, &self.uvs, &self.chart, s.chart, s.uv)
                    .or_else(|| {
                        surface
                            .get_or_init(|| Surface::new(triangles, rest_of))
                            .closest(s.rest)
                    });
                // No triangle at all: the whole point is the error.
                if let Some((tri, w)) = located {
                    for k in 0..3 {
                        accumulate(&mut diff, influences(tri[k]), -w[k]);
                    }
                }
                diff
            })
            .collect();
        summarise(&self.frames_p, &self.frames, diffs)
    }
}

/// `Σ G_i p_i` in the rest pose.
fn rest_point(rest_bones: &[Affine3A], value: &SparseVec) -> DVec3 {
    value
        .iter()
        .map(|&(bone, p)| {
            let m = rest_bones[bone as usize];
            m.matrix3.as_dmat3() * DVec3::new(p[0], p[1], p[2]) + m.translation.as_dvec3() * p[3]
        })
        .sum()
}

/// Differences in animation space, one per sample → RMS over samples and frames, and the
/// maximum over the worst samples' frames.
fn summarise(
    frames_p: &ExpectationMatrix,
    frames: &[Vec<Affine3A>],
    diffs: Vec<SparseVec>,
) -> MeshError {
    let mut per_sample: Vec<(f64, SparseVec)> =
        diffs.into_iter().map(|d| (frames_p.norm2(&d), d)).collect();
    let sum: f64 = per_sample.iter().map(|p| p.0).sum();
    let count = per_sample.len().max(1);
    // The worst frame of the samples worst on average.
    per_sample.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut max2: f64 = 0.0;
    for (_, diff) in per_sample.iter().take(MAX_CANDIDATES) {
        for g in frames {
            max2 = max2.max(posed_length2(g, diff));
        }
    }
    MeshError {
        rms: (sum / count as f64).sqrt(),
        max: max2.sqrt(),
    }
}

/// `|Σ G_i s_i|²` in one pose.
fn posed_length2(g: &[Affine3A], diff: &SparseVec) -> f64 {
    let mut v = [0.0f64; 3];
    for &(bone, p) in diff {
        let m = &g[bone as usize];
        let c = m.matrix3.to_cols_array();
        let t = m.translation;
        for r in 0..3 {
            v[r] += c[r] as f64 * p[0]
                + c[3 + r] as f64 * p[1]
                + c[6 + r] as f64 * p[2]
                + t[r] as f64 * p[3];
        }
    }
    v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
}

/// `acc += w · influences`, merging by bone.
fn accumulate(acc: &mut SparseVec, influences: &[AsInfluence], w: f64) {
    for i in influences {
        let p = i.p.to_array().map(|x| x as f64 * w);
        match acc.iter_mut().find(|(b, _)| *b == i.bone) {
            Some((_, q)) => (0..4).for_each(|c| q[c] += p[c]),
            None => acc.push((i.bone, p)),
        }
    }
}

//! Measuring how far a simplified character is from the original, over its whole animation
//! (the error of Merry et al. §6.1, Figure 7).
//!
//! Two correspondences between the original surface and a simplified one:
//! - [`ErrorProbe`], through the parameterisation, as in appearance-preserving simplification:
//!   a point of the original surface at texture coordinate `u` in chart `c` is compared with
//!   the point of the simplified mesh at the same `u` in the same chart. It needs texture
//!   coordinates that are a parameterisation.
//! - [`SurfaceProbe`], geometric: every sample point corresponds to the closest point of the
//!   other surface in the rest pose, both ways (original to simplified, which sees holes and
//!   shrinkage, and simplified to original, which sees spikes and slivers: a two-sided,
//!   sampled Hausdorff distance), and the two points are then compared in every frame. It
//!   needs nothing but the surfaces, and it is what a silhouette shows.
//!
//! Points are drawn area-weighted. The RMS over all frames of a difference `s` in animation
//! space is `sqrt(sᵀ P s)` with `P` estimated from exactly those frames, so the RMS error over
//! samples and frames is `sqrt(mean_samples(sᵀ P s))`. The maximum is over samples and frames.

use super::animation_space::{AnimationSpaceMesh, AsInfluence};
use super::simplify::expectation::ExpectationMatrix;
use crate::anim::bone_matrices;
use crate::bake::anim_texture::DEFAULT_RATE;
use crate::model::Model;
use glam::{Affine3A, DVec2, DVec3, Vec2};
use serde::Serialize;

/// The error of one simplified mesh, in scene units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MeshError {
    pub rms: f64,
    pub max: f64,
}

/// A sparse animation-space vector: one 4-vector per bone.
type SparseVec = Vec<(u32, [f64; 4])>;

struct Sample {
    chart: u32,
    uv: DVec2,
    /// The original surface point in animation space.
    value: SparseVec,
}

/// Surface samples of the original mesh and the poses to measure them in.
pub struct ErrorProbe {
    samples: Vec<Sample>,
    chart: Vec<u32>,
    uvs: Vec<Vec2>,
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
        let rest_bones = super::simplify::SimplifyInput::rest_bones(&model.skeleton);
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
            frames_p,
            frames,
        })
    }

    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// The error of a simplified mesh given as triangles of the original's render vertices,
    /// each vertex with its (possibly simplified) influences.
    pub fn measure<'a>(
        &self,
        triangles: &[[u32; 3]],
        influences: impl Fn(u32) -> &'a [AsInfluence],
    ) -> MeshError {
        let grid = Grid::new(triangles, &self.uvs);
        let diffs = self
            .samples
            .iter()
            .map(|s| {
                let (tri, w) = grid.locate(triangles, &self.uvs, &self.chart, s.chart, s.uv);
                let mut diff = s.value.clone();
                for k in 0..3 {
                    accumulate(&mut diff, influences(tri[k]), -w[k]);
                }
                diff
            })
            .collect();
        summarise(&self.frames_p, &self.frames, diffs)
    }
}

/// How the points of two surfaces are made to correspond when measuring.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Correspondence {
    /// Same texture coordinate in the same chart (appearance-preserving).
    Texture,
    /// Closest point in the rest pose, both ways.
    ClosestPoint,
}

impl Correspondence {
    pub fn describe(self) -> &'static str {
        match self {
            Correspondence::Texture => "texture coordinates (the same point of the same chart)",
            Correspondence::ClosestPoint => "closest point in the rest pose, both ways",
        }
    }
}

/// The measurement a report uses: through the texture where the model's texture coordinates
/// are a parameterisation, else geometric.
pub enum Probe<'a> {
    Texture(ErrorProbe),
    ClosestPoint(Box<SurfaceProbe<'a>>),
}

impl<'a> Probe<'a> {
    /// The texture correspondence if at least 99% of the rest-pose surface has texture area,
    /// else the closest-point one; `count` samples, frames at the animation texture's rate.
    pub fn for_model(model: &Model, base: &'a AnimationSpaceMesh, count: usize) -> Probe<'a> {
        if texture_coverage(model, base) >= 0.99
            && let Ok(p) = ErrorProbe::new(model, base, count)
        {
            return Probe::Texture(p);
        }
        Probe::ClosestPoint(Box::new(SurfaceProbe::new(
            model,
            base,
            count / 2,
            count / 2,
            animation_frames(model),
        )))
    }

    pub fn correspondence(&self) -> Correspondence {
        match self {
            Probe::Texture(_) => Correspondence::Texture,
            Probe::ClosestPoint(_) => Correspondence::ClosestPoint,
        }
    }

    pub fn frame_count(&self) -> usize {
        match self {
            Probe::Texture(p) => p.frame_count(),
            Probe::ClosestPoint(p) => p.frames.len(),
        }
    }

    pub fn measure<'b>(
        &self,
        triangles: &[[u32; 3]],
        influences: impl Fn(u32) -> &'b [AsInfluence] + Sync,
    ) -> MeshError {
        match self {
            Probe::Texture(p) => p.measure(triangles, influences),
            Probe::ClosestPoint(p) => p.measure(triangles, influences, None, 0.0),
        }
    }
}

/// The share of the rest-pose surface of `base` on triangles with texture area.
pub fn texture_coverage(model: &Model, base: &AnimationSpaceMesh) -> f64 {
    let rest_bones = super::simplify::SimplifyInput::rest_bones(&model.skeleton);
    let rest = base.rest_positions(&rest_bones);
    let (mut with, mut total) = (0.0f64, 0.0f64);
    for t in base.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|v| v as usize);
        let area = 0.5 * (rest[b] - rest[a]).cross(rest[c] - rest[a]).length() as f64;
        total += area;
        let uv_area = (base.uvs[b] - base.uvs[a]).perp_dot(base.uvs[c] - base.uvs[a]);
        if uv_area.abs() > 1e-12 {
            with += area;
        }
    }
    if total > 0.0 { with / total } else { 0.0 }
}

/// Every clip's frames at the animation texture's rate (the rest pose for a model without
/// clips): the poses a report measures over.
pub fn animation_frames(model: &Model) -> Vec<Vec<Affine3A>> {
    let mut frames = Vec::new();
    for clip in &model.clips {
        let count = (clip.duration * DEFAULT_RATE).round().max(1.0) as usize;
        for f in 0..count {
            frames.push(bone_matrices(
                &model.skeleton,
                Some(clip),
                clip.duration * f as f32 / count as f32,
            ));
        }
    }
    if frames.is_empty() {
        frames.push(bone_matrices(&model.skeleton, None, 0.0));
    }
    frames
}

/// A triangle, for closest points.
struct Located {
    corners: [[f64; 3]; 3],
}

impl Located {
    /// The closest point to `p` and its barycentric weights (Ericson, *Real-Time Collision
    /// Detection*, §5.1.5).
    fn closest(&self, p: DVec3) -> (DVec3, [f64; 3]) {
        let [a, b, c] = self.corners.map(DVec3::from_array);
        let (ab, ac, ap) = (b - a, c - a, p - a);
        let (d1, d2) = (ab.dot(ap), ac.dot(ap));
        if d1 <= 0.0 && d2 <= 0.0 {
            return (a, [1.0, 0.0, 0.0]);
        }
        let bp = p - b;
        let (d3, d4) = (ab.dot(bp), ac.dot(bp));
        if d3 >= 0.0 && d4 <= d3 {
            return (b, [0.0, 1.0, 0.0]);
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            let v = d1 / (d1 - d3);
            return (a + ab * v, [1.0 - v, v, 0.0]);
        }
        let cp = p - c;
        let (d5, d6) = (ab.dot(cp), ac.dot(cp));
        if d6 >= 0.0 && d5 <= d6 {
            return (c, [0.0, 0.0, 1.0]);
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            let w = d2 / (d2 - d6);
            return (a + ac * w, [1.0 - w, 0.0, w]);
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            return (b + (c - b) * w, [0.0, 1.0 - w, w]);
        }
        let denom = va + vb + vc;
        if denom.abs() < 1e-300 {
            return (a, [1.0, 0.0, 0.0]);
        }
        let (v, w) = (vb / denom, vc / denom);
        (a + ab * v + ac * w, [1.0 - v - w, v, w])
    }
}

/// Triangles binned in a uniform grid over their bounding box, for the few nearest to a point.
/// Built in two linear passes (a count, then a fill into one flat array) where an R-tree's
/// bulk load sorts: cutting levels measures a freshly simplified surface for every probe, and
/// the build was most of a measurement.
struct TriangleGrid {
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
    /// Cell `i`'s triangles are `items[start[i]..start[i + 1]]`.
    start: Vec<u32>,
    items: Vec<u32>,
}

impl TriangleGrid {
    fn new(corners: &[[DVec3; 3]]) -> TriangleGrid {
        let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        for c in corners.iter().flatten() {
            lo = lo.min(*c);
            hi = hi.max(*c);
        }
        if corners.is_empty() {
            (lo, hi) = (DVec3::ZERO, DVec3::ONE);
        }
        let extent = (hi - lo).max(DVec3::splat(1e-9));
        // About two triangles per cell, at most 128 cells along an axis.
        let volume = extent.x.max(1e-3 * extent.max_element())
            * extent.y.max(1e-3 * extent.max_element())
            * extent.z.max(1e-3 * extent.max_element());
        let cell = (volume / (2.0 * corners.len().max(1) as f64))
            .cbrt()
            .max(extent.max_element() / 128.0);
        let dims = [extent.x, extent.y, extent.z].map(|e| ((e / cell) as usize + 1).min(129));
        let mut grid = TriangleGrid {
            lo,
            cell,
            dims,
            start: vec![0; dims[0] * dims[1] * dims[2] + 1],
            items: Vec::new(),
        };
        let ranges: Vec<[[usize; 3]; 2]> = corners
            .iter()
            .map(|[a, b, c]| {
                [
                    grid.cell_of(a.min(*b).min(*c)),
                    grid.cell_of(a.max(*b).max(*c)),
                ]
            })
            .collect();
        for pass in 0..2 {
            if pass == 1 {
                let mut sum = 0;
                for s in grid.start.iter_mut() {
                    let n = *s;
                    *s = sum;
                    sum += n;
                }
                grid.items = vec![0; sum as usize];
            }
            let mut fill = grid.start.clone();
            for (t, [a, b]) in ranges.iter().enumerate() {
                for z in a[2]..=b[2] {
                    for y in a[1]..=b[1] {
                        for x in a[0]..=b[0] {
                            let i = grid.index([x, y, z]);
                            if pass == 0 {
                                grid.start[i] += 1;
                            } else {
                                grid.items[fill[i] as usize] = t as u32;
                                fill[i] += 1;
                            }
                        }
                    }
                }
            }
        }
        grid
    }

    fn cell_of(&self, p: DVec3) -> [usize; 3] {
        let c = (p - self.lo) / self.cell;
        let at = |x: f64, d: usize| (x.max(0.0) as usize).min(d - 1);
        [
            at(c.x, self.dims[0]),
            at(c.y, self.dims[1]),
            at(c.z, self.dims[2]),
        ]
    }

    fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        (z * self.dims[1] + y) * self.dims[0] + x
    }

    /// The `k` triangles nearest `p` (by `distance2`, of which `lower2` is a cheap lower
    /// bound), nearest first, into `out`.
    fn nearest(
        &self,
        p: DVec3,
        k: usize,
        lower2: impl Fn(u32) -> f64,
        distance2: impl Fn(u32) -> f64,
        out: &mut Vec<(f64, u32)>,
    ) {
        out.clear();
        let c = self.cell_of(p).map(|x| x as i64);
        let dims = self.dims.map(|d| d as i64);
        let rings = dims.iter().copied().max().unwrap_or(1);
        let mut seen: Vec<u32> = Vec::new();
        for r in 0..=rings {
            // Every cell of ring r is at least r − 1 cells from the point.
            if out.len() == k {
                let bound = (r - 1).max(0) as f64 * self.cell;
                if out[k - 1].0 <= bound * bound {
                    break;
                }
            }
            let range = |i: usize| (c[i] - r).max(0)..=(c[i] + r).min(dims[i] - 1);
            for z in range(2) {
                for y in range(1) {
                    for x in range(0) {
                        let ring = (x - c[0]).abs().max((y - c[1]).abs()).max((z - c[2]).abs());
                        if ring != r {
                            continue;
                        }
                        // A cell no nearer than the k-th best has nothing for us.
                        let min = self.lo + DVec3::new(x as f64, y as f64, z as f64) * self.cell;
                        let gap = (min - p)
                            .max(p - (min + DVec3::splat(self.cell)))
                            .max(DVec3::ZERO);
                        let full = out.len() == k;
                        if full && gap.length_squared() >= out[k - 1].0 {
                            continue;
                        }
                        let i = self.index([x as usize, y as usize, z as usize]);
                        for &t in &self.items[self.start[i] as usize..self.start[i + 1] as usize] {
                            if seen.contains(&t) {
                                continue;
                            }
                            seen.push(t);
                            if out.len() == k && lower2(t) >= out[k - 1].0 {
                                continue;
                            }
                            let d = distance2(t);
                            if out.len() < k || d < out[k - 1].0 {
                                let at = out.partition_point(|e| e.0 <= d);
                                out.insert(at, (d, t));
                                out.truncate(k);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// A rest-pose surface given as triangles of render vertices, indexed for closest points.
struct Surface {
    grid: TriangleGrid,
    /// Area-weighted running sums over `triangles`, for sampling.
    cumulative: Vec<f64>,
    triangles: Vec<[u32; 3]>,
    corners: Vec<[DVec3; 3]>,
}

impl Surface {
    fn new(triangles: &[[u32; 3]], rest: impl Fn(u32) -> DVec3) -> Surface {
        let corners: Vec<[DVec3; 3]> = triangles.iter().map(|t| t.map(&rest)).collect();
        let mut total = 0.0;
        let cumulative = corners
            .iter()
            .map(|[a, b, c]| {
                total += 0.5 * (*b - *a).cross(*c - *a).length();
                total
            })
            .collect();
        Surface {
            grid: TriangleGrid::new(&corners),
            cumulative,
            triangles: triangles.to_vec(),
            corners,
        }
    }

    /// The `k` triangles nearest `p` in the rest pose.
    fn nearest(&self, p: DVec3, k: usize) -> Vec<[u32; 3]> {
        let mut out = Vec::with_capacity(k + 1);
        self.grid.nearest(
            p,
            k,
            |t| {
                let [a, b, c] = self.corners[t as usize];
                let gap = (a.min(b).min(c) - p).max(p - a.max(b).max(c));
                gap.max(DVec3::ZERO).length_squared()
            },
            |t| {
                let tri = Located {
                    corners: self.corners[t as usize].map(|x| x.to_array()),
                };
                tri.closest(p).0.distance_squared(p)
            },
            &mut out,
        );
        out.into_iter()
            .map(|(_, t)| self.triangles[t as usize])
            .collect()
    }

    /// The share of the surface's area on the triangles `mask` picks.
    fn area_share(&self, mask: &[bool]) -> f64 {
        let total = self.cumulative.last().copied().unwrap_or(0.0);
        let picked: f64 = (0..self.corners.len())
            .filter(|&t| mask[t])
            .map(|t| self.cumulative[t] - if t > 0 { self.cumulative[t - 1] } else { 0.0 })
            .sum();
        if total > 0.0 { picked / total } else { 0.0 }
    }

    /// `count` points drawn area-weighted from a fixed seed (on the triangles `mask` picks, if
    /// given): triangle and weights.
    fn samples(&self, count: usize, seed: u64, mask: Option<&[bool]>) -> Vec<([u32; 3], [f64; 3])> {
        let areas = (0..self.corners.len()).map(|t| {
            let area = self.cumulative[t] - if t > 0 { self.cumulative[t - 1] } else { 0.0 };
            if mask.is_none_or(|m| m[t]) { area } else { 0.0 }
        });
        draw_weighted(areas, count, seed, |t, rng| {
            let (r1, r2) = (rng.f64().sqrt(), rng.f64());
            (self.triangles[t], [1.0 - r1, r1 * (1.0 - r2), r1 * r2])
        })
    }

    /// `count` points on the triangles' edges (of the triangles `mask` picks, if given), drawn
    /// by edge length: a sliver or a spike is all edge and little area, so these find it where
    /// area samples would not.
    fn edge_samples(
        &self,
        count: usize,
        seed: u64,
        mask: Option<&[bool]>,
    ) -> Vec<([u32; 3], [f64; 3])> {
        let lengths = self.corners.iter().enumerate().flat_map(|(t, c)| {
            let picked = mask.is_none_or(|m| m[t]);
            (0..3).map(move |k| {
                if picked {
                    c[k].distance(c[(k + 1) % 3])
                } else {
                    0.0
                }
            })
        });
        draw_weighted(lengths, count, seed, |e, rng| {
            let (t, k) = (e / 3, e % 3);
            let along = rng.f64();
            let mut w = [0.0; 3];
            w[k] = 1.0 - along;
            w[(k + 1) % 3] = along;
            (self.triangles[t], w)
        })
    }
}

/// `count` draws of an index with probability proportional to `weights`, each turned into a
/// sample by `sample` (which may draw more from the generator); none if the weights are all 0.
fn draw_weighted<T>(
    weights: impl Iterator<Item = f64>,
    count: usize,
    seed: u64,
    mut sample: impl FnMut(usize, &mut fastrand::Rng) -> T,
) -> Vec<T> {
    let mut total = 0.0;
    let cumulative: Vec<f64> = weights
        .map(|w| {
            total += w;
            total
        })
        .collect();
    if total <= 0.0 {
        return Vec::new();
    }
    let mut rng = fastrand::Rng::with_seed(seed);
    (0..count)
        .map(|_| {
            let x = rng.f64() * total;
            let i = cumulative
                .partition_point(|&c| c <= x)
                .min(cumulative.len() - 1);
            sample(i, &mut rng)
        })
        .collect()
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

/// The geometric measurement: the distance from every sample of one surface to the other
/// surface in each frame, both ways. See the module comment.
pub struct SurfaceProbe<'a> {
    base: &'a AnimationSpaceMesh,
    original: Surface,
    /// The original's render vertices in the rest pose, and posed: vertex `v` in frame `f` at
    /// `v * frames + f`.
    original_rest: Vec<DVec3>,
    original_posed: Vec<DVec3>,
    /// A pool of samples of the original surface (triangle, weights, rest point), area-weighted
    /// and in random order, of which those on changed triangles are measured, `forward` at
    /// most.
    forward_pool: Vec<SurfaceSample>,
    forward: usize,
    /// Samples drawn from a simplified surface's changed triangles: half by area, half along
    /// edges.
    backward: usize,
    /// The original's triangles, by their sorted corners.
    original_triangles: rustc_hash::FxHashSet<[u32; 3]>,
    /// Rest-pose triangles searched for a sample's closest point in each frame: a pose moves
    /// the closest point of the other surface, but not far from where it was at rest.
    candidates: usize,
    /// Measure every vertex the simplification removed (until none left can beat the largest
    /// distance found), not just a spread of them.
    every_vertex: bool,
    /// Every render vertex's welded position, and the original triangles round each position.
    position: Vec<u32>,
    original_fans: Fans,
    rest_bones: Vec<Affine3A>,
    frames: Vec<Vec<Affine3A>>,
}

/// Original samples pooled per sample measured (see [`SurfaceProbe`]): the changed part of
/// a fine level is a small share of the surface, and its samples come from this pool.
const FORWARD_POOL: usize = 16;

/// A sample of a surface: its triangle (render vertices), weights and rest-pose point.
type SurfaceSample = ([u32; 3], [f64; 3], DVec3);

/// A triangle's corners in ascending order: the same triangle whatever corner it starts at.
fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// Triangles round every position, flat: position `p`'s are `items[start[p]..start[p + 1]]`.
struct Fans {
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Fans {
    /// The fans of `triangles` (render vertices) by `position` of their corners.
    fn new(triangles: &[[u32; 3]], position: &[u32], positions: usize) -> Fans {
        let mut start = vec![0u32; positions + 1];
        for t in triangles {
            for &v in t {
                start[position[v as usize] as usize + 1] += 1;
            }
        }
        for i in 1..start.len() {
            start[i] += start[i - 1];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; start[positions] as usize];
        for (i, t) in triangles.iter().enumerate() {
            for &v in t {
                let p = position[v as usize] as usize;
                items[fill[p] as usize] = i as u32;
                fill[p] += 1;
            }
        }
        Fans { start, items }
    }

    fn of(&self, position: u32) -> &[u32] {
        let p = position as usize;
        &self.items[self.start[p] as usize..self.start[p + 1] as usize]
    }
}

/// A point's distance to a set of triangles in every frame.
struct Reach<'p> {
    frames: usize,
    posed: &'p (dyn Fn(u32, usize) -> DVec3 + Sync),
}

impl Reach<'_> {
    /// The smallest distance from `point(f)` to any of `candidates` in frame `f`, squared, for
    /// every frame: added to `sum`, the largest returned. Where the first candidate is within
    /// `enough` (squared) that distance is taken as it is: an upper bound, exact enough below
    /// what the caller cares about.
    fn worst(
        &self,
        point: impl Fn(usize) -> DVec3,
        candidates: &[[u32; 3]],
        enough: f64,
        sum: &mut f64,
    ) -> f64 {
        let distance2 = |t: &[u32; 3], f: usize, p: DVec3| {
            let tri = Located {
                corners: t.map(|v| (self.posed)(v, f).to_array()),
            };
            tri.closest(p).0.distance_squared(p)
        };
        let mut worst: f64 = 0.0;
        for f in 0..self.frames {
            let p = point(f);
            let Some((first, rest)) = candidates.split_first() else {
                continue;
            };
            let mut best = distance2(first, f, p);
            if best > enough {
                for t in rest {
                    best = best.min(distance2(t, f, p));
                }
            }
            *sum += best;
            worst = worst.max(best);
        }
        worst
    }
}

impl<'a> SurfaceProbe<'a> {
    /// `forward` samples of `base` (the full-detail mesh of `model`) and `backward` samples of
    /// every simplified mesh measured, compared in `frames`.
    pub fn new(
        model: &Model,
        base: &'a AnimationSpaceMesh,
        forward: usize,
        backward: usize,
        frames: Vec<Vec<Affine3A>>,
    ) -> SurfaceProbe<'a> {
        let rest_bones = super::simplify::SimplifyInput::rest_bones(&model.skeleton);
        let rest = base.rest_positions(&rest_bones);
        let triangles: Vec<[u32; 3]> = base
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let original = Surface::new(&triangles, |v| rest[v as usize].as_dvec3());
        let forward_pool = original
            .samples(forward * FORWARD_POOL, 0x10d1ab, None)
            .into_iter()
            .map(|(t, w)| {
                let p = (0..3).map(|k| rest[t[k] as usize].as_dvec3() * w[k]).sum();
                (t, w, p)
            })
            .collect();
        let original_triangles = triangles.iter().map(|t| sorted(*t)).collect();
        let original_posed = (0..base.vertex_count())
            .flat_map(|v| {
                let infl = base.influences_of(v);
                frames.iter().map(move |g| pose_point(g, infl))
            })
            .collect();
        let position = crate::import::weld::position_groups(
            &rest,
            crate::import::weld::tolerance_for(&rest) * 10.0,
        );
        let positions = position.iter().max().map_or(0, |&m| m as usize + 1);
        let original_fans = Fans::new(&triangles, &position, positions);
        SurfaceProbe {
            base,
            original,
            original_rest: rest.iter().map(|p| p.as_dvec3()).collect(),
            original_posed,
            forward_pool,
            forward,
            backward,
            original_triangles,
            candidates: 6,
            every_vertex: false,
            position,
            original_fans,
            rest_bones,
            frames,
        }
    }

    /// The same probe searching `candidates` triangles per sample and frame (6 by default).
    pub fn with_candidates(mut self, candidates: usize) -> Self {
        self.candidates = candidates.max(1);
        self
    }

    /// The same probe measuring every removed vertex that could be furthest, where
    /// [`Self::measure`] is given where vertices went: the largest distance at the original's
    /// vertices is then exact, not sampled. Dearer; for a level's error.
    pub fn every_vertex(mut self) -> Self {
        self.every_vertex = true;
        self
    }

    /// The error of a simplified mesh given as triangles of the original's render vertices,
    /// each vertex with its (possibly simplified) influences. A mesh with no triangles left is
    /// infinitely far.
    ///
    /// Besides the nearest triangles in the rest pose, a sample is compared with the other
    /// surface's triangles round its own triangle's corners: for a point of the simplified
    /// mesh, the original's round those (original) vertices; for a point of the original,
    /// given `follow` (which vertex of the simplified mesh each original vertex became), the
    /// simplified mesh's round those. Where two parts of a character touch at rest (a tail on
    /// a rump), the nearest triangles at rest can all lie on the wrong one.
    ///
    /// Distances below `resolution` need not be exact: a sample that close to the first triangle
    /// it is compared with is taken at that distance (an upper bound), which spares most of the
    /// work when only distances near a level's error matter. 0 measures exactly.
    pub fn measure<'b>(
        &self,
        triangles: &[[u32; 3]],
        influences: impl Fn(u32) -> &'b [AsInfluence] + Sync,
        follow: Option<&(dyn Fn(u32) -> u32 + Sync)>,
        resolution: f64,
    ) -> MeshError {
        let enough = resolution * resolution;
        use rayon::prelude::*;
        if triangles.is_empty() {
            return MeshError {
                rms: f64::INFINITY,
                max: f64::INFINITY,
            };
        }
        let frames = self.frames.len();
        // The simplified mesh's vertices, in the rest pose and posed.
        let mut slot = vec![u32::MAX; self.base.vertex_count()];
        let mut used = Vec::new();
        for &v in triangles.iter().flatten() {
            if slot[v as usize] == u32::MAX {
                slot[v as usize] = used.len() as u32;
                used.push(v);
            }
        }
        // A vertex whose influences are the original's (no influence simplification) is where
        // the original's is: only the others are posed again.
        let moved: Vec<bool> = used
            .iter()
            .map(|&v| influences(v) != self.base.influences_of(v as usize))
            .collect();
        let rest: Vec<DVec3> = used
            .iter()
            .zip(&moved)
            .map(|(&v, &moved)| {
                if moved {
                    pose_point(&self.rest_bones, influences(v))
                } else {
                    self.original_rest[v as usize]
                }
            })
            .collect();
        let posed: Vec<DVec3> = used
            .iter()
            .zip(&moved)
            .flat_map(|(&v, &moved)| {
                let infl = influences(v);
                let original = &self.original_posed[v as usize * frames..(v as usize + 1) * frames];
                (0..frames).map(move |f| {
                    if moved {
                        pose_point(&self.frames[f], infl)
                    } else {
                        original[f]
                    }
                })
            })
            .collect();
        let simplified = Surface::new(triangles, |v| rest[slot[v as usize] as usize]);
        // A triangle both surfaces have, on vertices that did not move, is 0 away in every
        // frame: samples go where the surfaces differ, so a few hundred find the largest
        // distance even when the simplification changed a sliver of the surface.
        let unmoved = |t: &[u32; 3]| t.iter().all(|&v| !moved[slot[v as usize] as usize]);
        let kept: rustc_hash::FxHashSet<[u32; 3]> = triangles
            .iter()
            .filter(|t| unmoved(t) && self.original_triangles.contains(&sorted(**t)))
            .map(|t| sorted(*t))
            .collect();
        let changed: Vec<bool> = triangles
            .iter()
            .map(|t| !kept.contains(&sorted(*t)))
            .collect();
        let forward: Vec<&([u32; 3], [f64; 3], DVec3)> = self
            .forward_pool
            .iter()
            .filter(|(t, _, _)| !kept.contains(&sorted(*t)))
            .collect();
        // The share of the original surface that changed, and of the simplified one: what the
        // samples stand for in the RMS.
        let forward_share = forward.len() as f64 / self.forward_pool.len().max(1) as f64;
        let backward_share = simplified.area_share(&changed);
        let forward = &forward[..forward.len().min(self.forward)];
        let simplified_fans = Fans::new(
            triangles,
            &self.position,
            self.original_fans.start.len() - 1,
        );
        let to_simplified = Reach {
            frames,
            posed: &|v, f| posed[slot[v as usize] as usize * frames + f],
        };
        let to_original = Reach {
            frames,
            posed: &|v, f| self.original_posed[v as usize * frames + f],
        };
        // The largest distances sit at cell corners, foremost at the vertices a collapse
        // removed (the original's) and at those an influence removal moved (the simplified
        // mesh's): they are measured as well, for the maximum.
        let at_vertex = |tris: &[[u32; 3]], t: u32, v: u32| {
            let tri = tris[t as usize];
            let k = (0..3)
                .find(|&k| self.position[tri[k] as usize] == self.position[v as usize])
                .unwrap_or(0);
            let mut w = [0.0; 3];
            w[k] = 1.0;
            (tri, w)
        };
        // With `follow`: every removed vertex with a bound on its distance (squared), furthest
        // bound first; without, a spread of them, unbounded.
        let removed: Vec<(f64, SurfaceSample)> = {
            let positions = self.original_fans.start.len() - 1;
            let mut present = vec![false; positions];
            for &v in &used {
                present[self.position[v as usize] as usize] = true;
            }
            // One render vertex of every position the simplification removed.
            let gone: Vec<u32> = (0..positions as u32)
                .filter(|&p| !present[p as usize])
                .filter_map(|p| {
                    let t = *self.original_fans.of(p).first()?;
                    self.original.triangles[t as usize]
                        .into_iter()
                        .find(|&v| self.position[v as usize] == p)
                })
                .collect();
            let budget = self.forward.max(1);
            let bounded: Vec<(f64, u32)> = match follow {
                // The distance from the vertex it became (in its worst frame) bounds a removed
                // vertex's distance from the simplified surface.
                Some(follow) => {
                    let mut bound: Vec<(f64, u32)> = gone
                        .par_iter()
                        .map(|&v| {
                            let to = follow(v);
                            let far = match slot.get(to as usize) {
                                Some(&i) if i != u32::MAX => (0..frames)
                                    .map(|f| {
                                        posed[i as usize * frames + f].distance_squared(
                                            self.original_posed[v as usize * frames + f],
                                        )
                                    })
                                    .fold(0.0, f64::max),
                                _ => f64::INFINITY,
                            };
                            // So does the distance from the nearest triangle at rest, often
                            // much less: checked where it could matter.
                            let far = if self.every_vertex && far > enough {
                                let p = self.original_rest[v as usize];
                                let near = simplified.nearest(p, 1);
                                let point = |f: usize| self.original_posed[v as usize * frames + f];
                                let mut unused = 0.0;
                                far.min(to_simplified.worst(
                                    point,
                                    &near,
                                    f64::INFINITY,
                                    &mut unused,
                                ))
                            } else {
                                far
                            };
                            (far, v)
                        })
                        .collect();
                    bound.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
                    if !self.every_vertex {
                        bound.truncate(budget);
                    }
                    bound
                }
                None => {
                    let stride = gone.len().div_ceil(budget).max(1);
                    gone.into_iter()
                        .step_by(stride)
                        .map(|v| (f64::INFINITY, v))
                        .collect()
                }
            };
            bounded
                .into_iter()
                .map(|(bound, v)| {
                    let t = self.original_fans.of(self.position[v as usize])[0];
                    let (tri, w) = at_vertex(&self.original.triangles, t, v);
                    (bound, (tri, w, self.original_rest[v as usize]))
                })
                .collect()
        };
        let mut shifted: Vec<(f64, u32)> = used
            .iter()
            .zip(&moved)
            .filter(|(_, m)| **m)
            .map(|(&v, _)| {
                let i = slot[v as usize] as usize;
                let shift = (0..frames)
                    .map(|f| {
                        posed[i * frames + f]
                            .distance_squared(self.original_posed[v as usize * frames + f])
                    })
                    .fold(0.0, f64::max);
                (shift, v)
            })
            .collect();
        shifted.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let moved_samples: Vec<([u32; 3], [f64; 3])> = shifted
            .iter()
            .take(self.backward / 4)
            .filter_map(|&(_, v)| {
                let t = *simplified_fans.of(self.position[v as usize]).first()?;
                Some(at_vertex(triangles, t, v))
            })
            .collect();
        let with_fans =
            |mut candidates: Vec<[u32; 3]>, fans: &Fans, of: &[[u32; 3]], corners: [u32; 3]| {
                for v in corners {
                    for &t in fans.of(self.position[v as usize]) {
                        if !candidates.contains(&of[t as usize]) {
                            candidates.push(of[t as usize]);
                        }
                    }
                }
                candidates
            };
        let nearest = |surface: &Surface, p: DVec3| surface.nearest(p, self.candidates);
        let half = self.backward / 2;
        let backward: Vec<([u32; 3], [f64; 3])> = simplified
            .samples(half, 0x5a3b1e, Some(&changed))
            .into_iter()
            .chain(simplified.edge_samples(self.backward - half, 0xed9e, Some(&changed)))
            .collect();
        let per_sample = |(t, w, p): &&([u32; 3], [f64; 3], DVec3)| {
            let mut sum = 0.0;
            let mut candidates = nearest(&simplified, *p);
            if let Some(follow) = follow {
                candidates = with_fans(candidates, &simplified_fans, triangles, t.map(follow));
            }
            let point = |f| {
                (0..3)
                    .map(|k| self.original_posed[t[k] as usize * frames + f] * w[k])
                    .sum()
            };
            let worst = to_simplified.worst(point, &candidates, enough, &mut sum);
            (sum, worst, frames)
        };
        let (forward_sum, forward_max, forward_count) = forward.par_iter().map(per_sample).reduce(
            || (0.0, 0.0, 0),
            |a, b| (a.0 + b.0, a.1.max(b.1), a.2 + b.2),
        );
        let backward_sample = |(t, w): &([u32; 3], [f64; 3])| {
            let mut sum = 0.0;
            let p = (0..3)
                .map(|k| rest[slot[t[k] as usize] as usize] * w[k])
                .sum();
            let candidates = with_fans(
                nearest(&self.original, p),
                &self.original_fans,
                &self.original.triangles,
                *t,
            );
            let point = |f| (0..3).map(|k| (to_simplified.posed)(t[k], f) * w[k]).sum();
            let worst = to_original.worst(point, &candidates, enough, &mut sum);
            (sum, worst, frames)
        };
        let (backward_sum, backward_max, backward_count) =
            backward.par_iter().map(backward_sample).reduce(
                || (0.0, 0.0, 0),
                |a, b| (a.0 + b.0, a.1.max(b.1), a.2 + b.2),
            );
        let moved_max = moved_samples
            .par_iter()
            .map(|s| backward_sample(s).1)
            .reduce(|| 0.0, f64::max);
        // Removed vertices, furthest bound first, in batches, until no bound left can beat
        // the largest distance found: that maximum is then exact over every vertex.
        let mut max2 = forward_max.max(backward_max).max(moved_max);
        for batch in removed.chunks(64) {
            if batch[0].0 <= max2 {
                break;
            }
            let m = batch
                .par_iter()
                .map(|(_, s)| per_sample(&s).1)
                .reduce(|| 0.0, f64::max);
            max2 = max2.max(m);
        }
        let mean = |sum: f64, count: usize| if count > 0 { sum / count as f64 } else { 0.0 };
        let ms = 0.5
            * (forward_share * mean(forward_sum, forward_count)
                + backward_share * mean(backward_sum, backward_count));
        MeshError {
            rms: ms.sqrt(),
            max: max2.sqrt(),
        }
    }
}

/// `Σ G_i p_i` for one vertex's influences and bone matrices `g`.
fn pose_point(g: &[Affine3A], influences: &[AsInfluence]) -> DVec3 {
    influences
        .iter()
        .map(|i| super::animation_space::transform_homogeneous(&g[i.bone as usize], i.p).as_dvec3())
        .sum()
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

/// A uniform grid over texture space for locating points in triangles.
struct Grid {
    lo: DVec2,
    cell: DVec2,
    size: usize,
    cells: Vec<Vec<u32>>,
}

impl Grid {
    fn new(triangles: &[[u32; 3]], uvs: &[Vec2]) -> Grid {
        let (mut lo, mut hi) = (DVec2::splat(f64::MAX), DVec2::splat(f64::MIN));
        for t in triangles {
            for &v in t {
                let u = uvs[v as usize].as_dvec2();
                lo = lo.min(u);
                hi = hi.max(u);
            }
        }
        let size = ((triangles.len() as f64).sqrt().ceil() as usize).clamp(1, 512);
        let cell = ((hi - lo) / size as f64).max(DVec2::splat(1e-12));
        let mut cells = vec![Vec::new(); size * size];
        let clamp = |x: f64| (x.max(0.0) as usize).min(size - 1);
        for (i, t) in triangles.iter().enumerate() {
            let p = t.map(|v| (uvs[v as usize].as_dvec2() - lo) / cell);
            let (a, b) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
            for y in clamp(a.y)..=clamp(b.y) {
                for x in clamp(a.x)..=clamp(b.x) {
                    cells[y * size + x].push(i as u32);
                }
            }
        }
        Grid {
            lo,
            cell,
            size,
            cells,
        }
    }

    /// The triangle of `chart` containing `uv` and the barycentric weights there; if none
    /// contains it (a simplifier that changed the chart's outline), the nearest one, with the
    /// point clamped onto it.
    fn locate(
        &self,
        triangles: &[[u32; 3]],
        uvs: &[Vec2],
        chart: &[u32],
        want: u32,
        uv: DVec2,
    ) -> ([u32; 3], [f64; 3]) {
        let c = (uv - self.lo) / self.cell;
        let (cx, cy) = (c.x.floor() as i64, c.y.floor() as i64);
        let mut best: Option<(f64, [u32; 3], [f64; 3])> = None;
        for ring in 0..self.size as i64 {
            for y in (cy - ring)..=(cy + ring) {
                for x in (cx - ring)..=(cx + ring) {
                    let on_ring = (y - cy).abs() == ring || (x - cx).abs() == ring;
                    if !on_ring || x < 0 || y < 0 || x >= self.size as i64 || y >= self.size as i64
                    {
                        continue;
                    }
                    for &t in &self.cells[y as usize * self.size + x as usize] {
                        let tri = triangles[t as usize];
                        if chart[tri[0] as usize] != want {
                            continue;
                        }
                        let [a, b, cc] = tri.map(|v| uvs[v as usize].as_dvec2());
                        let w = super::simplify::collapse::barycentric(uv, a, b, cc);
                        let worst = w[0].min(w[1]).min(w[2]);
                        if worst >= -1e-9 {
                            return (tri, w);
                        }
                        if worst.is_finite() && best.as_ref().is_none_or(|b| worst > b.0) {
                            best = Some((worst, tri, w));
                        }
                    }
                }
            }
            // A candidate from the first rings that had any is as good as any farther one.
            if best.is_some() && ring >= 1 {
                break;
            }
        }
        match best {
            Some((_, tri, w)) => {
                let clamped = w.map(|x| x.max(0.0));
                let s: f64 = clamped.iter().sum::<f64>().max(1e-300);
                (tri, clamped.map(|x| x / s))
            }
            None => (triangles[0], [1.0, 0.0, 0.0]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_finds_the_nearest_triangles() {
        let mut rng = fastrand::Rng::with_seed(7);
        let mut v = || DVec3::new(rng.f64(), rng.f64() * 0.3, rng.f64() * 2.0);
        let corners: Vec<[DVec3; 3]> = (0..300)
            .map(|_| {
                let a = v();
                [a, a + (v() - a) * 0.1, a + (v() - a) * 0.1]
            })
            .collect();
        let grid = TriangleGrid::new(&corners);
        let distance2 = |p: DVec3, t: u32| {
            let tri = Located {
                corners: corners[t as usize].map(|x| x.to_array()),
            };
            tri.closest(p).0.distance_squared(p)
        };
        let mut out = Vec::new();
        for i in 0..200 {
            // Inside the grid's box and well outside it.
            let p = v() * if i % 4 == 0 { 3.0 } else { 1.0 } - DVec3::splat(0.2);
            grid.nearest(p, 4, |_| 0.0, |t| distance2(p, t), &mut out);
            let mut all: Vec<f64> = (0..corners.len() as u32).map(|t| distance2(p, t)).collect();
            all.sort_by(f64::total_cmp);
            let found: Vec<f64> = out.iter().map(|e| e.0).collect();
            assert_eq!(found, all[..4].to_vec(), "at {p}");
        }
    }
}

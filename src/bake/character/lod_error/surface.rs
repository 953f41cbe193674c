//! The geometric correspondence: every sample of one surface against the closest point of
//! the other in the rest pose, both ways, compared in every frame (a two-sided, sampled
//! Hausdorff distance over the animation).

use super::MeshError;
use super::geometry::{Located, Surface};
use crate::bake::character::uv_grid::sorted;
use crate::bake::gpu_data::animation_space::{AnimationSpaceMesh, AsInfluence};
use crate::model::Model;
use glam::{Affine3A, DVec3, Vec3};

/// The geometric measurement: the distance from every sample of one surface to the other
/// surface in each frame, both ways. See the module comment.
pub struct SurfaceProbe<'a> {
    base: &'a AnimationSpaceMesh,
    /// What depends on the full-detail mesh alone, shared by probes of one model (see
    /// [`SurfaceProbe::sharing`]).
    shared: std::sync::Arc<Original>,
    /// The original's render vertices posed: vertex `v` in frame `f` at `v * frames + f`, in
    /// single precision as the bone matrices that pose them are (on a 2-million-triangle
    /// model the frames of both probes took 410 MB in double).
    original_posed: Vec<Vec3>,
    /// A pool of samples of the original surface (triangle, weights, rest point), area-weighted
    /// and in random order, of which those on changed triangles are measured, `forward` at
    /// most.
    forward_pool: Vec<SurfaceSample>,
    forward: usize,
    /// Samples drawn from a simplified surface's changed triangles: half by area, half along
    /// edges.
    backward: usize,
    /// Rest-pose triangles searched for a sample's closest point in each frame: a pose moves
    /// the closest point of the other surface, but not far from where it was at rest.
    candidates: usize,
    /// Measure every vertex the simplification removed (until none left can beat the largest
    /// distance found), not just a spread of them.
    every_vertex: bool,
    frames: Vec<Vec<Affine3A>>,
}

/// The full-detail surface as every probe of a model sees it: its rest pose, the index its
/// closest points are found in, its triangles and fans. On a 2-million-triangle model, about
/// 200 MB that a model's two level probes each held.
struct Original {
    surface: Surface,
    /// The original's render vertices in the rest pose.
    rest: Vec<DVec3>,
    /// The original's triangles, by their sorted corners.
    triangle_set: rustc_hash::FxHashSet<[u32; 3]>,
    /// Every render vertex's welded position, and the original triangles round each position.
    position: Vec<u32>,
    fans: Fans,
    rest_bones: Vec<Affine3A>,
}

/// Original samples pooled per sample measured (see [`SurfaceProbe`]): the changed part of
/// a fine level is a small share of the surface, and its samples come from this pool.
const FORWARD_POOL: usize = 16;

/// A simplified mesh's vertices (render vertices of the original) in the rest pose and in
/// every frame of the probe.
struct PosedMesh {
    /// Each original render vertex's index in `used`, or `u32::MAX` where the mesh lacks it.
    slot: Vec<u32>,
    used: Vec<u32>,
    /// Whether a used vertex's influences differ from the original's.
    moved: Vec<bool>,
    rest: Vec<DVec3>,
    /// Used vertex `i` in frame `f` at `i * frames + f` (single precision, as
    /// [`SurfaceProbe::original_posed`]).
    posed: Vec<Vec3>,
}

/// Removed vertices whose bounds are tightened at a time (see [`SurfaceProbe::measure`]).
const TIGHTEN_CHUNK: usize = 4096;

/// A sample of a surface: its triangle (render vertices), weights and rest-pose point.
type SurfaceSample = ([u32; 3], [f64; 3], DVec3);

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
        let rest_bones =
            crate::bake::character::simplify::SimplifyInput::rest_bones(&model.skeleton);
        let rest = base.rest_positions(&rest_bones);
        let triangles: Vec<[u32; 3]> = base
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let surface = Surface::new(&triangles, |v| rest[v as usize].as_dvec3());
        let triangle_set = triangles.iter().map(|t| sorted(*t)).collect();
        let position = crate::geometry::weld::position_groups(
            &rest,
            crate::geometry::weld::tolerance_for(&rest) * 10.0,
        );
        let positions = position.iter().max().map_or(0, |&m| m as usize + 1);
        let fans = Fans::new(&triangles, &position, positions);
        let shared = std::sync::Arc::new(Original {
            surface,
            rest: rest.iter().map(|p| p.as_dvec3()).collect(),
            triangle_set,
            position,
            fans,
            rest_bones,
        });
        Self::with_original(base, shared, forward, backward, frames)
    }

    /// A probe of the same full-detail mesh as `other`, sharing what depends on it alone, with
    /// its own samples and frames.
    pub fn sharing(
        other: &SurfaceProbe<'a>,
        forward: usize,
        backward: usize,
        frames: Vec<Vec<Affine3A>>,
    ) -> SurfaceProbe<'a> {
        Self::with_original(other.base, other.shared.clone(), forward, backward, frames)
    }

    fn with_original(
        base: &'a AnimationSpaceMesh,
        shared: std::sync::Arc<Original>,
        forward: usize,
        backward: usize,
        frames: Vec<Vec<Affine3A>>,
    ) -> SurfaceProbe<'a> {
        let rest = &shared.rest;
        let forward_pool = shared
            .surface
            .samples(forward * FORWARD_POOL, 0x10d1ab, None)
            .into_iter()
            .map(|(t, w)| {
                let p = (0..3).map(|k| rest[t[k] as usize] * w[k]).sum();
                (t, w, p)
            })
            .collect();
        let mut original_posed = Vec::with_capacity(base.vertex_count() * frames.len());
        for v in 0..base.vertex_count() {
            let infl = base.influences_of(v);
            original_posed.extend(frames.iter().map(|g| pose_point(g, infl).as_vec3()));
        }
        SurfaceProbe {
            base,
            shared,
            original_posed,
            forward_pool,
            forward,
            backward,
            candidates: 6,
            every_vertex: false,
            frames,
        }
    }

    pub fn frame_count(&self) -> usize {
        self.frames.len()
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
        use rayon::prelude::*;
        if triangles.is_empty() {
            return MeshError {
                rms: f64::INFINITY,
                max: f64::INFINITY,
            };
        }
        let enough = resolution * resolution;
        let frames = self.frames.len();
        let mesh = self.pose(triangles, influences);
        let simplified = Surface::new(triangles, |v| mesh.rest[mesh.slot[v as usize] as usize]);
        let Changed {
            changed,
            forward,
            forward_share,
            backward_share,
        } = self.changed(triangles, &mesh, &simplified);
        let forward = &forward[..forward.len().min(self.forward)];
        let simplified_fans = Fans::new(triangles, &self.shared.position, self.positions());
        let to_simplified = Reach {
            frames,
            posed: &|v, f| mesh.posed[mesh.slot[v as usize] as usize * frames + f].as_dvec3(),
        };
        let to_original = Reach {
            frames,
            posed: &|v, f| self.original_posed[v as usize * frames + f].as_dvec3(),
        };
        let moved_samples = self.moved_vertices(&mesh, &simplified_fans, triangles);
        let nearest = |surface: &Surface, p: DVec3| surface.nearest(p, self.candidates);
        let backward = self.backward_samples(&simplified, &changed);
        let forward_sample = |(t, w, p): &&SurfaceSample| {
            let mut sum = 0.0;
            let mut candidates = nearest(&simplified, *p);
            if let Some(follow) = follow {
                candidates = self.with_fans(candidates, &simplified_fans, triangles, t.map(follow));
            }
            let point = |f: usize| -> DVec3 {
                (0..3)
                    .map(|k| self.original_posed[t[k] as usize * frames + f].as_dvec3() * w[k])
                    .sum()
            };
            let worst = to_simplified.worst(point, &candidates, enough, &mut sum);
            (sum, worst, frames)
        };
        let backward_sample = |(t, w): &([u32; 3], [f64; 3])| {
            let mut sum = 0.0;
            let p = (0..3)
                .map(|k| mesh.rest[mesh.slot[t[k] as usize] as usize] * w[k])
                .sum();
            let candidates = self.with_fans(
                nearest(&self.shared.surface, p),
                &self.shared.fans,
                &self.shared.surface.triangles,
                *t,
            );
            let point = |f| (0..3).map(|k| (to_simplified.posed)(t[k], f) * w[k]).sum();
            let worst = to_original.worst(point, &candidates, enough, &mut sum);
            (sum, worst, frames)
        };
        let totals =
            |a: (f64, f64, usize), b: (f64, f64, usize)| (a.0 + b.0, a.1.max(b.1), a.2 + b.2);
        let (forward_sum, forward_max, forward_count) = forward
            .par_iter()
            .map(forward_sample)
            .reduce(|| (0.0, 0.0, 0), totals);
        let (backward_sum, backward_max, backward_count) = backward
            .par_iter()
            .map(backward_sample)
            .reduce(|| (0.0, 0.0, 0), totals);
        let moved_max = moved_samples
            .par_iter()
            .map(|s| backward_sample(s).1)
            .reduce(|| 0.0, f64::max);
        // The largest distances sit at cell corners, foremost at the vertices a collapse
        // removed (the original's) and at those an influence removal moved (the simplified
        // mesh's): they are measured as well, for the maximum (the moved ones above, with the
        // samples, and the removed ones now, those of them that can beat what the samples
        // found).
        let mut max2 = forward_max.max(backward_max).max(moved_max);
        let removed = self.removed_vertices(&mesh, follow, (&simplified_fans, triangles), max2);
        // A removed vertex's bound, tightened where every vertex counts (see
        // [`removed_maximum`]).
        let tighten = |&(far, v, sample): &(f64, u32, SurfaceSample)| {
            if !self.every_vertex || follow.is_none() || far <= enough {
                return (far, sample);
            }
            let near = simplified.nearest(sample.2, 1);
            let point = |f: usize| self.original_posed[v as usize * frames + f].as_dvec3();
            let mut unused = 0.0;
            (
                far.min(to_simplified.worst(point, &near, f64::INFINITY, &mut unused)),
                sample,
            )
        };
        max2 = removed_maximum(&removed, max2, tighten, |s| forward_sample(&s).1);
        mesh_error(
            (forward_share, forward_sum, forward_count),
            (backward_share, backward_sum, backward_count),
            max2,
        )
    }

    /// Which of a simplified mesh's triangles changed, and the original samples on changed
    /// triangles, with the share of either surface that changed.
    ///
    /// A triangle both surfaces have, on vertices that did not move, is 0 away in every
    /// frame: samples go where the surfaces differ, so a few hundred find the largest
    /// distance even when the simplification changed a sliver of the surface.
    fn changed(
        &self,
        triangles: &[[u32; 3]],
        mesh: &PosedMesh,
        simplified: &Surface,
    ) -> Changed<'_> {
        let unmoved = |t: &[u32; 3]| {
            t.iter()
                .all(|&v| !mesh.moved[mesh.slot[v as usize] as usize])
        };
        let kept: rustc_hash::FxHashSet<[u32; 3]> = triangles
            .iter()
            .filter(|t| unmoved(t) && self.shared.triangle_set.contains(&sorted(**t)))
            .map(|t| sorted(*t))
            .collect();
        let changed: Vec<bool> = triangles
            .iter()
            .map(|t| !kept.contains(&sorted(*t)))
            .collect();
        let forward: Vec<&SurfaceSample> = self
            .forward_pool
            .iter()
            .filter(|(t, _, _)| !kept.contains(&sorted(*t)))
            .collect();
        // The share of the original surface that changed, and of the simplified one: what the
        // samples stand for in the RMS.
        let forward_share = forward.len() as f64 / self.forward_pool.len().max(1) as f64;
        let backward_share = simplified.area_share(&changed);
        Changed {
            changed,
            forward,
            forward_share,
            backward_share,
        }
    }

    /// The backward samples of a simplified mesh's changed triangles: half by area, half
    /// along edges, where the largest distances of a collapse tend to lie.
    fn backward_samples(
        &self,
        simplified: &Surface,
        changed: &[bool],
    ) -> Vec<([u32; 3], [f64; 3])> {
        let half = self.backward / 2;
        simplified
            .samples(half, 0x5a3b1e, Some(changed))
            .into_iter()
            .chain(simplified.edge_samples(self.backward - half, 0xed9e, Some(changed)))
            .collect()
    }

    /// How many welded positions the original has.
    fn positions(&self) -> usize {
        self.shared.fans.start.len() - 1
    }

    /// The simplified mesh's vertices, in the rest pose and posed in every frame.
    fn pose<'b>(
        &self,
        triangles: &[[u32; 3]],
        influences: impl Fn(u32) -> &'b [AsInfluence],
    ) -> PosedMesh {
        let frames = self.frames.len();
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
                    pose_point(&self.shared.rest_bones, influences(v))
                } else {
                    self.shared.rest[v as usize]
                }
            })
            .collect();
        let mut posed: Vec<Vec3> = Vec::with_capacity(used.len() * frames);
        for (&v, &moved) in used.iter().zip(&moved) {
            let original = &self.original_posed[v as usize * frames..(v as usize + 1) * frames];
            if moved {
                let infl = influences(v);
                posed.extend(self.frames.iter().map(|g| pose_point(g, infl).as_vec3()));
            } else {
                posed.extend_from_slice(original);
            }
        }
        PosedMesh {
            slot,
            used,
            moved,
            rest,
            posed,
        }
    }

    /// The sample at vertex `v` of triangle `t` of `tris` (the corner at `v`'s position).
    fn at_vertex(&self, tris: &[[u32; 3]], t: u32, v: u32) -> ([u32; 3], [f64; 3]) {
        let tri = tris[t as usize];
        let k = (0..3)
            .find(|&k| self.shared.position[tri[k] as usize] == self.shared.position[v as usize])
            .unwrap_or(0);
        let mut w = [0.0; 3];
        w[k] = 1.0;
        (tri, w)
    }

    /// `candidates` and the triangles of `of` round the positions of `corners` (by `fans`).
    fn with_fans(
        &self,
        mut candidates: Vec<[u32; 3]>,
        fans: &Fans,
        of: &[[u32; 3]],
        corners: [u32; 3],
    ) -> Vec<[u32; 3]> {
        for v in corners {
            for &t in fans.of(self.shared.position[v as usize]) {
                if !candidates.contains(&of[t as usize]) {
                    candidates.push(of[t as usize]);
                }
            }
        }
        candidates
    }

    /// The original's vertices at the positions the simplification removed, as samples with
    /// their vertex. With `follow`: each with a bound on its distance (squared) in its worst
    /// frame, furthest bound first, those whose bound is above `beyond` only (no other can
    /// change the largest distance found), `self.forward` of them unless every vertex is
    /// wanted. Without, a spread of them, unbounded.
    ///
    /// The bound is the distance from the vertex it became (`follow`), and where every vertex
    /// is wanted, the distance from a point of a triangle round that vertex (of `near`, the
    /// simplified mesh's fans and triangles): the point nearest at rest, followed in every
    /// frame. A collapse's region is covered by its target's fan, so that point is mostly
    /// as near as the surface gets, and few bounds are left to tighten by a search.
    fn removed_vertices(
        &self,
        mesh: &PosedMesh,
        follow: Option<&(dyn Fn(u32) -> u32 + Sync)>,
        near: (&Fans, &[[u32; 3]]),
        beyond: f64,
    ) -> Vec<(f64, u32, SurfaceSample)> {
        use rayon::prelude::*;
        let frames = self.frames.len();
        let positions = self.positions();
        let mut present = vec![false; positions];
        for &v in &mesh.used {
            present[self.shared.position[v as usize] as usize] = true;
        }
        // One render vertex of every position the simplification removed.
        let gone: Vec<u32> = (0..positions as u32)
            .filter(|&p| !present[p as usize])
            .filter_map(|p| {
                let t = *self.shared.fans.of(p).first()?;
                self.shared.surface.triangles[t as usize]
                    .into_iter()
                    .find(|&v| self.shared.position[v as usize] == p)
            })
            .collect();
        let budget = self.forward.max(1);
        let posed = |v: u32, f: usize| mesh.posed[mesh.slot[v as usize] as usize * frames + f];
        let original = |v: u32, f: usize| self.original_posed[v as usize * frames + f].as_dvec3();
        // The largest distance (squared) over the frames from `v` to the point of weights `w`
        // on the simplified mesh's triangle `t`.
        let followed = |v: u32, t: [u32; 3], w: [f64; 3]| {
            (0..frames)
                .map(|f| {
                    let q: DVec3 = (0..3).map(|k| posed(t[k], f).as_dvec3() * w[k]).sum();
                    q.distance_squared(original(v, f))
                })
                .fold(0.0, f64::max)
        };
        let (fans, triangles) = near;
        let bounded: Vec<(f64, u32)> = match follow {
            Some(follow) => {
                let bound = |&v: &u32| {
                    let to = follow(v);
                    if mesh.slot.get(to as usize).is_none_or(|&i| i == u32::MAX) {
                        return (f64::INFINITY, v);
                    }
                    let mut far = followed(v, [to; 3], [1.0, 0.0, 0.0]);
                    if self.every_vertex && far > beyond {
                        let p = self.shared.rest[v as usize];
                        let closest = fans
                            .of(self.shared.position[to as usize])
                            .iter()
                            .map(|&t| {
                                let tri = triangles[t as usize];
                                let located = Located {
                                    corners: tri.map(|c| {
                                        mesh.rest[mesh.slot[c as usize] as usize].to_array()
                                    }),
                                };
                                let (q, w) = located.closest(p);
                                (q.distance_squared(p), tri, w)
                            })
                            .min_by(|a, b| a.0.total_cmp(&b.0));
                        if let Some((_, tri, w)) = closest {
                            far = far.min(followed(v, tri, w));
                        }
                    }
                    (far, v)
                };
                let by_bound =
                    |a: &(f64, u32), b: &(f64, u32)| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1));
                let mut bound: Vec<(f64, u32)> = gone.par_iter().map(bound).collect();
                if !self.every_vertex && bound.len() > budget {
                    bound.select_nth_unstable_by(budget, by_bound);
                    bound.truncate(budget);
                }
                bound.retain(|&(far, _)| far > beyond);
                bound.par_sort_unstable_by(by_bound);
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
                let t = self.shared.fans.of(self.shared.position[v as usize])[0];
                let (tri, w) = self.at_vertex(&self.shared.surface.triangles, t, v);
                (bound, v, (tri, w, self.shared.rest[v as usize]))
            })
            .collect()
    }

    /// Samples at the simplified mesh's vertices that influence simplification moved furthest
    /// (in their worst frame), a quarter of the backward samples at most.
    fn moved_vertices(
        &self,
        mesh: &PosedMesh,
        simplified_fans: &Fans,
        triangles: &[[u32; 3]],
    ) -> Vec<([u32; 3], [f64; 3])> {
        let frames = self.frames.len();
        let mut shifted: Vec<(f64, u32)> = mesh
            .used
            .iter()
            .zip(&mesh.moved)
            .filter(|(_, m)| **m)
            .map(|(&v, _)| {
                let i = mesh.slot[v as usize] as usize;
                let shift = (0..frames)
                    .map(|f| {
                        mesh.posed[i * frames + f].as_dvec3().distance_squared(
                            self.original_posed[v as usize * frames + f].as_dvec3(),
                        )
                    })
                    .fold(0.0, f64::max);
                (shift, v)
            })
            .collect();
        shifted.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        shifted
            .iter()
            .take(self.backward / 4)
            .filter_map(|&(_, v)| {
                let t = *simplified_fans
                    .of(self.shared.position[v as usize])
                    .first()?;
                Some(self.at_vertex(triangles, t, v))
            })
            .collect()
    }
}

/// The changed part of a simplified mesh (see [`SurfaceProbe::changed`]).
struct Changed<'p> {
    /// Per simplified triangle, whether the original lacks it or its vertices moved.
    changed: Vec<bool>,
    /// The pooled original samples on changed triangles.
    forward: Vec<&'p SurfaceSample>,
    /// The share of the original surface that changed, and of the simplified one.
    forward_share: f64,
    backward_share: f64,
}

/// The largest distance (squared) over the removed vertices and `max2`, what the samples
/// found.
///
/// Removed vertices, furthest bound first, in batches, until no bound left can beat
/// the largest distance found: that maximum is then exact over every vertex. Where
/// every vertex counts, a bound is tightened (by the nearest triangle at rest, often
/// much nearer than the vertex it became) only for vertices whose first bound can
/// still beat the maximum: on a 2-million-triangle model, a level's million removed
/// vertices mostly cannot, and tightening them all was most of its measurement.
fn removed_maximum(
    removed: &[(f64, u32, SurfaceSample)],
    mut max2: f64,
    tighten: impl Fn(&(f64, u32, SurfaceSample)) -> (f64, SurfaceSample) + Sync,
    distance: impl Fn(&SurfaceSample) -> f64 + Sync,
) -> f64 {
    use rayon::prelude::*;
    let (mut tightened, mut exact) = (0, 0);
    for chunk in removed.chunks(TIGHTEN_CHUNK) {
        let live = chunk.partition_point(|r| r.0 > max2);
        if live == 0 {
            break;
        }
        tightened += live;
        let mut bounded: Vec<(f64, SurfaceSample)> =
            chunk[..live].par_iter().map(&tighten).collect();
        bounded.sort_by(|a, b| b.0.total_cmp(&a.0));
        for batch in bounded.chunks(64) {
            if batch[0].0 <= max2 {
                break;
            }
            exact += batch.len();
            let m = batch
                .par_iter()
                .map(|(_, s)| distance(s))
                .reduce(|| 0.0, f64::max);
            max2 = max2.max(m);
        }
    }
    log::trace!(
        "{} removed vertices: {tightened} bounds tightened, {exact} measured exactly",
        removed.len()
    );
    max2
}

/// The error from the sample totals, each with the share of its surface the samples stand
/// for (squared distance sum, sample count), and the largest distance found (squared): the
/// RMS is the mean of the two sides' shares of their mean squared distance.
fn mesh_error(forward: (f64, f64, usize), backward: (f64, f64, usize), max2: f64) -> MeshError {
    let (forward_share, forward_sum, forward_count) = forward;
    let (backward_share, backward_sum, backward_count) = backward;
    let mean = |sum: f64, count: usize| if count > 0 { sum / count as f64 } else { 0.0 };
    let ms = 0.5
        * (forward_share * mean(forward_sum, forward_count)
            + backward_share * mean(backward_sum, backward_count));
    MeshError {
        rms: ms.sqrt(),
        max: max2.sqrt(),
    }
}

/// `Σ G_i p_i` for one vertex's influences and bone matrices `g`.
fn pose_point(g: &[Affine3A], influences: &[AsInfluence]) -> DVec3 {
    influences
        .iter()
        .map(|i| {
            crate::bake::gpu_data::animation_space::transform_homogeneous(&g[i.bone as usize], i.p)
                .as_dvec3()
        })
        .sum()
}

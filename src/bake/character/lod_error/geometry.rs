//! Rest-pose surfaces for the closest-point correspondence: closest points on triangles, a
//! uniform grid for the nearest triangles, and area- and edge-weighted sampling.

use glam::DVec3;

/// A triangle, for closest points.
pub(super) struct Located {
    pub(super) corners: [[f64; 3]; 3],
}

impl Located {
    /// The closest point to `p` and its barycentric weights (Ericson, *Real-Time Collision
    /// Detection*, §5.1.5).
    pub(super) fn closest(&self, p: DVec3) -> (DVec3, [f64; 3]) {
        let [a, b, c] = self.corners.map(DVec3::from_array);
        let (ab, ac, ap) = (b - a, c - a, p - a);
        // A triangle of no area (two corners at one point, or all three on a line: a file's
        // debris, or a fold of a pose) is the nearest of its edges. Ericson's regions below
        // divide by the edges' lengths and gave NaN there, which made a level's RMS error NaN.
        if ab.cross(ac).length_squared() <= 1e-24 * ab.length_squared() * ac.length_squared() {
            let on = |x: DVec3, y: DVec3| {
                let d = y - x;
                let t = if d.length_squared() > 0.0 {
                    ((p - x).dot(d) / d.length_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (x + d * t, t)
            };
            let (pab, t1) = on(a, b);
            let (pbc, t2) = on(b, c);
            let (pca, t3) = on(c, a);
            return [
                (pab, [1.0 - t1, t1, 0.0]),
                (pbc, [0.0, 1.0 - t2, t2]),
                (pca, [t3, 0.0, 1.0 - t3]),
            ]
            .into_iter()
            .min_by(|x, y| x.0.distance_squared(p).total_cmp(&y.0.distance_squared(p)))
            .expect("three edges");
        }
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
    /// Triangles binned.
    count: usize,
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
            count: corners.len(),
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
        let consider = |t: u32, out: &mut Vec<(f64, u32)>| {
            if out.len() == k && lower2(t) >= out[k - 1].0 {
                return;
            }
            let d = distance2(t);
            if out.len() < k || d < out[k - 1].0 {
                let at = out.partition_point(|e| e.0 <= d);
                out.insert(at, (d, t));
                out.truncate(k);
            }
        };
        let c = self.cell_of(p).map(|x| x as i64);
        let dims = self.dims.map(|d| d as i64);
        let rings = dims.iter().copied().max().unwrap_or(1);
        let mut seen: Vec<u32> = Vec::new();
        // Cells looked at so far: a point far from a sparse surface (a coarse level whose
        // parts were pruned, far from where the original's samples lie) would search ring
        // after empty ring, each larger than the last; once the rings cost more than looking
        // at every triangle, every triangle is looked at instead.
        let mut visited = 0usize;
        for r in 0..=rings {
            // Every cell of ring r is at least r − 1 cells from the point.
            if out.len() == k {
                let bound = (r - 1).max(0) as f64 * self.cell;
                if out[k - 1].0 <= bound * bound {
                    break;
                }
            }
            let range = |i: usize| (c[i] - r).max(0)..=(c[i] + r).min(dims[i] - 1);
            let shell: usize = (0..3).map(|i| range(i).count()).product::<usize>()
                - (0..3)
                    .map(|i| ((c[i] - r + 1).max(0)..=(c[i] + r - 1).min(dims[i] - 1)).count())
                    .product::<usize>();
            visited += shell;
            if visited > 4 * self.count + 64 {
                out.clear();
                for t in 0..self.count as u32 {
                    consider(t, out);
                }
                return;
            }
            for z in range(2) {
                for y in range(1) {
                    // Inside the shell's faces in z and y, only its two x ends are on ring r:
                    // step from one to the other.
                    let inner = (y - c[1]).abs() < r && (z - c[2]).abs() < r;
                    let (x0, x1) = (*range(0).start(), *range(0).end());
                    let (first, last, step) = if inner {
                        (c[0] - r, c[0] + r, 2 * r)
                    } else {
                        (x0, x1, 1)
                    };
                    for x in (first..=last).step_by(step as usize) {
                        if x < x0 || x > x1 {
                            continue;
                        }
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
                            consider(t, out);
                        }
                    }
                }
            }
        }
    }
}

/// A rest-pose surface given as triangles of render vertices, indexed for closest points.
pub(crate) struct Surface {
    grid: TriangleGrid,
    /// Area-weighted running sums over `triangles`, for sampling.
    cumulative: Vec<f64>,
    pub(super) triangles: Vec<[u32; 3]>,
    corners: Vec<[DVec3; 3]>,
}

impl Surface {
    pub(crate) fn new(triangles: &[[u32; 3]], rest: impl Fn(u32) -> DVec3) -> Surface {
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
    /// The triangle nearest `p` and the barycentric weights of its point nearest `p`.
    pub(crate) fn closest(&self, p: DVec3) -> Option<([u32; 3], [f64; 3])> {
        let located = |t: u32| Located {
            corners: self.corners[t as usize].map(|x| x.to_array()),
        };
        let mut out = Vec::with_capacity(2);
        self.grid.nearest(
            p,
            1,
            |t| {
                let [a, b, c] = self.corners[t as usize];
                let gap = (a.min(b).min(c) - p).max(p - a.max(b).max(c));
                gap.max(DVec3::ZERO).length_squared()
            },
            |t| located(t).closest(p).0.distance_squared(p),
            &mut out,
        );
        let &(_, t) = out.first()?;
        Some((self.triangles[t as usize], located(t).closest(p).1))
    }

    pub(super) fn nearest(&self, p: DVec3, k: usize) -> Vec<[u32; 3]> {
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
    pub(super) fn area_share(&self, mask: &[bool]) -> f64 {
        let total = self.cumulative.last().copied().unwrap_or(0.0);
        let picked: f64 = (0..self.corners.len())
            .filter(|&t| mask[t])
            .map(|t| self.cumulative[t] - if t > 0 { self.cumulative[t - 1] } else { 0.0 })
            .sum();
        if total > 0.0 { picked / total } else { 0.0 }
    }

    /// `count` points drawn area-weighted from a fixed seed (on the triangles `mask` picks, if
    /// given): triangle and weights.
    pub(super) fn samples(
        &self,
        count: usize,
        seed: u64,
        mask: Option<&[bool]>,
    ) -> Vec<([u32; 3], [f64; 3])> {
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
    pub(super) fn edge_samples(
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

    #[test]
    fn a_triangle_of_no_area_is_its_nearest_edge() {
        let at = |c: [[f64; 3]; 3], p: [f64; 3]| {
            let (q, w) = Located { corners: c }.closest(DVec3::from_array(p));
            assert!(
                q.is_finite() && w.iter().all(|x| x.is_finite()),
                "{q} {w:?}"
            );
            q
        };
        // Two corners at one point: the segment to the third.
        let q = at([[0.0; 3], [0.0; 3], [2.0, 0.0, 0.0]], [1.0, 1.0, 0.0]);
        assert!(q.distance(DVec3::new(1.0, 0.0, 0.0)) < 1e-12, "{q}");
        // Three on a line, and all three at one point.
        let q = at(
            [[0.0; 3], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]],
            [2.5, -1.0, 0.0],
        );
        assert!(q.distance(DVec3::new(2.5, 0.0, 0.0)) < 1e-12, "{q}");
        let q = at([[1.0; 3]; 3], [0.0; 3]);
        assert_eq!(q, DVec3::ONE);
    }
}

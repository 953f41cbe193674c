//! A uniform grid over texture space for finding the triangles at a texture coordinate: how
//! points correspond through the parameterisation (appearance-preserving simplification, Cohen,
//! Olano & Manocha 1998), for the texture-space error of a level and for its normal map.

use glam::{DVec2, Vec2};

/// A uniform grid over texture space for locating points in triangles.
pub(crate) struct UvGrid {
    lo: DVec2,
    cell: DVec2,
    size: usize,
    cells: Vec<Vec<u32>>,
}

impl UvGrid {
    pub(crate) fn new(triangles: &[[u32; 3]], uvs: &[Vec2]) -> UvGrid {
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
        UvGrid {
            lo,
            cell,
            size,
            cells,
        }
    }

    /// The triangles whose texture-space bounds overlap the cell of `uv` (none outside the
    /// grid): the candidates for containing it.
    pub(crate) fn candidates(&self, uv: DVec2) -> &[u32] {
        let c = (uv - self.lo) / self.cell;
        let size = self.size as f64;
        if !(0.0..=size).contains(&c.x) || !(0.0..=size).contains(&c.y) {
            return &[];
        }
        let [x, y] = [c.x, c.y].map(|v| (v as usize).min(self.size - 1));
        &self.cells[y * self.size + x]
    }

    /// The triangle of `chart` containing `uv` and the barycentric weights there; if none
    /// contains it (a simplifier that changed the chart's outline), the nearest one, with the
    /// point clamped onto it; None where no triangle of the chart is left.
    ///
    /// A triangle is of the chart when all three corners are: one torn across charts by a
    /// corner collapse spans two islands of texture space and belongs to neither, and judging
    /// it by one corner made the answer depend on which corner a file lists first. Where
    /// triangles overlap (a fold left by the simplifier), the one the point is deepest inside
    /// wins, not the first listed, for the same reason.
    pub(crate) fn locate(
        &self,
        triangles: &[[u32; 3]],
        uvs: &[Vec2],
        chart: &[u32],
        want: u32,
        uv: DVec2,
    ) -> Option<([u32; 3], [f64; 3])> {
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
                        if tri.iter().any(|&v| chart[v as usize] != want) {
                            continue;
                        }
                        let [a, b, cc] = tri.map(|v| uvs[v as usize].as_dvec2());
                        let w =
                            crate::bake::character::simplify::collapse::barycentric(uv, a, b, cc);
                        let worst = w[0].min(w[1]).min(w[2]);
                        // Deepest inside, or least outside; equal ones by their corners.
                        let better = best.as_ref().is_none_or(|b| {
                            worst > b.0 || (worst == b.0 && sorted(tri) < sorted(b.1))
                        });
                        if worst.is_finite() && better {
                            best = Some((worst, tri, w));
                        }
                    }
                }
            }
            // A triangle containing the point overlaps its cell (ring 0); otherwise a
            // candidate from the first rings that had any is as good as any farther one.
            if best.as_ref().is_some_and(|b| b.0 >= -1e-9 || ring >= 1) {
                break;
            }
        }
        best.map(|(_, tri, w)| {
            let clamped = w.map(|x| x.max(0.0));
            let s: f64 = clamped.iter().sum::<f64>().max(1e-300);
            (tri, clamped.map(|x| x / s))
        })
    }
}

/// A triangle's corners in ascending order: the same key however the triangle is rotated.
pub(crate) fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two charts side by side in texture space (vertices 0–3 of chart 0, 4–7 of chart 1) and
    /// a triangle torn across them (corners 2, 3 and 4).
    fn charts() -> (Vec<[u32; 3]>, Vec<Vec2>, Vec<u32>) {
        let uvs = [
            (0.0, 0.0),
            (0.4, 0.0),
            (0.4, 1.0),
            (0.0, 1.0),
            (0.6, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.6, 1.0),
        ]
        .map(|(u, v)| Vec2::new(u, v))
        .to_vec();
        let triangles = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7], [2, 3, 4]];
        (triangles, uvs, vec![0, 0, 0, 0, 1, 1, 1, 1])
    }

    /// The answer is the same whichever corner of each triangle is listed first and whichever
    /// triangle comes first: a torn triangle belongs to neither chart.
    #[test]
    fn a_point_is_located_alike_in_any_order() {
        let (triangles, uvs, chart) = charts();
        let uv = DVec2::new(0.3, 0.8);
        let reference = UvGrid::new(&triangles, &uvs)
            .locate(&triangles, &uvs, &chart, 0, uv)
            .unwrap();
        for rotation in 0..3 {
            let mut turned: Vec<[u32; 3]> = triangles
                .iter()
                .map(|t| [t[rotation], t[(rotation + 1) % 3], t[(rotation + 2) % 3]])
                .collect();
            turned.reverse();
            let (tri, w) = UvGrid::new(&turned, &uvs)
                .locate(&turned, &uvs, &chart, 0, uv)
                .unwrap();
            assert_eq!(sorted(tri), sorted(reference.0));
            let point = |t: [u32; 3], w: [f64; 3]| -> DVec2 {
                (0..3).map(|k| uvs[t[k] as usize].as_dvec2() * w[k]).sum()
            };
            assert!(point(tri, w).distance(uv) < 1e-9);
            assert!(tri.iter().all(|&v| chart[v as usize] == 0), "{tri:?}");
        }
    }

    /// A chart with no triangle left has no answer: the caller matches the point otherwise.
    #[test]
    fn a_lost_chart_has_no_triangle() {
        let (triangles, uvs, chart) = charts();
        let kept: Vec<[u32; 3]> = triangles[..2].to_vec();
        let grid = UvGrid::new(&kept, &uvs);
        assert!(
            grid.locate(&kept, &uvs, &chart, 1, DVec2::new(0.8, 0.5))
                .is_none()
        );
        // A point of chart 0 outside its triangles is clamped onto the nearest.
        let (tri, w) = grid
            .locate(&kept, &uvs, &chart, 0, DVec2::new(0.5, 0.5))
            .unwrap();
        assert!(tri.iter().all(|&v| v < 4) && w.iter().all(|&x| x >= 0.0));
    }
}

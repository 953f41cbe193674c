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
    /// point clamped onto it.
    pub(crate) fn locate(
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
                        let w =
                            crate::bake::character::simplify::collapse::barycentric(uv, a, b, cc);
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

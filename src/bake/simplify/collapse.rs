//! Half-edge collapse candidates: legality, and the cell corners of the memoryless
//! appearance-preserving metric.
//!
//! Merry et al. §4, Figure 3, after Sander et al. 2001: in parameter space, the triangles around
//! v1 before the collapse and the triangles after it (v1's fan re-triangulated from v2) are
//! both linear within each cell of their overlay, so the difference between mesh Mᵢ and Mᵢ₊₁
//! is linear there and its largest norm sits at a cell corner. Away from v1's fan nothing
//! changes, and on the fan's outline the two meshes agree, so the corners that matter are v1's
//! own parameter point and the crossings of old interior edges (v1, a) with new ones (v2, b).
//! Each corner is returned as a combination of positions whose coefficients sum to zero; the
//! metric (rest-pose Euclidean, or L2,2 in animation space) turns it into a distance.
//!
//! The parameter space is each wedge's texture chart when the model has texture coordinates,
//! else a local flattening of v1's fan (its geodesic polar map: distances kept, angles scaled
//! to fill 2π, or π on a border, so a border vertex's two border neighbours lie on one line).

use super::mesh::{EdgeKind, Kind, Mesh, can_collapse};
use glam::{DVec2, DVec3};

/// One cell corner: `Σ c·p(position)` with `Σ c = 0`, at most four terms.
pub type Corner = [(u32, f64); 4];

/// Where parameter coordinates come from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Parameterisation {
    /// Texture coordinates. A border or seam vertex may slide along its chart outline only
    /// where it lies within `tolerance` of the line through its two outline neighbours, so the
    /// charts keep their area.
    Texture { tolerance: f64 },
    /// A local flattening of v1's fan, for models without texture coordinates.
    Flattening,
}

/// Why a candidate was turned down, for statistics and tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rejection {
    Kind,
    NotAlongOutline,
    Wedges,
    Link,
    /// v1's own fan is degenerate or inconsistently oriented in parameter space.
    BadFan,
    ParameterFold,
    NormalFlip,
    ChangesParameterArea,
}

/// Parameter coordinates of v1's fan in the flattening, by position (v1 at the origin).
pub struct Flattening {
    coords: Vec<(u32, DVec2)>,
}

impl Flattening {
    /// The geodesic polar map of `u`'s fan, or `None` if the fan is not a single ordered ring
    /// or is degenerate.
    pub fn new(mesh: &Mesh, rest: &[DVec3], u: u32) -> Option<Flattening> {
        let fan = &mesh.incident[u as usize];
        let mut next: Vec<(u32, u32)> = Vec::with_capacity(fan.len());
        for &t in fan {
            let [_, a, b] = mesh.corners_from(t, u);
            next.push((mesh.pos(a), mesh.pos(b)));
        }
        // Start at a neighbour nothing points to (an open fan), else anywhere (closed).
        let start = next
            .iter()
            .map(|&(a, _)| a)
            .find(|a| next.iter().all(|&(_, b)| b != *a));
        let closed = start.is_none();
        let mut ring = vec![start.unwrap_or(next[0].0)];
        loop {
            let last = *ring.last()?;
            let Some(&(_, b)) = next.iter().find(|&&(a, _)| a == last) else {
                break;
            };
            if closed && b == ring[0] {
                break;
            }
            if ring.contains(&b) || ring.len() > next.len() + 1 {
                return None;
            }
            ring.push(b);
        }
        let expected = if closed { next.len() } else { next.len() + 1 };
        if ring.len() != expected {
            return None;
        }
        let centre = rest[u as usize];
        let dirs: Vec<DVec3> = ring.iter().map(|&p| rest[p as usize] - centre).collect();
        let steps = if closed { ring.len() } else { ring.len() - 1 };
        let angles: Vec<f64> = (0..steps)
            .map(|j| dirs[j].angle_between(dirs[(j + 1) % ring.len()]))
            .collect();
        let total: f64 = angles.iter().sum();
        if total.is_nan() || total <= 1e-9 || angles.iter().any(|a| !a.is_finite()) {
            return None;
        }
        let scale = if closed {
            std::f64::consts::TAU
        } else {
            std::f64::consts::PI
        } / total;
        let mut phi = 0.0;
        let mut coords = Vec::with_capacity(ring.len() + 1);
        coords.push((u, DVec2::ZERO));
        for (j, &p) in ring.iter().enumerate() {
            coords.push((p, DVec2::from_angle(phi) * dirs[j].length()));
            if j < angles.len() {
                phi += angles[j] * scale;
            }
        }
        Some(Flattening { coords })
    }

    fn get(&self, position: u32) -> Option<DVec2> {
        self.coords
            .iter()
            .find(|(p, _)| *p == position)
            .map(|&(_, c)| c)
    }
}

/// Everything a candidate evaluation reads.
pub struct Context<'a> {
    pub mesh: &'a Mesh,
    pub uv: &'a [DVec2],
    /// Rest-pose positions, by position.
    pub rest: &'a [DVec3],
    pub param: Parameterisation,
}

/// Scratch space reused between evaluations.
#[derive(Default)]
pub struct Scratch {
    pub corners: Vec<Corner>,
    pub link: [Vec<u32>; 2],
    old: Vec<[u32; 3]>,
    new: Vec<[u32; 3]>,
    outline: Vec<(u32, u32)>,
    ends_old: Vec<u32>,
    ends_new: Vec<u32>,
}

impl Context<'_> {
    fn param(&self, flat: Option<&Flattening>, r: u32) -> Option<DVec2> {
        match flat {
            Some(f) => f.get(self.mesh.pos(r)),
            None => Some(self.uv[r as usize]),
        }
    }

    /// Checks the half-edge collapse `u1 → u2` and fills `scratch.corners` with its cell
    /// corners. `flat` is `u1`'s flattening when the parameterisation is [`Parameterisation::
    /// Flattening`].
    pub fn corners(
        &self,
        u1: u32,
        u2: u32,
        flat: Option<&Flattening>,
        scratch: &mut Scratch,
    ) -> Result<(), Rejection> {
        let mesh = self.mesh;
        let (k1, k2) = (mesh.kind[u1 as usize], mesh.kind[u2 as usize]);
        if !can_collapse(k1, k2) {
            return Err(Rejection::Kind);
        }
        let edge = mesh.edge_kind(u1, u2);
        match k1 {
            Kind::Border if edge != EdgeKind::Border => return Err(Rejection::NotAlongOutline),
            Kind::Seam if edge != EdgeKind::Seam => return Err(Rejection::NotAlongOutline),
            _ => {}
        }
        if edge == EdgeKind::NonManifold {
            return Err(Rejection::Link);
        }
        let map = mesh.wedge_map(u1, u2).ok_or(Rejection::Wedges)?;
        if !mesh.link_condition(u1, u2, &mut scratch.link) {
            return Err(Rejection::Link);
        }
        scratch.corners.clear();
        for &[r1, r2] in &map {
            self.wedge_corners(u1, u2, r1, r2, flat, scratch)?;
        }
        Ok(())
    }

    /// The part of the evaluation in one wedge's chart.
    fn wedge_corners(
        &self,
        u1: u32,
        u2: u32,
        r1: u32,
        r2: u32,
        flat: Option<&Flattening>,
        s: &mut Scratch,
    ) -> Result<(), Rejection> {
        let mesh = self.mesh;
        s.old.clear();
        s.new.clear();
        for &t in &mesh.incident[u1 as usize] {
            let tri = mesh.tris[t as usize];
            if !tri.contains(&r1) {
                continue;
            }
            // Rotate so r1 comes first; winding kept.
            let k = tri.iter().position(|&r| r == r1).unwrap_or(0);
            let tri = [tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]];
            s.old.push(tri);
            if mesh.pos(tri[1]) != u2 && mesh.pos(tri[2]) != u2 {
                s.new.push([r2, tri[1], tri[2]]);
            }
        }
        if s.new.is_empty() {
            return Err(Rejection::BadFan);
        }
        let p = |r: u32| self.param(flat, r).ok_or(Rejection::BadFan);
        let p1 = p(r1)?;
        let p2 = p(r2)?;

        // Orientation of the chart around r1, and a scale for the tolerances.
        let mut extent2: f64 = 0.0;
        let mut sign = 0.0;
        for tri in &s.old {
            let (a, b) = (p(tri[1])?, p(tri[2])?);
            extent2 = extent2
                .max((a - p1).length_squared())
                .max((b - p1).length_squared());
            let area = (a - p1).perp_dot(b - p1);
            if sign == 0.0 {
                sign = area.signum();
            }
            if area * sign <= 0.0 {
                return Err(Rejection::BadFan);
            }
        }
        let min_area = 1e-10 * extent2;
        if s.old.iter().any(|tri| {
            let (a, b) = (p(tri[1]).unwrap_or(p1), p(tri[2]).unwrap_or(p1));
            ((a - p1).perp_dot(b - p1) * sign) <= min_area
        }) {
            return Err(Rejection::BadFan);
        }

        // No fold-over in parameter space, no flipped normal in the rest pose.
        for (i, tri) in s.new.iter().enumerate() {
            let (a, b) = (p(tri[1])?, p(tri[2])?);
            if (a - p2).perp_dot(b - p2) * sign <= min_area {
                return Err(Rejection::ParameterFold);
            }
            let old = s
                .old
                .iter()
                .find(|o| o[1] == tri[1] && o[2] == tri[2])
                .copied()
                .unwrap_or(s.old[i]);
            let x = |r: u32| self.rest[mesh.pos(r) as usize];
            let n_old = (x(old[1]) - x(old[0])).cross(x(old[2]) - x(old[0]));
            let n_new = (x(tri[1]) - x(tri[0])).cross(x(tri[2]) - x(tri[0]));
            if n_old.dot(n_new) <= 0.0 {
                return Err(Rejection::NormalFlip);
            }
        }

        // The chart outline through r1 (edges used by one fan triangle only): a border or seam
        // vertex keeps the chart's area only if it lies on the straight line from its other
        // outline neighbour to r2.
        s.outline.clear();
        for tri in &s.old {
            for (a, dir) in [(tri[1], 0u32), (tri[2], 1u32)] {
                match s.outline.iter().position(|&(x, _)| x == a) {
                    Some(i) => s.outline[i].1 = 2,
                    None => s.outline.push((a, dir)),
                }
            }
        }
        s.outline.retain(|&(_, n)| n < 2);
        match s.outline.len() {
            0 => {}
            2 => {
                let (Some(&(prev, _)), true) = (
                    s.outline.iter().find(|&&(a, _)| mesh.pos(a) != u2),
                    s.outline.iter().any(|&(a, _)| mesh.pos(a) == u2),
                ) else {
                    return Err(Rejection::NotAlongOutline);
                };
                let q = p(prev)?;
                let tolerance = match self.param {
                    Parameterisation::Texture { tolerance } => tolerance,
                    Parameterisation::Flattening => 1e-9 * extent2.sqrt(),
                };
                let line = p2 - q;
                let len = line.length();
                let off = (p1 - q).perp_dot(line).abs() / len.max(1e-300);
                let along = (p1 - q).dot(line) / (len * len).max(1e-300);
                if off > tolerance || !(along > 0.0 && along < 1.0) {
                    return Err(Rejection::ChangesParameterArea);
                }
            }
            _ => return Err(Rejection::NotAlongOutline),
        }

        // Corner 1: v1's parameter point, inside (or on the edge of) one new triangle.
        let mut best: Option<([u32; 3], [f64; 3])> = None;
        for tri in &s.new {
            let bary = barycentric(p1, p(tri[0])?, p(tri[1])?, p(tri[2])?);
            let worst = bary[0].min(bary[1]).min(bary[2]);
            if best.is_none_or(|(_, b)| worst > b[0].min(b[1]).min(b[2])) {
                best = Some((*tri, bary));
            }
        }
        let (tri, bary) = best.ok_or(Rejection::BadFan)?;
        s.corners.push([
            (u1, 1.0),
            (mesh.pos(tri[0]), -bary[0]),
            (mesh.pos(tri[1]), -bary[1]),
            (mesh.pos(tri[2]), -bary[2]),
        ]);

        // Crossings of old edges (v1, a) with new edges (v2, b).
        s.ends_old.clear();
        s.ends_new.clear();
        for tri in &s.old {
            for &a in &tri[1..] {
                if mesh.pos(a) != u2 && !s.ends_old.contains(&a) {
                    s.ends_old.push(a);
                }
            }
        }
        for tri in &s.new {
            for &b in &tri[1..] {
                if !s.ends_new.contains(&b) {
                    s.ends_new.push(b);
                }
            }
        }
        for &a in &s.ends_old {
            let pa = p(a)?;
            for &b in &s.ends_new {
                if a == b {
                    continue;
                }
                let pb = p(b)?;
                let (da, db) = (pa - p1, pb - p2);
                let denom = da.perp_dot(db);
                if denom.abs() <= 1e-14 * da.length() * db.length() {
                    continue;
                }
                let w = p2 - p1;
                let alpha = w.perp_dot(db) / denom;
                let beta = w.perp_dot(da) / denom;
                const EDGE: f64 = 1e-9;
                if alpha > EDGE && alpha < 1.0 - EDGE && beta > EDGE && beta < 1.0 - EDGE {
                    s.corners.push([
                        (u1, 1.0 - alpha),
                        (mesh.pos(a), alpha),
                        (u2, -(1.0 - beta)),
                        (mesh.pos(b), -beta),
                    ]);
                }
            }
        }
        Ok(())
    }
}

/// Barycentric coordinates of `p` in triangle `(a, b, c)`.
pub fn barycentric(p: DVec2, a: DVec2, b: DVec2, c: DVec2) -> [f64; 3] {
    let d = (b - a).perp_dot(c - a);
    if d == 0.0 {
        return [f64::NEG_INFINITY; 3];
    }
    let wb = (p - a).perp_dot(c - a) / d;
    let wc = (b - a).perp_dot(p - a) / d;
    [1.0 - wb - wc, wb, wc]
}

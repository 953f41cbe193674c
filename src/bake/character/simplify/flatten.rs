//! A texture chart round a vertex flattened into the plane, so that a collapse's texture
//! slide can be priced and its fan checked for folds in texture space.

use super::mesh::Mesh;
use glam::{DVec2, DVec3};

/// Parameter coordinates of one wedge's sector of v1's fan (or of the whole fan) in its
/// geodesic polar map, by position (v1 at the origin).
pub struct Flattening {
    pub(crate) coords: Vec<(u32, DVec2)>,
}

impl Flattening {
    /// The geodesic polar map of the triangles round position `u` that use render vertex `r`
    /// (all of `u`'s fan for `None` or a position with one wedge), or `None` if they do not
    /// form a single ordered fan or are degenerate.
    pub fn new(mesh: &Mesh, rest: &[DVec3], u: u32, r: Option<u32>) -> Option<Flattening> {
        let fan = &mesh.incident[u as usize];
        let mut next: Vec<(u32, u32)> = Vec::with_capacity(fan.len());
        for &t in fan {
            if r.is_some_and(|r| !mesh.tris[t as usize].contains(&r)) {
                continue;
            }
            let [_, a, b] = mesh.corners_from(t, u);
            next.push((mesh.pos(a), mesh.pos(b)));
        }
        if next.is_empty() {
            return None;
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

    pub(crate) fn get(&self, position: u32) -> Option<DVec2> {
        self.coords
            .iter()
            .find(|(p, _)| *p == position)
            .map(|&(_, c)| c)
    }
}

/// The parameter space one wedge's corners are computed in.
#[derive(Clone, Copy)]
pub(crate) enum Chart<'f> {
    Texture,
    /// The wedge's sector of the fan.
    Polar(&'f Flattening),
    /// The whole fan, for the geometry alone.
    Whole(&'f Flattening),
}

impl Chart<'_> {
    /// Which kind of chart this is: with the wedge, what v1's old fan is cached under (the
    /// flattening of a wedge or of the whole fan is itself cached per v1).
    pub(crate) fn kind(self) -> u8 {
        match self {
            Chart::Texture => 0,
            Chart::Polar(_) => 1,
            Chart::Whole(_) => 2,
        }
    }
}

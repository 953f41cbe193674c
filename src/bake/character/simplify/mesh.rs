//! The simplifier's view of a mesh: flat arrays, no pointer graph (after meshoptimizer's
//! `simplifier.cpp`).
//!
//! A *render vertex* is what the GPU draws: a position with one normal, one texture coordinate
//! and one material. Render vertices at the same animation-space point are the *wedges* of one
//! *position*; a *seam* is where two wedges meet, whether a texture chart, a hard edge (a
//! normal split) or a material ends there. Topology (neighbours, borders, seams,
//! manifoldness, connected parts) is worked out on positions, so a seam never looks like a
//! hole, while the parameter-space tests work on each wedge's own chart.
//!
//! Positions come from welding ([`weld_positions`]): exporters write the copies of a split
//! vertex independently, and after their transforms and weight normalisation the copies differ
//! by rounding. Render vertices whose rest positions agree within [`WELD_TOLERANCE`] of the
//! model's size and whose weights agree within [`WEIGHT_TOLERANCE`] are one position, indexed
//! or not, as meshoptimizer's `generatePositionRemap` does for exact copies.
//!
//! Each position gets a [`Kind`], and [`CAN_COLLAPSE`] says which kind may collapse onto which.

use super::influence::Influence64;
use glam::DVec3;
use rustc_hash::{FxHashMap, FxHashSet};
use smallvec::SmallVec;

/// Rest positions closer than this fraction of the bounding-box diagonal are one point.
pub const WELD_TOLERANCE: f32 = 1e-5;
/// Skin weights differing by less than this are the same skinning.
pub const WEIGHT_TOLERANCE: f64 = 1e-3;

/// For every render vertex, the position it belongs to: one of the render vertices at the
/// same rest position (within [`WELD_TOLERANCE`] of the bounding-box diagonal) with the same
/// skinning (every bone's weight within [`WEIGHT_TOLERANCE`]). Copies whose weights differ
/// more move apart when the character moves: they stay separate positions.
///
/// The position is the copy least in rest position, then in skinning, not the first listed:
/// its rest point and weights are the position's, copies differ by rounding, and a tube's
/// rings have one coordinate equal but for that rounding, so which copy speaks for a position
/// must not depend on the file's vertex order (see [`Ties`](super::prepare::Ties)).
pub fn weld_positions(rest: &[DVec3], infl: &[Vec<Influence64>]) -> Vec<u32> {
    let mut position = first_copies(rest, infl);
    let least = |a: usize, b: usize| {
        point_order(rest[a], rest[b])
            .then_with(|| {
                let p = |v: usize| {
                    infl[v]
                        .iter()
                        .flat_map(|i| i.p)
                        .collect::<SmallVec<[f64; 16]>>()
                };
                p(a).iter()
                    .zip(p(b).iter())
                    .map(|(s, t)| s.total_cmp(t))
                    .find(|o| o.is_ne())
                    .unwrap_or(std::cmp::Ordering::Equal)
            })
            .then(a.cmp(&b))
            .is_lt()
    };
    let mut speaker: Vec<u32> = (0..position.len() as u32).collect();
    for (v, &first) in position.iter().enumerate() {
        let first = first as usize;
        if least(v, speaker[first] as usize) {
            speaker[first] = v as u32;
        }
    }
    for p in &mut position {
        *p = speaker[*p as usize];
    }
    position
}

/// A total order of points, by x, then y, then z: ties and copies are decided by what a point
/// is, not by where a file lists it.
pub(crate) fn point_order(a: DVec3, b: DVec3) -> std::cmp::Ordering {
    (a.x.total_cmp(&b.x))
        .then(a.y.total_cmp(&b.y))
        .then(a.z.total_cmp(&b.z))
}

/// [`weld_positions`] with each position named by its first copy.
fn first_copies(rest: &[DVec3], infl: &[Vec<Influence64>]) -> Vec<u32> {
    let points: Vec<glam::Vec3> = rest.iter().map(|p| p.as_vec3()).collect();
    let diagonal = crate::model::Bounds::of(points.iter().copied()).map_or(0.0, |b| b.diagonal());
    let groups = crate::geometry::weld::position_groups(&points, diagonal * WELD_TOLERANCE);
    let mut members: FxHashMap<u32, Vec<u32>> = FxHashMap::default();
    let mut position = Vec::with_capacity(rest.len());
    for (v, &g) in groups.iter().enumerate() {
        let list = members.entry(g).or_default();
        let rep = list
            .iter()
            .copied()
            .find(|&r| same_skinning(&infl[r as usize], &infl[v]))
            .unwrap_or(v as u32);
        if rep == v as u32 {
            list.push(rep);
        }
        position.push(rep);
    }
    position
}

/// Every bone's weight (the homogeneous part of its `p_i`) agrees within
/// [`WEIGHT_TOLERANCE`]; a bone one list lacks counts as weight 0.
fn same_skinning(a: &[Influence64], b: &[Influence64]) -> bool {
    let weight = |list: &[Influence64], bone: u32| {
        list.iter().find(|i| i.bone == bone).map_or(0.0, |i| i.p[3])
    };
    a.iter()
        .chain(b)
        .all(|i| (weight(a, i.bone) - weight(b, i.bone)).abs() <= WEIGHT_TOLERANCE)
}

/// A wedge map: pairs of render vertices (of `u1`, of `u2`), each marked torn or not. On the
/// stack for the usual one to four wedges, since one is built for every candidate priced.
pub type WedgeMap = SmallVec<[([u32; 2], bool); 4]>;

/// What a position is, topologically. Decides which half-edge collapses may remove it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Inside one chart, one closed fan of triangles.
    Manifold,
    /// On an open border of the mesh: exactly two border edges, one wedge.
    Border,
    /// On a seam (texture chart, hard edge or material): exactly two seam edges, two wedges,
    /// no border.
    Seam,
    /// Where three or more charts meet, or a seam ends: one closed fan, no border, seam edges
    /// other than the two of a plain seam.
    /// It may slide along one of its seams, tearing the charts that do not reach the vertex it
    /// slides onto; what that does to the texture is priced (see `collapse`), so it happens
    /// only at coarse levels.
    Corner,
    /// Anything else that is still a valid surface point: where a seam meets a border, a
    /// border vertex of several fans, a bow-tie. Collapsing it would reshape the outline.
    Complex,
    /// Cannot be handled safely: a non-manifold edge, inconsistent winding.
    Locked,
}

impl Kind {
    fn index(self) -> usize {
        self as usize
    }
}

/// Which kind of vertex v1 may collapse onto which kind of v2 in a half-edge collapse v1 → v2
/// (rows: v1, columns: v2, in [`Kind`] order), as meshoptimizer's `kCanCollapse`:
/// - a manifold vertex may go anywhere: its whole fan lies in one chart;
/// - a border or seam vertex may only slide along its own border or seam onto the next vertex
///   there (checked in the cost evaluation), so the mesh's outline and its charts' outlines
///   keep their place; it may end on a vertex that cannot move itself, as a seam ends at a
///   chart corner;
/// - a corner may slide along one of its seams onto the next vertex there;
/// - complex and locked vertices stay.
pub const CAN_COLLAPSE: [[bool; 6]; 6] = [
    // Manifold Border Seam  Corner Complex Locked     v1 ↓  v2 →
    [true, true, true, true, true, true],       // Manifold
    [false, true, false, false, true, true],    // Border
    [false, false, true, true, true, true],     // Seam
    [false, false, true, true, true, true],     // Corner
    [false, false, false, false, false, false], // Complex
    [false, false, false, false, false, false], // Locked
];

pub fn can_collapse(from: Kind, to: Kind) -> bool {
    CAN_COLLAPSE[from.index()][to.index()]
}

/// How the edge between two positions sits in the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeKind {
    /// One triangle: an open border.
    Border,
    /// Two triangles that use the same wedges at both ends.
    Interior,
    /// Two triangles that use different wedges at one end at least.
    Seam,
    /// More than two triangles.
    NonManifold,
}

/// A position's triangles: about six on a mesh of even valence, held inline so that a mesh is
/// a few flat arrays rather than a million small allocations (the level cutter clones one
/// for every probe of a cut, and on a 2-million-triangle model the lists were most of it).
pub type Fan = SmallVec<[u32; 6]>;
/// A position's render vertices: one, or two on a seam, almost always.
pub type Wedges = SmallVec<[u32; 2]>;

/// The mutable mesh being simplified.
#[derive(Clone)]
pub struct Mesh {
    /// Triangles as render vertices.
    pub tris: Vec<[u32; 3]>,
    pub tri_alive: Vec<bool>,
    /// Render vertex → its position (one of its copies, see [`weld_positions`]).
    pub position: Vec<u32>,
    /// Position → its render vertices (empty for ids that are not positions).
    pub wedges: Vec<Wedges>,
    /// Position → its alive triangles.
    pub incident: Vec<Fan>,
    pub kind: Vec<Kind>,
    /// Positions still in the mesh.
    pub alive: Vec<bool>,
    /// Render vertex → how many alive triangles use it.
    pub refs: Vec<u32>,
    pub alive_triangles: usize,
    /// Triangles dropped before simplifying: repeated positions, duplicates.
    pub dropped_triangles: usize,
}

impl Mesh {
    /// Builds the mesh from indexed triangles and every render vertex's position (see
    /// [`weld_positions`]), every position [`Kind::Locked`] until [`Self::classify_all`].
    /// Triangles that repeat a position or duplicate another triangle are dropped: they cover
    /// no area and would make edges look non-manifold.
    pub fn new(indices: &[u32], position: Vec<u32>) -> Mesh {
        let n = position.len();
        let mut wedges = vec![Wedges::new(); n];
        let mut tris = Vec::with_capacity(indices.len() / 3);
        let mut seen = FxHashSet::with_capacity_and_hasher(indices.len() / 3, Default::default());
        let mut dropped = 0;
        for t in indices.chunks_exact(3) {
            let tri = [t[0], t[1], t[2]];
            if tri.iter().any(|&v| v as usize >= n) {
                dropped += 1;
                continue;
            }
            let mut p = tri.map(|v| position[v as usize]);
            if p[0] == p[1] || p[1] == p[2] || p[0] == p[2] {
                dropped += 1;
                continue;
            }
            p.sort_unstable();
            if !seen.insert(p) {
                dropped += 1;
                continue;
            }
            tris.push(tri);
        }
        let mut incident = vec![Fan::new(); n];
        let mut refs = vec![0u32; n];
        for (i, t) in tris.iter().enumerate() {
            for &v in t {
                incident[position[v as usize] as usize].push(i as u32);
                refs[v as usize] += 1;
            }
        }
        for v in 0..n {
            if refs[v] > 0 {
                wedges[position[v] as usize].push(v as u32);
            }
        }
        let alive: Vec<bool> = (0..n).map(|u| !incident[u].is_empty()).collect();
        Mesh {
            tri_alive: vec![true; tris.len()],
            alive_triangles: tris.len(),
            tris,
            position,
            wedges,
            incident,
            kind: vec![Kind::Locked; n],
            alive,
            refs,
            dropped_triangles: dropped,
        }
    }

    /// Gives every position its [`Kind`]: what the simplifier needs and a replay of its steps
    /// does not.
    pub fn classify_all(&mut self) {
        for u in 0..self.position.len() {
            if self.alive[u] {
                self.kind[u] = self.classify(u as u32);
            }
        }
    }

    pub fn pos(&self, r: u32) -> u32 {
        self.position[r as usize]
    }

    /// The triangle's corner at position `u` and the other two corners in winding order.
    pub fn corners_from(&self, t: u32, u: u32) -> [u32; 3] {
        let tri = self.tris[t as usize];
        let k = (0..3).find(|&k| self.pos(tri[k]) == u).unwrap_or(0);
        [tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]]
    }

    pub fn contains_position(&self, t: u32, u: u32) -> bool {
        self.tris[t as usize].iter().any(|&r| self.pos(r) == u)
    }

    /// Distinct neighbouring positions of `u`, in first-seen order.
    pub fn neighbours(&self, u: u32, out: &mut Vec<u32>) {
        out.clear();
        for &t in &self.incident[u as usize] {
            for r in self.tris[t as usize] {
                let x = self.pos(r);
                if x != u && !out.contains(&x) {
                    out.push(x);
                }
            }
        }
    }

    /// Classifies the edge between positions `u` and `x` (which must share a triangle).
    pub fn edge_kind(&self, u: u32, x: u32) -> EdgeKind {
        let mut count = 0;
        let mut ends: Option<(u32, u32)> = None;
        let mut seam = false;
        for &t in &self.incident[u as usize] {
            let tri = self.tris[t as usize];
            let ru = tri.iter().copied().find(|&r| self.pos(r) == u);
            let rx = tri.iter().copied().find(|&r| self.pos(r) == x);
            if let (Some(ru), Some(rx)) = (ru, rx) {
                count += 1;
                match ends {
                    None => ends = Some((ru, rx)),
                    Some(e) => seam |= e != (ru, rx),
                }
            }
        }
        match count {
            0 | 1 => EdgeKind::Border,
            2 if seam => EdgeKind::Seam,
            2 => EdgeKind::Interior,
            _ => EdgeKind::NonManifold,
        }
    }

    fn classify(&self, u: u32) -> Kind {
        let fan = &self.incident[u as usize];
        let mut neighbours = Vec::new();
        self.neighbours(u, &mut neighbours);
        let (mut border, mut seam) = (0, 0);
        for &x in &neighbours {
            match self.edge_kind(u, x) {
                EdgeKind::NonManifold => return Kind::Locked,
                EdgeKind::Border => border += 1,
                EdgeKind::Seam => seam += 1,
                EdgeKind::Interior => {}
            }
            // Two triangles on an edge must run along it in opposite directions, or the surface
            // is not orientable here and "fold-over" means nothing.
            let mut forward = 0;
            let mut backward = 0;
            for &t in fan {
                let [_, a, b] = self.corners_from(t, u);
                if self.pos(a) == x {
                    forward += 1;
                }
                if self.pos(b) == x {
                    backward += 1;
                }
            }
            if forward > 1 || backward > 1 {
                return Kind::Locked;
            }
        }
        // The fan must be one connected piece (else it is a bow-tie).
        let mut reached = vec![false; fan.len()];
        let mut stack = vec![0usize];
        reached[0] = true;
        while let Some(i) = stack.pop() {
            let ti = self.tris[fan[i] as usize].map(|r| self.pos(r));
            for (j, &tj) in fan.iter().enumerate() {
                if reached[j] {
                    continue;
                }
                let tj = self.tris[tj as usize].map(|r| self.pos(r));
                let shared = ti.iter().filter(|&&p| p != u && tj.contains(&p)).count();
                if shared > 0 {
                    reached[j] = true;
                    stack.push(j);
                }
            }
        }
        if reached.iter().any(|r| !r) {
            return Kind::Complex;
        }
        match (self.wedges[u as usize].len(), border, seam) {
            (1, 0, 0) => Kind::Manifold,
            (1, 2, 0) => Kind::Border,
            (2, 0, 2) => Kind::Seam,
            (_, 0, s) if s > 0 => Kind::Corner,
            _ => Kind::Complex,
        }
    }

    /// Classifies position `u` again: a corner's collapse can change what its neighbours are.
    pub fn reclassify(&mut self, u: u32) {
        if self.alive[u as usize] {
            self.kind[u as usize] = self.classify(u);
        }
    }

    /// For a collapse of position `u1` onto `u2`: which wedge of `u2` each wedge of `u1` becomes.
    /// A wedge of `u1` goes to the wedge of `u2` it shares a triangle with; `None` if a wedge
    /// shares none or more than one (the collapse would tear a chart).
    pub fn wedge_map(&self, u1: u32, u2: u32) -> Option<Vec<[u32; 2]>> {
        self.torn_wedge_map(u1, u2, |_, _| None)
            .map(|m| m.into_iter().map(|(pair, _)| pair).collect())
    }

    /// [`Self::wedge_map`] for a corner: a wedge of `u1` that shares no triangle with `u2`
    /// (its chart does not reach `u2`), or shares triangles with two of its wedges, goes to
    /// the wedge of `u2` that `torn` picks among the candidates it is given, and is marked
    /// torn. `None` where `torn` picks none.
    pub fn torn_wedge_map(
        &self,
        u1: u32,
        u2: u32,
        torn: impl Fn(u32, &[u32]) -> Option<u32>,
    ) -> Option<WedgeMap> {
        let mut map = WedgeMap::new();
        let mut shared: SmallVec<[u32; 4]> = SmallVec::new();
        for &r1 in &self.wedges[u1 as usize] {
            shared.clear();
            for &t in &self.incident[u1 as usize] {
                let tri = self.tris[t as usize];
                if !tri.contains(&r1) {
                    continue;
                }
                if let Some(r2) = tri.iter().copied().find(|&r| self.pos(r) == u2)
                    && !shared.contains(&r2)
                {
                    shared.push(r2);
                }
            }
            match shared.len() {
                1 => map.push(([r1, shared[0]], false)),
                0 => map.push(([r1, torn(r1, &self.wedges[u2 as usize])?], true)),
                _ => map.push(([r1, torn(r1, &shared)?], true)),
            }
        }
        Some(map)
    }

    /// Hoppe's link condition for a manifold result: the positions adjacent to both ends must
    /// be exactly the apexes of the triangles on the edge. Otherwise the collapse would glue two
    /// sheets together along an edge. `n1` holds the neighbours of `u1`.
    pub fn link_condition(&self, u1: u32, u2: u32, n1: &[u32]) -> bool {
        // The apex of every triangle on the edge.
        let mut apexes: SmallVec<[u32; 4]> = SmallVec::new();
        for &t in &self.incident[u1 as usize] {
            if self.contains_position(t, u2) {
                let apex = self.tris[t as usize]
                    .iter()
                    .map(|&r| self.pos(r))
                    .find(|&x| x != u1 && x != u2);
                apexes.push(apex.unwrap_or(u32::MAX));
            }
        }
        // Every common neighbour must be an apex, and there must be as many as there are
        // triangles on the edge. Adjacency to u2 is read off x's own fan: no list of u2's
        // neighbours is built for each candidate.
        let mut common = 0;
        for &x in n1 {
            if x == u2
                || !self.incident[x as usize]
                    .iter()
                    .any(|&t| self.contains_position(t, u2))
            {
                continue;
            }
            if !apexes.contains(&x) {
                return false;
            }
            common += 1;
        }
        common == apexes.len()
    }

    /// Applies the half-edge collapse `u1 → u2` with the given wedge map. Returns how many
    /// triangles died, and the render vertices that stopped being used.
    pub fn collapse(&mut self, u1: u32, u2: u32, map: &[[u32; 2]]) -> (usize, Vec<u32>) {
        let fan = std::mem::take(&mut self.incident[u1 as usize]);
        let mut died = 0;
        let mut released = Vec::new();
        for t in fan {
            let tri = self.tris[t as usize];
            if tri.iter().any(|&r| self.pos(r) == u2) {
                self.kill_triangle(t, u1, &mut released);
                died += 1;
            } else {
                let tri = &mut self.tris[t as usize];
                for r in tri.iter_mut() {
                    if let Some(&[from, to]) = map.iter().find(|m| m[0] == *r) {
                        debug_assert_eq!(from, *r);
                        self.refs[from as usize] -= 1;
                        self.refs[to as usize] += 1;
                        if self.refs[from as usize] == 0 {
                            released.push(from);
                        }
                        *r = to;
                    }
                }
                self.incident[u2 as usize].push(t);
            }
        }
        self.alive_triangles -= died;
        self.alive[u1 as usize] = false;
        // A wedge of u2 can drop to no triangles midway and gain some back.
        released.retain(|&r| self.refs[r as usize] == 0);
        released.sort_unstable();
        released.dedup();
        for &r in &released {
            let p = self.pos(r) as usize;
            self.wedges[p].retain(|w| *w != r);
        }
        (died, released)
    }

    /// Marks triangle `t` dead: its render vertices lose a reference (those left with none go
    /// to `released`), and it leaves the fans of its positions other than `owner`, whose fan
    /// the caller has taken.
    fn kill_triangle(&mut self, t: u32, owner: u32, released: &mut Vec<u32>) {
        self.tri_alive[t as usize] = false;
        for r in self.tris[t as usize] {
            self.refs[r as usize] -= 1;
            if self.refs[r as usize] == 0 {
                released.push(r);
            }
            let p = self.pos(r);
            if p != owner {
                self.incident[p as usize].retain(|x| *x != t);
            }
        }
    }

    /// Removes every triangle of the positions `positions` (one connected part): returns how
    /// many died and the render vertices that stopped being used.
    pub fn prune(&mut self, positions: &[u32]) -> (usize, Vec<u32>) {
        let mut died = 0;
        let mut released = Vec::new();
        for &u in positions {
            for t in std::mem::take(&mut self.incident[u as usize]) {
                if !self.tri_alive[t as usize] {
                    continue;
                }
                self.kill_triangle(t, u, &mut released);
                died += 1;
            }
            self.alive[u as usize] = false;
        }
        self.alive_triangles -= died;
        released.sort_unstable();
        released.dedup();
        for &r in &released {
            let p = self.pos(r) as usize;
            self.wedges[p].retain(|w| *w != r);
        }
        (died, released)
    }

    /// The connected parts of the mesh, as lists of positions (joined through triangles, so
    /// seams do not split a part).
    pub fn components(&self) -> Vec<Vec<u32>> {
        let tris: Vec<[u32; 3]> = self
            .tris
            .iter()
            .zip(&self.tri_alive)
            .filter(|(_, alive)| **alive)
            .map(|(t, _)| t.map(|r| self.pos(r)))
            .collect();
        let piece =
            crate::geometry::connected_pieces(self.position.len(), tris.iter().map(|t| &t[..]));
        let mut index: FxHashMap<u32, usize> = FxHashMap::default();
        let mut parts: Vec<Vec<u32>> = Vec::new();
        for u in 0..self.position.len() as u32 {
            if !self.alive[u as usize] || self.pos(u) != u {
                continue;
            }
            let i = *index.entry(piece[u as usize]).or_insert_with(|| {
                parts.push(Vec::new());
                parts.len() - 1
            });
            parts[i].push(u);
        }
        parts
    }
}

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
//! Which parameter space makes points correspond is chosen per wedge, that is per chart that
//! meets at v1:
//! - **the texture chart** where it is a parameterisation: every triangle of the wedge's fan
//!   has texture area and they agree in orientation. This is the appearance-preserving
//!   correspondence of the paper: points with the same texture coordinate.
//! - **a geometric correspondence** where texture coordinates are missing, degenerate (zero or
//!   tiny area, as exporters leave untextured parts) or folded, and where the collapse would
//!   fold the chart or change its outline. The wedge's sector of v1's fan is mapped to the
//!   plane by its geodesic polar map (distances to v1 kept, angles scaled to fill 2π, or π for
//!   a sector bounded by a border or seam, whose two outline neighbours then lie on one line),
//!   and points correspond where they map to the same point: the local-plane correspondence
//!   of Cohen, Manocha & Olano, "Simplifying polygonal models using successive mappings"
//!   (1997), with the polar map instead of a projection so that a curved fan never folds.
//!   Under this correspondence the texture coordinates of corresponding points can differ: a
//!   textured model pays for that as well, the texture's slide over the surface
//!   (`|Δuv|` times the atlas's metres per texture unit) added in quadrature to the position's
//!   deviation, so moving a chart outline costs what it does to the picture.
//! - **the whole fan's polar map** where charts do not survive the collapse whole: a corner
//!   (where three or more charts meet) collapses onto a neighbour that some of its charts do
//!   not reach, and those charts get that vertex's attributes (texture coordinate, normal)
//!   from another chart; or a chart's whole sector dies with the collapsed edge. The fan's
//!   geometry is then measured over all of it at once. The torn or lost charts' triangles
//!   show the wrong part of the texture (or the wrong normal): what that costs is bounded by
//!   the triangles' size, as if they were missing (no point of them is further than that from
//!   surface shown right), weighted by how much the attributes differ (fully for a texture,
//!   by `1 − cos` of the angle for a normal alone). So a model tears its charts and hard edges
//!   only where that size is within the level's error.
//!
//! A collapse must also leave every triangle facing the way it faced, and no thinner than a
//! sliver, in the rest pose and in every sampled pose: a triangle that turns over or thins to
//! a needle in some pose is a fold or a spike the metric, an average over poses, could
//! overlook.

use super::mesh::{EdgeKind, Kind, Mesh, WedgeMap, can_collapse};
use crate::bake::character::simplify::flatten::{Chart, Flattening};
use crate::bake::character::simplify::posed::{MAX_FAN, Posed, Rejection, check_triangle};
use glam::{DVec2, DVec3};

/// One cell corner: `Σ c·p(position)` with `Σ c = 0`, at most four terms, and how far the
/// texture slides over the surface there, in scene units (zero where the points correspond
/// through the texture itself, or where there is no texture).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Corner {
    pub terms: [(u32, f64); 4],
    pub texture: f64,
}

/// Everything a candidate evaluation reads.
pub struct Context<'a> {
    /// Changes whenever the mesh or a position does: what the scratch space may cache v1's
    /// neighbours and flattenings under.
    pub stamp: u64,
    pub mesh: &'a Mesh,
    pub uv: &'a [DVec2],
    /// Triangles whose texture coordinates span area (per triangle of `mesh`).
    pub uv_valid: &'a [bool],
    /// A border or seam vertex keeps its chart's area only if it lies within this distance (in
    /// texture units) of the line through its two outline neighbours.
    pub uv_tolerance: f64,
    /// Metres of surface per texture unit where a texture can slide; 0 for none.
    pub slide_scale: f64,
    /// Per render vertex, its material; per material, whether it has a texture.
    pub materials: &'a [u16],
    pub textured: &'a [bool],
    /// Rest-pose positions, by position.
    pub rest: &'a [DVec3],
    /// Rest-pose normals, by render vertex.
    pub normals: &'a [DVec3],
    /// Posed positions, by position and sampled pose (see [`Posed`]).
    pub posed: &'a Posed,
}

/// A triangle of v1's fan before or after the collapse, rotated so that v1 (or v2) comes
/// first, with its vertices' points in the chart's parameter space.
#[derive(Clone, Copy)]
struct FanTriangle {
    r: [u32; 3],
    p: [DVec2; 3],
}

/// The cache key of the whole fan's flattening among the wedges' ones.
const WHOLE_FAN: u32 = u32::MAX;

/// Scratch space reused between evaluations, and what the evaluations of one v1's candidates
/// share: its neighbours, its wedges' flattenings and each chart's old fan.
#[derive(Default)]
pub struct Scratch {
    pub corners: Vec<Corner>,
    /// v1 and the stamp the cached fan data below belong to.
    fan_of: Option<(u32, u64)>,
    flats: Vec<(u32, Option<Flattening>)>,
    /// v1's side of each chart evaluated so far (the first `old_len`; the rest are spare
    /// space for the next v1).
    old_fans: Vec<OldFan>,
    old_len: usize,
    new: Vec<FanTriangle>,
    /// Ends of the new edges from v2: render vertex and its parameter point relative to v2's.
    ends_new: Vec<(u32, DVec2)>,
}

/// v1's fan in one chart before the collapse, the same for every candidate v2: each of the
/// candidates (about six a vertex, a vertex priced again whenever its fan changes) looked its
/// points up and walked its outline again before.
struct OldFan {
    /// The wedge (or [`WHOLE_FAN`]) and the kind of chart ([`Chart::kind`]).
    key: (u32, u8),
    tris: Vec<FanTriangle>,
    /// [`fan_orientation`] of `tris`.
    orientation: Result<(f64, f64), Rejection>,
    /// Outline candidates: render vertices that one fan triangle alone reaches by an edge
    /// from v1, with that count and their parameter points.
    outline: Vec<(u32, u32, DVec2)>,
    /// Ends of the old edges from v1: render vertex and its parameter point relative to v1's.
    ends: Vec<(u32, DVec2)>,
}

impl Default for OldFan {
    fn default() -> Self {
        OldFan {
            key: (WHOLE_FAN, u8::MAX),
            tris: Vec::new(),
            orientation: Err(Rejection::BadFan),
            outline: Vec::new(),
            ends: Vec::new(),
        }
    }
}

impl Context<'_> {
    /// Checks the half-edge collapse `u1 → u2`, all but [`Self::check_link`] and
    /// [`Self::check_orientation`], and fills `scratch.corners` with its cell corners.
    pub fn corners(&self, u1: u32, u2: u32, scratch: &mut Scratch) -> Result<(), Rejection> {
        let mesh = self.mesh;
        let (k1, k2) = (mesh.kind[u1 as usize], mesh.kind[u2 as usize]);
        if !can_collapse(k1, k2) {
            return Err(Rejection::Kind);
        }
        if mesh.incident[u1 as usize].len() > MAX_FAN {
            return Err(Rejection::Crowded);
        }
        let edge = mesh.edge_kind(u1, u2);
        match k1 {
            Kind::Border if edge != EdgeKind::Border => return Err(Rejection::NotAlongOutline),
            Kind::Seam if edge != EdgeKind::Seam => return Err(Rejection::NotAlongOutline),
            Kind::Corner if edge == EdgeKind::Border => return Err(Rejection::NotAlongOutline),
            _ => {}
        }
        if edge == EdgeKind::NonManifold {
            return Err(Rejection::Link);
        }
        let map = self.wedge_map(u1, u2).ok_or(Rejection::Wedges)?;
        if scratch.fan_of != Some((u1, self.stamp)) {
            scratch.flats.clear();
            scratch.old_len = 0;
            scratch.fan_of = Some((u1, self.stamp));
        }
        scratch.corners.clear();
        // A chart that dies whole: every triangle of its sector is on the collapsed edge.
        let vanishes = |r1: u32| {
            mesh.incident[u1 as usize]
                .iter()
                .filter(|&&t| mesh.tris[t as usize].contains(&r1))
                .all(|&t| mesh.contains_position(t, u2))
        };
        let whole = k1 == Kind::Corner || map.iter().any(|&([r1, _], _)| vanishes(r1));
        if whole {
            self.with_flattening(u1, None, scratch, |ctx, flat, s| {
                ctx.wedge_corners(u1, u2, None, u2, Chart::Whole(flat), s)
            })?;
        }
        for &([r1, r2], torn) in &map {
            if torn || vanishes(r1) {
                let others: Vec<u32> = if torn {
                    vec![r2]
                } else {
                    map.iter()
                        .map(|&([r, _], _)| r)
                        .filter(|&r| r != r1)
                        .collect()
                };
                let corner = self.tear(u1, u2, r1, &others, torn);
                scratch.corners.push(corner);
                continue;
            }
            let uses_texture = mesh.incident[u1 as usize]
                .iter()
                .filter(|&&t| mesh.tris[t as usize].contains(&r1))
                .all(|&t| self.uv_valid[t as usize]);
            let mark = scratch.corners.len();
            if uses_texture {
                match self.wedge_corners(u1, u2, Some(r1), r2, Chart::Texture, scratch) {
                    Ok(()) => continue,
                    Err(e) if e.texture_only() => scratch.corners.truncate(mark),
                    Err(e) => return Err(e),
                }
            }
            self.with_flattening(u1, Some(r1), scratch, |ctx, flat, s| {
                ctx.wedge_corners(u1, u2, Some(r1), r2, Chart::Polar(flat), s)
            })?;
        }
        Ok(())
    }

    /// Runs `f` with the flattening of `u1`'s sector of wedge `r1` (the whole fan for `None`),
    /// cached in `scratch` for the other candidates of the same `u1`.
    fn with_flattening(
        &self,
        u1: u32,
        r1: Option<u32>,
        scratch: &mut Scratch,
        f: impl FnOnce(&Self, &Flattening, &mut Scratch) -> Result<(), Rejection>,
    ) -> Result<(), Rejection> {
        let key = r1.unwrap_or(WHOLE_FAN);
        let i = match scratch.flats.iter().position(|(r, _)| *r == key) {
            Some(i) => i,
            None => {
                let flat = Flattening::new(self.mesh, self.rest, u1, r1);
                scratch.flats.push((key, flat));
                scratch.flats.len() - 1
            }
        };
        // Taken out while the corners are written into the same scratch space.
        let flat = scratch.flats[i].1.take().ok_or(Rejection::BadFan)?;
        let result = f(self, &flat, scratch);
        scratch.flats[i].1 = Some(flat);
        result
    }

    /// What a chart costs that the collapse tears (`torn`: its triangles get `others[0]`, a
    /// wedge of another chart) or loses (its sector dies and the charts of `others` cover the
    /// place): the size of the triangles concerned, weighted by how much the attributes differ
    /// (see the module comment). The geometry is measured over the whole fan elsewhere.
    fn tear(&self, u1: u32, u2: u32, r1: u32, others: &[u32], torn: bool) -> Corner {
        let mesh = self.mesh;
        let mut size: f64 = 0.0;
        for &t in &mesh.incident[u1 as usize] {
            let tri = mesh.tris[t as usize];
            if !tri.contains(&r1) || mesh.contains_position(t, u2) == torn {
                continue;
            }
            let [a, b, c] = tri.map(|r| {
                let p = mesh.pos(r);
                self.rest[if p == u1 && torn { u2 } else { p } as usize]
            });
            size = size
                .max(a.distance(b))
                .max(b.distance(c))
                .max(c.distance(a));
        }
        let weight = if self.slide_scale > 0.0 || others.iter().any(|&r| !self.same_colour(r1, r)) {
            1.0
        } else {
            let n = self.normals[r1 as usize];
            let closest = others
                .iter()
                .map(|&r| self.normals[r as usize].dot(n))
                .fold(f64::INFINITY, f64::min);
            (1.0 - closest).clamp(0.0, 1.0)
        };
        Corner {
            terms: [(u1, 0.0); 4],
            texture: size * weight,
        }
    }

    /// Which wedge of `u2` each wedge of `u1` becomes, and whether that tears its chart. Only
    /// a corner tears: a chart of its that does not reach `u2` takes a wedge of `u2` of its own
    /// colour where there is one (its material, and its texture coordinate on a textured one),
    /// and among those the one whose normal is closest to its own (the same side of a hard
    /// edge, where one is), then the nearest in texture space (the least torn), then by texture
    /// coordinate and normal: never by index, so that the choice does not depend on the file's vertex
    /// order. A material border is a seam like any other: a chart that must take another colour
    /// pays for it in [`Self::tear`].
    pub fn wedge_map(&self, u1: u32, u2: u32) -> Option<WedgeMap> {
        if self.mesh.kind[u1 as usize] != Kind::Corner {
            return self.mesh.torn_wedge_map(u1, u2, |_, _| None);
        }
        self.mesh.torn_wedge_map(u1, u2, |r1, candidates| {
            let n = self.normals[r1 as usize];
            let t = self.uv[r1 as usize];
            candidates.iter().copied().max_by(|&a, &b| {
                let (ca, cb) = (self.same_colour(r1, a), self.same_colour(r1, b));
                let (da, db) = (
                    self.normals[a as usize].dot(n),
                    self.normals[b as usize].dot(n),
                );
                let (ua, ub) = (self.uv[a as usize], self.uv[b as usize]);
                ca.cmp(&cb)
                    .then(da.total_cmp(&db))
                    .then(ub.distance_squared(t).total_cmp(&ua.distance_squared(t)))
                    .then(ub.x.total_cmp(&ua.x))
                    .then(ub.y.total_cmp(&ua.y))
                    .then_with(|| {
                        super::mesh::point_order(self.normals[b as usize], self.normals[a as usize])
                    })
            })
        })
    }

    /// Whether render vertices `a` and `b` show the same colour: the same material, and on a
    /// textured one the same texture coordinate (a palette of plain colours in one texture
    /// tells its colours apart by coordinate alone).
    fn same_colour(&self, a: u32, b: u32) -> bool {
        let material = |r: u32| self.materials.get(r as usize).copied().unwrap_or(0);
        let (ma, mb) = (material(a), material(b));
        ma == mb
            && !(self.textured.get(ma as usize).copied().unwrap_or(false)
                && self.uv[a as usize] != self.uv[b as usize])
    }

    /// Hoppe's link condition ([`Mesh::link_condition`]): the collapse must not glue two
    /// sheets together. It reads the fans of all of v1's neighbours, so, like
    /// [`Self::check_orientation`], the simplifier runs it on the cheapest candidates only,
    /// until one passes (most do): pricing every candidate first and checking after finds the
    /// same collapse, and the link condition was 6% of a bake when every candidate paid it.
    /// `n1` holds the neighbours of `u1` ([`Mesh::neighbours`]).
    pub fn check_link(&self, u1: u32, u2: u32, n1: &[u32]) -> Result<(), Rejection> {
        if self.mesh.link_condition(u1, u2, n1) {
            Ok(())
        } else {
            Err(Rejection::Link)
        }
    }

    /// No triangle of v1's fan may turn over, nor become a sliver (thinner than
    /// [`SLIVER`](super::posed::SLIVER) and less than half as round as it was), in the rest pose or in any sampled
    /// pose: either shows as a spike of light or a crack where the metric, an average over
    /// poses, could overlook it. Kept apart from [`Self::corners`] because it is the dearest
    /// check: the simplifier runs it on the cheapest candidates only, until one passes.
    pub fn check_orientation(&self, u1: u32, u2: u32) -> Result<(), Rejection> {
        let mesh = self.mesh;
        for &t in &mesh.incident[u1 as usize] {
            let [_, a, b] = mesh.corners_from(t, u1);
            let (a, b) = (mesh.pos(a), mesh.pos(b));
            if a == u2 || b == u2 {
                continue;
            }
            check_triangle(
                self.rest[u1 as usize],
                self.rest[u2 as usize],
                self.rest[a as usize],
                self.rest[b as usize],
            )?;
            self.posed.check_triangle(u1, u2, a, b)?;
        }
        Ok(())
    }

    /// The part of the evaluation in one wedge's chart (`r1`), or over the whole fan for the
    /// geometry alone (`None`, with `r2` any render vertex of `u2`): the checks that the
    /// collapse keeps the chart a valid parameterisation, then the cell corners of the
    /// deviation (Sander et al.'s memoryless APS, as Merry et al. §4 use it): v1's point and
    /// every crossing of an old edge with a new one.
    fn wedge_corners(
        &self,
        u1: u32,
        u2: u32,
        r1: Option<u32>,
        r2: u32,
        chart: Chart,
        s: &mut Scratch,
    ) -> Result<(), Rejection> {
        let key = (r1.unwrap_or(WHOLE_FAN), chart.kind());
        let i = match s.old_fans[..s.old_len].iter().position(|o| o.key == key) {
            Some(i) => i,
            None => {
                if s.old_len == s.old_fans.len() {
                    s.old_fans.push(OldFan::default());
                }
                let i = s.old_len;
                s.old_len += 1;
                self.old_fan(u1, r1, chart, key, &mut s.old_fans[i]);
                i
            }
        };
        // Taken out while the candidate's own data is written into the same scratch space.
        let old = std::mem::take(&mut s.old_fans[i]);
        let result = self.wedge_corners_from(&old, u1, u2, r2, chart, s);
        s.old_fans[i] = old;
        result
    }

    /// v1's side of one chart's evaluation, which every candidate of v1 shares: the fan
    /// before the collapse with its parameter points, its orientation and extent, its outline
    /// and the ends of its edges from v1.
    fn old_fan(&self, u1: u32, r1: Option<u32>, chart: Chart, key: (u32, u8), out: &mut OldFan) {
        let mesh = self.mesh;
        out.key = key;
        out.tris.clear();
        out.outline.clear();
        out.ends.clear();
        out.orientation = Err(Rejection::BadFan);
        for &t in &mesh.incident[u1 as usize] {
            let tri = mesh.tris[t as usize];
            if r1.is_some_and(|r1| !tri.contains(&r1)) {
                continue;
            }
            // Rotate so v1 comes first; winding kept.
            let k = tri.iter().position(|&r| mesh.pos(r) == u1).unwrap_or(0);
            let r = [tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]];
            let (Ok(a), Ok(b), Ok(c)) = (
                self.point(chart, r[0]),
                self.point(chart, r[1]),
                self.point(chart, r[2]),
            ) else {
                out.tris.clear();
                return;
            };
            out.tris.push(FanTriangle { r, p: [a, b, c] });
        }
        let Some(first) = out.tris.first() else {
            return;
        };
        let p1 = first.p[0];
        out.orientation = fan_orientation(&out.tris, p1);
        // Outline candidates: render vertices reached from v1 by one fan triangle's edge only.
        for tri in &out.tris {
            for j in 1..3 {
                let a = tri.r[j];
                match out.outline.iter().position(|o| o.0 == a) {
                    Some(i) => out.outline[i].1 = 2,
                    None => out.outline.push((a, 1, tri.p[j])),
                }
            }
        }
        out.outline.retain(|o| o.1 < 2);
        for tri in &out.tris {
            for j in 1..3 {
                let a = tri.r[j];
                if !out.ends.iter().any(|e| e.0 == a) {
                    out.ends.push((a, tri.p[j] - p1));
                }
            }
        }
    }

    /// [`Self::wedge_corners`] from v1's side of the chart, `old`.
    fn wedge_corners_from(
        &self,
        old: &OldFan,
        u1: u32,
        u2: u32,
        r2: u32,
        chart: Chart,
        s: &mut Scratch,
    ) -> Result<(), Rejection> {
        let p2 = self.new_fan(old, u2, r2, chart, s)?;
        let p1 = old.tris[0].p[0];
        let (sign, extent2) = old.orientation?;
        let min_area = 1e-10 * extent2;
        // No fold-over in parameter space.
        for tri in &s.new {
            let [_, a, b] = tri.p;
            if (a - p2).perp_dot(b - p2) * sign <= min_area {
                return Err(Rejection::ParameterFold);
            }
        }
        if !matches!(chart, Chart::Whole(_)) {
            self.check_outline(old, u2, p1, p2, chart, extent2)?;
        }
        self.corner_of_v1(old, u1, p1, chart, s)?;
        self.edge_crossings(old, u1, u2, r2, p1, p2, chart, s);
        Ok(())
    }

    /// A render vertex's point in the chart's parameter space.
    fn point(&self, chart: Chart, r: u32) -> Result<DVec2, Rejection> {
        match chart {
            Chart::Texture => Ok(self.uv[r as usize]),
            Chart::Polar(f) | Chart::Whole(f) => f.get(self.mesh.pos(r)).ok_or(Rejection::BadFan),
        }
    }

    /// The texture coordinate a corner's texture deviation is measured in: under the
    /// texture's own correspondence texture coordinates never slide, and the whole fan's map
    /// measures geometry alone. Nor do they on an untextured model (no slide to price), which
    /// then reads no texture coordinates: a load for every term of every corner, mostly
    /// missing the cache on a large model.
    fn slide_uv(&self, chart: Chart, r: u32) -> DVec2 {
        match chart {
            Chart::Polar(_) if self.slide_scale > 0.0 => self.uv[r as usize],
            Chart::Polar(_) | Chart::Texture | Chart::Whole(_) => DVec2::ZERO,
        }
    }

    /// The fan of `u1` after the collapse into `s.new`: the old fan's triangles that do not
    /// reach `u2`, with v2 (render vertex `r2`) in place of v1. Returns v2's point.
    fn new_fan(
        &self,
        old: &OldFan,
        u2: u32,
        r2: u32,
        chart: Chart,
        s: &mut Scratch,
    ) -> Result<DVec2, Rejection> {
        let mesh = self.mesh;
        s.new.clear();
        let p2 = self.point(chart, r2)?;
        if old.tris.is_empty() {
            return Err(Rejection::BadFan);
        }
        for tri in &old.tris {
            let r = tri.r;
            if mesh.pos(r[1]) != u2 && mesh.pos(r[2]) != u2 {
                s.new.push(FanTriangle {
                    r: [r2, r[1], r[2]],
                    p: [p2, tri.p[1], tri.p[2]],
                });
            }
        }
        if s.new.is_empty() {
            return Err(Rejection::BadFan);
        }
        Ok(p2)
    }

    /// The chart outline through v1 (edges used by one fan triangle only): a border or seam
    /// vertex keeps the chart's area only if it lies on the straight line from its other
    /// outline neighbour to v2. (The whole fan of a corner is closed, and a dying chart's
    /// outline goes with it.)
    fn check_outline(
        &self,
        old: &OldFan,
        u2: u32,
        p1: DVec2,
        p2: DVec2,
        chart: Chart,
        extent2: f64,
    ) -> Result<(), Rejection> {
        let mesh = self.mesh;
        let outline = &old.outline;
        match outline.len() {
            0 => Ok(()),
            2 => {
                let (Some(&(_, _, q)), true) = (
                    outline.iter().find(|o| mesh.pos(o.0) != u2),
                    outline.iter().any(|o| mesh.pos(o.0) == u2),
                ) else {
                    return Err(Rejection::NotAlongOutline);
                };
                let tolerance = match chart {
                    Chart::Texture => self.uv_tolerance,
                    Chart::Polar(_) | Chart::Whole(_) => 1e-9 * extent2.sqrt(),
                };
                let line = p2 - q;
                let len = line.length();
                let off = (p1 - q).perp_dot(line).abs() / len.max(1e-300);
                let along = (p1 - q).dot(line) / (len * len).max(1e-300);
                if off > tolerance || !(along > 0.0 && along < 1.0) {
                    return Err(Rejection::ChangesParameterArea);
                }
                Ok(())
            }
            _ => Err(Rejection::NotAlongOutline),
        }
    }

    /// Corner 1: v1's parameter point, inside (or on the edge of) one new triangle.
    fn corner_of_v1(
        &self,
        old: &OldFan,
        u1: u32,
        p1: DVec2,
        chart: Chart,
        s: &mut Scratch,
    ) -> Result<(), Rejection> {
        let mesh = self.mesh;
        let mut best: Option<([u32; 3], [f64; 3])> = None;
        for tri in &s.new {
            let bary = barycentric(p1, tri.p[0], tri.p[1], tri.p[2]);
            let worst = bary[0].min(bary[1]).min(bary[2]);
            if best.is_none_or(|(_, b)| worst > b[0].min(b[1]).min(b[2])) {
                best = Some((tri.r, bary));
            }
        }
        let (tri, bary) = best.ok_or(Rejection::BadFan)?;
        let uv = |r: u32| self.slide_uv(chart, r);
        let r1 = old.tris[0].r[0];
        s.corners.push(Corner {
            terms: [
                (u1, 1.0),
                (mesh.pos(tri[0]), -bary[0]),
                (mesh.pos(tri[1]), -bary[1]),
                (mesh.pos(tri[2]), -bary[2]),
            ],
            texture: self.slide_scale
                * (uv(r1) - (uv(tri[0]) * bary[0] + uv(tri[1]) * bary[1] + uv(tri[2]) * bary[2]))
                    .length(),
        });
        Ok(())
    }

    /// The other corners: crossings of old edges (v1, a) with new edges (v2, b).
    #[allow(clippy::too_many_arguments)]
    fn edge_crossings(
        &self,
        old: &OldFan,
        u1: u32,
        u2: u32,
        r2: u32,
        p1: DVec2,
        p2: DVec2,
        chart: Chart,
        s: &mut Scratch,
    ) {
        let mesh = self.mesh;
        s.ends_new.clear();
        for tri in &s.new {
            for j in 1..3 {
                let b = tri.r[j];
                if !s.ends_new.iter().any(|e| e.0 == b) {
                    s.ends_new.push((b, tri.p[j] - p2));
                }
            }
        }
        let uv = |r: u32| self.slide_uv(chart, r);
        let r1 = old.tris[0].r[0];
        let w = p2 - p1;
        for &(a, da) in old.ends.iter().filter(|e| mesh.pos(e.0) != u2) {
            let la = da.length_squared();
            for &(b, db) in &s.ends_new {
                if a == b {
                    continue;
                }
                let denom = da.perp_dot(db);
                // Parallel (within rounding): no crossing.
                if denom * denom <= 1e-28 * la * db.length_squared() {
                    continue;
                }
                // Both crossing parameters strictly inside (0, 1), tested before dividing:
                // most pairs do not cross.
                const EDGE: f64 = 1e-9;
                let (na, nb) = (w.perp_dot(db), w.perp_dot(da));
                let inside = |n: f64| {
                    let (n, d) = if denom > 0.0 {
                        (n, denom)
                    } else {
                        (-n, -denom)
                    };
                    n > EDGE * d && n < (1.0 - EDGE) * d
                };
                if inside(na) && inside(nb) {
                    let (alpha, beta) = (na / denom, nb / denom);
                    s.corners.push(Corner {
                        terms: [
                            (u1, 1.0 - alpha),
                            (mesh.pos(a), alpha),
                            (u2, -(1.0 - beta)),
                            (mesh.pos(b), -beta),
                        ],
                        texture: self.slide_scale
                            * (uv(r1) * (1.0 - alpha) + uv(a) * alpha
                                - uv(r2) * (1.0 - beta)
                                - uv(b) * beta)
                                .length(),
                    });
                }
            }
        }
    }
}

/// The orientation (sign of area) of v1's fan in parameter space, and its extent squared (a
/// scale for tolerances). A fan that is not consistently oriented, or has a triangle of no
/// area, is no chart to measure in.
fn fan_orientation(old: &[FanTriangle], p1: DVec2) -> Result<(f64, f64), Rejection> {
    let mut extent2: f64 = 0.0;
    let mut sign = 0.0;
    for tri in old {
        let [_, a, b] = tri.p;
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
    if old.iter().any(|tri| {
        let [_, a, b] = tri.p;
        ((a - p1).perp_dot(b - p1) * sign) <= min_area
    }) {
        return Err(Rejection::BadFan);
    }
    Ok((sign, extent2))
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// The block test in single precision gives the verdict of [`check_triangle`] in double
    /// precision, pose by pose: on random triangles, on nearly flat ones turning over or not,
    /// on slivers at the bound, and with corners far from the origin.
    #[test]
    fn posed_checks_agree_with_double_precision() {
        let mut rng = fastrand::Rng::with_seed(11);
        let mut f = |scale: f32| (rng.f32() - 0.5) * scale;
        for case in 0..4000 {
            let poses = 1 + case % 19;
            let offset = if case % 3 == 0 { 1000.0 } else { 0.0 };
            // Positions 0..4: x1, x2, a, b; some cases nearly degenerate.
            let flat = case % 4 == 1;
            let thin = case % 4 == 2;
            let points: Vec<Vec<Vec3>> = (0..4)
                .map(|corner| {
                    (0..poses)
                        .map(|_| {
                            let mut p = Vec3::new(f(2.0), f(2.0), f(2.0));
                            if flat {
                                p.z = f(1e-4);
                            }
                            if thin && corner == 3 {
                                p = Vec3::new(1.0 + f(0.04), f(0.04), 0.0);
                            }
                            p + Vec3::splat(offset)
                        })
                        .collect()
                })
                .collect();
            let posed = Posed::new(4, poses, |u, s| points[u][s]);
            let double = (0..poses).try_for_each(|s| {
                let at = |u: usize| points[u][s].as_dvec3();
                check_triangle(at(0), at(1), at(2), at(3))
            });
            assert_eq!(posed.check_triangle(0, 1, 2, 3), double, "case {case}");
        }
    }
}

//! A quad control cage for box-modelled creatures, smoothed by Catmull–Clark subdivision.
//!
//! Creatures are built the way a modeller builds them by hand: a body tube, limbs *extruded*
//! from its faces, then subdivision. Extrusion keeps the cage closed and manifold by
//! construction, so the final mesh has no holes and no cracks.
//!
//! Three things ride along with the positions:
//! - **skin weights** per cage vertex, subdivided with the same stencils as the positions. A ring
//!   at a joint weighted half and half between the two bones becomes, after two levels, a smooth
//!   blend of two to four bones across the joint: automatic weights with no painting;
//! - **UV charts**, face-varying: every face stores the UVs of its four corners in its chart's
//!   own coordinates (metres along the surface). They are subdivided bilinearly, so every cage
//!   face maps to a regular grid of its UV quad and the layout stays free of fold-overs;
//! - a **part** per chart, which the texture painter uses to tell a hoof from a flank.

use glam::{Quat, Vec2, Vec3};
use std::collections::HashMap;

/// Sparse skin weights: `(bone, weight)` pairs sorted by bone.
pub type Weights = Vec<(u32, f32)>;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FaceId(pub usize);

#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// Corners counter-clockwise seen from outside.
    pub v: [u32; 4],
    /// Chart coordinates of the corners.
    pub uv: [Vec2; 4],
    pub chart: u32,
    pub alive: bool,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Cage {
    pub positions: Vec<Vec3>,
    pub weights: Vec<Weights>,
    pub faces: Vec<Face>,
    /// Part of each chart.
    pub chart_parts: Vec<u32>,
}

/// One cross-section of a tube: its centre, its points in order round it, and the skin weights
/// of all of them.
#[derive(Clone, Debug)]
pub struct Ring {
    pub center: Vec3,
    pub points: Vec<Vec3>,
    pub weights: Weights,
}

/// How a tube is capped at one end.
#[derive(Clone, Copy, Debug)]
pub struct Cap {
    /// Which ring point starts the ladder of quads (see [`Cage::tube`]).
    pub offset: usize,
    pub part: u32,
}

/// The faces of a tube, for later extrusions.
#[derive(Clone, Debug, Default)]
pub struct Tube {
    pub rings: Vec<Vec<u32>>,
    /// `sides[j]`: the faces between ring `j` and ring `j + 1`.
    pub sides: Vec<Vec<FaceId>>,
    pub start_cap: Vec<FaceId>,
    pub end_cap: Vec<FaceId>,
}

/// One ring of an extrusion: centre, half extents across the two face axes, weights.
#[derive(Clone, Debug)]
pub struct ExtrudeRing {
    pub center: Vec3,
    pub half: Vec2,
    pub weights: Weights,
}

#[derive(Clone, Debug)]
pub struct Extrusion {
    /// `sides[j]`: the four faces ending at ring `j`.
    pub sides: Vec<[FaceId; 4]>,
    pub cap: FaceId,
}

/// A linear combination of sparse weight vectors.
fn mix_weights(terms: &[(&Weights, f32)]) -> Weights {
    let mut out: Weights = Vec::new();
    for (w, k) in terms {
        for &(bone, value) in w.iter() {
            match out.iter_mut().find(|e| e.0 == bone) {
                Some(e) => e.1 += value * k,
                None => out.push((bone, value * k)),
            }
        }
    }
    out.retain(|e| e.1 > 1e-7);
    out.sort_by_key(|e| e.0);
    out
}

impl Cage {
    pub fn new_chart(&mut self, part: u32) -> u32 {
        self.chart_parts.push(part);
        (self.chart_parts.len() - 1) as u32
    }

    fn add_vertex(&mut self, p: Vec3, w: Weights) -> u32 {
        self.positions.push(p);
        self.weights.push(w);
        (self.positions.len() - 1) as u32
    }

    fn add_face(&mut self, v: [u32; 4], uv: [Vec2; 4], chart: u32) -> FaceId {
        self.faces.push(Face {
            v,
            uv,
            chart,
            alive: true,
        });
        FaceId(self.faces.len() - 1)
    }

    /// Cuts every chart into square patches of `size(part)` metres of chart space, each a
    /// chart of its own, as automatic unwrappers (lightmap packers, game exporters) leave them:
    /// many small charts, with corners where three or four of them meet.
    pub fn split_charts(&mut self, size: impl Fn(u32) -> f32) {
        let mut patches: HashMap<(u32, i32, i32), u32> = HashMap::new();
        let mut parts = Vec::new();
        for f in self.faces.iter_mut().filter(|f| f.alive) {
            let part = self.chart_parts[f.chart as usize];
            let centre = f.uv.iter().sum::<Vec2>() / 4.0;
            let cell = (centre / size(part)).floor();
            let key = (f.chart, cell.x as i32, cell.y as i32);
            f.chart = *patches.entry(key).or_insert_with(|| {
                parts.push(part);
                (parts.len() - 1) as u32
            });
        }
        self.chart_parts = parts;
    }

    pub fn face_center(&self, f: FaceId) -> Vec3 {
        self.faces[f.0]
            .v
            .iter()
            .map(|&i| self.positions[i as usize])
            .sum::<Vec3>()
            / 4.0
    }

    /// Unit normal of a (possibly non-planar) quad: the cross product of its diagonals.
    pub fn face_normal(&self, f: FaceId) -> Vec3 {
        let p = self.faces[f.0].v.map(|i| self.positions[i as usize]);
        (p[2] - p[0]).cross(p[3] - p[1]).normalize_or_zero()
    }

    /// The face among `candidates` whose normal points most nearly along `direction`.
    pub fn face_towards(&self, candidates: &[FaceId], direction: Vec3) -> FaceId {
        let d = direction.normalize_or_zero();
        *candidates
            .iter()
            .max_by(|a, b| {
                self.face_normal(**a)
                    .dot(d)
                    .total_cmp(&self.face_normal(**b).dot(d))
            })
            .expect("at least one candidate")
    }

    /// Builds a closed tube through `rings` (all with the same number of points, an even
    /// number). `sections` split its length into charts: `(first ring, part)`, the first at
    /// ring 0. Each end is closed with a ladder of quads: with the ring points `q_i` counted from
    /// `offset`, the quads `(q_i, q_{i+1}, q_{n-2-i}, q_{n-1-i})`.
    pub fn tube(
        &mut self,
        rings: &[Ring],
        sections: &[(usize, u32)],
        start: Cap,
        end: Cap,
    ) -> Tube {
        let n = rings[0].points.len();
        assert!(n >= 4 && n.is_multiple_of(2) && rings.iter().all(|r| r.points.len() == n));
        assert!(rings.len() >= 2 && sections.first().map(|s| s.0) == Some(0));
        let ids: Vec<Vec<u32>> = rings
            .iter()
            .map(|r| {
                r.points
                    .iter()
                    .map(|&p| self.add_vertex(p, r.weights.clone()))
                    .collect()
            })
            .collect();
        // Ring order round the tube decides which way the faces point: measure it once.
        let axis = (rings[1].center - rings[0].center).normalize_or(Vec3::Y);
        // Points running counter-clockwise about the axis give outward quads as they are.
        let around = (rings[0].points[0] - rings[0].center)
            .cross(rings[0].points[1] - rings[0].center)
            .dot(axis);
        let flip = around < 0.0;

        let mut tube = Tube {
            rings: ids.clone(),
            ..Default::default()
        };
        for (s, &(first, part)) in sections.iter().enumerate() {
            let last = sections.get(s + 1).map_or(rings.len() - 1, |n| n.0);
            let chart = self.new_chart(part);
            // u: arc length round the section's average ring; v: distance along the centres.
            let mut u = vec![0.0f32; n + 1];
            for k in 0..n {
                let mut len = 0.0;
                for r in &rings[first..=last] {
                    len += r.points[k].distance(r.points[(k + 1) % n]);
                }
                u[k + 1] = u[k] + len / (last - first + 1) as f32;
            }
            let mut v = vec![0.0f32; last - first + 1];
            for j in first + 1..=last {
                v[j - first] = v[j - 1 - first] + rings[j].center.distance(rings[j - 1].center);
            }
            for j in first..last {
                let mut faces = Vec::with_capacity(n);
                for k in 0..n {
                    let k1 = (k + 1) % n;
                    let (v0, v1) = (v[j - first], v[j + 1 - first]);
                    let quad = [ids[j][k], ids[j][k1], ids[j + 1][k1], ids[j + 1][k]];
                    let uv = [
                        Vec2::new(u[k], v0),
                        Vec2::new(u[k + 1], v0),
                        Vec2::new(u[k + 1], v1),
                        Vec2::new(u[k], v1),
                    ];
                    faces.push(if flip {
                        self.add_face(
                            [quad[0], quad[3], quad[2], quad[1]],
                            [uv[0], uv[3], uv[2], uv[1]],
                            chart,
                        )
                    } else {
                        self.add_face(quad, uv, chart)
                    });
                }
                tube.sides.push(faces);
            }
        }
        let first_ring = &ids[0];
        let last_ring = &ids[rings.len() - 1];
        tube.start_cap = self.cap(first_ring, rings[0].center, -axis, start);
        let end_axis =
            (rings[rings.len() - 1].center - rings[rings.len() - 2].center).normalize_or(axis);
        tube.end_cap = self.cap(last_ring, rings[rings.len() - 1].center, end_axis, end);
        tube
    }

    /// Closes a ring with a ladder of quads facing `outward`, in a chart of its own.
    fn cap(&mut self, ring: &[u32], center: Vec3, outward: Vec3, cap: Cap) -> Vec<FaceId> {
        let n = ring.len();
        let q = |i: usize| ring[(i + cap.offset) % n];
        let chart = self.new_chart(cap.part);
        let e1 = {
            let d = self.positions[q(0) as usize] - center;
            (d - outward * d.dot(outward)).normalize_or(outward.any_orthonormal_vector())
        };
        let e2 = outward.cross(e1);
        let uv_of = |cage: &Cage, i: u32| {
            let d = cage.positions[i as usize] - center;
            Vec2::new(d.dot(e1), d.dot(e2))
        };
        let mut faces = Vec::new();
        for i in 0..n / 2 - 1 {
            let mut quad = [q(i), q(i + 1), q(n - 2 - i), q(n - 1 - i)];
            let p = quad.map(|v| self.positions[v as usize]);
            if (p[2] - p[0]).cross(p[3] - p[1]).dot(outward) < 0.0 {
                quad = [quad[0], quad[3], quad[2], quad[1]];
            }
            let uv = quad.map(|v| uv_of(self, v));
            faces.push(self.add_face(quad, uv, chart));
        }
        faces
    }

    /// Extrudes `face` through `rings`, replacing it with a four-sided tube whose end is capped by
    /// a copy of the face. The cross-sections keep the face's shape, scaled to each ring's half
    /// extents (`half.x` along the face axis nearer `lateral`, `half.y` along the other), and
    /// turn with the path (a rotation-minimising frame).
    pub fn extrude_along(
        &mut self,
        face: FaceId,
        rings: &[ExtrudeRing],
        lateral: Vec3,
        part: u32,
        cap_part: u32,
    ) -> Extrusion {
        let base = self.faces[face.0].v;
        self.faces[face.0].alive = false;
        let p = base.map(|i| self.positions[i as usize]);
        let c = p.iter().sum::<Vec3>() / 4.0;
        let n = self.face_normal(face);
        let in_plane = |d: Vec3| (d - n * d.dot(n)).normalize_or(n.any_orthonormal_vector());
        let axes = [
            in_plane((p[1] - p[0]) + (p[2] - p[3])),
            in_plane((p[3] - p[0]) + (p[2] - p[1])),
        ];
        let pick = if axes[0].dot(lateral).abs() >= axes[1].dot(lateral).abs() {
            0
        } else {
            1
        };
        let u0 = if axes[pick].dot(lateral) < 0.0 {
            -axes[pick]
        } else {
            axes[pick]
        };
        let v0 = n.cross(u0);
        let mut ab = p.map(|q| Vec2::new((q - c).dot(u0), (q - c).dot(v0)));
        let ext = ab
            .iter()
            .fold(Vec2::ZERO, |m, q| m.max(q.abs()))
            .max(Vec2::splat(1e-6));
        for q in &mut ab {
            *q /= ext;
        }

        let chart = self.new_chart(part);
        let mut prev_ring = base;
        let mut prev_t = n;
        let (mut u, mut v) = (u0, v0);
        let mut centers = vec![c];
        centers.extend(rings.iter().map(|r| r.center));
        // Chart coordinates: arc length round the average ring and along the path.
        let perim: Vec<f32> = {
            let mut acc = vec![0.0f32; 5];
            for k in 0..4 {
                let avg = rings
                    .iter()
                    .map(|r| {
                        let a = ab[k] * r.half;
                        let b = ab[(k + 1) % 4] * r.half;
                        a.distance(b)
                    })
                    .sum::<f32>()
                    / rings.len() as f32;
                acc[k + 1] = acc[k] + avg;
            }
            acc
        };
        let mut along = 0.0f32;
        let mut sides = Vec::with_capacity(rings.len());
        let mut ring_ids = [0u32; 4];
        for (j, r) in rings.iter().enumerate() {
            let next = centers.get(j + 2).copied().unwrap_or(r.center);
            let t = (next - centers[j]).normalize_or(prev_t);
            let turn = Quat::from_rotation_arc(prev_t, t);
            u = (turn * u).normalize();
            v = (turn * v).normalize();
            prev_t = t;
            for k in 0..4 {
                let q = r.center + u * (r.half.x * ab[k].x) + v * (r.half.y * ab[k].y);
                ring_ids[k] = self.add_vertex(q, r.weights.clone());
            }
            let v_prev = along;
            along += r.center.distance(centers[j]);
            let mut ring_faces = [FaceId(0); 4];
            for k in 0..4 {
                let k1 = (k + 1) % 4;
                ring_faces[k] = self.add_face(
                    [prev_ring[k], prev_ring[k1], ring_ids[k1], ring_ids[k]],
                    [
                        Vec2::new(perim[k], v_prev),
                        Vec2::new(perim[k + 1], v_prev),
                        Vec2::new(perim[k + 1], along),
                        Vec2::new(perim[k], along),
                    ],
                    chart,
                );
            }
            sides.push(ring_faces);
            prev_ring = ring_ids;
        }
        let last = rings.last().expect("at least one ring");
        let cap_chart = self.new_chart(cap_part);
        let cap = self.add_face(prev_ring, ab.map(|q| q * last.half), cap_chart);
        Extrusion { sides, cap }
    }

    /// Replaces the weights of every vertex for which `f` returns new ones.
    pub fn reweight(&mut self, vertices: &[u32], f: impl Fn(Vec3, &Weights) -> Option<Weights>) {
        for &v in vertices {
            if let Some(w) = f(self.positions[v as usize], &self.weights[v as usize]) {
                self.weights[v as usize] = w;
            }
        }
    }

    /// Faces still in the cage.
    pub fn live_faces(&self) -> impl Iterator<Item = &Face> {
        self.faces.iter().filter(|f| f.alive)
    }

    /// Every edge of the live faces with the number of faces using it, keyed by sorted vertex
    /// pair. A closed manifold cage has every count equal to two.
    pub fn edge_uses(&self) -> HashMap<(u32, u32), u32> {
        let mut uses = HashMap::new();
        for f in self.live_faces() {
            for k in 0..4 {
                let (a, b) = (f.v[k], f.v[(k + 1) % 4]);
                *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        uses
    }

    /// One level of Catmull–Clark subdivision of positions and weights, and bilinear
    /// subdivision of the face-varying UVs.
    pub fn subdivide(&self) -> Cage {
        let faces: Vec<&Face> = self.live_faces().collect();
        let topology = Topology::of(&faces);
        let (face_points, face_weights) = self.face_points(&faces);

        let mut out = Cage {
            chart_parts: self.chart_parts.clone(),
            ..Default::default()
        };
        // Vertex points.
        self.push_vertex_points(&mut out, &faces, &topology, &face_points, &face_weights);
        // Edge points.
        let edge_base = out.positions.len() as u32;
        self.push_edge_points(&mut out, &topology, &face_points, &face_weights);
        // Face points.
        let face_base = out.positions.len() as u32;
        out.positions.extend_from_slice(&face_points);
        out.weights.extend(face_weights);
        // Four quads per face.
        push_child_faces(&mut out, &faces, &topology.face_edges, edge_base, face_base);
        out
    }

    /// Subdivision's face points: each live face's centroid and the average of its corners'
    /// weights, which the edge and vertex stencils and the child faces' centres all use.
    fn face_points(&self, faces: &[&Face]) -> (Vec<Vec3>, Vec<Weights>) {
        let face_points: Vec<Vec3> = faces
            .iter()
            .map(|f| {
                f.v.iter()
                    .map(|&i| self.positions[i as usize])
                    .sum::<Vec3>()
                    / 4.0
            })
            .collect();
        let face_weights: Vec<Weights> = faces
            .iter()
            .map(|f| {
                let terms: Vec<(&Weights, f32)> =
                    f.v.iter()
                        .map(|&i| (&self.weights[i as usize], 0.25))
                        .collect();
                mix_weights(&terms)
            })
            .collect();
        (face_points, face_weights)
    }

    /// Subdivision's vertex points, one per old vertex in order, pushed onto `out`: each
    /// vertex moved by the Catmull–Clark stencil over the faces and edges round it.
    fn push_vertex_points(
        &self,
        out: &mut Cage,
        faces: &[&Face],
        topology: &Topology,
        face_points: &[Vec3],
        face_weights: &[Weights],
    ) {
        let nv = self.positions.len();
        let mut v_faces: Vec<Vec<usize>> = vec![Vec::new(); nv];
        for (fi, f) in faces.iter().enumerate() {
            for &v in &f.v {
                v_faces[v as usize].push(fi);
            }
        }
        let mut v_edges: Vec<Vec<usize>> = vec![Vec::new(); nv];
        for (e, &(a, b)) in topology.edge_ends.iter().enumerate() {
            v_edges[a as usize].push(e);
            v_edges[b as usize].push(e);
        }
        for v in 0..nv {
            let (p, w) = self.vertex_point(
                v,
                &v_faces[v],
                &v_edges[v],
                topology,
                face_points,
                face_weights,
            );
            out.positions.push(p);
            out.weights.push(w);
        }
    }

    /// Vertex `v`'s new position and weights, given the faces `fs` and edges `es` round it:
    /// unchanged if no face uses it, the B-spline border rule on an open border, else the
    /// Catmull–Clark stencil (the same on positions and on weights).
    fn vertex_point(
        &self,
        v: usize,
        fs: &[usize],
        es: &[usize],
        topology: &Topology,
        face_points: &[Vec3],
        face_weights: &[Weights],
    ) -> (Vec3, Weights) {
        let (edge_faces, edge_ends) = (&topology.edge_faces, &topology.edge_ends);
        let p = self.positions[v];
        let w = &self.weights[v];
        let boundary: Vec<usize> = es
            .iter()
            .copied()
            .filter(|&e| edge_faces[e].len() != 2)
            .collect();
        if fs.is_empty() {
            (p, w.clone())
        } else if !boundary.is_empty() {
            // Open border (never in a closed creature, kept for robustness): cubic B-spline
            // along the border.
            let ends: Vec<u32> = boundary
                .iter()
                .map(|&e| {
                    let (a, b) = edge_ends[e];
                    if a as usize == v { b } else { a }
                })
                .take(2)
                .collect();
            let mut q = p * 0.75;
            let mut terms: Vec<(&Weights, f32)> = vec![(w, 0.75)];
            for &o in &ends {
                q += self.positions[o as usize] * (0.25 / ends.len() as f32);
                terms.push((&self.weights[o as usize], 0.25 / ends.len() as f32));
            }
            (q, mix_weights(&terms))
        } else {
            let n = fs.len() as f32;
            let f_avg = fs.iter().map(|&f| face_points[f]).sum::<Vec3>() / n;
            let r_avg = es
                .iter()
                .map(|&e| {
                    let (a, b) = edge_ends[e];
                    (self.positions[a as usize] + self.positions[b as usize]) * 0.5
                })
                .sum::<Vec3>()
                / es.len() as f32;
            let position = (f_avg + 2.0 * r_avg + (n - 3.0) * p) / n;
            // The same stencil on the weights: faces 1/n², edge ends 2/(n·m) each half,
            // the vertex itself (n − 3)/n.
            let mut terms: Vec<(&Weights, f32)> = Vec::new();
            for &f in fs {
                terms.push((&face_weights[f], 1.0 / (n * n)));
            }
            let m = es.len() as f32;
            for &e in es {
                let (a, b) = edge_ends[e];
                terms.push((&self.weights[a as usize], 1.0 / (n * m)));
                terms.push((&self.weights[b as usize], 1.0 / (n * m)));
            }
            terms.push((w, (n - 3.0) / n));
            (position, mix_weights(&terms))
        }
    }

    /// Subdivision's edge points, one per edge in first-use order, pushed onto `out`: the
    /// average of the ends and the two faces' points, or the midpoint on an open border.
    fn push_edge_points(
        &self,
        out: &mut Cage,
        topology: &Topology,
        face_points: &[Vec3],
        face_weights: &[Weights],
    ) {
        let edge_faces = &topology.edge_faces;
        for (e, &(a, b)) in topology.edge_ends.iter().enumerate() {
            let (pa, pb) = (self.positions[a as usize], self.positions[b as usize]);
            let (wa, wb) = (&self.weights[a as usize], &self.weights[b as usize]);
            if edge_faces[e].len() == 2 {
                let (f0, f1) = (edge_faces[e][0], edge_faces[e][1]);
                out.positions
                    .push((pa + pb + face_points[f0] + face_points[f1]) * 0.25);
                out.weights.push(mix_weights(&[
                    (wa, 0.25),
                    (wb, 0.25),
                    (&face_weights[f0], 0.25),
                    (&face_weights[f1], 0.25),
                ]));
            } else {
                out.positions.push((pa + pb) * 0.5);
                out.weights.push(mix_weights(&[(wa, 0.5), (wb, 0.5)]));
            }
        }
    }
}

/// The edges of a cage's live faces, numbered in the order the faces first use them: what
/// subdivision needs to place edge points and to stitch the child faces to them.
struct Topology {
    /// `edge_faces[e]`: the faces (by place among the live faces) using edge `e`.
    edge_faces: Vec<Vec<usize>>,
    /// `edge_ends[e]`: edge `e`'s vertices, the smaller first.
    edge_ends: Vec<(u32, u32)>,
    /// `face_edges[f][k]`: the edge from corner `k` of face `f` to corner `k + 1`.
    face_edges: Vec<[usize; 4]>,
}

impl Topology {
    /// The edges of `faces`, in the order the faces first use them.
    fn of(faces: &[&Face]) -> Topology {
        // Edges and their adjacent faces.
        let mut edge_index: HashMap<(u32, u32), usize> = HashMap::new();
        let mut edge_faces: Vec<Vec<usize>> = Vec::new();
        let mut edge_ends: Vec<(u32, u32)> = Vec::new();
        let mut face_edges: Vec<[usize; 4]> = Vec::with_capacity(faces.len());
        for (fi, f) in faces.iter().enumerate() {
            let mut fe = [0; 4];
            for (k, slot) in fe.iter_mut().enumerate() {
                let (a, b) = (f.v[k], f.v[(k + 1) % 4]);
                let key = (a.min(b), a.max(b));
                let e = *edge_index.entry(key).or_insert_with(|| {
                    edge_faces.push(Vec::new());
                    edge_ends.push(key);
                    edge_ends.len() - 1
                });
                edge_faces[e].push(fi);
                *slot = e;
            }
            face_edges.push(fe);
        }
        Topology {
            edge_faces,
            edge_ends,
            face_edges,
        }
    }
}

/// Subdivision's child faces: four quads per old face (corner, edge point, face point, edge
/// point), in face order, with UVs split bilinearly so every chart stays a regular grid.
fn push_child_faces(
    out: &mut Cage,
    faces: &[&Face],
    face_edges: &[[usize; 4]],
    edge_base: u32,
    face_base: u32,
) {
    for (fi, f) in faces.iter().enumerate() {
        let center_uv = f.uv.iter().sum::<Vec2>() / 4.0;
        for k in 0..4 {
            let prev = (k + 3) % 4;
            let next = (k + 1) % 4;
            let v = [
                f.v[k],
                edge_base + face_edges[fi][k] as u32,
                face_base + fi as u32,
                edge_base + face_edges[fi][prev] as u32,
            ];
            let uv = [
                f.uv[k],
                (f.uv[k] + f.uv[next]) * 0.5,
                center_uv,
                (f.uv[k] + f.uv[prev]) * 0.5,
            ];
            out.add_face(v, uv, f.chart);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(b: u32) -> Weights {
        vec![(b, 1.0)]
    }

    /// A box-like tube of three rings with one leg extruded from a side face.
    fn sample() -> Cage {
        let mut cage = Cage::default();
        let ring = |z: f32, s: f32, b: u32| Ring {
            center: Vec3::new(0.0, 0.0, z),
            points: (0..8)
                .map(|k| {
                    let a = k as f32 * std::f32::consts::TAU / 8.0;
                    Vec3::new(a.cos() * s, a.sin() * s, z)
                })
                .collect(),
            weights: w(b),
        };
        let tube = cage.tube(
            &[ring(0.0, 1.0, 0), ring(1.0, 1.2, 0), ring(2.0, 1.0, 1)],
            &[(0, 0)],
            Cap { offset: 0, part: 1 },
            Cap { offset: 1, part: 1 },
        );
        let down = cage.face_towards(&tube.sides[0], Vec3::NEG_Y);
        cage.extrude_along(
            down,
            &[
                ExtrudeRing {
                    center: Vec3::new(0.0, -1.6, 0.5),
                    half: Vec2::splat(0.2),
                    weights: w(2),
                },
                ExtrudeRing {
                    center: Vec3::new(0.0, -2.5, 0.5),
                    half: Vec2::splat(0.15),
                    weights: w(2),
                },
            ],
            Vec3::X,
            2,
            3,
        );
        cage
    }

    fn signed_volume(cage: &Cage) -> f32 {
        cage.live_faces()
            .map(|f| {
                let p = f.v.map(|i| cage.positions[i as usize]);
                (p[0].dot(p[1].cross(p[2])) + p[0].dot(p[2].cross(p[3]))) / 6.0
            })
            .sum()
    }

    #[test]
    fn tube_and_extrusion_are_closed_and_outward() {
        let cage = sample();
        assert!(cage.edge_uses().values().all(|&c| c == 2));
        assert!(signed_volume(&cage) > 0.0);
        // Every directed edge once: consistent orientation.
        let mut directed = std::collections::HashSet::new();
        for f in cage.live_faces() {
            for k in 0..4 {
                assert!(directed.insert((f.v[k], f.v[(k + 1) % 4])));
            }
        }
    }

    #[test]
    fn subdivision_stays_closed_and_weights_stay_normalised() {
        let cage = sample().subdivide().subdivide();
        assert!(cage.edge_uses().values().all(|&c| c == 2));
        assert!(signed_volume(&cage) > 0.0);
        for w in &cage.weights {
            let s: f32 = w.iter().map(|e| e.1).sum();
            assert!((s - 1.0).abs() < 1e-4, "{w:?}");
        }
        // Weights now blend across the tube/leg seam.
        assert!(cage.weights.iter().any(|w| w.len() >= 2));
    }

    #[test]
    fn subdivision_converges_towards_a_smooth_shape() {
        // Catmull–Clark shrinks a cube towards its inscribed rounded shape, never outside it.
        let cage = sample();
        let max0 = cage
            .positions
            .iter()
            .map(|p| p.x.abs())
            .fold(0.0f32, f32::max);
        let s = cage.subdivide();
        let max1 = s.positions.iter().map(|p| p.x.abs()).fold(0.0f32, f32::max);
        assert!(max1 <= max0 + 1e-5);
    }
}

//! The wood of a tree at coarser levels: the trunk and branches simplified by the skinned LOD
//! engine (Merry et al., the `as` metric: animation-space L2,2 error), cut where its error
//! bound reaches a level's ε, so wood and foliage of a level have the same error budget.
//!
//! Half-edge collapses keep every surviving vertex as it was, influences included, so each
//! simplified wood is a subset of the original vertices with new triangles, and stays a plain
//! skinned mesh that the tree's model can carry.
//!
//! Each branch is a closed piece of its own, which collapses cannot remove, only flatten: a
//! tube thinner than ε collapses, within the error bound, to a sliver that vanishes edge-on,
//! and the crown it carries floats. So the pieces are taken one by one, thickness `d`:
//!
//! | piece | at ε |
//! |---|---|
//! | `d > ε` | collapsed with the rest (its shape holds within ε) |
//! | a twig (holds no other wood), `d ≤ ε/2` | dropped: narrower than half the screen tolerance where the level comes in, its leaves close to the branch it grew from |
//! | holds other wood, `d ≤ ε/2`, all it holds dropped, and it and all it held reach no farther than ε/2 from its base | dropped: the foliage it carried stays within ε/2 of wood |
//! | otherwise | a generalised cylinder: three sides, as few rings as keep its axis within ε/2, a point at the tip |
//!
//! so wood and foliage share the level's error bound, and no level shows leaves far from the
//! wood that holds them. The trunk (the piece reaching lowest) always stays.

use super::{BoneTree, is_cut_out};
use crate::bake::character::lod::{extract, progressive_mesh};
use crate::bake::character::simplify::{Method, Sequence};
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use crate::model::{Model, SkinnedMesh};
use glam::Vec3;

/// No simplified wood goes below this many triangles.
pub const WOOD_FLOOR: u32 = 60;

/// Sides of the generalised cylinders that stand in for thin pieces.
const SIDES: usize = 3;

/// A tree's wood and its progressive mesh.
pub struct WoodChain {
    /// The tree without its foliage.
    pub wood: Model,
    base: AnimationSpaceMesh,
    /// Base (GPU-ordered) vertex → vertex of `wood`.
    order: Vec<usize>,
    sequence: Sequence,
    /// The piece of every vertex of `wood`, and the pieces.
    piece_of: Vec<usize>,
    pieces: Vec<Piece>,
    /// Every piece, each after all those it holds.
    holders_last: Vec<usize>,
}

/// One connected piece of the wood (a branch, the trunk).
struct Piece {
    /// Twice the radius of a tube with the same spread across its length.
    thickness: f32,
    /// The trunk: never dropped.
    trunk: bool,
    /// How far it and all the wood it holds reach from its base.
    reach: f32,
    /// The pieces it holds (whose root bone is its own, or below one of its own).
    holds: Vec<usize>,
    /// Its axis, base to tip: centres of slabs across it, with their radii.
    axis: Vec<AxisPoint>,
}

#[derive(Clone, Copy)]
struct AxisPoint {
    centre: Vec3,
    radius: f32,
    /// The piece's vertex nearest the centre: the cylinder's ring there copies its skin
    /// influences, material and texture row.
    source: usize,
}

impl WoodChain {
    /// Simplifies the wood of `tree` (everything not cut out with alpha).
    pub fn new(tree: &Model) -> WoodChain {
        let wood = without_foliage(tree);
        let (base, sequence, _) = progressive_mesh(&wood, Method::AnimationSpace, &|_| {});
        // The same ordering progressive_mesh applied, to map its vertices back.
        let (_, order) = AnimationSpaceMesh::from_skinned(&wood.mesh, &wood.skeleton)
            .optimized_for_gpu_with_order();
        let (piece_of, pieces) = pieces(&wood.mesh, &BoneTree::new(&tree.skeleton));
        let holders_last = holders_last(&pieces);
        WoodChain {
            wood,
            base,
            order,
            sequence,
            piece_of,
            pieces,
            holders_last,
        }
    }

    pub fn full_triangles(&self) -> u32 {
        self.sequence.base_triangle_count()
    }

    /// The tree with its wood simplified as far as an error of `error` scene units allows
    /// (the collapsed part never below [`WOOD_FLOOR`] triangles), thin pieces made
    /// cylinders or dropped (see the module's table), foliage as in `tree`.
    pub fn tree_at(&self, tree: &Model, error: f32) -> Model {
        let floor = WOOD_FLOOR.min(self.sequence.base_triangle_count());
        let steps = &self.sequence.steps;
        let within = steps.partition_point(|s| s.max_cost <= error);
        let above_floor = steps.partition_point(|s| s.triangles >= floor);
        let prefix = within.min(above_floor);
        let levels = extract(&self.base, &self.sequence, &[0, prefix]);
        let level = levels
            .last()
            .expect("extract returns every prefix asked for");
        let collapsed = |p: &Piece| p.thickness > error;
        let dropped = self.dropped(error);
        let mut simplified = SkinnedMesh::empty();
        for &b in &level.source {
            simplified.copy_vertex_from(&self.wood.mesh, self.order[b as usize]);
        }
        simplified.indices = level.mesh.indices.clone();
        let piece_of = |v: u32| self.piece_of[self.order[level.source[v as usize] as usize]];
        let mut mesh = SkinnedMesh::empty();
        mesh.copy_triangles_from(&simplified, |t| collapsed(&self.pieces[piece_of(t[0])]));
        for (p, dropped) in self.pieces.iter().zip(dropped) {
            if collapsed(p) || dropped {
                continue;
            }
            generalised_cylinder(&mut mesh, &self.wood.mesh, p, error * 0.5);
        }
        copy_triangles(&mut mesh, tree, true);
        Model {
            mesh,
            ..tree.clone()
        }
    }

    /// Which pieces are dropped at `error` (see the module's table): pieces that hold others
    /// are decided after them.
    fn dropped(&self, error: f32) -> Vec<bool> {
        let mut dropped = vec![false; self.pieces.len()];
        for &p in &self.holders_last {
            let piece = &self.pieces[p];
            // A twig (holding no wood) goes when thin; a branch holding others only when they
            // all went and none of it reaches far.
            dropped[p] = !piece.trunk
                && piece.thickness <= error * 0.5
                && (piece.holds.is_empty()
                    || (piece.reach <= error * 0.5 && piece.holds.iter().all(|&q| dropped[q])));
        }
        dropped
    }
}

/// The connected pieces of `mesh` (vertices at one position joined): the piece of every
/// vertex, and the pieces.
///
/// A piece holds another when the other's root bone (its bone nearest the skeleton's root) is the
/// piece's own or below one of its own, a piece owning the bones that most of its vertices
/// follow.
fn pieces(mesh: &SkinnedMesh, bones: &BoneTree) -> (Vec<usize>, Vec<Piece>) {
    let n = mesh.vertex_count();
    // Connected through positions, not vertex indices: a file split along UV or normal seams
    // (or at every corner, flat-shaded) still has one piece per branch.
    let at = crate::geometry::weld::position_groups(
        &mesh.positions,
        crate::geometry::weld::tolerance_for(&mesh.positions),
    );
    let welded: Vec<u32> = mesh.indices.iter().map(|&v| at[v as usize]).collect();
    let positions = at.iter().max().map_or(0, |&g| g as usize + 1);
    let roots = crate::geometry::connected_pieces(positions, welded.chunks_exact(3));
    let mut piece_of_root = std::collections::HashMap::new();
    let piece: Vec<usize> = at
        .iter()
        .map(|&g| roots[g as usize])
        .map(|r| {
            let next = piece_of_root.len();
            *piece_of_root.entry(r).or_insert(next)
        })
        .collect();
    let count = piece_of_root.len();
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); count];
    for (v, &p) in piece.iter().enumerate() {
        members[p].push(v);
    }
    let trunk = (0..n)
        .min_by(|&a, &b| mesh.positions[a].y.total_cmp(&mesh.positions[b].y))
        .map(|v| piece[v]);
    // How many vertices of each piece follow each bone most.
    let mut follow: std::collections::HashMap<(usize, u32), u32> = std::collections::HashMap::new();
    for (v, &p) in piece.iter().enumerate() {
        let dominant = mesh
            .influences_of(v)
            .iter()
            .max_by(|a, b| a.weight.total_cmp(&b.weight).then(b.bone.cmp(&a.bone)))
            .map(|i| i.bone);
        if let Some(b) = dominant.filter(|&b| (b as usize) < bones.parent.len()) {
            *follow.entry((p, b)).or_insert(0) += 1;
        }
    }
    // The owner of a bone: the piece with most vertices following it (ties: the first).
    let mut owner: std::collections::HashMap<u32, (usize, u32)> = std::collections::HashMap::new();
    let mut own_bones: Vec<Vec<u32>> = vec![Vec::new(); count];
    for (&(p, b), &k) in &follow {
        own_bones[p].push(b);
        let e = owner.entry(b).or_insert((p, k));
        if k > e.1 || (k == e.1 && p < e.0) {
            *e = (p, k);
        }
    }
    let mut holder: Vec<Option<usize>> = vec![None; count];
    for (p, own) in own_bones.iter().enumerate() {
        if Some(p) == trunk {
            continue;
        }
        let Some(&root) = own.iter().min_by_key(|&&b| (bones.depth[b as usize], b)) else {
            continue;
        };
        // Up from the root bone to the first bone another piece owns.
        let mut b = Some(root);
        while let Some(bone) = b {
            match owner.get(&bone) {
                Some(&(q, _)) if q != p => {
                    holder[p] = Some(q);
                    break;
                }
                _ => b = bones.parent[bone as usize],
            }
        }
    }
    let mut pieces: Vec<Piece> = members
        .iter()
        .enumerate()
        .map(|(p, vertices)| {
            let (thickness, axis) = axis_of(mesh, vertices, lowest(mesh, vertices));
            Piece {
                thickness,
                trunk: Some(p) == trunk,
                reach: 0.0,
                holds: Vec::new(),
                axis,
            }
        })
        .collect();
    // A piece's base is the end of its axis nearer the piece holding it (the trunk's, and a
    // loose piece's, its lowest end).
    for p in 0..count {
        let Some(q) = holder[p] else { continue };
        pieces[q].holds.push(p);
        let near = |c: Vec3| {
            pieces[q]
                .axis
                .iter()
                .map(|a| a.centre.distance(c))
                .fold(f32::MAX, f32::min)
        };
        let axis = &pieces[p].axis;
        if let (Some(first), Some(last)) = (axis.first(), axis.last())
            && near(last.centre) < near(first.centre)
        {
            pieces[p].axis.reverse();
        }
    }
    // Reach: the farthest axis point of the piece and all it holds, from its base.
    for p in 0..count {
        let Some(base) = pieces[p].axis.first().map(|a| a.centre) else {
            continue;
        };
        let mut reach = 0.0f32;
        let mut stack = vec![p];
        while let Some(q) = stack.pop() {
            for a in &pieces[q].axis {
                reach = reach.max(a.centre.distance(base) + a.radius);
            }
            stack.extend(pieces[q].holds.iter().copied());
        }
        pieces[p].reach = reach;
    }
    (piece, pieces)
}

/// Every piece, each after all the pieces it holds (the holding relation is a forest: every
/// piece has at most one holder, found up the skeleton).
fn holders_last(pieces: &[Piece]) -> Vec<usize> {
    let mut held = vec![false; pieces.len()];
    for p in pieces {
        for &q in &p.holds {
            held[q] = true;
        }
    }
    // Depth-first from every piece no one holds, each piece listed after its children.
    let mut order = Vec::with_capacity(pieces.len());
    let mut visited = vec![false; pieces.len()];
    for root in (0..pieces.len()).filter(|&p| !held[p]) {
        let mut stack = vec![(root, false)];
        while let Some((p, children_done)) = stack.pop() {
            if children_done {
                order.push(p);
            } else if !visited[p] {
                visited[p] = true;
                stack.push((p, true));
                stack.extend(pieces[p].holds.iter().map(|&q| (q, false)));
            }
        }
    }
    order
}

/// Where a piece starts: its vertex nearest the ground. A branch grows up and out from where it
/// leaves its parent, so its lowest end is nearly always its base; where it droops, the axis
/// merely runs tip to base, which draws the same cylinder.
fn lowest(mesh: &SkinnedMesh, vertices: &[usize]) -> Vec3 {
    vertices
        .iter()
        .map(|&v| mesh.positions[v])
        .min_by(|a, b| a.y.total_cmp(&b.y))
        .unwrap_or(Vec3::ZERO)
}

/// Slabs across a piece's length, for its axis.
const SLABS: usize = 8;

/// A piece's thickness and its axis: its vertices' principal direction, cut into [`SLABS`]
/// slabs, each slab's centroid and mean distance from it across the axis; the ends carried
/// out to the piece's extent along the axis, running from the end nearer `base`.
fn axis_of(mesh: &SkinnedMesh, vertices: &[usize], base: Vec3) -> (f32, Vec<AxisPoint>) {
    let points: Vec<glam::DVec3> = vertices
        .iter()
        .map(|&v| mesh.positions[v].as_dvec3())
        .collect();
    let count = points.len().max(1) as f64;
    let m = points.iter().sum::<glam::DVec3>() / count;
    let mut cov = nalgebra::Matrix3::<f64>::zeros();
    for p in &points {
        let d = nalgebra::Vector3::new(p.x - m.x, p.y - m.y, p.z - m.z);
        cov += d * d.transpose() / count;
    }
    let eig = cov.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    // A tube of radius r spreads r²/2 across its axis, in both directions.
    let thickness = 2.0 * (2.0 * eig.eigenvalues[order[1]].max(0.0)).sqrt();
    let e = eig.eigenvectors.column(order[2]);
    let mut dir = glam::DVec3::new(e[0], e[1], e[2]).normalize_or(glam::DVec3::Y);
    if (base.as_dvec3() - m).dot(dir) > 0.0 {
        dir = -dir;
    }
    let t: Vec<f64> = points.iter().map(|p| (*p - m).dot(dir)).collect();
    let (lo, hi) = t
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    let span = (hi - lo).max(1e-9);
    let mut slabs = vec![(0.0f64, glam::DVec3::ZERO, Vec::new()); SLABS];
    for (k, (p, &tk)) in points.iter().zip(&t).enumerate() {
        let s = (((tk - lo) / span * SLABS as f64) as usize).min(SLABS - 1);
        slabs[s].0 += 1.0;
        slabs[s].1 += *p;
        slabs[s].2.push(k);
    }
    let mut axis: Vec<AxisPoint> = slabs
        .iter()
        .filter(|s| s.0 > 0.0)
        .map(|(n, sum, ks)| {
            let c = *sum / *n;
            let across = |p: glam::DVec3| {
                let d = p - c;
                (d - dir * d.dot(dir)).length()
            };
            let radius = ks.iter().map(|&k| across(points[k])).sum::<f64>() / *n;
            let source = ks
                .iter()
                .copied()
                .min_by(|&a, &b| points[a].distance(c).total_cmp(&points[b].distance(c)))
                .map_or(vertices[0], |k| vertices[k]);
            AxisPoint {
                centre: c.as_vec3(),
                radius: radius as f32,
                source,
            }
        })
        .collect();
    // The end slabs' centroids lie inside the piece: carry them out to its ends.
    if let (Some(first), Some(last)) = (axis.first().copied(), axis.last().copied()) {
        let along = |p: Vec3| (p.as_dvec3() - m).dot(dir);
        axis.insert(
            0,
            AxisPoint {
                centre: first.centre + (dir * (lo - along(first.centre))).as_vec3(),
                ..first
            },
        );
        axis.push(AxisPoint {
            centre: last.centre + (dir * (hi - along(last.centre))).as_vec3(),
            ..last
        });
    }
    (thickness as f32, axis)
}

/// The points of `axis` that keep it within `tolerance` of every dropped one (Douglas and
/// Peucker 1973): the ends, and recursively the farthest point from the chord while it is
/// farther than `tolerance`.
fn simplified_axis(axis: &[AxisPoint], tolerance: f32) -> Vec<AxisPoint> {
    fn keep(axis: &[AxisPoint], a: usize, b: usize, tolerance: f32, out: &mut Vec<bool>) {
        let (p, q) = (axis[a].centre, axis[b].centre);
        let chord = q - p;
        let len2 = chord.length_squared().max(1e-20);
        let far = (a + 1..b)
            .map(|k| {
                let d = axis[k].centre - p;
                let s = (d.dot(chord) / len2).clamp(0.0, 1.0);
                (k, (d - chord * s).length())
            })
            .max_by(|x, y| x.1.total_cmp(&y.1));
        if let Some((k, d)) = far
            && d > tolerance
        {
            out[k] = true;
            keep(axis, a, k, tolerance, out);
            keep(axis, k, b, tolerance, out);
        }
    }
    if axis.len() <= 2 {
        return axis.to_vec();
    }
    let mut kept = vec![false; axis.len()];
    kept[0] = true;
    kept[axis.len() - 1] = true;
    keep(axis, 0, axis.len() - 1, tolerance, &mut kept);
    axis.iter()
        .zip(kept)
        .filter(|(_, k)| *k)
        .map(|(p, _)| *p)
        .collect()
}

/// Appends `piece` as a generalised cylinder to `mesh`: a [`SIDES`]-sided ring at every point
/// of its axis kept within `tolerance`, the tip closed by one triangle, the base too where
/// no other piece hides it (the trunk). Its rings take skin, material and texture row from the
/// piece's vertex nearest their centre, so the cylinder bends with the branch it stands for.
/// A held branch with a straight axis costs 7 triangles.
///
/// A ring's circumradius is chosen for the cylinder to cover as much of the screen as the
/// round branch: by Cauchy's formula a convex polygon's width averaged over directions is its
/// perimeter over π, so a regular n-gon of circumradius R is on average as wide as a circle of
/// radius r when R = π r / (n sin(π/n)) (×1.21 for a triangle).
fn generalised_cylinder(mesh: &mut SkinnedMesh, wood: &SkinnedMesh, piece: &Piece, tolerance: f32) {
    let axis = simplified_axis(&piece.axis, tolerance);
    if axis.len() < 2 {
        return;
    }
    let n = SIDES as f32;
    let widen = std::f32::consts::PI / (n * (std::f32::consts::PI / n).sin());
    let dir = (axis[axis.len() - 1].centre - axis[0].centre).normalize_or(Vec3::Y);
    // One frame across the whole piece, u × v = dir: rings stay in step and do not twist.
    let u = dir.any_orthonormal_vector();
    let v = dir.cross(u);
    let rings: Vec<u32> = axis
        .iter()
        .map(|at| {
            // A ring's vertices are consecutive: its first one names it.
            let ring: Vec<u32> = (0..SIDES)
                .map(|s| {
                    let a = std::f32::consts::TAU * s as f32 / n;
                    let out = u * a.cos() + v * a.sin();
                    let k = mesh.copy_vertex_from(wood, at.source);
                    mesh.positions[k as usize] = at.centre + out * at.radius * widen;
                    mesh.normals[k as usize] = out;
                    mesh.uvs[k as usize].x = s as f32 / n;
                    k
                })
                .collect();
            ring[0]
        })
        .collect();
    let side = |ring: u32, s: usize| ring + (s % SIDES) as u32;
    let indices = &mut mesh.indices;
    // Counter-clockwise seen from outside: u × v = dir, and the sides go round from u to v.
    for s in 0..SIDES {
        for w in rings.windows(2) {
            let (a0, a1) = (side(w[0], s), side(w[0], s + 1));
            let (b0, b1) = (side(w[1], s), side(w[1], s + 1));
            indices.extend([a0, a1, b1, a0, b1, b0]);
        }
    }
    let (first, last) = (rings[0], rings[rings.len() - 1]);
    // The caps: fans facing along the axis at the tip, against it at the base.
    for s in 1..SIDES - 1 {
        indices.extend([last, side(last, s), side(last, s + 1)]);
        if piece.trunk {
            indices.extend([first, side(first, s + 1), side(first, s)]);
        }
    }
}

/// `tree` with the triangles of cut-out materials (and the vertices only they use) removed.
pub fn without_foliage(tree: &Model) -> Model {
    let mut mesh = SkinnedMesh::empty();
    copy_triangles(&mut mesh, tree, false);
    Model {
        mesh,
        ..tree.clone()
    }
}

/// `tree` with only the triangles of cut-out materials: its foliage (or billboards).
pub fn only_foliage(tree: &Model) -> Model {
    let mut mesh = SkinnedMesh::empty();
    copy_triangles(&mut mesh, tree, true);
    Model {
        mesh,
        ..tree.clone()
    }
}

/// Appends the triangles of `tree` whose material is (or is not) cut out.
fn copy_triangles(mesh: &mut SkinnedMesh, tree: &Model, foliage: bool) {
    let cut: Vec<bool> = tree.materials.iter().map(is_cut_out).collect();
    let src = &tree.mesh;
    mesh.copy_triangles_from(src, |t| {
        cut.get(src.materials[t[0] as usize] as usize)
            .copied()
            .unwrap_or(false)
            == foliage
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vertical branch: one vertex per axis point, for skins to copy.
    fn branch(bend: f32) -> (SkinnedMesh, Piece) {
        let mut wood = SkinnedMesh::empty();
        let axis: Vec<AxisPoint> = (0..=8)
            .map(|k| {
                let y = k as f32 * 0.5;
                let centre = Vec3::new(bend * (y * 0.7).sin(), y, 0.0);
                wood.positions.push(centre);
                wood.normals.push(Vec3::X);
                wood.uvs.push(glam::Vec2::new(0.0, y));
                wood.materials.push(0);
                wood.influences.push(crate::model::Influence {
                    bone: k,
                    weight: 1.0,
                });
                wood.influence_offsets.push(wood.influences.len() as u32);
                AxisPoint {
                    centre,
                    radius: 0.1,
                    source: k as usize,
                }
            })
            .collect();
        let piece = Piece {
            thickness: 0.2,
            trunk: true,
            reach: 4.0,
            holds: Vec::new(),
            axis,
        };
        (wood, piece)
    }

    #[test]
    fn a_cylinder_faces_out_and_is_as_wide_as_its_branch_on_average() {
        let (wood, piece) = branch(0.0);
        let mut mesh = SkinnedMesh::empty();
        generalised_cylinder(&mut mesh, &wood, &piece, 0.05);
        // Straight: two rings, three sides of two triangles, and both caps.
        assert_eq!(mesh.vertex_count(), 2 * SIDES);
        assert_eq!(mesh.triangle_count(), 2 * SIDES + 2);
        let mut perimeter = 0.0;
        for t in mesh.indices.chunks_exact(3) {
            let p = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            let c = (p[0] + p[1] + p[2]) / 3.0;
            let out = if n.y.abs() > 0.99 * n.length() {
                // A cap: it faces away from the middle of the branch.
                c - Vec3::new(0.0, 2.0, 0.0)
            } else {
                Vec3::new(c.x, 0.0, c.z)
            };
            assert!(n.dot(out) > 0.0, "triangle {t:?} faces in");
        }
        for s in 0..SIDES {
            perimeter += mesh.positions[s].distance(mesh.positions[(s + 1) % SIDES]);
        }
        // Cauchy: the mean width is perimeter / π, the branch's is 2r.
        assert!((perimeter / std::f32::consts::PI - 0.2).abs() < 1e-4);
        // Rings take their skin from the branch's vertices at their end.
        assert_eq!(mesh.influences_of(0)[0].bone, 0);
        assert_eq!(mesh.influences_of(SIDES)[0].bone, 8);
    }

    #[test]
    fn a_bent_branch_keeps_rings_where_it_bends() {
        let (wood, piece) = branch(0.5);
        let straight = simplified_axis(&piece.axis, 10.0).len();
        let close = simplified_axis(&piece.axis, 0.02).len();
        assert_eq!(straight, 2);
        assert!(close > 3, "{close} rings");
        let mut mesh = SkinnedMesh::empty();
        generalised_cylinder(&mut mesh, &wood, &piece, 0.02);
        // Every axis point dropped lies within the tolerance of the kept polyline.
        let kept = simplified_axis(&piece.axis, 0.02);
        for a in &piece.axis {
            let d = kept
                .windows(2)
                .map(|w| {
                    let (p, q) = (w[0].centre, w[1].centre);
                    let s = ((a.centre - p).dot(q - p) / (q - p).length_squared()).clamp(0.0, 1.0);
                    a.centre.distance(p + (q - p) * s)
                })
                .fold(f32::MAX, f32::min);
            assert!(d <= 0.02 + 1e-5, "{d}");
        }
        assert_eq!(mesh.vertex_count(), SIDES * close);
    }
}

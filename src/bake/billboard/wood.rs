//! The wood of a tree at coarser levels: the trunk and branches simplified by the skinned LOD
//! engine (Merry et al., the `as` metric: animation-space L2,2 error), cut where its error
//! bound reaches a level's ε, so wood and foliage of a level have the same error budget.
//!
//! Half-edge collapses keep every surviving vertex as it was, influences included, so each
//! simplified wood is a subset of the original vertices with new triangles, and stays a plain
//! skinned mesh that the tree's model can carry.
//!
//! Each branch is a closed piece of its own, which collapses cannot remove. A piece no thicker
//! than ε/2 is dropped instead: seen from where its level comes in, it is narrower than half
//! the screen tolerance, and the foliage around it covers it. The trunk (the piece that
//! reaches lowest) always stays.

use super::is_cut_out;
use crate::bake::animation_space::AnimationSpaceMesh;
use crate::bake::lod::{extract, progressive_mesh};
use crate::bake::simplify::{Method, Sequence};
use crate::model::{Model, SkinnedMesh};

/// No simplified wood goes below this many triangles.
pub const WOOD_FLOOR: u32 = 60;

/// A tree's wood and its progressive mesh.
pub struct WoodChain {
    /// The tree without its foliage.
    pub wood: Model,
    base: AnimationSpaceMesh,
    /// Base (GPU-ordered) vertex → vertex of `wood`.
    order: Vec<usize>,
    sequence: Sequence,
}

impl WoodChain {
    /// Simplifies the wood of `tree` (everything not cut out with alpha).
    pub fn new(tree: &Model) -> WoodChain {
        let wood = without_foliage(tree);
        let (base, sequence, _) = progressive_mesh(&wood, Method::AnimationSpace, &|_| {});
        // The same ordering progressive_mesh applied, to map its vertices back.
        let (_, order) = AnimationSpaceMesh::from_skinned(&wood.mesh, &wood.skeleton)
            .optimized_for_gpu_with_order();
        WoodChain {
            wood,
            base,
            order,
            sequence,
        }
    }

    pub fn full_triangles(&self) -> u32 {
        self.sequence.base_triangle_count()
    }

    /// The tree with its wood simplified as far as an error of `error` scene units allows
    /// (never below [`WOOD_FLOOR`] triangles), foliage as in `tree`.
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
        let mut mesh = SkinnedMesh::empty();
        for &b in &level.source {
            mesh.copy_vertex_from(&self.wood.mesh, self.order[b as usize]);
        }
        mesh.indices = level.mesh.indices.clone();
        drop_thin_pieces(&mut mesh, error * 0.5);
        copy_triangles(&mut mesh, tree, true);
        Model {
            mesh,
            ..tree.clone()
        }
    }
}

/// Removes the connected pieces of `mesh` whose thickness (twice the radius of a tube with the
/// same spread across its length) is at most `width`, and the vertices only they used; never
/// the piece holding the lowest vertex (the trunk).
fn drop_thin_pieces(mesh: &mut SkinnedMesh, width: f32) {
    let n = mesh.vertex_count();
    let roots = super::connected_pieces(n, mesh.indices.chunks_exact(3));
    let trunk = (0..n)
        .min_by(|&a, &b| mesh.positions[a].y.total_cmp(&mesh.positions[b].y))
        .map(|v| roots[v]);
    // Covariance of every piece's vertices.
    let mut stats: std::collections::HashMap<u32, (f64, glam::DVec3, [f64; 6])> =
        std::collections::HashMap::new();
    for (v, &r) in roots.iter().enumerate() {
        let p = mesh.positions[v].as_dvec3();
        let e = stats.entry(r).or_insert((0.0, glam::DVec3::ZERO, [0.0; 6]));
        e.0 += 1.0;
        e.1 += p;
        e.2[0] += p.x * p.x;
        e.2[1] += p.y * p.y;
        e.2[2] += p.z * p.z;
        e.2[3] += p.x * p.y;
        e.2[4] += p.x * p.z;
        e.2[5] += p.y * p.z;
    }
    let thin: std::collections::HashSet<u32> = stats
        .iter()
        .filter(|(r, _)| Some(**r) != trunk)
        .filter(|(_, (count, sum, sq))| {
            let m = *sum / *count;
            let c = |i: usize, a: f64, b: f64| sq[i] / count - a * b;
            let cov = nalgebra::Matrix3::new(
                c(0, m.x, m.x),
                c(3, m.x, m.y),
                c(4, m.x, m.z),
                c(3, m.x, m.y),
                c(1, m.y, m.y),
                c(5, m.y, m.z),
                c(4, m.x, m.z),
                c(5, m.y, m.z),
                c(2, m.z, m.z),
            );
            let mut ev: Vec<f64> = cov.symmetric_eigenvalues().iter().copied().collect();
            ev.sort_by(f64::total_cmp);
            // A tube of radius r spreads r²/2 across its axis, in both directions.
            let radius = (2.0 * ev[1].max(0.0)).sqrt();
            2.0 * radius <= width as f64
        })
        .map(|(&r, _)| r)
        .collect();
    if thin.is_empty() {
        return;
    }
    let mut compact = SkinnedMesh::empty();
    compact.copy_triangles_from(mesh, |t| !thin.contains(&roots[t[0] as usize]));
    *mesh = compact;
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

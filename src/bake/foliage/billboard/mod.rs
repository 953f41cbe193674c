//! Animated billboard clouds for foliage (the thesis of Bennett-Therkildsen, Carlsen & Schmid,
//! "Animated Billboard Clouds for Foliage Simplification", Aalborg University, 2007: Ch. 2, 3 and
//! 7): pure CPU.
//!
//! - [`foliage`] finds a tree's leaves: the connected pieces of the triangles whose material
//!   cuts its shape out with alpha, each bound to one bone.
//! - [`cloud::stochastic_cloud`] clusters leaves onto billboards (§3.3–3.7).
//! - [`skeleton_cloud`] builds one cloud per bone (the thesis's "skeleton billboard cloud
//!   simplification", Ch. 7): every billboard is then skinned with weight 1 to its bone and
//!   moves rigidly with its branch, exactly as its leaves did.

pub mod atlas;
pub mod bends;
pub mod chain;
pub mod cloud;
pub mod clumps;
pub mod occlusion;
pub mod rect;
pub mod siblings;
pub mod trim;
pub mod wood;

use crate::model::Model;
use cloud::{Billboard, CloudParams, Leaf, stochastic_cloud};
use glam::Vec3;
use rayon::prelude::*;

/// A tree's leaves, rest pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Foliage {
    pub leaves: Vec<Leaf>,
    /// The bone every leaf is bound to.
    pub bones: Vec<u32>,
    /// For every leaf, its triangles (indices into the model's triangle list).
    pub triangles: Vec<Vec<u32>>,
    /// Leaves whose vertices were bound to more than one bone, rebound to the bone that holds
    /// most of their weight (the thesis's pre-processing §8.3).
    pub rebound: usize,
}

pub use super::classify::is_tree;

/// Does this material cut its shape out with alpha (foliage)?
pub fn is_cut_out(m: &crate::model::Material) -> bool {
    m.cuts_out()
}

/// The leaves of `model`: triangles of cut-out materials, joined into leaves where they share
/// vertices (a quad's two triangles are one leaf). Fails, in one line, where there are none.
pub fn foliage(model: &Model) -> Result<Foliage, String> {
    let mesh = &model.mesh;
    let cut_out: Vec<bool> = model.materials.iter().map(is_cut_out).collect();
    let is_leaf = |v: u32| {
        cut_out
            .get(mesh.materials[v as usize] as usize)
            .copied()
            .unwrap_or(false)
    };
    let tris: Vec<u32> = (0..mesh.triangle_count() as u32)
        .filter(|&t| is_leaf(mesh.indices[3 * t as usize]))
        .collect();
    if tris.is_empty() {
        return Err(
            "no foliage: no triangle has a material that cuts leaves out with alpha".into(),
        );
    }
    let roots = crate::geometry::connected_pieces(
        mesh.vertex_count(),
        tris.iter()
            .map(|&t| &mesh.indices[3 * t as usize..3 * t as usize + 3]),
    );
    let mut piece_of = std::collections::HashMap::new();
    let mut pieces: Vec<Vec<u32>> = Vec::new();
    for &t in &tris {
        let root = roots[mesh.indices[3 * t as usize] as usize];
        let k = *piece_of.entry(root).or_insert_with(|| {
            pieces.push(Vec::new());
            pieces.len() - 1
        });
        pieces[k].push(t);
    }
    let mut out = Foliage {
        leaves: Vec::with_capacity(pieces.len()),
        bones: Vec::with_capacity(pieces.len()),
        triangles: Vec::with_capacity(pieces.len()),
        rebound: 0,
    };
    for piece in pieces {
        // Corners: the piece's vertices in order of first use, which for a quad (0 1 2, 0 2 3)
        // goes round it.
        let mut corners: Vec<u32> = Vec::new();
        for &t in &piece {
            for &v in &mesh.indices[3 * t as usize..3 * t as usize + 3] {
                if !corners.contains(&v) {
                    corners.push(v);
                }
            }
        }
        let mut weight_of_bone: Vec<(u32, f32)> = Vec::new();
        for &v in &corners {
            for inf in mesh.influences_of(v as usize) {
                match weight_of_bone.iter_mut().find(|(b, _)| *b == inf.bone) {
                    Some(e) => e.1 += inf.weight,
                    None => weight_of_bone.push((inf.bone, inf.weight)),
                }
            }
        }
        if weight_of_bone.len() > 1 {
            out.rebound += 1;
        }
        let bone = weight_of_bone
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
            .map_or(0, |e| e.0);
        // A quad or a triangle by its corners; a larger piece (a strip, a fold, crossed
        // cards) by its triangles, whose corners in order of use do not go round it.
        out.leaves.push(if piece.len() <= 2 {
            Leaf::new(
                corners
                    .iter()
                    .map(|&v| mesh.positions[v as usize])
                    .collect(),
            )
        } else {
            Leaf::of_mesh(&piece, mesh)
        });
        out.bones.push(bone);
        out.triangles.push(piece);
    }
    Ok(out)
}

/// A skeleton billboard cloud: billboards built bone by bone, each bound to its bone.
#[derive(Clone, Debug, PartialEq)]
pub struct SkeletonCloud {
    pub billboards: Vec<Billboard>,
    /// The bone of every billboard.
    pub bones: Vec<u32>,
}

impl SkeletonCloud {
    pub fn total_area(&self) -> f32 {
        self.billboards.iter().map(Billboard::area).sum()
    }
}

/// How leaves are split into separate clouds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Grouping {
    /// One cloud per bone (thesis Ch. 7): billboards move exactly as their leaves did.
    PerBone,
    /// One cloud per set of sibling bones whose leaves move alike within ε (common joint
    /// rotation, thesis §7.1, see [`siblings`]): the leaves are rebound to one bone of their
    /// set with [`siblings::merge_siblings`] first, then clouds are built per bone.
    Siblings,
    /// One cloud per branch subtree hanging below `forks` forks of the skeleton (0: one cloud
    /// for the whole crown). Coarser groups give fewer billboards; a billboard then moves with
    /// the deepest bone its leaves share, and the finer sway below it is lost (the thesis's
    /// joint collapses §7.1, taken a whole subtree at a time).
    Subtree { forks: u32 },
}

/// The skeleton as bones: the parent bone of every bone (through non-joint nodes) and the
/// number of forks (bones with two or more child bones) above it.
struct BoneTree {
    parent: Vec<Option<u32>>,
    forks: Vec<u32>,
    depth: Vec<u32>,
}

impl BoneTree {
    fn new(skeleton: &crate::model::Skeleton) -> BoneTree {
        let n = skeleton.joints.len();
        let mut bone_of_node = vec![None; skeleton.nodes.len()];
        for (b, &node) in skeleton.joints.iter().enumerate() {
            bone_of_node[node as usize] = Some(b as u32);
        }
        let parent: Vec<Option<u32>> = skeleton
            .joints
            .iter()
            .map(|&node| {
                let mut p = skeleton.nodes[node as usize].parent;
                while let Some(q) = p {
                    if let Some(b) = bone_of_node[q as usize] {
                        return Some(b);
                    }
                    p = skeleton.nodes[q as usize].parent;
                }
                None
            })
            .collect();
        let mut children = vec![0u32; n];
        for p in parent.iter().flatten() {
            children[*p as usize] += 1;
        }
        let chain = |mut b: u32, f: &dyn Fn(u32) -> u32| {
            let mut total = 0;
            while let Some(p) = parent[b as usize] {
                total += f(p);
                b = p;
            }
            total
        };
        let forks = (0..n as u32)
            .map(|b| chain(b, &|p| (children[p as usize] >= 2) as u32))
            .collect();
        let depth = (0..n as u32).map(|b| chain(b, &|_| 1)).collect();
        BoneTree {
            parent,
            forks,
            depth,
        }
    }

    /// The bone whose cloud a leaf on `bone` joins.
    fn group(&self, bone: u32, grouping: Grouping) -> u32 {
        match grouping {
            Grouping::PerBone | Grouping::Siblings => bone,
            Grouping::Subtree { forks } => {
                let mut b = bone;
                while let Some(p) = self.parent[b as usize] {
                    if self.forks[b as usize] <= forks {
                        break;
                    }
                    b = p;
                }
                b
            }
        }
    }

    /// The deepest bone that is `a` or an ancestor of it and also of `b`.
    fn shared(&self, mut a: u32, mut b: u32) -> u32 {
        while a != b {
            if self.depth[a as usize] >= self.depth[b as usize] {
                match self.parent[a as usize] {
                    Some(p) => a = p,
                    None => return a,
                }
            } else {
                match self.parent[b as usize] {
                    Some(p) => b = p,
                    None => return b,
                }
            }
        }
        a
    }
}

/// The root of the bone hierarchy that `bone` belongs to.
pub fn root_bone(skeleton: &crate::model::Skeleton, bone: u32) -> u32 {
    let tree = BoneTree::new(skeleton);
    let mut b = bone;
    while let Some(p) = tree.parent.get(b as usize).copied().flatten() {
        b = p;
    }
    b
}

/// A billboard cloud of the foliage, one cloud per group of `grouping`, in parallel; every
/// billboard is bound to the deepest bone its leaves share. Leaf indices in the billboards are
/// indices into `foliage.leaves`; ε is in scene units.
pub fn grouped_cloud(
    skeleton: &crate::model::Skeleton,
    foliage: &Foliage,
    params: &CloudParams,
    grouping: Grouping,
) -> SkeletonCloud {
    let tree = BoneTree::new(skeleton);
    let bone_count = tree.parent.len() as u32;
    let group_of: Vec<u32> = foliage
        .bones
        .iter()
        .map(|&b| {
            if b < bone_count {
                tree.group(b, grouping)
            } else {
                b
            }
        })
        .collect();
    cloud_of_groups(skeleton, foliage, params, &group_of)
}

/// A billboard cloud of the foliage, one cloud per distinct value of `group_of` (one per leaf),
/// in parallel; every billboard is bound to the deepest bone its leaves share.
pub fn cloud_of_groups(
    skeleton: &crate::model::Skeleton,
    foliage: &Foliage,
    params: &CloudParams,
    group_of: &[u32],
) -> SkeletonCloud {
    let tree = BoneTree::new(skeleton);
    let bone_count = tree.parent.len() as u32;
    let mut groups: Vec<u32> = group_of.to_vec();
    groups.sort_unstable();
    groups.dedup();
    let per_group: Vec<Vec<Billboard>> = groups
        .par_iter()
        .map(|&g| {
            let members: Vec<u32> = (0..foliage.leaves.len() as u32)
                .filter(|&i| group_of[i as usize] == g)
                .collect();
            let leaves: Vec<Leaf> = members
                .iter()
                .map(|&i| foliage.leaves[i as usize].clone())
                .collect();
            let group = CloudParams {
                seed: params.seed ^ (g as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15),
                ..*params
            };
            let mut cloud = stochastic_cloud(&leaves, &group);
            for b in &mut cloud {
                for i in b.leaves.iter_mut().chain(b.drawn.iter_mut()) {
                    *i = members[*i as usize];
                }
            }
            cloud
        })
        .collect();
    let mut out = SkeletonCloud {
        billboards: Vec::new(),
        bones: Vec::new(),
    };
    for cloud in per_group {
        for b in cloud {
            let bone = b
                .leaves
                .iter()
                .map(|&i| foliage.bones[i as usize])
                .reduce(|a, c| {
                    if a < bone_count && c < bone_count {
                        tree.shared(a, c)
                    } else {
                        a
                    }
                })
                .unwrap_or(0);
            out.bones.push(bone);
            out.billboards.push(b);
        }
    }
    out
}

/// One cloud per bone that carries leaves (thesis Ch. 7).
pub fn skeleton_cloud(
    skeleton: &crate::model::Skeleton,
    foliage: &Foliage,
    params: &CloudParams,
) -> SkeletonCloud {
    grouped_cloud(skeleton, foliage, params, Grouping::PerBone)
}

/// The tree's height in its rest pose (ε is given in units of it).
pub fn tree_height(model: &Model) -> f32 {
    let (lo, hi) = model.mesh.positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    (hi.y - lo.y).max(1e-3)
}

/// The tree with its foliage replaced by a billboard cloud: the wood as it was, and every
/// billboard a polygon skinned with weight 1 to its bone (its entry of `outlines`, trimmed
/// round its leaves by [`trim::outline`]; the whole rectangle where there is none), textured
/// from `atlas` (a new material after the wood's), its vertices' normal its entry of
/// `normals` (the normal it is lit by, see [`atlas::AtlasTriangles`]; its plane's where there
/// is none). The billboards' vertices come last, billboard after billboard. Materials that
/// cut leaves out are dropped with the leaves.
pub fn cloud_model(
    tree: &Model,
    cloud: &SkeletonCloud,
    layout: &crate::bake::gpu_products::AtlasLayout,
    atlas: crate::model::Rgba8Image,
    normals: &[Vec3],
    outlines: &[trim::Outline],
) -> Model {
    use crate::model::{Influence, Material, SkinnedMesh};
    let src = &tree.mesh;
    let keep: Vec<bool> = tree.materials.iter().map(|m| !is_cut_out(m)).collect();
    let mut material_map = vec![0u16; tree.materials.len()];
    let mut materials: Vec<Material> = Vec::new();
    for (i, m) in tree.materials.iter().enumerate() {
        if keep[i] {
            material_map[i] = materials.len() as u16;
            materials.push(m.clone());
        }
    }
    let atlas_material = materials.len() as u16;
    materials.push(
        Material::cut_out(
            crate::bake::gpu_data::materials::BILLBOARD_MATERIAL,
            [1.0; 4],
            Some(atlas),
        )
        .with_role(crate::model::MaterialRole::BillboardAtlas),
    );
    let mut mesh = SkinnedMesh::empty();
    mesh.copy_triangles_from(src, |t| {
        keep.get(src.materials[t[0] as usize] as usize)
            .copied()
            .unwrap_or(true)
    });
    for m in &mut mesh.materials {
        *m = material_map[*m as usize];
    }
    let whole = trim::whole();
    for (b, (bb, &bone)) in cloud.billboards.iter().zip(&cloud.bones).enumerate() {
        let uvs = layout.corner_uvs(b);
        let first = mesh.positions.len() as u32;
        // The billboard is a rectangle: a point of its outline at (s, t) is the affine
        // blend of its corners 0, 1 and 3, in space and in the atlas alike.
        let c = &bb.corners;
        let outline = outlines.get(b).unwrap_or(&whole);
        for st in outline {
            mesh.positions
                .push(c[0] + (c[1] - c[0]) * st.x + (c[3] - c[0]) * st.y);
            mesh.normals
                .push(normals.get(b).copied().unwrap_or(bb.plane.normal));
            mesh.uvs
                .push(uvs[0] + (uvs[1] - uvs[0]) * st.x + (uvs[3] - uvs[0]) * st.y);
            mesh.materials.push(atlas_material);
            mesh.influences.push(Influence { bone, weight: 1.0 });
            mesh.influence_offsets.push(mesh.influences.len() as u32);
        }
        // A fan: the outline is convex.
        for k in 1..outline.len().saturating_sub(1) as u32 {
            mesh.indices
                .extend_from_slice(&[first, first + k, first + k + 1]);
        }
    }
    Model {
        name: tree.name.clone(),
        mesh,
        skeleton: tree.skeleton.clone(),
        clips: tree.clips.clone(),
        materials,
    }
}

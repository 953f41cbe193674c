//! Animation space (Merry, Marais & Gain, "Analytic simplification of animated characters",
//! §2.1.2).
//!
//! Linear blend skinning writes a vertex as `v = Σ_i w_i G_i Ĝ_i⁻¹ v̂` (equation 1). Folding the
//! weight and the inverse rest-pose matrix into the vertex gives one homogeneous 4-vector per
//! influence, `p_i = w_i Ĝ_i⁻¹ v̂`, and skinning becomes a plain sum `v = Σ_i G_i p_i`
//! (equation 2). The homogeneous parts of the `p_i` sum to one. Normals go the same way through
//! the vector (3×3) part: `n_i = w_i Ĝ_i⁻¹ (n̂, 0)`, `n = Σ_i G_i n_i`.
//!
//! Everything later (the L2,2 metric, influence simplification, geomorphs, the GPU skinning)
//! works on these coordinates. This module builds them and holds the CPU reference evaluation.

use crate::model::{Skeleton, SkinnedMesh};
use glam::{Affine3A, Vec2, Vec3, Vec4};
use serde::{Deserialize, Serialize};

/// One influence of a vertex in animation space: `p_i` and the normal's `n_i` for bone `bone`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AsInfluence {
    pub bone: u32,
    pub p: Vec4,
    pub n: Vec3,
}

/// A mesh whose vertices live in animation space.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AnimationSpaceMesh {
    /// Influences of vertex `v` are `influences[offsets[v]..offsets[v + 1]]`.
    pub offsets: Vec<u32>,
    pub influences: Vec<AsInfluence>,
    pub uvs: Vec<Vec2>,
    pub materials: Vec<u16>,
    pub indices: Vec<u32>,
    /// Per vertex, the row of the spectra texture whose offset moves it
    /// ([`crate::bake::gpu_data::spectra::NO_ROW`]: none); empty where nothing moves by
    /// spectra (every character, and every level but a spectral cloud's).
    pub spectral_rows: Vec<u32>,
    /// Per vertex, the light the crown takes from it (see
    /// [`crate::bake::foliage::billboard::occlusion`]); empty where nothing is occluded (every
    /// character).
    #[serde(default)]
    pub crown_occlusion: Vec<f32>,
    /// Per vertex, the view window of the billboard it is a corner of (see
    /// [`crate::bake::foliage::billboard::clumps`]; 0: drawn from every view); empty where no billboard
    /// has one.
    #[serde(default)]
    pub view_windows: Vec<f32>,
}

impl AnimationSpaceMesh {
    /// Converts a skinned mesh: `p_i = w_i Ĝ_i⁻¹ v̂` for every influence (equation 2).
    pub fn from_skinned(mesh: &SkinnedMesh, skeleton: &Skeleton) -> Self {
        let mut offsets = Vec::with_capacity(mesh.vertex_count() + 1);
        let mut influences = Vec::with_capacity(mesh.influences.len());
        offsets.push(0);
        for v in 0..mesh.vertex_count() {
            let rest = mesh.positions[v].extend(1.0);
            let normal = mesh.normals[v].extend(0.0);
            for inf in mesh.influences_of(v) {
                let inv_rest = skeleton.inverse_bind[inf.bone as usize];
                influences.push(AsInfluence {
                    bone: inf.bone,
                    p: inf.weight * (inv_rest * rest),
                    n: (inf.weight * (inv_rest * normal)).truncate(),
                });
            }
            offsets.push(influences.len() as u32);
        }
        AnimationSpaceMesh {
            offsets,
            influences,
            uvs: mesh.uvs.clone(),
            materials: mesh.materials.clone(),
            indices: mesh.indices.clone(),
            spectral_rows: Vec::new(),
            crown_occlusion: Vec::new(),
            view_windows: Vec::new(),
        }
    }

    /// Back to linear-blend skinning, for formats that know no animation space (glTF): each
    /// vertex at its rest-pose position `v̂ = Σ Ĝ_i p_i` and normal, each influence weighted
    /// `w_i` = the homogeneous coordinate of `p_i`, renormalised. The inverse of
    /// [`Self::from_skinned`] wherever `p_i = w_i Ĝ_i⁻¹ v̂` still holds: every level of the
    /// rest-pose and AS methods, whose half-edge collapses keep vertices as they were.
    /// Influence simplification gives a vertex per-bone positions that linear-blend skinning
    /// cannot hold ("not representable within the SSD framework", Merry et al. §6.4): the result
    /// is exact in the rest pose and an approximation elsewhere. Influences of no weight are
    /// dropped.
    pub fn to_skinned(&self, skeleton: &Skeleton) -> SkinnedMesh {
        let bind: Vec<glam::Affine3A> = skeleton
            .inverse_bind
            .iter()
            .map(|m| glam::Affine3A::from_mat4(m.inverse()))
            .collect();
        let (positions, normals) = self.evaluate(&bind);
        let mut mesh = SkinnedMesh {
            positions,
            normals: normals
                .into_iter()
                .map(|n| n.normalize_or(Vec3::Y))
                .collect(),
            uvs: self.uvs.clone(),
            materials: self.materials.clone(),
            indices: self.indices.clone(),
            ..Default::default()
        };
        mesh.influence_offsets.push(0);
        for v in 0..self.vertex_count() {
            let infs = self.influences_of(v);
            let total: f32 = infs.iter().map(|i| i.p.w.max(0.0)).sum();
            for i in infs {
                let w = i.p.w.max(0.0) / total.max(f32::MIN_POSITIVE);
                if w > 0.0 {
                    mesh.influences.push(crate::model::Influence {
                        bone: i.bone,
                        weight: w,
                    });
                }
            }
            if mesh.influences.len() == *mesh.influence_offsets.last().unwrap_or(&0) as usize {
                // No weight at all: the vertex follows its first bone.
                mesh.influences.push(crate::model::Influence {
                    bone: infs.first().map_or(0, |i| i.bone),
                    weight: 1.0,
                });
            }
            mesh.influence_offsets.push(mesh.influences.len() as u32);
        }
        mesh
    }

    pub fn vertex_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    pub fn influences_of(&self, v: usize) -> &[AsInfluence] {
        &self.influences[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    /// Whether some triangle covers area in some pose: its corners are three points in
    /// animation space (`v = Σ G_i p_i` with different `p_i`). Two corners with the same
    /// influences are one point in every pose, and such a triangle never covers a pixel.
    pub fn draws(&self) -> bool {
        self.indices.chunks_exact(3).any(|t| {
            // Normals aside: two corners with different normals are still one point.
            let same = |a: u32, b: u32| {
                let (x, y) = (
                    self.influences_of(a as usize),
                    self.influences_of(b as usize),
                );
                a == b
                    || (x.len() == y.len()
                        && x.iter().zip(y).all(|(i, j)| i.bone == j.bone && i.p == j.p))
            };
            !same(t[0], t[1]) && !same(t[1], t[2]) && !same(t[2], t[0])
        })
    }

    /// The same mesh in the order a GPU draws fastest: triangles reordered for the
    /// post-transform vertex cache, then vertices renumbered in order of first use
    /// (meshoptimizer's `optimizeVertexCache` and `optimizeVertexFetchRemap`). Vertices no
    /// triangle uses are dropped. Every vertex then tends to be skinned once instead of up to
    /// one and a half times, and neighbouring vertices sit next to each other in the vertex
    /// texture.
    pub fn optimized_for_gpu(&self) -> AnimationSpaceMesh {
        self.optimized_for_gpu_with_order().0
    }

    /// [`Self::optimized_for_gpu`], also returning which old vertex each new one is.
    pub fn optimized_for_gpu_with_order(&self) -> (AnimationSpaceMesh, Vec<usize>) {
        let n = self.vertex_count();
        // The web build has no meshoptimizer (C++): its triangles keep their order.
        #[cfg(not(target_arch = "wasm32"))]
        let indices = meshopt::optimize_vertex_cache(&self.indices, n);
        #[cfg(target_arch = "wasm32")]
        let indices = self.indices.clone();
        let (remap, order) = fetch_order(&indices, n);
        let mut out = AnimationSpaceMesh {
            offsets: Vec::with_capacity(order.len() + 1),
            influences: Vec::with_capacity(self.influences.len()),
            uvs: order.iter().map(|&v| self.uvs[v]).collect(),
            materials: order.iter().map(|&v| self.materials[v]).collect(),
            indices: indices.iter().map(|&i| remap[i as usize]).collect(),
            spectral_rows: if self.spectral_rows.is_empty() {
                Vec::new()
            } else {
                order.iter().map(|&v| self.spectral_rows[v]).collect()
            },
            crown_occlusion: if self.crown_occlusion.is_empty() {
                Vec::new()
            } else {
                order.iter().map(|&v| self.crown_occlusion[v]).collect()
            },
            view_windows: if self.view_windows.is_empty() {
                Vec::new()
            } else {
                order.iter().map(|&v| self.view_windows[v]).collect()
            },
        };
        out.offsets.push(0);
        for &v in &order {
            out.influences.extend_from_slice(self.influences_of(v));
            out.offsets.push(out.influences.len() as u32);
        }
        (out, order)
    }

    /// Rest-pose positions `Σ Ĝ_i p_i` (which is `Σ w_i v̂ = v̂`) for rest bone matrices
    /// `rest_bones`.
    pub fn rest_positions(&self, rest_bones: &[Affine3A]) -> Vec<Vec3> {
        (0..self.vertex_count())
            .map(|v| {
                self.influences_of(v)
                    .iter()
                    .map(|i| transform_homogeneous(&rest_bones[i.bone as usize], i.p))
                    .sum()
            })
            .collect()
    }

    /// Every vertex's normal in the rest pose, `Σ Ĝ_i n_i` normalised (zero where it vanishes),
    /// for the rest-pose bone matrices `rest_bones`.
    pub fn rest_normals(&self, rest_bones: &[Affine3A]) -> Vec<Vec3> {
        (0..self.vertex_count())
            .map(|v| {
                self.influences_of(v)
                    .iter()
                    .map(|i| rest_bones[i.bone as usize].matrix3 * i.n)
                    .sum::<Vec3>()
                    .normalize_or_zero()
            })
            .collect()
    }

    /// The CPU reference of animation-space skinning: `v = Σ G_i p_i` and `n = Σ G_i n_i`
    /// (normals not renormalised), for bone matrices `g`.
    pub fn evaluate(&self, g: &[Affine3A]) -> (Vec<Vec3>, Vec<Vec3>) {
        let mut positions = Vec::with_capacity(self.vertex_count());
        let mut normals = Vec::with_capacity(self.vertex_count());
        for v in 0..self.vertex_count() {
            let (mut pos, mut nrm) = (Vec3::ZERO, Vec3::ZERO);
            for inf in self.influences_of(v) {
                pos += transform_homogeneous(&g[inf.bone as usize], inf.p);
                nrm += g[inf.bone as usize].transform_vector3(inf.n);
            }
            positions.push(pos);
            normals.push(nrm);
        }
        (positions, normals)
    }
}

/// `G p` for an affine `G` and a homogeneous 4-vector `p` (whose w need not be 1).
pub fn transform_homogeneous(g: &Affine3A, p: Vec4) -> Vec3 {
    g.matrix3 * p.truncate() + Vec3::from(g.translation) * p.w
}

/// Vertices numbered in order of first use by `indices` (meshoptimizer's
/// `optimizeVertexFetchRemap`): for every old vertex its new index (`u32::MAX` for one no
/// triangle uses), and for every new vertex the old one. Written here because the `meshopt`
/// crate's wrapper (0.7) cuts its remap, which is indexed by *old* vertex, to the number of
/// vertices in use: with a vertex no triangle uses (a file's degenerate triangles dropped on
/// import leave such vertices), the later vertices lost their entries and every bake panicked.
fn fetch_order(indices: &[u32], vertex_count: usize) -> (Vec<u32>, Vec<usize>) {
    let mut remap = vec![u32::MAX; vertex_count];
    let mut order = Vec::with_capacity(vertex_count);
    for &i in indices {
        let r = &mut remap[i as usize];
        if *r == u32::MAX {
            *r = order.len() as u32;
            order.push(i as usize);
        }
    }
    (remap, order)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::anim::linear_blend_skinning;
    use crate::model::{Influence, Node, Trs};
    use glam::{Mat4, Quat};

    /// Two bones, one vertex halfway, weights 0.5 / 0.5.
    fn two_bone() -> (SkinnedMesh, Skeleton) {
        let skel = Skeleton {
            nodes: vec![
                Node {
                    name: "a".into(),
                    parent: None,
                    rest: Trs::IDENTITY,
                },
                Node {
                    name: "b".into(),
                    parent: Some(0),
                    rest: Trs {
                        translation: Vec3::Y,
                        ..Trs::IDENTITY
                    },
                },
            ],
            joints: vec![0, 1],
            inverse_bind: vec![Mat4::IDENTITY, Mat4::from_translation(-Vec3::Y)],
            root_transform: Affine3A::IDENTITY,
        };
        let mesh = SkinnedMesh {
            positions: vec![Vec3::new(0.2, 1.0, 0.0)],
            normals: vec![Vec3::X],
            uvs: vec![Vec2::ZERO],
            materials: vec![0],
            influence_offsets: vec![0, 2],
            influences: vec![
                Influence {
                    bone: 0,
                    weight: 0.5,
                },
                Influence {
                    bone: 1,
                    weight: 0.5,
                },
            ],
            indices: vec![],
        };
        (mesh, skel)
    }

    #[test]
    fn homogeneous_parts_sum_to_one() {
        let (mesh, skel) = two_bone();
        let am = AnimationSpaceMesh::from_skinned(&mesh, &skel);
        let w: f32 = am.influences_of(0).iter().map(|i| i.p.w).sum();
        assert!((w - 1.0).abs() < 1e-6);
    }

    #[test]
    fn rest_pose_reproduces_rest_positions() {
        let (mesh, skel) = two_bone();
        let am = AnimationSpaceMesh::from_skinned(&mesh, &skel);
        let g = crate::anim::bone_matrices(&skel, None, 0.0);
        let (p, n) = am.evaluate(&g);
        assert!((p[0] - mesh.positions[0]).length() < 1e-6);
        assert!((n[0] - Vec3::X).length() < 1e-6);
    }

    #[test]
    fn bent_pose_matches_linear_blend_skinning() {
        let (mesh, mut skel) = two_bone();
        skel.nodes[1].rest.rotation = Quat::from_rotation_z(1.0);
        let g = crate::anim::bone_matrices(&skel, None, 0.0);
        let am = AnimationSpaceMesh::from_skinned(&mesh, &skel);
        let (p, _) = am.evaluate(&g);
        let lbs = linear_blend_skinning(&mesh, &skel, &g);
        assert!((p[0] - lbs[0]).length() < 1e-6);
        // And the bend moved it: the test would pass vacuously otherwise.
        assert!((p[0] - mesh.positions[0]).length() > 0.01);
    }
}

#[cfg(test)]
mod order_tests {
    use super::*;

    #[test]
    fn gpu_order_keeps_every_triangle_and_its_vertices() {
        let m = crate::generate::generate("walker").unwrap();
        let am = AnimationSpaceMesh::from_skinned(&m.mesh, &m.skeleton);
        let opt = am.optimized_for_gpu();
        assert_eq!(opt.vertex_count(), am.vertex_count());
        assert_eq!(opt.triangle_count(), am.triangle_count());
        // The same set of triangles, each with the same corners (compared by their data).
        let key = |mesh: &AnimationSpaceMesh, t: &[u32]| {
            let mut corners: Vec<String> = t
                .iter()
                .map(|&v| {
                    format!(
                        "{:?}{:?}",
                        mesh.influences_of(v as usize),
                        mesh.uvs[v as usize]
                    )
                })
                .collect();
            let first = corners
                .iter()
                .enumerate()
                .min_by_key(|c| c.1.clone())
                .unwrap()
                .0;
            corners.rotate_left(first);
            corners.join("|")
        };
        let mut a: Vec<String> = am.indices.chunks(3).map(|t| key(&am, t)).collect();
        let mut b: Vec<String> = opt.indices.chunks(3).map(|t| key(&opt, t)).collect();
        a.sort();
        b.sort();
        assert!(a == b);
        // Vertices are numbered in order of first use.
        let mut next = 0;
        for &i in &opt.indices {
            assert!(i <= next);
            if i == next {
                next += 1;
            }
        }
    }
}

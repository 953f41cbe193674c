//! The vertex texture: the animation-space influences of every vertex, which the vertex shader
//! reads by `vertex_index` (Merry et al. §6.4 keep them in textures for the same reason: the
//! number of influences per vertex is not bounded by the vertex attribute slots).
//!
//! Layout, by linear texel index (see [`super::texels`]):
//! - texel `2v` for vertex `v`: `(first influence texel, count + 256 · material, u, v)`;
//! - texel `2v + 1`: `(geomorph target, spectral row + 1, normal-map layer + 1, occlusion or
//!   view window)`:
//!   the vertex (index into this texture) that `v` morphs into at the next coarser level
//!   (Houle & Poulin §5.1), itself on the coarsest level; the row of the spectra texture whose
//!   offset moves it, 0 for none (see [`crate::bake::gpu_data::spectra`]); the layer of the
//!   normal maps that lights it, 0 for none (see [`crate::bake::character::normal_map`]; on a billboard of
//!   a cloud, 1: lit through its atlas, whose lighting is the next material layer, see
//!   [`crate::bake::foliage::billboard::atlas`]); and the light the crown takes from it, 0 for none
//!   (see [`crate::bake::foliage::billboard::occlusion`]), or on a billboard (whose atlas carries the
//!   occlusion per texel) its view window, 0 for drawn from every view (see
//!   [`crate::bake::foliage::billboard::clumps`]);
//! - each influence two texels: `p_i` as `(x, y, z, w)`, then `(n_i.x, n_i.y, n_i.z, bone)`.
//!
//! Integers are stored as floats, exact up to 2^24 texels. The levels of detail of a model share
//! one texture: each level gets a base vertex, which the draw passes as `base_vertex` so that
//! `vertex_index` lands on its headers, and the geomorph targets of level k are vertices of level
//! k+1, so a morph over several levels follows the targets hop by hop.

use super::animation_space::{AnimationSpaceMesh, transform_homogeneous};
use super::texels::TexelGrid;
use glam::{Affine3A, Vec3, Vec4};
use serde::{Deserialize, Serialize};

/// A vertex for the trivial unskinned calibration shader: one fixed pose baked into plain
/// positions (see [`VertexTexture::static_vertices`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct StaticVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
}

/// Influence counts are packed below this; materials above.
pub const MATERIAL_STRIDE: u32 = 256;

/// Largest index a texel can address exactly in an `f32`.
const MAX_EXACT: usize = 1 << 24;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VertexTexture {
    pub grid: TexelGrid,
    /// Base vertex of each packed mesh.
    pub base_vertices: Vec<u32>,
    pub vertex_count: u32,
    pub influence_count: u32,
}

impl VertexTexture {
    /// Packs meshes one after another: all headers first, then all influences. `geomorphs[k]`,
    /// where given, maps every vertex of mesh k to a vertex of mesh k+1; a mesh without one
    /// morphs into itself. `normal_layers[k][m]`, where given, is the normal-map layer of mesh
    /// k's vertices of material m.
    pub fn pack(
        meshes: &[&AnimationSpaceMesh],
        geomorphs: &[&[u32]],
        normal_layers: &[Vec<Option<u32>>],
    ) -> Result<Self, String> {
        let vertex_count: usize = meshes.iter().map(|m| m.vertex_count()).sum();
        let influence_count: usize = meshes.iter().map(|m| m.influences.len()).sum();
        let total = 2 * vertex_count + 2 * influence_count;
        if total >= MAX_EXACT {
            return Err(format!(
                "too large for the vertex texture: {vertex_count} vertices, {influence_count} influences"
            ));
        }
        let mut base_vertices = Vec::with_capacity(meshes.len() + 1);
        let mut base = 0u32;
        for mesh in meshes {
            base_vertices.push(base);
            base += mesh.vertex_count() as u32;
        }
        base_vertices.push(base);
        let mut headers = Vec::with_capacity(2 * vertex_count);
        let mut body = Vec::with_capacity(2 * influence_count);
        for (k, mesh) in meshes.iter().enumerate() {
            let morph = geomorphs
                .get(k)
                .filter(|g| !g.is_empty() && k + 1 < meshes.len());
            if let Some(g) = morph {
                let next = meshes[k + 1].vertex_count() as u32;
                if g.len() != mesh.vertex_count() || g.iter().any(|&t| t >= next) {
                    return Err(format!(
                        "level {k}: geomorph map does not fit level {}",
                        k + 1
                    ));
                }
            }
            for v in 0..mesh.vertex_count() {
                let infs = mesh.influences_of(v);
                if infs.len() >= MATERIAL_STRIDE as usize {
                    return Err(format!(
                        "vertex {v} has {} influences (at most 255)",
                        infs.len()
                    ));
                }
                let first = 2 * vertex_count + body.len();
                let packed = infs.len() as u32 + MATERIAL_STRIDE * mesh.materials[v] as u32;
                let uv = mesh.uvs[v];
                headers.push([first as f32, packed as f32, uv.x, uv.y]);
                let target = match morph {
                    Some(g) => base_vertices[k + 1] + g[v],
                    None => base_vertices[k] + v as u32,
                };
                let row = match mesh.spectral_rows.get(v) {
                    Some(&r) if r != crate::bake::gpu_data::spectra::NO_ROW => r as f32 + 1.0,
                    _ => 0.0,
                };
                let layer = normal_layers
                    .get(k)
                    .and_then(|l| l.get(mesh.materials[v] as usize).copied().flatten())
                    .map_or(0.0, |l| l as f32 + 1.0);
                // A billboard's occlusion is in its atlas: the slot holds its view window.
                let window = mesh.view_windows.get(v).copied().unwrap_or(0.0);
                let occlusion = mesh.crown_occlusion.get(v).copied().unwrap_or(0.0);
                let last = if window != 0.0 { window } else { occlusion };
                headers.push([target as f32, row, layer, last]);
                for inf in infs {
                    body.push(inf.p.to_array());
                    body.push([inf.n.x, inf.n.y, inf.n.z, inf.bone as f32]);
                }
            }
        }
        headers.extend(body);
        base_vertices.pop();
        Ok(VertexTexture {
            grid: TexelGrid::from_linear(headers),
            base_vertices,
            vertex_count: vertex_count as u32,
            influence_count: influence_count as u32,
        })
    }

    /// Every vertex of every packed mesh posed by `pose` (one matrix per bone), read back from
    /// the texels: v = Σ G_i p_i and n = Σ G_i n_i, as `skin_vertex` in shaders/skinning.wgsl
    /// computes them, without spectral offsets. What the unskinned calibration draw reads from a
    /// vertex buffer, so that it draws exactly the triangles of whatever levels the skinned
    /// draw shows.
    pub fn static_vertices(&self, pose: &[Affine3A]) -> Vec<StaticVertex> {
        (0..self.vertex_count as usize)
            .map(|v| {
                let header = self.grid.get(2 * v);
                let first = header[0] as usize;
                let count = header[1] as u32 % MATERIAL_STRIDE;
                let (mut position, mut normal) = (Vec3::ZERO, Vec3::ZERO);
                for i in 0..count as usize {
                    let p = Vec4::from(self.grid.get(first + 2 * i));
                    let nb = self.grid.get(first + 2 * i + 1);
                    let g = pose
                        .get(nb[3] as usize)
                        .copied()
                        .unwrap_or(Affine3A::IDENTITY);
                    position += transform_homogeneous(&g, p);
                    normal += g.transform_vector3(Vec3::new(nb[0], nb[1], nb[2]));
                }
                StaticVertex {
                    position: position.to_array(),
                    normal: normal.normalize_or(Vec3::Y).to_array(),
                    uv: [header[2], header[3]],
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::gpu_data::animation_space::AsInfluence;
    use glam::{Vec2, Vec3, Vec4};

    #[test]
    fn headers_point_at_their_influences() {
        let mesh = AnimationSpaceMesh {
            offsets: vec![0, 1, 3],
            influences: vec![
                AsInfluence {
                    bone: 4,
                    p: Vec4::new(1.0, 2.0, 3.0, 1.0),
                    n: Vec3::X,
                },
                AsInfluence {
                    bone: 1,
                    p: Vec4::new(0.0, 1.0, 0.0, 0.25),
                    n: Vec3::Y,
                },
                AsInfluence {
                    bone: 2,
                    p: Vec4::new(0.0, 3.0, 0.0, 0.75),
                    n: Vec3::Z,
                },
            ],
            uvs: vec![Vec2::new(0.1, 0.2), Vec2::new(0.3, 0.4)],
            materials: vec![0, 3],
            indices: vec![],
            spectral_rows: vec![crate::bake::gpu_data::spectra::NO_ROW, 7],
            crown_occlusion: vec![0.0, 0.25],
            view_windows: Vec::new(),
        };
        let t = VertexTexture::pack(
            &[&mesh, &mesh],
            &[&[1, 1]],
            &[vec![], vec![None, None, None, Some(5)]],
        )
        .unwrap();
        assert_eq!(t.base_vertices, vec![0, 2]);
        // Level 0 morphs into vertex 1 of level 1; level 1, the coarsest, into itself.
        assert_eq!(t.grid.get(1)[0], 3.0);
        assert_eq!(t.grid.get(3)[0], 3.0);
        assert_eq!(t.grid.get(2 * 3 + 1)[0], 3.0);
        assert_eq!(t.grid.get(2 * 2 + 1)[0], 2.0);
        // Vertex 1 reads spectra row 7 (stored plus one); vertex 0 none.
        assert_eq!(t.grid.get(1)[1], 0.0);
        assert_eq!(t.grid.get(3)[1], 8.0);
        // Only level 1's vertex of material 3 has a normal-map layer (stored plus one).
        let layers: Vec<f32> = (0..4).map(|v| t.grid.get(2 * v + 1)[2]).collect();
        assert_eq!(layers, vec![0.0, 0.0, 0.0, 6.0]);
        let occlusion: Vec<f32> = (0..4).map(|v| t.grid.get(2 * v + 1)[3]).collect();
        assert_eq!(occlusion, vec![0.0, 0.25, 0.0, 0.25]);
        // A billboard's view window takes the slot where it has one (its atlas carries its
        // occlusion).
        let windowed = AnimationSpaceMesh {
            view_windows: vec![-0.4, 0.0],
            ..mesh.clone()
        };
        let t2 = VertexTexture::pack(&[&windowed], &[], &[]).unwrap();
        assert_eq!(t2.grid.get(1)[3], -0.4);
        assert_eq!(t2.grid.get(3)[3], 0.25);
        // A map that does not fit the next level is refused.
        assert!(VertexTexture::pack(&[&mesh, &mesh], &[&[0, 2]], &[]).is_err());
        let h = t.grid.get(2 * 3);
        assert_eq!(h[1] as u32 % MATERIAL_STRIDE, 2);
        assert_eq!(h[1] as u32 / MATERIAL_STRIDE, 3);
        assert_eq!([h[2], h[3]], [0.3, 0.4]);
        let first = h[0] as usize;
        assert_eq!(t.grid.get(first), [0.0, 1.0, 0.0, 0.25]);
        assert_eq!(t.grid.get(first + 1)[3], 1.0);
        assert_eq!(t.grid.get(first + 3)[3], 2.0);

        // Read back and posed, every packed vertex is where the mesh itself puts it.
        let pose: Vec<Affine3A> = (0..5)
            .map(|b| {
                Affine3A::from_rotation_translation(
                    glam::Quat::from_rotation_y(0.3 * b as f32),
                    Vec3::new(b as f32, 0.5, -1.0),
                )
            })
            .collect();
        let (positions, normals) = mesh.evaluate(&pose);
        let posed = t.static_vertices(&pose);
        assert_eq!(posed.len(), 4);
        for (k, v) in posed.iter().enumerate() {
            let i = k % 2;
            assert!(Vec3::from(v.position).distance(positions[i]) < 1e-5);
            assert!(Vec3::from(v.normal).distance(normals[i].normalize()) < 1e-5);
            assert_eq!(v.uv, mesh.uvs[i].to_array());
        }
    }
}

//! A model's levels of detail by one method, packed for the GPU: one vertex texture holding every
//! level with its geomorph map (see [`super::vertex_texture`]) and one index buffer holding every
//! level's triangles. The renderer uploads this once; drawing level k is then a range of the index
//! buffer with k's base vertex, and morphing k towards k+h follows h geomorph hops in the vertex
//! shader (Merry et al. §6.4, Houle & Poulin §5.1). Switching level, method or tolerance at run
//! time therefore allocates nothing. A pack may carry normal maps for its coarse levels (see
//! [`crate::bake::character::normal_map`]), which the vertex texture points each vertex at.

use super::animation_space::AnimationSpaceMesh;
use super::vertex_texture::VertexTexture;
use crate::bake::character::lod::LodLevel;
use crate::bake::character::normal_map::NormalMaps;
use crate::bake::gpu_data::drawable::Drawable;

/// Where one level lives in a [`LodPack`] and what drawing it costs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PackedLevel {
    pub first_index: u32,
    pub index_count: u32,
    pub base_vertex: u32,
    pub vertices: u32,
    pub influences: u32,
    /// The level's error bound in scene units (0 for full detail).
    pub error: f32,
    /// Some of its vertices are lit through a normal map.
    pub normal_mapped: bool,
    /// A character's triangles of cut-out materials (hair cards, feathers, lace) are the last
    /// `cut_indices` of its range: the renderer draws them two-sided and alpha-tested, the
    /// rest culled and opaque. 0 for foliage and impostors, whose own shaders cut out.
    pub cut_indices: u32,
}

impl PackedLevel {
    pub fn triangles(&self) -> u32 {
        self.index_count / 3
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct LodPack {
    pub vertices: VertexTexture,
    /// Every level's triangles, level after level, indices local to the level.
    pub indices: Vec<u32>,
    /// Finest first.
    pub levels: Vec<PackedLevel>,
    /// The coarse levels' normal maps, where baked.
    pub normal_maps: Option<NormalMaps>,
    /// A clump level's triangles by view sector (see [`super::view_subsets`]): each sector's
    /// range (first index, count) in `indices`, after the level's own; empty for everything
    /// else.
    pub view_subsets: Vec<[u32; 2]>,
    /// How far (radians, horizontally) its planes' normals turn from rest over its clip at
    /// wind strength 1 ([`super::view_subsets::sway`]), and the margin they were filed into
    /// sectors with ([`super::view_subsets::margin`]): where an instance's wind turns them
    /// past the margin, the sectors do not hold and it is drawn whole.
    pub view_subset_sway: f32,
    pub view_subset_margin: f32,
}

impl LodPack {
    /// The levels of a bake, each linked to the next by its geomorph map.
    /// The levels of a bake of a model whose materials all are opaque, each linked to the
    /// next by its geomorph map.
    pub fn from_levels(levels: &[LodLevel]) -> Result<LodPack, String> {
        let meshes: Vec<&AnimationSpaceMesh> = levels.iter().map(|l| &l.mesh).collect();
        let maps: Vec<&[u32]> = levels.iter().map(|l| l.geomorph.as_slice()).collect();
        let vertices = VertexTexture::pack(&meshes, &maps, &[])?;
        let errors: Vec<f32> = levels.iter().map(|l| l.error).collect();
        Ok(Self::assemble(vertices, &meshes, &errors, None, &[]))
    }

    /// [`Self::from_levels`] for a model of `materials`, with normal maps `size` texels square
    /// for every level but full detail, baked against `full` (the full-detail mesh, whose
    /// vertices the levels keep) posed by `rest_bones`.
    pub fn with_normal_maps(
        levels: &[LodLevel],
        full: &AnimationSpaceMesh,
        rest_bones: &[glam::Affine3A],
        materials: &[crate::model::Material],
        size: u32,
    ) -> Result<LodPack, String> {
        let meshes: Vec<&AnimationSpaceMesh> = levels.iter().map(|l| &l.mesh).collect();
        let mapped: Vec<Option<&AnimationSpaceMesh>> = levels
            .iter()
            .map(|l| (l.prefix > 0).then_some(&l.mesh))
            .collect();
        let normal_maps = crate::bake::character::normal_map::bake(
            full,
            &mapped,
            rest_bones,
            materials.len().max(1),
            size,
        );
        let maps: Vec<&[u32]> = levels.iter().map(|l| l.geomorph.as_slice()).collect();
        let vertices = VertexTexture::pack(&meshes, &maps, &normal_maps.layers)?;
        let errors: Vec<f32> = levels.iter().map(|l| l.error).collect();
        let cut_out: Vec<bool> = materials.iter().map(|m| m.cuts_out()).collect();
        Ok(Self::assemble(
            vertices,
            &meshes,
            &errors,
            Some(normal_maps),
            &cut_out,
        ))
    }

    /// The full-detail mesh of a character as a pack of one level (the `none` method). A
    /// clump level's also holds its triangles by view sector ([`super::view_subsets`]).
    pub fn full_detail(bake: &Drawable) -> LodPack {
        // Only a mesh draws its cut-out triangles apart; foliage's own shaders cut out.
        let cut_out: &[bool] = match bake.kind {
            super::drawable::DrawKind::Mesh => &bake.materials.cut_out,
            _ => &[],
        };
        let mut pack = Self::assemble(
            bake.vertices.clone(),
            &[&bake.animation_space],
            &[0.0],
            None,
            cut_out,
        );
        let am = &bake.animation_space;
        if !am.view_windows.is_empty() {
            let (_, normals) = bake.evaluate(0, 0.0, 0.0);
            let sway = super::view_subsets::sway(bake, &normals);
            let margin = super::view_subsets::margin(sway);
            if let Some((subsets, ranges)) =
                super::view_subsets::view_subsets(&am.indices, &am.view_windows, &normals, margin)
            {
                let base = pack.indices.len() as u32;
                pack.indices.extend_from_slice(&subsets);
                pack.view_subsets = ranges.iter().map(|&[f, c]| [base + f, c]).collect();
                pack.view_subset_sway = sway;
                pack.view_subset_margin = margin;
            }
        }
        pack
    }

    /// The pack of `meshes`, each level's triangles of materials `cut_out` moved to the end
    /// of its range, in their order (see [`PackedLevel::cut_indices`]).
    fn assemble(
        vertices: VertexTexture,
        meshes: &[&AnimationSpaceMesh],
        errors: &[f32],
        normal_maps: Option<NormalMaps>,
        cut_out: &[bool],
    ) -> LodPack {
        let mut indices = Vec::with_capacity(meshes.iter().map(|m| m.indices.len()).sum());
        let mut levels = Vec::with_capacity(meshes.len());
        for (k, m) in meshes.iter().enumerate() {
            let is_cut = |t: &&[u32]| {
                let material = m.materials.get(t[0] as usize).copied().unwrap_or(0);
                cut_out.get(material as usize).copied().unwrap_or(false)
            };
            let (cut, solid): (Vec<&[u32]>, Vec<&[u32]>) =
                m.indices.chunks_exact(3).partition(is_cut);
            levels.push(PackedLevel {
                first_index: indices.len() as u32,
                index_count: m.indices.len() as u32,
                base_vertex: vertices.base_vertices[k],
                vertices: m.vertex_count() as u32,
                influences: m.influences.len() as u32,
                error: errors[k],
                normal_mapped: normal_maps.as_ref().is_some_and(|n| n.maps_level(k)),
                cut_indices: 3 * cut.len() as u32,
            });
            indices.extend(solid.into_iter().chain(cut).flatten());
        }
        LodPack {
            vertices,
            indices,
            levels,
            normal_maps,
            view_subsets: Vec::new(),
            view_subset_sway: 0.0,
            view_subset_margin: 0.0,
        }
    }

    /// The error bound of every level, finest first.
    pub fn errors(&self) -> Vec<f32> {
        self.levels.iter().map(|l| l.error).collect()
    }
}

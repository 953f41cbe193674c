//! Bake: pure CPU code that turns an imported [`Model`] into the plain data the renderer uploads.
//!
//! Nothing here touches the GPU; everything is testable headless. The renderer sees only the
//! public fields of [`CharacterBake`].

pub mod anim_texture;
pub mod animation_space;
pub mod billboard;
pub mod cache;
pub mod lod;
pub mod lod_error;
pub mod lod_pack;
pub mod materials;
pub mod simplify;
pub mod spectral;
pub mod texels;
pub mod vertex_texture;

use crate::model::{Bounds, Model};
use anim_texture::AnimationTexture;
use animation_space::AnimationSpaceMesh;
use glam::{Vec2, Vec3};
use materials::MaterialLayers;
use vertex_texture::VertexTexture;

/// A vertex for the trivial unskinned calibration shader: the first frame of the first clip,
/// baked into plain positions.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct StaticVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
}

/// Everything the renderer needs to draw one skinned character.
#[derive(Clone, Debug)]
pub struct CharacterBake {
    pub name: String,
    pub animation: AnimationTexture,
    pub vertices: VertexTexture,
    pub indices: Vec<u32>,
    pub materials: MaterialLayers,
    /// The same triangles as plain vertices, for the unskinned calibration draw.
    pub static_vertices: Vec<StaticVertex>,
    /// Bounds over the sampled frames of every clip, in scene units, model-local.
    pub bounds: Bounds,
    pub animation_space: AnimationSpaceMesh,
    /// Some material has cut-out alpha (foliage): drawn two-sided and alpha-tested.
    pub alpha_tested: bool,
}

impl CharacterBake {
    pub fn new(model: &Model) -> Result<Self, String> {
        let am = AnimationSpaceMesh::from_skinned(&model.mesh, &model.skeleton).optimized_for_gpu();
        let animation = AnimationTexture::bake(model, anim_texture::DEFAULT_RATE);
        let vertices = VertexTexture::pack(&[&am], &[])?;
        let materials = MaterialLayers::bake(&model.materials);

        let (pos, nrm) = am.evaluate(&animation.sample(0, 0.0));
        let static_vertices = pos
            .iter()
            .zip(&nrm)
            .zip(&am.uvs)
            .map(|((p, n), uv): ((&Vec3, &Vec3), &Vec2)| StaticVertex {
                position: p.to_array(),
                normal: n.normalize_or(Vec3::Y).to_array(),
                uv: uv.to_array(),
            })
            .collect();

        // Bounds over a few frames of every clip: enough for framing, shadows and culling.
        let mut points = Vec::new();
        for (c, clip) in animation.clips.iter().enumerate() {
            let steps = 8.min(clip.frame_count);
            for k in 0..steps {
                let t = clip.duration * k as f32 / steps as f32;
                let (p, _) = am.evaluate(&animation.sample(c, t));
                points.extend(p);
            }
        }
        let bounds = Bounds::of(points).ok_or("model has no vertices")?;

        Ok(CharacterBake {
            name: model.name.clone(),
            animation,
            vertices,
            indices: am.indices.clone(),
            materials,
            static_vertices,
            bounds,
            alpha_tested: model.materials.iter().any(|m| {
                m.base_color[3] < 0.5
                    || m.texture
                        .as_ref()
                        .is_some_and(|t| t.pixels.chunks_exact(4).any(|px| px[3] < 128))
            }),
            animation_space: am,
        })
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    pub fn clip_names(&self) -> Vec<String> {
        self.animation
            .clips
            .iter()
            .map(|c| c.name.clone())
            .collect()
    }
}

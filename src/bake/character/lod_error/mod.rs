//! Measuring how far a simplified character is from the original, over its whole animation
//! (the error of Merry et al. §6.1, Figure 7).
//!
//! Two correspondences between the original surface and a simplified one:
//! - [`ErrorProbe`], through the parameterisation, as in appearance-preserving simplification:
//!   a point of the original surface at texture coordinate `u` in chart `c` is compared with
//!   the point of the simplified mesh at the same `u` in the same chart. It needs texture
//!   coordinates that are a parameterisation.
//! - [`SurfaceProbe`], geometric: every sample point corresponds to the closest point of the
//!   other surface in the rest pose, both ways (original to simplified, which sees holes and
//!   shrinkage, and simplified to original, which sees spikes and slivers: a two-sided,
//!   sampled Hausdorff distance), and the two points are then compared in every frame. It
//!   needs nothing but the surfaces, and it is what a silhouette shows.
//!
//! Points are drawn area-weighted. The RMS over all frames of a difference `s` in animation
//! space is `sqrt(sᵀ P s)` with `P` estimated from exactly those frames, so the RMS error over
//! samples and frames is `sqrt(mean_samples(sᵀ P s))`. The maximum is over samples and frames.

mod geometry;
mod surface;
mod texture;

pub(crate) use geometry::Surface;
pub use surface::SurfaceProbe;
pub use texture::ErrorProbe;

use crate::anim::bone_matrices;
use crate::bake::gpu_data::anim_texture::DEFAULT_RATE;
use crate::bake::gpu_data::animation_space::{AnimationSpaceMesh, AsInfluence};
use crate::model::Model;
use glam::Affine3A;
use serde::Serialize;

/// The error of one simplified mesh, in scene units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MeshError {
    pub rms: f64,
    pub max: f64,
}

/// How the points of two surfaces are made to correspond when measuring.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Correspondence {
    /// Same texture coordinate in the same chart (appearance-preserving).
    Texture,
    /// Closest point in the rest pose, both ways.
    ClosestPoint,
}

impl Correspondence {
    pub fn describe(self) -> &'static str {
        match self {
            Correspondence::Texture => "texture coordinates (the same point of the same chart)",
            Correspondence::ClosestPoint => "closest point in the rest pose, both ways",
        }
    }
}

/// The measurement a report uses: through the texture where the model's texture coordinates
/// are a parameterisation, else geometric.
pub enum Probe<'a> {
    Texture(ErrorProbe),
    ClosestPoint(Box<SurfaceProbe<'a>>),
}

impl<'a> Probe<'a> {
    /// The texture correspondence if at least 99% of the rest-pose surface has texture area,
    /// else the closest-point one; `count` samples, frames at the animation texture's rate.
    pub fn for_model(model: &Model, base: &'a AnimationSpaceMesh, count: usize) -> Probe<'a> {
        if texture_coverage(model, base) >= 0.99
            && let Ok(p) = ErrorProbe::new(model, base, count)
        {
            return Probe::Texture(p);
        }
        Probe::ClosestPoint(Box::new(SurfaceProbe::new(
            model,
            base,
            count / 2,
            count / 2,
            animation_frames(model),
        )))
    }

    pub fn correspondence(&self) -> Correspondence {
        match self {
            Probe::Texture(_) => Correspondence::Texture,
            Probe::ClosestPoint(_) => Correspondence::ClosestPoint,
        }
    }

    pub fn frame_count(&self) -> usize {
        match self {
            Probe::Texture(p) => p.frame_count(),
            Probe::ClosestPoint(p) => p.frame_count(),
        }
    }

    pub fn measure<'b>(
        &self,
        triangles: &[[u32; 3]],
        influences: impl Fn(u32) -> &'b [AsInfluence] + Sync,
    ) -> MeshError {
        match self {
            Probe::Texture(p) => p.measure(triangles, influences),
            Probe::ClosestPoint(p) => p.measure(triangles, influences, None, 0.0),
        }
    }
}

/// The share of the rest-pose surface of `base` on triangles with texture area.
pub fn texture_coverage(model: &Model, base: &AnimationSpaceMesh) -> f64 {
    let rest_bones = super::simplify::SimplifyInput::rest_bones(&model.skeleton);
    let rest = base.rest_positions(&rest_bones);
    let (mut with, mut total) = (0.0f64, 0.0f64);
    for t in base.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|v| v as usize);
        let area = 0.5 * (rest[b] - rest[a]).cross(rest[c] - rest[a]).length() as f64;
        total += area;
        let uv_area = (base.uvs[b] - base.uvs[a]).perp_dot(base.uvs[c] - base.uvs[a]);
        if uv_area.abs() > 1e-12 {
            with += area;
        }
    }
    if total > 0.0 { with / total } else { 0.0 }
}

/// At most this many frames are measured over, spread over the clips by their length.
pub const MAX_FRAMES: usize = 96;

/// Every clip's frames at the animation texture's rate, or [`MAX_FRAMES`] spread over them by
/// their length where there would be more (the rest pose for a model without clips): the poses
/// a report measures over. Every frame of a character sent with a few long clips (ten seconds
/// of walking, an idle, a run) is thousands of poses, and the probes hold every sample in
/// every pose: a 61,000-triangle report took ten minutes and 2.4 GB for an RMS a hundred
/// frames estimate as well.
pub fn animation_frames(model: &Model) -> Vec<Vec<Affine3A>> {
    let all: usize = model
        .clips
        .iter()
        .map(|c| (c.duration * DEFAULT_RATE).round().max(1.0) as usize)
        .sum();
    let total: f32 = model.clips.iter().map(|c| c.duration.max(0.0)).sum();
    let mut frames = Vec::new();
    for clip in &model.clips {
        let own = (clip.duration * DEFAULT_RATE).round().max(1.0) as usize;
        let count = if all <= MAX_FRAMES || total <= 0.0 {
            own
        } else {
            ((MAX_FRAMES as f32 * clip.duration.max(0.0) / total).round() as usize).clamp(1, own)
        };
        for f in 0..count {
            frames.push(bone_matrices(
                &model.skeleton,
                Some(clip),
                clip.duration * f as f32 / count as f32,
            ));
        }
    }
    if frames.is_empty() {
        frames.push(bone_matrices(&model.skeleton, None, 0.0));
    }
    frames
}

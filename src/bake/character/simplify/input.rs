//! What the simplifier is asked: the method (Merry et al.'s three rankings), the character in
//! animation space, its expectation matrix and the poses no collapse may fold a triangle in.

use super::expectation::ExpectationMatrix;
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use glam::Affine3A;
use serde::{Deserialize, Serialize};

crate::choice! {
    /// How a character's levels are made: the three ways of ranking simplifications the paper
    /// compares, and meshoptimizer, what engines ship today, to compare them against.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
    pub enum Method {
        /// Edge collapses ranked by Euclidean deviation in the rest pose ("3D" in Table 1).
        #[serde(rename = "rest-pose")]
        RestPose => "rest-pose",
        /// Edge collapses ranked by the L2,2 deviation in animation space (§4).
        #[serde(rename = "as")]
        AnimationSpace => "as",
        /// As `AnimationSpace`, with influence simplifications in the same queue (§5).
        #[serde(rename = "as+is")]
        InfluenceSimplification => "as+is",
        /// meshoptimizer's attribute-aware simplifier on the rest pose, as gltfpack runs it,
        /// at the same error targets (`bake::character::lod::meshopt`).
        #[serde(rename = "meshopt")]
        Meshopt => "meshopt",
    }
}

impl Method {
    /// The paper's three methods: those that make a collapse sequence.
    pub const PAPERS: [Method; 3] = [
        Method::RestPose,
        Method::AnimationSpace,
        Method::InfluenceSimplification,
    ];
}

/// What the simplifier needs to know about a character.
pub struct SimplifyInput<'a> {
    pub mesh: &'a AnimationSpaceMesh,
    /// The rest-pose bone matrices `Ĝ_i` in scene space (the root transform applied), so the
    /// rest-pose metric measures in the same units as the L2,2 one.
    pub rest_bones: &'a [Affine3A],
    pub expectation: &'a ExpectationMatrix,
    /// Bone matrices of sampled poses (scene space): no collapse may turn a triangle over in
    /// any of them. See [`pose_samples`].
    pub poses: &'a [Vec<Affine3A>],
    /// Per material (as [`AnimationSpaceMesh::materials`] numbers them): it has a texture,
    /// so its texture coordinates say what colour a point shows. A texture sliding over the
    /// surface costs what it moves, and two wedges of one position that differ in material,
    /// or in texture coordinate on a textured one, show different colours: a chart torn
    /// between them costs the triangles it recolours (see [`collapse`](super::collapse)). A material missing
    /// here counts as untextured.
    pub textured: &'a [bool],
}

impl SimplifyInput<'_> {
    /// `Ĝ_i` for every bone of `skeleton`, in scene space.
    pub fn rest_bones(skeleton: &crate::model::Skeleton) -> Vec<Affine3A> {
        skeleton
            .inverse_bind
            .iter()
            .map(|inv| skeleton.root_transform * Affine3A::from_mat4(inv.inverse()))
            .collect()
    }
}

/// Poses sampled evenly over every clip of `model` (at least one, the rest pose for a model
/// without clips), `count` in all, in scene space: what the simplifier checks orientation in
/// and the level error is measured over.
pub fn pose_samples(model: &crate::model::Model, count: usize) -> Vec<Vec<Affine3A>> {
    let skel = &model.skeleton;
    if model.clips.is_empty() {
        return vec![crate::anim::bone_matrices(skel, None, 0.0)];
    }
    let per_clip = count.div_ceil(model.clips.len()).max(1);
    model
        .clips
        .iter()
        .flat_map(|clip| {
            (0..per_clip).map(move |k| {
                let t = clip.duration.max(0.0) * (k as f32 + 0.5) / per_clip as f32;
                crate::anim::bone_matrices(skel, Some(clip), t)
            })
        })
        .collect()
}

//! Which models are trees. A tree's levels are billboard clouds (the Aalborg thesis); every
//! other model is a character, simplified by the progressive meshes of Merry et al. Both may
//! have materials that cut their shape out with alpha: leaves, but also a character's hair
//! cards, feathers, fur or lace. What tells them apart is how much of the surface is cut out
//! and how the model moves: foliage is mostly cards and sways in place (a wind rig, or no
//! animation at all); a character's clips swing its limbs, flap its wings or carry it along.
//!
//! Measured with this module's own measures on the project's models: the built-in and card
//! trees have 82–99% of their area cut out, and their wind moves the 95th-percentile vertex
//! 5–8% of their size (the card trees have no clips); the characters' clips move it 33–40%
//! (walker, horse, robot, knight, the Khronos fox). A skinned bird whose every material
//! blends is all cut out, but its flight moves it as a character's clips do.

use crate::model::{Material, Model};
use glam::Vec3;

/// Below this share of its surface cut out, a model is a character whatever its motion: its
/// cut-out parts are details (hair, lashes, a cape's lace) of an opaque body.
pub const FOLIAGE_AREA_SHARE: f32 = 0.5;

/// From this motion on (the 95th-percentile vertex's farthest move from its clip's first
/// pose, as a share of the model's largest extent) a model moves as a character does. Wind
/// sways trees by under a tenth of their size; a walk, a wave or a wingbeat moves most of a
/// character by a third of its size or more.
pub const CHARACTER_MOTION: f32 = 0.15;

/// The vertices the motion is measured on, at most: evenly spread over the mesh, enough for a
/// 95th percentile, few enough that classifying costs well under a millisecond.
const MOTION_SAMPLES: usize = 512;
/// The poses of a clip measured against its first, evenly spread over its length.
const MOTION_POSES: usize = 8;

/// Is this model a tree: has it foliage cut out with alpha, covering most of its surface, that
/// moves as foliage does (see the module's notes)? Trees get billboard-cloud chains;
/// everything else is a character, its cut-out parts drawn alpha-tested with its surface.
pub fn is_tree(model: &Model) -> bool {
    let cut_out: Vec<bool> = model.materials.iter().map(Material::cuts_out).collect();
    cut_out.contains(&true)
        && cut_out_share(model, &cut_out) >= FOLIAGE_AREA_SHARE
        && clip_motion(model) < CHARACTER_MOTION
}

/// The share of the bind pose's surface area whose material cuts out (`cut_out`, by material).
pub fn cut_out_share(model: &Model, cut_out: &[bool]) -> f32 {
    let mesh = &model.mesh;
    let (mut cut, mut all) = (0.0f64, 0.0f64);
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
        let area = f64::from((b - a).cross(c - a).length());
        if !area.is_finite() {
            continue;
        }
        all += area;
        let material = mesh.materials[t[0] as usize] as usize;
        if cut_out.get(material).copied().unwrap_or(false) {
            cut += area;
        }
    }
    if all > 0.0 { (cut / all) as f32 } else { 0.0 }
}

/// How far the model's clips move it: over every clip, the farthest the 95th-percentile
/// vertex (of up to [`MOTION_SAMPLES`]) gets from its place in the clip's first pose, as a
/// share of the bind pose's largest extent. 0 for a model without clips. Stops at the first
/// clip that reaches [`CHARACTER_MOTION`].
pub fn clip_motion(model: &Model) -> f32 {
    let mesh = &model.mesh;
    let n = mesh.vertex_count();
    if n == 0 || model.clips.is_empty() {
        return 0.0;
    }
    let size = crate::model::Bounds::of(mesh.positions.iter().copied())
        .map_or(0.0, |b| b.size().max_element());
    if !size.is_finite() || size <= 0.0 {
        return 0.0;
    }
    let step = n.div_ceil(MOTION_SAMPLES);
    let sampled: Vec<usize> = (0..n).step_by(step).collect();
    let skinning = |clip, t| -> Vec<Vec3> {
        let g = crate::anim::bone_matrices(&model.skeleton, Some(clip), t);
        let skin: Vec<glam::Affine3A> = g
            .iter()
            .zip(&model.skeleton.inverse_bind)
            .map(|(g, inv)| *g * glam::Affine3A::from_mat4(*inv))
            .collect();
        sampled
            .iter()
            .map(|&v| {
                mesh.influences_of(v)
                    .iter()
                    .filter_map(|i| skin.get(i.bone as usize).map(|m| (i.weight, m)))
                    .map(|(w, m)| w * m.transform_point3(mesh.positions[v]))
                    .sum()
            })
            .collect()
    };
    let mut most = 0.0f32;
    for clip in &model.clips {
        let first = skinning(clip, 0.0);
        for k in 1..=MOTION_POSES {
            let posed = skinning(clip, clip.duration * k as f32 / MOTION_POSES as f32);
            let mut moved: Vec<f32> = posed
                .iter()
                .zip(&first)
                .map(|(a, b)| a.distance(*b))
                .filter(|d| d.is_finite())
                .collect();
            if moved.is_empty() {
                continue;
            }
            let rank = (moved.len() * 95 / 100).min(moved.len() - 1);
            let (_, p95, _) = moved.select_nth_unstable_by(rank, f32::total_cmp);
            most = most.max(*p95 / size);
        }
        if most >= CHARACTER_MOTION {
            break;
        }
    }
    most
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_trees_are_trees_and_the_characters_are_not() {
        for name in ["broadleaf", "conifer", "sapling", "card-palm", "card-bush"] {
            let m = crate::import::load_model(name).unwrap();
            assert!(is_tree(&m), "{name}");
            assert!(clip_motion(&m) < 0.1, "{name}: {}", clip_motion(&m));
        }
        for name in ["walker", "horse", "robot"] {
            let m = crate::import::load_model(name).unwrap();
            assert!(!is_tree(&m), "{name}");
            assert!(clip_motion(&m) >= CHARACTER_MOTION, "{name}");
        }
    }

    /// A walker whose every material is cut out (feathers, say): it moves as a character, so
    /// it stays one; held still (no clips), it is all cards and taken for foliage. With only
    /// a small cut-out part a model is a character even still.
    #[test]
    fn a_cut_out_character_stays_a_character() {
        let walker = crate::import::load_model("walker").unwrap();
        let mut feathered = walker.clone();
        for m in &mut feathered.materials {
            m.alpha_mode = crate::model::AlphaMode::Blend;
            m.base_color[3] = 0.4;
        }
        let all: Vec<bool> = feathered.materials.iter().map(|m| m.cuts_out()).collect();
        assert!((cut_out_share(&feathered, &all) - 1.0).abs() < 1e-6);
        assert!(!is_tree(&feathered));
        let still = Model {
            clips: Vec::new(),
            ..feathered.clone()
        };
        assert!(is_tree(&still));

        // A few feathers on a still robot: a small cut-out part of an opaque body.
        let mut one_part = crate::generate::wild::feathers::feathered(
            &crate::import::load_model("robot").unwrap(),
            20,
        );
        let flags: Vec<bool> = one_part.materials.iter().map(|m| m.cuts_out()).collect();
        let share = cut_out_share(&one_part, &flags);
        assert!(share > 0.0 && share < FOLIAGE_AREA_SHARE, "{share}");
        one_part.clips.clear();
        assert!(!is_tree(&one_part));
    }
}

//! Root motion: clips that carry a character away from where it stands (a flight that climbs
//! and swoops, a leap, a walk exported with its travel). The union of every pose of every
//! clip is then far larger than the character: drawn from it, the character's sphere, its
//! blob shadow, its size on screen and the framing of a shot all take the size of the whole
//! flight. Here each pose is put back where the rest pose stands, by the offset of its centre
//! (the *travel*), so that the bounds are the body's; the travel, kept per frame of each clip,
//! says where the body is at any moment, and the world moves the sphere, shadow and
//! screen-size measure of each instance with it.

use super::anim_texture::{AnimationTexture, frame_time};
use super::animation_space::{AnimationSpaceMesh, transform_homogeneous};
use crate::model::Bounds;
use glam::Vec3;

/// Vertices the travel is measured on, at most (evenly spread over the mesh): a centre needs
/// few, and every frame of every clip is measured.
const TRAVEL_SAMPLES: usize = 512;

/// Clips count as carrying the character where the union of their poses is this much larger
/// (by diagonal) than the body's bounds: below it, the travel is limbs swinging about a
/// character that stays put, and the union stays, as it always was.
const ROOT_MOTION_GROWTH: f32 = 1.25;

/// Poses of each clip the bounds are taken over (evenly spread, the start included).
const BOUND_POSES: u32 = 8;

/// The bounds of `am` animated by `animation`, and, where its clips carry it (see
/// [`ROOT_MOTION_GROWTH`]), the travel of each clip at each of its frames (else empty). With
/// travel, the bounds are the body's: each pose moved back by its travel. None for a mesh
/// without vertices.
pub fn bounds_and_travel(
    am: &AnimationSpaceMesh,
    animation: &AnimationTexture,
) -> Option<(Bounds, Vec<Vec<Vec3>>)> {
    let n = am.vertex_count();
    let sampled: Vec<usize> = (0..n).step_by(n.div_ceil(TRAVEL_SAMPLES).max(1)).collect();
    let centre = |g: &[glam::Affine3A]| {
        let points = sampled.iter().map(|&v| {
            am.influences_of(v)
                .iter()
                .map(|i| transform_homogeneous(&g[i.bone as usize], i.p))
                .sum::<Vec3>()
        });
        Bounds::of(points).map_or(Vec3::ZERO, |b| b.center())
    };
    let rest = centre(&animation.sample(0, 0.0));
    let travel: Vec<Vec<Vec3>> = (0..animation.clips.len())
        .map(|c| {
            let clip = &animation.clips[c];
            (0..clip.frame_count)
                .map(|f| {
                    let t = frame_time(clip.duration, clip.frame_count, f);
                    centre(&animation.sample(c, t)) - rest
                })
                .collect()
        })
        .collect();
    let mut union: Vec<Vec3> = Vec::new();
    let mut body: Vec<Vec3> = Vec::new();
    for (c, clip) in animation.clips.iter().enumerate() {
        let steps = BOUND_POSES.min(clip.frame_count);
        for k in 0..steps {
            let t = clip.duration * k as f32 / steps as f32;
            let (p, _) = am.evaluate(&animation.sample(c, t));
            let moved = travel_at(&travel, c, clip.frame_count, clip.duration, t);
            body.extend(p.iter().map(|&q| q - moved));
            union.extend(p);
        }
    }
    let union = Bounds::of(union)?;
    let body = Bounds::of(body)?;
    if union.diagonal() > ROOT_MOTION_GROWTH * body.diagonal() {
        Some((body, travel))
    } else {
        Some((union, Vec::new()))
    }
}

/// [`travel_at`] for a time within the clip, `duration` itself its last frame (a page or a
/// frame of a bake at the clip's end), not its first again as the looping playback has it.
pub fn travel_within(
    travel: &[Vec<Vec3>],
    clip: usize,
    frame_count: u32,
    duration: f32,
    time: f32,
) -> Vec3 {
    let Some(frames) = travel.get(clip).filter(|f| !f.is_empty()) else {
        return Vec3::ZERO;
    };
    if frame_count <= 1 || duration.is_nan() || duration <= 0.0 {
        return frames[0];
    }
    let f = (time / duration).clamp(0.0, 1.0) * (frame_count - 1) as f32;
    let f0 = (f.floor() as usize).min(frames.len() - 1);
    let f1 = (f0 + 1).min(frames.len() - 1);
    frames[f0].lerp(frames[f1], f - f0 as f32)
}

/// Where the body is `time` seconds into clip `clip` (of `frame_count` frames over
/// `duration`, looped as the shader loops it), against the rest pose: the travel of the
/// frames round that time, blended as the shader blends their poses. Zero without travel.
pub fn travel_at(
    travel: &[Vec<Vec3>],
    clip: usize,
    frame_count: u32,
    duration: f32,
    time: f32,
) -> Vec3 {
    // Looped as `frame_pair` loops the clip: its length is its start again.
    let u = time / duration;
    let looped = if duration > 0.0 {
        duration * (u - u.floor())
    } else {
        time
    };
    travel_within(travel, clip, frame_count, duration, looped)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A clip that ends elsewhere than it starts (a leap): the playback loops back to the
    /// start at its length, a bake's last page is at its end.
    #[test]
    fn a_clips_end_is_its_last_frame_within_and_its_first_looped() {
        let travel = vec![vec![Vec3::ZERO, Vec3::X, 2.0 * Vec3::X]];
        assert_eq!(travel_within(&travel, 0, 3, 1.0, 1.0), 2.0 * Vec3::X);
        assert_eq!(travel_at(&travel, 0, 3, 1.0, 1.0), Vec3::ZERO);
        assert_eq!(travel_within(&travel, 0, 3, 1.0, 0.75), 1.5 * Vec3::X);
        assert_eq!(travel_at(&travel, 0, 3, 1.0, 0.75), 1.5 * Vec3::X);
        assert_eq!(travel_within(&travel, 1, 3, 1.0, 0.5), Vec3::ZERO);
    }
}

//! Evaluating clips: keyframe interpolation (glTF 2.0 Appendix C), local poses and the bone
//! matrices `G_i` of Merry et al. §2.1.1.

use crate::model::{Channel, ChannelTarget, Clip, Interpolation, Skeleton, Trs};
use glam::{Affine3A, Quat, Vec4};

/// Wraps a time into a clip of the given duration. Time exactly at the end of a positive-length
/// clip stays at the end, so resampling `[0, duration]` inclusive sees the last key.
pub fn wrap_time(t: f32, duration: f32) -> f32 {
    if duration <= 0.0 || !t.is_finite() {
        return 0.0;
    }
    if (0.0..=duration).contains(&t) {
        return t;
    }
    t.rem_euclid(duration)
}

/// Finds the key interval of `t`: the index `i` of the key at or before `t` and the fraction
/// towards key `i + 1`. Times outside the keys clamp to the first or last key.
fn locate(times: &[f32], t: f32) -> (usize, f32) {
    let n = times.len();
    if n == 1 || t <= times[0] {
        return (0, 0.0);
    }
    if t >= times[n - 1] {
        return (n - 1, 0.0);
    }
    // First key strictly after t; the interval starts one before it.
    let next = times.partition_point(|&k| k <= t);
    let i = next - 1;
    let span = times[next] - times[i];
    let f = if span > 0.0 {
        (t - times[i]) / span
    } else {
        0.0
    };
    (i, f)
}

/// Cubic Hermite spline between two keys, tangents already scaled by the key interval.
fn hermite(p0: Vec4, m0: Vec4, p1: Vec4, m1: Vec4, s: f32) -> Vec4 {
    let s2 = s * s;
    let s3 = s2 * s;
    p0 * (2.0 * s3 - 3.0 * s2 + 1.0)
        + m0 * (s3 - 2.0 * s2 + s)
        + p1 * (-2.0 * s3 + 3.0 * s2)
        + m1 * (s3 - s2)
}

/// Samples one channel at time `t` (seconds, not wrapped).
pub fn sample_channel(ch: &Channel, t: f32) -> Vec4 {
    let is_rotation = ch.target == ChannelTarget::Rotation;
    let (i, f) = locate(&ch.times, t);
    let last = ch.times.len() - 1;
    let v = match ch.interpolation {
        Interpolation::Step => ch.values[i],
        Interpolation::Linear => {
            let a = ch.values[i];
            if i == last || f == 0.0 {
                a
            } else {
                let b = ch.values[i + 1];
                if is_rotation {
                    let qa = Quat::from_vec4(a);
                    let mut qb = Quat::from_vec4(b);
                    // Take the short way round; slerp would otherwise spin the long way.
                    if qa.dot(qb) < 0.0 {
                        qb = -qb;
                    }
                    Vec4::from(qa.slerp(qb, f))
                } else {
                    a.lerp(b, f)
                }
            }
        }
        Interpolation::CubicSpline => {
            // Keys are stored as (in-tangent, value, out-tangent) triples.
            let value = |k: usize| ch.values[3 * k + 1];
            if i == last || f == 0.0 {
                value(i)
            } else {
                let dt = ch.times[i + 1] - ch.times[i];
                let out_tangent = ch.values[3 * i + 2] * dt;
                let in_tangent = ch.values[3 * (i + 1)] * dt;
                hermite(value(i), out_tangent, value(i + 1), in_tangent, f)
            }
        }
    };
    if is_rotation {
        let q = Quat::from_vec4(v);
        let len = q.length();
        if len > 1e-12 {
            Vec4::from(q / len)
        } else {
            Vec4::from(Quat::IDENTITY)
        }
    } else {
        v
    }
}

/// The local transforms of every skeleton node at time `t` of `clip` (rest pose without a clip).
pub fn local_pose(skeleton: &Skeleton, clip: Option<&Clip>, t: f32) -> Vec<Trs> {
    let mut pose: Vec<Trs> = skeleton.nodes.iter().map(|n| n.rest).collect();
    if let Some(clip) = clip {
        let t = wrap_time(t, clip.duration);
        for ch in &clip.channels {
            let v = sample_channel(ch, t);
            let trs = &mut pose[ch.node as usize];
            match ch.target {
                ChannelTarget::Translation => trs.translation = v.truncate(),
                ChannelTarget::Scale => trs.scale = v.truncate(),
                ChannelTarget::Rotation => trs.rotation = Quat::from_vec4(v),
            }
        }
    }
    pose
}

/// Global (model-space) transforms of every node from local ones. Nodes are parents first.
pub fn global_transforms(skeleton: &Skeleton, local: &[Trs]) -> Vec<Affine3A> {
    let mut global: Vec<Affine3A> = Vec::with_capacity(local.len());
    for (node, trs) in skeleton.nodes.iter().zip(local) {
        let m = trs.matrix();
        global.push(match node.parent {
            Some(p) => global[p as usize] * m,
            None => skeleton.root_transform * m,
        });
    }
    global
}

/// The bone matrices `G_i` (bone space to scene space) at time `t` of `clip`.
pub fn bone_matrices(skeleton: &Skeleton, clip: Option<&Clip>, t: f32) -> Vec<Affine3A> {
    let global = global_transforms(skeleton, &local_pose(skeleton, clip, t));
    skeleton
        .joints
        .iter()
        .map(|&n| global[n as usize])
        .collect()
}

/// The skinning matrices `G_i Ĝ_i⁻¹` (bind pose to scene space) of every bone at `samples`
/// times evenly over one loop of the model's first clip, starting at its beginning.
pub fn skinning_over_loop(model: &crate::model::Model, samples: usize) -> Vec<Vec<Affine3A>> {
    let skeleton = &model.skeleton;
    let clip = model.clips.first();
    let duration = clip.map_or(0.0, |c| c.duration);
    (0..samples)
        .map(|n| {
            let t = duration * n as f32 / samples.max(1) as f32;
            bone_matrices(skeleton, clip, t)
                .iter()
                .zip(&skeleton.inverse_bind)
                .map(|(g, inv)| *g * Affine3A::from_mat4(*inv))
                .collect()
        })
        .collect()
}

/// Classic linear blend skinning, `v = Σ w_i (G_i Ĝ_i⁻¹) v̂` (Merry et al., equation 1): the skinning matrices
/// are formed first, the way a conventional renderer does it. Used to check animation space.
pub fn linear_blend_skinning(
    mesh: &crate::model::SkinnedMesh,
    skeleton: &Skeleton,
    g: &[Affine3A],
) -> Vec<glam::Vec3> {
    let skinning: Vec<glam::Mat4> = g
        .iter()
        .zip(&skeleton.inverse_bind)
        .map(|(g, inv)| glam::Mat4::from(*g) * *inv)
        .collect();
    (0..mesh.vertex_count())
        .map(|v| {
            let rest = mesh.positions[v].extend(1.0);
            mesh.influences_of(v)
                .iter()
                .map(|inf| inf.weight * (skinning[inf.bone as usize] * rest))
                .sum::<Vec4>()
                .truncate()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Node;
    use glam::{Mat4, Vec3};

    fn channel(
        target: ChannelTarget,
        interp: Interpolation,
        times: &[f32],
        values: &[Vec4],
    ) -> Channel {
        Channel {
            node: 0,
            target,
            interpolation: interp,
            times: times.to_vec(),
            values: values.to_vec(),
        }
    }

    #[test]
    fn linear_translation_interpolates_and_clamps() {
        let ch = channel(
            ChannelTarget::Translation,
            Interpolation::Linear,
            &[1.0, 3.0],
            &[Vec4::ZERO, Vec4::new(2.0, 4.0, 6.0, 0.0)],
        );
        assert_eq!(sample_channel(&ch, 0.0), Vec4::ZERO);
        assert_eq!(sample_channel(&ch, 2.0), Vec4::new(1.0, 2.0, 3.0, 0.0));
        assert_eq!(sample_channel(&ch, 9.0), Vec4::new(2.0, 4.0, 6.0, 0.0));
    }

    #[test]
    fn step_holds_previous_key() {
        let ch = channel(
            ChannelTarget::Scale,
            Interpolation::Step,
            &[0.0, 1.0, 2.0],
            &[Vec4::ONE, Vec4::splat(2.0), Vec4::splat(3.0)],
        );
        assert_eq!(sample_channel(&ch, 0.99), Vec4::ONE);
        assert_eq!(sample_channel(&ch, 1.0), Vec4::splat(2.0));
        assert_eq!(sample_channel(&ch, 1.5), Vec4::splat(2.0));
    }

    #[test]
    fn linear_rotation_is_slerp_the_short_way() {
        let a = Quat::from_rotation_y(0.0);
        // The same 90° rotation written with the opposite sign must still interpolate to 45°.
        let b = -Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let ch = channel(
            ChannelTarget::Rotation,
            Interpolation::Linear,
            &[0.0, 1.0],
            &[Vec4::from(a), Vec4::from(b)],
        );
        let q = Quat::from_vec4(sample_channel(&ch, 0.5));
        let expected = Quat::from_rotation_y(std::f32::consts::FRAC_PI_4);
        assert!(q.dot(expected).abs() > 0.99999, "{q:?}");
    }

    #[test]
    fn cubic_spline_matches_hermite_and_hits_keys() {
        // A single axis going 0 -> 1 with tangents 0 is the smoothstep curve.
        let ch = channel(
            ChannelTarget::Translation,
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            &[
                Vec4::ZERO,
                Vec4::ZERO,
                Vec4::ZERO,
                Vec4::ZERO,
                Vec4::new(1.0, 0.0, 0.0, 0.0),
                Vec4::ZERO,
            ],
        );
        assert_eq!(sample_channel(&ch, 0.0).x, 0.0);
        assert_eq!(sample_channel(&ch, 2.0).x, 1.0);
        let s: f32 = 0.25;
        let smooth = 3.0 * s * s - 2.0 * s * s * s;
        assert!((sample_channel(&ch, 0.5).x - smooth).abs() < 1e-6);
        // Non-zero out-tangent (units per second) is scaled by the 2 s interval.
        let ch2 = channel(
            ChannelTarget::Translation,
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            &[
                Vec4::ZERO,
                Vec4::ZERO,
                Vec4::new(1.0, 0.0, 0.0, 0.0),
                Vec4::ZERO,
                Vec4::ZERO,
                Vec4::ZERO,
            ],
        );
        let v = sample_channel(&ch2, 1.0).x;
        // hermite(0, 2, 0, 0, 0.5) = 2 * (0.125 - 0.5 + 0.5) = 0.25
        assert!((v - 0.25).abs() < 1e-6, "{v}");
    }

    #[test]
    fn wrap_time_loops() {
        assert_eq!(wrap_time(2.5, 2.0), 0.5);
        assert_eq!(wrap_time(2.0, 2.0), 2.0);
        assert_eq!(wrap_time(-0.5, 2.0), 1.5);
        assert_eq!(wrap_time(f32::NAN, 2.0), 0.0);
    }

    #[test]
    fn global_transforms_chain_parents() {
        let skel = Skeleton {
            nodes: vec![
                Node {
                    name: "a".into(),
                    parent: None,
                    rest: Trs {
                        translation: Vec3::new(0.0, 1.0, 0.0),
                        ..Trs::IDENTITY
                    },
                },
                Node {
                    name: "b".into(),
                    parent: Some(0),
                    rest: Trs {
                        translation: Vec3::new(1.0, 0.0, 0.0),
                        rotation: Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
                        ..Trs::IDENTITY
                    },
                },
            ],
            joints: vec![0, 1],
            inverse_bind: vec![Mat4::IDENTITY; 2],
            root_transform: Affine3A::from_scale(Vec3::splat(2.0)),
        };
        let g = bone_matrices(&skel, None, 0.0);
        let p = g[1].transform_point3(Vec3::X);
        // x axis of b rotated to +y, offset (1,1,0), all scaled by 2.
        assert!((p - Vec3::new(2.0, 4.0, 0.0)).length() < 1e-5, "{p}");
    }
}

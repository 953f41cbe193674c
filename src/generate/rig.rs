//! Skeletons and keyframed clips for the generated creatures.
//!
//! Bones are placed by their head (joint) positions in the rest pose, with identity rotations,
//! so a bone's local axes are the world axes and a rotation about x swings a leg fore and aft.
//! Clips are written as functions of the loop phase and sampled into LINEAR keys; every function
//! is periodic, so the loops are seamless.

use super::cage::Weights;
use crate::model::{Channel, ChannelTarget, Clip, Interpolation, Node, Skeleton, Trs};
use glam::{Affine3A, Mat4, Quat, Vec3, Vec4};

#[derive(Clone, Debug, Default)]
pub struct Rig {
    pub names: Vec<String>,
    pub parents: Vec<Option<usize>>,
    pub heads: Vec<Vec3>,
}

impl Rig {
    pub fn bone(&mut self, name: &str, parent: Option<usize>, head: Vec3) -> usize {
        assert!(parent.is_none_or(|p| p < self.names.len()));
        self.names.push(name.to_string());
        self.parents.push(parent);
        self.heads.push(head);
        self.names.len() - 1
    }

    pub fn index(&self, name: &str) -> usize {
        self.names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no bone {name}"))
    }

    pub fn len(&self) -> usize {
        self.names.len()
    }

    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// The skeleton: one node per bone, translated from its parent, and inverse bind matrices
    /// that move the rest pose back to each bone's origin.
    pub fn skeleton(&self) -> Skeleton {
        let nodes = (0..self.len())
            .map(|i| Node {
                name: self.names[i].clone(),
                parent: self.parents[i].map(|p| p as u32),
                rest: Trs {
                    translation: self.heads[i]
                        - self.parents[i].map_or(Vec3::ZERO, |p| self.heads[p]),
                    ..Trs::IDENTITY
                },
            })
            .collect();
        Skeleton {
            nodes,
            joints: (0..self.len() as u32).collect(),
            inverse_bind: self
                .heads
                .iter()
                .map(|h| Mat4::from_translation(-*h))
                .collect(),
            root_transform: Affine3A::IDENTITY,
        }
    }
}

/// A chain of bones, each running from its head to the next one's head (the last to `end`),
/// with the bone it hangs from. Positions and weights are given by a chain coordinate `s`: bone
/// `floor(s)`, fraction `fract(s)` along it.
#[derive(Clone, Debug)]
pub struct Chain {
    pub parent: Option<usize>,
    pub bones: Vec<usize>,
    pub points: Vec<Vec3>,
}

/// Half the width of the blend zone at a joint, in bone lengths.
const BLEND: f32 = 0.3;

impl Chain {
    pub fn new(rig: &Rig, bones: &[usize], end: Vec3) -> Chain {
        let mut points: Vec<Vec3> = bones.iter().map(|&b| rig.heads[b]).collect();
        points.push(end);
        Chain {
            parent: rig.parents[bones[0]],
            bones: bones.to_vec(),
            points,
        }
    }

    pub fn point(&self, s: f32) -> Vec3 {
        let n = self.bones.len();
        let s = s.clamp(0.0, n as f32);
        let i = (s.floor() as usize).min(n - 1);
        self.points[i].lerp(self.points[i + 1], s - i as f32)
    }

    /// Weights at chain coordinate `s`: the bone alone mid-way, half and half with its
    /// neighbour at a joint, blending linearly over ±[`BLEND`] around it.
    pub fn weights(&self, s: f32) -> Weights {
        let n = self.bones.len();
        let s = s.clamp(0.0, n as f32);
        let i = (s.floor() as usize).min(n - 1);
        let t = s - i as f32;
        let bone = self.bones[i] as u32;
        let below = if i > 0 {
            Some(self.bones[i - 1] as u32)
        } else {
            self.parent.map(|p| p as u32)
        };
        let above = self.bones.get(i + 1).map(|&b| b as u32);
        let mut w: Weights = match (below, above) {
            (Some(b), _) if t < BLEND => {
                let k = 0.5 + 0.5 * t / BLEND;
                vec![(bone, k), (b, 1.0 - k)]
            }
            (_, Some(a)) if t > 1.0 - BLEND => {
                let k = 0.5 + 0.5 * (1.0 - t) / BLEND;
                vec![(bone, k), (a, 1.0 - k)]
            }
            _ => vec![(bone, 1.0)],
        };
        w.retain(|e| e.1 > 1e-6);
        w.sort_by_key(|e| e.0);
        w
    }
}

/// Rigid weights: everything on one bone.
pub fn rigid(bone: usize) -> Weights {
    vec![(bone as u32, 1.0)]
}

/// Local rotations of every bone (relative to the rest pose) and the root's offset.
#[derive(Clone, Debug)]
pub struct Pose {
    pub rotations: Vec<Quat>,
    pub root_offset: Vec3,
}

impl Pose {
    pub fn rest(bones: usize) -> Pose {
        Pose {
            rotations: vec![Quat::IDENTITY; bones],
            root_offset: Vec3::ZERO,
        }
    }

    /// Turns bone `b` further by `q` (applied after what it already has).
    pub fn rotate(&mut self, b: usize, q: Quat) {
        self.rotations[b] = q * self.rotations[b];
    }
}

/// Rotation by Euler angles in degrees: pitch about x, then yaw about y, then roll about z.
pub fn euler(pitch: f32, yaw: f32, roll: f32) -> Quat {
    Quat::from_rotation_z(roll.to_radians())
        * Quat::from_rotation_y(yaw.to_radians())
        * Quat::from_rotation_x(pitch.to_radians())
}

/// Samples a looping clip: `pose(phase)` for phase in [0, 1], keyed at about 30 Hz.
pub fn bake_clip(
    name: &str,
    duration: f32,
    ground_speed: f32,
    rig: &Rig,
    root: usize,
    pose: impl Fn(f32) -> Pose,
) -> Clip {
    let keys = ((duration * 30.0).round() as usize).max(12);
    let times: Vec<f32> = (0..=keys)
        .map(|k| duration * k as f32 / keys as f32)
        .collect();
    let poses: Vec<Pose> = (0..=keys)
        .map(|k| {
            // The last key repeats the first exactly, so the loop closes.
            let phase = if k == keys {
                0.0
            } else {
                k as f32 / keys as f32
            };
            pose(phase)
        })
        .collect();
    let mut channels = Vec::new();
    for b in 0..rig.len() {
        // Quaternions of neighbouring keys on the same hemisphere, for clean interpolation.
        let mut values: Vec<Vec4> = Vec::with_capacity(poses.len());
        let mut prev = Quat::IDENTITY;
        for p in &poses {
            let mut q = p.rotations[b].normalize();
            if q.dot(prev) < 0.0 {
                q = -q;
            }
            prev = q;
            values.push(Vec4::from(q));
        }
        if values.iter().all(|v| (*v - Vec4::W).length() < 1e-6) {
            continue;
        }
        channels.push(Channel {
            node: b as u32,
            target: ChannelTarget::Rotation,
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values,
        });
    }
    let rest = rig.heads[root];
    channels.push(Channel {
        node: root as u32,
        target: ChannelTarget::Translation,
        interpolation: Interpolation::Linear,
        times: times.clone(),
        values: poses
            .iter()
            .map(|p| (rest + p.root_offset).extend(0.0))
            .collect(),
    });
    Clip {
        name: name.to_string(),
        duration,
        channels,
        ground_speed,
    }
}

/// A smooth periodic bump: 1 at `center` (phase units), falling to 0 at ±`half_width`.
pub fn bump(phase: f32, center: f32, half_width: f32) -> f32 {
    let d = (phase - center + 0.5).rem_euclid(1.0) - 0.5;
    if d.abs() >= half_width {
        0.0
    } else {
        0.5 + 0.5 * (std::f32::consts::PI * d / half_width).cos()
    }
}

/// `sin(2π (phase · cycles + offset))`.
pub fn wave(phase: f32, cycles: f32, offset: f32) -> f32 {
    (std::f32::consts::TAU * (phase * cycles + offset)).sin()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rig() -> Rig {
        let mut r = Rig::default();
        let a = r.bone("a", None, Vec3::ZERO);
        let b = r.bone("b", Some(a), Vec3::Y);
        r.bone("c", Some(b), Vec3::Y * 2.0);
        r
    }

    #[test]
    fn chain_weights_blend_at_joints() {
        let r = rig();
        let chain = Chain::new(&r, &[1, 2], Vec3::Y * 3.0);
        assert_eq!(chain.weights(0.0), vec![(0, 0.5), (1, 0.5)]);
        assert_eq!(chain.weights(0.5), vec![(1, 1.0)]);
        assert_eq!(chain.weights(1.0), vec![(1, 0.5), (2, 0.5)]);
        assert_eq!(chain.weights(2.0), vec![(2, 1.0)]);
        assert_eq!(chain.point(1.5), Vec3::Y * 2.5);
    }

    #[test]
    fn skeleton_rest_pose_puts_bones_at_heads() {
        let r = rig();
        let s = r.skeleton();
        let g = crate::anim::bone_matrices(&s, None, 0.0);
        for (i, m) in g.iter().enumerate() {
            assert!((Vec3::from(m.translation) - r.heads[i]).length() < 1e-6);
            // G_i Ĝ_i⁻¹ is the identity in the rest pose.
            let skin = Mat4::from(*m) * s.inverse_bind[i];
            assert!(skin.abs_diff_eq(Mat4::IDENTITY, 1e-6));
        }
    }

    #[test]
    fn clips_loop_and_skip_still_bones() {
        let r = rig();
        let clip = bake_clip("swing", 1.0, 0.0, &r, 0, |ph| {
            let mut p = Pose::rest(3);
            p.rotate(1, euler(30.0 * wave(ph, 1.0, 0.0), 0.0, 0.0));
            p
        });
        // Bone 1 rotates; bones 0 and 2 do not; plus the root translation.
        assert_eq!(clip.channels.len(), 2);
        let ch = &clip.channels[0];
        assert_eq!(ch.values.first(), ch.values.last());
    }

    #[test]
    fn bump_is_periodic() {
        assert_eq!(bump(0.0, 0.0, 0.2), 1.0);
        assert_eq!(bump(0.3, 0.0, 0.2), 0.0);
        assert!((bump(0.95, 0.0, 0.2) - bump(0.05, 0.0, 0.2)).abs() < 1e-6);
    }
}

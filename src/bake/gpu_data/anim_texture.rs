//! The animation texture: every clip of a model resampled at a fixed rate into the bone matrices
//! `G_i` of Merry et al. §2.1.1, for the vertex shader to read with `textureLoad`.
//!
//! Layout, by linear texel index (see [`super::texels`]): frame `f` (counted over all clips)
//! and bone `b` occupy the three texels `3 (f B + b) + r`, row `r` of the 3×4 matrix `G_b`.
//! Frame 0 is the rest pose (the nodes' own transforms, no clip): the shader scales an
//! instance's motion by its wind strength s as `Ĝ + s (G − Ĝ)` ([`AnimationTexture::sample_with`]),
//! which moves every vertex `s` times as far from where it rests. Clips start at frame 1.
//! Which frames belong to which clip is in [`AnimationTexture::clips`]; the renderer hands the
//! vertex shader each instance's clip as a frame range ([`AnimationTexture::clip_rows`]), so
//! the shader reads nothing but matrices.
//!
//! Clip `c` of duration `d` is sampled at `n = round(d · rate) + 1` evenly spaced times covering
//! `[0, d]` inclusive, so the last frame lands exactly on the clip's end and a looping clip wraps
//! without a jump. The shader reads the two frames around the current time and blends them; the
//! CPU mirror [`AnimationTexture::sample`] does the same arithmetic.

use super::texels::TexelGrid;
use crate::model::Model;
use glam::{Affine3A, Mat3A, Vec3A};
use serde::{Deserialize, Serialize};

/// Default resampling rate in frames per second.
pub const DEFAULT_RATE: f32 = 30.0;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClipFrames {
    pub name: String,
    pub first_frame: u32,
    pub frame_count: u32,
    pub duration: f32,
    pub ground_speed: f32,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AnimationTexture {
    pub bones: u32,
    pub rate: f32,
    pub clips: Vec<ClipFrames>,
    pub grid: TexelGrid,
}

/// The time of frame `k` of a clip of `count` frames lasting `duration`: evenly spaced over
/// `[0, duration]`, ends included.
pub fn frame_time(duration: f32, count: u32, k: u32) -> f32 {
    if count > 1 {
        duration * k as f32 / (count - 1) as f32
    } else {
        0.0
    }
}

impl AnimationTexture {
    /// Resamples every clip of `model` (or its rest pose, if it has none) at `rate` Hz.
    pub fn bake(model: &Model, rate: f32) -> Self {
        Self::bake_counted(model, rate, |_, duration| {
            (duration * rate).round().max(1.0) as u32 + 1
        })
    }

    /// Resamples every clip of `model` at `frames` evenly spaced times over `[0, d]`
    /// inclusive, whatever its duration d (at least 2): an animated impostor's frames, one
    /// atlas page each (see [`crate::bake::impostor::animated`]). `rate` records the mean.
    pub fn bake_frames(model: &Model, frames: u32) -> Self {
        let frames = frames.max(2);
        let mean =
            model.clips.iter().map(|c| c.duration).sum::<f32>() / model.clips.len().max(1) as f32;
        Self::bake_counted(model, (frames - 1) as f32 / mean.max(1e-3), |_, _| frames)
    }

    /// [`Self::bake_frames`] with a count of its own for each clip (`counts[c]`, at least 2;
    /// the last count for clips past the list): an impostor whose clips share one sheet.
    pub fn bake_frames_each(model: &Model, counts: &[u32]) -> Self {
        let count = |c: usize| counts.get(c).or(counts.last()).copied().unwrap_or(2).max(2);
        let rates: Vec<f32> = (model.clips.iter().enumerate())
            .map(|(c, clip)| (count(c) - 1) as f32 / clip.duration.max(1e-3))
            .collect();
        let rate = rates.iter().sum::<f32>() / rates.len().max(1) as f32;
        Self::bake_counted(model, rate, |c, _| count(c))
    }

    /// [`Self::bake`] with clip frame counts from `count(clip, duration)` (for a clip that
    /// lasts).
    fn bake_counted(model: &Model, rate: f32, count: impl Fn(usize, f32) -> u32) -> Self {
        let skel = &model.skeleton;
        let bones = skel.bone_count() as u32;
        let mut clips = Vec::new();
        let mut frames: Vec<Vec<Affine3A>> = vec![crate::anim::bone_matrices(skel, None, 0.0)];
        let sources: Vec<Option<&crate::model::Clip>> = if model.clips.is_empty() {
            vec![None]
        } else {
            model.clips.iter().map(Some).collect()
        };
        for (c, clip) in sources.into_iter().enumerate() {
            let duration = clip.map_or(0.0, |c| c.duration.max(0.0));
            let count = if duration > 0.0 {
                count(c, duration)
            } else {
                1
            };
            clips.push(ClipFrames {
                name: clip.map_or_else(|| "rest".to_string(), |c| c.name.clone()),
                first_frame: frames.len() as u32,
                frame_count: count,
                duration,
                ground_speed: clip.map_or(0.0, |c| c.ground_speed),
            });
            for k in 0..count {
                let t = frame_time(duration, count, k);
                frames.push(crate::anim::bone_matrices(skel, clip, t));
            }
        }
        let mut texels = Vec::with_capacity(frames.len() * bones as usize * 3);
        for frame in &frames {
            for g in frame {
                texels.extend(matrix_rows(g));
            }
        }
        AnimationTexture {
            bones,
            rate,
            clips,
            grid: TexelGrid::from_linear(texels),
        }
    }

    /// Clip `clip` as the vertex shader receives it: texel of its first frame's first row,
    /// frame count, duration in seconds, and texels per frame.
    pub fn clip_rows(&self, clip: usize) -> [f32; 4] {
        let c = &self.clips[clip.min(self.clips.len() - 1)];
        let stride = 3 * self.bones;
        [
            (c.first_frame * stride) as f32,
            c.frame_count as f32,
            c.duration,
            stride as f32,
        ]
    }

    /// The stored `G_b` of global frame `frame`.
    pub fn matrix(&self, frame: u32, bone: u32) -> Affine3A {
        let i = 3 * (frame as usize * self.bones as usize + bone as usize);
        rows_to_affine([self.grid.get(i), self.grid.get(i + 1), self.grid.get(i + 2)])
    }

    /// The bone matrices the vertex shader uses at `time` seconds into `clip` (looping): the
    /// two frames around the time, blended linearly, exactly as `shaders/skinning.wgsl` does.
    pub fn sample(&self, clip: usize, time: f32) -> Vec<Affine3A> {
        self.sample_with(clip, time, 1.0)
    }

    /// [`Self::sample`] with the motion scaled by the wind strength `wind`: every matrix
    /// `Ĝ + wind · (G − Ĝ)` about the rest pose Ĝ (frame 0), as the shader does where the
    /// instance's strength is not 1.
    pub fn sample_with(&self, clip: usize, time: f32, wind: f32) -> Vec<Affine3A> {
        let c = &self.clips[clip];
        let (f0, f1, a) = frame_pair(c.frame_count, c.duration, time);
        let lerp = |m0: Affine3A, m1: Affine3A, a: f32| Affine3A {
            matrix3: Mat3A::from_cols(
                m0.matrix3.x_axis.lerp(m1.matrix3.x_axis, a),
                m0.matrix3.y_axis.lerp(m1.matrix3.y_axis, a),
                m0.matrix3.z_axis.lerp(m1.matrix3.z_axis, a),
            ),
            translation: m0.translation.lerp(m1.translation, a),
        };
        (0..self.bones)
            .map(|b| {
                let m0 = self.matrix(c.first_frame + f0, b);
                let m1 = self.matrix(c.first_frame + f1, b);
                let g = lerp(m0, m1, a);
                if wind == 1.0 {
                    g
                } else {
                    let rest = self.matrix(0, b);
                    Affine3A {
                        matrix3: rest.matrix3 + (g.matrix3 - rest.matrix3) * wind,
                        translation: rest.translation + (g.translation - rest.translation) * wind,
                    }
                }
            })
            .collect()
    }

    /// The bone matrices of a cross-fade from `clip` at `time` to clip `to` at `to_time` by
    /// `weight` (0: `clip` alone): each clip sampled as [`Self::sample`], then the two blended
    /// linearly, as `bone_rows` in `shaders/skinning.wgsl` does.
    pub fn sample_fade(
        &self,
        (clip, time): (usize, f32),
        (to, to_time): (usize, f32),
        weight: f32,
    ) -> Vec<Affine3A> {
        let w = weight.clamp(0.0, 1.0);
        self.sample(clip, time)
            .into_iter()
            .zip(self.sample(to, to_time))
            .map(|(a, b)| Affine3A {
                matrix3: a.matrix3 * (1.0 - w) + b.matrix3 * w,
                translation: a.translation * (1.0 - w) + b.translation * w,
            })
            .collect()
    }

    /// Loop time in [0, 1) of `time` seconds into `clip`, as the shader computes it for the
    /// spectral offsets.
    pub fn loop_time(&self, clip: usize, time: f32) -> f32 {
        let c = &self.clips[clip];
        if c.duration <= 0.0 {
            return 0.0;
        }
        let u = time / c.duration;
        u - u.floor()
    }
}

/// Frame indices (within the clip) and blend factor for `time`, wrapping the clip. Mirrors the
/// WGSL in `shaders/skinning.wgsl`.
pub fn frame_pair(frame_count: u32, duration: f32, time: f32) -> (u32, u32, f32) {
    if frame_count <= 1 || duration <= 0.0 {
        return (0, 0, 0.0);
    }
    let u = time / duration;
    let u = u - u.floor();
    let f = u * (frame_count - 1) as f32;
    let f0 = (f.floor() as u32).min(frame_count - 1);
    let f1 = (f0 + 1).min(frame_count - 1);
    (f0, f1, f - f0 as f32)
}

fn matrix_rows(g: &Affine3A) -> [[f32; 4]; 3] {
    let m = g.matrix3;
    let t = g.translation;
    [
        [m.x_axis.x, m.y_axis.x, m.z_axis.x, t.x],
        [m.x_axis.y, m.y_axis.y, m.z_axis.y, t.y],
        [m.x_axis.z, m.y_axis.z, m.z_axis.z, t.z],
    ]
}

fn rows_to_affine(r: [[f32; 4]; 3]) -> Affine3A {
    let col = |k: usize| Vec3A::new(r[0][k], r[1][k], r[2][k]);
    Affine3A {
        matrix3: Mat3A::from_cols(col(0), col(1), col(2)),
        translation: col(3),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_round_trip() {
        let g = Affine3A::from_scale_rotation_translation(
            glam::Vec3::new(1.0, 2.0, 3.0),
            glam::Quat::from_rotation_y(0.3),
            glam::Vec3::new(4.0, 5.0, 6.0),
        );
        let back = rows_to_affine(matrix_rows(&g));
        assert!(back.abs_diff_eq(g, 1e-7));
        let p = glam::Vec3::new(0.5, -1.0, 2.0);
        let rows = matrix_rows(&g).map(glam::Vec4::from);
        let via_rows = glam::Vec3::new(
            rows[0].dot(p.extend(1.0)),
            rows[1].dot(p.extend(1.0)),
            rows[2].dot(p.extend(1.0)),
        );
        assert!((via_rows - g.transform_point3(p)).length() < 1e-5);
    }

    #[test]
    fn frame_pair_wraps_and_blends() {
        // 1 s clip with 31 frames: frame k at k/30 s.
        assert_eq!(frame_pair(31, 1.0, 0.0), (0, 1, 0.0));
        let (a, b, f) = frame_pair(31, 1.0, 0.5 + 1.0 / 60.0);
        assert_eq!((a, b), (15, 16));
        assert!((f - 0.5).abs() < 1e-3);
        let (a, _, _) = frame_pair(31, 1.0, 2.25);
        assert_eq!(a, 7);
        assert_eq!(frame_pair(1, 0.0, 3.0), (0, 0, 0.0));
    }
}

//! Spectral descriptions of foliage motion (Bennett-Therkildsen, Carlsen & Schmid, "Animated
//! Billboard Clouds for Foliage Simplification", Aalborg University, 2007: Ch. 4 §6.1 and §6.3; the
//! thesis designed them and never built them). Pure CPU.
//!
//! - [`leaf_trajectories`] samples every leaf's centroid over one loop of the wind.
//! - [`dft`] turns each coordinate of a trajectory into a spectrum of whole-cycle cosines.
//! - [`description`] holds the thesis's three description types (naive, dominating axis,
//!   axis-phase), each with `describe`, `deviation`, `average` and `apply`, corrected where the
//!   thesis's printed formulas do not work as written: NEP instead of bare products,
//!   dominating axes sign-aligned before their phases are averaged, cosine phases, normalised
//!   amplitudes.
//! - [`bins`] reduces a spectrum to K lines per axis (§6.3.3), the record a billboard's vertex
//!   shader evaluates.
//! - [`cluster`] groups leaves by how they move (§6.2, App. C), [`cloud`] builds a billboard
//!   cloud per cluster whose billboards follow their leaves' shared bone and add the residual
//!   motion as lines (§6.4), and [`crate::bake::gpu_data::spectra`] lays those lines out for the vertex shader.

pub mod bins;
pub mod cloud;
pub mod cluster;
pub mod description;
pub mod dft;
pub mod metrics;

use crate::anim::skinning_over_loop;
use crate::model::Model;
use glam::Vec3;
use rayon::prelude::*;

/// Position samples per loop: a power of two for the FFT, and twice the fastest sway of the
/// demo trees (whole cycles per loop) with room to spare.
pub const DEFAULT_SAMPLES: usize = 64;
/// Lines per axis a billboard keeps (§6.3.3).
pub const DEFAULT_BINS: usize = 4;

/// Normalised error (thesis App. A): [0, ∞) onto [0, 1).
pub fn ne(a: f32) -> f32 {
    1.0 - 1.0 / (1.0 + a.max(0.0))
}

/// Normalised error product (App. A): large when either error is.
pub fn nep(a: f32, b: f32) -> f32 {
    1.0 - 1.0 / ((1.0 + a.max(0.0)) * (1.0 + b.max(0.0)))
}

/// The angle between two angles, in [0, π] (App. A.4).
pub fn cyclic_diff(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(std::f32::consts::TAU);
    d.min(std::f32::consts::TAU - d)
}

/// The weighted cyclic mean of `(angle, weight)` pairs (App. A.4): the angle of the sum of
/// weighted unit vectors; where they cancel, the heaviest angle.
pub fn cyclic_mean(items: impl IntoIterator<Item = (f32, f32)>) -> f32 {
    let (mut s, mut c, mut heaviest) = (0.0f32, 0.0f32, (0.0f32, f32::MIN));
    for (angle, w) in items {
        s += w * angle.sin();
        c += w * angle.cos();
        if w > heaviest.1 {
            heaviest = (angle, w);
        }
    }
    if s.hypot(c) > 1e-9 * heaviest.1.abs().max(1e-9) {
        s.atan2(c)
    } else {
        heaviest.0
    }
}

/// Every leaf's centroid at `samples` times evenly over one loop of the model's first clip,
/// in scene space (thesis §4.3: a leaf is represented by its centroid's trajectory).
pub fn leaf_trajectories(
    model: &Model,
    foliage: &crate::bake::foliage::billboard::Foliage,
    samples: usize,
) -> Vec<Vec<Vec3>> {
    let points: Vec<(Vec3, u32)> = foliage
        .leaves
        .iter()
        .zip(&foliage.bones)
        .map(|(leaf, &bone)| (leaf_centroid(&leaf.corners), bone))
        .collect();
    trajectories(model, &points, samples)
}

/// The centroid of a leaf's corners.
pub fn leaf_centroid(corners: &[Vec3]) -> Vec3 {
    corners.iter().copied().sum::<Vec3>() / corners.len().max(1) as f32
}

/// The trajectories of rest-pose points each bound rigidly to one bone, at `samples` times
/// evenly over one loop.
pub fn trajectories(model: &Model, points: &[(Vec3, u32)], samples: usize) -> Vec<Vec<Vec3>> {
    trajectories_in(&skinning_over_loop(model, samples), points)
}

/// [`trajectories`] through skinning matrices already sampled over the loop (one `Vec` of
/// bone matrices per sample, as [`skinning_over_loop`] gives them).
pub fn trajectories_in(frames: &[Vec<glam::Affine3A>], points: &[(Vec3, u32)]) -> Vec<Vec<Vec3>> {
    points
        .par_iter()
        .map(|&(c, bone)| {
            frames
                .iter()
                .map(|m| m.get(bone as usize).map_or(c, |m| m.transform_point3(c)))
                .collect()
        })
        .collect()
}

/// Animation zones (thesis App. C.2): leaves of one bone within `radius` of a zone's first leaf
/// (rest pose) move almost alike, so they are described and clustered as one item, weighted by
/// their count.
#[derive(Clone, Debug, PartialEq)]
pub struct Zones {
    /// The zone of every leaf.
    pub of: Vec<u32>,
    /// Per zone: its bone, its leaves' rest centroid and how many leaves it holds.
    pub bone: Vec<u32>,
    pub centre: Vec<Vec3>,
    pub leaves: Vec<u32>,
}

impl Zones {
    pub fn new(foliage: &crate::bake::foliage::billboard::Foliage, radius: f32) -> Zones {
        let mut zones = Zones {
            of: Vec::with_capacity(foliage.leaves.len()),
            bone: Vec::new(),
            centre: Vec::new(),
            leaves: Vec::new(),
        };
        // Per bone, the zones opened so far: (zone, its first leaf's centroid).
        let mut open: std::collections::HashMap<u32, Vec<(u32, Vec3)>> = Default::default();
        let mut sums: Vec<Vec3> = Vec::new();
        for (leaf, &bone) in foliage.leaves.iter().zip(&foliage.bones) {
            let c = leaf_centroid(&leaf.corners);
            let list = open.entry(bone).or_default();
            let z = match list.iter().find(|(_, seed)| seed.distance(c) <= radius) {
                Some(&(z, _)) => z,
                None => {
                    let z = zones.bone.len() as u32;
                    list.push((z, c));
                    zones.bone.push(bone);
                    zones.leaves.push(0);
                    sums.push(Vec3::ZERO);
                    z
                }
            };
            zones.of.push(z);
            zones.leaves[z as usize] += 1;
            sums[z as usize] += c;
        }
        zones.centre = sums
            .iter()
            .zip(&zones.leaves)
            .map(|(s, &n)| *s / n.max(1) as f32)
            .collect();
        zones
    }

    pub fn len(&self) -> usize {
        self.bone.len()
    }

    pub fn is_empty(&self) -> bool {
        self.bone.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::anim::bone_matrices;
    use glam::Affine3A;

    #[test]
    fn cyclic_helpers_wrap_round() {
        use std::f32::consts::{PI, TAU};
        assert!((cyclic_diff(0.1, TAU - 0.1) - 0.2).abs() < 1e-5);
        assert!((cyclic_diff(0.0, PI) - PI).abs() < 1e-6);
        let m = cyclic_mean([(110f32.to_radians(), 1.0), (330f32.to_radians(), 1.0)]);
        assert!((m.to_degrees() - 40.0).abs() < 1e-3, "{}", m.to_degrees());
        assert_eq!(ne(0.0), 0.0);
        assert!(nep(0.0, 3.0) == ne(3.0) && nep(1.0, 1.0) > ne(1.0));
    }

    /// Trajectories follow the leaves' bones: the first sample is the leaf at the loop's
    /// start, every leaf moves, twigs more than the trunk's lowest leaves.
    #[test]
    fn leaf_trajectories_follow_the_wind() {
        let tree = crate::generate::tree::sapling();
        let f = crate::bake::foliage::billboard::foliage(&tree).unwrap();
        let tr = leaf_trajectories(&tree, &f, 16);
        assert_eq!(tr.len(), f.leaves.len());
        let clip = tree.clips.first();
        let g = bone_matrices(&tree.skeleton, clip, 0.0);
        let b = f.bones[0] as usize;
        let c = leaf_centroid(&f.leaves[0].corners);
        let expect =
            (g[b] * Affine3A::from_mat4(tree.skeleton.inverse_bind[b])).transform_point3(c);
        assert!((tr[0][0] - expect).length() < 1e-5);
        for (i, t) in tr.iter().enumerate() {
            let spread = t
                .iter()
                .map(|p| (*p - t[0]).length())
                .fold(0.0f32, f32::max);
            assert!(spread > 1e-3, "leaf {i} does not move");
        }
    }
}

#[cfg(test)]
mod zone_tests {
    use super::*;

    /// Zones never mix bones, hold every leaf once, and stay within their radius.
    #[test]
    fn animation_zones_group_nearby_leaves_of_one_bone() {
        let tree = crate::generate::tree::sapling();
        let f = crate::bake::foliage::billboard::foliage(&tree).unwrap();
        let zones = Zones::new(&f, 0.3);
        assert!(zones.len() < f.leaves.len() / 2, "{} zones", zones.len());
        assert!(zones.len() >= 48, "at least one per foliage bone");
        assert_eq!(zones.leaves.iter().sum::<u32>() as usize, f.leaves.len());
        for (leaf, &z) in zones.of.iter().enumerate() {
            assert_eq!(zones.bone[z as usize], f.bones[leaf]);
            let c = leaf_centroid(&f.leaves[leaf].corners);
            assert!(c.distance(zones.centre[z as usize]) <= 0.6 + 1e-4);
        }
        assert_eq!(Zones::new(&f, 0.0).len(), f.leaves.len());
    }
}

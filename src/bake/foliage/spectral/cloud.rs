//! Spectral billboard clouds: the Spectral Clustering Algorithm (§6.2) of Bennett-Therkildsen,
//! Carlsen & Schmid's thesis "Animated Billboard Clouds for Foliage Simplification" (2007), with
//! the shared-bone improvement (§6.4), which the thesis designed and never built.
//!
//! 1. Leaves are gathered into animation zones (App. C.2), and every zone's centroid trajectory
//!    over the loop is described by the chosen description type.
//! 2. The zones are clustered into k clusters by k-means on the description's deviation
//!    ([`super::cluster`]); a leaf joins its zone's cluster.
//! 3. Every cluster gets its own stochastic billboard cloud, built from its leaves at rest.
//! 4. Every billboard is skinned to the deepest bone its leaves share (its branch still carries
//!    it exactly), and the rest of its leaves' motion, the *residual* seen from that bone, is
//!    described, averaged over its leaves and reduced to K lines per axis (§6.3.3). The vertex
//!    shader adds those lines' offset in the bone's space before skinning (brief §8:
//!    `v' = G_i (p + Δ(τ))`), so the offset turns with the branch.
//!
//! The offset oscillates about the leaves' mean pose (the thesis's "average pose", §6.2 step 2),
//! not their rest pose: the billboards are built where the leaves rest, and the residual's mean
//! (the DFT's DC bin) differs from that by how far the wind holds the branches over, and by
//! the sag of a swaying branch. Every row's first line per axis is that mean, a line of 0
//! cycles.

use super::bins::reduce;
use super::cluster::{ClusterParams, cluster};
use super::description::{Description, DescriptionType};
use super::dft::Dft;
use super::{Zones, trajectories_in};
use crate::anim::skinning_over_loop;
use crate::bake::foliage::billboard::cloud::CloudParams;
use crate::bake::foliage::billboard::{
    Foliage, SkeletonCloud, cloud_of_groups, root_bone, tree_height,
};
use crate::bake::gpu_data::spectra::Line;
use crate::model::Model;
use glam::{Affine3A, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// How a spectral cloud is made.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpectralParams {
    pub kind: DescriptionType,
    /// Motion clusters (k of §6.2).
    pub clusters: usize,
    /// Lines kept per axis (K of §6.3.3).
    pub bins: usize,
    /// Trajectory samples over the loop (a power of two).
    pub samples: usize,
    /// Animation zone radius as a fraction of the tree's height (App. C.2).
    pub zone_radius: f32,
    /// §6.4: every billboard follows its leaves' deepest shared bone and its spectra hold only
    /// the rest of their motion. Off: the plain Spectral Clustering Algorithm (§6.2), every
    /// billboard held by the skeleton's root and all of its leaves' motion in its spectra.
    pub shared_bone: bool,
    pub seed: u64,
}

impl Default for SpectralParams {
    fn default() -> Self {
        SpectralParams {
            kind: DescriptionType::AxisPhase,
            clusters: 16,
            bins: super::DEFAULT_BINS,
            samples: super::DEFAULT_SAMPLES,
            zone_radius: 0.03,
            shared_bone: true,
            seed: 1,
        }
    }
}

/// A spectral billboard cloud: the billboards (each bound to its leaves' shared bone) and the
/// lines per axis of every billboard's residual motion, in its bone's space: the mean first
/// (a line of 0 cycles), then K ([`lines_per_axis`] in all).
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralCloud {
    pub cloud: SkeletonCloud,
    pub lines: Vec<[Vec<Line>; 3]>,
    /// The clusters actually made (fewer than asked where there are fewer zones).
    pub clusters: usize,
}

/// Lines per axis of every row of a spectral cloud made with `params`: the mean pose, then K.
pub fn lines_per_axis(params: &SpectralParams) -> usize {
    params.bins.max(1) + 1
}

/// The spectral cloud of `model`'s `foliage` (see the module comment).
pub fn spectral_cloud(
    model: &Model,
    foliage: &Foliage,
    cloud: &CloudParams,
    params: &SpectralParams,
) -> SpectralCloud {
    let skeleton = &model.skeleton;
    let zones = Zones::new(foliage, params.zone_radius * tree_height(model));
    let points: Vec<(Vec3, u32)> = zones
        .centre
        .iter()
        .copied()
        .zip(zones.bone.iter().copied())
        .collect();
    let frames = skinning_over_loop(model, params.samples.max(4));
    let dft = Dft::new(frames.len());
    let kind = params.kind;
    let items: Vec<Description> = trajectories_in(&frames, &points)
        .par_iter()
        .map(|t| kind.describe(&dft, t))
        .collect();
    let weights: Vec<f32> = zones.leaves.iter().map(|&n| n as f32).collect();
    // Lever arm: distance from the joint of the zone's bone (the bind matrix's origin).
    let bind: Vec<Affine3A> = skeleton
        .inverse_bind
        .iter()
        .map(|m| Affine3A::from_mat4(*m))
        .collect();
    let lever: Vec<f32> = points
        .iter()
        .map(|&(c, b)| {
            bind.get(b as usize).map_or(c.length(), |inv| {
                c.distance(inv.inverse().translation.into())
            })
        })
        .collect();
    let clusters = cluster(
        kind,
        &items,
        &weights,
        &zones.bone,
        &lever,
        &ClusterParams {
            k: params.clusters.max(1),
            seed: params.seed,
            ..Default::default()
        },
    );
    let group_of: Vec<u32> = zones.of.iter().map(|&z| clusters.of[z as usize]).collect();
    let made = clusters.centroids.len();
    let mut billboards = cloud_of_groups(skeleton, foliage, cloud, &group_of);
    if !params.shared_bone {
        for bone in &mut billboards.bones {
            *bone = root_bone(skeleton, *bone);
        }
    }

    // Residual motion seen from each billboard's bone i: r(t) = Ĝ_i⁻¹ S_i(t)⁻¹ S_b(t) c for a
    // zone centre c on bone b (S the skinning matrices), i.e. the leaves' motion with the
    // shared bones held still, in bone i's space.
    let inverse_frames: Vec<Vec<Affine3A>> = frames
        .iter()
        .map(|f| f.iter().map(Affine3A::inverse).collect())
        .collect();
    let lines = billboards
        .billboards
        .par_iter()
        .zip(&billboards.bones)
        .enumerate()
        .map(|(b, (bb, &bone))| {
            let mut count: std::collections::BTreeMap<u32, f32> = Default::default();
            for &leaf in &bb.leaves {
                *count.entry(zones.of[leaf as usize]).or_default() += 1.0;
            }
            let to_bone = bind
                .get(bone as usize)
                .copied()
                .unwrap_or(Affine3A::IDENTITY);
            // The mean pose (the DC bin): how far the leaves' mean position over the loop
            // lies from their rest position, in the bone's space, weighted like the spectra.
            let mut mean = Vec3::ZERO;
            let members: Vec<(Description, f32)> = count
                .iter()
                .map(|(&z, &w)| {
                    let (c, zb) = points[z as usize];
                    let residual: Vec<Vec3> = frames
                        .iter()
                        .zip(&inverse_frames)
                        .map(|(f, inv)| {
                            let world = f.get(zb as usize).map_or(c, |m| m.transform_point3(c));
                            let still = inv
                                .get(bone as usize)
                                .map_or(world, |m| m.transform_point3(world));
                            to_bone.transform_point3(still)
                        })
                        .collect();
                    let at_rest = to_bone.transform_point3(c);
                    mean += w
                        * (residual.iter().sum::<Vec3>() / residual.len().max(1) as f32 - at_rest);
                    (kind.describe(&dft, &residual), w)
                })
                .collect();
            mean /= count.values().sum::<f32>().max(f32::MIN_POSITIVE);
            let refs: Vec<(&Description, f32)> = members.iter().map(|(d, w)| (d, *w)).collect();
            let average = kind.average(&refs);
            let seed = params.seed ^ (b as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
            let mut lines = reduce(&average.axis_spectra(seed), params.bins.max(1));
            for (axis, lines) in lines.iter_mut().enumerate() {
                lines.insert(0, Line::constant(mean[axis]));
            }
            lines
        })
        .collect();
    SpectralCloud {
        cloud: billboards,
        lines,
        clusters: made,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::foliage::billboard::foliage;

    /// Every leaf lands on exactly one billboard, billboards follow their leaves' shared bone,
    /// and the lines move them: a billboard on a twig sways less about its bone than its
    /// leaves do about the tree (the bone carries the rest), but not nothing.
    #[test]
    fn a_spectral_cloud_covers_every_leaf_and_moves_its_billboards() {
        let tree = crate::generate::tree::sapling();
        let f = foliage(&tree).unwrap();
        let h = tree_height(&tree);
        let params = SpectralParams {
            clusters: 6,
            ..Default::default()
        };
        let c = spectral_cloud(
            &tree,
            &f,
            &CloudParams {
                epsilon: 0.08 * h,
                ..Default::default()
            },
            &params,
        );
        assert_eq!(c.clusters, 6);
        assert_eq!(c.lines.len(), c.cloud.billboards.len());
        let mut seen = vec![0u32; f.leaves.len()];
        for bb in &c.cloud.billboards {
            for &l in &bb.leaves {
                seen[l as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&n| n == 1), "every leaf on one billboard");
        // Fewer billboards than one cloud per bone would give at the same ε.
        let per_bone = crate::bake::foliage::billboard::skeleton_cloud(
            &tree.skeleton,
            &f,
            &CloudParams {
                epsilon: 0.08 * h,
                ..Default::default()
            },
        );
        assert!(
            c.cloud.billboards.len() < per_bone.billboards.len(),
            "{} spectral, {} per bone",
            c.cloud.billboards.len(),
            per_bone.billboards.len()
        );
        let moving = c
            .lines
            .iter()
            .filter(|l| l.iter().flatten().any(|line| line.amplitude > 1e-4 * h))
            .count();
        assert!(
            moving * 2 > c.lines.len(),
            "{moving} of {} billboards move",
            c.lines.len()
        );
        for l in c.lines.iter().flatten() {
            assert_eq!(l.len(), lines_per_axis(&params));
            assert_eq!(l[0].cycles, 0, "the mean pose first");
        }
    }

    /// Without the shared bone (plain SCA), every billboard hangs from the skeleton's root and
    /// its spectra carry all of its leaves' motion: they sway wider than the residual that is
    /// left when the billboard follows its branch.
    #[test]
    fn plain_sca_holds_billboards_by_the_root_with_all_the_motion() {
        let tree = crate::generate::tree::sapling();
        let f = foliage(&tree).unwrap();
        let h = tree_height(&tree);
        let cloud = CloudParams {
            epsilon: 0.08 * h,
            ..Default::default()
        };
        let shared = SpectralParams {
            clusters: 6,
            ..Default::default()
        };
        let plain = SpectralParams {
            shared_bone: false,
            ..shared
        };
        let a = spectral_cloud(&tree, &f, &cloud, &shared);
        let b = spectral_cloud(&tree, &f, &cloud, &plain);
        let roots: Vec<u32> = (0..tree.skeleton.bone_count() as u32)
            .filter(|&i| root_bone(&tree.skeleton, i) == i)
            .collect();
        assert!(b.cloud.bones.iter().all(|bone| roots.contains(bone)));
        assert!(a.cloud.bones.iter().any(|bone| !roots.contains(bone)));
        let sway = |c: &SpectralCloud| -> f32 {
            c.lines
                .iter()
                .flatten()
                .flatten()
                .filter(|l| l.cycles > 0)
                .map(|l| l.amplitude)
                .sum::<f32>()
                / c.lines.len().max(1) as f32
        };
        assert!(
            sway(&b) > 1.5 * sway(&a),
            "plain SCA sways {} per billboard, shared bone {}",
            sway(&b),
            sway(&a)
        );
    }

    /// A tree the wind holds over (every joint's rotation turned 6° further the same way)
    /// has a mean pose away from its rest pose. Billboards built at rest then swing about
    /// the wrong place unless their rows carry the mean (the DC line): with it their motion
    /// follows the leaves' more closely than with the mean taken out.
    #[test]
    fn billboards_swing_about_the_mean_pose() {
        use crate::bake::foliage::spectral::metrics::{animation_error, traced_leaves};
        use crate::model::ChannelTarget;
        let mut tree = crate::generate::tree::sapling();
        let lean = glam::Quat::from_rotation_z(6f32.to_radians());
        for clip in &mut tree.clips {
            for ch in &mut clip.channels {
                if ch.target == ChannelTarget::Rotation {
                    for v in &mut ch.values {
                        *v = glam::Vec4::from(lean * glam::Quat::from_vec4(*v));
                    }
                }
            }
        }
        let f = foliage(&tree).unwrap();
        let h = tree_height(&tree);
        let cloud = CloudParams {
            epsilon: 0.04 * h,
            ..Default::default()
        };
        let params = SpectralParams {
            clusters: 8,
            ..Default::default()
        };
        let c = spectral_cloud(&tree, &f, &cloud, &params);
        let without: Vec<[Vec<Line>; 3]> = c
            .lines
            .iter()
            .map(|l| {
                l.clone().map(|mut axis| {
                    axis.retain(|line| line.cycles > 0);
                    axis
                })
            })
            .collect();
        let frames = skinning_over_loop(&tree, params.samples);
        let traced = traced_leaves(&f);
        let error = |lines: &[[Vec<Line>; 3]]| {
            animation_error(&tree, &f, &c.cloud, Some(lines), &frames, &traced).rms
        };
        let (with, without) = (error(&c.lines), error(&without));
        assert!(
            with < 0.8 * without,
            "RMS {with:.4} h with the mean pose, {without:.4} h without"
        );
    }
}

//! Animation error of a billboard cloud (Bennett-Therkildsen, Carlsen & Schmid's thesis "Animated
//! Billboard Clouds for Foliage Simplification" (2007) §5.1.2 and §5.1.4, defined there and never
//! computed): how far the billboards' motion strays from the leaves'.
//!
//! Every leaf is represented by its centroid, and on its billboard by the centroid's
//! projection onto the billboard's plane (at rest). Both are followed over the loop: the leaf
//! by its own bone, the projected point as the billboard moves (its bone, plus its spectral
//! offset for a spectral cloud, exactly as the vertex shader moves it). Per leaf:
//! - `rms`: the RMS distance between the two trajectories over the loop (so it holds the
//!   projection distance, at most ε, as well as the difference in motion);
//! - `spectral`: the dominating-axis spectral metric of §5.1.4, NE(amplitude distance) of the
//!   two trajectories' spectra along their dominating axes, with trajectories measured in tree
//!   heights so the figure does not depend on the tree's size. It is 0 for congruent motions
//!   (the same motion shifted, turned or mirrored) and grows with the amplitude lost or added.
//!
//! Both are averaged over the leaves.

use super::bins::eval;
use super::description::{Description, DescriptionType};
use super::dft::Dft;
use super::ne;
use crate::bake::foliage::billboard::{Foliage, SkeletonCloud, tree_height};
use crate::bake::gpu_data::spectra::Line;
use crate::model::Model;
use glam::{Affine3A, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Animation error of one cloud, averaged over its leaves.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AnimationError {
    /// Mean over leaves of the RMS distance between trajectories, in tree heights.
    pub rms: f32,
    /// Mean over leaves of NE(amplitude distance) of the dominating-axis spectra.
    pub spectral: f32,
    /// The original and billboard trajectories (scene units) of the leaves asked for.
    pub traces: Vec<LeafTrace>,
}

/// One leaf's trajectory and its billboard's, over one loop.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeafTrace {
    pub leaf: u32,
    pub original: Vec<Vec3>,
    pub billboard: Vec<Vec3>,
}

/// One leaf's RMS and spectral error, and its trajectories if traced.
type LeafError = (f32, f32, Option<LeafTrace>);

/// The animation error of `cloud` (built from `foliage`, the tree's own leaves and bones)
/// over `frames` (skinning matrices sampled evenly over the loop, see
/// [`crate::anim::skinning_over_loop`]). `lines` are a spectral cloud's per-billboard lines in
/// their bone's space. `traced` leaves get their trajectories returned.
pub fn animation_error(
    model: &Model,
    foliage: &Foliage,
    cloud: &SkeletonCloud,
    lines: Option<&[[Vec<Line>; 3]]>,
    frames: &[Vec<Affine3A>],
    traced: &[u32],
) -> AnimationError {
    let h = tree_height(model);
    let bind: Vec<Affine3A> = model
        .skeleton
        .inverse_bind
        .iter()
        .map(|m| Affine3A::from_mat4(*m).inverse())
        .collect();
    let dft = Dft::new(frames.len());
    let n = frames.len().max(1) as f32;
    let per_billboard: Vec<Vec<LeafError>> = cloud
        .billboards
        .par_iter()
        .zip(&cloud.bones)
        .enumerate()
        .map(|(b, (bb, &bone))| {
            // The billboard's offset at every sample, turned from bone space into rest space.
            let offsets: Vec<Vec3> = (0..frames.len())
                .map(|s| match lines {
                    Some(l) => bind.get(bone as usize).map_or(Vec3::ZERO, |m| {
                        m.transform_vector3(eval(&l[b], s as f32 / n))
                    }),
                    None => Vec3::ZERO,
                })
                .collect();
            bb.leaves
                .iter()
                .map(|&leaf| {
                    let c = super::leaf_centroid(&foliage.leaves[leaf as usize].corners);
                    let p = c - bb.plane.distance(c) * bb.plane.normal;
                    let own = foliage.bones[leaf as usize] as usize;
                    let (mut original, mut moved) = (Vec::new(), Vec::new());
                    for (f, d) in frames.iter().zip(&offsets) {
                        original.push(f.get(own).map_or(c, |m| m.transform_point3(c)));
                        moved.push(
                            f.get(bone as usize)
                                .map_or(p + *d, |m| m.transform_point3(p + *d)),
                        );
                    }
                    let rms = (original
                        .iter()
                        .zip(&moved)
                        .map(|(a, b)| a.distance_squared(*b))
                        .sum::<f32>()
                        / n)
                        .sqrt()
                        / h;
                    let spectrum = |t: &[Vec3]| {
                        let scaled: Vec<Vec3> = t.iter().map(|p| *p / h).collect();
                        match DescriptionType::DominatingAxis.describe(&dft, &scaled) {
                            Description::DominatingAxis { spectrum, .. } => spectrum,
                            _ => unreachable!("a dominating-axis description"),
                        }
                    };
                    let spectral = ne(spectrum(&original).amplitude_distance(&spectrum(&moved)));
                    let trace = traced.contains(&leaf).then_some(LeafTrace {
                        leaf,
                        original,
                        billboard: moved,
                    });
                    (rms, spectral, trace)
                })
                .collect()
        })
        .collect();
    let mut out = AnimationError::default();
    let mut count = 0usize;
    for (rms, spectral, trace) in per_billboard.into_iter().flatten() {
        out.rms += rms;
        out.spectral += spectral;
        count += 1;
        out.traces.extend(trace);
    }
    out.traces.sort_by_key(|t| t.leaf);
    out.rms /= count.max(1) as f32;
    out.spectral /= count.max(1) as f32;
    out
}

/// Leaves worth tracing on a tree: the one at the top of the crown, the one farthest out to
/// the side, and one low down (first-found, so the choice is deterministic).
pub fn traced_leaves(foliage: &Foliage) -> Vec<u32> {
    let centres: Vec<Vec3> = foliage
        .leaves
        .iter()
        .map(|l| super::leaf_centroid(&l.corners))
        .collect();
    let pick = |key: &dyn Fn(Vec3) -> f32| {
        (0..centres.len() as u32)
            .max_by(|&a, &b| key(centres[a as usize]).total_cmp(&key(centres[b as usize])))
            .unwrap_or(0)
    };
    let mut out = vec![
        pick(&|c| c.y),
        pick(&|c| c.x * c.x + c.z * c.z),
        pick(&|c| -c.y),
    ];
    out.sort_unstable();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::anim::skinning_over_loop;
    use crate::bake::foliage::billboard::cloud::CloudParams;
    use crate::bake::foliage::billboard::{Grouping, foliage, grouped_cloud};

    /// A cloud per bone at ε = 0 puts every leaf's centroid on its billboard and moves it with
    /// its own bone: no animation error. A whole-crown cloud bound to the trunk loses the
    /// twigs' sway.
    #[test]
    fn per_bone_clouds_at_epsilon_zero_move_exactly() {
        let tree = crate::generate::tree::sapling();
        let f = foliage(&tree).unwrap();
        let frames = skinning_over_loop(&tree, 32);
        let traced = traced_leaves(&f);
        let exact = CloudParams {
            epsilon: 0.0,
            ..Default::default()
        };
        let exact = grouped_cloud(&tree.skeleton, &f, &exact, Grouping::PerBone);
        let e = animation_error(&tree, &f, &exact, None, &frames, &traced);
        assert!(
            e.rms < 1e-4 && e.spectral < 1e-4,
            "{} {}",
            e.rms,
            e.spectral
        );
        assert_eq!(e.traces.len(), traced.len());
        assert_eq!(e.traces[0].original.len(), 32);
        let h = tree_height(&tree);
        let crown = grouped_cloud(
            &tree.skeleton,
            &f,
            &CloudParams {
                epsilon: 0.1 * h,
                ..Default::default()
            },
            Grouping::Subtree { forks: 0 },
        );
        let c = animation_error(&tree, &f, &crown, None, &frames, &[]);
        assert!(
            c.rms > 0.01 && c.spectral > 0.01,
            "{} {}",
            c.rms,
            c.spectral
        );
    }
}

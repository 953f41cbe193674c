//! Common joint rotation (Bennett-Therkildsen, Carlsen & Schmid, "Animated Billboard Clouds for
//! Foliage Simplification", Aalborg University, 2007 §7.1, "CJR"): sibling bones whose leaves move
//! alike share one cloud, bound to one of them, so a skeleton billboard cloud needs fewer
//! billboards.
//!
//! The thesis merges, while there are more than a target number of sets, the pair of sibling
//! sets whose average animations deviate least, and moves each set's foliage onto one rotation;
//! its prototype took the sibling with the most foliage as that rotation. We keep the greedy
//! sibling merging and the prototype's choice, but measure the deviation where it shows: the
//! largest distance, over the loop, between where a leaf goes with its own bone and where it
//! goes with the set's bone. That is a length like the cloud's ε, so the merging stops at ε
//! instead of at a count, and a level's error budget covers both the flattening onto planes and
//! the borrowed motion. (The thesis's axis-angle deviation has the faults its brief lists: a
//! product that is 0 when either factor is, and no sense of where on the branch a leaf hangs.)

use super::Foliage;
use crate::anim::skinning_over_loop;
use crate::model::Model;
use glam::Vec3;

/// Frames of the loop the deviation is measured at.
const FRAMES: usize = 24;

/// The foliage with the leaves of sibling bones that move alike (within `tolerance`, scene
/// units) rebound to one bone of their set: the one with the most leaves.
pub fn merge_siblings(model: &Model, foliage: &Foliage, tolerance: f32) -> Foliage {
    let skeleton = &model.skeleton;
    let bones = skeleton.bone_count();
    let parent = super::BoneTree::new(skeleton).parent;
    // Skinning matrices G_i Ĝ_i⁻¹ at evenly spaced times of the loop.
    let frames = skinning_over_loop(model, FRAMES);
    let centroid = |leaf: usize| {
        let c = &foliage.leaves[leaf].corners;
        c.iter().copied().sum::<Vec3>() / c.len().max(1) as f32
    };
    let mut leaves_of: Vec<Vec<usize>> = vec![Vec::new(); bones];
    for (leaf, &b) in foliage.bones.iter().enumerate() {
        if (b as usize) < bones {
            leaves_of[b as usize].push(leaf);
        }
    }
    // How far the leaves of `set` stray, at worst, when they follow `to` instead of their own
    // bones.
    let deviation = |set: &[u32], to: u32| -> f32 {
        let mut worst = 0.0f32;
        for &b in set.iter().filter(|&&b| b != to) {
            for &leaf in &leaves_of[b as usize] {
                let c = centroid(leaf);
                for m in &frames {
                    let d = m[b as usize].transform_point3(c) - m[to as usize].transform_point3(c);
                    worst = worst.max(d.length());
                }
            }
        }
        worst
    };
    let representative = |set: &[u32]| {
        *set.iter()
            .max_by_key(|&&b| (leaves_of[b as usize].len(), std::cmp::Reverse(b)))
            .expect("sets are not empty")
    };
    // One set per bone with leaves, grouped by parent: only siblings merge.
    let mut family: std::collections::BTreeMap<Option<u32>, Vec<Vec<u32>>> = Default::default();
    for b in (0..bones as u32).filter(|&b| !leaves_of[b as usize].is_empty()) {
        family.entry(parent[b as usize]).or_default().push(vec![b]);
    }
    let mut bone_of = foliage.bones.clone();
    for sets in family.values_mut() {
        // Greedy: merge the pair of sets whose union strays least, while within tolerance.
        loop {
            let mut best: Option<(f32, usize, usize)> = None;
            for i in 0..sets.len() {
                for j in i + 1..sets.len() {
                    let union: Vec<u32> = sets[i].iter().chain(&sets[j]).copied().collect();
                    let d = deviation(&union, representative(&union));
                    if d <= tolerance && best.is_none_or(|(e, _, _)| d < e) {
                        best = Some((d, i, j));
                    }
                }
            }
            let Some((_, i, j)) = best else {
                break;
            };
            let merged = sets.swap_remove(j);
            sets[i].extend(merged);
        }
        for set in sets.iter() {
            let to = representative(set);
            for &b in set {
                for &leaf in &leaves_of[b as usize] {
                    bone_of[leaf] = to;
                }
            }
        }
    }
    Foliage {
        bones: bone_of,
        ..foliage.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::anim::bone_matrices;
    use crate::generate::tree::sapling;
    use glam::Affine3A;

    /// With no tolerance nothing merges; with a generous one, sibling leaves share bones, every
    /// leaf's new bone is its own or a sibling of it, and the measured stray stays within the
    /// tolerance.
    #[test]
    fn siblings_merge_within_tolerance_only() {
        let tree = sapling();
        let f = super::super::foliage(&tree).unwrap();
        assert_eq!(merge_siblings(&tree, &f, 0.0).bones, f.bones);
        let parent = super::super::BoneTree::new(&tree.skeleton).parent;
        let distinct = |bones: &[u32]| bones.iter().collect::<std::collections::HashSet<_>>().len();
        let tolerance = 0.05 * super::super::tree_height(&tree);
        let merged = merge_siblings(&tree, &f, tolerance);
        assert!(
            distinct(&merged.bones) < distinct(&f.bones),
            "{} bones before and after",
            distinct(&f.bones)
        );
        let clip = tree.clips.first();
        for (leaf, (&was, &now)) in f.bones.iter().zip(&merged.bones).enumerate() {
            assert_eq!(parent[was as usize], parent[now as usize], "leaf {leaf}");
            let c = f.leaves[leaf].corners.iter().copied().sum::<Vec3>() / 4.0;
            for k in 0..10 {
                let t = clip.unwrap().duration * k as f32 / 10.0;
                let g = bone_matrices(&tree.skeleton, clip, t);
                let at = |b: u32| {
                    (g[b as usize] * Affine3A::from_mat4(tree.skeleton.inverse_bind[b as usize]))
                        .transform_point3(c)
                };
                // Between the measured frames the stray may exceed the bound a little.
                assert!(
                    (at(was) - at(now)).length() <= tolerance * 1.2,
                    "leaf {leaf}"
                );
            }
        }
    }
}

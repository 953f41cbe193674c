//! Spectral clustering (Bennett-Therkildsen, Carlsen & Schmid's thesis "Animated Billboard Clouds
//! for Foliage Simplification" (2007) §6.2 and App. C.1): leaves grouped by how they move, k-means
//! with a description type's `deviation` as the distance and its `average` as the centroid.
//!
//! Initialisation follows App. C.1: one cluster per foliage-bearing bone, then the pair of
//! clusters whose averages deviate least is merged until there are k, or the cluster with the
//! largest variance is split by its leaves' distance from their bone's joint (leaves with
//! equal lever arms move alike) until there are k. Random restarts (k distinct leaves as
//! centroids) run as well, and the clustering with the lowest total squared deviation is
//! kept (§6.2, Eq. 3.1). Items carry weights, so that animation zones (App. C.2, see
//! [`super::Zones`]) count for the leaves they hold.

use super::description::{Description, DescriptionType};
use rayon::prelude::*;

/// How to cluster.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterParams {
    pub k: usize,
    /// Random initialisations tried besides the skeleton's.
    pub restarts: usize,
    pub max_iterations: usize,
    pub seed: u64,
}

impl Default for ClusterParams {
    fn default() -> Self {
        ClusterParams {
            k: 16,
            restarts: 2,
            max_iterations: 40,
            seed: 1,
        }
    }
}

/// A clustering of descriptions.
#[derive(Clone, Debug, PartialEq)]
pub struct Clusters {
    /// The cluster of every item.
    pub of: Vec<u32>,
    /// Every cluster's average description.
    pub centroids: Vec<Description>,
    /// Σ deviation(item, its centroid)².
    pub error: f32,
}

/// Clusters `items` (descriptions of one type, each standing for `weights` leaves: 1, or an
/// animation zone's count) into at most `params.k` clusters. `bones` and `lever` give every
/// item's bone and its distance from that bone's joint, for the skeleton initialisation.
pub fn cluster(
    kind: DescriptionType,
    items: &[Description],
    weights: &[f32],
    bones: &[u32],
    lever: &[f32],
    params: &ClusterParams,
) -> Clusters {
    let k = params.k.clamp(1, items.len().max(1));
    if items.is_empty() {
        return Clusters {
            of: Vec::new(),
            centroids: Vec::new(),
            error: 0.0,
        };
    }
    let start = skeleton_start(kind, items, weights, bones, lever, k);
    let mut best = k_means(kind, items, weights, start, params);
    let mut rng = fastrand::Rng::with_seed(params.seed);
    for _ in 0..params.restarts {
        let mut picks: Vec<usize> = (0..items.len()).collect();
        rng.shuffle(&mut picks);
        let start: Vec<u32> = nearest_assignment(
            items,
            &picks[..k]
                .iter()
                .map(|&i| items[i].clone())
                .collect::<Vec<_>>(),
        );
        let c = k_means(kind, items, weights, start, params);
        if c.error < best.error {
            best = c;
        }
    }
    best
}

/// The skeleton initialisation of App. C.1, as a cluster per item.
pub fn skeleton_start(
    kind: DescriptionType,
    items: &[Description],
    weights: &[f32],
    bones: &[u32],
    lever: &[f32],
    k: usize,
) -> Vec<u32> {
    // One group per bone.
    let mut groups: Vec<Vec<usize>> = {
        let mut by_bone: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
        for (i, &b) in bones.iter().enumerate().take(items.len()) {
            by_bone.entry(b).or_default().push(i);
        }
        by_bone.into_values().collect()
    };
    let average = |g: &[usize]| -> Description {
        let members: Vec<(&Description, f32)> =
            g.iter().map(|&i| (&items[i], weight(weights, i))).collect();
        kind.average(&members)
    };
    let mut centres: Vec<Description> = groups.par_iter().map(|g| average(g)).collect();
    // Merge: the pair whose averages deviate least, with the deviations cached.
    if groups.len() > k {
        let n = groups.len();
        let mut dev: Vec<Vec<f32>> = (0..n)
            .into_par_iter()
            .map(|i| {
                (0..n)
                    .map(|j| {
                        if j > i {
                            centres[i].deviation(&centres[j])
                        } else {
                            f32::INFINITY
                        }
                    })
                    .collect()
            })
            .collect();
        let mut alive = vec![true; n];
        let mut count = n;
        while count > k {
            let mut pick = (f32::INFINITY, 0, 0);
            for i in (0..n).filter(|&i| alive[i]) {
                for j in (i + 1..n).filter(|&j| alive[j]) {
                    if dev[i][j] < pick.0 {
                        pick = (dev[i][j], i, j);
                    }
                }
            }
            let (_, i, j) = pick;
            let moved = std::mem::take(&mut groups[j]);
            groups[i].extend(moved);
            alive[j] = false;
            count -= 1;
            centres[i] = average(&groups[i]);
            for other in (0..n).filter(|&o| alive[o] && o != i) {
                let d = centres[i].deviation(&centres[other]);
                if other > i {
                    dev[i][other] = d;
                } else {
                    dev[other][i] = d;
                }
            }
        }
        let kept: Vec<usize> = (0..n).filter(|&i| alive[i]).collect();
        groups = kept
            .iter()
            .map(|&i| std::mem::take(&mut groups[i]))
            .collect();
        centres = kept.iter().map(|&i| centres[i].clone()).collect();
    }
    // Split: the cluster with the largest variance, by lever arm about its mean.
    while groups.len() < k {
        let variance = |g: &[usize], c: &Description| -> f32 {
            let w: f32 = g.iter().map(|&i| weight(weights, i)).sum();
            g.iter()
                .map(|&i| weight(weights, i) * items[i].deviation(c).powi(2))
                .sum::<f32>()
                / w.max(1e-9)
        };
        let Some(worst) = (0..groups.len())
            .filter(|&g| groups[g].len() > 1)
            .max_by(|&a, &b| {
                variance(&groups[a], &centres[a]).total_cmp(&variance(&groups[b], &centres[b]))
            })
        else {
            break;
        };
        let mut g = std::mem::take(&mut groups[worst]);
        g.sort_by(|&a, &b| lever[a].total_cmp(&lever[b]));
        let mean = g.iter().map(|&i| lever[i]).sum::<f32>() / g.len() as f32;
        let mut cut = g.partition_point(|&i| lever[i] <= mean);
        if cut == 0 || cut == g.len() {
            cut = g.len() / 2;
        }
        let far = g.split_off(cut);
        centres[worst] = average(&g);
        groups[worst] = g;
        centres.push(average(&far));
        groups.push(far);
    }
    let mut of = vec![0u32; items.len()];
    for (c, g) in groups.iter().enumerate() {
        for &i in g {
            of[i] = c as u32;
        }
    }
    of
}

/// Every item's nearest centre.
fn nearest_assignment(items: &[Description], centres: &[Description]) -> Vec<u32> {
    items
        .par_iter()
        .map(|d| {
            (0..centres.len())
                .min_by(|&a, &b| {
                    d.deviation(&centres[a])
                        .total_cmp(&d.deviation(&centres[b]))
                })
                .unwrap_or(0) as u32
        })
        .collect()
}

/// Item `i`'s weight (1 where none is given).
fn weight(weights: &[f32], i: usize) -> f32 {
    weights.get(i).copied().unwrap_or(1.0)
}

/// Every cluster's average, for the assignment `of` into `k` clusters.
fn centroids(
    kind: DescriptionType,
    items: &[Description],
    weights: &[f32],
    of: &[u32],
    k: usize,
) -> Vec<Description> {
    (0..k)
        .into_par_iter()
        .map(|c| {
            let members: Vec<(&Description, f32)> = items
                .iter()
                .zip(of)
                .enumerate()
                .filter(|(_, (_, o))| **o as usize == c)
                .map(|(i, (d, _))| (d, weight(weights, i)))
                .collect();
            kind.average(&members)
        })
        .collect()
}

/// Lloyd's iterations from the assignment `of`.
fn k_means(
    kind: DescriptionType,
    items: &[Description],
    weights: &[f32],
    mut of: Vec<u32>,
    params: &ClusterParams,
) -> Clusters {
    let k = of.iter().max().map_or(0, |&m| m as usize + 1);
    for _ in 0..params.max_iterations.max(1) {
        let mut centres = centroids(kind, items, weights, &of, k);
        // An emptied cluster takes the item farthest from its centre.
        for c in 0..k {
            if !of.iter().any(|&o| o as usize == c) {
                let stray = |i: usize| items[i].deviation(&centres[of[i] as usize]);
                let far = (0..items.len())
                    .max_by(|&a, &b| stray(a).total_cmp(&stray(b)))
                    .unwrap_or(0);
                of[far] = c as u32;
                centres[c] = items[far].clone();
            }
        }
        let next = nearest_assignment(items, &centres);
        if next == of {
            break;
        }
        of = next;
    }
    let centroids = centroids(kind, items, weights, &of, k);
    let error = items
        .iter()
        .zip(&of)
        .enumerate()
        .map(|(i, (d, &o))| weight(weights, i) * d.deviation(&centroids[o as usize]).powi(2))
        .sum();
    Clusters {
        of,
        centroids,
        error,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::foliage::spectral::dft::Dft;
    use glam::Vec3;
    use std::f32::consts::TAU;

    /// Leaves of two kinds: slow wide sways on bones 0 and 1, fast small flutters on bones 2
    /// and 3, with scattered time shifts and amplitudes.
    fn leaves() -> (Vec<Vec<Vec3>>, Vec<u32>, Vec<f32>) {
        let mut rng = fastrand::Rng::with_seed(9);
        let (mut tr, mut bones, mut lever) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..80 {
            let fast = i % 2 == 1;
            let (cycles, amp) = if fast { (7.0, 0.03) } else { (2.0, 0.3) };
            let amp = amp * (0.8 + 0.4 * rng.f32());
            let shift = rng.f32();
            tr.push(
                (0..32)
                    .map(|n| {
                        let t = n as f32 / 32.0 + shift;
                        Vec3::new(
                            amp * (TAU * cycles * t).cos(),
                            0.0,
                            0.5 * amp * (TAU * cycles * t + 0.3).cos(),
                        )
                    })
                    .collect(),
            );
            bones.push(2 * fast as u32 + (i % 4 >= 2) as u32);
            lever.push(rng.f32());
        }
        (tr, bones, lever)
    }

    #[test]
    fn leaves_that_move_alike_cluster_together() {
        let (tr, bones, lever) = leaves();
        let dft = Dft::new(32);
        for kind in [DescriptionType::DominatingAxis, DescriptionType::AxisPhase] {
            let items: Vec<Description> = tr.iter().map(|t| kind.describe(&dft, t)).collect();
            let params = ClusterParams {
                k: 2,
                ..Default::default()
            };
            let c = cluster(kind, &items, &[], &bones, &lever, &params);
            assert_eq!(c.centroids.len(), 2);
            for (i, &o) in c.of.iter().enumerate() {
                assert_eq!(o == c.of[1], i % 2 == 1, "{}: leaf {i}", kind.name());
            }
            // Deterministic.
            assert_eq!(cluster(kind, &items, &[], &bones, &lever, &params), c);
        }
    }

    /// App. C.1: one cluster per bone when k is the bone count; merged or split to k.
    #[test]
    fn the_skeleton_start_has_k_clusters_made_of_bones() {
        let (tr, bones, lever) = leaves();
        let dft = Dft::new(32);
        let kind = DescriptionType::AxisPhase;
        let items: Vec<Description> = tr.iter().map(|t| kind.describe(&dft, t)).collect();
        for k in [1, 2, 4, 6, 9] {
            let of = skeleton_start(kind, &items, &[], &bones, &lever, k);
            let used: std::collections::BTreeSet<u32> = of.iter().copied().collect();
            assert_eq!(used.len(), k, "k = {k}");
            if k <= 4 {
                // Whole bones stay together.
                for (i, j) in (0..80).flat_map(|i| (0..80).map(move |j| (i, j))) {
                    if bones[i] == bones[j] {
                        assert_eq!(of[i], of[j]);
                    }
                }
            }
            if k == 2 {
                // The slow bones merge with each other, the fast with each other.
                assert_eq!(of[0], of[2]);
                assert_eq!(of[1], of[3]);
                assert_ne!(of[0], of[1]);
            }
        }
    }
}

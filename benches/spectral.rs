//! Spectral analysis and clustering of the demo trees' leaves (thesis Ch. 4, §6.1–6.3):
//! `cargo bench --bench spectral`. Times sampling the trajectories, describing every leaf (or
//! every animation zone, App. C.2) by each description type, and k-means into k clusters, and
//! prints the clustering error (Σ weight · deviation², so zones count for their leaves).
//! Then times a whole spectral cloud (analysis, clustering, clouds and every billboard's
//! lines) of a broadleaf grown to about 10,000 leaves.

use anyhow::{Result, anyhow};
use lodlab::bake::foliage::billboard::{foliage, tree_height};
use lodlab::bake::foliage::spectral::cluster::{ClusterParams, cluster};
use lodlab::bake::foliage::spectral::description::{Description, DescriptionType};
use lodlab::bake::foliage::spectral::dft::Dft;
use lodlab::bake::foliage::spectral::{DEFAULT_SAMPLES, Zones, leaf_centroid, trajectories};
use rayon::prelude::*;
use std::time::Instant;

fn main() -> Result<()> {
    {
        use lodlab::bake::foliage::billboard::cloud::CloudParams;
        use lodlab::bake::foliage::spectral::cloud::{SpectralParams, spectral_cloud};
        let tree = lodlab::generate::tree::dense_broadleaf(93);
        let f = foliage(&tree).map_err(|e| anyhow!(e))?;
        let h = tree_height(&tree);
        println!(
            "{}: {} leaves; whole spectral cloud at ε 0.32 h (zones of 0.03 h):",
            tree.name,
            f.leaves.len()
        );
        println!(
            "{:<16} {:>4} {:>11} {:>11}",
            "type", "k", "billboards", "seconds"
        );
        for kind in DescriptionType::ALL {
            for k in [16, 64] {
                let start = Instant::now();
                let c = spectral_cloud(
                    &tree,
                    &f,
                    &CloudParams {
                        epsilon: 0.32 * h,
                        ..Default::default()
                    },
                    &SpectralParams {
                        kind,
                        clusters: k,
                        ..Default::default()
                    },
                );
                println!(
                    "{:<16} {k:>4} {:>11} {:>11.3}",
                    kind.name(),
                    c.cloud.billboards.len(),
                    start.elapsed().as_secs_f64()
                );
            }
        }
    }
    for name in ["broadleaf", "conifer"] {
        let tree = lodlab::import::load_model(name)?;
        let f = foliage(&tree).map_err(|e| anyhow!(e))?;
        for zone_radius in [None, Some(0.03 * tree_height(&tree))] {
            let start = Instant::now();
            // Items: leaves, or animation zones weighted by their leaf count.
            let (points, weights): (Vec<(glam::Vec3, u32)>, Vec<f32>) = match zone_radius {
                None => f
                    .leaves
                    .iter()
                    .zip(&f.bones)
                    .map(|(l, &b)| ((leaf_centroid(&l.corners), b), 1.0))
                    .unzip(),
                Some(r) => {
                    let z = Zones::new(&f, r);
                    (0..z.len())
                        .map(|i| ((z.centre[i], z.bone[i]), z.leaves[i] as f32))
                        .unzip()
                }
            };
            let tr = trajectories(&tree, &points, DEFAULT_SAMPLES);
            let sample_s = start.elapsed().as_secs_f64();
            let what = match zone_radius {
                None => "leaves".to_string(),
                Some(r) => format!("zones of {r:.2} m"),
            };
            println!(
                "\n{name}: {} leaves as {} {what}, {DEFAULT_SAMPLES} samples a loop: trajectories {sample_s:.3} s",
                f.leaves.len(),
                points.len()
            );
            println!(
                "{:<16} {:>10} {:>4} {:>11} {:>10} {:>9}",
                "type", "describe s", "k", "cluster s", "total s", "error"
            );
            // The distance of every item from the tree's base, standing in for its lever arm.
            let lever: Vec<f32> = points.iter().map(|(p, _)| p.length()).collect();
            let bones: Vec<u32> = points.iter().map(|(_, b)| *b).collect();
            let dft = Dft::new(DEFAULT_SAMPLES);
            for kind in DescriptionType::ALL {
                let start = Instant::now();
                let items: Vec<Description> =
                    tr.par_iter().map(|t| kind.describe(&dft, t)).collect();
                let describe_s = start.elapsed().as_secs_f64();
                for k in [16, 64] {
                    let start = Instant::now();
                    let params = ClusterParams {
                        k,
                        ..Default::default()
                    };
                    let c = cluster(kind, &items, &weights, &bones, &lever, &params);
                    let cluster_s = start.elapsed().as_secs_f64();
                    println!(
                        "{:<16} {describe_s:>10.3} {k:>4} {cluster_s:>11.3} {:>10.3} {:>9.4}",
                        kind.name(),
                        sample_s + describe_s + cluster_s,
                        c.error
                    );
                }
            }
        }
    }
    Ok(())
}

//! Spectral analysis and clustering of the demo trees' leaves (thesis Ch. 4, §6.1–6.3):
//! `cargo bench --bench spectral`. Times sampling the trajectories, describing every leaf by
//! each description type, and k-means into k clusters, and prints the clustering error.

use anyhow::{Result, anyhow};
use lodlab::bake::billboard::foliage;
use lodlab::bake::spectral::cluster::{ClusterParams, cluster};
use lodlab::bake::spectral::description::{Description, DescriptionType};
use lodlab::bake::spectral::dft::Dft;
use lodlab::bake::spectral::{DEFAULT_SAMPLES, leaf_trajectories};
use rayon::prelude::*;
use std::time::Instant;

fn main() -> Result<()> {
    for name in ["broadleaf", "conifer"] {
        let tree = lodlab::import::load_model(name)?;
        let f = foliage(&tree).map_err(|e| anyhow!(e))?;
        let start = Instant::now();
        let tr = leaf_trajectories(&tree, &f, DEFAULT_SAMPLES);
        let sample_s = start.elapsed().as_secs_f64();
        println!(
            "\n{name}: {} leaves, {DEFAULT_SAMPLES} samples a loop: trajectories {sample_s:.3} s",
            f.leaves.len()
        );
        println!(
            "{:<16} {:>10} {:>4} {:>11} {:>10} {:>9}",
            "type", "describe s", "k", "cluster s", "total s", "error"
        );
        // The distance of every leaf from its bone's joint, for the skeleton start.
        let lever: Vec<f32> = (0..f.leaves.len()).map(|i| tr[i][0].length()).collect();
        let dft = Dft::new(DEFAULT_SAMPLES);
        for kind in DescriptionType::ALL {
            let start = Instant::now();
            let items: Vec<Description> = tr.par_iter().map(|t| kind.describe(&dft, t)).collect();
            let describe_s = start.elapsed().as_secs_f64();
            for k in [16, 64] {
                let start = Instant::now();
                let params = ClusterParams {
                    k,
                    ..Default::default()
                };
                let c = cluster(kind, &items, &f.bones, &lever, &params);
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
    Ok(())
}

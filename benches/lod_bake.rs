//! Bake-time and memory figures for the skinned LOD bake (Merry et al. Table 1), as ratios
//! measured in one run: `cargo bench --bench lod_bake`.
//!
//! - every method on the paper's cylinder at about 10k and 50k vertices, on the built-in
//!   horse and walker, on the test models with real-world properties (split-tube, armour,
//!   patchwork) and on the armour at about 60k triangles, one method at a time, best of three;
//!   the whole bake: simplification and cutting the levels (which measures each);
//! - the peak resident memory of the process after the 50k-vertex AS+IS bake.

use lodlab::bake::character::lod::{LodOptions, bake_lods};
use lodlab::bake::character::simplify::Method;
use lodlab::generate::cylinder::bent_cylinder;
use lodlab::model::Model;
use std::time::Instant;

fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn time(model: &Model, method: Method, runs: usize) -> f64 {
    let opts = LodOptions {
        base_error: 1e-3,
        floor_triangles: 100,
        budgets: None,
    };
    (0..runs)
        .map(|_| {
            let start = Instant::now();
            let lods = bake_lods(model, method, &opts, &|_| {});
            std::hint::black_box(&lods);
            start.elapsed().as_secs_f64()
        })
        .fold(f64::MAX, f64::min)
}

fn main() {
    // Memory first, while the process is fresh.
    let big = bent_cylinder(250, 199);
    let before = peak_rss_mb();
    let t = time(&big, Method::InfluenceSimplification, 1);
    println!(
        "cylinder {} vertices, AS+IS: {:.2} s, peak RSS {:.0} MB (before the bake {:.0} MB)",
        big.mesh.vertex_count(),
        t,
        peak_rss_mb().unwrap_or(f64::NAN),
        before.unwrap_or(f64::NAN)
    );
    let mut models = vec![bent_cylinder(100, 99), big];
    for name in ["horse", "walker", "split-tube", "armour", "patchwork"] {
        models.push(lodlab::import::load_model(name).expect("built-in asset"));
    }
    let mut detailed = lodlab::generate::armour::armour_at(2.25);
    detailed.name = "armour ×2.25".into();
    models.push(detailed);
    println!("\n| model | vertices | triangles | 3D (s) | AS (s) | AS+IS (s) | AS/3D | AS+IS/3D |");
    println!("|---|---|---|---|---|---|---|---|");
    for m in &models {
        let runs = if m.mesh.vertex_count() > 20_000 { 1 } else { 3 };
        let t: Vec<f64> = Method::PAPERS.iter().map(|&k| time(m, k, runs)).collect();
        println!(
            "| {} | {} | {} | {:.3} | {:.3} | {:.3} | {:.2} | {:.2} |",
            m.name,
            m.mesh.vertex_count(),
            m.mesh.triangle_count(),
            t[0],
            t[1],
            t[2],
            t[1] / t[0],
            t[2] / t[0]
        );
    }
}

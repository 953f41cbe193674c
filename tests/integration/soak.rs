//! `lodlab soak`, short: two cycles of every setting (method, transition, foliage policy,
//! character count, frame size down to 0×0) on the mixed scene made small (its horses and
//! walkers, and three saplings), with no GPU error, the GPU's memory the same at the same
//! point of each cycle, and the resident set steady. The 10,000-frame run, on the default
//! scene, is `tools/soak.sh`. The sapling stands in for the default scene's two trees: each
//! foliage policy is a chain of its own, and the two trees' six took a minute to bake here,
//! the sapling's three a few seconds.

use std::process::Command;

#[test]
fn two_cycles_of_every_setting_hold_memory_steady() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("soak.csv");
    // 20 phases of 3 frames: a cycle is 60 frames, read at its end twice.
    let out = Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args([
            "soak",
            "--model",
            "horse",
            "--model",
            "walker",
            "--model",
            "sapling",
            "--count",
            "6",
            "--trees",
            "3",
            "--frames",
            "120",
            "--phase-frames",
            "3",
            "--every",
            "60",
            "--size",
            "96x54",
            "--max-growth-mb",
            "40",
            "--cache",
        ])
        .arg(crate::common::shared_cache())
        .arg("--csv")
        .arg(&csv)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("GPU memory the same at every reading after the first cycle"),
        "{stdout}"
    );
    let rows = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(rows.lines().count(), 3, "{rows}");
}

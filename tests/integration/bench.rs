//! `lodlab bench` as a user runs it, on a small scene (lavapipe in CI).

use lodlab::generate::cylinder::bent_cylinder;
use lodlab::generate::glb::to_glb;
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn lodlab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args(args)
        .output()
        .expect("lodlab runs")
}

fn cylinder_glb(dir: &Path) -> String {
    let p = dir.join("cylinder.glb");
    std::fs::write(&p, to_glb(&bent_cylinder(24, 16))).unwrap();
    p.display().to_string()
}

#[test]
fn bench_writes_json_and_a_table_of_every_method() {
    let dir = tempfile::tempdir().unwrap();
    let model = cylinder_glb(dir.path());
    let json = dir.path().join("bench.json");
    let md = dir.path().join("bench.md");
    let cache = dir.path().join("cache");
    let s = |p: &Path| p.display().to_string();
    let out = lodlab(&[
        "bench",
        "--scene",
        "crowd",
        "--model",
        &model,
        "--count",
        "12",
        "--size",
        "160x90",
        "--msaa",
        "1",
        "--frames",
        "3",
        "--warmup",
        "0",
        &format!("--json={}", s(&json)),
        "--markdown",
        &s(&md),
        "--cache",
        &s(&cache),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}\n{stdout}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(!r["adapter"].as_str().unwrap().is_empty());
    assert!(!r["backend"].as_str().unwrap().is_empty());
    assert_eq!(r["size"], serde_json::json!([160, 90]));
    assert_eq!(r["scene"], "crowd");
    assert_eq!(r["instances"], 12);
    assert_eq!(r["frames_per_method"], 3);
    assert_eq!(r["schema_version"], 3);
    assert!(r["measured_seconds"].as_f64().unwrap() > 0.0);
    assert!(r["warmup_seconds"].as_f64().unwrap() >= 0.0);
    // Once warm it says how long the rest takes: the other coverage views, then the frames.
    let stderr = String::from_utf8_lossy(&out.stderr);
    let rest = stderr
        .lines()
        .find(|l| l.starts_with("lodlab: bench: about "))
        .unwrap_or_else(|| panic!("no announcement: {stderr}"));
    assert!(
        rest.contains("the other 3 coverage views a method")
            && rest.contains("measuring 3 frames of each of 4 methods"),
        "{rest}"
    );
    assert!(r["announced_seconds"].as_f64().unwrap() > 0.0);
    assert!(r["rest_seconds"].as_f64().unwrap() > 0.0);
    assert!(stdout.contains("measured for"), "{stdout}");
    assert!(stdout.contains("CPU per frame"), "{stdout}");
    assert!(r["calibration"]["triangles_per_second"].as_f64().unwrap() > 0.0);
    assert_eq!(r["calibration"]["method"], "none");
    let methods = r["methods"].as_object().unwrap();
    assert_eq!(methods.len(), 4);
    let full = bent_cylinder(24, 16).mesh.indices.len() as u64 / 3;
    for name in ["none", "rest-pose", "as", "as+is"] {
        let m = &methods[name];
        let f = |k: &str| m[k].as_f64().unwrap_or_else(|| panic!("{name}: {k}"));
        assert!(f("p5_ms") > 0.0 && f("p5_ms") <= f("median_ms"), "{name}");
        assert!(f("median_ms") <= f("p95_ms"), "{name}");
        // Both written to six significant digits.
        assert!(
            (f("fps") * f("median_ms") / 1000.0 - 1.0).abs() < 1e-5,
            "{name}"
        );
        // Every frame's own time, the median among them.
        let frames: Vec<f64> = m["frame_ms"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(frames.len(), 3, "{name}");
        assert!(frames.contains(&f("median_ms")), "{name}: {frames:?}");
        assert!(f("efficiency") > 0.0 && f("calibration_ms") > 0.0, "{name}");
        // The CPU's share of a frame: selection and upload take some time, and far less than
        // a second for a dozen instances.
        assert!(
            f("cpu_ms") > 0.0 && f("cpu_ms") < 1000.0,
            "{name}: {}",
            f("cpu_ms")
        );
        let triangles = m["triangles"].as_u64().unwrap();
        assert!(
            triangles > 0 && triangles <= 12 * full,
            "{name}: {triangles}"
        );
        assert!(m["vertices"].as_u64().unwrap() > 0);
        assert!(m["influences"].as_u64().unwrap() > 0);
        let histogram: Vec<u64> = m["lod_histogram"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect();
        assert!(histogram.iter().sum::<u64>() > 0, "{name}");
        if name == "none" {
            assert_eq!(histogram.len(), 1, "full detail is level 0 only");
            // Whole characters at full detail (both are means over the frames).
            assert!(
                triangles.abs_diff(histogram[0] * full) <= full,
                "{triangles}"
            );
        }
        assert!(
            stdout
                .lines()
                .any(|l| l.starts_with(&format!("| {name} |"))),
            "{stdout}"
        );
    }
    // Where the frame goes, pass by pass, where the adapter has timestamp queries (lavapipe
    // has them).
    if r["timing"] == "gpu timestamps" {
        for name in ["none", "as+is"] {
            let passes = methods[name]["passes"].as_object().unwrap();
            for pass in ["characters", "sky and ground"] {
                let ms = passes[pass]
                    .as_f64()
                    .unwrap_or_else(|| panic!("{name}: {pass}"));
                assert!(ms > 0.0, "{name}: {pass} {ms}");
            }
            assert!(
                !passes.contains_key("ui") && !passes.contains_key("transitions"),
                "only what a frame draws: {passes:?}"
            );
            let sum: f64 = passes.values().map(|v| v.as_f64().unwrap()).sum();
            let frame = methods[name]["median_ms"].as_f64().unwrap();
            assert!(
                sum <= 2.0 * frame,
                "{name}: passes {sum} ms, frame {frame} ms"
            );
        }
        assert!(stdout.contains("GPU time by pass"), "{stdout}");
        // Where fragments are counted, each pass's against the pixels it covers: every
        // covered pixel is shaded at least once, and never more pixels than the view.
        if methods["none"]["overdraw"].is_number() {
            for name in ["none", "as+is"] {
                let c = &methods[name]["fragments_by_pass"]["characters"];
                let f = |k: &str| c[k].as_f64().unwrap_or_else(|| panic!("{name}: {k} {c}"));
                assert!(f("covered") > 0.0 && f("covered") <= 1.0, "{name}: {c}");
                assert!(f("per_covered_pixel") >= 1.0, "{name}: {c}");
                assert!(f("per_covered_pixel") >= f("per_pixel"), "{name}: {c}");
            }
            assert!(stdout.contains("Fragments by pass"), "{stdout}");
        }
    } else {
        assert!(methods["none"]["passes"].as_object().unwrap().is_empty());
    }
    // Every instance drawn is a character's mesh here, counted once by its kind.
    for name in ["none", "as+is"] {
        let kinds = methods[name]["instances_by_kind"].as_object().unwrap();
        assert_eq!(
            kinds.keys().collect::<Vec<_>>(),
            ["mesh"],
            "{name}: {kinds:?}"
        );
        let drawn: u64 = methods[name]["lod_histogram"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .sum();
        let meshes = kinds["mesh"].as_f64().unwrap();
        assert!(
            (meshes - drawn as f64).abs() <= 1.0 + drawn as f64 * 0.05,
            "{name}: {meshes} meshes, {drawn} drawn"
        );
    }
    assert!(stdout.contains("Instances by level kind"), "{stdout}");
    // Levels of detail never draw more than full detail along the same frames.
    let none = methods["none"]["triangles"].as_u64().unwrap();
    assert!(methods["as+is"]["triangles"].as_u64().unwrap() <= none);
    // The Markdown file is the table printed.
    assert_eq!(std::fs::read_to_string(&md).unwrap(), stdout);
}

#[test]
fn bench_refuses_an_unwritable_output_before_measuring() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("missing").join("bench.json");
    let out = lodlab(&[
        "bench",
        &format!("--json={}", json.display()),
        "--frames",
        "1",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("bench.json"), "{err}");
}

/// A forest's trees are counted by what their levels show (clouds, clumps, impostors), and
/// the foliage pass's fragments against the pixels the trees cover: a small share of the view
/// shaded several times over.
#[test]
fn bench_counts_trees_by_level_kind_and_foliage_by_covered_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("bench.json");
    let cache = crate::common::shared_cache();
    let out = lodlab(&[
        "bench",
        "--scene",
        "forest",
        "--count",
        "16",
        "--methods",
        "as+is",
        "--size",
        "240x135",
        "--msaa",
        "1",
        "--frames",
        "2",
        "--warmup",
        "0",
        &format!("--json={}", json.display()),
        "--cache",
        &cache.display().to_string(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}\n{stdout}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let m = &r["methods"]["as+is"];
    let kinds = m["instances_by_kind"].as_object().unwrap();
    let trees = ["full tree", "cloud", "clumps", "tree impostor"];
    assert!(!kinds.is_empty(), "{kinds:?}");
    assert!(
        kinds.keys().all(|k| trees.contains(&k.as_str())),
        "only trees in a forest: {kinds:?}"
    );
    // Trees far along the forest are coarser than those near: more than one kind.
    assert!(kinds.len() >= 2, "{kinds:?}");
    if r["timing"] == "gpu timestamps" && m["overdraw"].is_number() {
        let foliage = &m["fragments_by_pass"]["foliage"];
        let f = |k: &str| {
            foliage[k]
                .as_f64()
                .unwrap_or_else(|| panic!("{k}: {foliage}"))
        };
        assert!(f("covered") > 0.0 && f("covered") < 1.0, "{foliage}");
        assert!(f("per_covered_pixel") > f("per_pixel"), "{foliage}");
        assert!(
            (f("per_pixel") / f("covered") - f("per_covered_pixel")).abs()
                <= 0.5 * f("per_covered_pixel"),
            "the three figures agree: {foliage}"
        );
        // Each kind drawn alone is a tree kind and shades some foliage, but not far more than
        // the whole foliage pass (alone, nothing in front of it is drawn to hide it, hence
        // the margin).
        let alone = m["cost_by_kind"].as_object().unwrap();
        assert!(!alone.is_empty(), "{m}");
        for (kind, figures) in alone {
            assert!(trees.contains(&kind.as_str()), "{kind}");
            let x = figures[1].as_f64().unwrap();
            assert!(
                x > 0.0 && x <= f("per_pixel") * 4.0,
                "{kind}: {figures} against {foliage}"
            );
        }
    }
}

/// Ctrl-C in a long benchmark stops it at once with 130, saying so in one line (it exited
/// silently), and leaves no half-written output behind.
#[test]
fn an_interrupted_bench_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("b.json");
    let child = Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args([
            "bench",
            "--scene",
            "crowd",
            "--count",
            "4",
            "--size",
            "160x90",
            "--seconds",
            "120",
        ])
        .arg(format!("--json={}", json.display()))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_secs(4));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert_eq!(
        err.trim_end().lines().last(),
        Some("lodlab: interrupted"),
        "{err}"
    );
    assert!(!json.exists());
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert!(left.is_empty(), "{left:?}");
}

/// `--seconds` bounds the measuring, which the bench announces before it starts, with at
/// least six frames of each method for a median; `--no-coverage` leaves out the fragment and
/// level-kind views.
#[test]
fn bench_says_what_it_will_measure_and_can_leave_out_the_coverage() {
    let dir = tempfile::tempdir().unwrap();
    let model = cylinder_glb(dir.path());
    let json = dir.path().join("bench.json");
    let cache = dir.path().join("cache");
    let s = |p: &Path| p.display().to_string();
    let out = lodlab(&[
        "bench",
        "--scene",
        "crowd",
        "--model",
        &model,
        "--count",
        "4",
        "--size",
        "96x54",
        "--msaa",
        "1",
        "--methods",
        "none,as",
        "--seconds",
        "0.5",
        "--warmup",
        "0",
        "--no-coverage",
        &format!("--json={}", s(&json)),
        "--cache",
        &s(&cache),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let announced = stderr
        .lines()
        .find(|l| l.starts_with("lodlab: bench: about "))
        .unwrap_or_else(|| panic!("no announcement: {stderr}"));
    assert!(
        announced.contains("s more: measuring") && announced.contains("2 methods"),
        "{announced}"
    );
    assert!(!stderr.contains("coverage"), "{stderr}");
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let n = r["frames_per_method"].as_u64().unwrap();
    assert!(n >= 6, "{n} frames");
    assert_eq!(r["coverage_seconds"], 0.0);
    assert!(r["announced_seconds"].as_f64().unwrap() > 0.0);
    for m in ["none", "as"] {
        let m = &r["methods"][m];
        assert_eq!(m["frame_ms"].as_array().unwrap().len() as u64, n);
        assert!(m.get("fragments_by_pass").is_none(), "{m}");
        assert!(m.get("cost_by_kind").is_none(), "{m}");
    }
}

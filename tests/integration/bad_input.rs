//! Bad input gets one line naming the file and the problem, exit code 1, and no panic.

use crate::common::{edit_glb, tiny_model};
use lodlab::generate::glb::to_glb;
use lodlab::import::gltf::load;
use lodlab::model::Influence;
use std::path::{Path, PathBuf};
use std::process::Command;

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Loads `path`, expecting an error that names the file, says `problem`, on one line.
fn expect_error(path: &Path, problem: &str) -> String {
    let err = load(path)
        .expect_err("broken input must not load")
        .to_string();
    assert!(err.starts_with(&path.display().to_string()), "{err}");
    assert!(err.contains(problem), "expected '{problem}' in: {err}");
    assert!(!err.contains('\n'), "{err}");
    eprintln!("{err}");
    err
}

#[test]
fn the_tiny_model_itself_loads() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "tiny.glb", &to_glb(&tiny_model()));
    let m = load(&p).unwrap();
    assert_eq!(m.mesh.vertex_count(), 10);
    assert_eq!(m.clips[0].name, "bend");
}

#[test]
fn missing_file_and_directory() {
    let dir = tempfile::tempdir().unwrap();
    expect_error(&dir.path().join("nope.glb"), "no such file");
    expect_error(dir.path(), "is a directory");
}

#[test]
fn truncated_and_non_gltf_files() {
    let dir = tempfile::tempdir().unwrap();
    let glb = to_glb(&tiny_model());
    expect_error(
        &write(dir.path(), "cut.glb", &glb[..glb.len() / 2]),
        "truncated or corrupt",
    );
    expect_error(
        &write(dir.path(), "notes.gltf", b"these are my notes, not a model"),
        "not a glTF file",
    );
    expect_error(
        &write(dir.path(), "empty.glb", b""),
        "is empty, not a glTF file",
    );
}

/// A file without a skin loads as a prop (see tests/integration/import_features.rs); one without any mesh
/// in its scene is one line.
#[test]
fn gltf_without_a_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let glb = edit_glb(&to_glb(&tiny_model()), |j| {
        j.as_object_mut().unwrap().remove("skins");
        for n in j["nodes"].as_array_mut().unwrap() {
            let n = n.as_object_mut().unwrap();
            n.remove("skin");
            n.remove("mesh");
        }
    });
    expect_error(&write(dir.path(), "empty-scene.glb", &glb), "has no mesh");
}

#[test]
fn bad_joint_indices_and_weights() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, Influence, &str); 4] = [
        (
            "range.glb",
            Influence {
                bone: 7,
                weight: 1.0,
            },
            "uses joint index 7, but the skin has only 2 joints",
        ),
        (
            "nan.glb",
            Influence {
                bone: 0,
                weight: f32::NAN,
            },
            "has a NaN weight",
        ),
        (
            "negative.glb",
            Influence {
                bone: 0,
                weight: -0.5,
            },
            "has an invalid weight -0.5",
        ),
        (
            "zero.glb",
            Influence {
                bone: 0,
                weight: 0.0,
            },
            "has all-zero skin weights",
        ),
    ];
    for (name, bad, problem) in cases {
        let mut m = tiny_model();
        // Vertex 0 gets the bad influence as its only one.
        m.mesh.influences[0] = bad;
        let err = expect_error(&write(dir.path(), name, &to_glb(&m)), problem);
        assert!(err.contains("vertex 0"), "{err}");
    }
}

#[test]
fn unsupported_features() {
    let dir = tempfile::tempdir().unwrap();
    let glb = to_glb(&tiny_model());
    let draco = edit_glb(&glb, |j| {
        j["extensionsUsed"] = serde_json::json!(["KHR_draco_mesh_compression"]);
        j["extensionsRequired"] = serde_json::json!(["KHR_draco_mesh_compression"]);
    });
    expect_error(
        &write(dir.path(), "draco.glb", &draco),
        "KHR_draco_mesh_compression",
    );
    let lines = edit_glb(&glb, |j| {
        j["meshes"][0]["primitives"][0]["mode"] = serde_json::json!(1)
    });
    expect_error(
        &write(dir.path(), "lines.glb", &lines),
        "not supported (triangles only)",
    );
}

#[test]
fn gltf_with_a_missing_external_buffer() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = to_glb(&tiny_model());
    let glb = gltf::binary::Glb::from_slice(&bytes).unwrap();
    let mut json: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
    json["buffers"][0]["uri"] = serde_json::json!("tiny.bin");
    let p = write(
        dir.path(),
        "external.gltf",
        &serde_json::to_vec(&json).unwrap(),
    );
    expect_error(&p, "refers to tiny.bin, which cannot be read");
}

#[test]
fn gltf_with_an_external_buffer_loads() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = to_glb(&tiny_model());
    let glb = gltf::binary::Glb::from_slice(&bytes).unwrap();
    let mut json: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
    json["buffers"][0]["uri"] = serde_json::json!("tiny.bin");
    write(dir.path(), "tiny.bin", glb.bin.as_ref().unwrap());
    let p = write(
        dir.path(),
        "external.gltf",
        &serde_json::to_vec(&json).unwrap(),
    );
    assert_eq!(load(&p).unwrap().mesh.triangle_count(), 8);
}

#[test]
fn cli_refuses_an_unwritable_output_before_rendering() {
    let out = Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args([
            "shot",
            "--scene",
            "crowd",
            "--count",
            "1",
            "--out",
            "/no/such/folder/x.png",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("/no/such/folder/x.png") && stderr.contains("does not exist"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("adapter"),
        "it must fail before opening the GPU: {stderr}"
    );
}

/// The command line: one line on stderr, exit code 1, no panic, for every broken file.
#[test]
fn cli_reports_bad_models_in_one_line_with_exit_code_1() {
    let dir = tempfile::tempdir().unwrap();
    let glb = to_glb(&tiny_model());
    let mut nan = tiny_model();
    nan.mesh.influences[0].weight = f32::NAN;
    let files = [
        dir.path().join("missing.glb"),
        write(dir.path(), "cut.glb", &glb[..40]),
        write(dir.path(), "nan.glb", &to_glb(&nan)),
    ];
    let out_png = dir.path().join("out.png");
    for f in &files {
        let out = Command::new(env!("CARGO_BIN_EXE_lodlab"))
            .args(["shot", "--scene", "crowd", "--count", "3", "--out"])
            .arg(&out_png)
            .arg("--model")
            .arg(f)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{}: {stderr}", f.display());
        let lines: Vec<&str> = stderr
            .lines()
            .filter(|l| !l.contains("XDG_RUNTIME_DIR"))
            .collect();
        assert_eq!(lines.len(), 1, "{stderr}");
        assert!(lines[0].contains(&*f.display().to_string()), "{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(!out_png.exists(), "no output may be written for bad input");
    }
}

/// More characters than the device's instance buffer can hold (issue 20): one line naming the
/// count and the limit, exit code 1, no panic (it was a wgpu validation panic, and a capacity
/// overflow for the largest count), and no picture.
#[test]
fn cli_refuses_more_instances_than_the_adapter_holds() {
    let dir = tempfile::tempdir().unwrap();
    let out_png = dir.path().join("out.png");
    for count in ["10000000", "18446744073709551615"] {
        let out = Command::new(env!("CARGO_BIN_EXE_lodlab"))
            .args(["shot", "--scene", "crowd", "--count", count, "--out"])
            .arg(&out_png)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "--count {count}: {stderr}");
        // A container without XDG_RUNTIME_DIR has the Vulkan loader's window-system probe
        // print its own "error:" lines; they are not lodlab's.
        let errors: Vec<&str> = stderr
            .lines()
            .filter(|l| l.starts_with("error") && !l.contains("XDG_RUNTIME_DIR"))
            .collect();
        assert_eq!(errors.len(), 1, "{stderr}");
        assert!(
            errors[0].contains(count) && errors[0].contains("at most"),
            "{stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(!out_png.exists());
    }
}

/// A misspelt built-in name (no such file either) lists the built-in names, in one line.
#[test]
fn an_unknown_builtin_lists_the_builtins() {
    let err = lodlab::import::load_model("hors").unwrap_err().to_string();
    assert!(err.starts_with("hors: no such file"), "{err}");
    for name in ["horse", "walker", "broadleaf", "conifer", "sapling"] {
        assert!(err.contains(name), "{err}");
    }
    assert!(!err.contains('\n'));
    // A path that is not there stays a plain missing file.
    let err = lodlab::import::load_model("models/hors.glb")
        .unwrap_err()
        .to_string();
    assert!(!err.contains("built-in"), "{err}");
}

/// Non-finite and absurd option values are refused by the parser, naming the value, before
/// anything is loaded or drawn (`--time nan` drew an empty picture and claimed full draws).
#[test]
fn non_finite_and_absurd_options_are_refused() {
    let cases: [&[&str]; 9] = [
        &["shot", "--time", "nan"],
        &["shot", "--time", "inf"],
        &["shot", "--tolerance", "NaN"],
        &["shot", "--wind=-inf"],
        &["shot", "--frames", "100000000"],
        &["bake", "horse", "--first-error", "nan"],
        &["bench", "--seconds", "inf"],
        &["record", "--length", "nan", "--out", "x.mp4"],
        &["view", "--cross-fade", "nan"],
    ];
    for args in cases {
        let out = Command::new(env!("CARGO_BIN_EXE_lodlab"))
            .args(args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        let last = args[args.len() - 1 - usize::from(args.contains(&"--out")) * 2];
        let value = last.rsplit('=').next().unwrap();
        assert!(
            stderr
                .lines()
                .next()
                .unwrap_or("")
                .contains(&format!("'{value}'")),
            "{args:?}: {stderr}"
        );
    }
}

/// Where `XDG_RUNTIME_DIR` is not set (containers, ssh sessions), Mesa's device-select layer
/// has libwayland print "error: XDG_RUNTIME_DIR is invalid…" as each Vulkan instance is made;
/// lodlab switches that probe off for itself, so a headless command's stderr holds its own
/// lines only.
#[test]
fn headless_commands_print_no_window_system_noise() {
    let dir = tempfile::tempdir().unwrap();
    let out_png = dir.path().join("out.png");
    let out = Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args([
            "shot", "--scene", "crowd", "--count", "1", "--size", "32x24",
        ])
        .arg("--out")
        .arg(&out_png)
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(out_png.is_file());
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "{stderr}");
    assert!(
        stderr.lines().all(|l| l.starts_with("lodlab: ")),
        "lines that are not lodlab's: {stderr}"
    );
}

/// `lodlab doctor` on a machine like a bare container (no `XDG_RUNTIME_DIR`, no display): it
/// names the adapter and the cache, shows the limits in force (`--limit` included), and lists
/// each problem it sees with its remedy, its own noise-free output on stdout.
#[test]
fn doctor_names_the_adapter_the_limits_and_the_problems_it_sees() {
    let cache = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args(["doctor", "--limit", "nodes=5", "--cache"])
        .arg(cache.path())
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "{stderr}");
    let line = |key: &str| {
        stdout
            .lines()
            .find(|l| l.starts_with(key))
            .unwrap_or_else(|| panic!("no {key} line: {stdout}"))
            .to_string()
    };
    assert!(line("adapter").len() > "adapter".len() + 4, "{stdout}");
    assert!(line("cache").contains("empty"), "{stdout}");
    let limits = line("limits");
    assert!(
        limits.contains("nodes=5") && limits.contains("file-mb=1024"),
        "{limits}"
    );
    let problems = &stdout[stdout.find("problems:").expect("a problems list")..];
    for seen in ["XDG_RUNTIME_DIR is not set", "no display"] {
        let p = problems
            .lines()
            .find(|l| l.contains(seen))
            .unwrap_or_else(|| panic!("{seen}: {problems}"));
        assert!(
            p.contains(':') && p.len() > seen.len() + 20,
            "no remedy: {p}"
        );
    }
}

/// A global option a command does not read is refused in one line naming it and the command
/// (accepted, `doctor --clips FILE` read no file and exited 0); the commands that read models
/// still take them.
#[test]
fn global_options_a_command_does_not_read_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    for (args, option, command) in [
        (
            vec!["doctor", "--clips", "/nonexistent.glb"],
            "--clips",
            "doctor",
        ),
        (vec!["doctor", "--levels", "error"], "--levels", "doctor"),
        (
            vec!["study", "analyze", d, "--limit", "nodes=5"],
            "--limit",
            "study analyze",
        ),
        (
            vec![
                "study",
                "run",
                d,
                "--participant",
                "P01",
                "--allow-outside-files",
            ],
            "--allow-outside-files",
            "study run",
        ),
        (
            vec!["gen-assets", "--out", d, "--clips", "mocap-walk"],
            "--clips",
            "gen-assets",
        ),
    ] {
        let out = crate::common::lodlab(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        let lines: Vec<&str> = stderr.lines().collect();
        assert_eq!(lines.len(), 1, "{args:?}: {stderr}");
        assert!(
            lines[0].contains(option) && lines[0].contains(&format!("`lodlab {command}`")),
            "{args:?}: {stderr}"
        );
    }
    // `bake` reads models: it takes them (and fails on the missing clip file, naming it).
    let out = crate::common::lodlab(&["bake", "robot", "--clips", "/nonexistent.glb"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nonexistent.glb"));
}

/// `study make` and `study web` take their plan the same two ways, as a word or `--plan`
/// (`study web --plan P` was a usage error): a missing plan is one line naming it either way.
#[test]
fn a_study_plan_is_given_the_same_way_to_make_and_web() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("study");
    let d = d.to_str().unwrap();
    for args in [
        vec!["study", "make", "/nonexistent/plan.toml", "--out", d],
        vec![
            "study",
            "make",
            "--plan",
            "/nonexistent/plan.toml",
            "--out",
            d,
        ],
        vec!["study", "web", "/nonexistent/plan.toml", "--out", d],
        vec![
            "study",
            "web",
            "--plan",
            "/nonexistent/plan.toml",
            "--out",
            d,
        ],
    ] {
        let out = crate::common::lodlab(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
        assert!(
            stderr.contains("/nonexistent/plan.toml"),
            "{args:?}: {stderr}"
        );
    }
}

/// The commands that need a model say so the same way, in one line, exit 1 (`export` gave
/// clap's usage, `report` its own line).
#[test]
fn a_missing_model_is_one_line_for_every_command_that_needs_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    for (args, command) in [
        (vec!["bake"], "bake"),
        (vec!["export", "--out", d], "export"),
        (vec!["report", "--out", d], "report"),
    ] {
        let out = crate::common::lodlab(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
        assert!(
            stderr.contains(&format!("{command} needs a model: lodlab {command} ")),
            "{args:?}: {stderr}"
        );
    }
}

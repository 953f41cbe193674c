//! lodlab in a real browser: Debian's Chromium, headless, driven through the DevTools protocol
//! by `tools/web` (puppeteer-core). The web viewer is opened on WebGPU (SwiftShader) and its
//! method switched with the M key; the online study is played through by a participant's key
//! presses, reloaded halfway, its answers downloaded and POSTed, and analysed beside a desktop
//! participant's. And `lodlab web` itself, without a browser.

use crate::common::{browser_tools, lodlab, ok, shared_cache, web_package};
use lodlab::app::study::session::{Trial, read_answers_file};
use std::process::Command;

/// A port nothing listens on now (the page POSTs to the check's server there).
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

#[test]
fn an_online_study_runs_resumes_and_is_analysed() {
    let Some(tools) = browser_tools() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let plan = crate::common::cylinder_plan(
        tmp.path(),
        "pairs = [[\"rest-pose\", \"as+is\"]]\ntolerances = [2.0]\n\
         participants = 2\ncount = 3\nseconds = 0.4\nfps = 10\nsize = \"64x48\"\n",
    );
    let dir = tmp.path().join("study");
    let d = dir.display().to_string();
    let port = free_port();
    let post = format!("http://127.0.0.1:{port}/answers");
    let cache = tmp.path().join("cache").display().to_string();
    let o = lodlab(&[
        "study",
        "web",
        &plan.display().to_string(),
        "--out",
        &d,
        "--cache",
        &cache,
        "--msaa",
        "1",
        "--post",
        &post,
    ]);
    ok(&o);
    assert!(dir.join("sessions/P01.json").is_file());
    // The site is a folder of its own, holding only what the page loads.
    let site = dir.join("site");
    for f in ["index.html", "study.js", "study-data.js"] {
        assert!(site.join(f).is_file(), "{f}");
    }
    let site_d = site.display().to_string();

    // P01 online: a training trial and the condition in both orders; reloaded after one.
    let trials: Vec<Trial> =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sessions/P01.json")).unwrap())
            .unwrap();
    assert_eq!(trials.len(), 3);
    let answers = ["2", "1", "2"];
    let out = tmp.path().join("browser");
    let o = Command::new("node")
        .arg(tools.join("study-check.mjs"))
        .args(["--site", &site_d, "--participant", "P01", "--answers"])
        .arg(answers.join(","))
        .args(["--reload-after", "1", "--port", &port.to_string(), "--out"])
        .arg(&out)
        .output()
        .expect("node runs");
    ok(&o);
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // The desktop's order of screens: welcome, then per trial a grey gap before each clip and
    // the question; after the reload, welcome again.
    let stages: Vec<&str> = report["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    let trial = ["gap", "playing", "gap", "playing", "ask"];
    let mut expected = vec!["welcome"];
    expected.extend(trial);
    // The answer starts the next trial's gap; the reload cuts it short.
    expected.extend(["gap", "welcome"]);
    expected.extend(trial);
    expected.extend(trial);
    expected.extend(["sending", "done"]);
    assert_eq!(stages, expected, "{report}");
    assert!(
        report["resumed"]
            .as_str()
            .unwrap()
            .contains("1 of 3 answered"),
        "{report}"
    );
    assert!(report["done"].as_str().unwrap().contains("were sent"));
    assert_eq!(
        report["posted"], true,
        "the POSTed answers are the download"
    );
    // Both clips of every trial played at their size and are not black (the cylinders on the
    // study's ground).
    let frames = report["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 2 * answers.len(), "{report}");
    for f in frames {
        assert_eq!(
            (f["width"].as_u64(), f["height"].as_u64()),
            (Some(64), Some(48))
        );
        assert!(f["mean_luma"].as_f64().unwrap() > 30.0, "{f}");
    }
    let download = out.join("answers-P01.csv");
    let (got, bad) = read_answers_file(&download).unwrap();
    assert_eq!(bad, 0);
    assert_eq!(got.len(), 3);
    for ((a, t), choice) in got.iter().zip(&trials).zip(answers) {
        assert_eq!(
            (a.trial, &a.block, a.first, a.second),
            (t.trial, &t.block, t.first, t.second)
        );
        assert_eq!(a.choice.to_string(), choice);
        assert_eq!(a.preferred, if choice == "1" { t.first } else { t.second });
    }

    // P02 on the desktop; analyze reads both.
    std::fs::copy(&download, dir.join("answers-P01.csv")).unwrap();
    ok(&lodlab(&[
        "study",
        "run",
        &d,
        "--participant",
        "P02",
        "--script",
        "1,1,1",
    ]));
    let o = lodlab(&["study", "analyze", &d]);
    ok(&o);
    let analysis: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("analysis.json")).unwrap()).unwrap();
    assert_eq!(analysis["participants"], 2, "{analysis}");
    assert_eq!(analysis["training_answers_left_out"], 2);
    assert_eq!(analysis["conditions"][0]["answers"], 4);
    let files = analysis["answer_files"].to_string();
    assert!(
        files.contains("answers-P01.csv") && files.contains("answers.csv"),
        "{files}"
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("answers-P01.csv (3)"));
}

/// `lodlab web` copies exactly the cache files the page's scene reads (under every method),
/// lists them in its manifest, and writes only into a new folder or its own.
#[test]
fn the_web_folder_holds_the_levels_its_scene_reads() {
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    let cache = shared_cache().display().to_string();
    let view = ["--scene", "study", "--model", "horse", "--count", "3"];
    let mut args = vec![
        "web",
        "--out",
        site.to_str().unwrap(),
        "--cache",
        &cache,
        "--",
    ];
    args.extend(view);
    let o = lodlab(&args);
    ok(&o);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("build-wasm.sh"),
        "says how to build the viewer itself"
    );
    let manifest: lodlab::app::site::SiteManifest =
        serde_json::from_str(&std::fs::read_to_string(site.join("lodlab-web.json")).unwrap())
            .unwrap();
    assert_eq!(manifest.view, view);
    let names: Vec<&str> = manifest.files.iter().map(|f| f.name.as_str()).collect();
    for kind in [
        "horse-rest-pose-",
        "horse-as-",
        "horse-as-is-",
        "horse-impostor-",
    ] {
        assert!(
            names.iter().any(|n| n.starts_with(kind)),
            "{kind}: {names:?}"
        );
    }
    for f in &manifest.files {
        let copy = std::fs::read(site.join("levels").join(&f.name)).unwrap();
        let original = std::fs::read(shared_cache().join(&f.name)).unwrap();
        assert_eq!(
            (copy.len() as u64, &copy),
            (f.bytes, &original),
            "{}",
            f.name
        );
    }
    assert!(
        std::fs::read_to_string(site.join("index.html"))
            .unwrap()
            .contains("lodlab.js")
    );
    // Written again over its own folder: fine. Into someone else's, or with a bad view: one
    // line, exit 1.
    ok(&lodlab(&args));
    let other = tmp.path().join("other");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "mine").unwrap();
    for bad in [
        vec!["web", "--out", other.to_str().unwrap()],
        vec![
            "web",
            "--out",
            site.to_str().unwrap(),
            "--",
            "--scene",
            "nowhere",
        ],
        // The page reads no files: built-in models only.
        vec![
            "web",
            "--out",
            site.to_str().unwrap(),
            "--",
            "--model",
            "mine.glb",
        ],
        vec![
            "web",
            "--out",
            site.to_str().unwrap(),
            "--wasm",
            other.to_str().unwrap(),
        ],
    ] {
        let o = lodlab(&bad);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{bad:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    assert_eq!(
        std::fs::read_to_string(other.join("notes.txt")).unwrap(),
        "mine"
    );
    // A run that stopped before its manifest left only its own files: the next one goes on.
    let stopped = tmp.path().join("stopped");
    std::fs::create_dir_all(stopped.join("levels")).unwrap();
    let stopped_s = stopped.display().to_string();
    args[2] = &stopped_s;
    ok(&lodlab(&args));
    assert!(stopped.join("lodlab-web.json").is_file());
}

/// The web viewer in Chromium on WebGPU, and on WebGL2 (both over SwiftShader): frames come,
/// the console has no errors, the screenshot shows the panel beside the scene, a mouse's drag
/// and a finger's orbit the camera, and M (the next method) changes the triangles the page
/// shows.
#[test]
fn the_web_viewer_draws_and_switches_method_in_a_browser() {
    let (Some(tools), Some(pkg)) = (browser_tools(), web_package()) else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    let cache = shared_cache().display().to_string();
    ok(&lodlab(&[
        "web",
        "--out",
        site.to_str().unwrap(),
        "--cache",
        &cache,
        "--wasm",
        pkg.to_str().unwrap(),
        "--",
        "--scene",
        "study",
        "--model",
        "horse",
        "--count",
        "12",
    ]));
    // WebGPU, and WebGL2 where a browser has none (WebGPU left out of Chromium).
    for (api, backend) in [("webgpu", "BrowserWebGpu"), ("webgl", "(Gl, ")] {
        let out = tmp.path().join(api);
        let o = Command::new("node")
            .arg(tools.join("viewer-check.mjs"))
            .arg("--site")
            .arg(&site)
            .arg("--out")
            .arg(&out)
            .args(["--size", "800x450", "--frames", "3"])
            .args((api == "webgl").then_some("--webgl"))
            .output()
            .expect("node runs");
        ok(&o);
        let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(report["errors"], serde_json::json!([]), "{report}");
        assert!(
            report["adapter"].as_str().unwrap().contains(backend),
            "{report}"
        );
        let methods = report["methods"].as_array().unwrap();
        let names: Vec<&str> = methods
            .iter()
            .map(|m| m["method"].as_str().unwrap())
            .collect();
        assert_eq!(
            names,
            ["as+is", "meshopt", "none"],
            "M goes to the next method, meshoptimizer's levels in the page too: {report}"
        );
        let triangles: Vec<u64> = methods
            .iter()
            .map(|m| m["triangles"].as_u64().unwrap())
            .collect();
        assert!(
            triangles[0] > 0 && triangles[1] > 0 && triangles[2] > triangles[0].max(triangles[1]),
            "{report}"
        );
        // Dragging right orbits one way, a finger dragging left the other.
        let orbit = &report["orbit"];
        assert!(
            orbit["mouse"].as_f64().unwrap() * orbit["touch"].as_f64().unwrap() < 0.0,
            "{report}"
        );
        // The picture: the panel (dark, with text) on the left, the scene (sky and ground,
        // horses) on the right.
        let shot = image::open(out.join("viewer.png")).unwrap().to_luma8();
        let stats = |x0: u32, x1: u32| {
            let v: Vec<f64> = (0..shot.height())
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .map(|(x, y)| shot.get_pixel(x, y)[0] as f64 / 255.0)
                .collect();
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let sd = (v.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
            (mean, sd)
        };
        let (panel, scene) = (stats(0, 180), stats(400, 800));
        assert!(
            panel.0 < 0.3 && panel.1 > 0.02,
            "{api}: the panel: {panel:?}"
        );
        assert!(
            scene.0 > 0.35 && scene.1 > 0.03,
            "{api}: the scene: {scene:?}"
        );
    }
}

//! `lodlab record` as a user runs it, on a small scene (lavapipe in CI): the clip holds exactly
//! seconds × fps frames that decode, it is the same on every run, and an interrupted recording
//! leaves nothing under the final name.

use lodlab::app::video::probe;
use lodlab::generate::cylinder::bent_cylinder;
use lodlab::generate::glb::to_glb;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn cylinder_glb(dir: &Path) -> String {
    let p = dir.join("cylinder.glb");
    std::fs::write(&p, to_glb(&bent_cylinder(24, 16))).unwrap();
    p.display().to_string()
}

fn record_args(dir: &Path, out: &Path, seconds: &str, frames_dir: Option<&Path>) -> Vec<String> {
    let mut args: Vec<String> = [
        "record",
        "--model",
        &cylinder_glb(dir),
        "--count",
        "8",
        "--method",
        "as+is",
        "--transition",
        "morph",
        "--tolerance",
        "3",
        "--size",
        "96x64",
        "--msaa",
        "1",
        "--fps",
        "10",
        "--length",
        seconds,
        "--cache",
        &dir.join("cache").display().to_string(),
        "--out",
        &out.display().to_string(),
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    if let Some(f) = frames_dir {
        args.push("--frames-dir".into());
        args.push(f.display().to_string());
    }
    args
}

fn lodlab(args: &[String]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args(args)
        .output()
        .expect("lodlab runs")
}

fn pngs(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    v.sort();
    v
}

#[test]
fn a_clip_holds_seconds_times_fps_frames_and_is_the_same_every_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("clip.mp4");
    let frames = dir.path().join("frames");
    let o = lodlab(&record_args(dir.path(), &out, "1.5", Some(&frames)));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["frames"], 15);
    assert_eq!(report["scene"], "study");
    assert_eq!(report["count"], 8);
    let info = probe(&out).unwrap();
    assert_eq!(info.frames, 15, "1.5 s at 10 fps");
    assert_eq!(info.decoded, 15, "every frame decodes");
    assert_eq!((info.width, info.height), (96, 64));
    assert!((info.fps - 10.0).abs() < 1e-6);
    let first = pngs(&frames);
    assert_eq!(first.len(), 15);
    // The camera moves: the first and the last frame differ.
    let a = image::open(&first[0]).unwrap().to_rgba8();
    let b = image::open(&first[14]).unwrap().to_rgba8();
    assert_ne!(a, b);

    // A second recording is the same clip, frame for frame and byte for byte.
    let out2 = dir.path().join("again.mp4");
    let frames2 = dir.path().join("frames2");
    let o = lodlab(&record_args(dir.path(), &out2, "1.5", Some(&frames2)));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (p, q) in first.iter().zip(pngs(&frames2)) {
        assert_eq!(
            std::fs::read(p).unwrap(),
            std::fs::read(&q).unwrap(),
            "{p:?}"
        );
    }
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&out2).unwrap());

    // A frames folder that holds something is refused, and what it holds is kept.
    let o = lodlab(&record_args(
        dir.path(),
        &dir.path().join("third.mp4"),
        "1",
        Some(&frames),
    ));
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("not empty"), "{err}");
    assert_eq!(pngs(&frames), first);
    assert!(!dir.path().join("third.mp4").exists());
}

#[test]
fn an_interrupted_recording_leaves_no_file_under_its_name() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("clip.mp4");
    let frames = dir.path().join("frames");
    let mut child = Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args(record_args(dir.path(), &out, "60", Some(&frames)))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Killed once it is well into the clip (frames are being written and encoded).
    let start = Instant::now();
    while !(frames.is_dir() && pngs(&frames).len() >= 5) {
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "no frames written"
        );
        assert!(child.try_wait().unwrap().is_none(), "record ended early");
        std::thread::sleep(Duration::from_millis(50));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!out.exists(), "half a clip under the final name");
}

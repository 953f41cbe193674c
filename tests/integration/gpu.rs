//! Headless rendering on whatever adapter wgpu finds (Mesa lavapipe in CI, where
//! `WGPU_BACKEND=vulkan` makes a missing driver fail loudly instead of falling back).

use glam::{Affine3A, Quat, Vec3};
use lodlab::app::commands::shot::{ShotOptions, run as shot};
use lodlab::render::Gpu;
use lodlab::render::capture::capture_skinned;
use lodlab::render::targets::OFFSCREEN_FORMAT;
use lodlab::runtime::spec::{Loaded, SceneSpec};
use lodlab::runtime::world::World;
use lodlab::scene::Camera;

fn spec(models: &[&str], count: usize, clip: Option<&str>) -> SceneSpec {
    SceneSpec {
        models: models.iter().map(|s| s.to_string()).collect(),
        count,
        clip: clip.map(str::to_string),
        ..Default::default()
    }
}

#[test]
fn gpu_skinning_matches_the_cpu_reference() {
    let gpu = crate::common::gpu().clone();
    let Some(fox) = crate::common::shared_model("Fox.glb") else {
        return;
    };
    let fox = fox.display().to_string();
    // Six influences per vertex: more than any fixed-attribute skinning would take.
    let dir = tempfile::tempdir().unwrap();
    let six = dir.path().join("six.glb");
    std::fs::write(
        &six,
        lodlab::generate::glb::to_glb(&crate::common::six_influence_model()),
    )
    .unwrap();
    let six = six.display().to_string();
    let world = World::new(
        &gpu,
        Loaded::new(spec(&["horse", "walker", &fox, &six], 4, None)).unwrap(),
        OFFSCREEN_FORMAT,
        1,
    )
    .unwrap();
    let place =
        Affine3A::from_rotation_translation(Quat::from_rotation_y(0.7), Vec3::new(3.0, 0.0, -2.0));
    for (m, bake) in world.bakes.iter().enumerate() {
        for clip in 0..bake.animation.clips.len() {
            for time in [0.0f32, 0.37, 1.91] {
                let gpu_pos =
                    capture_skinned(&gpu, &world.renderer, m, clip as u32, time, place).unwrap();
                let g = bake.animation.sample(clip, time);
                let (cpu_pos, _) = bake.animation_space.evaluate(&g);
                let size = bake.bounds.diagonal();
                assert_eq!(gpu_pos.len(), cpu_pos.len());
                let mut worst = 0.0f32;
                for (v, (a, b)) in gpu_pos.iter().zip(&cpu_pos).enumerate() {
                    let expected = place.transform_point3(*b);
                    let err = a.truncate().distance(expected);
                    worst = worst.max(err);
                    assert!(
                        err <= 1e-4 * size,
                        "{} clip {clip} t={time} vertex {v}: GPU {} CPU {expected}",
                        bake.name,
                        a.truncate()
                    );
                    assert_eq!(
                        a.w as usize,
                        bake.animation_space.influences_of(v).len(),
                        "influence count of vertex {v}"
                    );
                }
                assert!(worst.is_finite());
            }
        }
    }
}

fn render(
    spec: SceneSpec,
    time: f32,
    size: (u32, u32),
    camera: Option<Camera>,
) -> (image::RgbaImage, lodlab::app::commands::shot::ShotReport) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("shot.png");
    let report = shot(&ShotOptions {
        spec,
        out: out.clone(),
        width: size.0,
        height: size.1,
        time,
        samples: Some(4),
        camera,
        timed_frames: 1,
        calibrate: false,
        backdrop: Default::default(),
        lod: Default::default(),
    })
    .unwrap();
    (image::open(&out).unwrap().to_rgba8(), report)
}

/// Share of pixels that differ by more than a few levels in any channel.
fn changed(a: &image::RgbaImage, b: &image::RgbaImage) -> f32 {
    let n = a
        .pixels()
        .zip(b.pixels())
        .filter(|(p, q)| p.0.iter().zip(q.0.iter()).any(|(x, y)| x.abs_diff(*y) > 6))
        .count();
    n as f32 / (a.width() * a.height()) as f32
}

#[test]
fn two_times_of_a_clip_render_differently() {
    let close = Some(Camera::new(Vec3::new(0.0, 0.9, 0.0), 90.0, 5.0, 3.4));
    let (a, _) = render(spec(&["walker"], 1, Some("walk")), 0.1, (96, 96), close);
    let (b, _) = render(spec(&["walker"], 1, Some("walk")), 0.45, (96, 96), close);
    let d = changed(&a, &b);
    assert!(d > 0.01, "the legs must have moved: {d}");
}

#[test]
fn a_crowd_covers_a_sensible_share_of_the_image() {
    let (empty, r0) = render(spec(&[], 0, None), 1.0, (320, 180), None);
    assert_eq!((r0.instances, r0.triangles), (0, 0));
    // 15 characters, under 200k triangles: a small scene, as tests should be.
    let (crowd, r) = render(spec(&[], 15, None), 1.0, (320, 180), None);
    assert_eq!(r.instances + r.culled, 15);
    assert!(r.instances >= 10, "{} of 15 drawn", r.instances);
    assert!(
        (15 * 8_000..=200_000).contains(&r.triangles),
        "{}",
        r.triangles
    );
    // Blob shadows blend over the ground; the image stays opaque.
    assert!(crowd.pixels().all(|p| p[3] == 255), "see-through pixels");
    let share = changed(&empty, &crowd);
    assert!(
        (0.02..0.6).contains(&share),
        "crowd covers {share} of the image"
    );
}

#[test]
fn the_empty_scene_is_sky_over_ground() {
    let (img, _) = render(spec(&[], 0, None), 0.0, (64, 64), None);
    let top = img.get_pixel(32, 1).0;
    let bottom = img.get_pixel(32, 62).0;
    assert!(top[2] > top[0], "sky is blue: {top:?}");
    assert!(bottom[1] > bottom[2], "ground is green-grey: {bottom:?}");
    assert_ne!(top, bottom);
}

#[test]
fn shots_are_deterministic() {
    let (a, _) = render(spec(&["horse", "walker"], 12, None), 2.5, (200, 120), None);
    let (b, _) = render(spec(&["horse", "walker"], 12, None), 2.5, (200, 120), None);
    assert!(a == b, "same arguments, same picture");
}

/// `lodlab shot` writes the same PNG file, byte for byte, for the same arguments: a crowd with
/// its levels of detail and transitions, and the forest.
#[test]
fn shot_files_are_the_same_bytes_for_the_same_arguments() {
    let dir = tempfile::tempdir().unwrap();
    let cache = crate::common::shared_cache();
    let scenes: [&[&str]; 2] = [
        &[
            "--scene",
            "crowd",
            "--count",
            "8",
            "--method",
            "as+is",
            "--tolerance",
            "6",
        ],
        &["--scene", "forest", "--count", "3", "--method", "none"],
    ];
    for (k, args) in scenes.into_iter().enumerate() {
        let shoot = |name: &str| {
            let out = dir.path().join(name);
            let status = std::process::Command::new(env!("CARGO_BIN_EXE_lodlab"))
                .arg("shot")
                .args(args)
                .args([
                    "--size", "96x64", "--time", "1.5", "--frames", "1", "--cache",
                ])
                .arg(&cache)
                .arg("--out")
                .arg(&out)
                .output()
                .unwrap();
            assert!(
                status.status.success(),
                "{args:?}: {}",
                String::from_utf8_lossy(&status.stderr)
            );
            std::fs::read(&out).unwrap()
        };
        let a = shoot(&format!("{k}a.png"));
        let b = shoot(&format!("{k}b.png"));
        assert!(a.len() > 100, "{args:?}: a PNG");
        assert!(a == b, "{args:?}: two runs wrote different files");
    }
}

/// `WGPU_ADAPTER_NAME` picks the adapter by a piece of its name; a name that matches nothing is
/// an error that lists what there is.
#[test]
fn adapter_is_chosen_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.png");
    let run = |name: Option<&str>| {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_lodlab"));
        c.args([
            "shot", "--scene", "crowd", "--count", "0", "--size", "32x32", "--out",
        ])
        .arg(&out);
        match name {
            Some(n) => c.env("WGPU_ADAPTER_NAME", n),
            None => c.env_remove("WGPU_ADAPTER_NAME"),
        };
        c.output().unwrap()
    };
    let default = run(None);
    assert!(default.status.success());
    let report: serde_json::Value = serde_json::from_slice(&default.stdout).unwrap();
    let adapter = report["adapter"].as_str().unwrap().to_string();
    let stderr = String::from_utf8_lossy(&default.stderr);
    assert!(
        stderr.contains(&adapter),
        "the chosen adapter is printed at start: {stderr}"
    );

    let word = adapter.split_whitespace().next().unwrap().to_uppercase();
    let named = run(Some(&word));
    assert!(named.status.success());
    let report: serde_json::Value = serde_json::from_slice(&named.stdout).unwrap();
    assert_eq!(report["adapter"].as_str(), Some(adapter.as_str()));

    let bogus = run(Some("no-such-gpu-anywhere"));
    assert_eq!(bogus.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&bogus.stderr);
    assert!(
        stderr.contains("no-such-gpu-anywhere") && stderr.contains(&adapter),
        "{stderr}"
    );
}

/// Without `--msaa`, `shot` draws with the adapter's default, 1 sample on a CPU adapter and 4
/// on a GPU, says so on stderr with how to change it, and reports what it drew with; `--msaa`
/// overrides it silently.
#[test]
fn multisampling_defaults_by_adapter() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.png");
    let run = |extra: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_lodlab"))
            .args([
                "shot", "--scene", "crowd", "--count", "0", "--size", "32x32", "--out",
            ])
            .arg(&out)
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (report, String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (report, stderr) = run(&[]);
    let cpu = stderr.contains("Cpu)");
    let (expected, other) = if cpu { (1, 4) } else { (4, 1) };
    assert_eq!(report["msaa"].as_u64(), Some(expected), "{stderr}");
    assert!(
        stderr.contains(&format!("multisampling {expected}×"))
            && stderr.contains(&format!("--msaa {other}")),
        "the default and how to change it are printed: {stderr}"
    );
    let (report, stderr) = run(&["--msaa", &other.to_string()]);
    assert_eq!(report["msaa"].as_u64(), Some(other));
    assert!(!stderr.contains("multisampling"), "{stderr}");
}

/// `shot` reports each pass's GPU time where the adapter has timestamp queries: only the passes
/// the frame draws, none longer than the frame; and where it counts fragments, the sky and
/// ground alone shade every pixel at least once. It reports where memory goes too.
#[test]
fn shot_reports_where_the_frame_goes() {
    let (_, empty) = render(spec(&[], 0, None), 0.0, (64, 48), None);
    let close = Some(Camera::new(Vec3::new(0.0, 0.9, 0.0), 90.0, 5.0, 3.4));
    let (_, one) = render(spec(&["walker"], 1, None), 0.5, (64, 48), close);
    // Where memory goes: the walker's textures and buffers by kind, and the process's
    // resident size (Linux) above what is counted.
    let mb = |r: &lodlab::app::commands::shot::ShotReport, k: &str| {
        r.memory_mb.get(k).copied().unwrap_or(0.0)
    };
    for kind in [
        "animation textures",
        "vertex textures",
        "material textures",
        "index buffers",
    ] {
        assert!(mb(&one, kind) > 0.0, "{kind}: {:?}", one.memory_mb);
    }
    if cfg!(target_os = "linux") {
        let counted: f64 = one
            .memory_mb
            .iter()
            .filter(|(k, _)| !k.starts_with("resident"))
            .map(|(_, v)| v)
            .sum();
        assert!(
            mb(&one, "resident (process)") > counted,
            "{:?}",
            one.memory_mb
        );
    }
    if empty.passes.is_empty() {
        eprintln!("no timestamp queries on this adapter: nothing to check");
        return;
    }
    let names =
        |r: &lodlab::app::commands::shot::ShotReport| r.passes.keys().cloned().collect::<Vec<_>>();
    assert_eq!(names(&empty), ["sky and ground"]);
    assert_eq!(names(&one), ["characters", "shadows", "sky and ground"]);
    for r in [&empty, &one] {
        let sum: f64 = r.passes.values().sum();
        assert!(r.passes.values().all(|&ms| ms >= 0.0), "{:?}", r.passes);
        assert!(
            sum <= r.frame_ms * 1.01 + 0.05,
            "{sum} ms of passes in a {} ms frame",
            r.frame_ms
        );
    }
    if let Some(x) = empty.overdraw {
        assert!(x >= 1.0, "sky and ground shade every pixel: {x}");
        assert!(x < 3.0, "{x}");
    }
}

/// A clip cross-fade (issue 20): the GPU blends the two clips' bone matrices, each at its own
/// time, as the CPU reference does, at every weight from one clip to the other.
#[test]
fn gpu_clip_cross_fade_matches_the_cpu_reference() {
    use lodlab::render::capture::capture_skinned_fading;
    let gpu = crate::common::gpu().clone();
    let world = World::new(
        &gpu,
        Loaded::new(spec(&["walker", "horse"], 2, None)).unwrap(),
        OFFSCREEN_FORMAT,
        1,
    )
    .unwrap();
    let place = Affine3A::from_translation(Vec3::new(1.0, 0.0, -3.0));
    for (m, bake) in world.bakes.iter().enumerate() {
        assert!(
            bake.animation.clips.len() >= 2,
            "{} has one clip",
            bake.name
        );
        let (from, to) = ((0usize, 0.43f32), (1usize, 1.37f32));
        let size = bake.bounds.diagonal();
        let mut moved = 0.0f32;
        for weight in [0.0f32, 0.3, 0.5, 1.0] {
            let gpu_pos = capture_skinned_fading(
                &gpu,
                &world.renderer,
                m,
                (from.0 as u32, from.1),
                (to.0 as u32, to.1),
                weight,
                place,
            )
            .unwrap();
            let g = bake.animation.sample_fade(from, to, weight);
            let (cpu_pos, _) = bake.animation_space.evaluate(&g);
            for (v, (a, b)) in gpu_pos.iter().zip(&cpu_pos).enumerate() {
                let expected = place.transform_point3(*b);
                let err = a.truncate().distance(expected);
                assert!(
                    err <= 1e-4 * size,
                    "{} weight {weight} vertex {v}: GPU {} CPU {expected}",
                    bake.name,
                    a.truncate()
                );
            }
            // The fade really moves the pose: weight 1 is the other clip, not the first.
            if weight == 1.0 {
                let (first, _) = bake
                    .animation_space
                    .evaluate(&bake.animation.sample(from.0, from.1));
                moved = first
                    .iter()
                    .zip(&cpu_pos)
                    .map(|(a, b)| a.distance(*b))
                    .fold(0.0, f32::max);
            }
        }
        assert!(moved > 0.01 * size, "{}: the clips pose alike", bake.name);
    }
}

/// What the GPU refuses is an error to report, never a panic: sizes past the device's limits
/// are refused before anything is made, work that fails validation inside
/// [`Gpu::checked`] fails it, and an error outside any scope waits in [`Gpu::take_error`].
#[test]
fn gpu_errors_are_errors_not_panics() {
    let gpu = Gpu::headless().expect("a GPU adapter (lavapipe in CI)");
    let limits = gpu.device.limits();
    let layers = gpu
        .texture_fits("300 materials", 64, 64, limits.max_texture_array_layers + 1)
        .unwrap_err()
        .to_string();
    assert!(
        layers.contains("300 materials") && layers.contains("texture layers"),
        "{layers}"
    );
    let side = limits.max_texture_dimension_2d + 1;
    assert!(gpu.texture_fits("a target", side, 4, 1).is_err());
    assert!(gpu.texture_fits("a target", 64, 64, 1).is_ok());
    assert!(
        gpu.buffer_fits("instances", limits.max_buffer_size + 1)
            .is_err()
    );

    // Mapped for reading and writing at once: invalid on every backend.
    let invalid = wgpu::BufferDescriptor {
        label: Some("invalid"),
        size: 16,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::MAP_WRITE,
        mapped_at_creation: false,
    };
    let refused = gpu
        .checked("a test buffer", || gpu.device.create_buffer(&invalid))
        .expect_err("refused");
    let line = refused.to_string();
    assert!(
        line.starts_with("a test buffer: the GPU refused it"),
        "{line}"
    );
    assert!(!line.contains('\n'), "{line}");
    assert!(gpu.take_error().is_ok(), "a scoped error is not left over");

    let _ = gpu.device.create_buffer(&invalid);
    assert!(gpu.take_error().is_err(), "the unscoped error is kept");
    assert!(gpu.take_error().is_ok(), "and taken once");
}

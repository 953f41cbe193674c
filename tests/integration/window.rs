//! The real window, egui panel included, rendered under Xvfb (or the display there is) and read
//! back through `lodlab view --screenshot`.

use std::path::Path;
use std::process::Command;

fn on_path(program: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(program).is_file()))
}

/// Mean and standard deviation of the luma of a region.
fn luma_stats(img: &image::RgbaImage, x0: u32, y0: u32, x1: u32, y1: u32) -> (f32, f32) {
    let mut v = Vec::new();
    for y in y0..y1 {
        for x in x0..x1 {
            let p = img.get_pixel(x, y).0;
            v.push(0.299 * p[0] as f32 + 0.587 * p[1] as f32 + 0.114 * p[2] as f32);
        }
    }
    let mean = v.iter().sum::<f32>() / v.len() as f32;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f32>() / v.len() as f32;
    (mean, var.sqrt())
}

#[test]
fn viewer_window_shows_the_scene_and_the_panel() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("window.png");
    let out = run_viewer(
        &["view", "--scene", "crowd", "--count", "12"],
        &crate::common::shared_cache(),
        &shot,
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "viewer failed: {stderr}");
    check_screenshot(&shot);
}

/// The comparison in the window: a light divider down the middle of the 3D view.
#[test]
fn viewer_compares_two_methods_side_by_side() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("compare.png");
    let args = [
        "--scene",
        "crowd",
        "--count",
        "30",
        "--compare",
        "none,as+is",
        "--transition",
        "alpha",
    ];
    let out = run_viewer(&args, &crate::common::shared_cache(), &shot);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "viewer failed: {stderr}");
    check_screenshot(&shot);
    let img = image::open(&shot).unwrap().to_rgba8();
    // The 3D view is right of the 270-point panel, drawn at 0.75 in this 960×540 window (the
    // interface shrinks with windows under 1280×720); its middle column is the divider.
    let panel = (270.0f32 * (960.0 / 1280.0f32).min(540.0 / 720.0)).round() as u32;
    let mid = panel + (960 - panel) / 2;
    let light = |x: u32| {
        (40..540)
            .filter(|&y| img.get_pixel(x, y).0[..3].iter().all(|&c| c > 220))
            .count()
    };
    let divider = (mid - 2..=mid + 2).map(light).max().unwrap();
    assert!(
        divider > 450,
        "no divider at x = {mid}: {divider} light pixels"
    );
}

/// Runs the viewer under Xvfb (or on the display there is) until it writes `shot`, with the
/// level-of-detail cache in `cache`.
fn run_viewer(args: &[&str], cache: &Path, shot: &Path) -> std::process::Output {
    run_viewer_with(args, cache, shot, 3, &[])
}

/// [`run_viewer`] for `frames` frames, with environment variables `env`.
fn run_viewer_with(
    args: &[&str],
    cache: &Path,
    shot: &Path,
    frames: usize,
    env: &[(&str, &str)],
) -> std::process::Output {
    let exe = env!("CARGO_BIN_EXE_lodlab");
    let mut cmd = if on_path("xvfb-run") {
        let mut c = Command::new("xvfb-run");
        c.args(["-a", "-s", "-screen 0 960x540x24", exe]);
        c
    } else if std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some()
    {
        Command::new(exe)
    } else {
        panic!("this test needs xvfb-run (apt-get install xvfb) or a display");
    };
    cmd.envs(env.iter().copied())
        .args(args)
        .args([
            "--size",
            "960x540",
            "--frames",
            &frames.to_string(),
            "--cache",
        ])
        .arg(cache)
        .arg("--screenshot")
        .arg(shot)
        .output()
        .unwrap()
}

/// A device lost mid-run (here destroyed before frame 3, as a driver reset would lose it) is
/// replaced: the viewer opens another, puts the scene back on it and goes on drawing.
#[test]
fn viewer_recovers_from_a_lost_device() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("recovered.png");
    let out = run_viewer_with(
        &["view", "--scene", "crowd", "--count", "12"],
        &crate::common::shared_cache(),
        &shot,
        8,
        &[("LODLAB_LOSE_DEVICE_AT_FRAME", "3")],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "viewer failed: {stderr}");
    assert!(stderr.contains("destroying the GPU device"), "{stderr}");
    assert!(
        stderr.contains("the scene is back on a new device"),
        "{stderr}"
    );
    check_screenshot(&shot);
}

fn check_screenshot(path: &Path) {
    let img = image::open(path).expect("a PNG").to_rgba8();
    assert_eq!((img.width(), img.height()), (960, 540));
    // Not blank.
    let (_, all_sd) = luma_stats(&img, 0, 0, 960, 540);
    assert!(all_sd > 10.0, "the window is blank (luma sd {all_sd})");
    // The panel: a dark strip on the left with light text on it.
    let (panel_mean, _) = luma_stats(&img, 0, 0, 250, 540);
    assert!(
        panel_mean < 70.0,
        "no dark panel on the left (mean luma {panel_mean})"
    );
    let bright_text = (0..250)
        .flat_map(|x| (0..540).map(move |y| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x, y).0[0] > 150)
        .count();
    assert!(
        bright_text > 200,
        "the panel shows no text ({bright_text} light pixels)"
    );
    // The scene right of it: sky above ground.
    let sky = img.get_pixel(700, 10).0;
    assert!(
        sky[2] > sky[0] + 20,
        "no sky at the top of the 3D view: {sky:?}"
    );
    let (scene_mean, scene_sd) = luma_stats(&img, 300, 0, 960, 540);
    assert!(
        scene_mean > 90.0 && scene_sd > 8.0,
        "3D view looks wrong: {scene_mean} {scene_sd}"
    );
}

#[test]
fn viewer_without_a_display_points_to_shot_and_exits_2() {
    // `lodlab`, `lodlab view` and `lodlab` with the viewer's options are the same command.
    let forms: [&[&str]; 3] = [
        &[],
        &["view", "--scene", "crowd", "--count", "5"],
        &["--count", "5", "--model", "walker"],
    ];
    for args in forms {
        let out = Command::new(env!("CARGO_BIN_EXE_lodlab"))
            .args(args)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        let lines: Vec<&str> = stderr.lines().collect();
        assert_eq!(lines.len(), 1, "{args:?}: {stderr}");
        assert!(lines[0].contains("lodlab shot"), "{args:?}: {stderr}");
    }
}

/// The panel copied from its image onto an sRGB frame looks as egui drawing it straight onto
/// a frame without sRGB encoding does (egui blends in gamma space, and the viewer's egui
/// draws so): the fill and the text exactly, a label over the view closely (the copy blends
/// its soft edges in linear space), and the frame beside left as it was.
#[test]
fn the_panel_image_matches_egui_drawing_the_panel_directly() {
    use lodlab::app::panel_image::PanelImage;
    use lodlab::render::targets::Offscreen;
    let gpu = crate::common::gpu();
    let (w, h) = (320u32, 200u32);
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let ctx = egui::Context::default();
    let raw = egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(
            egui::Pos2::ZERO,
            egui::vec2(w as f32, h as f32),
        )),
        ..Default::default()
    };
    let frame = |ctx: &egui::Context| {
        ctx.run_ui(raw.clone(), |ui| {
            egui::Panel::left("test panel")
                .exact_size(120.0)
                .show(ui, |ui| {
                    ui.heading("lodlab");
                    ui.label("triangles 10,392");
                    let _ = ui.button("Open…");
                });
            ui.painter().text(
                egui::pos2(250.0, 30.0),
                egui::Align2::CENTER_CENTER,
                "as+is",
                egui::FontId::proportional(16.0),
                egui::Color32::WHITE,
            );
        })
    };
    // The first run lays the fonts out (and sends their atlas); the second is the frame drawn.
    let mut first = frame(&ctx);
    let mut output = frame(&ctx);
    let primitives = ctx.tessellate(std::mem::take(&mut output.shapes), output.pixels_per_point);
    let screen = egui_wgpu::ScreenDescriptor {
        size_in_pixels: [w, h],
        pixels_per_point: output.pixels_per_point,
    };
    let plain = format.remove_srgb_suffix();
    let mut renderer = egui_wgpu::Renderer::new(&gpu.device, plain, Default::default());
    let sets = first.textures_delta.set.drain();
    for (id, deltas) in sets.chain(output.textures_delta.set.drain()) {
        for delta in &deltas {
            renderer.update_texture(&gpu.device, &gpu.queue, id, delta);
        }
    }
    first.textures_delta.clear();
    output.textures_delta.clear();
    let background = wgpu::Color {
        r: 0.2,
        g: 0.4,
        b: 0.7,
        a: 1.0,
    };
    // With an sRGB view of the image (the desktop, WebGPU), and with a plain image the copy's
    // shader decodes (WebGL2, which has no view formats): the same picture.
    for view_formats in [true, false] {
        // egui straight onto a frame without sRGB encoding; the copy onto an sRGB frame. Both
        // store the same gamma-encoded bytes, so they compare byte for byte.
        let direct = Offscreen::with_format(gpu, w, h, 1, plain);
        let copied = Offscreen::with_format(gpu, w, h, 1, format);
        let mut image = PanelImage::new(&gpu.device, format, view_formats);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let uploads =
            renderer.update_buffers(&gpu.device, &gpu.queue, &mut encoder, &primitives, &screen);
        lodlab::app::window::draw_panel(
            &renderer,
            &mut encoder,
            &direct.view,
            &primitives,
            &screen,
            "direct",
            Some(background),
            None,
        );
        assert!(image.needs_refresh([w, h]));
        image.refresh(
            &gpu.device,
            &renderer,
            &mut encoder,
            &primitives,
            &screen,
            None,
        );
        assert!(!image.needs_refresh([w, h]));
        // The frame under the panel: the background colour (as linear values, which the sRGB
        // frame stores as the gamma bytes the direct frame holds), then the image over it.
        let linear = |c: f64| {
            if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            }
        };
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("background"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &copied.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: linear(background.r),
                        g: linear(background.g),
                        b: linear(background.b),
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        image.draw(&mut encoder, &copied.view, None, true);
        gpu.queue
            .submit(uploads.into_iter().chain([encoder.finish()]));
        let a = direct.read_rgba(gpu).unwrap();
        let b = copied.read_rgba(gpu).unwrap();
        // Worst difference inside the panel (120 px wide, opaque) and over the view.
        let (mut panel, mut view) = (0u8, 0u8);
        for ((x, _, p), q) in a.enumerate_pixels().zip(b.pixels()) {
            let d = (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap();
            if x < 118 {
                panel = panel.max(d);
            } else {
                view = view.max(d);
            }
        }
        // Rounding only inside the panel; the label's soft edges over the view blend in linear
        // space in the copy.
        assert!(
            panel <= 3,
            "view formats {view_formats}: the copy differs from egui's drawing by {panel} of 255 in the panel"
        );
        assert!(
            view <= 64,
            "view formats {view_formats}: the copy differs from egui's drawing by {view} of 255 over the view"
        );
        // And the copy did draw: the panel's fill is not the background, the text over the view
        // is there, and the view away from the panel is untouched.
        let bg = b.get_pixel(200, 150).0;
        assert_ne!(b.get_pixel(60, 190).0, bg, "the panel's fill");
        assert!(
            (230..270).any(|x| b.get_pixel(x, 30).0 != bg),
            "the label over the view"
        );
        assert_eq!(a.get_pixel(200, 150).0, bg);
    }
}

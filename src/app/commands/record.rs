//! `lodlab record`: a clip for a perceptual study (Merry et al. §6.2), rendered offline.
//!
//! Frame k shows scene time k / fps, the camera on its path at that time, and selection steps
//! by exactly 1 / fps between frames: a clip is the same however slowly the machine renders
//! it. Before the first frame, selection runs over the second before it at 60 Hz, so the clip
//! opens with the levels and transitions a viewer would be in the middle of.

use crate::app::cli::RecordArgs;
use std::process::ExitCode;

use crate::app::progress::Progress;
use crate::app::video::Mp4Video;
use crate::atomic::{check_target, write_png};
use crate::render::DebugView;
use crate::runtime::headless::{Headless, ShotLod};
use crate::runtime::spec::SceneSpec;
use crate::scene::camera_path::PathKind;
use crate::scene::{CameraPath, Drive, LodMethod, SceneKind, Transition};
use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Clone, Debug)]
pub struct RecordOptions {
    pub spec: SceneSpec,
    /// Method, transition, tolerance, debug view, foliage (no comparison: a study shows one
    /// method per clip).
    pub lod: ShotLod,
    pub width: u32,
    pub height: u32,
    pub samples: u32,
    pub fps: u32,
    pub seconds: f32,
    /// The camera path, over the whole clip.
    pub path: PathKind,
    pub out: PathBuf,
    /// Also write every frame as a PNG here.
    pub frames_dir: Option<PathBuf>,
    pub progress: bool,
}

/// What `record` prints (one JSON line) and `study make` keeps per clip.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RecordReport {
    pub out: String,
    pub scene: SceneKind,
    pub models: Vec<String>,
    pub count: usize,
    pub method: LodMethod,
    pub transition: Transition,
    pub drive: Drive,
    pub tolerance_px: f32,
    pub debug_view: DebugView,
    pub path: PathKind,
    pub size: [u32; 2],
    pub fps: u32,
    pub seconds: f32,
    pub frames: u32,
    /// Means per frame, and the influences over all frames (what Merry et al. matched
    /// conditions by).
    pub triangles_per_frame: f64,
    pub influences_per_frame: f64,
    pub total_influences: u64,
    pub render_seconds: f64,
}

/// Frames of a clip: `seconds × fps`, rounded.
pub fn frame_count(seconds: f32, fps: u32) -> u32 {
    (seconds as f64 * fps as f64).round() as u32
}

/// Checks a frames folder: created if missing; refused if it holds anything, so that no file
/// of the user's is overwritten.
fn prepare_frames_dir(dir: &Path) -> Result<()> {
    if dir.is_file() {
        bail!("{}: is a file, not a folder for frames", dir.display());
    }
    if dir.is_dir() {
        let mut entries =
            std::fs::read_dir(dir).with_context(|| format!("{}: cannot read", dir.display()))?;
        if entries.next().is_some() {
            bail!(
                "{}: not empty; frames go into an empty or new folder",
                dir.display()
            );
        }
    }
    crate::atomic::make_folder(dir)
}

/// What rendering a clip's frames found (beside the frames themselves).
pub struct Rendered {
    pub models: Vec<String>,
    pub count: usize,
    pub frames: u32,
    pub triangles: u64,
    pub influences: u64,
    pub render_seconds: f64,
}

/// Renders the frames of the clip `o` describes, in order, handing each to `each` (frame
/// index, RGBA image) before the next is drawn: what [`run`] encodes, and what `study proxy`
/// scores before any encoding. `o.out` and `o.frames_dir` are not touched here.
pub fn render_frames(
    o: &RecordOptions,
    each: &mut dyn FnMut(u32, &image::RgbaImage) -> Result<()>,
) -> Result<Rendered> {
    if !(o.seconds.is_finite() && o.seconds > 0.0) {
        bail!("--seconds must be positive");
    }
    let frames = frame_count(o.seconds, o.fps);
    if frames == 0 {
        bail!("{} s at {} fps is no frame", o.seconds, o.fps);
    }
    let lod = &o.lod;
    if lod.compare.is_some() {
        bail!("a clip shows one method; record the two of a comparison as two clips");
    }
    let mut scene = Headless::new(
        &o.spec,
        o.width,
        o.height,
        Some(o.samples),
        &crate::measure::GpuMeasurer,
    )?;
    scene.show(lod)?;
    let Headless {
        gpu,
        target,
        mut world,
        ..
    } = scene;
    let home = world.camera;
    let path = CameraPath::new(o.path, &home, o.seconds);
    let aspect = o.width as f32 / o.height as f32;

    // The second before the clip at 60 Hz, then frame after frame at the clip's rate.
    let settle = 1.0 / 60.0;
    for k in (1..=60).rev() {
        let t = -(k as f32) * settle;
        world.camera = path.at(t, home.fov_y);
        world.select(o.height, t, settle);
    }
    let name = o
        .out
        .file_name()
        .map_or_else(|| "record".into(), |n| n.to_string_lossy().into_owned());
    let progress = Progress::new(o.progress, name, frames as u64);
    let started = Instant::now();
    let dt = 1.0 / o.fps as f32;
    let (mut triangles, mut influences) = (0u64, 0u64);
    for k in 0..frames {
        let t = k as f32 * dt;
        world.camera = path.at(t, home.fov_y);
        world.select(o.height, t, if k == 0 { settle } else { dt });
        let stats = world.upload(&gpu, aspect, t);
        triangles += stats.triangles;
        influences += stats.influences;
        world
            .renderer
            .render_to(&gpu, &target.targets, &target.view)?;
        let image = target.read_rgba(&gpu)?;
        each(k, &image)?;
        progress.inc();
    }
    progress.finish();
    Ok(Rendered {
        models: world.bakes.iter().map(|b| b.name.clone()).collect(),
        count: world.crowd.agents.len(),
        frames,
        triangles,
        influences,
        render_seconds: started.elapsed().as_secs_f64(),
    })
}

pub fn run(o: &RecordOptions) -> Result<RecordReport> {
    check_target(&o.out)?;
    // The encoder checks size and rate before anything is rendered.
    let mut video = Mp4Video::create(&o.out, o.width, o.height, o.fps)?;
    if let Some(dir) = &o.frames_dir {
        prepare_frames_dir(dir)?;
    }
    let r = render_frames(o, &mut |k, image| {
        video.push(image.as_raw())?;
        if let Some(dir) = &o.frames_dir {
            write_png(&dir.join(frame_file(k)), image)?;
        }
        Ok(())
    })?;
    let written = video.frames();
    video.finish()?;
    let lod = &o.lod;
    Ok(RecordReport {
        out: o.out.display().to_string(),
        scene: o.spec.scene,
        models: r.models,
        count: r.count,
        method: lod.method,
        transition: lod.policy.transition,
        drive: lod.policy.drive,
        tolerance_px: lod.policy.tolerance_px,
        debug_view: lod.debug,
        path: o.path,
        size: [o.width, o.height],
        fps: o.fps,
        seconds: o.seconds,
        frames: written,
        triangles_per_frame: r.triangles as f64 / r.frames as f64,
        influences_per_frame: r.influences as f64 / r.frames as f64,
        total_influences: r.influences,
        render_seconds: r.render_seconds,
    })
}

/// The file of frame `k` in a frames folder.
pub fn frame_file(k: u32) -> String {
    format!("frame_{k:04}.png")
}

/// `lodlab record`: a study clip as MP4.
pub fn command(
    a: RecordArgs,
    inputs: &crate::runtime::spec::BakeInputs,
) -> anyhow::Result<ExitCode> {
    let report = run(&RecordOptions {
        spec: a.scene.spec_or(SceneKind::Study, inputs),
        lod: ShotLod {
            method: a.method,
            policy: a.policy.policy(),
            debug: a.debug_view,
            foliage: a.foliage.view(),
            ..Default::default()
        },
        width: a.size.0,
        height: a.size.1,
        samples: a.msaa,
        fps: a.fps,
        seconds: a.seconds,
        path: a.path,
        out: a.out,
        frames_dir: a.frames_dir,
        progress: true,
    })?;
    println!("{}", crate::app::json::line(&report)?);
    Ok(ExitCode::SUCCESS)
}

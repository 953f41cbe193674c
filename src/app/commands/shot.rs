//! `lodlab shot`: render a scene headless and deterministically to a PNG.

use crate::app::cli::ShotArgs;
use crate::scene::LodMethod;
use std::process::ExitCode;

use crate::render::targets::Offscreen;
use crate::render::timer::{FrameTimer, PassTimes, overdraw_median, pass_medians};
use crate::render::{CharacterShader, FrameStats, Gpu};
use crate::runtime::headless::{Headless, ShotLod, time_renderer};
use crate::runtime::spec::SceneSpec;
use crate::runtime::world::World;
use crate::scene::Camera;
use anyhow::Result;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;

#[derive(Clone, Debug)]
pub struct ShotOptions {
    pub spec: SceneSpec,
    pub out: PathBuf,
    pub width: u32,
    pub height: u32,
    pub time: f32,
    /// Samples per pixel; `None` for the adapter's default (see [`crate::render::Gpu::samples`]).
    pub samples: Option<u32>,
    /// Overrides the scene's default camera.
    pub camera: Option<Camera>,
    /// Timed frames after one warm-up frame.
    pub timed_frames: usize,
    /// Also time the same triangles drawn by the trivial unskinned shader.
    pub calibrate: bool,
    pub lod: ShotLod,
    /// What the figures are drawn over.
    pub backdrop: crate::app::cli::values::Backdrop,
}

/// The JSON line `shot` prints.
#[derive(Clone, Debug, Serialize)]
pub struct ShotReport {
    pub out: String,
    pub scene: String,
    pub adapter: String,
    pub backend: String,
    pub size: [u32; 2],
    /// Samples per pixel drawn with.
    pub msaa: u32,
    pub time: f32,
    /// Instances drawn, and those outside the view left out.
    pub instances: u64,
    pub culled: u64,
    pub triangles: u64,
    pub vertices: u64,
    pub influences: u64,
    pub draw_calls: u32,
    /// The method drawn (on the left half in compare mode) and the one on the right.
    pub method: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub compare: Option<String>,
    pub transition: String,
    pub drive: String,
    pub tolerance_px: f32,
    pub debug_view: String,
    /// What trees become under a simplified method (the foliage level policy).
    pub foliage: String,
    /// How billboards are lit: "atlas" (per texel) or "flat" (one normal a billboard).
    pub billboard_lighting: String,
    /// Instances by level of detail, finest first (the last bin holds coarser ones too).
    pub levels: Vec<u32>,
    /// Instances by what their level shows (mesh, cloud, forest patch, ...), those drawn.
    pub level_kinds: BTreeMap<String, u32>,
    /// The layout's forest patches where they were asked for: how many, and the trees'
    /// height in pixels below which they are drawn (None: never, they measured worse).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forest_patches: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub patch_switch_px: Option<f32>,
    pub in_transition: u64,
    /// Median over the timed frames, submit to GPU completion.
    pub frame_ms: f64,
    /// Median GPU milliseconds of each pass drawn, by name, from timestamp queries (empty
    /// where the adapter has none).
    pub passes: BTreeMap<String, f64>,
    /// Median fragments shaded per pixel, where the adapter counts them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub overdraw: Option<f64>,
    /// Where memory goes, in MB by kind (see [`World::memory`]).
    pub memory_mb: BTreeMap<String, f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub plain_frame_ms: Option<f64>,
    /// `frame_ms / plain_frame_ms`: what skinning costs over a plain draw of the same triangles.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skinning_ratio: Option<f64>,
}

/// Renders `frames` times and returns the median frame time in milliseconds, and the frames'
/// passes where `timer` is given.
fn time_frames(
    gpu: &Gpu,
    world: &World,
    target: &Offscreen,
    frames: usize,
    timer: Option<&mut FrameTimer>,
) -> Result<(f64, Vec<PassTimes>)> {
    time_renderer(gpu, &world.renderer, target, frames, timer)
}

pub fn run(options: &ShotOptions) -> Result<ShotReport> {
    crate::atomic::check_target(&options.out)?;
    let Headless {
        gpu,
        target,
        mut world,
        samples,
        ..
    } = {
        let mut h = Headless::new(
            &options.spec,
            options.width,
            options.height,
            options.samples,
            &crate::measure::GpuMeasurer,
        )?;
        if let Some(c) = options.camera {
            h.world.camera = c;
        }
        if options.backdrop == crate::app::cli::values::Backdrop::Plain {
            let r = &mut h.world.renderer;
            (r.environment, r.shadows, r.lighting.fog_density) = (false, false, 0.0);
        }
        h.show(&options.lod)?;
        h
    };
    let lod = &options.lod;
    world.settle(options.height, options.time, lod.settle_seconds);
    let aspect = options.width as f32 / options.height as f32;
    let stats: FrameStats = world.upload(&gpu, aspect, options.time);

    // Warm-up (pipeline creation, first uploads), then timed frames.
    let mut timer = FrameTimer::new(&gpu);
    time_frames(&gpu, &world, &target, 1, None)?;
    let (frame_ms, passes) =
        time_frames(&gpu, &world, &target, options.timed_frames, timer.as_mut())?;
    let mut image = target.read_rgba(&gpu)?;
    if lod.compare.is_some() {
        draw_divider(&mut image);
    }

    let plain_frame_ms = if options.calibrate {
        world.renderer.shader = CharacterShader::Plain;
        time_frames(&gpu, &world, &target, 1, None)?;
        let (ms, _) = time_frames(&gpu, &world, &target, options.timed_frames, None)?;
        world.renderer.shader = CharacterShader::Skinned;
        Some(ms)
    } else {
        None
    };

    crate::atomic::write_png(&options.out, &image)?;
    Ok(ShotReport {
        out: options.out.display().to_string(),
        scene: options.spec.scene.to_string(),
        adapter: gpu.info.name.clone(),
        backend: gpu.backend_name(),
        size: [options.width, options.height],
        msaa: samples,
        time: options.time,
        instances: stats.instances,
        culled: stats.culled,
        triangles: stats.triangles,
        vertices: stats.vertices,
        influences: stats.influences,
        draw_calls: stats.draw_calls,
        method: lod.method.name().into(),
        compare: lod.compare.map(|m| m.name().into()),
        transition: lod.policy.transition.name().into(),
        drive: lod.policy.drive.name().into(),
        tolerance_px: lod.policy.tolerance_px,
        debug_view: lod.debug.name().into(),
        foliage: lod.foliage.policy.name().into(),
        billboard_lighting: if world.renderer.atlas_lighting {
            "atlas"
        } else {
            "flat"
        }
        .into(),
        levels: histogram(&stats.levels),
        level_kinds: crate::bake::gpu_data::drawable::LevelKind::ALL
            .into_iter()
            .filter(|&k| stats.kinds[k as usize] > 0)
            .map(|k| (k.name().to_string(), stats.kinds[k as usize]))
            .collect(),
        forest_patches: world.patches().map(|p| p.patches.len()),
        patch_switch_px: world.patches().and_then(|p| p.switch_px),
        in_transition: stats.in_transition,
        frame_ms,
        passes: pass_medians(&passes),
        memory_mb: world
            .memory(target.targets.bytes())
            .into_iter()
            .map(|(k, b)| (k.to_string(), (b as f64 / 1e6 * 10.0).round() / 10.0))
            .collect(),
        overdraw: overdraw_median(&passes, options.width, options.height),
        plain_frame_ms,
        skinning_ratio: plain_frame_ms.map(|p| frame_ms / p.max(1e-9)),
    })
}

/// The level histogram without its empty tail.
pub fn histogram(levels: &[u32]) -> Vec<u32> {
    let used = levels.iter().rposition(|&n| n > 0).map_or(0, |i| i + 1);
    levels[..used].to_vec()
}

/// The line between the halves of a comparison: two pixels of light grey down the middle.
fn draw_divider(image: &mut image::RgbaImage) {
    let (w, h) = image.dimensions();
    let x0 = (w / 2).saturating_sub(1);
    for x in x0..(x0 + 2).min(w) {
        for y in 0..h {
            image.put_pixel(x, y, image::Rgba([235, 235, 235, 255]));
        }
    }
}

/// `lodlab shot`: one PNG and a JSON line of figures.
pub fn command(a: ShotArgs, inputs: &crate::runtime::spec::BakeInputs) -> anyhow::Result<ExitCode> {
    let spec = a.scene.spec(inputs);
    let lod = a.lod.shot_lod(LodMethod::None);
    if lod.method != LodMethod::None {
        super::first_run::first_run_note(spec.cache_dir.as_deref(), true);
    }
    let report = run(&ShotOptions {
        spec,
        out: a.out,
        width: a.size.0,
        height: a.size.1,
        time: a.time,
        samples: a.msaa,
        camera: a.camera,
        timed_frames: a.frames,
        calibrate: a.calibrate,
        lod,
        backdrop: a.backdrop,
    })?;
    println!("{}", crate::app::json::line(&report)?);
    Ok(ExitCode::SUCCESS)
}

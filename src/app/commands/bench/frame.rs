//! What a bench draws a frame with: the scene taken apart ([`Bench`]), a frame shown as a 60 Hz
//! viewer would show it and timed, and the samples a method's frames add up to.

use crate::bake::gpu_data::drawable::LevelKind;
use crate::render::targets::Offscreen;
use crate::render::timer::{FrameTimer, Pass, PassTimes};
use crate::render::{CharacterShader, FrameStats, Gpu};
use crate::runtime::world::World;
use crate::scene::lod::MAX_LEVELS;
use crate::scene::{CameraPath, LodMethod};
use anyhow::Result;
use std::time::Instant;

/// Selection runs this many 60 Hz steps before every measured frame.
const SETTLE_STEPS: usize = 60;

/// The frame times and statistics of one method.
#[derive(Default)]
pub struct Samples {
    pub skinned: Vec<f64>,
    /// CPU milliseconds of each frame's selection and upload.
    pub cpu: Vec<f64>,
    /// The skinned frames' passes, where timed.
    pub passes: Vec<PassTimes>,
    pub plain: Vec<f64>,
    pub triangles: u64,
    pub vertices: u64,
    pub influences: u64,
    pub levels: [u64; MAX_LEVELS],
    pub in_transition: u64,
    pub kinds: [u64; LevelKind::COUNT],
    /// Per coverage view, each pass's fragments per pixel of the view, per pixel covered, and
    /// share covered.
    pub coverage: Vec<[Option<[f64; 3]>; Pass::COUNT]>,
    /// Per coverage view, each level kind drawn alone: its pass's GPU ms and fragments per
    /// pixel of the view.
    pub kind_costs: Vec<[Option<[f64; 2]>; LevelKind::COUNT]>,
}

/// The scene, its target and its timer: what a frame needs.
pub struct Bench {
    pub gpu: Gpu,
    pub world: World,
    pub target: Offscreen,
    pub timer: Option<FrameTimer>,
    pub path: CameraPath,
    pub fov_y: f32,
    pub size: [u32; 2],
}

impl Bench {
    /// Shows path time `t` as a 60 Hz viewer of `method` would, from a clean state; with
    /// the CPU milliseconds the frame itself took to select every instance's level and to
    /// encode and upload the instances (its last selection step and the upload).
    pub fn show(&mut self, method: LodMethod, t: f32) -> (FrameStats, f64) {
        let world = &mut self.world;
        world.lod.method = method;
        world.lod.reset();
        let dt = 1.0 / 60.0;
        for k in (1..=SETTLE_STEPS).rev() {
            let tk = t - k as f32 * dt;
            world.camera = self.path.at(tk, self.fov_y);
            world.select(self.size[1], tk, dt);
        }
        world.camera = self.path.at(t, self.fov_y);
        let start = Instant::now();
        world.select(self.size[1], t, dt);
        let stats = world.upload(&self.gpu, self.size[0] as f32 / self.size[1] as f32, t);
        (stats, start.elapsed().as_secs_f64() * 1e3)
    }

    /// Renders what is shown with `shader` and returns the frame's time in milliseconds, and
    /// its passes' figures where the adapter has timestamp queries.
    pub fn time(&mut self, shader: CharacterShader) -> Result<(f64, Option<PassTimes>)> {
        self.world.renderer.shader = shader;
        let start = Instant::now();
        self.world.renderer.render_timed(
            &self.gpu,
            &self.target.targets,
            &self.target.view,
            self.timer.as_mut(),
        )?;
        let timed = match &mut self.timer {
            Some(timer) => {
                let t = timer.read(&self.gpu)?;
                (t.frame_ms, Some(t))
            }
            None => {
                self.gpu.wait()?;
                (start.elapsed().as_secs_f64() * 1e3, None)
            }
        };
        self.world.renderer.shader = CharacterShader::Skinned;
        Ok(timed)
    }
}

/// Path time of frame `i` of `n`: the middles of `n` equal stretches of the path.
pub fn path_time(path: &CameraPath, i: usize, n: usize) -> f32 {
    path.duration() * (i as f32 + 0.5) / n as f32
}

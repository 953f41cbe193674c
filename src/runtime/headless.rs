//! The headless harness: a scene drawn without a window into an offscreen target, with the
//! level-of-detail choices a front end makes, and frame timing. `shot`, `bench`, `record`, the
//! study and the tests all drive worlds through it.

use super::levels::Measurer;
use super::spec::{Loaded, SceneSpec};
use super::world::World;
use crate::render::targets::Offscreen;
use crate::render::timer::{FrameTimer, PassTimes};
use crate::render::{DebugView, Gpu, SceneRenderer};
use crate::scene::foliage::FoliageView;
use crate::scene::{LodMethod, LodPolicy};
use anyhow::Result;
use web_time::Instant;

/// The level-of-detail choices of a headless frame (a shot's, a benchmark's, a clip's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShotLod {
    pub method: LodMethod,
    /// Compare mode: `method` on the left half, this on the right.
    pub compare: Option<LodMethod>,
    pub policy: LodPolicy,
    pub debug: DebugView,
    /// Light coarse levels through their normal maps (off: vertex normals everywhere).
    pub normal_maps: bool,
    /// What trees become, and how they look.
    pub foliage: FoliageView,
    /// Selection runs over this many seconds before the shot's time at 60 Hz, so that the
    /// frame shows the transitions a viewer would be in the middle of.
    pub settle_seconds: f32,
}

impl Default for ShotLod {
    fn default() -> Self {
        ShotLod {
            method: LodMethod::None,
            compare: None,
            policy: LodPolicy::default(),
            debug: DebugView::Shaded,
            normal_maps: true,
            foliage: FoliageView::default(),
            settle_seconds: 1.0,
        }
    }
}

/// A scene rendered without a window: a device, a target of the given size and the world.
pub struct Headless {
    pub gpu: Gpu,
    pub target: Offscreen,
    pub world: World,
    /// Samples per pixel, as asked or chosen for the adapter (see [`Gpu::samples`]).
    pub samples: u32,
    /// What a bake of levels measures (see [`Measurer`]).
    measure: &'static dyn Measurer,
}

impl Headless {
    /// Loads the models of `spec` (bad input fails here, before any GPU work), opens a device
    /// and builds the world into a `width`×`height` target, with `samples` per pixel (`None`:
    /// the adapter's default, see [`Gpu::samples`]); a bake of levels measures through `measure`.
    pub fn new(
        spec: &SceneSpec,
        width: u32,
        height: u32,
        samples: Option<u32>,
        measure: &'static dyn Measurer,
    ) -> Result<Headless> {
        Self::of(Loaded::new(spec.clone())?, width, height, samples, measure)
    }

    /// [`Self::new`] of a scene already loaded (over a cache of the caller's, say).
    pub fn of(
        loaded: Loaded,
        width: u32,
        height: u32,
        samples: Option<u32>,
        measure: &'static dyn Measurer,
    ) -> Result<Headless> {
        let gpu = Gpu::headless()?;
        // Said once a process: bench, soak and study proxy make several scenes.
        static SAID: std::sync::Once = std::sync::Once::new();
        SAID.call_once(|| eprintln!("lodlab: adapter {}", gpu.describe()));
        let samples = gpu.samples(samples);
        let target = Offscreen::new(&gpu, width, height, samples);
        let world = World::new(
            &gpu,
            loaded,
            crate::render::targets::OFFSCREEN_FORMAT,
            samples,
        )?;
        Ok(Headless {
            gpu,
            target,
            world,
            samples,
            measure,
        })
    }

    /// Takes the level-of-detail choices of `lod` and waits for the levels they need.
    pub fn show(&mut self, lod: &ShotLod) -> Result<()> {
        let world = &mut self.world;
        world.lod.method = lod.method;
        world.lod.compare = lod.compare;
        world.lod.policy = lod.policy;
        world.renderer.debug = lod.debug;
        world.renderer.normal_maps = lod.normal_maps;
        let mut foliage = lod.foliage;
        foliage.atlas_lighting = Some(
            self.gpu
                .atlas_lighting(foliage.atlas_lighting, world.has_trees()),
        );
        world.apply_foliage(&foliage);
        if lod.debug == DebugView::Wireframe && !world.renderer.has_wireframe() {
            anyhow::bail!(
                "--debug-view wireframe: this adapter cannot draw lines (POLYGON_MODE_LINE)"
            );
        }
        world.ensure_levels(&self.gpu, self.measure)?;
        if lod.foliage.patches {
            let colour = self.measure.colour(&self.gpu);
            world.ensure_patches(&self.gpu, colour.as_ref())
        } else {
            world.drop_patches();
            Ok(())
        }
    }
}

/// Renders what `renderer` has prepared `frames` times, waiting for the GPU each time, and
/// returns the median frame time in milliseconds (submit to completion), with each frame's
/// passes where `timer` is given.
pub fn time_renderer(
    gpu: &Gpu,
    renderer: &SceneRenderer,
    target: &Offscreen,
    frames: usize,
    mut timer: Option<&mut FrameTimer>,
) -> Result<(f64, Vec<PassTimes>)> {
    let mut times = Vec::with_capacity(frames);
    let mut passes = Vec::new();
    for _ in 0..frames.max(1) {
        let start = Instant::now();
        renderer.render_timed(gpu, &target.targets, &target.view, timer.as_deref_mut())?;
        match timer.as_deref_mut() {
            Some(t) => passes.push(t.read(gpu)?),
            None => gpu.wait()?,
        }
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok((median(times), passes))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        0.0
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

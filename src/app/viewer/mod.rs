//! `lodlab view`: the interactive viewer. A winit window, the scene renderer in the area right of
//! an egui side panel, and the camera controls of [`controls`].
//!
//! `--screenshot FILE --frames N` renders N frames of the real window, panel included, writes
//! the last one to FILE and exits: how the window itself is tested under Xvfb.

mod clipboard;
mod controls;
mod event_loop;
pub(crate) mod figures;
mod foliage_panel;
mod history;
mod inspect;
mod open;
mod options;
mod overlay;
mod panel;
mod panel_schedule;
mod patches;
mod select;
mod selection;
mod state;
#[cfg(target_arch = "wasm32")]
pub mod web;

use super::panel_image::PanelImage;
use super::window::{Began, PanelFrame, WindowGpu};
use crate::atomic::write_png;
use crate::render::DebugView;
use crate::render::FrameStats;
use crate::render::targets::{Offscreen, RenderTargets};
use crate::render::timer::{FrameTimer, Pass};
use crate::runtime::headless::ShotLod;
use crate::runtime::levels::{BackgroundBake, Poll};
use crate::runtime::spec::{Loaded, SceneSpec};
use crate::runtime::world::World;
use crate::scene::{LodMethod, Transition};
use anyhow::{Result, anyhow};
use controls::{Controls, KeyAction};
pub use event_loop::{display_available, run};
use history::FrameHistory;
use panel::{Info, Settings};
use panel_schedule::PanelSchedule;
use state::{Baking, Clock, Figures, Launch, Startup};
use std::path::PathBuf;
use web_time::Instant;
use winit::event::WindowEvent;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

/// The choice after `current` in `all`, wrapping round.
fn next<T: Copy + PartialEq>(all: &[T], current: T) -> T {
    let i = all.iter().position(|&x| x == current).map_or(0, |i| i + 1);
    all[i % all.len()]
}

#[derive(Clone, Debug)]
pub struct ViewOptions {
    pub spec: SceneSpec,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel; `None` for the adapter's default (see [`crate::render::Gpu::samples`]).
    pub samples: Option<u32>,
    pub screenshot: Option<PathBuf>,
    pub frames: usize,
    /// The level-of-detail choices the viewer starts with.
    pub lod: ShotLod,
}

struct Viewer {
    /// When it was launched, and whether its start-up figures were reported.
    startup: Startup,
    win: WindowGpu,
    world: World,
    targets: RenderTargets,
    egui: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    controls: Controls,
    settings: Settings,
    /// What the panel's figures show: frame times, passes, memory, the adapter.
    figures: Figures,
    model_names: Vec<String>,
    clip_names: Vec<Vec<String>>,
    /// The scene's time and the frames drawn.
    clock: Clock,
    /// The 3D view in physical pixels: x, y, width, height.
    view: [u32; 4],
    /// Levels of detail being baked in the background.
    baking: Baking,
    /// F12 asked for a screenshot of the next frame.
    screenshot_requested: bool,
    /// A line for the panel: where the last screenshot went, or why a model did not open.
    notice: Option<String>,
    /// The frame at which to destroy the device, to try recovery ([`LOSE_DEVICE_ENV`]).
    lose_device_at: Option<usize>,
    /// When the panel runs again (it is drawn as it was in between).
    panel: PanelSchedule,
    /// The panel's last drawing, copied onto each frame.
    panel_image: PanelImage,
    /// The instance looked at, the camera's bookmark, the recent files.
    selection: selection::Selection,
}

/// `LODLAB_LOSE_DEVICE_AT_FRAME=N` destroys the GPU device before frame N, as a driver reset
/// would lose it: how the recovery is tested.
const LOSE_DEVICE_ENV: &str = "LODLAB_LOSE_DEVICE_AT_FRAME";

/// How long the foliage settings must stay put before their chains are baked.
const SETTLE_BEFORE_BAKE: std::time::Duration = std::time::Duration::from_millis(400);

impl Viewer {
    fn new(
        event_loop: &ActiveEventLoop,
        options: &ViewOptions,
        loaded: Loaded,
        launched: Launch,
    ) -> Result<Viewer> {
        let attributes = Window::default_attributes()
            .with_title("lodlab")
            .with_inner_size(winit::dpi::PhysicalSize::new(options.width, options.height));
        let win = WindowGpu::open(event_loop, attributes, true)?;
        Self::with_window(win, options, loaded, launched)
    }

    /// The viewer in `win`, a window with its device (see [`Self::new`]).
    fn with_window(
        win: WindowGpu,
        options: &ViewOptions,
        loaded: Loaded,
        launched: Launch,
    ) -> Result<Viewer> {
        let (gpu, config) = (&win.gpu, &win.config);
        let samples = gpu.samples(options.samples);
        let mut world = World::new(gpu, loaded, win.format(), samples)?;
        world.lod.method = options.lod.method;
        world.lod.compare = options.lod.compare;
        world.lod.policy = options.lod.policy;
        world.renderer.debug = options.lod.debug;
        world.renderer.normal_maps = options.lod.normal_maps;
        let mut foliage = options.lod.foliage;
        foliage.atlas_lighting =
            Some(gpu.atlas_lighting(foliage.atlas_lighting, world.has_trees()));
        world.apply_foliage(&foliage);
        if options.screenshot.is_some() || world.levels_cached() {
            // A screenshot shows the levels asked for, so it waits for them; and levels all in
            // the cache load faster than a first frame at full detail draws, so the viewer
            // waits for those too. Anything to bake is baked in the background instead.
            world.ensure_levels(gpu, &crate::measure::GpuMeasurer)?;
            if foliage.patches {
                let colour =
                    crate::runtime::levels::Measurer::colour(&crate::measure::GpuMeasurer, gpu);
                if let Err(e) = world.ensure_patches(gpu, colour.as_ref()) {
                    eprintln!("warning: forest patches: {e:#}; the trees are drawn as they are");
                }
            }
        }
        let targets = RenderTargets::new(
            &gpu.device,
            config.width,
            config.height,
            win.format(),
            samples,
        );
        let (egui, egui_renderer) = win.egui();
        let panel_image = PanelImage::new(&gpu.device, win.format(), gpu.views_formats());
        let timer = FrameTimer::new(gpu);
        let settings = Settings {
            count: world.spec.count,
            model: None,
            clip: world.spec.clip.clone(),
            cross_fade: world.spec.cross_fade,
            playing: true,
            speed: 1.0,
            shadows: true,
            method: world.lod.method,
            compare: world.lod.compare,
            policy: world.lod.policy,
            debug: world.renderer.debug,
            normal_maps: world.renderer.normal_maps,
            foliage,
            impostors: world.lod.impostors_shown(),
            panel_shown: true,
        };
        let (adapter, backend) = (gpu.info.name.clone(), gpu.backend_name());
        Ok(Viewer {
            startup: Startup {
                launched,
                reported_first_frame: false,
                reported_levels: false,
            },
            model_names: world.bakes.iter().map(|b| b.name.clone()).collect(),
            clip_names: world.bakes.iter().map(|b| b.clip_names()).collect(),
            win,
            world,
            targets,
            egui,
            egui_renderer,
            controls: Controls::default(),
            settings,
            figures: Figures {
                history: FrameHistory::default(),
                adapter,
                backend,
                stats: FrameStats::default(),
                timer,
                passes: None,
                memory: Vec::new(),
                memory_at: None,
            },
            clock: Clock {
                started: Instant::now(),
                last_frame: None,
                time: 0.0,
                frames: 0,
            },
            view: [0, 0, 1, 1],
            baking: Baking {
                bake: None,
                bake_error: None,
                foliage_changed: Instant::now() - SETTLE_BEFORE_BAKE,
            },
            screenshot_requested: false,
            notice: None,
            lose_device_at: std::env::var(LOSE_DEVICE_ENV)
                .ok()
                .and_then(|v| v.parse().ok()),
            panel: PanelSchedule::default(),
            panel_image,
            selection: selection::Selection::load(),
        })
    }

    /// The first `lodlab-screenshot-N.png` in the working folder that is not there yet.
    fn screenshot_path() -> PathBuf {
        (1..)
            .map(|n| PathBuf::from(format!("lodlab-screenshot-{n}.png")))
            .find(|p| !p.exists())
            .expect("some number is free")
    }

    /// Takes a finished background bake in, and starts the next one a side needs.
    fn update_levels(&mut self) -> Result<()> {
        if let Some(job) = &mut self.baking.bake {
            // Each model's levels go in as soon as they are ready: the characters' within a
            // second or two, while the trees' chains take longer.
            let (ready, over) = match job.poll() {
                Poll::Running(ready) => (ready, false),
                Poll::Done(ready) => (ready, true),
                Poll::Failed => {
                    self.baking.bake_error = Some(format!("{}: the bake stopped", job.method));
                    (Vec::new(), true)
                }
            };
            let (method, chain) = (job.method, job.chain);
            if over {
                self.baking.bake = None;
            }
            if !ready.is_empty() {
                let installed = self
                    .world
                    .install_levels(&self.win.gpu, method, &chain, ready);
                if let Err(e) = installed {
                    self.baking.bake_error = Some(format!("{method}: {e:#}"));
                }
            }
            if !over {
                return Ok(());
            }
        }
        if self.world.missing_levels().is_none() {
            self.patches_as_asked()?;
        }
        if let Some(method) = self.world.missing_levels()
            && self.baking.bake_error.is_none()
            && self.baking.foliage_changed.elapsed() >= SETTLE_BEFORE_BAKE
        {
            // A page bakes nothing (its GPU read-backs cannot be waited for): it shows what
            // `lodlab web` wrote for it.
            if cfg!(target_arch = "wasm32") && !self.world.levels_cached() {
                self.baking.bake_error = Some(format!(
                    "{method}: these levels are not in the page's data (write the page with \
                     these settings: lodlab web)"
                ));
                return Ok(());
            }
            self.baking.bake = Some(BackgroundBake::start(
                self.win.gpu.clone(),
                self.world.sources.clone(),
                self.world.has_levels(method),
                method,
                self.world.lod.chain(),
                self.world.cache(),
                &crate::measure::GpuMeasurer,
            ));
        }
        Ok(())
    }

    /// Handles one window event; `Ok(false)` ends the viewer.
    fn handle(&mut self, event: &WindowEvent, options: &ViewOptions) -> Result<bool> {
        let response = self.egui.on_window_event(&self.win.window, event);
        match event {
            WindowEvent::CloseRequested => return Ok(false),
            WindowEvent::Resized(size) => {
                self.resize(size.width, size.height);
                self.panel.touch();
            }
            WindowEvent::RedrawRequested => return self.redraw(options),
            WindowEvent::DroppedFile(path) => self.open_model(path),
            _ => {
                let ctx = self.egui.egui_ctx();
                // The pointer is the camera's over the 3D view only: the wheel over the panel
                // scrolls the panel, whatever egui made of the last frame.
                let pointer_free = !response.consumed
                    && controls::over_view(self.controls.cursor(), self.view)
                    && (!ctx.egui_wants_pointer_input() || self.controls.is_dragging());
                let keyboard_free = !ctx.egui_wants_keyboard_input();
                let action = self.controls.on_event(
                    event,
                    &mut self.world.camera,
                    self.view[3] as f32,
                    pointer_free,
                    keyboard_free,
                );
                if action.is_some() {
                    // A key changed what the panel shows.
                    self.panel.touch();
                }
                let s = &mut self.settings;
                match action {
                    Some(KeyAction::TogglePlay) => s.playing = !s.playing,
                    Some(KeyAction::ResetCamera) => self.world.reset_camera(),
                    Some(KeyAction::NextMethod) => s.method = next(&LodMethod::ALL, s.method),
                    Some(KeyAction::NextTransition) => {
                        s.policy.transition = next(&Transition::ALL, s.policy.transition)
                    }
                    Some(KeyAction::NextDebugView) => {
                        let views: Vec<DebugView> = DebugView::ALL
                            .into_iter()
                            .filter(|&v| {
                                v != DebugView::Wireframe || self.world.renderer.has_wireframe()
                            })
                            .collect();
                        s.debug = next(&views, s.debug);
                    }
                    Some(KeyAction::ToggleCompare) => s.compare = panel::toggle_compare(s),
                    Some(KeyAction::Quit) => return Ok(false),
                    Some(KeyAction::ToggleFullscreen) => {
                        let window = &self.win.window;
                        window.set_fullscreen(match window.fullscreen() {
                            Some(_) => None,
                            None => Some(winit::window::Fullscreen::Borderless(None)),
                        });
                    }
                    // A page cannot wait for the read-back: the browser's own screenshot serves.
                    Some(KeyAction::Screenshot) if cfg!(target_arch = "wasm32") => {
                        self.notice = Some("no F12 screenshots in the browser".into());
                    }
                    Some(KeyAction::Screenshot) => self.screenshot_requested = true,
                    Some(KeyAction::TogglePanel) => {
                        s.panel_shown = !s.panel_shown;
                        self.panel.touch();
                    }
                    Some(KeyAction::Pick) => self.pick_at_cursor(),
                    Some(KeyAction::Frame) => self.frame_selection(),
                    Some(KeyAction::Bookmark) => self.bookmark(false),
                    Some(KeyAction::BackToBookmark) => self.bookmark(true),
                    Some(KeyAction::CopyCommand) => self.copy_command(),
                    None => {}
                }
            }
        }
        Ok(true)
    }

    /// Opens another device after the old one was lost (a driver reset, a GPU removed) and
    /// puts the scene back on it: the characters, the levels of detail from the cache (or
    /// baked again in the background), the panel's textures. The settings, the camera and the
    /// scene's time carry on.
    fn recover_device(&mut self) -> Result<()> {
        eprintln!("lodlab: the GPU device was lost; opening another and uploading the scene again");
        // A bake in flight may hold the old device; it starts again for what is missing.
        self.baking.bake = None;
        self.baking.bake_error = None;
        self.win.reopen_device()?;
        let gpu = &self.win.gpu;
        let old = &self.world;
        let loaded = Loaded {
            spec: old.spec.clone(),
            bakes: old.bakes.clone(),
            sources: old.sources.clone(),
            cache: old.cache(),
        };
        let mut world = World::new(gpu, loaded, self.win.format(), self.targets.sample_count)?;
        // The same walkers where they were, the camera where it was.
        world.camera = old.camera;
        world.crowd = old.crowd.clone();
        self.world = world;
        self.apply_lod_settings();
        if self.world.levels_cached() {
            self.world
                .ensure_levels(&self.win.gpu, &crate::measure::GpuMeasurer)?;
        }
        self.remake_targets();
        // A new egui context sends its whole font atlas again, to the new renderer.
        (self.egui, self.egui_renderer) = self.win.egui();
        self.win.panel.renderer_replaced();
        self.panel_image = PanelImage::new(
            &self.win.gpu.device,
            self.win.format(),
            self.win.gpu.views_formats(),
        );
        self.figures.timer = FrameTimer::new(&self.win.gpu);
        self.figures.passes = None;
        self.panel.touch();
        self.notice = Some("the GPU device was lost and has been reopened".into());
        eprintln!("lodlab: the scene is back on a new device");
        Ok(())
    }

    fn resize(&mut self, width: u32, height: u32) {
        self.win.resize(width, height);
        self.remake_targets();
    }

    /// The render targets again, for the surface's size on the current device.
    fn remake_targets(&mut self) {
        self.targets = RenderTargets::new(
            &self.win.gpu.device,
            self.win.config.width,
            self.win.config.height,
            self.win.format(),
            self.targets.sample_count,
        );
    }

    fn redraw(&mut self, options: &ViewOptions) -> Result<bool> {
        if self.lose_device_at == Some(self.clock.frames) {
            self.lose_device_at = None;
            eprintln!("lodlab: destroying the GPU device ({LOSE_DEVICE_ENV})");
            self.win.gpu.device.destroy();
        }
        if self.win.gpu.is_lost() {
            self.recover_device()?;
        }
        let dt = self.tick();
        self.upkeep()?;
        let (output, ran) = self.panel_if_due();
        let central = self.panel.central;
        let ppp = output
            .as_ref()
            .map_or(self.win.panel.pixels_per_point, |o| o.pixels_per_point);

        // The 3D view: what the panel leaves.
        let (w, h) = (self.win.config.width, self.win.config.height);
        let x0 = ((central.min.x * ppp).round().max(0.0) as u32).min(w - 1);
        let y0 = ((central.min.y * ppp).round().max(0.0) as u32).min(h - 1);
        let x1 = ((central.max.x * ppp).round() as u32).clamp(x0 + 1, w);
        let y1 = ((central.max.y * ppp).round() as u32).clamp(y0 + 1, h);
        self.view = [x0, y0, x1 - x0, y1 - y0];
        self.figures.stats = self.world.prepare(
            &self.win.gpu,
            [self.view[2], self.view[3]],
            self.clock.time,
            dt,
        );

        let panel_started = Instant::now();
        if output.is_some() {
            self.panel_image.stale();
        }
        let began = self
            .win
            .begin_frame(self.egui.egui_ctx(), &mut self.egui_renderer, output);
        // The panel's CPU time: running it, and tessellating and uploading its meshes.
        let panel_cpu = match ran {
            Some(run) => run + panel_started.elapsed(),
            None => std::time::Duration::ZERO,
        };
        self.panel.count(panel_cpu);
        let mut frame = match began {
            Ok(Began::Frame(f)) => f,
            Ok(Began::Skipped) => return Ok(true),
            Ok(Began::Reconfigure) => {
                self.resize(w, h);
                return Ok(true);
            }
            // The surface of a device lost since this frame began fails validation.
            Err(_) if self.win.gpu.is_lost() => return Ok(true),
            Err(e) => return Err(e),
        };
        self.encode_frame(&mut frame);
        if let Some(t) = &mut self.figures.timer {
            t.resolve(&mut frame.encoder);
        }

        // The screenshot: the same frame once more into a texture that can be read back.
        let last = options.screenshot.is_some() && self.clock.frames + 1 >= options.frames.max(1);
        let capture = (last || self.screenshot_requested).then(|| {
            let shot = Offscreen::with_format(
                &self.win.gpu,
                w,
                h,
                self.targets.sample_count,
                self.win.format(),
            );
            let renderer = &self.world.renderer;
            renderer.encode(
                &mut frame.encoder,
                &shot.targets,
                &shot.view,
                Some(self.view),
                None,
            );
            self.panel_image
                .draw(&mut frame.encoder, &shot.view, None, true);
            shot
        });
        if let Err(e) = self.win.finish_frame(&mut self.egui_renderer, frame) {
            // The next frame recovers a lost device.
            if self.win.gpu.is_lost() {
                return Ok(true);
            }
            return Err(e);
        }
        if let Some(t) = &mut self.figures.timer {
            t.submitted();
            if let Some(new) = t.try_read(&self.win.gpu)? {
                self.figures.passes = Some(match self.figures.passes {
                    Some(old) => old.smoothed(&new, 0.1),
                    None => new,
                });
            }
        }
        self.clock.frames += 1;
        self.report_start_up();

        if let Some(shot) = capture {
            if last && let Some(path) = &options.screenshot {
                self.write_screenshot(&shot, path)?;
                return Ok(false);
            }
            self.screenshot_requested = false;
            let path = Self::screenshot_path();
            let where_ = std::env::current_dir().map_or(path.clone(), |d| d.join(&path));
            self.panel.touch();
            self.notice = Some(match self.write_screenshot(&shot, &path) {
                Ok(()) => format!("screenshot: {}", where_.display()),
                Err(e) => format!("screenshot failed: {e:#}"),
            });
        }
        Ok(true)
    }

    /// Runs the panel if it is due (see [`PanelSchedule::due`]): its output, and the CPU time
    /// running it took.
    fn panel_if_due(&mut self) -> (Option<egui::FullOutput>, Option<std::time::Duration>) {
        let raw = self.egui.take_egui_input(&self.win.window);
        let started = Instant::now();
        let image = &self.panel_image;
        let ppp = self.win.panel.pixels_per_point;
        let attention = panel_schedule::Attention {
            covers: &|p| image.covers(p * ppp),
            keyboard: self.egui.egui_ctx().egui_wants_keyboard_input(),
        };
        let due = self.panel.due(started, &raw, attention);
        let output = due.then(|| self.run_panel(raw));
        let ran = output.is_some().then(|| started.elapsed());
        (output, ran)
    }

    /// Records the frame: the scene into the 3D view, the panel drawn again where it changed
    /// (its timing begins there), and the panel's image copied over the frame.
    fn encode_frame(&mut self, frame: &mut PanelFrame) {
        self.world.renderer.encode(
            &mut frame.encoder,
            &self.targets,
            &frame.view,
            Some(self.view),
            self.figures.timer.as_ref(),
        );
        // The panel drawn again where it changed (its timing begins there), then copied.
        let refreshed = self.panel_image.needs_refresh(frame.screen.size_in_pixels);
        if refreshed {
            self.panel_image.refresh(
                &self.win.gpu.device,
                &self.egui_renderer,
                &mut frame.encoder,
                &self.win.panel.primitives,
                &frame.screen,
                self.figures.timer.as_ref().map(|t| t.writes(Pass::Ui)),
            );
        }
        self.panel_image.draw(
            &mut frame.encoder,
            &frame.view,
            self.figures.timer.as_ref().map(|t| t.writes(Pass::Ui)),
            !refreshed,
        );
    }

    /// Says on stderr when the first frame was shown, and when every level the view asks for
    /// came in: what a user waits for at start-up.
    fn report_start_up(&mut self) {
        let seconds = self.startup.launched.at.elapsed().as_secs_f32();
        if !self.startup.reported_first_frame {
            self.startup.reported_first_frame = true;
            eprintln!(
                "lodlab: first frame after {seconds:.1} s (models loaded after {:.1} s, window \
                 and scene on the GPU after {:.1} s)",
                self.startup.launched.models_seconds, self.startup.launched.window_seconds
            );
        }
        if !self.startup.reported_levels
            && self.baking.bake.is_none()
            && self.world.missing_levels().is_none()
        {
            self.startup.reported_levels = true;
            eprintln!("lodlab: every level in place after {seconds:.1} s");
        }
    }

    /// Advances the clocks by the time since the last frame, and flies the camera: the
    /// frame's time step. The statistics get the frame's true time, however long; the
    /// animation too, unless the frame was a pause (see [`FrameHistory::animation_step`]).
    fn tick(&mut self) -> f32 {
        let now = Instant::now();
        let elapsed = self
            .clock
            .last_frame
            .map_or(0.0, |t| (now - t).as_secs_f32());
        let dt = self.figures.history.animation_step(elapsed);
        if self.clock.last_frame.is_some() {
            self.figures
                .history
                .push((now - self.clock.started).as_secs_f64(), elapsed * 1000.0);
        }
        self.clock.last_frame = Some(now);
        if self.settings.playing {
            self.clock.time += dt * self.settings.speed;
        }
        self.controls.fly(&mut self.world.camera, dt);
        self.follow_selection();
        dt
    }

    /// What every frame does besides drawing: levels baked and loaded, where memory goes
    /// (once a second: it reads /proc), the panel's settings handed to the world.
    fn upkeep(&mut self) -> Result<()> {
        self.update_levels()?;
        if self
            .figures
            .memory_at
            .is_none_or(|t| t.elapsed().as_secs_f32() >= 1.0)
        {
            self.figures.memory = self.world.memory(self.targets.bytes());
            self.figures.memory_at = Some(Instant::now());
        }
        self.world.renderer.shadows = self.settings.shadows;
        self.apply_lod_settings();
        Ok(())
    }

    /// Runs the panel on egui's input `raw` and acts on what it asked for: its output to
    /// draw. The rectangle it leaves to the 3D view goes to [`Self::panel`].
    fn run_panel(&mut self, raw: egui::RawInput) -> egui::FullOutput {
        let inspected = self
            .selection
            .picked
            .and_then(|i| self.world.inspect(i, self.view[3]));
        let info = Info {
            adapter: &self.figures.adapter,
            backend: &self.figures.backend,
            models: &self.model_names,
            clips: &self.clip_names,
            stats: self.figures.stats,
            passes: self.figures.passes,
            view_pixels: self.view[2] as u64 * self.view[3] as u64,
            panel_cpu_ms: self.panel.cpu_ms(),
            memory: &self.figures.memory,
            time: self.clock.time,
            baking: self
                .baking
                .bake
                .as_ref()
                .map(|b| (b.status(), b.fraction())),
            bake_error: self.baking.bake_error.as_deref(),
            wireframe: self.world.renderer.has_wireframe(),
            ready: LodMethod::ALL.map(|m| self.world.lod.has(m)),
            trees: self.world.bakes.iter().any(|b| b.kind.is_tree()),
            chains: self.world.shown_chains(),
            impostors: self.world.impostor_summary(),
            normal_maps: self.world.normal_map_summary(),
            notice: self.notice.as_deref(),
            selection: inspect::SelectionInfo {
                inspected: inspected.as_ref(),
                just_picked: std::mem::take(&mut self.selection.just_picked),
                bookmarked: self.selection.bookmark.is_some(),
                command: self.selection.command.as_deref(),
                recent: &self.selection.recent,
            },
        };
        let (settings, history) = (&mut self.settings, &self.figures.history);
        let mut requests = panel::Requests::default();
        let mut central = egui::Rect::NOTHING;
        let ctx = self.egui.egui_ctx().clone();
        panel::zoom_for_window(&ctx, [self.win.config.width, self.win.config.height]);
        let mut output = ctx.run_ui(raw, |ui| {
            (requests, central) = panel::frame(ui, settings, history, &info);
        });
        self.egui.handle_platform_output(
            &self.win.window,
            std::mem::take(&mut output.platform_output),
        );
        if requests.relayout {
            // Instances are laid out afresh: an index no longer names the one picked.
            self.selection.picked = None;
            self.world.spec.cross_fade = self.settings.cross_fade;
            self.world.relayout(
                self.settings.model,
                self.settings.count,
                self.settings.clip.clone(),
            );
        }
        if requests.reset_camera {
            self.world.reset_camera();
        }
        let repaint = output
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .map_or(std::time::Duration::MAX, |v| v.repaint_delay);
        self.panel.ran(Instant::now(), central, repaint);
        if requests.open {
            self.pick_and_open();
        }
        self.act_on_selection(&requests.selection);
        // What the panel changed reaches the world this frame.
        self.world.renderer.shadows = self.settings.shadows;
        self.apply_lod_settings();
        output
    }

    /// Writes the screenshot taken into `shot` (the window's size) to `path` as an RGBA PNG.
    fn write_screenshot(&self, shot: &Offscreen, path: &std::path::Path) -> Result<()> {
        let (w, h) = (self.win.config.width, self.win.config.height);
        let mut bytes = shot.read_bytes(&self.win.gpu)?;
        if matches!(
            self.win.format(),
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        ) {
            for px in bytes.chunks_exact_mut(4) {
                px.swap(0, 2);
            }
        }
        let image = image::RgbaImage::from_raw(w, h, bytes)
            .ok_or_else(|| anyhow!("screenshot size mismatch"))?;
        write_png(path, &image)?;
        let panel_gpu = self
            .figures
            .passes
            .and_then(|p| p.ms[Pass::Ui as usize])
            .map_or(String::new(), |ms| format!(", {ms:.2} ms of GPU"));
        eprintln!(
            "lodlab: wrote {} after {} frames ({:.1} fps; the panel took {:.2} ms of CPU{panel_gpu} a frame)",
            path.display(),
            self.clock.frames,
            self.figures.history.fps(),
            self.panel.cpu_ms(),
        );
        Ok(())
    }

    /// Hands the panel's level-of-detail choices to the world; a change of method (or of the
    /// comparison) restarts selection, and a failed bake may be retried.
    fn apply_lod_settings(&mut self) {
        let s = &self.settings;
        let lod = &mut self.world.lod;
        if lod.method != s.method || lod.compare != s.compare {
            lod.method = s.method;
            lod.compare = s.compare;
            lod.reset();
            self.baking.bake_error = None;
        }
        if lod.policy.transition != s.policy.transition || lod.policy.drive != s.policy.drive {
            lod.reset();
        }
        lod.policy = s.policy;
        self.world.show_impostors(s.impostors);
        self.world.renderer.debug = s.debug;
        self.world.renderer.normal_maps = s.normal_maps;
        let chain_before = (self.world.lod.foliage(), self.world.lod.chain());
        self.world.apply_foliage(&s.foliage);
        if (self.world.lod.foliage(), self.world.lod.chain()) != chain_before {
            self.baking.foliage_changed = Instant::now();
            self.baking.bake_error = None;
        }
    }
}

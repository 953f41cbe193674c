//! `lodlab study run`: a participant's session in a window. Each trial plays its two clips one
//! after the other, full size on black, never side by side (Merry et al. §6.2: so that clips
//! are judged as wholes, not compared pixel by pixel), then asks for a forced choice with the
//! keys 1 and 2. Escape leaves; the answers given so far are on disk and the session resumes
//! at the next trial.

use super::session::{CHOICES, GAP, INSTRUCTIONS, QUESTION, Session, THANKS};
use crate::app::video::ClipReader;
use crate::app::viewer::display_available;
use crate::app::window::{Began, WindowGpu, draw_panel};
use anyhow::{Context, Result};
use std::process::ExitCode;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, KeyEvent, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Fullscreen, Window, WindowId};

pub struct RunOptions {
    pub fullscreen: bool,
    pub width: u32,
    pub height: u32,
}

/// Where the participant is.
enum Stage {
    /// Before the first trial (or a resumed one): press space.
    Welcome,
    /// A short grey screen, then clip `which` (1 or 2) of the current trial.
    Gap {
        until: Instant,
        which: u8,
    },
    Playing {
        which: u8,
        clip: Box<ClipReader>,
        started: Instant,
        shown: u32,
    },
    /// Waiting for 1 or 2.
    Ask,
    Done,
}

pub fn run(mut session: Session, o: RunOptions) -> Result<ExitCode> {
    if !display_available() {
        eprintln!("lodlab: no display to open a window on (DISPLAY and WAYLAND_DISPLAY are unset)");
        return Ok(ExitCode::from(2));
    }
    let event_loop = EventLoop::new().context("cannot open a window")?;
    let stage = if session.current().is_some() {
        Stage::Welcome
    } else {
        Stage::Done
    };
    let mut app = App {
        options: o,
        screen: None,
        stage,
        error: None,
        session: &mut session,
    };
    event_loop.run_app(&mut app).context("window event loop")?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(ExitCode::SUCCESS),
    }
}

struct App<'a> {
    options: RunOptions,
    screen: Option<StudyWindow>,
    stage: Stage,
    error: Option<anyhow::Error>,
    session: &'a mut Session,
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.screen.is_none() {
            match StudyWindow::new(event_loop, &self.options) {
                Ok(w) => self.screen = Some(w),
                Err(e) => {
                    self.error = Some(e);
                    event_loop.exit();
                }
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match self.handle(&event) {
            Ok(true) => {}
            Ok(false) => event_loop.exit(),
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some(w) = &self.screen {
            w.win.window.request_redraw();
        }
    }
}

impl App<'_> {
    /// One window event; `Ok(false)` closes the window.
    fn handle(&mut self, event: &WindowEvent) -> Result<bool> {
        let Some(w) = &mut self.screen else {
            return Ok(true);
        };
        let _ = w.egui.on_window_event(&w.win.window, event);
        match event {
            WindowEvent::CloseRequested => return Ok(false),
            WindowEvent::Resized(size) => w.win.resize(size.width, size.height),
            WindowEvent::KeyboardInput {
                event:
                    KeyEvent {
                        logical_key,
                        state: ElementState::Pressed,
                        repeat: false,
                        ..
                    },
                ..
            } => return self.key(logical_key),
            WindowEvent::RedrawRequested => {
                self.advance()?;
                let text = self.caption();
                let w = self.screen.as_mut().expect("checked above");
                w.draw(&text)?;
            }
            _ => {}
        }
        Ok(true)
    }

    fn key(&mut self, key: &Key) -> Result<bool> {
        if matches!(key, Key::Named(NamedKey::Escape)) {
            return Ok(false);
        }
        let choice = match key {
            Key::Character(c) if c == "1" => Some(1),
            Key::Character(c) if c == "2" => Some(2),
            _ => None,
        };
        match (&self.stage, choice) {
            (Stage::Welcome, None) if matches!(key, Key::Named(NamedKey::Space)) => {
                self.stage = Stage::Gap {
                    until: Instant::now() + GAP,
                    which: 1,
                };
            }
            (Stage::Ask, Some(c)) => {
                self.session.answer(c)?;
                self.stage = if self.session.current().is_some() {
                    Stage::Gap {
                        until: Instant::now() + GAP,
                        which: 1,
                    }
                } else {
                    Stage::Done
                };
            }
            _ => {}
        }
        Ok(true)
    }

    /// Moves the stage on with the clock, and puts the frame due on screen.
    fn advance(&mut self) -> Result<()> {
        let now = Instant::now();
        match &mut self.stage {
            Stage::Gap { until, which } if now >= *until => {
                let which = *which;
                let t = self.session.current().context("a trial to play")?;
                let file = if which == 1 {
                    &t.first_clip
                } else {
                    &t.second_clip
                };
                let clip = ClipReader::open(&self.session.clip(file))?;
                self.stage = Stage::Playing {
                    which,
                    clip: Box::new(clip),
                    started: now,
                    shown: 0,
                };
            }
            Stage::Playing {
                which,
                clip,
                started,
                shown,
            } => {
                // Frames are due at the clip's own rate; a late one is decoded and skipped.
                let due = ((now - *started).as_secs_f64() * clip.fps).floor() as u32 + 1;
                let mut latest = None;
                while *shown < due.min(clip.frames) {
                    latest = clip.next_frame()?;
                    *shown += 1;
                }
                if let (Some(image), Some(w)) = (latest, self.screen.as_mut()) {
                    w.show_frame(&image);
                }
                if *shown >= clip.frames && due > clip.frames {
                    let which = *which;
                    if let Some(w) = self.screen.as_mut() {
                        w.hide_frame();
                    }
                    self.stage = if which == 1 {
                        Stage::Gap {
                            until: now + GAP,
                            which: 2,
                        }
                    } else {
                        Stage::Ask
                    };
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// What the screen says at this stage (nothing while a clip plays).
    fn caption(&self) -> String {
        let s = &self.session;
        let progress = format!("{} of {} answered", s.answered(), s.total());
        match &self.stage {
            Stage::Welcome => format!(
                "Participant {}\n\n{INSTRUCTIONS}\n\n\
                 Press space to start. Escape stops; you can go on later.\n\n{progress}",
                s.participant
            ),
            Stage::Gap { which, .. } => format!("Clip {which}"),
            Stage::Playing { .. } => String::new(),
            Stage::Ask => format!("{QUESTION}\n\n{CHOICES}\n\n{progress}"),
            Stage::Done => format!("{THANKS}\n\nEscape closes the window."),
        }
    }
}

/// The window, its surface and egui, which draws everything (clips are egui textures).
struct StudyWindow {
    win: WindowGpu,
    egui: egui_winit::State,
    renderer: egui_wgpu::Renderer,
    frame: Option<egui::TextureHandle>,
    showing: bool,
}

impl StudyWindow {
    fn new(event_loop: &ActiveEventLoop, o: &RunOptions) -> Result<StudyWindow> {
        let mut attributes = Window::default_attributes()
            .with_title("lodlab study")
            .with_inner_size(winit::dpi::PhysicalSize::new(o.width, o.height));
        if o.fullscreen {
            attributes = attributes.with_fullscreen(Some(Fullscreen::Borderless(None)));
        }
        let win = WindowGpu::open(event_loop, attributes, false)?;
        let (egui, renderer) = win.egui();
        Ok(StudyWindow {
            win,
            egui,
            renderer,
            frame: None,
            showing: false,
        })
    }

    fn show_frame(&mut self, image: &image::RgbaImage) {
        let size = [image.width() as usize, image.height() as usize];
        let colour = egui::ColorImage::from_rgba_unmultiplied(size, image.as_raw());
        match &mut self.frame {
            Some(t) => t.set(colour, egui::TextureOptions::LINEAR),
            None => {
                self.frame = Some(self.egui.egui_ctx().load_texture(
                    "clip",
                    colour,
                    egui::TextureOptions::LINEAR,
                ))
            }
        }
        self.showing = true;
    }

    fn hide_frame(&mut self) {
        self.showing = false;
    }

    /// One frame: the clip's picture (as large as fits, on black) or the caption (on grey).
    fn draw(&mut self, caption: &str) -> Result<()> {
        let raw = self.egui.take_egui_input(&self.win.window);
        let frame = self.frame.clone().filter(|_| self.showing);
        let output = self.egui.egui_ctx().clone().run_ui(raw, |ui| {
            let fill = if frame.is_some() {
                egui::Color32::BLACK
            } else {
                egui::Color32::from_gray(96)
            };
            egui::CentralPanel::default()
                .frame(egui::Frame::NONE.fill(fill))
                .show(ui, |ui| {
                    let area = ui.available_rect_before_wrap();
                    if let Some(t) = &frame {
                        let [w, h] = t.size().map(|x| x as f32);
                        let scale = (area.width() / w).min(area.height() / h);
                        let rect =
                            egui::Rect::from_center_size(area.center(), egui::vec2(w, h) * scale);
                        ui.painter().image(
                            t.id(),
                            rect,
                            egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                            egui::Color32::WHITE,
                        );
                    } else {
                        // Wrapped to the window, centred both ways.
                        ui.centered_and_justified(|ui| {
                            ui.label(
                                egui::RichText::new(caption)
                                    .size(22.0)
                                    .color(egui::Color32::WHITE),
                            );
                        });
                    }
                });
        });
        let mut output = output;
        self.egui.handle_platform_output(
            &self.win.window,
            std::mem::take(&mut output.platform_output),
        );
        let began = self
            .win
            .begin_frame(self.egui.egui_ctx(), &mut self.renderer, Some(output))?;
        let mut frame = match began {
            Began::Frame(f) => f,
            Began::Skipped => return Ok(()),
            Began::Reconfigure => {
                let (w, h) = (self.win.config.width, self.win.config.height);
                self.win.resize(w, h);
                return Ok(());
            }
        };
        draw_panel(
            &self.renderer,
            &mut frame.encoder,
            &frame.view,
            &self.win.panel.primitives,
            &frame.screen,
            "study",
            Some(wgpu::Color::BLACK),
            None,
        );
        self.win.finish_frame(&mut self.renderer, frame)
    }
}

//! The viewer's event loop: winit's application handler opening the window and handing it
//! events, and `lodlab view`'s entry, which says in one line what is missing where no display
//! or windowing library is there.

use super::{Launch, ViewOptions, Viewer};
use crate::runtime::spec::Loaded;
use anyhow::{Context, Result};
use std::process::ExitCode;
use web_time::Instant;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::WindowId;

/// Printed, with exit code 2, where no window can be opened.
pub const NO_DISPLAY: &str = "lodlab: no display to open a window on (DISPLAY and WAYLAND_DISPLAY are unset); \
     to render without one use `lodlab shot --out FILE.png`";

/// Is there a display server to talk to? On Linux and the BSDs that means X11 or Wayland.
pub fn display_available() -> bool {
    if cfg!(all(unix, not(target_os = "macos"))) {
        std::env::var_os("DISPLAY").is_some_and(|d| !d.is_empty())
            || std::env::var_os("WAYLAND_DISPLAY").is_some_and(|d| !d.is_empty())
    } else {
        true
    }
}

pub fn run(options: ViewOptions) -> Result<ExitCode> {
    if !display_available() {
        eprintln!("{NO_DISPLAY}");
        return Ok(ExitCode::from(2));
    }
    if let Some(path) = &options.screenshot {
        crate::atomic::check_target(path)?;
    }
    let launched = Instant::now();
    let loaded = Loaded::new(options.spec.clone())?;
    let models_seconds = launched.elapsed().as_secs_f32();
    // winit loads the windowing system's libraries at run time, and panics where one it
    // needs is missing: say which package holds it, in one line.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let created = std::panic::catch_unwind(EventLoop::new);
    std::panic::set_hook(hook);
    let event_loop = match created {
        Ok(Ok(el)) => el,
        Ok(Err(e)) => {
            if let Some(line) = crate::app::window::missing_library(&e.to_string()) {
                anyhow::bail!(line);
            }
            eprintln!("{NO_DISPLAY} ({e})");
            return Ok(ExitCode::from(2));
        }
        Err(panic) => {
            let message = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            match crate::app::window::missing_library(&message) {
                Some(line) => anyhow::bail!(line),
                None => anyhow::bail!("cannot open a window: {message}"),
            }
        }
    };
    let mut app = App {
        options,
        launched: Launch {
            at: launched,
            models_seconds,
            window_seconds: 0.0,
        },
        loaded: Some(loaded),
        viewer: None,
        error: None,
    };
    event_loop.run_app(&mut app).context("window event loop")?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(ExitCode::SUCCESS),
    }
}

pub(crate) struct App {
    options: ViewOptions,
    launched: Launch,
    loaded: Option<Loaded>,
    viewer: Option<Viewer>,
    error: Option<anyhow::Error>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.viewer.is_some() {
            return;
        }
        let Some(loaded) = self.loaded.take() else {
            return;
        };
        match Viewer::new(event_loop, &self.options, loaded, self.launched) {
            Ok(mut v) => {
                v.startup.launched.window_seconds = self.launched.at.elapsed().as_secs_f32();
                self.viewer = Some(v)
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(viewer) = &mut self.viewer else {
            return;
        };
        match viewer.handle(&event, &self.options) {
            Ok(true) => {}
            Ok(false) => event_loop.exit(),
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        // Always animating: ask for the next frame straight away.
        if let Some(v) = &self.viewer {
            v.win.window.request_redraw();
        }
    }
}

//! The viewer in a browser: the same [`Viewer`], its panel and controls, drawn by wgpu on the
//! page's WebGPU (WebGL2 where the browser has none) into a canvas winit made.
//!
//! What differs from the desktop is only how it starts, because a page may not block: the
//! manifest and the levels `lodlab web` put beside the page are fetched first (all at once,
//! with their progress on the page), and handed to the cache's memory (see
//! [`crate::bake::cache::memory`]), so that the world reads them exactly as the desktop reads its
//! cache and bakes nothing; then the window's device is asked for, and the viewer is built
//! when the browser answers (a user event of the event loop). What the page shows each half
//! second (frames, frame rate, triangles, method) is also written on the page's `<body>` as
//! `data-` attributes, for scripts and tests.

use super::{Launch, ViewOptions, Viewer};
use crate::app::site::{LEVELS, MANIFEST, SiteManifest};
use crate::app::window::WindowGpu;
use crate::runtime::spec::Loaded;
use anyhow::{Context, Result, anyhow};
use std::sync::Arc;
use wasm_bindgen::JsCast;
use wasm_bindgen_futures::JsFuture;
use web_time::Instant;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop, EventLoopProxy};
use winit::platform::web::{EventLoopExtWebSys, WindowAttributesExtWebSys};
use winit::window::{Window, WindowId};

/// The page's entry: everything happens once the browser has answered, so this only starts it.
pub fn start() {
    console_error_panic_hook::set_once();
    let _ = log::set_logger(&CONSOLE).map(|()| log::set_max_level(log::LevelFilter::Info));
    wasm_bindgen_futures::spawn_local(async {
        if let Err(e) = run().await {
            log::error!("{e:#}");
            status(&format!("lodlab could not start: {e:#}"), true);
        }
    });
}

/// Fetches the page's data, then runs the viewer's event loop on the page.
async fn run() -> Result<()> {
    let launched = Instant::now();
    status("Loading the scene…", false);
    let manifest: SiteManifest = serde_json::from_slice(&fetch(MANIFEST).await?)
        .map_err(|e| anyhow!("{MANIFEST}: not a lodlab web manifest: {e}"))?;
    if manifest.lodlab != env!("CARGO_PKG_VERSION") {
        log::warn!(
            "{MANIFEST} was written by lodlab {}, this is {}",
            manifest.lodlab,
            env!("CARGO_PKG_VERSION")
        );
    }
    let options = crate::app::site::view_options(&manifest.view)?;
    let cache = crate::bake::cache::LodCache::new(options.spec.cache_dir.clone());
    fetch_levels(&manifest, &cache).await?;
    let loaded = Loaded::new(options.spec.clone())?.with_cache(cache);
    let models_seconds = launched.elapsed().as_secs_f32();
    status("Opening the GPU…", false);
    let event_loop = EventLoop::<Ready>::with_user_event()
        .build()
        .context("cannot start the page's event loop")?;
    let proxy = event_loop.create_proxy();
    event_loop.spawn_app(WebApp {
        options,
        loaded: Some(loaded),
        launched: Launch {
            at: launched,
            models_seconds,
            window_seconds: 0.0,
        },
        proxy,
        asked: false,
        viewer: None,
        shown_at: None,
    });
    Ok(())
}

/// Every file the manifest lists, fetched at once (the browser runs the requests together),
/// into the cache's memory, with the bytes so far on the page.
async fn fetch_levels(manifest: &SiteManifest, cache: &crate::bake::cache::LodCache) -> Result<()> {
    let total = manifest.total_bytes().max(1) as f64;
    let pending: Vec<(String, JsFuture)> = manifest
        .files
        .iter()
        .map(|f| Ok((f.name.clone(), request(&format!("{LEVELS}/{}", f.name))?)))
        .collect::<Result<_>>()?;
    let mut done = 0.0;
    for (name, response) in pending {
        let bytes = body(&format!("{LEVELS}/{name}"), response).await?;
        done += bytes.len() as f64;
        status(
            &format!(
                "Loading the levels of detail: {:.0} of {:.0} MB",
                done / 1e6,
                total / 1e6
            ),
            false,
        );
        cache.memory.preload(&name, bytes);
    }
    Ok(())
}

/// The window's device, as the browser gave it.
struct Ready(Result<WindowGpu>);

struct WebApp {
    options: ViewOptions,
    loaded: Option<Loaded>,
    launched: Launch,
    proxy: EventLoopProxy<Ready>,
    /// Whether the window and its device have been asked for.
    asked: bool,
    viewer: Option<Viewer>,
    /// When the page's figures were last written.
    shown_at: Option<Instant>,
}

impl ApplicationHandler<Ready> for WebApp {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.asked {
            return;
        }
        self.asked = true;
        let attributes = Window::default_attributes()
            .with_title("lodlab")
            .with_append(true)
            .with_prevent_default(true)
            .with_focusable(true);
        let window = match event_loop.create_window(attributes) {
            Ok(w) => Arc::new(w),
            Err(e) => return fail(&anyhow!("cannot make the canvas: {e}")),
        };
        let proxy = self.proxy.clone();
        wasm_bindgen_futures::spawn_local(async move {
            let desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
            // WebGPU where the browser has it, else WebGL2.
            let instance = wgpu::util::new_instance_with_webgpu_detection(desc).await;
            let ready = WindowGpu::connect(window, instance, true).await;
            let _ = proxy.send_event(Ready(ready));
        });
    }

    fn user_event(&mut self, _: &ActiveEventLoop, ready: Ready) {
        let Some(loaded) = self.loaded.take() else {
            return;
        };
        let viewer = ready.0.and_then(|win| {
            if let Some(canvas) = winit::platform::web::WindowExtWebSys::canvas(&*win.window) {
                let _ = canvas.focus();
            }
            Viewer::with_window(win, &self.options, loaded, self.launched)
        });
        match viewer {
            Ok(mut v) => {
                v.startup.launched.window_seconds = self.launched.at.elapsed().as_secs_f32();
                status("", false);
                self.viewer = Some(v);
            }
            Err(e) => fail(&e),
        }
    }

    fn window_event(&mut self, _: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(viewer) = &mut self.viewer else {
            return;
        };
        let redraw = matches!(event, WindowEvent::RedrawRequested);
        // A page is not closed from inside: Esc and Ctrl+Q do nothing here.
        if let Err(e) = viewer.handle(&event, &self.options) {
            fail(&e);
            self.viewer = None;
            return;
        }
        if redraw
            && self
                .shown_at
                .is_none_or(|t| t.elapsed().as_secs_f32() >= 0.5)
        {
            self.shown_at = Some(Instant::now());
            show_figures(viewer);
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some(v) = &self.viewer {
            v.win.window.request_redraw();
        }
    }
}

/// The viewer's figures on the page's `<body>`: `data-frames`, `data-fps`, `data-triangles`,
/// `data-method`, `data-adapter`, `data-camera` (yaw and pitch in radians, distance),
/// `data-first-frame-ms`.
fn show_figures(v: &Viewer) {
    let Some(body) = web_sys::window()
        .and_then(|w| w.document())
        .and_then(|d| d.body())
    else {
        return;
    };
    let first =
        (v.clock.frames > 0).then(|| v.startup.launched.at.elapsed().as_millis().to_string());
    let set = |k: &str, value: String| {
        let _ = body.set_attribute(&format!("data-{k}"), &value);
    };
    set("frames", v.clock.frames.to_string());
    set("fps", format!("{:.1}", v.figures.history.fps()));
    set("triangles", v.figures.stats.triangles.to_string());
    set("method", v.world.lod.method.name().to_string());
    set("adapter", v.win.gpu.describe());
    let c = &v.world.camera;
    set(
        "camera",
        format!("{:.4} {:.4} {:.3}", c.yaw, c.pitch, c.distance),
    );
    if body.get_attribute("data-first-frame-ms").is_none()
        && let Some(ms) = first
    {
        set("first-frame-ms", ms);
    }
}

/// A failure, on the page and the console.
fn fail(e: &anyhow::Error) {
    log::error!("{e:#}");
    status(&format!("lodlab stopped: {e:#}"), true);
}

/// The line over the canvas (empty: none).
fn status(text: &str, error: bool) {
    let Some(el) = web_sys::window()
        .and_then(|w| w.document())
        .and_then(|d| d.get_element_by_id("status"))
    else {
        return;
    };
    el.set_text_content(Some(text));
    if error {
        el.set_class_name("error");
    }
}

/// Starts fetching `url` (relative to the page).
fn request(url: &str) -> Result<JsFuture> {
    let window = web_sys::window().ok_or_else(|| anyhow!("no window"))?;
    Ok(JsFuture::from(window.fetch_with_str(url)))
}

/// The body of the response `pending` is for, all of it.
async fn body(url: &str, pending: JsFuture) -> Result<Vec<u8>> {
    let js = |e: wasm_bindgen::JsValue| anyhow!("{url}: {e:?}");
    let response: web_sys::Response = pending.await.map_err(js)?.dyn_into().map_err(js)?;
    if !response.ok() {
        return Err(anyhow!("{url}: the server answered {}", response.status()));
    }
    let buffer = JsFuture::from(response.array_buffer().map_err(js)?)
        .await
        .map_err(js)?;
    Ok(js_sys::Uint8Array::new(&buffer).to_vec())
}

async fn fetch(url: &str) -> Result<Vec<u8>> {
    body(url, request(url)?).await
}

/// `log` to the browser's console.
struct Console;
static CONSOLE: Console = Console;

impl log::Log for Console {
    fn enabled(&self, m: &log::Metadata) -> bool {
        // wgpu's own chatter stays out unless it is a problem.
        m.level() <= log::Level::Warn || m.target().starts_with("lodlab")
    }

    fn log(&self, record: &log::Record) {
        if !self.enabled(record.metadata()) {
            return;
        }
        let text = format!("{}: {}", record.target(), record.args());
        let text = wasm_bindgen::JsValue::from_str(&text);
        match record.level() {
            log::Level::Error => web_sys::console::error_1(&text),
            log::Level::Warn => web_sys::console::warn_1(&text),
            _ => web_sys::console::log_1(&text),
        }
    }

    fn flush(&self) {}
}

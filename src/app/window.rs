//! What every lodlab window needs: the window with a device that can draw into it, egui on
//! top, and the frame to draw. Shared by the viewer and the study window.

use crate::render::Gpu;
use anyhow::{Context, Result, anyhow};
use std::sync::Arc;
use winit::event_loop::ActiveEventLoop;
use winit::window::{Window, WindowAttributes};

/// A window and a device drawing into it through its surface (sRGB where offered, vsync).
pub struct WindowGpu {
    pub window: Arc<Window>,
    pub surface: wgpu::Surface<'static>,
    pub config: wgpu::SurfaceConfiguration,
    pub gpu: Gpu,
    /// The panel's meshes as egui last tessellated them.
    pub panel: PanelMeshes,
}

/// The panel's meshes as egui last tessellated them: drawn again as they are on a frame where
/// the panel did not run, without egui's layout, tessellation or uploads.
#[derive(Default)]
pub struct PanelMeshes {
    pub primitives: Vec<egui::ClippedPrimitive>,
    pub pixels_per_point: f32,
    /// The surface size and scale egui's buffers were last filled for, if they hold these
    /// meshes: `None` until they are uploaded (and after a new device or renderer).
    uploaded: Option<([u32; 2], f32)>,
}

impl PanelMeshes {
    /// Forgets that egui's buffers hold the meshes: a new renderer has none.
    pub fn renderer_replaced(&mut self) {
        self.uploaded = None;
    }
}

impl WindowGpu {
    /// Opens a window and a device for it. Its surface is sRGB where offered when `srgb`
    /// (the scene writes linear colours), else not (a window egui alone draws, in the
    /// gamma-space colours it blends in).
    pub fn open(
        event_loop: &ActiveEventLoop,
        attributes: WindowAttributes,
        srgb: bool,
    ) -> Result<WindowGpu> {
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .context("cannot open a window")?,
        );
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        pollster::block_on(Self::connect(window, instance, srgb))
    }

    /// A device for `window` from `instance`, and its surface configured (see [`Self::open`]);
    /// without blocking, as a page must.
    pub async fn connect(
        window: Arc<Window>,
        instance: wgpu::Instance,
        srgb: bool,
    ) -> Result<WindowGpu> {
        let surface = instance
            .create_surface(window.clone())
            .context("cannot draw into the window")?;
        let gpu = Gpu::with_instance_async(instance, Some(&surface)).await?;
        eprintln!("lodlab: adapter {}", gpu.describe());
        log::info!("adapter {}", gpu.describe());
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&gpu.adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| anyhow!("the adapter cannot draw into this window"))?;
        let caps = surface.get_capabilities(&gpu.adapter);
        if let Some(f) = caps.formats.iter().copied().find(|f| f.is_srgb() == srgb) {
            config.format = f;
        } else if srgb && gpu.views_formats() {
            // WebGPU's canvas offers plain formats only: the scene, which writes linear
            // colours, draws through an sRGB view of it (see `Self::format`).
            config.view_formats = vec![config.format.add_srgb_suffix()];
        }
        config.present_mode = wgpu::PresentMode::AutoVsync;
        // The window is a picture, not a layer over the desktop.
        if caps.alpha_modes.contains(&wgpu::CompositeAlphaMode::Opaque) {
            config.alpha_mode = wgpu::CompositeAlphaMode::Opaque;
        }
        surface.configure(&gpu.device, &config);
        Ok(WindowGpu {
            window,
            surface,
            config,
            gpu,
            panel: PanelMeshes::default(),
        })
    }

    /// The format frames are drawn in: the surface's own, or the view format it was configured
    /// with where the surface offers no sRGB format (a browser's canvas).
    pub fn format(&self) -> wgpu::TextureFormat {
        self.config
            .view_formats
            .first()
            .copied()
            .unwrap_or(self.config.format)
    }

    /// Opens a new device on the same adapter for this window's surface, after the old one
    /// was lost, and configures the surface for it. Everything made on the old device must be
    /// made again on [`Self::gpu`].
    pub fn reopen_device(&mut self) -> Result<()> {
        self.gpu = Gpu::with_instance(self.gpu.instance.clone(), Some(&self.surface))?;
        self.surface.configure(&self.gpu.device, &self.config);
        Ok(())
    }

    /// Makes the window's surface again (it was lost: the platform took it away) and
    /// configures it.
    pub fn recreate_surface(&mut self) -> Result<()> {
        self.surface = self
            .gpu
            .instance
            .create_surface(self.window.clone())
            .context("cannot draw into the window again")?;
        self.surface.configure(&self.gpu.device, &self.config);
        Ok(())
    }

    /// Reconfigures the surface for a new size.
    pub fn resize(&mut self, width: u32, height: u32) {
        self.config.width = width.max(1);
        self.config.height = height.max(1);
        self.surface.configure(&self.gpu.device, &self.config);
    }

    /// egui's input state for this window and its renderer for this surface.
    pub fn egui(&self) -> (egui_winit::State, egui_wgpu::Renderer) {
        let state = egui_winit::State::new(
            egui_context(),
            egui::ViewportId::ROOT,
            &self.window,
            Some(self.window.scale_factor() as f32),
            None,
            Some(self.gpu.device.limits().max_texture_dimension_2d as usize),
        );
        // egui blends in gamma space: it draws into views without sRGB encoding (the
        // viewer's panel image has one, see `PanelImage`).
        let renderer = egui_wgpu::Renderer::new(
            &self.gpu.device,
            self.config.format.remove_srgb_suffix(),
            egui_wgpu::RendererOptions::default(),
        );
        (state, renderer)
    }

    /// The texture to draw this frame into, if there is one.
    pub fn acquire(&self) -> Result<Acquired> {
        acquired(self.surface.get_current_texture())
    }
}

/// A frame of a window with an egui panel, from the surface acquired to the frame presented:
/// the part of drawing a frame the viewer and the study window share ([`WindowGpu::begin_frame`],
/// [`WindowGpu::finish_frame`]). What the window draws goes into `encoder`, onto `view`;
/// egui's own pass draws the window's [`PanelMeshes`] at `screen`.
pub struct PanelFrame {
    surface: wgpu::SurfaceTexture,
    pub view: wgpu::TextureView,
    pub encoder: wgpu::CommandEncoder,
    pub screen: egui_wgpu::ScreenDescriptor,
    /// egui's vertex and index uploads, submitted before the frame.
    egui_buffers: Vec<wgpu::CommandBuffer>,
    /// egui's textures the frame no longer needs, freed once it is submitted.
    frees: Vec<egui::TextureId>,
}

/// What [`WindowGpu::begin_frame`] found.
pub enum Began {
    Frame(Box<PanelFrame>),
    /// No frame this time (the surface skipped it, or was made again): draw next time.
    Skipped,
    /// The surface no longer fits the window: resize (the window and whatever else has its
    /// size), and draw next time.
    Reconfigure,
}

impl WindowGpu {
    /// Begins a frame of egui's `output` (of `ctx`, drawn by `renderer`), or of the panel as
    /// it was where `output` is `None` (the panel did not run): tessellates the output into
    /// [`Self::panel`] and uploads its textures, acquires the surface (making it again where
    /// it was lost), and records egui's buffer uploads where the meshes or the surface
    /// changed. Where no frame comes, egui's freed textures are freed at once.
    pub fn begin_frame(
        &mut self,
        ctx: &egui::Context,
        renderer: &mut egui_wgpu::Renderer,
        output: Option<egui::FullOutput>,
    ) -> Result<Began> {
        let mut frees = Vec::new();
        if let Some(mut output) = output {
            let ppp = output.pixels_per_point;
            self.panel.primitives = ctx.tessellate(std::mem::take(&mut output.shapes), ppp);
            self.panel.pixels_per_point = ppp;
            self.panel.uploaded = None;
            // egui's texture uploads go in whether or not this frame reaches the screen; its
            // frees once the frame no longer needs the textures.
            for (id, deltas) in output.textures_delta.set.drain() {
                for delta in &deltas {
                    renderer.update_texture(&self.gpu.device, &self.gpu.queue, id, delta);
                }
            }
            frees = output.textures_delta.free.drain().collect();
        }
        let surface = match self.acquire() {
            Ok(Acquired::Frame(f)) => f,
            other => {
                for id in &frees {
                    renderer.free_texture(id);
                }
                return match other? {
                    Acquired::Reconfigure => Ok(Began::Reconfigure),
                    Acquired::Recreate => {
                        self.recreate_surface()?;
                        Ok(Began::Skipped)
                    }
                    Acquired::Skip | Acquired::Frame(_) => Ok(Began::Skipped),
                };
            }
        };
        let size = [self.config.width, self.config.height];
        let ppp = self.panel.pixels_per_point;
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: size,
            pixels_per_point: ppp,
        };
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        // egui's renderer keeps the meshes it was last given: upload only what changed.
        let mut egui_buffers = Vec::new();
        if self.panel.uploaded != Some((size, ppp)) {
            egui_buffers = renderer.update_buffers(
                &self.gpu.device,
                &self.gpu.queue,
                &mut encoder,
                &self.panel.primitives,
                &screen,
            );
            self.panel.uploaded = Some((size, ppp));
        }
        let view = surface.texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(self.format()),
            ..Default::default()
        });
        Ok(Began::Frame(Box::new(PanelFrame {
            surface,
            view,
            encoder,
            screen,
            egui_buffers,
            frees,
        })))
    }

    /// Submits `frame`, presents it, and frees egui's textures it no longer needs. A GPU error
    /// of the frame fails it, unpresented.
    pub fn finish_frame(
        &self,
        renderer: &mut egui_wgpu::Renderer,
        frame: Box<PanelFrame>,
    ) -> Result<()> {
        let PanelFrame {
            surface,
            encoder,
            mut egui_buffers,
            frees,
            ..
        } = *frame;
        egui_buffers.push(encoder.finish());
        self.gpu.queue.submit(egui_buffers);
        let submitted = self.gpu.take_error();
        if submitted.is_ok() {
            self.window.pre_present_notify();
            self.gpu.queue.present(surface);
        }
        for id in &frees {
            renderer.free_texture(id);
        }
        submitted
    }
}

/// egui's pass: `primitives` drawn at `screen` into `view`, over what is there (`clear`: None)
/// or over a clear colour.
#[allow(clippy::too_many_arguments)]
pub fn draw_panel(
    renderer: &egui_wgpu::Renderer,
    encoder: &mut wgpu::CommandEncoder,
    view: &wgpu::TextureView,
    primitives: &[egui::ClippedPrimitive],
    screen: &egui_wgpu::ScreenDescriptor,
    label: &str,
    clear: Option<wgpu::Color>,
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
) {
    let mut pass = encoder
        .begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            timestamp_writes,
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: clear.map_or(wgpu::LoadOp::Load, wgpu::LoadOp::Clear),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        })
        .forget_lifetime();
    renderer.render(&mut pass, primitives, screen);
}

/// What to do about the surface's answer: draw, skip this frame, reconfigure it (outdated:
/// the window changed size or format), make it again (lost), or give up (validation: a bug).
fn acquired(status: wgpu::CurrentSurfaceTexture) -> Result<Acquired> {
    match status {
        wgpu::CurrentSurfaceTexture::Success(f) | wgpu::CurrentSurfaceTexture::Suboptimal(f) => {
            Ok(Acquired::Frame(f))
        }
        wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
            Ok(Acquired::Skip)
        }
        wgpu::CurrentSurfaceTexture::Outdated => Ok(Acquired::Reconfigure),
        wgpu::CurrentSurfaceTexture::Lost => Ok(Acquired::Recreate),
        wgpu::CurrentSurfaceTexture::Validation => {
            Err(anyhow!("the window's surface failed validation"))
        }
    }
}

/// What [`WindowGpu::acquire`] found.
pub enum Acquired {
    Frame(wgpu::SurfaceTexture),
    /// No frame this time (hidden, or not ready): draw nothing.
    Skip,
    /// The surface no longer fits the window: resize, and draw next time.
    Reconfigure,
    /// The surface is gone: make it again ([`WindowGpu::recreate_surface`]), draw next time.
    Recreate,
}

/// The Debian package of each windowing library winit loads at run time, by a part of its
/// file name, most specific first.
const RUNTIME_LIBRARIES: &[(&str, &str)] = &[
    ("libxkbcommon-x11", "libxkbcommon-x11-0"),
    ("libxkbcommon", "libxkbcommon0"),
    ("libX11-xcb", "libx11-xcb1"),
    ("libXcursor", "libxcursor1"),
    ("libXrandr", "libxrandr2"),
    ("libXi.", "libxi6"),
    ("libX11.", "libx11-6"),
    ("libwayland-client", "libwayland-client0"),
    ("libvulkan", "libvulkan1"),
];

/// One line naming the package to install, where `message` (winit's error or panic) says a
/// windowing library could not be loaded; `None` for anything else.
pub fn missing_library(message: &str) -> Option<String> {
    RUNTIME_LIBRARIES
        .iter()
        .find(|(file, _)| message.contains(file))
        .map(|(file, package)| {
            format!(
                "cannot open a window: the {file}* library is missing (install it: sudo apt-get install {package})"
            )
        })
}

/// The egui context of a window's panel (the viewer's and the study's).
///
/// A press and its release make a click however far apart they are, as in desktop toolkits.
/// egui's default limit (0.8 s) is measured between the frames that saw them, so on lavapipe,
/// where a big crowd takes a second or more a frame, a click that straddled two frames was lost
/// and a checkbox or combo box needed several tries.
pub fn egui_context() -> egui::Context {
    let ctx = egui::Context::default();
    configure_egui(&ctx);
    ctx
}

/// Sets up `ctx` as [`egui_context`] does.
pub fn configure_egui(ctx: &egui::Context) {
    ctx.options_mut(|o| o.input_options.max_click_duration = f64::INFINITY);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_library_names_its_package() {
        let line =
            missing_library("Failed to load libxkbcommon-x11.so.0: cannot open shared object file")
                .unwrap();
        assert!(
            line.contains("apt-get install libxkbcommon-x11-0"),
            "{line}"
        );
        let line = missing_library("failed to open library libXcursor.so.1").unwrap();
        assert!(line.ends_with("libxcursor1)"), "{line}");
        assert!(!line.contains('\n'));
        assert_eq!(missing_library("the display went away"), None);
    }

    /// Every surface answer without a frame has its remedy: skip, reconfigure, recreate, or
    /// an error (validation: a bug, not a state to wait out).
    #[test]
    fn each_surface_state_has_its_remedy() {
        use wgpu::CurrentSurfaceTexture as S;
        let remedy = |s| match acquired(s) {
            Ok(Acquired::Skip) => "skip",
            Ok(Acquired::Reconfigure) => "reconfigure",
            Ok(Acquired::Recreate) => "recreate",
            Ok(Acquired::Frame(_)) => "frame",
            Err(_) => "error",
        };
        assert_eq!(remedy(S::Timeout), "skip");
        assert_eq!(remedy(S::Occluded), "skip");
        assert_eq!(remedy(S::Outdated), "reconfigure");
        assert_eq!(remedy(S::Lost), "recreate");
        assert_eq!(remedy(S::Validation), "error");
    }
}

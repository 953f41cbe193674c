//! GPU set-up: instance, adapter and device, honouring `WGPU_BACKEND` and `WGPU_ADAPTER_NAME`.

use anyhow::{Context, Result, anyhow, bail};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// The device and everything needed to use it. A clone is another handle on the same device
/// (for work on another thread).
#[derive(Clone)]
pub struct Gpu {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Errors wgpu reported outside any error scope, oldest first, until taken by
    /// [`Gpu::take_error`]. wgpu's own default handler panics on them.
    errors: Arc<Mutex<Vec<String>>>,
    /// Set when the device is lost (a driver reset, or [`wgpu::Device::destroy`]); everything
    /// made on it is gone, and a window recovers by opening another.
    lost: Arc<AtomicBool>,
}

impl Gpu {
    /// A device for headless rendering.
    pub fn headless() -> Result<Gpu> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        Self::with_instance(instance, None)
    }

    /// A device for the given instance, compatible with `surface` where one is given.
    pub fn with_instance(
        instance: wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Gpu> {
        pollster::block_on(Self::with_instance_async(instance, surface))
    }

    /// [`Self::with_instance`] without blocking: what a page must do (the browser answers
    /// adapter and device requests later, on its own event loop).
    pub async fn with_instance_async(
        instance: wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Gpu> {
        let adapter = select_adapter(&instance, surface).await?;
        Self::on_adapter_async(instance, adapter).await
    }

    /// A device of its own on the same adapter, with a queue of its own: work for it never
    /// waits behind this one's (a bake's read-backs behind a viewer's frames, which on a
    /// software rasteriser may take seconds each).
    pub fn separate(&self) -> Result<Gpu> {
        Self::on_adapter(self.instance.clone(), self.adapter.clone())
    }

    fn on_adapter(instance: wgpu::Instance, adapter: wgpu::Adapter) -> Result<Gpu> {
        pollster::block_on(Self::on_adapter_async(instance, adapter))
    }

    async fn on_adapter_async(instance: wgpu::Instance, adapter: wgpu::Adapter) -> Result<Gpu> {
        let info = adapter.get_info();
        // Features that only make the debug views nicer are taken when offered.
        let optional = wgpu::Features::POLYGON_MODE_LINE
            | wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::PIPELINE_STATISTICS_QUERY;
        let required_features = adapter.features() & optional;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("lodlab"),
                required_features,
                required_limits: required_limits(&adapter),
                ..Default::default()
            })
            .await
            .with_context(|| format!("cannot open a device on {}", info.name))?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            log::error!("GPU: {e}");
            sink.lock().unwrap().push(one_line(&e));
        }));
        let lost = Arc::new(AtomicBool::new(false));
        let flag = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            log::warn!("GPU device lost ({reason:?}): {message}");
            flag.store(true, Ordering::SeqCst);
        });
        Ok(Gpu {
            instance,
            adapter,
            device,
            queue,
            info,
            errors,
            lost,
        })
    }

    /// Whether the device has been lost: nothing more can be done with it. The device is
    /// polled first: a lost device says so (its callback runs) only when polled.
    pub fn is_lost(&self) -> bool {
        if !self.lost.load(Ordering::SeqCst) {
            let _ = self.device.poll(wgpu::PollType::Poll);
        }
        self.lost.load(Ordering::SeqCst)
    }

    /// The first error wgpu reported since the last call, as an error, or `Ok` if none.
    pub fn take_error(&self) -> Result<()> {
        let mut errors = self.errors.lock().unwrap();
        let first = errors.first().cloned();
        errors.clear();
        match first {
            Some(e) => bail!("the GPU refused a command: {e}"),
            None => Ok(()),
        }
    }

    /// Runs `f`, which creates resources or records work, and fails with what the GPU said if
    /// any of it was invalid or out of memory (rather than leaving the error to the handler).
    #[cfg(not(target_arch = "wasm32"))]
    pub fn checked<T>(&self, what: &str, f: impl FnOnce() -> T) -> Result<T> {
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f();
        let invalid = pollster::block_on(validation.pop());
        let oom = pollster::block_on(memory.pop());
        match invalid.or(oom) {
            Some(e) => bail!("{what}: the GPU refused it: {}", one_line(&e)),
            None => Ok(out),
        }
    }

    /// [`Self::checked`] in a page, which cannot wait for the browser's answer: the errors go to
    /// the handler (logged, and failing the next [`Self::take_error`]).
    #[cfg(target_arch = "wasm32")]
    pub fn checked<T>(&self, _what: &str, f: impl FnOnce() -> T) -> Result<T> {
        Ok(f())
    }

    /// Fails, naming `what`, unless a `width`×`height` texture of `layers` layers fits this
    /// device's limits.
    pub fn texture_fits(&self, what: &str, width: u32, height: u32, layers: u32) -> Result<()> {
        let l = self.device.limits();
        let side = l.max_texture_dimension_2d;
        if width > side || height > side {
            bail!("{what} need a {width}×{height} texture; this GPU allows {side}×{side}");
        }
        if layers > l.max_texture_array_layers {
            bail!(
                "{what} need {layers} texture layers; this GPU allows {}",
                l.max_texture_array_layers
            );
        }
        Ok(())
    }

    /// Fails, naming `what`, unless a buffer of `bytes` fits this device's limits.
    pub fn buffer_fits(&self, what: &str, bytes: u64) -> Result<()> {
        let max = self.device.limits().max_buffer_size;
        if bytes > max {
            bail!(
                "{what} need a {} MiB buffer; this GPU allows {} MiB",
                bytes >> 20,
                max >> 20
            );
        }
        Ok(())
    }

    /// `"llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Cpu)"`.
    pub fn describe(&self) -> String {
        // A browser keeps its adapter's name to itself.
        let name = if self.info.name.is_empty() {
            "an adapter"
        } else {
            &self.info.name
        };
        format!(
            "{name} ({:?}, {:?})",
            self.info.backend, self.info.device_type
        )
    }

    /// Whether the adapter is a software rasteriser (Mesa lavapipe, WARP): every sample
    /// shaded or resolved costs CPU time there, so defaults are chosen for fill rate.
    pub fn is_cpu(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// The multisampling a command draws with where none is asked: 1 on a CPU adapter, 4
    /// elsewhere (see [`Self::samples`]).
    pub fn default_samples(&self) -> u32 {
        if self.is_cpu() { 1 } else { 4 }
    }

    /// The multisampling to draw with: `asked`, or else by adapter, 1 on a CPU adapter (where
    /// 4× costs about 2.5× the frame on the default scenes, and alpha-tested foliage then needs
    /// no alpha to coverage) and 4 elsewhere. A default is said on stderr, with how to change
    /// it.
    pub fn samples(&self, asked: Option<u32>) -> u32 {
        if let Some(samples) = asked {
            return samples;
        }
        let samples = self.default_samples();
        let (why, other) = if self.is_cpu() {
            ("a CPU adapter", 4)
        } else {
            ("a GPU", 1)
        };
        // Said once a process: bench and soak make several worlds.
        static SAID: std::sync::Once = std::sync::Once::new();
        SAID.call_once(|| {
            eprintln!(
                "lodlab: multisampling {samples}× (the default on {why}; --msaa {other} for {other}×)"
            );
        });
        samples
    }

    /// Whether billboards are lit per texel through their atlases: `asked`, or else by
    /// adapter, off on a CPU adapter (the per-pixel lighting's second texture read costs lavapipe
    /// about a fifth of the default scene's frame, and the crown's occlusion, which is most of
    /// what the atlas's lighting buys, is in the atlas's colour either way) and on elsewhere.
    /// A default is said on stderr, with how to change it, once a process and only where
    /// there are `trees` to light.
    pub fn atlas_lighting(&self, asked: Option<bool>, trees: bool) -> bool {
        if let Some(on) = asked {
            return on;
        }
        let on = self.lights_atlases();
        static SAID: std::sync::Once = std::sync::Once::new();
        if trees {
            SAID.call_once(|| {
                let (how, why, other) = if on {
                    ("per texel through their atlases", "a GPU", "flat")
                } else {
                    ("one normal a billboard", "a CPU adapter", "atlas")
                };
                eprintln!(
                    "lodlab: billboards lit {how} (the default on {why}; --billboard-lighting {other} for the other)"
                );
            });
        }
        on
    }

    /// The default of [`Self::atlas_lighting`], said nowhere: off on a CPU adapter.
    pub fn lights_atlases(&self) -> bool {
        !self.is_cpu()
    }

    /// Whether an indexed draw can start at a base vertex (not on WebGL2).
    pub fn draws_base_vertex(&self) -> bool {
        self.adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::BASE_VERTEX)
    }

    /// Whether a texture can be viewed in another format than its own (not on WebGL2).
    pub fn views_formats(&self) -> bool {
        self.adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::VIEW_FORMATS)
    }

    pub fn backend_name(&self) -> String {
        format!("{:?}", self.info.backend)
    }

    /// Blocks until all submitted work is done.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| anyhow!("GPU wait failed: {e}"))
    }
}

/// The limits a device is asked for: the adapter's own texture sizes and layer counts (models
/// with many materials need more layers than the portable default of 256); otherwise wgpu's
/// defaults, or where the adapter is WebGL2, the most WebGL2 offers.
fn required_limits(adapter: &wgpu::Adapter) -> wgpu::Limits {
    let base = if adapter.get_info().backend == wgpu::Backend::Gl {
        wgpu::Limits::downlevel_webgl2_defaults()
    } else {
        wgpu::Limits::default()
    };
    wgpu::Limits {
        max_texture_array_layers: adapter.limits().max_texture_array_layers,
        ..base.using_resolution(adapter.limits())
    }
}

/// A wgpu error on one line: its text ("Validation Error", then "Caused by:" and the chain of
/// causes, one a line) without the headings, the causes joined by colons.
fn one_line(e: &wgpu::Error) -> String {
    let text = e.to_string();
    let parts: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && *l != "Caused by:" && *l != "Validation Error")
        .collect();
    if parts.is_empty() {
        text.trim().to_string()
    } else {
        parts.join(": ").replace(":: ", ": ")
    }
}

/// Picks the adapter: the first whose name contains `WGPU_ADAPTER_NAME` (case-insensitive) when
/// that is set, otherwise wgpu's preference (`WGPU_POWER_PREF` honoured).
async fn select_adapter(
    instance: &wgpu::Instance,
    surface: Option<&wgpu::Surface<'_>>,
) -> Result<wgpu::Adapter> {
    let adapters = instance.enumerate_adapters(wgpu::Backends::all()).await;
    if let Ok(wanted) = std::env::var("WGPU_ADAPTER_NAME") {
        let wanted_lc = wanted.to_lowercase();
        let names: Vec<String> = adapters
            .iter()
            .map(|a| format!("{} ({:?})", a.get_info().name, a.get_info().backend))
            .collect();
        return adapters
            .into_iter()
            .find(|a| {
                a.get_info().name.to_lowercase().contains(&wanted_lc)
                    && surface.is_none_or(|s| a.is_surface_supported(s))
            })
            .ok_or_else(|| {
                anyhow!(
                    "WGPU_ADAPTER_NAME={wanted} matches no adapter; available: {}",
                    if names.is_empty() {
                        "none".to_string()
                    } else {
                        names.join(", ")
                    }
                )
            });
    }
    instance
        .request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::from_env().unwrap_or_default(),
            compatible_surface: surface,
            ..Default::default()
        })
        .await
        .map_err(|e| {
            let backends = std::env::var("WGPU_BACKEND").unwrap_or_else(|_| "any".into());
            anyhow!(
                "no GPU adapter found (WGPU_BACKEND={backends}): {e}. Install a Vulkan driver, \
                 or Mesa lavapipe for software rendering (apt-get install mesa-vulkan-drivers)"
            )
        })
}

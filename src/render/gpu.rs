//! GPU set-up: instance, adapter and device, honouring `WGPU_BACKEND` and `WGPU_ADAPTER_NAME`.

use anyhow::{Context, Result, anyhow};

/// The device and everything needed to use it. A clone is another handle on the same device
/// (for work on another thread).
#[derive(Clone)]
pub struct Gpu {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
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
        let adapter = pollster::block_on(select_adapter(&instance, surface))?;
        Self::on_adapter(instance, adapter)
    }

    /// A device of its own on the same adapter, with a queue of its own: work for it never
    /// waits behind this one's (a bake's read-backs behind a viewer's frames, which on a
    /// software rasteriser may take seconds each).
    pub fn separate(&self) -> Result<Gpu> {
        Self::on_adapter(self.instance.clone(), self.adapter.clone())
    }

    fn on_adapter(instance: wgpu::Instance, adapter: wgpu::Adapter) -> Result<Gpu> {
        let info = adapter.get_info();
        // Features that only make the debug views nicer are taken when offered.
        let optional = wgpu::Features::POLYGON_MODE_LINE
            | wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::PIPELINE_STATISTICS_QUERY;
        let required_features = adapter.features() & optional;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("lodlab"),
            required_features,
            required_limits: wgpu::Limits::default().using_resolution(adapter.limits()),
            ..Default::default()
        }))
        .with_context(|| format!("cannot open a device on {}", info.name))?;
        Ok(Gpu {
            instance,
            adapter,
            device,
            queue,
            info,
        })
    }

    /// `"llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Cpu)"`.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.backend, self.info.device_type
        )
    }

    /// Whether the adapter is a software rasteriser (Mesa lavapipe, WARP): every sample
    /// shaded or resolved costs CPU time there, so defaults are chosen for fill rate.
    pub fn is_cpu(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// The multisampling to draw with: `asked`, or else by adapter, 1 on a CPU adapter (where
    /// 4× costs about 2.5× the frame on the default scenes, and alpha-tested foliage then needs
    /// no alpha to coverage) and 4 elsewhere. A default is said on stderr, with how to change
    /// it.
    pub fn samples(&self, asked: Option<u32>) -> u32 {
        if let Some(samples) = asked {
            return samples;
        }
        let (samples, why, other) = if self.is_cpu() {
            (1, "a CPU adapter", 4)
        } else {
            (4, "a GPU", 1)
        };
        eprintln!(
            "lodlab: multisampling {samples}× (the default on {why}; --msaa {other} for {other}×)"
        );
        samples
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

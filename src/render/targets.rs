//! Render targets: multisampled colour, depth, and an offscreen image that can be read back.

use super::gpu::Gpu;
use anyhow::{Result, anyhow};

pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Colour format of offscreen images (PNG output): sRGB, so shaders write linear light.
pub const OFFSCREEN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// Depth and (when multisampling) colour attachments of one size.
pub struct RenderTargets {
    pub width: u32,
    pub height: u32,
    pub sample_count: u32,
    msaa: Option<wgpu::TextureView>,
    depth: wgpu::TextureView,
}

impl RenderTargets {
    pub fn new(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        format: wgpu::TextureFormat,
        sample_count: u32,
    ) -> Self {
        let size = wgpu::Extent3d {
            width: width.max(1),
            height: height.max(1),
            depth_or_array_layers: 1,
        };
        let make = |label, format| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size,
                    mip_level_count: 1,
                    sample_count,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        };
        RenderTargets {
            width,
            height,
            sample_count,
            msaa: (sample_count > 1).then(|| make("msaa colour", format)),
            depth: make("depth", DEPTH_FORMAT),
        }
    }

    /// Bytes of the multisampled colour and the depth attachments.
    pub fn bytes(&self) -> u64 {
        let per_sample = 4 + if self.msaa.is_some() { 4 } else { 0 };
        self.width as u64 * self.height as u64 * self.sample_count as u64 * per_sample
    }

    /// The colour attachment of one of a frame's passes, which ends up in `target`: the first
    /// pass clears it (to black), the others load it; the last resolves the multisampled
    /// texture, when there is one, into `target` and leaves the samples behind.
    pub fn color<'a>(
        &'a self,
        target: &'a wgpu::TextureView,
        first: bool,
        last: bool,
    ) -> wgpu::RenderPassColorAttachment<'a> {
        let load = if first {
            wgpu::LoadOp::Clear(wgpu::Color::BLACK)
        } else {
            wgpu::LoadOp::Load
        };
        self.color_with(target, load, last)
    }

    /// [`Self::color`] loaded by `load` (a pass that clears to another colour).
    pub fn color_with<'a>(
        &'a self,
        target: &'a wgpu::TextureView,
        load: wgpu::LoadOp<wgpu::Color>,
        last: bool,
    ) -> wgpu::RenderPassColorAttachment<'a> {
        match &self.msaa {
            Some(msaa) => wgpu::RenderPassColorAttachment {
                view: msaa,
                depth_slice: None,
                resolve_target: last.then_some(target),
                ops: wgpu::Operations {
                    load,
                    store: if last {
                        wgpu::StoreOp::Discard
                    } else {
                        wgpu::StoreOp::Store
                    },
                },
            },
            None => wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                },
            },
        }
    }

    /// The depth attachment of one of a frame's passes: cleared by the first, kept between
    /// passes, dropped after the last.
    pub fn depth(&self, first: bool, last: bool) -> wgpu::RenderPassDepthStencilAttachment<'_> {
        wgpu::RenderPassDepthStencilAttachment {
            view: &self.depth,
            depth_ops: Some(wgpu::Operations {
                load: if first {
                    wgpu::LoadOp::Clear(1.0)
                } else {
                    wgpu::LoadOp::Load
                },
                store: if last {
                    wgpu::StoreOp::Discard
                } else {
                    wgpu::StoreOp::Store
                },
            }),
            stencil_ops: None,
        }
    }
}

/// An offscreen colour image plus its targets.
pub struct Offscreen {
    pub targets: RenderTargets,
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
}

impl Offscreen {
    pub fn new(gpu: &Gpu, width: u32, height: u32, sample_count: u32) -> Self {
        Self::with_format(gpu, width, height, sample_count, OFFSCREEN_FORMAT)
    }

    pub fn with_format(
        gpu: &Gpu,
        width: u32,
        height: u32,
        sample_count: u32,
        format: wgpu::TextureFormat,
    ) -> Self {
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("offscreen"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        Offscreen {
            targets: RenderTargets::new(&gpu.device, width, height, format, sample_count),
            texture,
            view,
        }
    }

    /// Reads the image back as tightly packed rows of texels.
    pub fn read_bytes(&self, gpu: &Gpu) -> Result<Vec<u8>> {
        read_texture(gpu, &self.texture)
    }

    pub fn read_rgba(&self, gpu: &Gpu) -> Result<image::RgbaImage> {
        let bytes = self.read_bytes(gpu)?;
        image::RgbaImage::from_raw(self.targets.width, self.targets.height, bytes)
            .ok_or_else(|| anyhow!("read-back size mismatch"))
    }
}

/// Copies a single-sampled 2D texture to the CPU, rows unpadded.
pub fn read_texture(gpu: &Gpu, texture: &wgpu::Texture) -> Result<Vec<u8>> {
    let (w, h) = (texture.width(), texture.height());
    let texel = texture
        .format()
        .block_copy_size(None)
        .ok_or_else(|| anyhow!("format cannot be read back"))?;
    let row = w * texel;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read-back"),
        size: (padded * h) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(h),
            },
        },
        texture.size(),
    );
    gpu.queue.submit([enc.finish()]);
    gpu.take_error()?;
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    gpu.wait()?;
    rx.recv()?.map_err(|e| anyhow!("read-back failed: {e}"))?;
    let data = buffer
        .get_mapped_range(..)
        .map_err(|e| anyhow!("read-back failed: {e}"))?;
    let mut out = Vec::with_capacity((row * h) as usize);
    for y in 0..h as usize {
        let start = y * padded as usize;
        out.extend_from_slice(&data[start..start + row as usize]);
    }
    drop(data);
    buffer.unmap();
    Ok(out)
}

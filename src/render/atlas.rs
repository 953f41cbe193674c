//! Bakes a billboard cloud's atlas on the GPU: the leaf triangles of every billboard (laid out
//! by [`crate::bake::foliage::billboard::atlas`]) rasterised into two textures, colour and lighting,
//! and read back; and an
//! octahedral impostor's views ([`crate::bake::impostor::octahedral`]), the whole tree drawn
//! from every view into its cell, colour and normal. The results are plain image data; the
//! bake's caller cleans them up and caches them.

use super::gpu::Gpu;
use super::shaders;
use super::targets::read_texture;
use crate::bake::gpu_data::materials::MaterialLayers;
use crate::bake::gpu_products::{
    AtlasImages, AtlasLayout, AtlasVertex, RasterizeAtlas, ViewCamera, ViewImages, ViewRequest,
    ViewVertex,
};
use crate::model::Rgba8Image;
use anyhow::Result;
use wgpu::util::DeviceExt;

const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// The impostor views' normal target: plain unsigned bytes.
const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Draws billboard-cloud atlases: the pipeline, its bind group layout and the leaf sampler are
/// made once, and every atlas of a chain reuses them.
pub struct AtlasRasterizer<'g> {
    gpu: &'g Gpu,
    bind_layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
    sampler: wgpu::Sampler,
    /// The impostor views' pipeline and its bind group layout.
    views: (wgpu::BindGroupLayout, wgpu::RenderPipeline),
}

impl<'g> AtlasRasterizer<'g> {
    pub fn new(gpu: &'g Gpu) -> AtlasRasterizer<'g> {
        let device = &gpu.device;
        // Wrapping as the renderer's material sampler wraps: a leaf's texture coordinates may
        // run past the texture (a strip repeating one leaflet along its length).
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let bind_layout = bake_layout(device, "atlas", wgpu::TextureViewDimension::D2Array);
        let module = shaders::ATLAS_SHADER.create(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("atlas"),
            bind_group_layouts: &[Some(&bind_layout)],
            immediate_size: 0,
        });
        let attributes = wgpu::vertex_attr_array![
            0 => Float32x2, 1 => Float32, 2 => Float32x2, 3 => Float32x3, 4 => Float32,
            5 => Uint32
        ];
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("atlas"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<AtlasVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attributes,
                })],
            },
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                // Colour over, alpha accumulated: C = Cs·As + Cd·(1 − As), A = As + Ad·(1 − As);
                // the lighting blended the same way, by the leaf's alpha.
                targets: &[over(FORMAT), over(NORMAL_FORMAT)],
            }),
            multiview_mask: None,
            cache: None,
        });
        let views = views_pipeline(device);
        AtlasRasterizer {
            gpu,
            bind_layout,
            pipeline,
            sampler,
            views,
        }
    }
}

impl RasterizeAtlas for AtlasRasterizer<'_> {
    /// `leaves` are mipmapped, so leaves shrunk onto few texels keep their coverage.
    fn rasterize(
        &self,
        layout: &AtlasLayout,
        vertices: &[AtlasVertex],
        leaves: &MaterialLayers,
    ) -> Result<AtlasImages> {
        let gpu = self.gpu;
        let device = &gpu.device;
        let size = wgpu::Extent3d {
            width: layout.width,
            height: layout.height,
            depth_or_array_layers: 1,
        };
        let target = render_target(device, "billboard atlas", size, FORMAT);
        let lighting = render_target(device, "billboard lighting", size, NORMAL_FORMAT);
        let depth = render_target(
            device,
            "billboard atlas depth",
            size,
            wgpu::TextureFormat::Depth32Float,
        );
        let leaf_tex = super::character::material_texture(gpu, leaves);
        let bind = self.bind_group(
            &self.bind_layout,
            &[layout.width as f32, layout.height as f32, 0.0, 0.0],
            &leaf_tex.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            }),
        );
        let mut enc = device.create_command_encoder(&Default::default());
        {
            let view = target.create_view(&Default::default());
            let lighting_view = lighting.create_view(&Default::default());
            let depth_view = depth.create_view(&Default::default());
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("atlas"),
                color_attachments: &[cleared(&view), cleared(&lighting_view)],
                depth_stencil_attachment: Some(cleared_depth(&depth_view)),
                ..Default::default()
            });
            if !vertices.is_empty() {
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &bind, &[]);
                for (buffer, count) in triangle_buffers(device, "atlas triangles", vertices) {
                    pass.set_vertex_buffer(0, buffer.slice(..));
                    pass.draw(0..count, 0..1);
                }
            }
        }
        gpu.queue.submit([enc.finish()]);
        gpu.take_error()?;
        let mut pixels = read_texture(gpu, &target)?;
        crate::bake::foliage::billboard::atlas::unpremultiply(&mut pixels);
        let mut light = read_texture(gpu, &lighting)?;
        crate::bake::foliage::billboard::atlas::unpremultiply_linear(&mut light);
        let image = |pixels| Rgba8Image {
            width: layout.width,
            height: layout.height,
            pixels,
        };
        Ok(AtlasImages {
            colour: image(pixels),
            lighting: image(light),
        })
    }

    fn rasterize_views(
        &self,
        request: &ViewRequest,
        materials: &MaterialLayers,
    ) -> Result<ViewImages> {
        let gpu = self.gpu;
        let device = &gpu.device;
        let size = wgpu::Extent3d {
            width: request.size,
            height: request.size,
            depth_or_array_layers: 1,
        };
        let colour = render_target(device, "impostor colour", size, FORMAT);
        let normal = render_target(device, "impostor normals", size, NORMAL_FORMAT);
        let depth = render_target(
            device,
            "impostor depth",
            size,
            wgpu::TextureFormat::Depth32Float,
        );
        let layers = super::character::material_texture(gpu, materials);
        let c = request.centre;
        let bind = self.bind_group(
            &self.views.0,
            &[
                request.size as f32,
                request.size as f32,
                0.0,
                0.0,
                c.x,
                c.y,
                c.z,
                0.0,
            ],
            &layers.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            }),
        );
        let mut enc = device.create_command_encoder(&Default::default());
        {
            let colour_view = colour.create_view(&Default::default());
            let normal_view = normal.create_view(&Default::default());
            let depth_view = depth.create_view(&Default::default());
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("impostor views"),
                color_attachments: &[cleared(&colour_view), cleared(&normal_view)],
                depth_stencil_attachment: Some(cleared_depth(&depth_view)),
                ..Default::default()
            });
            if !request.vertices.is_empty() && !request.views.is_empty() {
                let views = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("impostor cameras"),
                    contents: bytemuck::cast_slice(&request.views),
                    usage: wgpu::BufferUsages::VERTEX,
                });
                pass.set_pipeline(&self.views.1);
                pass.set_bind_group(0, &bind, &[]);
                pass.set_vertex_buffer(1, views.slice(..));
                for (buffer, count) in
                    triangle_buffers(device, "impostor triangles", &request.vertices)
                {
                    pass.set_vertex_buffer(0, buffer.slice(..));
                    pass.draw(0..count, 0..request.views.len() as u32);
                }
            }
        }
        gpu.queue.submit([enc.finish()]);
        gpu.take_error()?;
        let image = |texture: &wgpu::Texture| -> Result<Rgba8Image> {
            Ok(Rgba8Image {
                width: request.size,
                height: request.size,
                pixels: read_texture(gpu, texture)?,
            })
        };
        Ok(ViewImages {
            colour: image(&colour)?,
            normal: image(&normal)?,
        })
    }
}

/// `vertices` (whole triangles, unindexed) in vertex buffers no larger than the device takes,
/// with their vertex counts, to be drawn in turn: a 2-million-triangle character drawn
/// unindexed for its impostor is 280 MB, past lavapipe's 256 MB buffers.
fn triangle_buffers<T: bytemuck::Pod>(
    device: &wgpu::Device,
    label: &str,
    vertices: &[T],
) -> Vec<(wgpu::Buffer, u32)> {
    let largest = device.limits().max_buffer_size as usize;
    let per = (largest / std::mem::size_of::<T>().max(1) / 3 * 3)
        .min(u32::MAX as usize / 3 * 3)
        .max(3);
    vertices
        .chunks(per)
        .map(|chunk| {
            let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(chunk),
                usage: wgpu::BufferUsages::VERTEX,
            });
            (buffer, chunk.len() as u32)
        })
        .collect()
}

/// The impostor views' pipeline: tree triangles per vertex, views per instance, two colour
/// targets, depth-tested.
fn views_pipeline(device: &wgpu::Device) -> (wgpu::BindGroupLayout, wgpu::RenderPipeline) {
    let layout = bake_layout(
        device,
        "impostor views",
        wgpu::TextureViewDimension::D2Array,
    );
    let module = shaders::IMPOSTOR_BAKE_SHADER.create(device);
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("impostor views"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let vertex = wgpu::vertex_attr_array![
        0 => Float32x3, 1 => Uint32, 2 => Float32x3, 3 => Uint32, 4 => Float32x2, 9 => Float32
    ];
    let camera = wgpu::vertex_attr_array![
        5 => Float32x4, 6 => Float32x4, 7 => Float32x4, 8 => Float32x4
    ];
    let target = |format| {
        Some(wgpu::ColorTargetState {
            format,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })
    };
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("impostor views"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_view"),
            compilation_options: Default::default(),
            buffers: &[
                Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<ViewVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &vertex,
                }),
                Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<ViewCamera>() as u64,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &camera,
                }),
            ],
        },
        primitive: Default::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_view"),
            compilation_options: Default::default(),
            targets: &[target(FORMAT), target(NORMAL_FORMAT)],
        }),
        multiview_mask: None,
        cache: None,
    });
    (layout, pipeline)
}

impl AtlasRasterizer<'_> {
    /// A bind group of a bake pipeline's layout (see [`bake_layout`]): `params` as its
    /// uniform, `texture` and the shared sampler.
    fn bind_group(
        &self,
        layout: &wgpu::BindGroupLayout,
        params: &[f32],
        texture: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        let device = &self.gpu.device;
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("bake parameters"),
            contents: bytemuck::cast_slice(params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("bake"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(texture),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
            ],
        })
    }
}

/// The layout both bake pipelines bind: a uniform for the vertex stage, a filtered texture of
/// `dimension` and its sampler for the fragment stage.
fn bake_layout(
    device: &wgpu::Device,
    label: &str,
    dimension: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: dimension,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
        ],
    })
}

/// A single-sample target a bake draws into: colour ones are read back, depth is not.
fn render_target(
    device: &wgpu::Device,
    label: &str,
    size: wgpu::Extent3d,
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    let usage = if format.is_depth_stencil_format() {
        wgpu::TextureUsages::RENDER_ATTACHMENT
    } else {
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC
    };
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// A colour attachment cleared to transparent and kept.
fn cleared(view: &wgpu::TextureView) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
            store: wgpu::StoreOp::Store,
        },
    })
}

/// A depth attachment cleared to the far plane and dropped after the pass.
fn cleared_depth(view: &wgpu::TextureView) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store: wgpu::StoreOp::Discard,
        }),
        stencil_ops: None,
    }
}

/// A colour target that blends over: C = Cs·As + Cd·(1 − As), A = As + Ad·(1 − As).
fn over(format: wgpu::TextureFormat) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend: Some(wgpu::BlendState::ALPHA_BLENDING),
        write_mask: wgpu::ColorWrites::ALL,
    })
}

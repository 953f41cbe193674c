//! A character on the GPU: its baked textures and buffers, created once, and the bind group that
//! every character pass uses.

use super::gpu::Gpu;
use crate::bake::CharacterBake;
use crate::bake::texels::TexelGrid;
use wgpu::util::DeviceExt;

/// Shadow ellipse of a character, mirror of `Shadow` in `shaders/shadow.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadowUniform {
    ellipse: [f32; 4],
}

pub struct GpuCharacter {
    /// Every clip as the instance data carries it.
    pub clip_rows: Vec<[f32; 4]>,
    pub triangle_count: u32,
    pub vertex_count: u32,
    pub influence_count: u32,
    pub index_buffer: wgpu::Buffer,
    pub index_count: u32,
    pub static_vertices: wgpu::Buffer,
    pub bind_group: wgpu::BindGroup,
}

/// Layout of group 1: animation texture, vertex texture, material layers, sampler, shadow.
pub fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let data_texture = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("character"),
        entries: &[
            data_texture(0),
            data_texture(1),
            wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: wgpu::TextureViewDimension::D2Array,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 3,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 4,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
        ],
    })
}

fn data_texture(gpu: &Gpu, label: &str, grid: &TexelGrid) -> wgpu::Texture {
    gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: grid.width,
                height: grid.height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        grid.bytes(),
    )
}

impl GpuCharacter {
    pub fn upload(
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        sampler: &wgpu::Sampler,
        bake: &CharacterBake,
    ) -> GpuCharacter {
        let anim = data_texture(
            gpu,
            &format!("{} animation", bake.name),
            &bake.animation.grid,
        );
        let verts = data_texture(gpu, &format!("{} vertices", bake.name), &bake.vertices.grid);
        let m = &bake.materials;
        let material_data: Vec<u8> = m.mips.concat();
        let materials = gpu.device.create_texture_with_data(
            &gpu.queue,
            &wgpu::TextureDescriptor {
                label: Some("materials"),
                size: wgpu::Extent3d {
                    width: m.width,
                    height: m.height,
                    depth_or_array_layers: m.layer_count,
                },
                mip_level_count: m.mips.len() as u32,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8UnormSrgb,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::MipMajor,
            &material_data,
        );
        let index_buffer = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("indices"),
                contents: bytemuck::cast_slice(&bake.indices),
                usage: wgpu::BufferUsages::INDEX,
            });
        let static_vertices = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("static vertices"),
                contents: bytemuck::cast_slice(&bake.static_vertices),
                usage: wgpu::BufferUsages::VERTEX,
            });
        // The blob shadow covers the footprint of the animated bounds.
        let b = bake.bounds;
        let shadow = ShadowUniform {
            ellipse: [
                b.center().x,
                b.center().z,
                (b.size().x * 0.5).max(0.05),
                (b.size().z * 0.5).max(0.05),
            ],
        };
        let shadow_buffer = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("shadow"),
                contents: bytemuck::bytes_of(&shadow),
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let view = |t: &wgpu::Texture, dim| {
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(dim),
                ..Default::default()
            })
        };
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&bake.name),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view(
                        &anim,
                        wgpu::TextureViewDimension::D2,
                    )),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&view(
                        &verts,
                        wgpu::TextureViewDimension::D2,
                    )),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&view(
                        &materials,
                        wgpu::TextureViewDimension::D2Array,
                    )),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::Sampler(sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: shadow_buffer.as_entire_binding(),
                },
            ],
        });
        GpuCharacter {
            clip_rows: (0..bake.animation.clips.len())
                .map(|c| bake.animation.clip_rows(c))
                .collect(),
            triangle_count: bake.triangle_count() as u32,
            vertex_count: bake.vertices.vertex_count,
            influence_count: bake.vertices.influence_count,
            index_buffer,
            index_count: bake.indices.len() as u32,
            static_vertices,
            bind_group,
        }
    }
}

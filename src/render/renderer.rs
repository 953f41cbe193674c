//! The scene renderer: sky, ground, blob shadows and instanced skinned characters.
//!
//! Per frame the caller hands over the camera and a list of instances; [`SceneRenderer::prepare`]
//! groups them by model and uploads them in one buffer write, and [`SceneRenderer::draw`] issues
//! one instanced draw per model. Nothing is allocated per frame once the instance buffer is big
//! enough.

use super::character::{self, GpuCharacter};
use super::gpu::Gpu;
use super::shaders;
use super::targets::DEPTH_FORMAT;
use super::uniforms::{FrameUniforms, FrameView, GpuInstance, Lighting, static_vertex_layout};
use crate::bake::CharacterBake;
use crate::scene::Instance;
use anyhow::{Result, bail};
use std::ops::Range;

/// Which vertex shader draws the characters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CharacterShader {
    /// Animation-space skinning from the animation and vertex textures.
    Skinned,
    /// The same triangles in one fixed pose from a plain vertex buffer: the calibration baseline.
    Plain,
}

/// What a frame drew.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameStats {
    pub instances: u64,
    pub triangles: u64,
    pub vertices: u64,
    pub influences: u64,
    pub draw_calls: u32,
}

pub struct SceneRenderer {
    pub lighting: Lighting,
    pub shader: CharacterShader,
    pub shadows: bool,
    frame_buffer: wgpu::Buffer,
    frame_bind_group: wgpu::BindGroup,
    pub(crate) frame_layout: wgpu::BindGroupLayout,
    pub(crate) character_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    characters: Vec<GpuCharacter>,
    skinned: wgpu::RenderPipeline,
    plain: wgpu::RenderPipeline,
    sky: wgpu::RenderPipeline,
    ground: wgpu::RenderPipeline,
    shadow: wgpu::RenderPipeline,
    instance_buffer: wgpu::Buffer,
    staging: Vec<GpuInstance>,
    counts: Vec<u32>,
    cursor: Vec<u32>,
    draws: Vec<(usize, Range<u32>)>,
}

pub(crate) fn frame_bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("frame"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    })
}

/// Depth state: test and write, test only, or neither.
#[derive(Clone, Copy)]
enum Depth {
    Write,
    TestOnly,
    Ignore,
}

struct PipelineSpec<'a> {
    label: &'a str,
    module: &'a wgpu::ShaderModule,
    vs: &'a str,
    fs: &'a str,
    buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    depth: Depth,
    blend: Option<wgpu::BlendState>,
    cull: Option<wgpu::Face>,
}

fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    format: wgpu::TextureFormat,
    samples: u32,
    spec: PipelineSpec,
) -> wgpu::RenderPipeline {
    let depth_stencil = match spec.depth {
        Depth::Write => Some((true, wgpu::CompareFunction::Less)),
        Depth::TestOnly => Some((false, wgpu::CompareFunction::LessEqual)),
        Depth::Ignore => Some((false, wgpu::CompareFunction::Always)),
    }
    .map(|(write, compare)| wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: Default::default(),
        bias: Default::default(),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(spec.label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: spec.module,
            entry_point: Some(spec.vs),
            compilation_options: Default::default(),
            buffers: spec.buffers,
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: spec.cull,
            ..Default::default()
        },
        depth_stencil,
        multisample: wgpu::MultisampleState {
            count: samples,
            ..Default::default()
        },
        fragment: Some(wgpu::FragmentState {
            module: spec.module,
            entry_point: Some(spec.fs),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend: spec.blend,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

impl SceneRenderer {
    pub fn new(gpu: &Gpu, color_format: wgpu::TextureFormat, sample_count: u32) -> Self {
        let device = &gpu.device;
        let frame_layout = frame_bind_group_layout(device);
        let character_layout = character::bind_group_layout(device);
        let frame_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame uniforms"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_buffer.as_entire_binding(),
            }],
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("material"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let with_characters = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("characters"),
            bind_group_layouts: &[Some(&frame_layout), Some(&character_layout)],
            immediate_size: 0,
        });
        let frame_only = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("environment"),
            bind_group_layouts: &[Some(&frame_layout)],
            immediate_size: 0,
        });

        let character_module = shaders::CHARACTER_SHADER.create(device);
        let plain_module = shaders::PLAIN_SHADER.create(device);
        let environment_module = shaders::ENVIRONMENT_SHADER.create(device);
        let shadow_module = shaders::SHADOW_SHADER.create(device);
        let (f, s) = (color_format, sample_count);
        let skinned = pipeline(
            device,
            &with_characters,
            f,
            s,
            PipelineSpec {
                label: "skinned characters",
                module: &character_module,
                vs: "vs_main",
                fs: "fs_main",
                buffers: &[Some(GpuInstance::layout())],
                depth: Depth::Write,
                blend: None,
                cull: Some(wgpu::Face::Back),
            },
        );
        let plain = pipeline(
            device,
            &with_characters,
            f,
            s,
            PipelineSpec {
                label: "plain characters",
                module: &plain_module,
                vs: "vs_main",
                fs: "fs_main",
                buffers: &[Some(static_vertex_layout()), Some(GpuInstance::layout())],
                depth: Depth::Write,
                blend: None,
                cull: Some(wgpu::Face::Back),
            },
        );
        let sky = pipeline(
            device,
            &frame_only,
            f,
            s,
            PipelineSpec {
                label: "sky",
                module: &environment_module,
                vs: "vs_sky",
                fs: "fs_sky",
                buffers: &[],
                depth: Depth::Ignore,
                blend: None,
                cull: None,
            },
        );
        let ground = pipeline(
            device,
            &frame_only,
            f,
            s,
            PipelineSpec {
                label: "ground",
                module: &environment_module,
                vs: "vs_ground",
                fs: "fs_ground",
                buffers: &[],
                depth: Depth::Write,
                blend: None,
                cull: None,
            },
        );
        let shadow = pipeline(
            device,
            &with_characters,
            f,
            s,
            PipelineSpec {
                label: "blob shadows",
                module: &shadow_module,
                vs: "vs_main",
                fs: "fs_main",
                buffers: &[Some(GpuInstance::layout())],
                depth: Depth::TestOnly,
                blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                cull: None,
            },
        );
        let instance_buffer = Self::instance_buffer(device, 256);
        SceneRenderer {
            lighting: Lighting::default(),
            shader: CharacterShader::Skinned,
            shadows: true,
            frame_buffer,
            frame_bind_group,
            frame_layout,
            character_layout,
            sampler,
            characters: Vec::new(),
            skinned,
            plain,
            sky,
            ground,
            shadow,
            instance_buffer,
            staging: Vec::new(),
            counts: Vec::new(),
            cursor: Vec::new(),
            draws: Vec::new(),
        }
    }

    fn instance_buffer(device: &wgpu::Device, capacity: usize) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("instances"),
            size: (capacity * std::mem::size_of::<GpuInstance>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Uploads a baked character; returns its index for [`Instance::model`].
    pub fn add_character(&mut self, gpu: &Gpu, bake: &CharacterBake) -> Result<usize> {
        let limit = gpu.device.limits().max_texture_dimension_2d;
        if bake.animation.grid.height > limit || bake.vertices.grid.height > limit {
            bail!(
                "{}: animation or vertex data exceed this GPU's {limit}-texel texture limit",
                bake.name
            );
        }
        let c = GpuCharacter::upload(gpu, &self.character_layout, &self.sampler, bake);
        self.characters.push(c);
        Ok(self.characters.len() - 1)
    }

    pub fn characters(&self) -> &[GpuCharacter] {
        &self.characters
    }

    /// Uploads the frame's uniforms and instances (one buffer write each) and plans the draws.
    pub fn prepare(&mut self, gpu: &Gpu, view: &FrameView, instances: &[Instance]) -> FrameStats {
        let uniforms = FrameUniforms::new(view, &self.lighting, [0.0; 3]);
        gpu.queue
            .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&uniforms));

        // Counting sort by model: instances of one model become one contiguous range.
        let models = self.characters.len();
        self.counts.clear();
        self.counts.resize(models + 1, 0);
        for inst in instances.iter().filter(|i| i.model < models) {
            self.counts[inst.model + 1] += 1;
        }
        for m in 0..models {
            self.counts[m + 1] += self.counts[m];
        }
        let total = self.counts[models] as usize;
        self.staging.clear();
        self.staging.resize(total, bytemuck::Zeroable::zeroed());
        self.draws.clear();
        for m in 0..models {
            if self.counts[m + 1] > self.counts[m] {
                self.draws.push((m, self.counts[m]..self.counts[m + 1]));
            }
        }
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.counts);
        for inst in instances.iter().filter(|i| i.model < models) {
            let slot = &mut self.cursor[inst.model];
            let rows = &self.characters[inst.model].clip_rows;
            self.staging[*slot as usize] = GpuInstance::new(
                &inst.transform,
                rows[(inst.clip as usize).min(rows.len() - 1)],
                inst.time_offset,
                inst.speed,
                inst.tint,
            );
            *slot += 1;
        }
        if total * std::mem::size_of::<GpuInstance>() > self.instance_buffer.size() as usize {
            self.instance_buffer =
                Self::instance_buffer(&gpu.device, total.next_power_of_two().max(256));
        }
        if total > 0 {
            gpu.queue.write_buffer(
                &self.instance_buffer,
                0,
                bytemuck::cast_slice(&self.staging),
            );
        }

        let mut stats = FrameStats::default();
        for (m, range) in &self.draws {
            let c = &self.characters[*m];
            let n = (range.end - range.start) as u64;
            stats.instances += n;
            stats.triangles += n * c.triangle_count as u64;
            stats.vertices += n * c.vertex_count as u64;
            stats.influences += n * c.influence_count as u64;
            stats.draw_calls += 1;
        }
        stats
    }

    /// Records the frame: sky, ground, shadows, characters.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_bind_group(0, &self.frame_bind_group, &[]);
        pass.set_pipeline(&self.sky);
        pass.draw(0..3, 0..1);
        pass.set_pipeline(&self.ground);
        pass.draw(0..6, 0..1);
        if self.draws.is_empty() {
            return;
        }
        pass.set_vertex_buffer(0, self.instance_buffer.slice(..));
        if self.shadows {
            pass.set_pipeline(&self.shadow);
            for (m, range) in &self.draws {
                pass.set_bind_group(1, &self.characters[*m].bind_group, &[]);
                pass.draw(0..6, range.clone());
            }
        }
        match self.shader {
            CharacterShader::Skinned => {
                pass.set_pipeline(&self.skinned);
                for (m, range) in &self.draws {
                    let c = &self.characters[*m];
                    pass.set_bind_group(1, &c.bind_group, &[]);
                    pass.set_index_buffer(c.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..c.index_count, 0, range.clone());
                }
            }
            CharacterShader::Plain => {
                pass.set_pipeline(&self.plain);
                pass.set_vertex_buffer(1, self.instance_buffer.slice(..));
                for (m, range) in &self.draws {
                    let c = &self.characters[*m];
                    pass.set_bind_group(1, &c.bind_group, &[]);
                    pass.set_vertex_buffer(0, c.static_vertices.slice(..));
                    pass.set_index_buffer(c.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..c.index_count, 0, range.clone());
                }
            }
        }
    }

    /// Records the scene pass into `target` through `targets`, drawing only inside `viewport`
    /// (x, y, width, height in pixels) when one is given.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &super::targets::RenderTargets,
        target: &wgpu::TextureView,
        viewport: Option<[u32; 4]>,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("scene"),
            color_attachments: &[Some(
                targets.color(target, wgpu::LoadOp::Clear(wgpu::Color::BLACK)),
            )],
            depth_stencil_attachment: Some(targets.depth()),
            ..Default::default()
        });
        if let Some([x, y, w, h]) = viewport {
            pass.set_viewport(x as f32, y as f32, w as f32, h as f32, 0.0, 1.0);
            pass.set_scissor_rect(x, y, w, h);
        }
        self.draw(&mut pass);
    }

    /// Renders one complete frame into `target` through `targets` and submits it.
    pub fn render_to(
        &self,
        gpu: &Gpu,
        targets: &super::targets::RenderTargets,
        target: &wgpu::TextureView,
    ) -> wgpu::SubmissionIndex {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        self.encode(&mut enc, targets, target, None);
        gpu.queue.submit([enc.finish()])
    }
}

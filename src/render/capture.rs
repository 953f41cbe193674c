//! A debug pass that reads back what the GPU skinning computes.
//!
//! Every vertex of a character is drawn as one point into its own texel of an `Rgba32Float`
//! target (vertex `i` at `(i % width, i / width)`), coloured with its skinned position and its
//! influence count. The vertex shader is `skin_vertex` from `shaders/skinning.wgsl`, the same
//! function the character pipeline uses, so tests can compare the GPU's result with the CPU
//! reference in [`crate::bake::gpu_data::animation_space`].

use super::gpu::Gpu;
use super::renderer::SceneRenderer;
use super::shaders;
use super::targets::Offscreen;
use super::uniforms::{FrameUniforms, FrameView, GpuInstance};
use anyhow::{Result, bail};
use glam::{Affine3A, Mat4, Vec3, Vec4};
use wgpu::util::DeviceExt;

const WIDTH: u32 = 256;

/// Skinned positions (xyz, scene space) and influence counts (w) of every vertex of character
/// `model`, at `time` seconds into `clip`, placed by `transform`.
pub fn capture_skinned(
    gpu: &Gpu,
    renderer: &SceneRenderer,
    model: usize,
    clip: u32,
    time: f32,
    transform: Affine3A,
) -> Result<Vec<Vec4>> {
    capture_skinned_in_wind(gpu, renderer, model, clip, time, transform, 1.0)
}

/// [`capture_skinned`] with the instance's wind strength `wind`.
pub fn capture_skinned_in_wind(
    gpu: &Gpu,
    renderer: &SceneRenderer,
    model: usize,
    clip: u32,
    time: f32,
    transform: Affine3A,
    wind: f32,
) -> Result<Vec<Vec4>> {
    let playing = Playing {
        clip,
        time,
        wind,
        fade: None,
    };
    capture(gpu, renderer, model, transform, playing)
}

/// [`capture_skinned`] cross-fading from `clip` at `time` to `to.0` at `to.1` seconds by
/// `weight` (0: `clip` alone).
pub fn capture_skinned_fading(
    gpu: &Gpu,
    renderer: &SceneRenderer,
    model: usize,
    (clip, time): (u32, f32),
    to: (u32, f32),
    weight: f32,
    transform: Affine3A,
) -> Result<Vec<Vec4>> {
    let playing = Playing {
        clip,
        time,
        wind: 1.0,
        fade: Some((to, weight)),
    };
    capture(gpu, renderer, model, transform, playing)
}

/// What the captured instance plays: `clip` at `time` seconds with wind strength `wind`,
/// cross-fading to `fade.0` (clip, seconds) by `fade.1` where there is a fade.
struct Playing {
    clip: u32,
    time: f32,
    wind: f32,
    fade: Option<((u32, f32), f32)>,
}

fn capture(
    gpu: &Gpu,
    renderer: &SceneRenderer,
    model: usize,
    transform: Affine3A,
    playing: Playing,
) -> Result<Vec<Vec4>> {
    let Some(character) = renderer.characters().get(model) else {
        bail!("no character {model}");
    };
    let device = &gpu.device;
    let n = character.full().levels[0].vertices;
    let height = n.div_ceil(WIDTH).max(1);
    let format = wgpu::TextureFormat::Rgba32Float;
    let target = Offscreen::with_format(gpu, WIDTH, height, 1, format);
    let (_frame_buffer, frame_bind_group) = frame_bind_group(gpu, renderer, playing.time, height);
    let instance = playing_instance(&character.clip_rows, &transform, playing);
    let instance_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("capture instance"),
        contents: bytemuck::bytes_of(&instance),
        usage: wgpu::BufferUsages::VERTEX,
    });
    let (_layout, pipeline) = capture_pipeline(gpu, renderer, format);
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("capture"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &target.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &frame_bind_group, &[]);
        pass.set_bind_group(1, &character.full().bind_group, &[]);
        pass.set_vertex_buffer(0, instance_buffer.slice(..));
        pass.draw(0..n, 0..1);
    }
    gpu.queue.submit([enc.finish()]);
    gpu.take_error()?;
    let bytes = target.read_bytes(gpu)?;
    let texels: &[Vec4] = bytemuck::cast_slice(&bytes);
    Ok(texels[..n as usize].to_vec())
}

/// The frame uniforms of a capture at `time` seconds, and their bind group: identity view
/// and projection (the skinned position is written as a colour, not placed on screen) over a
/// target `height` rows of [`WIDTH`] texels. The buffer is returned to be held while the
/// bind group is used.
fn frame_bind_group(
    gpu: &Gpu,
    renderer: &SceneRenderer,
    time: f32,
    height: u32,
) -> (wgpu::Buffer, wgpu::BindGroup) {
    let device = &gpu.device;
    let view = FrameView {
        view: Mat4::IDENTITY,
        proj: Mat4::IDENTITY,
        eye: Vec3::ZERO,
        time,
    };
    let uniforms = FrameUniforms::new(&view, &renderer.lighting, [0, 0, WIDTH, height]);
    let frame_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("capture frame"),
        contents: bytemuck::bytes_of(&uniforms),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let frame_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("capture frame"),
        layout: &renderer.frame_layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: frame_buffer.as_entire_binding(),
        }],
    });
    (frame_buffer, frame_bind_group)
}

/// The one instance a capture draws: placed by `transform`, playing what `Playing` says (a
/// clip past the character's last is its last, `rows` its clips' frame ranges).
fn playing_instance(
    rows: &[[f32; 4]],
    transform: &Affine3A,
    Playing {
        clip,
        time,
        wind,
        fade,
    }: Playing,
) -> GpuInstance {
    let mut instance = GpuInstance::new(
        transform,
        rows[(clip as usize).min(rows.len() - 1)],
        0.0,
        1.0,
        Vec4::ONE,
    );
    instance.timing[2] = wind;
    if let Some(((to, to_time), weight)) = fade {
        // The frame's time is `time`: the second clip's offset puts it at `to_time`.
        instance = instance.with_fade(
            rows[(to as usize).min(rows.len() - 1)],
            to_time - time,
            1.0,
            weight,
        );
    }
    instance
}

/// The capture pipeline: `skin_vertex` through the capture shader, one point per vertex into
/// a `format` target, over the frame and character bind groups the scene's character
/// pipeline uses. Its layout is returned to be held with it.
fn capture_pipeline(
    gpu: &Gpu,
    renderer: &SceneRenderer,
    format: wgpu::TextureFormat,
) -> (wgpu::PipelineLayout, wgpu::RenderPipeline) {
    let device = &gpu.device;
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("capture"),
        bind_group_layouts: &[
            Some(&renderer.frame_layout),
            Some(&renderer.character_layout),
        ],
        immediate_size: 0,
    });
    let module = shaders::CAPTURE_SHADER.create(device);
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("capture"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(GpuInstance::layout())],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::PointList,
            ..Default::default()
        },
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        multiview_mask: None,
        cache: None,
    });
    (layout, pipeline)
}

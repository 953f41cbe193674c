//! The pixels each pass of a frame covers: how many of the fragments a pass shades fall on
//! the same pixels. Fragments per pixel of the whole view hide where they are: trees that are
//! a band near the horizon shade few pixels of the view many times over. Drawn apart from the
//! frame, once per pass, so the frame's own figures are not disturbed. And what each level
//! kind costs drawn alone ([`kinds_alone`]).

use crate::bake::gpu_data::drawable::LevelKind;
use crate::render::Gpu;
use crate::render::renderer::SceneRenderer;
use crate::render::targets::Offscreen;
use crate::render::timer::{FrameTimer, Pass};
use anyhow::Result;

/// The colour the coverage frames are cleared to, which no shaded pixel of a scene is
/// exactly: magenta (sRGB bytes 255, 0, 255). The passes never write alpha, so the colour is
/// what tells.
const UNDRAWN: [u8; 3] = [255, 0, 255];

/// The pixels of `target` that pass `which` of `renderer`'s prepared frame covers, drawn
/// alone over a cleared view and depth buffer: those whose colour it changes (a blended pass,
/// the shadows, counts where it blends). Leaves the picture in `target`.
pub fn covered_pixels(
    gpu: &Gpu,
    renderer: &SceneRenderer,
    target: &Offscreen,
    which: Pass,
) -> Result<u64> {
    let t = &target.targets;
    let clear = wgpu::Color {
        r: 1.0,
        g: 0.0,
        b: 1.0,
        a: 1.0,
    };
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("coverage"),
            color_attachments: &[Some(t.color_with(
                &target.view,
                wgpu::LoadOp::Clear(clear),
                true,
            ))],
            depth_stencil_attachment: Some(t.depth(true, true)),
            ..Default::default()
        });
        renderer.draw(&mut pass, which, [0, 0, t.width, t.height]);
    }
    gpu.queue.submit([encoder.finish()]);
    gpu.take_error()?;
    let bytes = target.read_bytes(gpu)?;
    Ok(bytes.chunks_exact(4).filter(|p| p[..3] != UNDRAWN).count() as u64)
}

/// Each level kind's instances of `renderer`'s prepared frame drawn alone into `target` (no
/// other kind hiding any of them), timed by `timer`: the GPU ms and fragments per pixel of
/// the view of the pass they draw in (foliage for trees, characters for the rest); `None`
/// for a kind that shaded nothing, or where the adapter does not count fragments.
pub fn kinds_alone(
    gpu: &Gpu,
    renderer: &mut SceneRenderer,
    target: &Offscreen,
    timer: &mut FrameTimer,
) -> Result<[Option<[f64; 2]>; LevelKind::COUNT]> {
    let pixels = (target.targets.width as f64 * target.targets.height as f64).max(1.0);
    let mut out = [None; LevelKind::COUNT];
    for kind in LevelKind::ALL {
        renderer.only_kind = Some(kind);
        let drawn = renderer.render_timed(gpu, &target.targets, &target.view, Some(timer));
        renderer.only_kind = None;
        drawn?;
        let times = timer.read(gpu)?;
        let pass = match kind {
            LevelKind::Mesh | LevelKind::CharacterImpostor => Pass::Characters,
            _ => Pass::Foliage,
        };
        if let (Some(ms), Some(f)) = (times.ms[pass as usize], times.fragments[pass as usize])
            && f > 0
        {
            out[kind as usize] = Some([ms, f as f64 / pixels]);
        }
    }
    Ok(out)
}

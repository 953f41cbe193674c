//! Frame-rate figures for levels of detail at run time, as ratios measured in one run:
//! `cargo bench --bench lod_runtime` (on lavapipe, or on whatever adapter wgpu picks).
//!
//! The crowd scene with 1,000 characters (horses and walkers) over a field, from the default
//! viewpoint, 1280×720 with 4× multisampling, tolerance 1.5 px:
//! - frames per second and triangles per frame for `none`, `rest-pose`, `as` and `as+is`;
//! - the cost of transitions: `as+is` with every visible instance forced into a morph (t = ½
//!   towards the next level), an alpha blend or a dithered cross-fade (p = ¼), against the same
//!   frame popping; and popping and dithering with the coarse levels lit by their vertex
//!   normals instead of their normal maps.

use anyhow::Result;
use lodlab::render::targets::{OFFSCREEN_FORMAT, Offscreen};
use lodlab::render::{FrameView, Gpu, Region, Side};
use lodlab::runtime::headless::time_renderer;
use lodlab::runtime::spec::{Loaded, SceneSpec};
use lodlab::runtime::world::World;
use lodlab::scene::{LodDraw, LodMethod, Transition};

const WIDTH: u32 = 1280;
const HEIGHT: u32 = 720;
const TIME: f32 = 2.0;
const FRAMES: usize = 9;

fn main() -> Result<()> {
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.describe());
    let spec = SceneSpec {
        count: 1000,
        ..Default::default()
    };
    let samples = 4;
    let mut world = World::new(&gpu, Loaded::new(spec)?, OFFSCREEN_FORMAT, samples)?;
    let target = Offscreen::new(&gpu, WIDTH, HEIGHT, samples);
    world.lod.policy.transition = Transition::Pop;

    println!(
        "\n1000 characters, {WIDTH}x{HEIGHT}, MSAA {samples}, tolerance {} px",
        world.lod.policy.tolerance_px
    );
    println!(
        "{:<10} {:>9} {:>8} {:>12} {:>12} {:>9}",
        "method", "ms/frame", "fps", "triangles", "influences", "vs none"
    );
    let mut none_ms = 0.0;
    for method in LodMethod::ALL {
        world.lod.method = method;
        world.ensure_levels(&gpu, &lodlab::measure::GpuMeasurer)?;
        world.lod.reset();
        world.settle(HEIGHT, TIME, 0.0);
        let stats = world.upload(&gpu, WIDTH as f32 / HEIGHT as f32, TIME);
        time_renderer(&gpu, &world.renderer, &target, 1, None)?;
        let ms = time_renderer(&gpu, &world.renderer, &target, FRAMES, None)?.0;
        if method == LodMethod::None {
            none_ms = ms;
        }
        println!(
            "{:<10} {:>9.1} {:>8.2} {:>12} {:>12} {:>8.1}x",
            method.name(),
            ms,
            1000.0 / ms,
            stats.triangles,
            stats.influences,
            none_ms / ms
        );
    }

    // Transitions: the as+is frame as it pops, then with every instance in transition.
    let method = LodMethod::ALL[3];
    world.lod.method = method;
    world.lod.reset();
    world.settle(HEIGHT, TIME, 0.0);
    let levels = world.renderer.characters()[0]
        .set(method.index())
        .map_or(1, |s| s.levels.len())
        .min(
            world.renderer.characters()[1]
                .set(method.index())
                .map_or(1, |s| s.levels.len()),
        ) as u8;
    let mut instances = Vec::new();
    world.crowd.instances_at(TIME, &mut instances);
    let popped: Vec<LodDraw> = world.lod.draws(0).to_vec();
    let pair = |d: &LodDraw| {
        let k = d.nearest_level().min(levels - 1);
        if k + 1 < levels {
            (k, k + 1)
        } else {
            (k - 1, k)
        }
    };
    let morphs: Vec<LodDraw> = popped
        .iter()
        .map(|d| {
            let (fine, coarse) = pair(d);
            LodDraw::Morph {
                fine,
                coarse,
                t: 0.5,
            }
        })
        .collect();
    let alphas: Vec<LodDraw> = popped
        .iter()
        .map(|d| {
            let (from, to) = pair(d);
            LodDraw::Alpha { from, to, p: 0.25 }
        })
        .collect();
    let dithers: Vec<LodDraw> = popped
        .iter()
        .map(|d| {
            let (from, to) = pair(d);
            LodDraw::Dither { from, to, p: 0.25 }
        })
        .collect();
    let view = FrameView::from_camera(&world.camera, WIDTH as f32 / HEIGHT as f32, TIME);
    println!("\nas+is, every instance in transition");
    println!(
        "{:<22} {:>9} {:>12} {:>9} {:>10}",
        "draw", "ms/frame", "triangles", "draws", "vs pop"
    );
    let mut pop_ms = 0.0;
    for (name, draws, normal_maps) in [
        ("pop", &popped, true),
        ("morph", &morphs, true),
        ("alpha", &alphas, true),
        ("dither", &dithers, true),
        ("pop, vertex normals", &popped, false),
        ("dither, vertex normals", &dithers, false),
    ] {
        world.renderer.normal_maps = normal_maps;
        let stats = world.renderer.prepare(
            &gpu,
            &view,
            &[Side {
                method: method.index(),
                instances: &instances,
                draws,
                region: Region::Full,
            }],
        );
        time_renderer(&gpu, &world.renderer, &target, 1, None)?;
        let ms = time_renderer(&gpu, &world.renderer, &target, FRAMES, None)?.0;
        if name == "pop" {
            pop_ms = ms;
        }
        println!(
            "{:<22} {:>9.1} {:>12} {:>9} {:>9.2}x",
            name,
            ms,
            stats.triangles,
            stats.draw_calls,
            ms / pop_ms
        );
    }
    Ok(())
}

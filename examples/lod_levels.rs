//! Renders every level of detail of one model by one method side by side, all in the same
//! pose, to a PNG: `cargo run --release --example lod_levels -- horse as+is levels.png`.
//!
//! A quick way to look at what `lodlab bake` produced before the viewer draws levels.

use anyhow::Result;
use glam::{Affine3A, Quat, Vec3, Vec4};
use lodlab::bake::character::lod::bake_lods;
use lodlab::bake::character::lod::lod_options;
use lodlab::bake::character::simplify::Method;
use lodlab::bake::gpu_data::drawable::Drawable;
use lodlab::bake::gpu_data::lod_pack::LodPack;
use lodlab::render::targets::{OFFSCREEN_FORMAT, Offscreen};
use lodlab::render::{FrameView, Gpu, Region, SceneRenderer, Side};
use lodlab::scene::crowd::Instance;
use lodlab::scene::{Camera, LodDraw, LodMethod};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [model, method, out] = args.as_slice() else {
        anyhow::bail!("usage: lod_levels MODEL METHOD OUT.png");
    };
    let method: Method = lodlab::choice::parse(method, "a method").map_err(anyhow::Error::msg)?;
    let model = lodlab::import::load_model(model)?;
    let lods = bake_lods(&model, method, &lod_options(&model, 0.5, None), &|_| {});
    let gpu = Gpu::headless()?;
    let mut renderer = SceneRenderer::new(&gpu, OFFSCREEN_FORMAT, 4);
    let bake = Drawable::new(&model).map_err(|e| anyhow::anyhow!(e))?;
    renderer.add_character(&gpu, &bake)?;
    let slot = LodMethod::Simplified(method).index();
    let pack = LodPack::from_levels(&lods.levels).map_err(|e| anyhow::anyhow!(e))?;
    renderer.add_levels(&gpu, 0, slot, &pack)?;
    let mut instances = Vec::new();
    let mut draws = Vec::new();
    let height = lodlab::bake::character::lod::model_height(&model);
    let spacing = height * 0.9;
    let n = lods.levels.len();
    for (k, level) in lods.levels.iter().enumerate() {
        draws.push(LodDraw::Level(k as u8));
        let x = (k as f32 - (n - 1) as f32 / 2.0) * spacing;
        instances.push(Instance {
            model: 0,
            transform: Affine3A::from_rotation_translation(
                Quat::from_rotation_y(1.2),
                Vec3::new(x, 0.0, 0.0),
            ),
            clip: 0,
            time_offset: 0.3,
            speed: 1.0,
            wind: 1.0,
            tint: Vec4::ONE,
            fade: None,
            travel: Vec3::ZERO,
        });
        println!(
            "LOD {k}: {} triangles, {} influences, error {:.2} mm",
            level.triangles(),
            level.influences(),
            level.error * 1000.0
        );
    }
    let (w, h) = (260 * n as u32, 420);
    let target = Offscreen::new(&gpu, w, h, 4);
    let camera = Camera::new(
        Vec3::new(0.0, height * 0.5, 0.0),
        0.0,
        5.0,
        n as f32 * spacing * 0.45,
    );
    let view = FrameView::from_camera(&camera, w as f32 / h as f32, 0.0);
    renderer.prepare(
        &gpu,
        &view,
        &[Side {
            method: slot,
            instances: &instances,
            draws: &draws,
            region: Region::Full,
        }],
    );
    renderer
        .render_to(&gpu, &target.targets, &target.view)
        .expect("rendered");
    target.read_rgba(&gpu)?.save(out)?;
    Ok(())
}

//! Normal maps on the coarse levels (lavapipe in CI): they bring a level's lighting closer to
//! full detail's, models without usable texture coordinates keep their vertex normals, and the
//! world and its panel line follow the toggle.

use lodlab::bake::character::lod::{SkinnedLods, bake_lods};
use lodlab::bake::character::normal_map::{NORMAL_MAP_SIZE, UvProblem};
use lodlab::bake::character::simplify::{Method, SimplifyInput};
use lodlab::bake::gpu_data::drawable::Drawable;
use lodlab::bake::gpu_data::lod_pack::LodPack;
use lodlab::import::load_model;
use lodlab::measure::shading_error::shading_errors;
use lodlab::model::Model;
use lodlab::render::Gpu;
use lodlab::render::targets::{OFFSCREEN_FORMAT, Offscreen};
use lodlab::runtime::levels::runtime_options;
use lodlab::runtime::spec::{Loaded, SceneSpec};
use lodlab::runtime::world::World;
use lodlab::scene::LodMethod;

fn gpu() -> &'static Gpu {
    crate::common::gpu()
}

/// Held by every test that draws: they share one device, and lavapipe (Mesa 22.3) crashed in
/// a rasteriser thread, about one run in six, with several of them drawing on it at once.
fn serial() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    LOCK.lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn levels(model: &Model) -> SkinnedLods {
    bake_lods(
        model,
        Method::InfluenceSimplification,
        &runtime_options(model, None),
        &|_| {},
    )
}

#[test]
fn coarse_levels_are_lit_closer_to_full_detail_through_their_maps() {
    let _serial = serial();
    let walker = load_model("walker").unwrap();
    let lods = levels(&walker);
    let full = Drawable::new(&walker).unwrap();
    let n = lods.levels.len();
    assert!(n >= 4, "{n} levels");
    let which = [n - 3, n - 2, n - 1];
    let errors = shading_errors(gpu(), &walker, &full, &lods.levels, &which, 200.0).unwrap();
    for e in &errors {
        assert!(e.mapped, "level {} has a map", e.level);
        assert!(
            e.normal_maps < 0.95 * e.vertex_normals,
            "level {} ({} triangles): {:.4} through its map against {:.4} by vertex normals",
            e.level,
            e.triangles,
            e.normal_maps,
            e.vertex_normals
        );
    }
}

#[test]
fn a_model_without_texture_coordinates_keeps_its_vertex_normals() {
    let _serial = serial();
    let mut walker = load_model("walker").unwrap();
    walker
        .mesh
        .uvs
        .iter_mut()
        .for_each(|uv| *uv = glam::Vec2::ZERO);
    let lods = levels(&walker);
    let rest = SimplifyInput::rest_bones(&walker.skeleton);
    let pack = LodPack::with_normal_maps(
        &lods.levels,
        &lods.levels[0].mesh,
        &rest,
        &walker.materials,
        NORMAL_MAP_SIZE,
    )
    .unwrap();
    let maps = pack.normal_maps.as_ref().unwrap();
    assert_eq!(maps.unmapped_reason(), Some(UvProblem::NoTexCoords));
    assert_eq!(maps.layer_count, 0);
    assert!(pack.levels.iter().all(|l| !l.normal_mapped));
    // Drawn with maps on, it is lit exactly as with them off.
    let full = Drawable::new(&walker).unwrap();
    let last = lods.levels.len() - 1;
    let e = shading_errors(gpu(), &walker, &full, &lods.levels, &[last], 120.0).unwrap();
    assert!(!e[0].mapped);
    assert_eq!(e[0].normal_maps, e[0].vertex_normals);
}

/// A walker crowd under AS+IS: the panel's line names the maps, the frame changes with the
/// toggle but draws the same triangles, and off, the line says so.
#[test]
fn the_world_lights_coarse_levels_through_maps_until_turned_off() {
    let _serial = serial();
    let gpu = gpu();
    let spec = SceneSpec {
        models: vec!["walker".into()],
        count: 60,
        cache_dir: Some(crate::common::shared_cache()),
        ..Default::default()
    };
    let mut world = World::new(gpu, Loaded::new(spec).unwrap(), OFFSCREEN_FORMAT, 1).unwrap();
    world.lod.method = LodMethod::AS_IS;
    world
        .ensure_levels(gpu, &lodlab::measure::GpuMeasurer)
        .unwrap();
    let info = world
        .normal_maps(0, LodMethod::AS_IS.index())
        .expect("the levels came with maps");
    assert!(info.levels >= 3 && info.unmapped.is_none(), "{info:?}");
    let summary = world.normal_map_summary();
    assert!(summary.starts_with("normal maps: walker"), "{summary}");
    world.camera =
        lodlab::scene::Camera::new(glam::Vec3::ZERO, 20.0, 20.0, world.crowd.radius * 1.5);
    let (w, h) = (480, 270);
    let target = Offscreen::new(gpu, w, h, 1);
    let frame = |world: &mut World| {
        world.lod.reset();
        world.settle(h, 2.0, 0.0);
        let stats = world.upload(gpu, w as f32 / h as f32, 2.0);
        world
            .renderer
            .render_to(gpu, &target.targets, &target.view)
            .expect("rendered");
        (stats, target.read_rgba(gpu).unwrap())
    };
    let (on, lit) = frame(&mut world);
    assert!(
        on.levels.iter().skip(1).sum::<u32>() > 10,
        "{:?}",
        on.levels
    );
    world.renderer.normal_maps = false;
    let (off, plain) = frame(&mut world);
    assert_eq!(on.triangles, off.triangles);
    let changed = lit
        .pixels()
        .zip(plain.pixels())
        .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b[c]) > 2))
        .count();
    assert!(changed > 100, "{changed} pixels changed");
    assert!(world.normal_map_summary().contains("off"));
}

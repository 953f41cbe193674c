//! Levels of detail at run time, on the CPU: no pop during a morph, and how levels are packed.

use glam::{Affine3A, Vec3, Vec4};
use lodlab::bake::character::lod::bake_lods;
use lodlab::bake::character::simplify::Method;
use lodlab::bake::gpu_data::drawable::Drawable;
use lodlab::bake::gpu_data::lod_pack::LodPack;
use lodlab::import::load_model;
use lodlab::runtime::levels::runtime_options;
use lodlab::scene::{Camera, Instance, LodDraw, LodModel, LodPolicy, LodTracker, ScreenProjection};

/// No pop (Merry et al. §6.4, Houle & Poulin §5): while the tracker morphs an instance from
/// one level to the next at 60 Hz with the default duration, no vertex moves on screen by more
/// than the tolerance from one frame to the next. The instance stands still in a frozen pose at
/// the distance where the morph starts, so every motion on screen is the morph's own.
#[test]
fn a_morph_moves_no_vertex_more_than_the_tolerance_per_frame() {
    let policy = LodPolicy::default();
    let (width, height) = (1280u32, 720u32);
    for name in ["horse", "walker"] {
        let model = load_model(name).unwrap();
        let bake = Drawable::new(&model).unwrap();
        let lods = bake_lods(
            &model,
            Method::InfluenceSimplification,
            &runtime_options(&model, None),
            &|_| {},
        );
        let pack = LodPack::from_levels(&lods.levels).unwrap();
        let lod_model = LodModel {
            errors: pack.errors(),
            center: bake.bounds.center(),
            radius: bake.bounds.diagonal() * 0.5,
        };
        let pose = bake.animation.sample(0, 0.4);
        let skinned: Vec<Vec<Vec3>> = lods
            .levels
            .iter()
            .map(|l| l.mesh.evaluate(&pose).0)
            .collect();
        let camera = Camera::new(Vec3::ZERO, 0.0, 5.0, 3.0);
        let screen = ScreenProjection::new(
            camera.eye(),
            camera.fov_y,
            height as f32,
            camera.near_far().0,
        );
        let view_proj = camera.proj(width as f32 / height as f32) * camera.view();
        let to_pixels = |p: Vec3| {
            let c = view_proj * p.extend(1.0);
            glam::Vec2::new(
                c.x / c.w * width as f32 * 0.5,
                c.y / c.w * height as f32 * 0.5,
            )
        };
        let mut worst = 0.0f32;
        let mut morph_frames = 0;
        for k in 1..lods.levels.len() {
            // Where level k becomes good enough with the hysteresis margin: the sphere's
            // nearest point just beyond that, along the view direction.
            let threshold = screen.threshold(lod_model.errors[k], policy.tolerance_px)
                / (1.0 - policy.hysteresis);
            let near = threshold * 0.999;
            let far = threshold * 1.01;
            let place = |d: f32| {
                let centre = camera.eye() + camera.forward() * (d + lod_model.radius);
                Affine3A::from_translation(centre - lod_model.center)
            };
            let instance = |d: f32| Instance {
                model: 0,
                transform: place(d),
                clip: 0,
                time_offset: 0.0,
                speed: 1.0,
                wind: 1.0,
                tint: Vec4::ONE,
                fade: None,
                travel: glam::Vec3::ZERO,
            };
            let mut tracker = LodTracker::default();
            let mut out = Vec::new();
            let models = std::slice::from_ref(&lod_model);
            tracker.update(&policy, models, &[instance(near)], &screen, 0.0, &mut out);
            assert_eq!(
                out[0],
                LodDraw::Level(k as u8 - 1),
                "{name}: before level {k}"
            );
            let t = place(far);
            let mut last: Option<Vec<glam::Vec2>> = None;
            for _ in 0..120 {
                tracker.update(
                    &policy,
                    models,
                    &[instance(far)],
                    &screen,
                    1.0 / 60.0,
                    &mut out,
                );
                let frame: Vec<glam::Vec2> = match out[0] {
                    LodDraw::Morph { fine, coarse, t: s } => {
                        morph_frames += 1;
                        let (f, c) = (fine as usize, coarse as usize);
                        assert_eq!((f, c), (k - 1, k));
                        let map = &lods.levels[f].geomorph;
                        skinned[f]
                            .iter()
                            .zip(map)
                            .map(|(p, &g)| {
                                let q = skinned[c][g as usize];
                                to_pixels(t.transform_point3((1.0 - s) * *p + s * q))
                            })
                            .collect()
                    }
                    LodDraw::Level(l) => {
                        assert_eq!(l as usize, k, "{name}: after the morph to {k}");
                        break;
                    }
                    other => panic!("{other:?}"),
                };
                if let Some(prev) = &last {
                    for (a, b) in prev.iter().zip(&frame) {
                        worst = worst.max(a.distance(*b));
                    }
                }
                last = Some(frame);
            }
        }
        assert!(morph_frames > 30 * (lods.levels.len() - 1) - 10);
        assert!(
            worst <= policy.tolerance_px,
            "{name}: a vertex moved {worst:.2} px in one frame (tolerance {} px)",
            policy.tolerance_px
        );
        eprintln!("{name}: largest move per frame {worst:.3} px");
    }
}

/// The viewer's background bake: it reports progress, ends with one pack per character and a
/// billboard-cloud chain per tree, and a second bake of the same method comes from the cache.
#[test]
fn background_bakes_finish_and_fill_the_cache() {
    use lodlab::bake::cache::LodCache;
    use lodlab::runtime::levels::{BackgroundBake, LevelSource, Levels, Poll};
    let dir = tempfile::tempdir().unwrap();
    let sources: Vec<LevelSource> = ["walker", "sapling"]
        .iter()
        .map(|name| LevelSource {
            model: load_model(name).unwrap(),
            hash: lodlab::import::import(name, &Default::default())
                .unwrap()
                .source_hash,
            impostor: None,
            budgets: None,
        })
        .collect();
    // Each model's levels come as soon as they are ready; the status names what is baking.
    let wait = |mut job: BackgroundBake| {
        let mut packs: Vec<lodlab::runtime::levels::Baked> = vec![None, None];
        let mut delivered = Vec::new();
        let status = job.status();
        loop {
            let (ready, over) = match job.poll() {
                Poll::Running(ready) => (ready, false),
                Poll::Done(ready) => (ready, true),
                Poll::Failed => panic!("the bake thread died"),
            };
            for (i, baked) in ready {
                delivered.push(i);
                packs[i] = baked;
            }
            if over {
                delivered.sort();
                assert_eq!(delivered, [0, 1], "every model handed over once");
                break (packs, job.fraction(), status);
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
    };
    let cache = LodCache::new(Some(dir.path().to_path_buf()));
    let gpu = crate::common::gpu().clone();
    let bake = |sources: Vec<LevelSource>, skip: Vec<bool>| {
        let method = Method::AnimationSpace;
        let chain = Default::default();
        BackgroundBake::start(
            gpu.clone(),
            sources,
            skip,
            method,
            chain,
            cache.clone(),
            &lodlab::measure::GpuMeasurer,
        )
    };
    let (packs, fraction, status) = wait(bake(sources.clone(), vec![false, false]));
    assert_eq!(fraction, 1.0);
    assert_eq!(
        status, "as levels of walker · billboard clouds of sapling",
        "the bar names what it bakes"
    );
    assert_eq!(packs.len(), 2);
    let Some(Ok(Levels::Pack(pack, _))) = &packs[0] else {
        panic!("the walker has no packed levels");
    };
    assert!(pack.levels.len() >= 4);
    let Some(Ok(Levels::Tree { chain, bakes })) = &packs[1] else {
        panic!("the sapling has no billboard-cloud chain");
    };
    assert!(chain.len() >= 4, "{} levels", chain.len());
    assert_eq!(
        bakes.len(),
        chain.len() - 1,
        "levels 1… are baked for the GPU"
    );
    assert!(chain.last().unwrap().cloud.drawn_billboards() <= 10);
    let mut files: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    // The tree's chain, and which of its levels each size draws (the default orders them by
    // error per cost).
    assert_eq!(
        files.len(),
        3,
        "one cache file per (model, method), two per tree: {files:?}"
    );
    assert!(
        files[0].starts_with("sapling-clouds-")
            && files[1].starts_with("sapling-order-")
            && files[2].starts_with("walker-as-"),
        "{files:?}"
    );
    let (again, _, _) = wait(bake(sources.clone(), vec![false, false]));
    let Some(Ok(Levels::Pack(again_pack, _))) = &again[0] else {
        panic!("the walker has no packed levels the second time");
    };
    assert_eq!(again_pack, pack);
    let Some(Ok(Levels::Tree { chain: again, .. })) = &again[1] else {
        panic!("the sapling has no chain the second time");
    };
    assert_eq!(again.len(), chain.len());
    for (a, b) in again.iter().zip(chain) {
        assert_eq!(
            (a.epsilon, a.cloud.billboards),
            (b.epsilon, b.cloud.billboards)
        );
        assert!(a.cloud.model == b.cloud.model, "a cached level differs");
    }
    // A model that has what it needs already is left alone.
    let (skipped, _, _) = wait(bake(sources, vec![true, true]));
    assert!(skipped.iter().all(Option::is_none));
}

/// Packed levels: every level's indices stay inside it, and every geomorph target is a vertex
/// of the next level.
#[test]
fn packed_levels_address_their_own_vertices() {
    let model = load_model("horse").unwrap();
    let lods = bake_lods(
        &model,
        Method::RestPose,
        &runtime_options(&model, None),
        &|_| {},
    );
    let pack = LodPack::from_levels(&lods.levels).unwrap();
    assert_eq!(pack.levels.len(), lods.levels.len());
    for (k, l) in pack.levels.iter().enumerate() {
        let range = l.first_index as usize..(l.first_index + l.index_count) as usize;
        assert!(pack.indices[range].iter().all(|&i| i < l.vertices));
        assert_eq!(l.triangles() as usize, lods.levels[k].triangles());
        let next = pack.levels.get(k + 1).unwrap_or(l);
        for v in 0..l.vertices {
            let texel = pack
                .vertices
                .grid
                .get((2 * (l.base_vertex + v) + 1) as usize);
            let target = texel[0] as u32;
            assert!(
                (next.base_vertex..next.base_vertex + next.vertices).contains(&target),
                "level {k} vertex {v} morphs to {target}"
            );
        }
    }
    // Errors never fall from level to level.
    assert!(pack.errors().windows(2).all(|w| w[0] <= w[1]));
}

/// A viewer waits for levels before its first frame only when they are all in the cache (a
/// read, not a bake): `levels_cached` says so once a first world has baked them, and not
/// before, nor for a method never baked.
#[test]
fn levels_count_as_cached_once_baked() {
    use lodlab::render::targets::OFFSCREEN_FORMAT;
    use lodlab::runtime::spec::{Loaded, SceneSpec};
    use lodlab::runtime::world::World;
    use lodlab::scene::LodMethod;
    let dir = tempfile::tempdir().unwrap();
    let gpu = crate::common::gpu().clone();
    let world = |method| {
        let spec = SceneSpec {
            models: vec!["walker".into(), "sapling".into()],
            count: 2,
            cache_dir: Some(dir.path().to_path_buf()),
            ..Default::default()
        };
        let mut w = World::new(&gpu, Loaded::new(spec).unwrap(), OFFSCREEN_FORMAT, 1).unwrap();
        w.lod.method = method;
        w
    };
    let mut first = world(LodMethod::AS_IS);
    assert!(!first.levels_cached(), "an empty cache holds nothing");
    first
        .ensure_levels(&gpu, &lodlab::measure::GpuMeasurer)
        .unwrap();
    assert!(world(LodMethod::AS_IS).levels_cached());
    assert!(
        world(LodMethod::None).levels_cached(),
        "full detail needs no level"
    );
    assert!(
        !world(LodMethod::Simplified(Method::RestPose)).levels_cached(),
        "rest-pose levels were never baked"
    );
}

/// Picking and inspecting, as the viewer's click and its Selection section do: the ray
/// through the centre of a view looking at an instance picks it (and a ray into the sky picks
/// nothing); its levels are bands of screen height, finest first and widest on screen, fewer
/// triangles each, and the level it draws is the one whose band holds its height on screen.
#[test]
fn a_click_picks_the_instance_under_it_and_its_levels_read_as_bands() {
    use lodlab::runtime::headless::{Headless, ShotLod};
    use lodlab::runtime::spec::SceneSpec;
    use lodlab::scene::{LodMethod, Transition};
    let spec = SceneSpec {
        scene: lodlab::scene::SceneKind::Crowd,
        models: vec!["walker".into()],
        count: 12,
        cache_dir: Some(crate::common::shared_cache()),
        ..Default::default()
    };
    let (w, h) = (320u32, 240u32);
    let mut scene = Headless::new(&spec, w, h, Some(1), &lodlab::measure::GpuMeasurer).unwrap();
    scene
        .show(&ShotLod {
            method: LodMethod::AS_IS,
            policy: LodPolicy {
                transition: Transition::Pop,
                hysteresis: 0.0,
                ..Default::default()
            },
            ..Default::default()
        })
        .unwrap();
    let world = &mut scene.world;
    world.select(h, 1.0, 1.0 / 60.0);
    let aspect = w as f32 / h as f32;
    for target in [0usize, 5, 11] {
        let (centre, radius) = world.instance_sphere(target).unwrap();
        world.camera.target = centre;
        world.camera.distance = radius * 6.0;
        world.select(h, 1.0, 1.0 / 60.0);
        assert_eq!(world.pick(glam::Vec2::ZERO, aspect), Some(target));
        // The top corner of the view looks over everyone's heads.
        world.camera.pitch = 0.0;
        assert_eq!(world.pick(glam::Vec2::new(-0.99, 0.99), aspect), None);
        world.camera.pitch = 0.3;
        world.select(h, 1.0, 1.0 / 60.0);
        let p = world.inspect(target, h).unwrap();
        assert_eq!((p.instance, p.name.as_str()), (target, "walker"));
        assert!(p.bands.len() >= 4, "{:?}", p.bands);
        assert!(p.bands[0].from_px.is_infinite());
        for pair in p.bands.windows(2) {
            assert!(pair[1].from_px < pair[0].from_px, "{:?}", p.bands);
            if let (Some(a), Some(b)) = (pair[0].triangles, pair[1].triangles) {
                assert!(b < a, "{:?}", p.bands);
            }
        }
        let LodDraw::Level(k) = p.draw else {
            panic!("a pop transition draws one level: {:?}", p.draw);
        };
        let band = &p.bands[k as usize];
        let below = p.bands.get(k as usize + 1).map_or(0.0, |b| b.from_px);
        // The shown level's band holds the instance's height (its nearest point decides, so
        // allow a little).
        assert!(
            p.height_px <= band.from_px * 1.1 && p.height_px >= below * 0.9,
            "level {k} at {} px: {:?}",
            p.height_px,
            p.bands
        );
        assert!(p.error_px <= 1.5 * 1.1, "{}", p.error_px);
    }
}

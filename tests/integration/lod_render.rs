//! Levels of detail on the GPU (lavapipe in CI): transition endpoints on pixels, batching, and
//! headless shots of every method, transition, debug view and comparison.

use lodlab::app::commands::shot::{ShotOptions, ShotReport, run as shot};
use lodlab::render::targets::{OFFSCREEN_FORMAT, Offscreen};
use lodlab::render::{DebugView, FrameView, Region, Side};
use lodlab::runtime::headless::ShotLod;
use lodlab::runtime::spec::{Loaded, SceneSpec};
use lodlab::runtime::world::World;
use lodlab::scene::{Drive, Instance, LodDraw, LodMethod, LodPolicy, Transition};
use std::collections::HashSet;
use std::path::PathBuf;

/// One cache for the whole file, so each (model, method) is baked once.
fn cache() -> PathBuf {
    crate::common::shared_cache()
}

fn spec(models: &[&str], count: usize) -> SceneSpec {
    SceneSpec {
        models: models.iter().map(|s| s.to_string()).collect(),
        count,
        cache_dir: Some(cache()),
        ..Default::default()
    }
}

fn max_diff(a: &image::RgbaImage, b: &image::RgbaImage) -> u8 {
    a.pixels()
        .zip(b.pixels())
        .flat_map(|(p, q)| (0..4).map(move |c| p[c].abs_diff(q[c])))
        .max()
        .unwrap_or(0)
}

/// Pixels where any channel differs by more than `by`.
fn differing(a: &image::RgbaImage, b: &image::RgbaImage, by: u8) -> usize {
    a.pixels()
        .zip(b.pixels())
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > by))
        .count()
}

#[test]
fn transitions_render_exactly_their_levels_at_t_0_and_t_1() {
    let gpu = crate::common::gpu().clone();
    let samples = 4;
    let mut world = World::new(
        &gpu,
        Loaded::new(spec(&["horse"], 1)).unwrap(),
        OFFSCREEN_FORMAT,
        samples,
    )
    .unwrap();
    let method = LodMethod::AS_IS;
    world.lod.method = method;
    world
        .ensure_levels(&gpu, &lodlab::measure::GpuMeasurer)
        .unwrap();
    let (w, h) = (240u32, 240u32);
    let target = Offscreen::new(&gpu, w, h, samples);
    let mut instances: Vec<Instance> = Vec::new();
    world.crowd.instances_at(0.7, &mut instances);
    let view = FrameView::from_camera(&world.camera, 1.0, 0.7);
    let set = world.renderer.characters()[0].set(method.index()).unwrap();
    let levels = set.levels.len();
    // Level pairs far enough apart to tell by eye: the first where the next level has a
    // quarter fewer triangles, and two coarser ones.
    let triangles: Vec<u32> = set.levels.iter().map(|l| l.triangles()).collect();
    assert!(levels >= 5, "{levels} levels");
    let mut render = |d: LodDraw| {
        world.renderer.prepare(
            &gpu,
            &view,
            &[Side {
                method: method.index(),
                instances: &instances,
                draws: &[d],
                region: Region::Full,
            }],
        );
        world
            .renderer
            .render_to(&gpu, &target.targets, &target.view)
            .expect("rendered");
        target.read_rgba(&gpu).unwrap()
    };
    let first = (1..levels - 2)
        .find(|&k| triangles[k + 1] * 4 <= triangles[k] * 3)
        .expect("levels a quarter apart") as u8;
    for k in [first, (levels as u8) / 2, levels as u8 - 3] {
        let fine = render(LodDraw::Level(k));
        let coarse = render(LodDraw::Level(k + 1));
        let coarser = render(LodDraw::Level(k + 2));
        // The levels differ where the test can see it.
        assert!(
            differing(&fine, &coarse, 8) > 20,
            "levels {k} and {} look alike",
            k + 1
        );
        let morph = |t| LodDraw::Morph {
            fine: k,
            coarse: k + 1,
            t,
        };
        let alpha = |p| LodDraw::Alpha {
            from: k,
            to: k + 1,
            p,
        };
        let dither = |p| LodDraw::Dither {
            from: k,
            to: k + 1,
            p,
        };
        for (what, image, expected) in [
            ("morph t = 0", render(morph(0.0)), &fine),
            ("morph t = 1", render(morph(1.0)), &coarse),
            ("alpha p = 0", render(alpha(0.0)), &fine),
            ("alpha p = 1", render(alpha(1.0)), &coarse),
            ("dither p = 0", render(dither(0.0)), &fine),
            ("dither p = 1", render(dither(1.0)), &coarse),
            (
                "morph over two levels, t = 1",
                render(LodDraw::Morph {
                    fine: k,
                    coarse: k + 2,
                    t: 1.0,
                }),
                &coarser,
            ),
        ] {
            let d = max_diff(&image, expected);
            assert!(d <= 1, "level {k}, {what}: differs by {d} from the level");
        }
        // A dithered cross-fade shows every pixel from exactly one of the two levels, and
        // more of the incoming one as p grows.
        let mut shares = Vec::new();
        for p in [0.25f32, 0.5, 0.75] {
            let image = render(dither(p));
            let (mut from_coarse, mut told) = (0usize, 0usize);
            for ((d, a), b) in image.pixels().zip(fine.pixels()).zip(coarse.pixels()) {
                let near = |x: &image::Rgba<u8>| (0..3).all(|c| d[c].abs_diff(x[c]) <= 1);
                assert!(
                    near(a) || near(b),
                    "level {k}, dither p = {p}: a pixel of neither level"
                );
                if !near(a) {
                    from_coarse += 1;
                }
                if (0..3).any(|c| a[c].abs_diff(b[c]) > 1) {
                    told += 1;
                }
            }
            shares.push(from_coarse as f32 / told.max(1) as f32);
        }
        assert!(
            shares[0] < shares[1] && shares[1] < shares[2],
            "level {k}: the incoming level's share does not grow with p: {shares:?}"
        );
        // Half-way is neither level.
        for (what, image) in [
            ("morph", render(morph(0.5))),
            ("alpha", render(alpha(0.5))),
            ("dither", render(dither(0.5))),
        ] {
            assert!(
                differing(&image, &fine, 2) > 0 && differing(&image, &coarse, 2) > 0,
                "level {k}: {what} half-way shows one of the levels"
            );
        }
    }
}

#[test]
fn a_thousand_instances_take_a_handful_of_draws() {
    let gpu = crate::common::gpu().clone();
    let mut world = World::new(
        &gpu,
        Loaded::new(spec(&["horse", "walker"], 1000)).unwrap(),
        OFFSCREEN_FORMAT,
        1,
    )
    .unwrap();
    world.lod.method = LodMethod::AS_IS;
    world
        .ensure_levels(&gpu, &lodlab::measure::GpuMeasurer)
        .unwrap();
    // From high above, with the whole crowd in view (nothing culled).
    world.camera =
        lodlab::scene::Camera::new(glam::Vec3::ZERO, 20.0, 55.0, world.crowd.radius * 2.6);
    // A tight tolerance, so that the crowd still spans several levels from up there.
    world.lod.policy.tolerance_px = 0.25;
    world.settle(720, 2.0, 1.0);
    let stats = world.upload(&gpu, 16.0 / 9.0, 2.0);
    assert_eq!(stats.instances, 1000);
    assert_eq!(stats.levels.iter().sum::<u32>(), 1000);
    // One draw per (model, level, transition state) in use.
    let mut groups = HashSet::new();
    let mut instances = Vec::new();
    world.crowd.instances_at(2.0, &mut instances);
    for (inst, d) in instances.iter().zip(world.lod.draws(0)) {
        match *d {
            LodDraw::Level(k) => groups.insert((inst.model, 0, k, 0)),
            LodDraw::Morph { fine, coarse, .. } => groups.insert((inst.model, 1, fine, coarse)),
            LodDraw::Alpha { .. } | LodDraw::Dither { .. } | LodDraw::Dissolve { .. } => {
                unreachable!("the default transition is a morph, and there are no trees")
            }
        };
    }
    assert_eq!(stats.draw_calls as usize, groups.len());
    assert!(
        stats.draw_calls <= 40,
        "{} draws for 1000 instances",
        stats.draw_calls
    );
    // More than one level is in use: the crowd spans distances.
    assert!(stats.levels.iter().filter(|&&n| n > 0).count() >= 2);
    // Full detail is one draw per model.
    world.lod.method = LodMethod::None;
    world.lod.reset();
    let stats = world.prepare(&gpu, [1280, 720], 2.0, 0.0);
    assert_eq!(stats.draw_calls, 2);
}

struct Shot {
    report: ShotReport,
    image: image::RgbaImage,
}

fn take(name: &str, lod: ShotLod) -> Shot {
    take_at(name, lod, 2.0)
}

fn take_at(name: &str, lod: ShotLod, time: f32) -> Shot {
    let dir = cache().join("shots");
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join(format!("{name}.png"));
    let report = shot(&ShotOptions {
        spec: spec(&["horse", "walker"], 120),
        out: out.clone(),
        width: 480,
        height: 270,
        time,
        samples: Some(1),
        camera: None,
        timed_frames: 1,
        calibrate: false,
        backdrop: Default::default(),
        lod,
    })
    .unwrap();
    let image = image::open(&out).unwrap().to_rgba8();
    Shot { report, image }
}

fn with(method: LodMethod, transition: Transition, drive: Drive) -> ShotLod {
    ShotLod {
        method,
        policy: LodPolicy {
            transition,
            drive,
            ..Default::default()
        },
        ..Default::default()
    }
}

#[test]
fn shots_of_every_method_and_transition_differ_where_they_should() {
    let pop = |m| {
        take(
            m,
            with(
                lodlab::choice::parse::<LodMethod>(m, "a method").unwrap(),
                Transition::Pop,
                Drive::Time,
            ),
        )
    };
    let none = pop("none");
    let rest = pop("rest-pose");
    let as_ = pop("as");
    let as_is = pop("as+is");
    assert_eq!(none.report.levels, vec![none.report.instances as u32]);
    for s in [&rest, &as_, &as_is] {
        assert!(s.report.triangles * 5 < none.report.triangles);
        assert_eq!(s.report.in_transition, 0);
        assert!(differing(&s.image, &none.image, 8) > 0);
    }
    assert!(differing(&rest.image, &as_.image, 8) > 0);
    assert!(differing(&as_.image, &as_is.image, 8) > 0);

    // A moment when some characters are between levels (the crowd walks, so levels change).
    let method = LodMethod::AS_IS;
    let (time, morph) = [2.0f32, 2.25, 2.5, 2.75, 3.0, 3.5]
        .into_iter()
        .map(|t| {
            (
                t,
                take_at("morph", with(method, Transition::Morph, Drive::Time), t),
            )
        })
        .find(|(_, s)| s.report.in_transition > 0)
        .expect("a moment with a transition");
    let as_is = take_at(
        "as+is-then",
        with(method, Transition::Pop, Drive::Time),
        time,
    );
    let alpha = take_at("alpha", with(method, Transition::Alpha, Drive::Time), time);
    let zones = take_at("zones", with(method, Transition::Morph, Drive::Zone), time);
    let pixels = (480 * 270) as usize;
    for s in [&morph, &alpha, &zones] {
        assert!(s.report.in_transition > 0, "{}", s.report.transition);
        // Only the instances in transition look different from popping.
        let d = differing(&s.image, &as_is.image, 8);
        assert!(d > 0 && d < pixels / 10, "{d} pixels differ");
    }
    assert!(differing(&morph.image, &alpha.image, 8) > 0);
}

#[test]
fn compare_shows_two_methods_from_one_camera_and_time() {
    let none = take(
        "cmp-none",
        with(LodMethod::None, Transition::Pop, Drive::Time),
    );
    let coarse = take(
        "cmp-as-is",
        with(LodMethod::AS_IS, Transition::Pop, Drive::Time),
    );
    let both = take(
        "cmp-both",
        ShotLod {
            compare: Some(LodMethod::AS_IS),
            ..with(LodMethod::None, Transition::Pop, Drive::Time)
        },
    );
    assert_eq!(both.report.compare.as_deref(), Some("as+is"));
    let (w, h) = both.image.dimensions();
    let half = |img: &image::RgbaImage, x0: u32, x1: u32| {
        image::imageops::crop_imm(img, x0, 0, x1 - x0, h).to_image()
    };
    // Left of the divider is exactly the full-detail shot, right of it the as+is one.
    let l = w / 2 - 2;
    let r = w / 2 + 2;
    assert_eq!(
        max_diff(&half(&both.image, 0, l), &half(&none.image, 0, l)),
        0
    );
    assert_eq!(
        max_diff(&half(&both.image, r, w), &half(&coarse.image, r, w)),
        0
    );
    assert!(differing(&none.image, &coarse.image, 8) > 0);
}

#[test]
fn debug_views_colour_what_they_say() {
    let method = LodMethod::AS_IS;
    let shaded = take("shaded", with(method, Transition::Morph, Drive::Time));
    for view in [
        DebugView::LodTint,
        DebugView::TransitionTint,
        DebugView::Influences,
    ] {
        let s = take(
            view.name(),
            ShotLod {
                debug: view,
                ..with(method, Transition::Morph, Drive::Time)
            },
        );
        assert_eq!(s.report.debug_view, view.name());
        assert!(
            differing(&s.image, &shaded.image, 16) > 200,
            "{}",
            view.name()
        );
    }
}

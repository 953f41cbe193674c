//! Root motion (issue "real assets, third round"): a creature whose clip flies it about keeps
//! its own size. Its bounds are its body's, and its sphere (culling, the size on screen that
//! picks its level), its blob shadow and picking follow where the clip has carried it.

use lodlab::bake::gpu_data::drawable::Drawable;
use lodlab::generate::wild::flight::{flight_offset, flying};
use lodlab::import::load_model;

/// Round a circle 3 m in radius, 2 m up at the far side.
const RADIUS: f32 = 3.0;
const CLIMB: f32 = 2.0;

#[test]
fn a_flying_clip_moves_the_bounds_with_the_body() {
    let dir = tempfile::tempdir().unwrap();
    let robot = load_model("robot").unwrap();
    let path = dir.path().join("flyer.glb");
    std::fs::write(
        &path,
        lodlab::generate::glb::to_glb(&flying(&robot, RADIUS, CLIMB)),
    )
    .unwrap();
    let flyer = load_model(path.to_str().unwrap()).unwrap();
    let plain = Drawable::new(&robot).unwrap();
    let full = Drawable::new(&flyer).unwrap();

    // Its bounds are the body's: the robot's size, not the flight's (6 m across, 2 m up).
    assert!(plain.travel.is_empty(), "the robot walks in place");
    assert!(!full.travel.is_empty());
    let (body, own) = (full.bounds.diagonal(), plain.bounds.diagonal());
    assert!(body < 1.1 * own, "{body} m against the robot's {own} m");

    // At every moment the posed body (as the shader poses it) lies in its bounds moved by its
    // travel, which follows the flight.
    let duration = flyer.clips[0].duration;
    for k in 0..40 {
        let t = duration * k as f32 / 40.0;
        let travel = full.travel_at(0, t);
        let (min, max) = (full.bounds.min + travel, full.bounds.max + travel);
        let margin = 0.03 * body;
        let (posed, _) = full.evaluate(0, t, 1.0);
        for p in posed {
            assert!(
                p.cmpge(min - margin).all() && p.cmple(max + margin).all(),
                "at {t} s, {p} lies outside {min}..{max}"
            );
        }
        let expect = flight_offset(RADIUS, CLIMB, duration, t);
        assert!(
            (travel - expect).length() < 0.25,
            "at {t} s it travelled {travel}, the flight {expect}"
        );
    }

    // In a scene: the one creature's sphere is where its body is, as small as its body.
    use lodlab::runtime::headless::Headless;
    use lodlab::runtime::spec::SceneSpec;
    let spec = SceneSpec {
        scene: lodlab::scene::SceneKind::Study,
        models: vec![path.to_str().unwrap().into()],
        count: 1,
        cache_dir: Some(dir.path().join("cache")),
        ..Default::default()
    };
    let mut scene = Headless::new(&spec, 160, 120, Some(1), &lodlab::measure::GpuMeasurer).unwrap();
    for time in [0.0, 0.3 * duration, 0.5 * duration] {
        scene.world.select(120, time, 1.0 / 60.0);
        let agent = &scene.world.crowd.agents[0];
        let inst = agent.instance_at(time);
        let anim_time = time * inst.speed + inst.time_offset;
        let (centre, radius) = scene.world.instance_sphere(0).unwrap();
        let (posed, _) = full.evaluate(0, anim_time, 1.0);
        let at = inst.transform;
        for p in posed {
            let d = at.transform_point3(p).distance(centre);
            assert!(
                d <= radius * 1.05,
                "at {time} s a vertex is {d} m from {centre}"
            );
        }
        assert!(radius < 0.6 * own, "{radius}");
    }
}

/// Its impostor's pages draw the body where it stands and the quad is moved by the travel
/// (kept per page): the views' sphere is the body's, so its error bound is a fraction of
/// what pages of the whole flight give.
#[test]
fn a_flying_creatures_impostor_is_drawn_round_its_body() {
    use lodlab::bake::impostor::animated::{ImpostorOptions, bake_animated_impostor, no_travel};
    let flyer = flying(&load_model("robot").unwrap(), RADIUS, CLIMB);
    let full = Drawable::new(&flyer).unwrap();
    let travel = |c: usize, t: f32| full.travel_within(c, t);
    let options: ImpostorOptions = "8x6x24".parse().unwrap();
    let raster = lodlab::render::atlas::AtlasRasterizer::new(crate::common::gpu());
    let body = bake_animated_impostor(&raster, &flyer, &travel, options).unwrap();
    let flight = bake_animated_impostor(&raster, &flyer, &no_travel, options).unwrap();
    assert!(flight.frame.travel.is_empty());
    assert_eq!(body.frame.travel.len(), body.frames as usize);
    // Each page's travel is the flight's at that page (6 frames a clip, the ends included).
    let duration = flyer.clips[0].duration;
    for (k, t) in body.frame.travel.iter().enumerate() {
        let at = duration * k as f32 / (body.frames - 1).max(1) as f32;
        let expect = flight_offset(RADIUS, CLIMB, duration, at);
        assert!(
            (glam::Vec3::from(*t) - expect).length() < 0.25,
            "page {k}: {t:?} against {expect}"
        );
    }
    let (r_body, r_flight) = (body.frame.radius, flight.frame.radius);
    assert!(r_body < 0.5 * r_flight, "{r_body} m against {r_flight} m");
    let (e_body, e_flight) = (body.error.total(), flight.error.total());
    assert!(e_body < 0.5 * e_flight, "{e_body} m against {e_flight} m");
}

//! Forest patches (`bake::foliage::patch`): a layout's cells baked into impostor cards from
//! their trees' impostors, placed by the error rule, cached, and drawn in place of far trees.

use lodlab::app::commands::shot::{ShotOptions, ShotReport, run};
use lodlab::runtime::headless::{Headless, ShotLod};
use lodlab::runtime::spec::SceneSpec;
use lodlab::scene::LodMethod;
use lodlab::scene::foliage::FoliageView;

fn spec(count: usize) -> SceneSpec {
    SceneSpec {
        scene: lodlab::scene::SceneKind::Forest,
        count,
        cache_dir: Some(crate::common::shared_cache()),
        ..Default::default()
    }
}

fn lod(patches: bool) -> ShotLod {
    ShotLod {
        method: LodMethod::Simplified(
            lodlab::bake::character::simplify::Method::InfluenceSimplification,
        ),
        foliage: FoliageView {
            patches,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// A shot of a forest of `count` trees from `distance` metres, 30° round and 4° above.
fn far_shot(out: &std::path::Path, count: usize, patches: bool, distance: f32) -> ShotReport {
    run(&ShotOptions {
        spec: spec(count),
        out: out.to_path_buf(),
        width: 320,
        height: 240,
        time: 1.0,
        samples: Some(1),
        camera: Some(lodlab::scene::Camera::new(
            glam::Vec3::new(0.0, 1.0, 0.0),
            30.0,
            4.0,
            distance,
        )),
        timed_frames: 1,
        calibrate: false,
        backdrop: Default::default(),
        lod: lod(patches),
    })
    .unwrap()
}

/// The patches of a small forest keep the rule: where they come in, the sample cell's patch
/// measures no worse against its full trees than the trees' own impostors against theirs,
/// and at every larger size it tried it measured worse (or it would have come in there).
#[test]
fn patches_come_in_where_they_are_no_worse_than_the_trees_impostors() {
    let mut h = Headless::new(&spec(12), 160, 120, Some(1), &lodlab::measure::GpuMeasurer).unwrap();
    h.show(&lod(true)).unwrap();
    let baked = h.world.patches().expect("patches baked for the layout");
    assert!(!baked.patches.is_empty());
    let members: usize = baked.patches.iter().map(|p| p.members.len()).sum();
    assert!((2..=12).contains(&members), "{members} trees in patches");
    let (_, measured) = &baked.measured[0];
    assert!(!measured.is_empty());
    for m in measured {
        assert!(
            m.patch.is_finite() && m.trees.is_finite() && m.patch >= 0.0,
            "{m:?}"
        );
    }
    match baked.switch_px {
        Some(px) => {
            let last = measured.last().unwrap();
            assert_eq!(last.px, px);
            assert!(last.patch <= last.trees, "{last:?}");
            for m in &measured[..measured.len() - 1] {
                assert!(m.patch > m.trees, "it would have come in at {m:?}");
                assert!(m.px > px);
            }
        }
        None => assert!(measured.iter().all(|m| m.patch > m.trees), "{measured:?}"),
    }
    // Each patch is a card over its trees: its bounds hold every member's trunk.
    for p in &baked.patches {
        let frame = p.level.impostor.expect("a card");
        let [lo, hi] = frame.bounds;
        for &m in &p.members {
            let at = h.world.crowd.agents[m as usize]
                .instance_at(0.0)
                .transform
                .translation;
            let (x, z) = (at.x - p.origin[0], at.z - p.origin[2]);
            assert!(
                (lo[0]..=hi[0]).contains(&x) && (lo[2]..=hi[2]).contains(&z),
                "tree {m} at ({x}, {z}) lies outside its card's bounds {lo:?}..{hi:?}"
            );
        }
    }
}

/// Far off, the trees of each cell are drawn as one card, which looks like the trees it
/// stands for; near, the trees are drawn. Without `--forest-patches` no patch is drawn.
#[test]
fn far_forests_draw_patches_that_look_like_their_trees() {
    let dir = tempfile::tempdir().unwrap();
    // The 12-tree forest's cell measures no worse than its trees' impostors once they are
    // 19 px high (10 s of measuring on a fresh cache; see docs/trees.md, Forest patches).
    let mut h = Headless::new(&spec(12), 160, 120, Some(1), &lodlab::measure::GpuMeasurer).unwrap();
    h.show(&lod(true)).unwrap();
    let baked = h.world.patches().expect("patches baked");
    let px = baked
        .switch_px
        .expect("the 12-tree forest's patches come in at some size");
    let tree_height = baked.patches[0].tree_height;
    // From where the trees stand 0.7 of that high at 240 rows (within the hysteresis).
    let fov = lodlab::scene::Camera::new(glam::Vec3::ZERO, 0.0, 0.0, 1.0).fov_y;
    let far = tree_height * 240.0 / (2.0 * (fov * 0.5).tan() * 0.7 * px);
    let with = far_shot(&dir.path().join("with.png"), 12, true, far);
    assert_eq!(with.patch_switch_px, Some(px));
    let kinds = &with.level_kinds;
    assert!(
        kinds.get("forest patch").copied().unwrap_or(0) > 0,
        "{kinds:?} from {far} m"
    );
    let without = far_shot(&dir.path().join("without.png"), 12, false, far);
    assert_eq!(without.level_kinds.get("forest patch"), None);
    assert!(
        without
            .level_kinds
            .get("tree impostor")
            .copied()
            .unwrap_or(0)
            > 0
    );
    let empty = far_shot(&dir.path().join("empty.png"), 0, false, far);
    assert_eq!(empty.instances, 0);
    let open = |name: &str| image::open(dir.path().join(name)).unwrap().to_rgba8();
    let (a, b, e) = (open("with.png"), open("without.png"), open("empty.png"));
    let apart = |x: &image::RgbaImage, y: &image::RgbaImage, by: u8| {
        x.pixels()
            .zip(y.pixels())
            .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > by))
            .count()
    };
    // What the patches and the trees' impostors each cover of the empty view.
    let (patch_px, tree_px) = (apart(&a, &e, 4), apart(&b, &e, 4));
    eprintln!("far forest: patches cover {patch_px} px, the trees' impostors {tree_px} px");
    assert!(tree_px > 100, "the far trees are seen: {tree_px} px");
    assert!(
        patch_px as f64 > 0.6 * tree_px as f64 && (patch_px as f64) < 1.6 * tree_px as f64,
        "patches cover {patch_px} px, their trees {tree_px} px"
    );
    let differ = apart(&a, &b, 24);
    assert!(
        (differ as f64) < 0.5 * tree_px as f64,
        "{differ} pixels differ by more than 24/255 (the trees cover {tree_px})"
    );
    // Near, the trees are drawn.
    let near = far_shot(&dir.path().join("near.png"), 12, true, 60.0);
    assert_eq!(
        near.level_kinds.get("forest patch"),
        None,
        "{:?}",
        near.level_kinds
    );
}

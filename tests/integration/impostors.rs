//! Characters' animated impostors (lavapipe in CI): what the bake makes, that an impostor plays
//! its character's clip where the character stands, and that far characters of a crowd become
//! their impostors under selection, and stop when the panel turns them off.

use lodlab::bake::character::simplify::Method;
use lodlab::bake::gpu_data::drawable::Drawable;
use lodlab::bake::impostor::animated::{
    AnimatedImpostor, ImpostorOptions, bake_animated_impostor, no_travel, sheet_layout,
};
use lodlab::bake::impostor::placement::Placement;
use lodlab::import::load_model;
use lodlab::measure::impostor_fit::impostor_error;
use lodlab::render::Gpu;
use lodlab::render::atlas::AtlasRasterizer;
use lodlab::render::targets::{OFFSCREEN_FORMAT, Offscreen};
use lodlab::runtime::levels::{ImpostorLevel, Levels};
use lodlab::runtime::spec::{Loaded, SceneSpec};
use lodlab::runtime::world::World;
use lodlab::scene::{LodDraw, LodMethod};
use std::sync::OnceLock;

/// Small enough to bake in a few seconds on lavapipe: 8 × 8 views, 6 frames a clip, 24-texel
/// cells.
const OPTIONS: &str = "8x6x24";

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

/// The walker's impostor, baked once for the file.
fn walker_impostor() -> &'static AnimatedImpostor {
    static IMPOSTOR: OnceLock<AnimatedImpostor> = OnceLock::new();
    IMPOSTOR.get_or_init(|| {
        let walker = load_model("walker").unwrap();
        let options: ImpostorOptions = OPTIONS.parse().unwrap();
        bake_animated_impostor(&AtlasRasterizer::new(gpu()), &walker, &no_travel, options).unwrap()
    })
}

#[test]
fn the_bake_lays_every_frame_of_every_clip_in_two_sheets() {
    let _serial = serial();
    let walker = load_model("walker").unwrap();
    let imp = walker_impostor();
    let options = imp.options;
    // Six frames of each of the walker's clips, one page each.
    assert_eq!(imp.frames as usize, 6 * walker.clips.len());
    let side = options.views * options.cell;
    let (columns, rows) = sheet_layout(imp.frames, side).unwrap();
    assert_eq!((imp.frame.columns, imp.frame.rows), (columns, rows));
    assert_eq!(imp.model.materials.len(), 2, "a colour and a normal sheet");
    for m in &imp.model.materials {
        let t = m.texture.as_ref().unwrap();
        assert_eq!((t.width, t.height), (columns * side, rows * side));
    }
    // Every page shows the walker in every view: each cell of the colour sheet has covered
    // texels.
    let colour = imp.model.materials[0].texture.as_ref().unwrap();
    let cell = options.cell as usize;
    for page in 0..imp.frames as usize {
        let px = (page % columns as usize) * side as usize;
        let py = (page / columns as usize) * side as usize;
        for j in 0..options.views as usize {
            for i in 0..options.views as usize {
                let (x0, y0) = (px + i * cell, py + j * cell);
                let covered = (0..cell * cell)
                    .filter(|&t| {
                        let k = 4 * ((y0 + t / cell) * colour.width as usize + x0 + t % cell);
                        colour.pixels[k + 3] >= 128
                    })
                    .count();
                assert!(
                    covered > 10,
                    "page {page}, view ({i}, {j}): {covered} texels"
                );
            }
        }
    }
    // The frame's sphere holds every vertex of every pose.
    let bake = Drawable::new(&walker).unwrap();
    let centre = glam::Vec3::from(imp.frame.centre);
    for c in 0..bake.animation.clips.len() {
        for k in 0..4 {
            let t = bake.animation.clips[c].duration * k as f32 / 4.0;
            let (p, _) = bake.evaluate(c, t, 1.0);
            assert!(p.iter().all(|v| v.distance(centre) <= imp.frame.radius));
        }
    }
    // The bake bounds its worst error, part by part.
    let e = imp.error;
    assert!(e.view > 0.0 && e.frame > 0.0 && e.texel > 0.0);
    assert!(
        e.view_angle > 10.0 && e.view_angle < 25.0,
        "{}°",
        e.view_angle
    );
}

/// Drawn as small as a far character, the impostor shows the walker as it is drawn at full
/// detail at the same moment: its colour error against it is low, and several times what it
/// is a quarter of a stride later (so it plays the clip in step, not a frame of its own).
#[test]
fn an_impostor_plays_its_characters_clip_where_it_stands() {
    let _serial = serial();
    let walker = load_model("walker").unwrap();
    let full = Drawable::new(&walker).unwrap();
    let imp = walker_impostor();
    let stride = walker.clips[0].duration;
    let in_step = impostor_error(gpu(), &walker, &full, imp, 48.0, 0.0).unwrap();
    let late = impostor_error(gpu(), &walker, &full, imp, 48.0, 0.25 * stride).unwrap();
    eprintln!("colour error at 48 px: in step {in_step:.3}, a quarter of a stride late {late:.3}");
    assert!(in_step < 0.2, "colour error {in_step:.3} at 48 px");
    assert!(
        late > 1.3 * in_step,
        "in step {in_step:.3}, a quarter of a stride late {late:.3}"
    );
}

/// A crowd seen from far off: with the walker's impostor placed in its as+is chain, the far
/// walkers draw it (a quad, two triangles, in place of the coarsest mesh), the picture stays
/// close to the one of meshes, and turning impostors off brings the meshes back.
#[test]
fn far_characters_become_their_impostors() {
    let _serial = serial();
    let gpu = gpu();
    let spec = SceneSpec {
        models: vec!["walker".into()],
        count: 300,
        cache_dir: Some(crate::common::shared_cache()),
        ..Default::default()
    };
    let mut world = World::new(gpu, Loaded::new(spec).unwrap(), OFFSCREEN_FORMAT, 1).unwrap();
    world.lod.method = LodMethod::AS_IS;
    world
        .ensure_levels(gpu, &lodlab::measure::GpuMeasurer)
        .unwrap();
    assert!(world.impostors()[0].is_none(), "the spec asked for none");
    // Far enough that most walkers sit at the coarsest mesh.
    world.camera =
        lodlab::scene::Camera::new(glam::Vec3::ZERO, 20.0, 25.0, world.crowd.radius * 4.0);
    let (w, h) = (640, 360);
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
    let (meshes, mesh_image) = frame(&mut world);
    let coarsest = meshes.levels.iter().rposition(|&n| n > 0).unwrap();
    assert!(meshes.levels[coarsest] > 100, "{:?}", meshes.levels);

    // Placed at the coarsest level's error, the impostor takes its place.
    let slot = LodMethod::AS_IS.index();
    let errors = world.lod.errors(0, slot).unwrap().to_vec();
    assert_eq!(errors.len(), coarsest + 1);
    let level = ImpostorLevel {
        impostor: Box::new(walker_impostor().clone()),
        placement: Placement {
            epsilon: Some(errors[coarsest]),
            tolerance_px: lodlab::scene::LodPolicy::default().tolerance_px,
            measured: Vec::new(),
        },
    };
    let chain = world.lod.chain();
    world
        .install_levels(
            gpu,
            Method::InfluenceSimplification,
            &chain,
            [(0, Some(Ok(Levels::Impostor(Some(level)))))],
        )
        .unwrap();
    assert_eq!(world.lod.impostor_level(0, slot), Some(coarsest as u8));
    assert!(world.impostors()[0].is_some());
    let (impostors, impostor_image) = frame(&mut world);
    assert_eq!(impostors.levels[coarsest], meshes.levels[coarsest]);
    // Two triangles for each walker that was a coarsest mesh.
    let per_mesh = (meshes.triangles - impostors.triangles) / meshes.levels[coarsest] as u64;
    assert!(per_mesh > 50, "{per_mesh} triangles saved a walker");
    assert!(world.lod.draws(0).contains(&LodDraw::Level(coarsest as u8)));
    // The picture barely changes: the crowd's pixels agree.
    let changed = mesh_image
        .pixels()
        .zip(impostor_image.pixels())
        .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b[c]) > 24))
        .count();
    let share = changed as f32 / (w * h) as f32;
    assert!(share < 0.01, "{share:.4} of the picture changed");
    // Turned off, the meshes come back.
    world.show_impostors(false);
    let (off, _) = frame(&mut world);
    assert_eq!(off.triangles, meshes.triangles);
    assert!(world.impostor_summary().contains("hidden"));
}

#[test]
fn a_bad_impostor_option_is_one_line() {
    let _serial = serial();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args(["shot", "--impostors", "1x12x24", "--out", "never.png"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("views must be 2 to 16, not 1"), "{err}");
    assert!(!std::path::Path::new("never.png").exists());
}

/// In the viewer's background bake a character's impostor comes after its levels, in a
/// delivery of its own, and is placed in the method's chain; a second bake reads both from the
/// cache.
#[test]
fn the_background_bake_hands_over_levels_then_the_impostor() {
    let _serial = serial();
    use lodlab::bake::cache::LodCache;
    use lodlab::runtime::levels::{BackgroundBake, LevelSource, Poll};
    let dir = tempfile::tempdir().unwrap();
    let cache = LodCache::new(Some(dir.path().to_path_buf()));
    let source = LevelSource {
        model: load_model("walker").unwrap(),
        hash: lodlab::import::import("walker", &Default::default())
            .unwrap()
            .source_hash,
        impostor: Some(OPTIONS.parse().unwrap()),
        budgets: None,
    };
    let run = || {
        let mut job = BackgroundBake::start(
            gpu().clone(),
            vec![source.clone()],
            vec![false],
            Method::InfluenceSimplification,
            Default::default(),
            cache.clone(),
            &lodlab::measure::GpuMeasurer,
        );
        let mut kinds = Vec::new();
        let mut statuses = std::collections::BTreeSet::new();
        loop {
            statuses.insert(job.status());
            let (ready, over) = match job.poll() {
                Poll::Running(ready) => (ready, false),
                Poll::Done(ready) => (ready, true),
                Poll::Failed => panic!("the bake thread died"),
            };
            for (i, baked) in ready {
                assert_eq!(i, 0);
                kinds.push(match baked {
                    Some(Ok(Levels::Pack(pack, None))) => format!("levels {}", pack.levels.len()),
                    Some(Ok(Levels::Impostor(Some(level)))) => {
                        let placed = level.placement.epsilon.is_some();
                        assert!(!level.placement.measured.is_empty());
                        format!("impostor placed {placed}")
                    }
                    _ => "something else".to_string(),
                });
            }
            if over {
                break (kinds, statuses);
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
    };
    let (first, statuses) = run();
    // While the impostor bakes, the progress bar says so.
    assert!(statuses.contains("impostors of walker"), "{statuses:?}");
    assert_eq!(first.len(), 2, "{first:?}");
    assert!(first[0].starts_with("levels "), "{first:?}");
    assert!(first[1].starts_with("impostor placed"), "{first:?}");
    // From the cache: the same, impostor and placement read back.
    assert_eq!(run().0, first);
    let files: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(files.iter().any(|f| f.contains("-impostor-")), "{files:?}");
    assert!(files.iter().any(|f| f.contains("-placement-")), "{files:?}");
}

/// Every limb is inside every view: the rigged character bound in a T-pose, arms out level
/// (its widest pose), baked as the crowd bakes it. In every view of its rest-pose page the
/// covered texels span what the mesh spans seen from there (an arm cut off, or left out,
/// would leave the view narrower), and each view's quad holds what any page covers there.
#[test]
fn every_limb_of_a_t_pose_is_inside_every_view() {
    use lodlab::bake::impostor::octahedral::{ViewGrid, posed};
    let _serial = serial();
    let model = load_model("mocap").unwrap();
    let options = ImpostorOptions::default();
    let imp =
        bake_animated_impostor(&AtlasRasterizer::new(gpu()), &model, &no_travel, options).unwrap();
    let colour = imp.model.materials[0].texture.as_ref().unwrap();
    let (cell, views) = (options.cell as usize, options.views as usize);
    let side = views * cell;
    let columns = imp.frame.columns as usize;
    let rest = posed(&model, None, 0.0);
    let (centre, radius) = (glam::Vec3::from(imp.frame.centre), imp.frame.radius);
    let texels = cell as f32 / (2.0 * radius);
    let mut widest = 0.0f32;
    for page in 0..imp.frames as usize {
        let (px, py) = ((page % columns) * side, (page / columns) * side);
        for j in 0..views {
            for i in 0..views {
                let (x0, y0) = (px + i * cell, py + j * cell);
                let (mut lo, mut hi) = ([usize::MAX; 2], [0usize; 2]);
                for t in 0..cell * cell {
                    let (x, y) = (t % cell, t / cell);
                    let k = 4 * ((y0 + y) * colour.width as usize + x0 + x);
                    if colour.pixels[k + 3] >= 128 {
                        lo = [lo[0].min(x), lo[1].min(y)];
                        hi = [hi[0].max(x), hi[1].max(y)];
                    }
                }
                assert!(lo[0] <= hi[0], "page {page}, view ({i}, {j}) is empty");
                let r = imp.frame.rects[j * views + i];
                let inside = |v: usize, a: f32, b: f32| {
                    let s = (v as f32 + 0.5) / cell as f32;
                    s >= a - 0.5 / cell as f32 && s <= b + 0.5 / cell as f32
                };
                assert!(
                    inside(lo[0], r[0], r[2])
                        && inside(hi[0], r[0], r[2])
                        && inside(lo[1], r[1], r[3])
                        && inside(hi[1], r[1], r[3]),
                    "view ({i}, {j}): its quad {r:?} cuts what page {page} covers"
                );
                let covered = [(hi[0] - lo[0] + 1) as f32, (hi[1] - lo[1] + 1) as f32];
                if page > 0 {
                    continue;
                }
                // The rest pose seen from this view, in the cell's texels.
                let d = ViewGrid {
                    frames: options.views,
                    cell: options.cell,
                }
                .direction(i as u32, j as u32);
                let (right, up) = ViewGrid::view_axes(d);
                let span = |axis: glam::Vec3| {
                    let (a, b) =
                        rest.mesh
                            .positions
                            .iter()
                            .fold((f32::MAX, f32::MIN), |(a, b), p| {
                                let x = (*p - centre).dot(axis);
                                (a.min(x), b.max(x))
                            });
                    (b - a) * texels
                };
                let spans = [span(right), span(up)];
                for k in 0..2 {
                    assert!(
                        (covered[k] - spans[k]).abs() <= 2.0,
                        "view ({i}, {j}): {:.1} texels covered {} where the mesh spans {:.1}",
                        covered[k],
                        ["across", "up"][k],
                        spans[k]
                    );
                }
                widest = widest.max(covered[0] / covered[1]);
            }
        }
    }
    assert!(
        widest > 0.85,
        "the widest view is {widest:.2} as wide as high"
    );
}

/// A character with more clips than its sheet holds frames for at the frames asked (asset-store
/// characters ship 10–30) still gets an impostor: the sheet's pages shared among its clips by
/// duration, the frame error measured over the wider gaps.
#[test]
fn a_character_of_many_clips_shares_its_sheet() {
    use lodlab::bake::impostor::animated::clip_frames;
    let _serial = serial();
    let mut walker = load_model("walker").unwrap();
    let first = walker.clips[0].clone();
    walker.clips = (0..7)
        .map(|k| lodlab::model::Clip {
            name: format!("clip{k}"),
            duration: first.duration * (1.0 + 0.5 * k as f32),
            ..first.clone()
        })
        .collect();
    // 8 views of 64 texels: pages of 512², 16 to a 2048² sheet, for 7 clips of 12 frames.
    let options: ImpostorOptions = "8x12x64".parse().unwrap();
    let counts = clip_frames(&walker, &options).unwrap();
    let pages: u32 = counts.iter().sum();
    assert!(pages <= 16 && counts.iter().all(|&c| c >= 2), "{counts:?}");
    let imp =
        bake_animated_impostor(&AtlasRasterizer::new(gpu()), &walker, &no_travel, options).unwrap();
    // It may trade texels for frames: a smaller cell, more pages, more frames a clip.
    assert!(imp.options.cell <= 64 && (imp.options.views, imp.options.frames) == (8, 12));
    let counts = clip_frames(&walker, &imp.options).unwrap();
    assert_eq!(imp.frames, counts.iter().sum::<u32>());
    assert!(imp.frames >= pages, "{} frames", imp.frames);
    let drawable = imp.bake(&Drawable::new(&walker).unwrap()).unwrap();
    let frames: Vec<u32> = drawable
        .animation
        .clips
        .iter()
        .map(|c| c.frame_count)
        .collect();
    assert_eq!(frames, counts, "pages and the impostor's animation agree");
    let e = imp.error;
    assert!(e.frame > 0.0 && e.total().is_finite(), "{e:?}");
}

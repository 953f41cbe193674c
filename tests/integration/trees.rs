//! The demo trees are cyclically animated skeletal tree models (Aalborg thesis §1.4): a closed
//! skinned wood mesh, foliage quads bound to one bone each, four generations of branches, and a
//! seamless wind loop that is faster and wider at the twigs than at the trunk.

use glam::Vec3;
use lodlab::anim::local_pose;
use lodlab::generate::tree::{FOLIAGE_MATERIAL, broadleaf, conifer};
use lodlab::model::Model;
use std::collections::HashMap;

fn trees() -> Vec<Model> {
    vec![broadleaf(), conifer()]
}

#[test]
fn sizes_are_those_of_the_issue() {
    for m in trees() {
        let bones = m.skeleton.bone_count();
        assert!((50..=200).contains(&bones), "{}: {bones} bones", m.name);
        let leaf_vertices = m
            .mesh
            .materials
            .iter()
            .filter(|&&x| x == FOLIAGE_MATERIAL)
            .count();
        let leaves = leaf_vertices / 4;
        assert!(
            (2_000..=20_000).contains(&leaves),
            "{}: {leaves} leaves",
            m.name
        );
        assert_eq!(m.clips.len(), 1);
        let d = m.clips[0].duration;
        assert!((4.0..=8.0).contains(&d), "{}: loop of {d} s", m.name);
        assert_eq!(m.materials.len(), 2);
        // The foliage texture cuts leaves out with its alpha.
        let tex = m.materials[FOLIAGE_MATERIAL as usize]
            .texture
            .as_ref()
            .unwrap();
        let alphas: Vec<u8> = tex.pixels.chunks_exact(4).map(|p| p[3]).collect();
        assert!(alphas.contains(&0) && alphas.contains(&255));
    }
}

#[test]
fn every_leaf_hangs_from_one_bone_with_weight_one() {
    for m in trees() {
        let mesh = &m.mesh;
        let mut leaf_triangles = 0;
        for t in mesh.indices.chunks_exact(3) {
            if mesh.materials[t[0] as usize] != FOLIAGE_MATERIAL {
                continue;
            }
            leaf_triangles += 1;
            let bones: Vec<u32> = t
                .iter()
                .map(|&v| {
                    let inf = mesh.influences_of(v as usize);
                    assert_eq!(
                        inf.len(),
                        1,
                        "{}: leaf vertex {v} has {} bones",
                        m.name,
                        inf.len()
                    );
                    assert_eq!(inf[0].weight, 1.0);
                    inf[0].bone
                })
                .collect();
            assert!(
                bones.iter().all(|&b| b == bones[0]),
                "{}: a leaf spans bones",
                m.name
            );
        }
        assert!(leaf_triangles > 0);
    }
}

#[test]
fn the_wood_is_closed_and_blends_bones_at_joints() {
    for m in trees() {
        let mesh = &m.mesh;
        // Weld by position: tube seams and cap rims repeat positions.
        let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
        let id: Vec<u32> = mesh
            .positions
            .iter()
            .map(|p| {
                let key = p.to_array().map(f32::to_bits);
                let n = ids.len() as u32;
                *ids.entry(key).or_insert(n)
            })
            .collect();
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        let mut wood = 0;
        for t in mesh.indices.chunks_exact(3) {
            if mesh.materials[t[0] as usize] == FOLIAGE_MATERIAL {
                continue;
            }
            wood += 1;
            for k in 0..3 {
                let (a, b) = (id[t[k] as usize], id[t[(k + 1) % 3] as usize]);
                if a != b {
                    // Directed: a closed, consistently wound surface uses each edge once each way.
                    *edges.entry((a, b)).or_default() += 1;
                    *edges.entry((b, a)).or_default() -= 1;
                }
            }
        }
        assert!(wood > 1000);
        let open = edges.values().filter(|&&c| c != 0).count();
        assert_eq!(open, 0, "{}: {open} boundary edges in the wood", m.name);
        let blended = (0..mesh.vertex_count())
            .filter(|&v| mesh.materials[v] != FOLIAGE_MATERIAL)
            .filter(|&v| mesh.influences_of(v).len() >= 2)
            .count();
        assert!(
            blended > 500,
            "{}: {blended} wood vertices blend bones",
            m.name
        );
    }
}

#[test]
fn branches_fork_four_generations_deep() {
    for m in trees() {
        let nodes = &m.skeleton.nodes;
        let mut children = vec![0usize; nodes.len()];
        for n in nodes {
            if let Some(p) = n.parent {
                children[p as usize] += 1;
            }
        }
        // Along every path from the root, count the bones where a branch forks off.
        let forks = |mut b: usize| {
            let mut count = 0;
            while let Some(p) = nodes[b].parent {
                count += (children[p as usize] >= 2) as usize;
                b = p as usize;
            }
            count
        };
        let deepest = (0..nodes.len()).map(forks).max().unwrap();
        assert!(deepest >= 4, "{}: only {deepest} generations", m.name);
    }
}

/// Rotation angle of every bone relative to its rest pose, over one loop.
fn bend_angles(m: &Model, samples: usize) -> Vec<Vec<f32>> {
    let clip = &m.clips[0];
    let mut out = vec![Vec::with_capacity(samples); m.skeleton.bone_count()];
    for k in 0..samples {
        let t = clip.duration * k as f32 / samples as f32;
        let pose = local_pose(&m.skeleton, Some(clip), t);
        for (b, local) in pose.iter().enumerate() {
            let rest = m.skeleton.nodes[b].rest.rotation;
            out[b].push((rest.inverse() * local.rotation).angle_between_identity());
        }
    }
    out
}

trait AngleFromIdentity {
    fn angle_between_identity(&self) -> f32;
}

impl AngleFromIdentity for glam::Quat {
    fn angle_between_identity(&self) -> f32 {
        2.0 * self.w.abs().min(1.0).acos()
    }
}

#[test]
fn the_wind_loops_and_twigs_move_faster_and_wider_than_the_trunk() {
    for m in trees() {
        let clip = &m.clips[0];
        // Seamless: every channel's last key is its first.
        for ch in &clip.channels {
            let (a, b) = (ch.values[0], *ch.values.last().unwrap());
            assert!(
                (a - b).length() < 1e-6,
                "{}: channel of node {}",
                m.name,
                ch.node
            );
            assert!((ch.times.last().unwrap() - clip.duration).abs() < 1e-4);
        }
        let angles = bend_angles(&m, 240);
        let depth = |mut b: usize| {
            let mut d = 0;
            while let Some(p) = m.skeleton.nodes[b].parent {
                d += 1;
                b = p as usize;
            }
            d
        };
        // Swing (max − min) and sign changes of the angle's deviation from its mean.
        let stats = |a: &[f32]| {
            let mean = a.iter().sum::<f32>() / a.len() as f32;
            let swing = a.iter().cloned().fold(f32::MIN, f32::max)
                - a.iter().cloned().fold(f32::MAX, f32::min);
            let crossings = a
                .windows(2)
                .filter(|w| (w[0] - mean).signum() != (w[1] - mean).signum())
                .count();
            (swing, crossings as f32)
        };
        let trunk = m
            .skeleton
            .nodes
            .iter()
            .position(|n| n.name == "trunk1")
            .unwrap();
        let max_depth = (0..m.skeleton.bone_count()).map(depth).max().unwrap();
        let twigs: Vec<usize> = (0..m.skeleton.bone_count())
            .filter(|&b| depth(b) + 1 >= max_depth)
            .collect();
        let (trunk_swing, trunk_rate) = stats(&angles[trunk]);
        let twig_stats: Vec<(f32, f32)> = twigs.iter().map(|&b| stats(&angles[b])).collect();
        let twig_swing = twig_stats.iter().map(|s| s.0).sum::<f32>() / twig_stats.len() as f32;
        let twig_rate = twig_stats.iter().map(|s| s.1).sum::<f32>() / twig_stats.len() as f32;
        assert!(
            twig_swing > 2.0 * trunk_swing,
            "{}: twigs swing {twig_swing}, trunk {trunk_swing}",
            m.name
        );
        assert!(
            twig_rate > 1.5 * trunk_rate,
            "{}: twigs cross {twig_rate} times a loop, trunk {trunk_rate}",
            m.name
        );
        assert!(trunk_swing > 0.0);
    }
}

#[test]
fn trees_stand_on_the_ground_and_are_metric() {
    for name in ["broadleaf", "conifer"] {
        let m = lodlab::import::load_model(name).unwrap();
        let lo = m
            .mesh
            .positions
            .iter()
            .map(|p| m.skeleton.root_transform.transform_point3(*p))
            .fold(Vec3::splat(f32::MAX), Vec3::min);
        let hi = m
            .mesh
            .positions
            .iter()
            .map(|p| m.skeleton.root_transform.transform_point3(*p))
            .fold(Vec3::splat(f32::MIN), Vec3::max);
        assert!(lo.y.abs() < 0.05, "{name}: lowest point at {}", lo.y);
        let h = hi.y - lo.y;
        assert!((5.0..=20.0).contains(&h), "{name}: {h} m tall");
    }
}

/// A 320×240 shot of a forest of 4 trees at 1.5 s with `samples` per pixel, into `out`.
fn forest_shot(
    out: &std::path::Path,
    samples: u32,
    lod: lodlab::runtime::headless::ShotLod,
) -> lodlab::app::commands::shot::ShotReport {
    use lodlab::app::commands::shot::{ShotOptions, run};
    use lodlab::runtime::spec::SceneSpec;
    run(&ShotOptions {
        spec: SceneSpec {
            scene: lodlab::scene::SceneKind::Forest,
            count: 4,
            cache_dir: Some(crate::common::shared_cache()),
            ..Default::default()
        },
        out: out.to_path_buf(),
        width: 320,
        height: 240,
        time: 1.5,
        samples: Some(samples),
        camera: None,
        timed_frames: 1,
        calibrate: false,
        backdrop: Default::default(),
        lod,
    })
    .unwrap()
}

/// The forest renders: trees with green foliage whose quads are cut out by the leaf alpha
/// (no dark quad corners), with and without multisampling; and every pixel is opaque, so no
/// leaf edge shows what lies under the image (a pale fringe over a viewer's white) where alpha
/// to coverage smooths it.
#[test]
fn a_forest_shot_shows_trees_with_cut_out_leaves() {
    let dir = tempfile::tempdir().unwrap();
    for samples in [1, 4] {
        let out = dir.path().join(format!("forest{samples}.png"));
        let report = forest_shot(&out, samples, Default::default());
        assert_eq!(report.scene, "forest");
        assert_eq!(report.instances + report.culled, 4);
        let img = image::open(&out).unwrap().to_rgba8();
        let n = (img.width() * img.height()) as f32;
        let green = img
            .pixels()
            .filter(|p| p[1] as i32 > p[0] as i32 + 15 && p[1] as i32 > p[2] as i32 + 10)
            .count() as f32;
        let dark = img
            .pixels()
            .filter(|p| p[0] < 20 && p[1] < 20 && p[2] < 20)
            .count() as f32;
        assert!(
            green / n > 0.03,
            "MSAA {samples}: foliage covers {:.3}",
            green / n
        );
        assert!(
            dark / n < 0.002,
            "MSAA {samples}: {:.4} of pixels are dark quads",
            dark / n
        );
        let see_through = img.pixels().filter(|p| p[3] < 255).count();
        assert_eq!(see_through, 0, "MSAA {samples}: pixels not opaque");
    }
}

/// With a simplified method chosen, trees switch to their billboard-cloud levels by the same
/// projected-error selection as characters: fewer triangles, several levels in use, and a
/// picture that stays close to the full trees.
#[test]
fn forest_trees_use_their_cloud_levels() {
    use lodlab::app::commands::shot::{ShotOptions, run};
    use lodlab::runtime::headless::ShotLod;
    use lodlab::runtime::spec::SceneSpec;
    use lodlab::scene::{LodMethod, LodPolicy, Transition};
    let dir = tempfile::tempdir().unwrap();
    let shoot = |method: LodMethod| {
        let out = dir.path().join(format!("{}.png", method.index()));
        let report = run(&ShotOptions {
            spec: SceneSpec {
                scene: lodlab::scene::SceneKind::Forest,
                count: 16,
                cache_dir: Some(crate::common::shared_cache()),
                ..Default::default()
            },
            out: out.clone(),
            width: 480,
            height: 270,
            time: 1.0,
            samples: Some(1),
            camera: None,
            timed_frames: 1,
            calibrate: false,
            backdrop: Default::default(),
            lod: ShotLod {
                method,
                policy: LodPolicy {
                    transition: Transition::Pop,
                    ..Default::default()
                },
                ..Default::default()
            },
        })
        .unwrap();
        (report, image::open(&out).unwrap().to_rgba8())
    };
    let (full, a) = shoot(LodMethod::None);
    let (lod, b) = shoot(LodMethod::AS_IS);
    assert_eq!(full.levels.len(), 1);
    assert!(
        lod.levels.iter().filter(|&&n| n > 0).count() >= 2,
        "{:?}",
        lod.levels
    );
    assert!(lod.levels[1..].iter().sum::<u32>() > 0);
    assert!(
        lod.triangles * 2 < full.triangles,
        "{} vs {}",
        lod.triangles,
        full.triangles
    );
    let differ = a
        .pixels()
        .zip(b.pixels())
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 40))
        .count();
    let n = (a.width() * a.height()) as usize;
    assert!(differ * 8 < n, "{differ} of {n} pixels differ a lot");
}

/// Trees change level by a screen-door cross-dissolve: at p = 0 and p = 1 the picture is
/// exactly the outgoing and the incoming model, and in between every pixel is exactly one of
/// the two, the incoming one on a share of the pixels that grows with p. The two halves are
/// one instance: counted once, with one shadow.
#[test]
fn a_dissolve_shows_each_pixel_from_exactly_one_level() {
    use lodlab::render::targets::{OFFSCREEN_FORMAT, Offscreen};
    use lodlab::render::{FrameView, Region, Side};
    use lodlab::runtime::spec::{Loaded, SceneSpec};
    use lodlab::runtime::world::World;
    use lodlab::scene::{Instance, LodDraw};
    let gpu = crate::common::gpu().clone();
    for samples in [1, 4] {
        // Two different trees stand in for the two levels: the dissolve does not care.
        let spec = SceneSpec {
            scene: lodlab::scene::SceneKind::Forest,
            models: vec!["broadleaf".into(), "conifer".into()],
            count: 1,
            ..Default::default()
        };
        let mut world =
            World::new(&gpu, Loaded::new(spec).unwrap(), OFFSCREEN_FORMAT, samples).unwrap();
        world.renderer.shadows = false;
        let (w, h) = (200u32, 200u32);
        let target = Offscreen::new(&gpu, w, h, samples);
        let mut instances: Vec<Instance> = Vec::new();
        world.crowd.instances_at(0.7, &mut instances);
        let one = instances[0];
        let pair = [Instance { model: 0, ..one }, Instance { model: 1, ..one }];
        let view = FrameView::from_camera(&world.camera, 1.0, 0.7);
        let mut render = |instances: &[Instance], draws: &[LodDraw]| {
            let stats = world.renderer.prepare(
                &gpu,
                &view,
                &[Side {
                    method: 0,
                    instances,
                    draws,
                    region: Region::Full,
                }],
            );
            world
                .renderer
                .render_to(&gpu, &target.targets, &target.view)
                .expect("rendered");
            (stats, target.read_rgba(&gpu).unwrap())
        };
        let (_, from) = render(&pair[..1], &[LodDraw::Level(0)]);
        let (_, to) = render(&pair[1..], &[LodDraw::Level(0)]);
        let dissolve = |p| {
            [false, true].map(|incoming| LodDraw::Dissolve {
                level: incoming as u8,
                p,
                incoming,
            })
        };
        let differ: Vec<usize> = (0..from.len() / 4)
            .filter(|&i| from.as_raw()[4 * i..4 * i + 4] != to.as_raw()[4 * i..4 * i + 4])
            .collect();
        assert!(
            differ.len() > 2000,
            "the two trees differ on {} pixels",
            differ.len()
        );
        for (p, expected) in [(0.0, &from), (1.0, &to)] {
            let (stats, img) = render(&pair, &dissolve(p));
            assert_eq!(img.as_raw(), expected.as_raw(), "MSAA {samples}, p = {p}");
            assert_eq!((stats.instances, stats.in_transition), (1, 1));
        }
        for p in [0.25f32, 0.5, 0.75] {
            let (_, img) = render(&pair, &dissolve(p));
            let px = |im: &image::RgbaImage, i: usize| im.as_raw()[4 * i..4 * i + 4].to_vec();
            let mut incoming = 0usize;
            for &i in &differ {
                let (a, b, c) = (px(&from, i), px(&to, i), px(&img, i));
                assert!(
                    c == a || c == b,
                    "MSAA {samples}, p = {p}: pixel {i} is neither"
                );
                incoming += (c == b) as usize;
            }
            let share = incoming as f32 / differ.len() as f32;
            assert!(
                (share - p).abs() < 0.1,
                "MSAA {samples}, p = {p}: {share:.3} of the pixels show the incoming tree"
            );
        }
    }
}

/// `lodlab report TREE --out DIR` end to end, on the sapling (the thesis tree's size): the
/// JSON of the issues with a level per ε down to 10 billboards or fewer, skeleton clouds
/// first and spectral ones at the coarse end, animation errors per level, the thesis's static
/// series, the skeleton-only levels and every description type beside it, the plot, the
/// contact sheet of every level and the motion plot.
///
/// Named to sort first: libtest starts tests in name order, and this one (over a minute) started
/// last ran alone at the end while the other thread idled.
#[test]
fn a_report_of_a_tree_writes_its_three_files() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("report");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_lodlab"))
        // A quarter of the thesis's 800x600 pictures: the same levels, measured coarser and
        // sooner.
        .args([
            "report",
            "sapling",
            "--out",
            out_dir.to_str().unwrap(),
            "--size",
            "400x300",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(json["model"], "sapling");
    assert_eq!(json["leaves"], 672);
    assert_eq!(json["bones"], 95);
    let levels = json["levels"].as_array().unwrap();
    assert!(levels.len() >= 5, "{} levels", levels.len());
    let f = |l: &serde_json::Value, k: &str| l[k].as_f64().unwrap();
    // L0 is the tree: no billboards, no error.
    assert_eq!(
        (f(&levels[0], "epsilon"), f(&levels[0], "colour_error")),
        (0.0, 0.0)
    );
    for l in &levels[1..] {
        for key in ["area", "texture_bytes", "colour_error", "bake_seconds"] {
            assert!(f(l, key) >= 0.0, "{key}: {l}");
        }
        // Seen from where it comes in, at the same size: some error, never all of it.
        let far = f(l, "colour_error_from_switch");
        assert!(far > 0.0 && far < 1.0, "{l}");
        assert!(f(l, "billboards") >= 1.0 && f(l, "area") > 0.0, "{l}");
        // Every covered pixel is shaded at least once (where the adapter counts fragments).
        if let Some(over) = l["fragments_per_covered_pixel"].as_f64() {
            assert!((1.0..1000.0).contains(&over), "{l}");
        }
        // Trimmed round their leaves, billboards are drawn with at most their rectangles.
        assert!(
            f(l, "drawn_area") > 0.0 && f(l, "drawn_area") <= f(l, "area") * 1.0001,
            "{l}"
        );
    }
    for w in levels[1..].windows(2) {
        assert!(f(&w[1], "epsilon") > f(&w[0], "epsilon"));
        assert!(f(&w[1], "drawn_billboards") < f(&w[0], "drawn_billboards"));
    }
    assert!(f(levels.last().unwrap(), "drawn_billboards") <= 10.0);
    // Skeleton clouds near, spectral clouds far, clumps farthest (the automatic chain).
    let kinds: Vec<&str> = levels
        .iter()
        .map(|l| l["grouping"].as_str().unwrap())
        .collect();
    assert!(kinds[1].starts_with("per bone"), "{kinds:?}");
    let first_spectral = kinds.iter().position(|k| k.starts_with("spectral"));
    let first_spectral = first_spectral.expect("spectral levels at the coarse end");
    let first_clumps = kinds
        .iter()
        .position(|k| k.contains("clumps"))
        .expect("clumps at the coarsest end");
    assert!(first_clumps > first_spectral, "{kinds:?}");
    assert!(
        kinds[first_spectral..first_clumps]
            .iter()
            .all(|k| k.starts_with("spectral"))
    );
    assert!(kinds[first_clumps..].iter().all(|k| k.contains("clumps")));
    for l in &levels[first_clumps..] {
        assert_eq!(f(l, "billboards"), 4.0 * f(l, "drawn_billboards"), "{l}");
    }
    let spectral_levels = first_clumps - first_spectral;
    // Animation errors: none for the tree, some for every cloud, growing to the coarse end.
    assert_eq!(f(&levels[0], "anim_rms"), 0.0);
    for l in &levels[1..] {
        assert!(
            f(l, "anim_rms") > 0.0 && f(l, "anim_spectral") >= 0.0,
            "{l}"
        );
        assert!(f(l, "anim_spectral") < 1.0);
    }
    assert!(f(&levels[1], "anim_rms") < f(levels.last().unwrap(), "anim_rms"));
    let skeleton = json["skeleton_levels"].as_array().unwrap();
    assert!(!skeleton.is_empty());
    assert!(
        skeleton
            .iter()
            .all(|l| !l["grouping"].as_str().unwrap().starts_with("spectral"))
    );
    let types = json["description_types"].as_array().unwrap();
    // Every description type with the shared bone, and the chain's own type as plain SCA.
    assert_eq!(types.len(), 4 * spectral_levels);
    for name in ["naive", "dominating-axis", "axis-phase"] {
        assert!(types.iter().any(|t| t["description"] == name
            && t["shared_bone"] == true
            && f(t, "anim_rms") > 0.0));
    }
    assert_eq!(
        types.iter().filter(|t| t["shared_bone"] == false).count(),
        spectral_levels
    );
    let motion = image::open(out_dir.join("motion.png")).unwrap().to_rgb8();
    let curve = |r: u8, g: u8, b: u8| {
        motion
            .pixels()
            .filter(|p| p[0].abs_diff(r) < 30 && p[1].abs_diff(g) < 30 && p[2].abs_diff(b) < 30)
            .count()
    };
    // The leaves (black), the spectral billboards (blue) and the skeleton ones (orange).
    for (name, n) in [
        ("black", curve(20, 20, 20)),
        ("blue", curve(30, 100, 220)),
        ("orange", curve(230, 120, 20)),
    ] {
        assert!(n > 500, "{name}: {n} pixels of its curves");
    }
    // Beside the chain, levels made at the thesis's counts, 36 and 6 clumps drawn.
    let rows = json["against_thesis"].as_array().unwrap();
    let counts: Vec<f64> = rows.iter().map(|r| f(&r["at_count"], "clumps")).collect();
    assert_eq!(counts, [36.0, 6.0]);
    for r in rows {
        for key in ["close", "from_switch"] {
            let e = f(&r["at_count"], key);
            assert!(e > 0.0 && e < 1.0, "{key}: {r}");
        }
    }
    // Error grows from the first cloud level to the last.
    assert!(f(&levels[1], "colour_error") < f(levels.last().unwrap(), "colour_error"));
    assert_eq!(
        json["static_clouds"].as_array().unwrap().len(),
        levels.len() - 1
    );
    let plot = image::open(out_dir.join("colour-error.png"))
        .unwrap()
        .to_rgb8();
    let blue = plot.pixels().filter(|p| p[2] > 180 && p[0] < 80).count();
    let red = plot
        .pixels()
        .filter(|p| p[0] > 180 && p[1] < 90 && p[2] < 90)
        .count();
    assert!(blue > 100 && red > 100, "blue {blue}, red {red}");
    // Both orders' chains drawn as curves: the ε order red, the cost order blue.
    let chains = image::open(out_dir.join("chains-error-per-cost.png"))
        .unwrap()
        .to_rgb8();
    let near = |p: &image::Rgb<u8>, c: [i32; 3]| (0..3).all(|i| (p[i] as i32 - c[i]).abs() < 30);
    let epsilon = chains.pixels().filter(|p| near(p, [200, 60, 40])).count();
    let cost = chains.pixels().filter(|p| near(p, [30, 110, 200])).count();
    assert!(
        epsilon > 50 && cost > 50,
        "ε order {epsilon}, cost order {cost}"
    );
    let sheet = image::open(out_dir.join("levels.png")).unwrap().to_rgb8();
    let columns = levels.len().min(6) as u32;
    assert_eq!(sheet.width(), 300 * columns);
    assert_eq!(
        sheet.height(),
        400 * (levels.len() as u32).div_ceil(columns)
    );
    // Every tile shows green foliage.
    for k in 0..levels.len() as u32 {
        let (x0, y0) = ((k % columns) * 300, (k / columns) * 400);
        let green = (y0..y0 + 400)
            .flat_map(|y| (x0..x0 + 300).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let p = sheet.get_pixel(x, y);
                p[1] as i32 > p[0] as i32 + 15 && p[1] as i32 > p[2] as i32 + 10
            })
            .count();
        assert!(green > 300, "level {k}: {green} green pixels");
    }
}

/// `lodlab bake` builds a tree's chain of billboard clouds (what the viewer then reads from the
/// cache) beside a character's levels, and a second run finds it cached.
#[test]
fn bake_builds_and_caches_a_tree_chain() {
    let dir = tempfile::tempdir().unwrap();
    let bake = || {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_lodlab"))
            .args(["bake", "sapling", "walker", "--methods", "as", "--cache"])
            .arg(dir.path())
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    let first = bake();
    assert!(
        first.contains("sapling (4780 triangles, 95 bones): billboard clouds"),
        "{first}"
    );
    assert!(
        first.contains("walker (11712 triangles, 25 bones)"),
        "{first}"
    );
    let rows: Vec<&str> = first
        .lines()
        .skip_while(|l| !l.starts_with("sapling"))
        .skip(2)
        .take_while(|l| !l.is_empty())
        .collect();
    assert!(rows.len() >= 5, "{first}");
    assert!(
        rows[0].starts_with("0 ") && rows[0].contains("full tree"),
        "{}",
        rows[0]
    );
    assert!(!first.contains("cached"), "{first}");
    let second = bake();
    assert_eq!(second.matches("cached").count(), 2, "{second}");
}

/// The foliage panel's choices, through the world the viewer and `shot` share: the level
/// policy decides which chain trees switch along (none for `full`), a chain already on the
/// GPU comes back without a bake while new cutting options ask for one, billboard outlines
/// draw over billboards only, and the level tint colours the trees.
#[test]
fn the_foliage_policy_decides_what_trees_become() {
    use lodlab::render::targets::{OFFSCREEN_FORMAT, Offscreen};
    use lodlab::runtime::spec::{Loaded, SceneSpec};
    use lodlab::runtime::world::World;
    use lodlab::scene::foliage::{FoliagePolicy, FoliageView};
    use lodlab::scene::{LodMethod, LodPolicy, Transition};
    let gpu = crate::common::gpu().clone();
    let dir = tempfile::tempdir().unwrap();
    let spec = SceneSpec {
        scene: lodlab::scene::SceneKind::Forest,
        models: vec!["sapling".into()],
        count: 12,
        cache_dir: Some(dir.path().to_path_buf()),
        ..Default::default()
    };
    let mut world = World::new(&gpu, Loaded::new(spec).unwrap(), OFFSCREEN_FORMAT, 1).unwrap();
    world.renderer.shadows = false;
    world.lod.method = LodMethod::AS_IS;
    world.lod.policy = LodPolicy {
        transition: Transition::Pop,
        tolerance_px: 4.0,
        ..Default::default()
    };
    let (w, h) = (320u32, 180u32);
    let target = Offscreen::new(&gpu, w, h, 1);
    let shoot = |world: &mut World, foliage: &FoliageView| {
        world.apply_foliage(foliage);
        world
            .ensure_levels(&gpu, &lodlab::measure::GpuMeasurer)
            .unwrap();
        let stats = world.prepare(&gpu, [w, h], 1.0, 0.0);
        world
            .renderer
            .render_to(&gpu, &target.targets, &target.view)
            .expect("rendered");
        (stats, target.read_rgba(&gpu).unwrap())
    };
    let kinds = |world: &World| -> Vec<&'static str> {
        let chains = world.shown_chains();
        assert_eq!(chains.len(), 1);
        assert!(chains[0].1, "the chain shown is the one asked for");
        chains[0]
            .2
            .iter()
            .map(|l| lodlab::bake::foliage::billboard::chain::CloudKind::word(l.kind.as_ref()))
            .collect()
    };
    // Clouds of one kind after the full tree, the last level maybe the impostor.
    let clouds_of = |k: &[&str], kind: &str| {
        let clouds = k.strip_suffix(&["impostor"]).unwrap_or(k);
        clouds.len() >= 2 && clouds[1..].iter().all(|&c| c == kind)
    };

    // Full: no chain is built, every tree stays at level 0.
    let full = FoliageView {
        policy: FoliagePolicy::Full,
        ..Default::default()
    };
    let (stats, plain) = shoot(&mut world, &full);
    assert!(world.shown_chains().is_empty());
    assert_eq!(stats.levels[0] as u64, stats.instances);
    let full_triangles = stats.triangles;

    // Skeleton clouds all the way, then spectral clouds from level 1.
    let skeleton = FoliageView {
        policy: FoliagePolicy::Skeleton,
        ..full
    };
    let (stats, _) = shoot(&mut world, &skeleton);
    let k = kinds(&world);
    assert_eq!(k[0], "full");
    assert!(clouds_of(&k, "skeleton"), "{k:?}");
    assert!(stats.levels[1..].iter().sum::<u32>() > 0);
    assert!(stats.triangles < full_triangles);
    let spectral = FoliageView {
        policy: FoliagePolicy::Spectral,
        ..full
    };
    shoot(&mut world, &spectral);
    let k = kinds(&world);
    assert!(clouds_of(&k, "spectral"), "{k:?}");

    // Back to skeleton clouds: still on the GPU, nothing to bake.
    world.apply_foliage(&skeleton);
    assert_eq!(world.missing_levels(), None);
    assert!(clouds_of(&kinds(&world), "skeleton"));
    // Other cutting options need a chain of their own; until it comes, the old one shows.
    let mut coarser = skeleton;
    coarser.chain.first_epsilon *= 4.0;
    world.apply_foliage(&coarser);
    assert!(world.missing_levels().is_some());
    assert!(!world.shown_chains()[0].1);
    shoot(&mut world, &coarser);
    assert!(world.shown_chains()[0].1);

    // Outlines draw over billboards, and there are none at full detail.
    let (_, bare) = shoot(&mut world, &skeleton);
    let outlined = FoliageView {
        outlines: true,
        ..skeleton
    };
    let (_, lines) = shoot(&mut world, &outlined);
    let magenta = |img: &image::RgbaImage| {
        img.pixels()
            .filter(|p| p[0] > 150 && p[2] > 120 && p[1] < 150)
            .count()
    };
    assert!(
        magenta(&lines) > magenta(&bare) + 200,
        "outlines: {} magenta pixels, {} without",
        magenta(&lines),
        magenta(&bare)
    );
    let (_, full_outlined) = shoot(
        &mut world,
        &FoliageView {
            outlines: true,
            ..full
        },
    );
    assert_eq!(full_outlined.as_raw(), plain.as_raw());

    // The level tint repaints the trees.
    let (_, tinted) = shoot(
        &mut world,
        &FoliageView {
            tint: true,
            ..skeleton
        },
    );
    let changed = bare
        .pixels()
        .zip(tinted.pixels())
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 30))
        .count();
    assert!(changed > 2000, "the tint changed {changed} pixels");
}

/// Ordered by error per cost (the default), every stretch of sizes of the three built-in
/// trees' chains draws a level whose colour error at the stretch's switch size is no worse
/// than the ε chain's level there, never finer further off, and all of them cost no more than
/// the ε chain's; the chain that results is what selection switches along, ε rising level by
/// level. The clump levels the ε chain cuts off
/// behind the impostor stand in for a cloud somewhere: the point of ordering by cost.
#[test]
fn the_cost_order_draws_no_worse_than_the_epsilon_chain_at_every_switch_size() {
    use lodlab::bake::cache::{LodCache, Origin};
    use lodlab::bake::foliage::billboard::chain::levels::FoliageOrder;
    use lodlab::bake::foliage::billboard::chain::{
        ChainOptions, CloudKind, load_or_build_chain, load_or_build_chains, load_or_choose, order,
    };
    let gpu = crate::common::gpu();
    let cache = LodCache::new(Some(crate::common::shared_cache()));
    let raster = lodlab::render::atlas::AtlasRasterizer::new(gpu);
    let measure = lodlab::measure::colour_error::GpuColourError::new(gpu);
    let opts = ChainOptions::default();
    assert_eq!(opts.order, FoliageOrder::Cost);
    let mut clumps_for_clouds = 0;
    for name in ["broadleaf", "conifer", "sapling"] {
        let tree = lodlab::import::load_model(name).unwrap();
        let source = lodlab::import::import(name, &Default::default())
            .unwrap()
            .source_hash;
        let (shown, _) =
            load_or_build_chain(&raster, &measure, &cache, &tree, &source, &opts, &|_| {}).unwrap();
        let (chains, origin) =
            load_or_build_chains(&raster, &measure, &cache, &tree, &source, &opts, &|_| {})
                .unwrap();
        assert_eq!(origin, Origin::Cache, "{name}: baked once for both orders");
        let (choices, origin) =
            load_or_choose(&measure, &cache, &tree, &source, &opts, &chains).unwrap();
        assert_eq!(origin, Origin::Cache, "{name}: the choices are cached");
        assert_eq!(choices.len(), chains.epsilon.len() - 1, "{name}");
        let total = |f: &dyn Fn(&order::CostChoice) -> f64| choices.iter().map(f).sum::<f64>();
        assert!(
            total(&|c| c.drawn_cost) <= total(&|c| c.epsilon_cost),
            "{name}: {choices:?}"
        );
        assert!(
            choices
                .windows(2)
                .all(|w| w[0].drawn_level <= w[1].drawn_level),
            "{name}: {choices:?}"
        );
        for c in &choices {
            assert!(c.drawn_error <= c.epsilon_error, "{name}: {c:?}");
            assert!(
                c.drawn_level == 0 || c.drawn_level >= chains.reference[c.epsilon_level],
                "{name}: the full tree or no finer than the ε chain's level: {c:?}"
            );
            let cloud = |k: &Option<CloudKind>| {
                matches!(k, Some(CloudKind::Skeleton(_) | CloudKind::Spectral(_)))
            };
            let clumps = |k: &Option<CloudKind>| matches!(k, Some(CloudKind::Clumps { .. }));
            clumps_for_clouds += (cloud(&chains.epsilon[c.epsilon_level].kind)
                && clumps(&chains.candidates[c.drawn_level].kind))
                as usize;
        }
        // What selection switches along: the chosen levels, from their stretches' ε.
        let expected = order::chain_of(&chains, &choices);
        let epsilons = |l: &[lodlab::bake::foliage::billboard::chain::TreeLevel]| {
            l.iter().map(|l| l.epsilon).collect::<Vec<_>>()
        };
        assert_eq!(epsilons(&shown), epsilons(&expected), "{name}");
        assert!(
            shown.windows(2).all(|w| w[1].epsilon > w[0].epsilon),
            "{name}"
        );
        // The ε order is the chain the cut made, ending in the impostor.
        let epsilon_opts = ChainOptions {
            order: FoliageOrder::Epsilon,
            ..opts
        };
        let (epsilon_chain, _) = load_or_build_chain(
            &raster,
            &measure,
            &cache,
            &tree,
            &source,
            &epsilon_opts,
            &|_| {},
        )
        .unwrap();
        assert_eq!(
            epsilons(&epsilon_chain),
            epsilons(&chains.epsilon),
            "{name}"
        );
    }
    assert!(
        clumps_for_clouds > 0,
        "no clump level stands in for a cloud"
    );
}

/// The foliage depth pre-pass (`--foliage-prepass`) draws the same forest as the single
/// alpha-tested pass: each pixel's nearest leaf, shaded alike; and it does run (the fragment
/// shaders invoked go up, where the adapter counts them: the leaves are drawn twice).
#[test]
fn the_foliage_depth_prepass_draws_the_same_forest() {
    let dir = tempfile::tempdir().unwrap();
    let shot = |prepass: bool| {
        let out = dir.path().join(format!("forest-{prepass}.png"));
        let mut lod = lodlab::runtime::headless::ShotLod::default();
        lod.foliage.prepass = prepass;
        let report = forest_shot(&out, 1, lod);
        (image::open(&out).unwrap().to_rgb8(), report.overdraw)
    };
    let (single, single_overdraw) = shot(false);
    let (prepass, prepass_overdraw) = shot(true);
    let differing = single
        .pixels()
        .zip(prepass.pixels())
        .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b[c]) > 8))
        .count();
    let n = (single.width() * single.height()) as usize;
    let green = prepass
        .pixels()
        .filter(|p| p[1] as i32 > p[0] as i32 + 15 && p[1] as i32 > p[2] as i32 + 10)
        .count();
    assert!(
        green > n / 50,
        "the forest's leaves: {green} green pixels of {n}"
    );
    assert!(
        differing * 200 < n,
        "{differing} of {n} pixels differ with the pre-pass"
    );
    if let (Some(a), Some(b)) = (single_overdraw, prepass_overdraw) {
        assert!(
            b > a * 1.2,
            "fragments per pixel {a:.2} alone, {b:.2} with the pre-pass"
        );
    }
}

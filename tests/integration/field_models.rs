//! The test models with the properties of files from elsewhere (`lodlab::generate::wild`, and
//! `lowpoly`), and random valid meshes: each loads as what it stands for, every level of each
//! exports as glTF the Khronos validator passes and lodlab reads back, the files gltfpack makes
//! of them when it simplifies and quantises load and bake, and clips come from a second file
//! by joint name.

use crate::common::{gltf_tools, validate};
use lodlab::bake::character::lod::bake_lods;
use lodlab::bake::character::simplify::{Method, SimplifyInput};
use lodlab::generate::wild;
use lodlab::import::load_model;
use lodlab::model::{Model, SkinnedMesh};
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn lodlab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args(args)
        .output()
        .expect("lodlab runs")
}

/// Triangles of `mesh` that draw something: no repeated vertex, no repeat of another triangle.
fn drawn(mesh: &SkinnedMesh) -> usize {
    let mut seen = HashSet::new();
    mesh.indices
        .chunks_exact(3)
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .filter(|t| {
            let k = (0..3).min_by_key(|&k| t[k]).unwrap();
            seen.insert([t[k], t[(k + 1) % 3], t[(k + 2) % 3]])
        })
        .count()
}

/// The name of the node bone `bone` of `m` is.
fn bone_name(m: &Model, bone: u32) -> &str {
    &m.skeleton.nodes[m.skeleton.joints[bone as usize] as usize].name
}

#[test]
fn the_field_models_load_as_what_they_stand_for() {
    // The robot: its 19 primitives of four skins in one mesh, the debris gone, every vertex
    // used, its four plain colours in one palette.
    let doc = wild::robot::robot();
    let robot = load_model("robot").unwrap();
    let expected: usize = doc
        .meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .map(|p| drawn(&p.mesh))
        .sum();
    assert_eq!(robot.mesh.triangle_count(), expected);
    let mut used = vec![false; robot.mesh.vertex_count()];
    robot
        .mesh
        .indices
        .iter()
        .for_each(|&v| used[v as usize] = true);
    assert!(used.iter().all(|&u| u), "a vertex no triangle uses");
    assert_eq!(robot.skeleton.bone_count(), 18);
    assert_eq!(robot.materials.len(), 1);

    // The knight: hundreds of plain materials load by default, and its two unskinned props
    // ride on what carries them: the spear on the right hand's bone, the cape on its own node.
    let doc = wild::knight::knight();
    assert!(doc.materials.len() > 300);
    let knight = load_model("knight").unwrap();
    let expected: usize = doc
        .meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .map(|p| drawn(&p.mesh))
        .sum();
    assert_eq!(knight.mesh.triangle_count(), expected);
    assert_eq!(knight.materials.len(), 1, "plain colours share one palette");
    let rest = lodlab::anim::linear_blend_skinning(
        &knight.mesh,
        &knight.skeleton,
        &lodlab::anim::bone_matrices(&knight.skeleton, None, 0.0),
    );
    let on = |name: &str| -> Vec<usize> {
        (0..knight.mesh.vertex_count())
            .filter(|&v| {
                let inf = knight.mesh.influences_of(v);
                inf.len() == 1 && bone_name(&knight, inf[0].bone) == name
            })
            .collect()
    };
    let spear = on("hand_r");
    let top = spear.iter().map(|&v| rest[v].y).fold(f32::MIN, f32::max);
    assert!(top > 1.7, "the spear rises above the head: {top}");
    let cape = on("Cape");
    assert!(
        cape.len() > 100,
        "{} vertices on the cape's node",
        cape.len()
    );
    // The cape hangs behind the back, from the shoulders to the knees.
    let (lo, hi) = cape.iter().fold((f32::MAX, f32::MIN), |(a, b), &v| {
        (a.min(rest[v].y), b.max(rest[v].y))
    });
    let back = cape.iter().map(|&v| rest[v].z).fold(f32::MIN, f32::max);
    assert!(lo < 0.7 && hi > 1.4 && back < 0.0, "{lo} {hi} {back}");

    // The rigged character: 65 joints, and bound in metres and Y up though its mesh was
    // written in its armature's centimetres, Z up: rest positions stand where the skinned
    // character stands.
    let mocap = load_model("mocap").unwrap();
    assert_eq!(mocap.skeleton.bone_count(), 65);
    let am = lodlab::bake::gpu_data::animation_space::AnimationSpaceMesh::from_skinned(
        &mocap.mesh,
        &mocap.skeleton,
    );
    let rest_bones = SimplifyInput::rest_bones(&mocap.skeleton);
    let at_rest = am.rest_positions(&rest_bones);
    let skinned = lodlab::anim::linear_blend_skinning(
        &mocap.mesh,
        &mocap.skeleton,
        &lodlab::anim::bone_matrices(&mocap.skeleton, None, 0.0),
    );
    let off = at_rest
        .iter()
        .zip(&skinned)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0f32, f32::max);
    assert!(
        off < 1e-4,
        "rest positions {off} m from the skinned rest pose"
    );
    let height = lodlab::bake::character::lod::model_height(&mocap);
    assert!((1.6..2.0).contains(&height), "{height}");

    // The low-poly character: flat-shaded, every position on several facets' normals.
    let lowpoly = load_model("lowpoly").unwrap();
    let groups = lodlab::geometry::weld::position_groups(&lowpoly.mesh.positions, 1e-6);
    let positions = groups.iter().max().unwrap() + 1;
    assert!(lowpoly.mesh.vertex_count() as u32 >= 2 * positions);
}

/// Every level of `model` by `method` exported, checked by the validator (0 errors), and
/// read back with the level's triangles.
fn export_checked(model: &str, method: &str, tools: Option<&Path>, dir: &Path) {
    let out = lodlab(&[
        "export",
        model,
        "--method",
        method,
        "--out",
        dir.to_str().unwrap(),
        "--cache",
        dir.join("cache").to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{model} {method}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let e: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut files = Vec::new();
    for l in e["levels"].as_array().unwrap() {
        let file = PathBuf::from(l["file"].as_str().unwrap());
        let back = load_model(file.to_str().unwrap()).unwrap();
        assert_eq!(
            back.mesh.triangle_count() as u64,
            l["triangles"].as_u64().unwrap(),
            "{model} {method}: {}",
            file.display()
        );
        files.push(file);
    }
    let lod_file = PathBuf::from(e["lod_file"].as_str().unwrap());
    // Coverage hints fall from below full screen, so an engine choosing by them shows full
    // detail before the model fills the whole screen.
    let bytes = std::fs::read(&lod_file).unwrap();
    let json: serde_json::Value =
        serde_json::from_slice(&gltf::binary::Glb::from_slice(&bytes).unwrap().json).unwrap();
    let hints: Vec<f64> = json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find_map(|n| n["extras"]["MSFT_screencoverage"].as_array())
        .unwrap()
        .iter()
        .map(|h| h.as_f64().unwrap())
        .collect();
    assert!(hints[0] < 1.0, "{model} {method}: {hints:?}");
    assert!(
        hints.windows(2).all(|w| w[1] < w[0]),
        "{model} {method}: {hints:?}"
    );
    files.push(lod_file);
    if let Some(tools) = tools {
        for (errors, _, report) in validate(tools, &files) {
            assert_eq!(errors, 0, "{model} {method}: {report}");
        }
    }
}

#[test]
fn every_level_of_the_field_models_exports_as_valid_gltf() {
    let tools = gltf_tools();
    let dir = tempfile::tempdir().unwrap();
    for method in ["rest-pose", "as", "as+is"] {
        export_checked("robot", method, tools.as_deref(), dir.path());
    }
    for model in ["lowpoly", "knight", "armour"] {
        export_checked(model, "as+is", tools.as_deref(), dir.path());
    }
}

fn gltfpack(tools: &Path, input: &Path, output: &Path, args: &[&str]) {
    let out = Command::new("node")
        .arg(tools.join("node_modules/gltfpack/cli.js"))
        .arg("-i")
        .arg(input)
        .arg("-o")
        .arg(output)
        .args(args)
        .output()
        .expect("node runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// What gltfpack writes when it simplifies a file (`-si 0.1`) and quantises it (its default):
/// skins through inverse bind matrices that scale by about 10⁻⁴, which an absolute test of
/// invertibility took for singular.
#[test]
fn files_gltfpack_simplified_and_quantised_load_and_bake() {
    let Some(tools) = gltf_tools() else { return };
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for name in ["robot", "mocap", "knight"] {
        let packed = dir.path().join(format!("{name}-packed.glb"));
        gltfpack(
            &tools,
            &root.join(format!("assets/{name}.glb")),
            &packed,
            &["-si", "0.1"],
        );
        let m = load_model(packed.to_str().unwrap())
            .unwrap_or_else(|e| panic!("{name}: gltfpack's output: {e}"));
        let source = load_model(name).unwrap().mesh.triangle_count();
        assert!(m.mesh.triangle_count() < source, "{name}");
        let out = lodlab(&[
            "bake",
            packed.to_str().unwrap(),
            "--methods",
            "as",
            "--cache",
            dir.path().join("cache").to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// `model` baked by every method at the viewer's options, each level written as glTF and read
/// back with the triangles it draws (`seed` names the model in failures): the levels' meshes by
/// method.
fn levels_read_back(model: &Model, seed: u64, dir: &Path) -> Vec<(Method, Vec<SkinnedMesh>)> {
    let limits = lodlab::import::validate::Limits::default();
    let opts = lodlab::runtime::levels::runtime_options(model, None);
    Method::ALL
        .into_iter()
        .map(|method| {
            let lods = bake_lods(model, method, &opts, &|_| {});
            assert!(!lods.levels.is_empty(), "seed {seed} {method}");
            let meshes = lodlab::app::commands::export::level_meshes(model, &lods);
            for mesh in &meshes {
                let one = lodlab::generate::glb::to_glb(&Model {
                    mesh: mesh.clone(),
                    ..model.clone()
                });
                let (back, _) = lodlab::import::gltf::from_bytes("level", one, dir, &limits)
                    .unwrap_or_else(|e| panic!("seed {seed} {method}: {e}"));
                assert_eq!(
                    back.mesh.triangle_count(),
                    drawn(mesh),
                    "seed {seed} {method}"
                );
            }
            (method, meshes)
        })
        .collect()
}

/// Valid files of random meshes (coincident points, degenerate and repeated triangles,
/// unused vertices, several skins): each loads (or, where nothing in it draws, is refused in
/// one line), bakes by every method, and its levels written as glTF read back as baked.
#[test]
fn random_meshes_load_bake_and_export() {
    let tools = gltf_tools();
    let dir = tempfile::tempdir().unwrap();
    let mut written = Vec::new();
    let mut loaded = 0;
    for seed in 0..120u64 {
        let mut rng = fastrand::Rng::with_seed(seed);
        let bytes: Vec<u8> = (0..rng.usize(20..900)).map(|_| rng.u8(..)).collect();
        let file = wild::random::random_file(&bytes);
        let limits = lodlab::import::validate::Limits::default();
        let model = match lodlab::import::gltf::from_bytes("random", file, dir.path(), &limits) {
            Ok((m, _)) => m,
            Err(e) => {
                assert!(
                    !e.contains('\n') && (e.contains("no triangles") || e.contains("zero size")),
                    "seed {seed}: {e}"
                );
                continue;
            }
        };
        loaded += 1;
        for (method, meshes) in levels_read_back(&model, seed, dir.path()) {
            let refs: Vec<&SkinnedMesh> = meshes.iter().collect();
            let coverage: Vec<f32> = (0..meshes.len())
                .map(|k| 0.5f32.powi(k as i32 + 1))
                .collect();
            let bytes = lodlab::generate::glb::to_lod_glb(&model, &refs, &coverage, "test");
            if seed % 10 == 0 {
                let path = dir.path().join(format!("random-{seed}-{method}.glb"));
                std::fs::write(&path, bytes).unwrap();
                written.push(path);
            }
        }
    }
    assert!(loaded > 60, "{loaded} of 120 random files loaded");
    if let Some(tools) = tools {
        for (errors, _, report) in validate(&tools, &written) {
            assert_eq!(errors, 0, "{report}");
        }
    }
}

/// Valid files of random structure (`wild::structure`: joints in any tree under a scaled
/// armature, several skins over subsets of them bound off the rest pose, rigid parts on joints
/// and on nodes drawn twice, clips of every channel kind and interpolation, textured, masked
/// and blended materials): every generated file passes glTF-Validator; each loads (or is
/// refused in one line where nothing in it draws), bakes by every method, and its levels,
/// written as glTF, read back with the level's triangles and pass glTF-Validator too.
#[test]
fn random_structures_load_bake_and_export() {
    let tools = gltf_tools();
    let dir = tempfile::tempdir().unwrap();
    let mut sources = Vec::new();
    let mut written = Vec::new();
    let mut loaded = 0;
    let limits = lodlab::import::validate::Limits::default();
    for seed in 0..100u64 {
        let mut rng = fastrand::Rng::with_seed(1000 + seed);
        let bytes: Vec<u8> = (0..rng.usize(50..1200)).map(|_| rng.u8(..)).collect();
        let file = wild::structure::structure_file(&bytes);
        if seed % 4 == 0 {
            let path = dir.path().join(format!("structure-{seed}.glb"));
            std::fs::write(&path, &file).unwrap();
            sources.push(path);
        }
        let model = match lodlab::import::gltf::from_bytes("structure", file, dir.path(), &limits) {
            Ok((m, _)) => m,
            Err(e) => {
                assert!(
                    !e.contains('\n') && (e.contains("no triangles") || e.contains("zero size")),
                    "seed {seed}: {e}"
                );
                continue;
            }
        };
        loaded += 1;
        for (method, meshes) in levels_read_back(&model, seed, dir.path()) {
            if seed % 10 == 0 {
                let refs: Vec<&SkinnedMesh> = meshes.iter().collect();
                let coverage: Vec<f32> = (0..meshes.len())
                    .map(|k| 0.5f32.powi(k as i32 + 1))
                    .collect();
                let bytes = lodlab::generate::glb::to_lod_glb(&model, &refs, &coverage, "test");
                let path = dir.path().join(format!("structure-{seed}-{method}.glb"));
                std::fs::write(&path, bytes).unwrap();
                written.push(path);
            }
        }
    }
    assert!(loaded > 60, "{loaded} of 100 random structures loaded");
    if let Some(tools) = tools {
        let files: Vec<PathBuf> = sources.iter().chain(&written).cloned().collect();
        for (file, (errors, _, report)) in files.iter().zip(validate(&tools, &files)) {
            assert_eq!(errors, 0, "{}: {report}", file.display());
        }
    }
}

/// The `random_mesh` fuzzer's first find: one triangle whose two corners stand at one point
/// with one skin. It draws nothing in any pose, and animation space welds it away, so its
/// levels held no triangle and their exports could not be read back. It is refused in one line.
#[test]
fn a_mesh_of_triangles_with_two_corners_at_one_point_is_refused_in_one_line() {
    let bytes = [
        0, 0, 0, 0, 56, 185, 90, 56, 56, 0, 10, 0, 0, 0, 0, 0, 0, 0, 56, 185, 90, 0, 0, 0, 0, 0,
        55, 0, 0, 0, 37, 0, 0, 71, 1, 0, 115,
    ];
    let dir = tempfile::tempdir().unwrap();
    let limits = lodlab::import::validate::Limits::default();
    let file = wild::random::random_file(&bytes);
    match lodlab::import::gltf::from_bytes("random", file, dir.path(), &limits) {
        Ok((m, _)) => panic!("loaded {} triangles", m.mesh.triangle_count()),
        Err(e) => assert!(
            !e.contains('\n') && e.contains("no triangles that draw"),
            "{e}"
        ),
    }
}

/// `--clips FILE` adds the clips of a file of the same skeleton by joint name; a file of
/// another skeleton is refused in one line naming joints it animates that the model lacks.
#[test]
fn clips_come_from_another_file_by_joint_name() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("walk.png");
    let out = lodlab(&[
        "shot",
        "--scene",
        "study",
        "--model",
        "mocap",
        "--clips",
        "mocap-walk",
        "--clip",
        "Walking",
        "--count",
        "1",
        "--size",
        "96x96",
        "--time",
        "0.3",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(png.is_file());

    let out = lodlab(&[
        "shot",
        "--scene",
        "study",
        "--model",
        "mocap",
        "--clips",
        "robot",
        "--count",
        "1",
        "--size",
        "96x96",
        "--out",
        dir.path().join("none.png").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(
        errors[0].contains("built-in robot")
            && errors[0].contains("shoulder_l")
            && errors[0].contains("mixamorig:Hips"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"));

    // Added by the library: the walk is the model's second clip, and it moves the hands.
    let mut m = load_model("mocap").unwrap();
    let walk = lodlab::import::source("mocap-walk");
    assert_eq!(
        lodlab::import::gltf::add_clips_from(&mut m, &walk, &Default::default())
            .unwrap()
            .0,
        1
    );
    assert_eq!(m.clips.len(), 2);
    assert_eq!(m.clips[1].name, "Walking");
    let hand = m
        .skeleton
        .joints
        .iter()
        .position(|&j| m.skeleton.nodes[j as usize].name == "mixamorig:LeftHand")
        .unwrap();
    let a = lodlab::anim::bone_matrices(&m.skeleton, Some(&m.clips[1]), 0.0)[hand].translation;
    let b = lodlab::anim::bone_matrices(&m.skeleton, Some(&m.clips[1]), 0.5)[hand].translation;
    assert!(a.distance(b) > 0.1, "the hand swings {}", a.distance(b));
}

/// The levels of `model` by `method` with their colour errors (see
/// `lodlab::measure::shading_error`) where the renderer switches to each at `tolerance` px,
/// no larger than `largest` px.
fn shading_at_switch(
    model: &Model,
    method: Method,
    tolerance: f32,
    largest: f32,
    levels: std::ops::Range<usize>,
) -> Vec<lodlab::measure::shading_error::LevelShading> {
    let gpu = crate::common::gpu().clone();
    let full = lodlab::bake::gpu_data::drawable::Drawable::new(model).unwrap();
    let opts = lodlab::runtime::levels::runtime_options(model, None);
    let lods = bake_lods(model, method, &opts, &|_| {});
    let height = lodlab::bake::character::lod::model_height(model);
    let at: Vec<(usize, f32)> = levels
        .filter(|&k| k < lods.levels.len())
        .map(|k| {
            (
                k,
                (tolerance * height / lods.levels[k].error).clamp(24.0, largest),
            )
        })
        .collect();
    lodlab::measure::shading_error::shading_errors_at(&gpu, model, &full, &lods.levels, &at)
        .unwrap()
}

/// Influence simplification keeps the shading of a flat-shaded model: every wedge of a
/// position keeps its own normal (it had given them all one, and turned the facets smooth at
/// the first level: colour error 0.068 against AS's 0.0002 on a faceted soldier).
#[test]
fn influence_simplification_keeps_a_faceted_models_shading() {
    let model = load_model("lowpoly").unwrap();
    let at = |method| {
        let gpu = crate::common::gpu().clone();
        let full = lodlab::bake::gpu_data::drawable::Drawable::new(&model).unwrap();
        let opts = lodlab::runtime::levels::runtime_options(&model, None);
        let lods = bake_lods(&model, method, &opts, &|_| {});
        lodlab::measure::shading_error::shading_errors(
            &gpu,
            &model,
            &full,
            &lods.levels,
            &[1, 2, 3],
            300.0,
        )
        .unwrap()
    };
    let (asm, asis) = (
        at(Method::AnimationSpace),
        at(Method::InfluenceSimplification),
    );
    for (a, b) in asm.iter().zip(&asis) {
        assert!(
            b.vertex_normals <= 1.5 * a.vertex_normals + 0.001,
            "level {}: as+is {:.4} against as {:.4}",
            a.level,
            b.vertex_normals,
            a.vertex_normals
        );
    }
}

/// A material border is a seam: the knight, coloured by hundreds of plain materials, shows
/// each part in its own colour at every level where the renderer switches to it (a torn
/// chart used to take the neighbouring material's corner for free: gilt trims flooded the
/// plates).
#[test]
fn a_model_coloured_by_materials_keeps_its_colours_at_every_level() {
    let model = load_model("knight").unwrap();
    for s in shading_at_switch(&model, Method::RestPose, 4.0, 300.0, 1..12) {
        let bound = if s.px >= 200.0 { 0.001 } else { 0.02 };
        assert!(
            s.recoloured <= bound,
            "level {} ({} triangles, {:.0} px): {:.2}% of its pixels show a colour full detail \
             has nowhere near",
            s.level,
            s.triangles,
            s.px,
            100.0 * s.recoloured
        );
    }
}

/// A normal map never makes a level's worst tile worse than its vertex normals do, beyond a
/// hundredth of the colour range (its eight-bit normals and their filtering); tiles where the
/// texture slid keep their vertex normals (`bake::normal_map`).
#[test]
fn normal_maps_do_not_make_the_worst_tile_worse() {
    let mut model = load_model("mocap").unwrap();
    let walk = lodlab::import::source("mocap-walk");
    lodlab::import::gltf::add_clips_from(&mut model, &walk, &Default::default()).unwrap();
    model.clips.reverse();
    for s in shading_at_switch(&model, Method::InfluenceSimplification, 1.5, 300.0, 1..7) {
        assert!(
            s.worst_tile_normal_maps <= s.worst_tile_vertex_normals + 0.01,
            "level {} ({} px): worst tile {:.4} through its map, {:.4} by its vertex normals",
            s.level,
            s.px,
            s.worst_tile_normal_maps,
            s.worst_tile_vertex_normals
        );
    }
}

/// The `valid_structure` fuzzer's finds (250,000 and 160,000 runs in): files of random
/// structure whose levels, cut by triangle budgets, exported and read back, were refused as
/// having "no triangles that draw" (the first a level of no drawing triangle in animation
/// space, the second one that draws there but not as a skin; see `export::level_meshes`).
#[test]
fn random_structures_levels_read_back() {
    let finds: [&[u8]; 2] = [
        &[
            43, 41, 19, 3, 126, 126, 126, 126, 126, 126, 126, 126, 50, 8, 0, 0, 185, 97, 169, 0, 0,
            35, 131, 131, 67, 101, 0, 97, 99, 101, 0, 47, 169, 67, 67, 169, 0, 0, 35, 131, 131,
            131, 131, 131, 131, 169, 101, 0, 47, 169, 67, 67, 70, 67, 101, 0, 97, 99, 99, 101, 115,
            115, 111, 114, 72, 255, 255, 120, 255, 255, 255, 255, 101, 0, 47, 70, 67, 101, 0, 97,
            99, 99, 101, 115, 115, 111, 114, 72, 255, 255, 120, 255, 255, 255, 255, 101, 0, 47,
            169,
        ],
        &[
            109, 97, 116, 101, 114, 105, 197, 197, 197, 197, 197, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
            0, 0, 0, 0, 197, 197, 197, 197, 197, 197, 197, 197, 197, 197, 200, 113, 28, 199, 113,
            28, 199, 1, 197, 197, 197, 197, 199, 197, 0, 4, 0, 126, 14, 0, 0, 0, 0, 0, 0, 0, 56,
            55, 55, 55, 49, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 222, 39, 0, 13, 59, 0,
            209, 222, 251, 40,
        ],
    ];
    for bytes in finds {
        levels_by_budget_read_back(bytes);
    }
}

/// The `valid_structure` fuzzer's third find (290,000 runs in): a file whose skin had as many
/// joints as the limit allowed, and whose unskinned parts each ride on a node of their own
/// (so each node is one more bone). It loaded; its export holds every bone in one skin and
/// was refused on reading back. The limit counts bones, what the file expands to: at the
/// model's bone count it loads and its export reads back, one below it is refused naming the
/// option.
#[test]
fn joint_limit_counts_the_bones_a_file_makes() {
    let bytes: &[u8] = &[
        36, 125, 35, 255, 255, 40, 255, 191, 255, 43, 41, 19, 67, 126, 126, 126, 1, 0, 1, 48, 126,
        50, 210, 0, 0, 185, 97, 0, 169, 0, 100, 134, 134, 134, 134, 166, 134, 134, 134, 134, 134,
        134, 141, 0, 0, 0, 0, 0, 0, 185, 97, 169, 87, 87, 87, 87, 87, 87, 87, 87, 87, 80, 79, 83,
        73, 84, 73, 87, 87, 0, 2, 0, 245, 245, 245, 245, 245, 245, 134, 134, 134, 134, 134, 134,
        134, 134, 43, 41, 19, 67, 126, 134, 169, 101, 134, 134, 65, 175, 166, 175, 87, 87, 0, 2, 0,
        245, 245, 245, 245, 245, 245, 134, 134, 134, 134, 134, 134, 134, 134, 134, 134, 134, 134,
        134, 134, 134, 134, 134, 134, 134, 134, 134, 134, 134, 134, 134, 6, 134, 134, 134, 134,
        134, 134, 134, 134, 134, 43, 41, 19, 67, 126, 134, 134, 134, 134, 134, 134, 255, 255, 255,
        14, 134, 232, 126, 126, 126, 126, 126, 126, 126, 50, 0, 0, 0, 185, 97, 0, 169, 0, 100, 185,
        97, 169, 87, 87, 87, 87, 87, 87, 87, 87, 87, 80, 79, 83, 73, 84, 73, 87, 87, 0, 2, 0, 245,
        245, 245, 245, 245, 245, 134, 134, 134, 134, 134, 134, 134, 134, 43, 41, 19, 67, 126, 134,
        169, 101, 134, 134, 65, 76, 80, 79, 83, 255, 214, 84, 73, 73, 127, 12, 46, 255, 120, 181,
        181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181,
        181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181, 181,
        181, 181, 181, 181, 181, 181, 181, 181, 181, 33, 251, 255, 255, 101, 100, 185, 97, 134,
        134, 0, 47, 171, 206, 1, 3, 239, 67, 91, 67, 101,
    ];
    let dir = tempfile::tempdir().unwrap();
    let file = wild::structure::structure_file(bytes);
    let limits = lodlab::import::validate::Limits::default();
    let (model, _) =
        lodlab::import::gltf::from_bytes("structure", file.clone(), dir.path(), &limits)
            .expect("loads under the default limits");
    let bones = model.skeleton.joints.len();
    let at = lodlab::import::validate::Limits {
        joints: bones,
        ..limits
    };
    let below = lodlab::import::validate::Limits {
        joints: bones - 1,
        ..limits
    };
    let Err(e) = lodlab::import::gltf::from_bytes("structure", file.clone(), dir.path(), &below)
    else {
        panic!("loaded one bone below the model's {bones}");
    };
    assert!(e.contains("bones") && e.contains("--limit joints"), "{e}");
    let (model, _) =
        lodlab::import::gltf::from_bytes("structure", file, dir.path(), &at).expect("loads");
    let export = lodlab::generate::glb::to_glb(&model);
    lodlab::import::gltf::from_bytes("export", export, dir.path(), &at)
        .expect("its export reads back under the same limits");
}

fn levels_by_budget_read_back(bytes: &[u8]) {
    let dir = tempfile::tempdir().unwrap();
    let limits = lodlab::import::validate::Limits::default();
    let file = wild::structure::structure_file(bytes);
    let (model, _) =
        lodlab::import::gltf::from_bytes("structure", file, dir.path(), &limits).expect("loads");
    let triangles = model.mesh.triangle_count() as u32;
    let options = lodlab::bake::character::lod::LodOptions {
        budgets: Some(vec![(triangles * 2 / 3).max(1), (triangles / 3).max(1), 1]),
        ..lodlab::bake::character::lod::LodOptions::from_pixels(
            1.5,
            lodlab::bake::character::lod::model_height(&model),
        )
    };
    for method in Method::ALL {
        let lods = bake_lods(&model, method, &options, &|_| {});
        let meshes = lodlab::app::commands::export::level_meshes(&model, &lods);
        assert!(!meshes.is_empty());
        for (k, mesh) in meshes.into_iter().enumerate() {
            let triangles = mesh.triangle_count();
            let one = lodlab::generate::glb::to_glb(&Model {
                mesh,
                ..model.clone()
            });
            let back = lodlab::import::gltf::from_bytes("level", one, dir.path(), &limits);
            assert!(
                back.is_ok(),
                "{method} level {k} of {}: {triangles} triangles: {:?}",
                lods.levels.len(),
                back.err()
            );
        }
    }
}

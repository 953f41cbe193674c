//! `lodlab export`: a character's levels, or a tree's clouds, as glTF files that other tools
//! accept and lodlab reads back as it drew them. The Khronos glTF-Validator runs where `tools/gltf` is installed
//! (`npm ci --prefix tools/gltf`; CI installs it and sets `LODLAB_REQUIRE_GLTF_TOOLS`).

use crate::common::{gltf_tools, validate};
use lodlab::bake::gpu_data::animation_space::AnimationSpaceMesh;
use lodlab::generate::glb::to_glb;
use lodlab::import::load_model;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn lodlab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args(args)
        .output()
        .expect("lodlab runs")
}

fn export(model: &str, method: &str, dir: &Path) -> Value {
    let cache = dir.join("cache");
    let out = lodlab(&[
        "export",
        model,
        "--method",
        method,
        "--out",
        dir.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn glb_json(path: &Path) -> Value {
    let bytes = std::fs::read(path).unwrap();
    let glb = gltf::binary::Glb::from_slice(&bytes).unwrap();
    serde_json::from_slice(&glb.json).unwrap()
}

#[test]
fn every_level_is_a_valid_glb_that_reads_back_as_exported() {
    let dir = tempfile::tempdir().unwrap();
    let e = export("walker", "as+is", dir.path());
    let levels = e["levels"].as_array().unwrap();
    assert!(levels.len() >= 5, "{} levels", levels.len());
    let mut files = Vec::new();
    let mut last_coverage = f64::MAX;
    for (k, l) in levels.iter().enumerate() {
        let file = PathBuf::from(l["file"].as_str().unwrap());
        // Each file reads back with the level's triangles and the model's clips.
        let m = load_model(file.to_str().unwrap()).unwrap();
        assert_eq!(
            m.mesh.triangle_count() as u64,
            l["triangles"].as_u64().unwrap()
        );
        assert_eq!(m.clips.len(), load_model("walker").unwrap().clips.len());
        assert!(
            m.materials[0].texture.is_some(),
            "level {k} keeps its texture"
        );
        let c = l["coverage"].as_f64().unwrap();
        assert!(c <= last_coverage, "coverage falls level by level");
        last_coverage = c;
        files.push(file);
    }
    assert_eq!(levels.last().unwrap()["coverage"], 0.0);

    // The all-levels file: MSFT_lod on the finest node naming the others, a coverage hint a
    // level, and lodlab (like any reader) takes the finest.
    let lod_file = PathBuf::from(e["lod_file"].as_str().unwrap());
    let json = glb_json(&lod_file);
    assert_eq!(json["extensionsUsed"], serde_json::json!(["MSFT_lod"]));
    let finest = json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n.get("extensions").is_some())
        .unwrap();
    let ids = finest["extensions"]["MSFT_lod"]["ids"].as_array().unwrap();
    assert_eq!(ids.len(), levels.len() - 1);
    let hints = finest["extras"]["MSFT_screencoverage"].as_array().unwrap();
    assert_eq!(hints.len(), levels.len());
    for id in ids {
        let node = &json["nodes"][id.as_u64().unwrap() as usize];
        assert!(node["mesh"].is_u64() && node["skin"] == finest["skin"]);
    }
    let m = load_model(lod_file.to_str().unwrap()).unwrap();
    assert_eq!(
        m.mesh.triangle_count() as u64,
        levels[0]["triangles"].as_u64().unwrap()
    );
    files.push(lod_file);

    if let Some(tools) = gltf_tools() {
        for (errors, warnings, report) in validate(&tools, &files) {
            assert_eq!((errors, warnings), (0, 0), "{report}");
        }
    }
}

/// Full detail exported and read back draws the same picture as the model itself.
#[test]
fn the_exported_full_detail_renders_as_the_original() {
    let dir = tempfile::tempdir().unwrap();
    let e = export("walker", "as", dir.path());
    let lod0 = e["levels"][0]["file"].as_str().unwrap().to_string();
    let shoot = |model: &str, name: &str| {
        let png = dir.path().join(name);
        let out = lodlab(&[
            "shot",
            "--scene",
            "study",
            "--model",
            model,
            "--count",
            "1",
            "--camera",
            "200,10,3.2,0,0.9,0",
            "--size",
            "200x300",
            "--frames",
            "1",
            "--out",
            png.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        image::open(&png).unwrap().to_rgba8()
    };
    let a = shoot("walker", "original.png");
    let b = shoot(&lod0, "exported.png");
    let off = a
        .pixels()
        .zip(b.pixels())
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 8))
        .count();
    assert!(off < 20, "{off} pixels differ");
}

/// Linear-blend skinning → animation space → linear-blend skinning gives the mesh back, and a
/// vertex of six influences keeps all six (two weight sets in glTF).
#[test]
fn linear_blend_skinning_survives_animation_space() {
    let model = crate::common::six_influence_model();
    let am = AnimationSpaceMesh::from_skinned(&model.mesh, &model.skeleton);
    let back = am.to_skinned(&model.skeleton);
    for v in 0..model.mesh.vertex_count() {
        assert!(back.positions[v].distance(model.mesh.positions[v]) < 1e-5);
        assert!(back.normals[v].distance(model.mesh.normals[v]) < 1e-5);
        let (a, b) = (model.mesh.influences_of(v), back.influences_of(v));
        assert_eq!(a.len(), 6);
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            assert_eq!(x.bone, y.bone);
            assert!((x.weight - y.weight).abs() < 1e-5);
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("six.glb");
    std::fs::write(&path, to_glb(&model)).unwrap();
    let e = export(path.to_str().unwrap(), "as", dir.path());
    assert_eq!(e["levels"][0]["max_influences"], 6);
    assert_eq!(e["levels"][0]["weight_sets"], 2);
    let json = glb_json(Path::new(e["levels"][0]["file"].as_str().unwrap()));
    let attributes = &json["meshes"][0]["primitives"][0]["attributes"];
    assert!(attributes.get("JOINTS_1").is_some() && attributes.get("WEIGHTS_1").is_some());
    if let Some(tools) = gltf_tools() {
        let file = PathBuf::from(e["levels"][0]["file"].as_str().unwrap());
        for (errors, _, report) in validate(&tools, &[file]) {
            assert_eq!(errors, 0, "{report}");
        }
    }
}

#[test]
fn export_refuses_a_missing_model_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = lodlab(&[
        "export",
        "no-such-model.glb",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

/// A tree goes out as its chain: the tree, then its clouds as skinned cards cut out of their
/// atlases (`MASK`) with the atlas's lighting as a normal map and a tangent a card vertex;
/// every file valid, read back with its level's triangles, clips and a cut-out material;
/// what glTF cannot draw said in a line.
#[test]
fn a_tree_exports_its_clouds_as_valid_gltf() {
    let dir = tempfile::tempdir().unwrap();
    let cache = crate::common::shared_cache();
    let out = lodlab(&[
        "export",
        "sapling",
        "--out",
        dir.path().to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let e: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(e["method"], "billboard clouds");
    let levels = e["levels"].as_array().unwrap();
    assert!(levels.len() >= 4, "{e}");
    assert_eq!(levels[0]["kind"], "full tree");
    let sapling = load_model("sapling").unwrap();
    let mut files = Vec::new();
    for (k, l) in levels.iter().enumerate() {
        let file = PathBuf::from(l["file"].as_str().unwrap());
        let m = load_model(file.to_str().unwrap()).unwrap();
        assert_eq!(
            m.mesh.triangle_count() as u64,
            l["triangles"].as_u64().unwrap(),
            "level {k}"
        );
        assert_eq!(m.clips.len(), sapling.clips.len(), "level {k}: the wind");
        assert_eq!(m.skeleton.bone_count(), sapling.skeleton.bone_count());
        assert!(
            m.materials
                .iter()
                .any(|m| m.cuts_out() && m.texture.is_some()),
            "level {k}: leaves cut out of a texture"
        );
        if k > 0 {
            // The atlas: cut out, lit through its normal map, its cards' tangents beside it.
            let json = glb_json(&file);
            let atlas = json["materials"]
                .as_array()
                .unwrap()
                .iter()
                .position(|m| m["alphaMode"] == "MASK")
                .unwrap();
            assert!(
                json["materials"][atlas]["normalTexture"].is_object(),
                "level {k}"
            );
            let primitive = json["meshes"][0]["primitives"]
                .as_array()
                .unwrap()
                .iter()
                .find(|p| p["material"] == atlas)
                .unwrap();
            assert!(primitive["attributes"]["TANGENT"].is_u64(), "level {k}");
            assert!(l["kind"].as_str().unwrap() != "full tree");
        }
        files.push(file);
    }
    // Each level comes in where its ε projects to the tolerance: hints falling to 0.
    let hints: Vec<f64> = levels
        .iter()
        .map(|l| l["coverage"].as_f64().unwrap())
        .collect();
    assert!(hints.windows(2).all(|w| w[1] < w[0]), "{hints:?}");
    assert_eq!(*hints.last().unwrap(), 0.0);
    let lod_file = PathBuf::from(e["lod_file"].as_str().unwrap());
    let json = glb_json(&lod_file);
    assert_eq!(json["extensionsUsed"], serde_json::json!(["MSFT_lod"]));
    assert_eq!(json["meshes"].as_array().unwrap().len(), levels.len());
    files.push(lod_file);
    // The impostor, where the chain has one, and levels heavier than a finer one are left
    // out, each in a line saying why; the levels written keep their chain's order.
    for line in e["left_out"].as_array().into_iter().flatten() {
        let line = line.as_str().unwrap();
        assert!(
            line.contains("impostor") || line.contains("triangles against"),
            "{line}"
        );
    }
    let chain: Vec<u64> = levels
        .iter()
        .map(|l| l["chain_level"].as_u64().unwrap())
        .collect();
    assert!(
        chain[0] == 0 && chain.windows(2).all(|w| w[1] > w[0]),
        "{chain:?}"
    );
    let triangles: Vec<u64> = levels
        .iter()
        .map(|l| l["triangles"].as_u64().unwrap())
        .collect();
    assert!(triangles.windows(2).all(|w| w[1] < w[0]), "{triangles:?}");
    if let Some(tools) = gltf_tools() {
        for (errors, warnings, report) in validate(&tools, &files) {
            assert_eq!((errors, warnings), (0, 0), "{report}");
        }
    }
}

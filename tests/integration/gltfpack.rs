//! Files as gltfpack writes them (quantised attributes with `KHR_mesh_quantization`, texture
//! coordinates mapped back by `KHR_texture_transform`, and with `-c` buffer views compressed
//! by `EXT_meshopt_compression`) open and draw as the originals do. gltfpack runs where
//! `tools/gltf` is installed (`npm ci --prefix tools/gltf`; CI installs it).

use crate::common::gltf_tools;
use std::path::{Path, PathBuf};
use std::process::Command;

fn gltfpack(tools: &Path, input: &Path, output: &Path, compress: bool) {
    let mut cmd = Command::new("node");
    cmd.arg(tools.join("node_modules/gltfpack/cli.js"))
        .arg("-i")
        .arg(input)
        .arg("-o")
        .arg(output);
    if compress {
        cmd.arg("-c");
    }
    let out = cmd.output().expect("node runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn used_extensions(path: &Path) -> Vec<String> {
    let bytes = std::fs::read(path).unwrap();
    let glb = gltf::binary::Glb::from_slice(&bytes).unwrap();
    let json: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
    json["extensionsUsed"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|e| e.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default()
}

/// `model` drawn by `lodlab shot` from a fixed camera.
fn picture(model: &Path, camera: &str, png: &Path) -> (image::RgbaImage, u64) {
    let out = Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args([
            "shot", "--scene", "study", "--count", "1", "--size", "240x240", "--frames", "1",
        ])
        .args(["--camera", camera, "--model"])
        .arg(model)
        .arg("--out")
        .arg(png)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    (
        image::open(png).unwrap().to_rgba8(),
        json["triangles"].as_u64().unwrap(),
    )
}

#[test]
fn gltfpack_output_opens_and_draws_as_the_original() {
    let Some(tools) = gltf_tools() else { return };
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut models: Vec<(PathBuf, &str)> =
        vec![(root.join("assets/walker.glb"), "200,10,3.2,0,0.9,0")];
    if let Some(fox) = crate::common::shared_model("Fox.glb") {
        models.push((fox, "60,15,2.2"));
    }
    for (model, camera) in &models {
        let (original, triangles) = picture(model, camera, &dir.path().join("original.png"));
        for compress in [false, true] {
            let packed = dir.path().join(format!("packed-{compress}.glb"));
            gltfpack(&tools, model, &packed, compress);
            let used = used_extensions(&packed);
            assert!(
                used.contains(&"KHR_mesh_quantization".to_string()),
                "{used:?}"
            );
            assert!(
                used.contains(&"KHR_texture_transform".to_string()),
                "{used:?}"
            );
            assert_eq!(
                used.contains(&"EXT_meshopt_compression".to_string()),
                compress,
                "{used:?}"
            );
            let (picture, drawn) = picture(&packed, camera, &dir.path().join("packed.png"));
            assert_eq!(drawn, triangles, "{}", model.display());
            // Quantisation moves a few edge pixels; the texture and the pose must not move.
            let off = original
                .pixels()
                .zip(picture.pixels())
                .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b[c]) > 24))
                .count();
            assert!(
                off < 150,
                "{} (-c {compress}): {off} pixels differ",
                model.display()
            );
        }
    }
}

/// A corrupt compressed view is one line naming the file and the view, not a panic.
#[test]
fn a_corrupt_compressed_view_is_one_line() {
    let Some(tools) = gltf_tools() else { return };
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let packed = dir.path().join("packed.glb");
    gltfpack(&tools, &root.join("assets/walker.glb"), &packed, true);
    let bytes = std::fs::read(&packed).unwrap();
    let broken = crate::common::edit_glb(&bytes, |json| {
        let views = json["bufferViews"].as_array_mut().unwrap();
        let view = views
            .iter_mut()
            .find(|v| v["extensions"]["EXT_meshopt_compression"].is_object())
            .unwrap();
        view["extensions"]["EXT_meshopt_compression"]["byteLength"] = 3.into();
    });
    let path = dir.path().join("broken.glb");
    std::fs::write(&path, broken).unwrap();
    let err = lodlab::import::load_model(path.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("broken.glb") && err.contains("bufferViews["),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}

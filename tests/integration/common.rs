//! Helpers the integration tests share: a tiny skinned model, and editing a `.glb`'s JSON to
//! make broken files.
#![allow(dead_code)]

use glam::{Vec2, Vec3};
use lodlab::generate::rig::{Pose, Rig, bake_clip, euler, wave};
use lodlab::model::{Influence, Material, Model, SkinnedMesh};
use serde_json::Value;
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A strip of four quads bent by two bones over one clip.
pub fn tiny_model() -> Model {
    let mut rig = Rig::default();
    let root = rig.bone("root", None, Vec3::ZERO);
    rig.bone("tip", Some(root), Vec3::new(0.0, 1.0, 0.0));
    let mut mesh = SkinnedMesh::default();
    mesh.influence_offsets.push(0);
    for row in 0..5 {
        for col in 0..2 {
            let y = row as f32 * 0.5;
            mesh.positions
                .push(Vec3::new(col as f32 * 0.5 - 0.25, y, 0.0));
            mesh.normals.push(Vec3::Z);
            mesh.uvs.push(Vec2::new(col as f32, y / 2.0));
            mesh.materials.push(0);
            let w = (y / 2.0).clamp(0.0, 1.0);
            if w > 0.0 {
                mesh.influences.push(Influence {
                    bone: 0,
                    weight: 1.0 - w,
                });
                mesh.influences.push(Influence { bone: 1, weight: w });
            } else {
                mesh.influences.push(Influence {
                    bone: 0,
                    weight: 1.0,
                });
            }
            mesh.influences.retain(|i| i.weight > 0.0);
            mesh.influence_offsets.push(mesh.influences.len() as u32);
        }
    }
    for row in 0..4u32 {
        let a = row * 2;
        mesh.indices.extend([a, a + 1, a + 3, a, a + 3, a + 2]);
    }
    let clip = bake_clip("bend", 1.0, 0.0, &rig, root, |ph| {
        let mut p = Pose::rest(2);
        p.rotate(1, euler(0.0, 0.0, 40.0 * wave(ph, 1.0, 0.0)));
        p
    });
    Model {
        name: "tiny".into(),
        mesh,
        skeleton: rig.skeleton(),
        clips: vec![clip],
        materials: vec![Material::opaque("grey", [0.6, 0.6, 0.6, 1.0], None)],
    }
}

/// A `.glb` of this JSON and binary chunk, padded as the format wants.
pub fn glb_of(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let mut j = json.to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let length = 12 + 8 + j.len() + bin.map_or(0, |b| 8 + b.len());
    gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: length as u32,
        },
        json: Cow::Owned(j),
        bin: bin.map(|b| Cow::Owned(b.to_vec())),
    }
    .to_vec()
    .unwrap()
}

/// Rewrites the JSON chunk of a `.glb`.
pub fn edit_glb(bytes: &[u8], edit: impl FnOnce(&mut Value)) -> Vec<u8> {
    let glb = gltf::binary::Glb::from_slice(bytes).expect("valid glb");
    let mut json: Value = serde_json::from_slice(&glb.json).unwrap();
    edit(&mut json);
    glb_of(&serde_json::to_vec(&json).unwrap(), glb.bin.as_deref())
}

/// A strip bent by a chain of six bones, every vertex weighted by all six (so the file needs
/// JOINTS_1/WEIGHTS_1 as well as JOINTS_0/WEIGHTS_0).
pub fn six_influence_model() -> Model {
    let mut rig = Rig::default();
    let mut parent = None;
    for k in 0..6 {
        parent = Some(rig.bone(
            &format!("b{k}"),
            parent,
            Vec3::new(0.0, 0.4 * k as f32, 0.0),
        ));
    }
    let mut mesh = SkinnedMesh::default();
    mesh.influence_offsets.push(0);
    let rows = 13;
    for row in 0..rows {
        for col in 0..2 {
            let y = row as f32 * 0.2;
            mesh.positions
                .push(Vec3::new(col as f32 * 0.3 - 0.15, y, 0.0));
            mesh.normals.push(Vec3::Z);
            mesh.uvs.push(Vec2::new(col as f32, y / 2.4));
            mesh.materials.push(0);
            let raw: Vec<f32> = (0..6)
                .map(|k| (-((y - 0.4 * k as f32) / 0.5).powi(2)).exp() + 0.01)
                .collect();
            let total: f32 = raw.iter().sum();
            for (k, w) in raw.iter().enumerate() {
                mesh.influences.push(Influence {
                    bone: k as u32,
                    weight: w / total,
                });
            }
            mesh.influence_offsets.push(mesh.influences.len() as u32);
        }
    }
    for row in 0..rows as u32 - 1 {
        let a = row * 2;
        mesh.indices.extend([a, a + 1, a + 3, a, a + 3, a + 2]);
    }
    let clip = bake_clip("curl", 2.0, 0.0, &rig, 0, |ph| {
        let mut p = Pose::rest(6);
        for k in 1..6 {
            p.rotate(k, euler(0.0, 0.0, 20.0 * wave(ph, 1.0, 0.1 * k as f32)));
        }
        p
    });
    Model {
        name: "six".into(),
        mesh,
        skeleton: rig.skeleton(),
        clips: vec![clip],
        materials: vec![Material::opaque("white", [1.0; 4], None)],
    }
}

/// `tools/gltf` with its packages installed (the Khronos glTF-Validator and gltfpack), or
/// `None`, with one line saying so, where they are not and CI does not require them
/// (`LODLAB_REQUIRE_GLTF_TOOLS`, which `.ci/run` sets after `npm ci --prefix tools/gltf`).
pub fn gltf_tools() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/gltf");
    let installed = dir.join("node_modules/gltf-validator").is_dir()
        && dir.join("node_modules/gltfpack").is_dir()
        && Command::new("node").arg("--version").output().is_ok();
    if installed {
        return Some(dir);
    }
    assert!(
        std::env::var_os("LODLAB_REQUIRE_GLTF_TOOLS").is_none(),
        "LODLAB_REQUIRE_GLTF_TOOLS is set but tools/gltf is not installed (npm ci --prefix tools/gltf)"
    );
    eprintln!("skipped: the glTF tools are not installed (npm ci --prefix tools/gltf)");
    None
}

/// `../shared/models/NAME` (the models from elsewhere beside the checkout), or `None`, with one
/// line saying so, where it is absent and CI does not require it
/// (`LODLAB_REQUIRE_SHARED_MODELS`, which `.ci/run` sets).
pub fn shared_model(name: &str) -> Option<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/models")
        .join(name);
    if path.is_file() {
        return Some(path);
    }
    assert!(
        std::env::var_os("LODLAB_REQUIRE_SHARED_MODELS").is_none(),
        "LODLAB_REQUIRE_SHARED_MODELS is set but {} is absent",
        path.display()
    );
    eprintln!("skipped: {} is absent", path.display());
    None
}

/// The Khronos glTF-Validator's verdict on each file (`tools` from [`gltf_tools`]): errors,
/// warnings, and its whole report line.
pub fn validate(tools: &Path, files: &[PathBuf]) -> Vec<(u64, u64, Value)> {
    let out = Command::new("node")
        .arg(tools.join("validate.js"))
        .args(files)
        .output()
        .expect("node runs");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| {
            let v: Value = serde_json::from_str(l).unwrap();
            (
                v["errors"].as_u64().unwrap(),
                v["warnings"].as_u64().unwrap(),
                v,
            )
        })
        .collect()
}

/// One bake cache for every test of a `cargo test` run whose subject is not the cache itself:
/// the default trees' billboard-cloud chains and the characters' levels are baked once for the
/// whole suite instead of once per test (a tree chain takes about 12 s here on lavapipe, and
/// half a dozen tests draw the same trees).
///
/// The folder is named after the build of the `lodlab` binary (its size and modification
/// time; cargo relinks it whenever the library changes), so a rebuilt crate never reads what
/// an earlier build baked, even where the change forgot to bump the cache format.
/// `LODLAB_TEST_CACHE` names another folder: `.ci/run` sets it, a fresh clone's build being
/// new anyway, so that its check of the window after the tests finds the scene baked.
pub fn shared_cache() -> PathBuf {
    if let Some(dir) = std::env::var_os("LODLAB_TEST_CACHE") {
        let dir = PathBuf::from(dir);
        std::fs::create_dir_all(&dir).unwrap();
        return dir;
    }
    let exe = Path::new(env!("CARGO_BIN_EXE_lodlab"));
    let meta = std::fs::metadata(exe).expect("the lodlab binary is built for the tests");
    let stamp = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "bake-cache-{:x}-{:x}",
        meta.len(),
        stamp
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The one device the tests share (lavapipe in CI): made once per run, not once per test.
/// A test that provokes device errors makes its own.
pub fn gpu() -> &'static lodlab::render::Gpu {
    static GPU: std::sync::OnceLock<lodlab::render::Gpu> = std::sync::OnceLock::new();
    GPU.get_or_init(|| lodlab::render::Gpu::headless().expect("a GPU adapter (lavapipe in CI)"))
}

/// `tools/web` with puppeteer-core installed and Debian's Chromium (or `$LODLAB_CHROMIUM`), or
/// `None`, with one line saying so, where either is missing and CI does not require them
/// (`LODLAB_REQUIRE_BROWSER`, which `.ci/run` sets after installing both).
pub fn browser_tools() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/web");
    let chromium = std::env::var_os("LODLAB_CHROMIUM")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/bin/chromium"));
    let installed = dir.join("node_modules/puppeteer-core").is_dir()
        && dir.join("node_modules/three").is_dir()
        && chromium.is_file()
        && Command::new("node").arg("--version").output().is_ok();
    if installed {
        return Some(dir);
    }
    assert!(
        std::env::var_os("LODLAB_REQUIRE_BROWSER").is_none(),
        "LODLAB_REQUIRE_BROWSER is set but the browser tools are missing (apt install chromium; \
         npm ci --prefix tools/web)"
    );
    eprintln!("skipped: no headless browser (apt install chromium; npm ci --prefix tools/web)");
    None
}

/// The web viewer built for the browser (lodlab.js and lodlab_bg.wasm, from
/// `tools/web/build-wasm.sh DIR`) in `$LODLAB_WEB_PKG`, or `None`, with one line saying so, where
/// it is not and CI does not require it (`LODLAB_REQUIRE_BROWSER`).
pub fn web_package() -> Option<PathBuf> {
    let dir = std::env::var_os("LODLAB_WEB_PKG").map(PathBuf::from);
    if let Some(dir) = dir.filter(|d| d.join("lodlab_bg.wasm").is_file()) {
        return Some(dir);
    }
    assert!(
        std::env::var_os("LODLAB_REQUIRE_BROWSER").is_none(),
        "LODLAB_REQUIRE_BROWSER is set but LODLAB_WEB_PKG names no built web viewer \
         (tools/web/build-wasm.sh DIR; LODLAB_WEB_PKG=DIR)"
    );
    eprintln!("skipped: no web viewer built (tools/web/build-wasm.sh DIR; LODLAB_WEB_PKG=DIR)");
    None
}

/// Runs the lodlab binary with `args`.
pub fn lodlab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args(args)
        .output()
        .expect("lodlab runs")
}

/// Fails, with what lodlab printed, unless it succeeded.
pub fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stderr),
        String::from_utf8_lossy(&o.stdout)
    );
}

/// A study plan over a bent cylinder written into `dir` (cylinder.glb and plan.toml), its
/// lines after `models` being `rest` (pairs, tolerances, participants, clip size…).
pub fn cylinder_plan(dir: &Path, rest: &str) -> PathBuf {
    let model = dir.join("cylinder.glb");
    std::fs::write(
        &model,
        lodlab::generate::glb::to_glb(&lodlab::generate::cylinder::bent_cylinder(16, 8)),
    )
    .unwrap();
    let plan = dir.join("plan.toml");
    std::fs::write(&plan, format!("models = [\"{}\"]\n{rest}", model.display())).unwrap();
    plan
}

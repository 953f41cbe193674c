//! Characters exported as one mesh and one skin per part over one skeleton (issue "real
//! assets, third round"): the skins' shared joints are one bone each, counted once against
//! the joint limit, and a part bound in a space of its own is skinned where it belongs.

use crate::common::{gltf_tools, lodlab, validate};
use lodlab::generate::wild::parts::parts_on_one_skeleton;
use lodlab::import::{ImportOptions, import, validate::Limits};
use lodlab::model::Model;
use std::path::Path;

/// The model's vertices posed at `t` seconds into its first clip, in the scene's units.
fn posed(m: &Model, t: f32) -> Vec<glam::Vec3> {
    let g = lodlab::anim::bone_matrices(&m.skeleton, m.clips.first(), t);
    lodlab::anim::linear_blend_skinning(&m.mesh, &m.skeleton, &g)
}

/// Whether every point of `a` lies within 1 mm of a point of `b` and the other way round:
/// the same surface, whatever the vertices' order and the parts they were split into.
fn same_points(a: &[glam::Vec3], b: &[glam::Vec3]) -> bool {
    let cell = |p: glam::Vec3| (p / 0.01).floor().as_ivec3();
    let covered = |from: &[glam::Vec3], to: &[glam::Vec3]| {
        let mut grid: std::collections::HashMap<glam::IVec3, Vec<glam::Vec3>> = Default::default();
        for &p in to {
            grid.entry(cell(p)).or_default().push(p);
        }
        from.iter().all(|&p| {
            let c = cell(p);
            (-1..=1).any(|x| {
                (-1..=1).any(|y| {
                    (-1..=1).any(|z| {
                        grid.get(&(c + glam::IVec3::new(x, y, z)))
                            .is_some_and(|v| v.iter().any(|q| q.distance(p) < 1e-3))
                    })
                })
            })
        })
    };
    covered(a, b) && covered(b, a)
}

fn write(doc: &lodlab::generate::wild::file::Document, dir: &Path, name: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, doc.to_glb()).unwrap();
    path.to_str().unwrap().to_string()
}

/// `lodlab export MODEL` into `dir`: the files of its levels, full detail first.
fn export(model: &str, dir: &Path) -> Vec<std::path::PathBuf> {
    let out = lodlab(&[
        "export",
        model,
        "--out",
        dir.join("export").to_str().unwrap(),
        "--cache",
        dir.join("cache").to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let e: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    e["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["file"].as_str().unwrap().into())
        .collect()
}

/// No skin of the glTF file `file` lists a node twice.
fn assert_each_node_once(file: &Path) {
    let doc = gltf::Gltf::from_slice(&std::fs::read(file).unwrap()).unwrap();
    assert!(doc.skins().next().is_some());
    for skin in doc.skins() {
        let mut nodes: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let n = nodes.len();
        nodes.sort_unstable();
        nodes.dedup();
        assert_eq!(nodes.len(), n, "a node listed twice in a skin");
    }
}

#[test]
fn skins_over_one_skeleton_share_its_bones() {
    let walker = lodlab::import::load_model("walker").unwrap();
    let bones = walker.skeleton.bone_count();
    let dir = tempfile::tempdir().unwrap();
    // Twenty skins of every joint: 20 × 25 joints listed, 25 nodes. A limit of four times
    // the bones refused them when every skin's joints were counted apart.
    let twenty = write(
        &parts_on_one_skeleton(&walker, 20, false),
        dir.path(),
        "twenty.glb",
    );
    let mut limits = Limits::default();
    limits.set(&format!("joints={}", 4 * bones)).unwrap();
    let options = ImportOptions {
        limits,
        ..Default::default()
    };
    let m = import(&twenty, &options).unwrap().model;
    assert_eq!(m.skeleton.bone_count(), bones);
    assert_eq!(m.mesh.triangle_count(), walker.mesh.triangle_count());
    // Four skins, each part in a space of its own that its inverse bind matrices undo.
    let four = write(
        &parts_on_one_skeleton(&walker, 4, true),
        dir.path(),
        "four.glb",
    );
    let m4 = import(&four, &options).unwrap().model;
    assert_eq!(m4.skeleton.bone_count(), bones, "one bone a node");
    let mut joints = m4.skeleton.joints.clone();
    joints.sort_unstable();
    joints.dedup();
    assert_eq!(joints.len(), bones);
    for t in [0.0, 0.37] {
        assert!(same_points(&posed(&walker, t), &posed(&m4, t)), "at {t} s");
    }
    // Exported, one joint a node: what glTF-Validator asks (DUPLICATE_ELEMENTS before).
    let files = export(&four, dir.path());
    assert_each_node_once(&files[0]);
    if let Some(tools) = gltf_tools() {
        for (errors, _, report) in validate(&tools, &files) {
            assert_eq!(errors, 0, "{report}");
        }
    }
}

/// A node of two skins bound in two different poses keeps a bone for each; exported, the
/// second is a child node of the first, so that no skin lists a node twice.
#[test]
fn a_node_bound_two_ways_exports_one_joint_a_node() {
    let walker = lodlab::import::load_model("walker").unwrap();
    let mut doc = parts_on_one_skeleton(&walker, 2, false);
    // The second skin's first joint bound a little elsewhere: no one transform for the skin.
    let ibm = &mut doc.skins[1].inverse_bind[0];
    *ibm = glam::Mat4::from_translation(glam::Vec3::new(0.0, 0.05, 0.0)) * *ibm;
    let dir = tempfile::tempdir().unwrap();
    let path = write(&doc, dir.path(), "two-poses.glb");
    let m = import(&path, &ImportOptions::default()).unwrap().model;
    assert!(m.skeleton.bone_count() > walker.skeleton.bone_count());
    let file = export(&path, dir.path()).swap_remove(0);
    assert_each_node_once(&file);
    // Read back, the exported model poses as the file did.
    let back = lodlab::import::load_model(file.to_str().unwrap()).unwrap();
    assert!(same_points(&posed(&m, 0.2), &posed(&back, 0.2)));
    if let Some(tools) = gltf_tools() {
        for (errors, _, report) in validate(&tools, &[file]) {
            assert_eq!(errors, 0, "{report}");
        }
    }
}

/// A rotation that is not a unit quaternion (one file had a length of 11.15) is read as the
/// rotation it stands for, with a line saying so.
#[test]
fn a_rotation_of_length_eleven_is_normalised_with_a_warning() {
    let walker = lodlab::import::load_model("walker").unwrap();
    let mut doc = parts_on_one_skeleton(&walker, 1, false);
    let plain = doc.to_glb();
    let joint = doc.skins[0].joints[3];
    let r = doc.nodes[joint].rest.rotation;
    doc.nodes[joint].rest.rotation = glam::Quat::from_xyzw(r.x, r.y, r.z, r.w) * 11.15;
    let limits = Limits::default();
    let read = |bytes: Vec<u8>| {
        lodlab::import::gltf::from_bytes("bird", bytes, Path::new("."), &limits).unwrap()
    };
    let (long, warnings) = read(doc.to_glb());
    let said: Vec<&String> = warnings
        .iter()
        .filter(|w| w.contains("length 11.150"))
        .collect();
    assert_eq!(said.len(), 1, "{warnings:?}");
    let (unit, warnings) = read(plain);
    assert!(
        !warnings.iter().any(|w| w.contains("quaternion")),
        "{warnings:?}"
    );
    assert!(same_points(&posed(&long, 0.3), &posed(&unit, 0.3)));
}

//! glTF features end to end through files: several JOINTS_n/WEIGHTS_n sets, STEP and
//! CUBICSPLINE and scale channels, several primitives merged, UV seams kept when welding.

use crate::common::{edit_glb, six_influence_model, tiny_model};
use glam::{Quat, Vec3, Vec4};
use lodlab::anim::linear_blend_skinning;
use lodlab::bake::gpu_data::animation_space::AnimationSpaceMesh;
use lodlab::generate::glb::to_glb;
use lodlab::import::gltf::load;
use lodlab::model::{Channel, ChannelTarget, Interpolation};

fn write(bytes: &[u8], name: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    (dir, p)
}

#[test]
fn more_than_four_influences_through_two_sets() {
    let original = six_influence_model();
    let bytes = to_glb(&original);
    let json = gltf::binary::Glb::from_slice(&bytes)
        .unwrap()
        .json
        .into_owned();
    let text = String::from_utf8(json).unwrap();
    assert!(text.contains("JOINTS_1") && text.contains("WEIGHTS_1"));
    let (_dir, p) = write(&bytes, "six.glb");
    let m = load(&p).unwrap();
    for v in 0..m.mesh.vertex_count() {
        let inf = m.mesh.influences_of(v);
        assert_eq!(inf.len(), 6, "vertex {v}");
        let sum: f32 = inf.iter().map(|i| i.weight).sum();
        assert!((sum - 1.0).abs() < 1e-5);
    }
    let am = AnimationSpaceMesh::from_skinned(&m.mesh, &m.skeleton);
    let g = lodlab::anim::bone_matrices(&m.skeleton, Some(&m.clips[0]), 0.7);
    let (a, _) = am.evaluate(&g);
    for (x, y) in a
        .iter()
        .zip(linear_blend_skinning(&m.mesh, &m.skeleton, &g))
    {
        assert!(x.distance(y) < 1e-5);
    }
}

#[test]
fn step_cubic_spline_and_scale_channels_from_a_file() {
    let mut m = tiny_model();
    let step = Channel {
        node: 1,
        target: ChannelTarget::Translation,
        interpolation: Interpolation::Step,
        times: vec![0.0, 0.5, 1.0],
        values: vec![
            Vec4::new(0.0, 1.0, 0.0, 0.0),
            Vec4::new(0.3, 1.0, 0.0, 0.0),
            Vec4::new(0.0, 1.0, 0.0, 0.0),
        ],
    };
    let q0 = Quat::IDENTITY;
    let q1 = Quat::from_rotation_z(0.8);
    let cubic = Channel {
        node: 1,
        target: ChannelTarget::Rotation,
        interpolation: Interpolation::CubicSpline,
        times: vec![0.0, 1.0],
        values: vec![
            Vec4::ZERO,
            Vec4::from(q0),
            Vec4::ZERO,
            Vec4::ZERO,
            Vec4::from(q1),
            Vec4::ZERO,
        ],
    };
    let scale = Channel {
        node: 0,
        target: ChannelTarget::Scale,
        interpolation: Interpolation::Linear,
        times: vec![0.0, 1.0],
        values: vec![Vec4::new(1.0, 1.0, 1.0, 0.0), Vec4::new(1.0, 2.0, 1.0, 0.0)],
    };
    m.clips[0].channels = vec![step, cubic, scale];
    m.clips[0].duration = 1.0;
    let (_dir, p) = write(&to_glb(&m), "channels.glb");
    let back = load(&p).unwrap();
    let c = &back.clips[0];
    let kinds: Vec<(ChannelTarget, Interpolation)> = c
        .channels
        .iter()
        .map(|ch| (ch.target, ch.interpolation))
        .collect();
    assert_eq!(
        kinds,
        vec![
            (ChannelTarget::Translation, Interpolation::Step),
            (ChannelTarget::Rotation, Interpolation::CubicSpline),
            (ChannelTarget::Scale, Interpolation::Linear),
        ]
    );
    let pose = |t: f32| lodlab::anim::local_pose(&back.skeleton, Some(c), t);
    // STEP holds the key before.
    assert_eq!(pose(0.49)[1].translation, Vec3::new(0.0, 1.0, 0.0));
    assert_eq!(pose(0.51)[1].translation, Vec3::new(0.3, 1.0, 0.0));
    // CUBICSPLINE with zero tangents eases: at a quarter of the way it has turned less than a
    // quarter of the angle, and it ends exactly on the key.
    let (_, angle) = pose(0.25)[1].rotation.to_axis_angle();
    assert!(angle > 0.01 && angle < 0.8 * 0.25, "{angle}");
    assert!(pose(1.0)[1].rotation.angle_between(q1) < 1e-5);
    // Scale interpolates linearly.
    assert!((pose(0.5)[0].scale.y - 1.5).abs() < 1e-6);
}

#[test]
fn primitives_of_one_skin_are_merged_with_their_materials() {
    let bytes = edit_glb(&to_glb(&tiny_model()), |j| {
        let prim = j["meshes"][0]["primitives"][0].clone();
        let mut second = prim.clone();
        second["material"] = serde_json::json!(1);
        j["meshes"][0]["primitives"] = serde_json::json!([prim, second]);
        let red = serde_json::json!({"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.0, 0.0, 1.0]}});
        j["materials"].as_array_mut().unwrap().push(red);
    });
    let (_dir, p) = write(&bytes, "two.glb");
    let m = load(&p).unwrap();
    assert_eq!(m.mesh.vertex_count(), 20);
    assert_eq!(m.mesh.triangle_count(), 16);
    assert!(m.mesh.indices[24..].iter().all(|&i| i >= 10));
    // Two plain colours: one palette texture, each primitive's vertices on its own colour.
    assert_eq!(m.materials.len(), 1);
    assert_eq!(
        m.materials[0].name,
        lodlab::import::palette::PALETTE_MATERIAL
    );
    let t = m.materials[0].texture.as_ref().unwrap();
    let colour = |v: usize| {
        let uv = m.mesh.uvs[v];
        let (x, y) = (
            (uv.x * t.width as f32) as u32,
            (uv.y * t.height as f32) as u32,
        );
        let i = ((y * t.width + x) * 4) as usize;
        [t.pixels[i], t.pixels[i + 1], t.pixels[i + 2]]
    };
    assert!((10..20).all(|v| colour(v) == [255, 0, 0]));
    assert!((0..10).all(|v| colour(v) != [255, 0, 0] && colour(v) == colour(0)));
}

#[test]
fn welding_keeps_uv_seams_split() {
    let Some(fox) = crate::common::shared_model("Fox.glb") else {
        return;
    };
    let m = load(&fox).unwrap();
    let groups = lodlab::geometry::weld::position_groups(&m.mesh.positions, 1e-6);
    let positions = *groups.iter().max().unwrap() as usize + 1;
    // Fewer positions than vertices: the extra vertices are the two sides of UV seams.
    assert!(positions < m.mesh.vertex_count());
    let mut uv_of: std::collections::HashMap<u32, glam::Vec2> = Default::default();
    let mut seam_vertices = 0;
    for (v, &g) in groups.iter().enumerate() {
        match uv_of.get(&g) {
            Some(uv) if *uv != m.mesh.uvs[v] => seam_vertices += 1,
            Some(_) => panic!("vertex {v} duplicates another with the same UV: not welded"),
            None => {
                uv_of.insert(g, m.mesh.uvs[v]);
            }
        }
    }
    assert!(seam_vertices > 0);
    // Both sides of a seam got the same computed normal.
    let mut normal_of: std::collections::HashMap<u32, glam::Vec3> = Default::default();
    for (v, &g) in groups.iter().enumerate() {
        let n = *normal_of.entry(g).or_insert(m.mesh.normals[v]);
        assert!(n.dot(m.mesh.normals[v]) > 0.9999);
    }
}

/// A model of `tiny_model`'s mesh with one textured material whose alpha is 0.4 on one half
/// of the texture and 1 on the other.
fn half_transparent(mode: lodlab::model::AlphaMode, cutoff: f32) -> lodlab::model::Model {
    let mut m = tiny_model();
    let mut pixels = Vec::new();
    for i in 0..16 {
        pixels.extend_from_slice(&[200, 120, 60, if i % 2 == 0 { 102 } else { 255 }]);
    }
    let texture = lodlab::model::Rgba8Image {
        width: 4,
        height: 4,
        pixels,
    };
    m.materials = vec![lodlab::model::Material {
        alpha_mode: mode,
        alpha_cutoff: cutoff,
        double_sided: mode != lodlab::model::AlphaMode::Opaque,
        ..lodlab::model::Material::opaque("half", [1.0; 4], Some(texture))
    }];
    m
}

/// alphaMode, alphaCutoff and doubleSided survive a file both ways, and only MASK and BLEND
/// cut anything out: an OPAQUE material's alpha is ignored however low it is.
#[test]
fn alpha_modes_round_trip_and_only_masks_cut_out() {
    use lodlab::bake::foliage::billboard::is_tree;
    use lodlab::bake::gpu_data::materials::MaterialLayers;
    use lodlab::model::AlphaMode;
    for (mode, cutoff, cuts, name) in [
        (AlphaMode::Opaque, 0.5, false, "OPAQUE"),
        (AlphaMode::Mask, 0.5, true, "MASK"),
        (AlphaMode::Mask, 0.3, false, "MASK"),
        (AlphaMode::Blend, 0.5, true, "BLEND"),
    ] {
        let model = half_transparent(mode, cutoff);
        let bytes = to_glb(&model);
        let glb = gltf::binary::Glb::from_slice(&bytes).unwrap();
        let json: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
        let material = &json["materials"][0];
        assert_eq!(material["alphaMode"].as_str().unwrap_or("OPAQUE"), name);
        assert_eq!(
            material["doubleSided"].as_bool().unwrap_or(false),
            mode != AlphaMode::Opaque
        );
        let (_dir, path) = write(&bytes, "alpha.glb");
        let back = load(&path).unwrap();
        let m = &back.materials[0];
        assert_eq!(
            (m.alpha_mode, m.double_sided),
            (mode, mode != AlphaMode::Opaque)
        );
        if mode == AlphaMode::Mask {
            assert_eq!(m.alpha_cutoff, cutoff);
        }
        // Alpha 0.4 is cut out under a 0.5 mask or a blend, kept under a 0.3 mask or opaque.
        assert_eq!(m.cuts_out(), cuts, "{mode:?} at {cutoff}");
        // Held still and all cut out, it is foliage (`bake::foliage::classify`).
        let still = lodlab::model::Model {
            clips: Vec::new(),
            ..back.clone()
        };
        assert_eq!(is_tree(&still), cuts);
        // The layer the shaders test at one half says the same.
        let layers = MaterialLayers::bake(&back.materials);
        let below_half = layers.mips[0].chunks_exact(4).any(|p| p[3] < 128);
        assert_eq!(below_half, cuts, "{mode:?} at {cutoff}");
    }
}

/// The generated trees' foliage is written MASK and double-sided, so other viewers cut the
/// leaves out instead of showing opaque squares; the bark stays opaque.
#[test]
fn generated_foliage_is_written_as_a_two_sided_mask() {
    let tree = lodlab::import::load_model("sapling").unwrap();
    let bytes = to_glb(&tree);
    let glb = gltf::binary::Glb::from_slice(&bytes).unwrap();
    let json: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
    let materials = json["materials"].as_array().unwrap();
    let leaves = materials.iter().find(|m| m["name"] == "leaves").unwrap();
    assert_eq!(leaves["alphaMode"], "MASK");
    assert_eq!(leaves["doubleSided"], true);
    let bark = materials.iter().find(|m| m["name"] == "bark").unwrap();
    assert!(bark.get("alphaMode").is_none_or(|m| m == "OPAQUE"));
    if let Some(tools) = crate::common::gltf_tools() {
        let (_dir, path) = write(&bytes, "sapling.glb");
        for (errors, _, report) in crate::common::validate(&tools, &[path]) {
            assert_eq!(errors, 0, "{report}");
        }
    }
}

/// `tiny_model`'s file with its skin, skin attributes and clips taken out: a static prop.
fn prop_glb() -> Vec<u8> {
    edit_glb(&to_glb(&tiny_model()), |j| {
        let root = j.as_object_mut().unwrap();
        root.remove("skins");
        root.remove("animations");
        for n in j["nodes"].as_array_mut().unwrap() {
            n.as_object_mut().unwrap().remove("skin");
        }
        for m in j["meshes"].as_array_mut().unwrap() {
            for p in m["primitives"].as_array_mut().unwrap() {
                let a = p["attributes"].as_object_mut().unwrap();
                a.retain(|k, _| !k.starts_with("JOINTS_") && !k.starts_with("WEIGHTS_"));
            }
        }
        // The mesh node moved and turned: the prop keeps the placement.
        let mesh_node = j["nodes"]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .find(|n| n.get("mesh").is_some())
            .unwrap();
        let h = std::f32::consts::FRAC_1_SQRT_2;
        mesh_node["rotation"] = serde_json::json!([0.0, h, 0.0, h]);
    })
}

/// An unskinned mesh is a character of one bone: it loads with its triangles turned by its
/// node, simplifies, and draws.
#[test]
fn an_unskinned_mesh_loads_as_a_one_bone_prop() {
    let original = tiny_model();
    let (dir, path) = write(&prop_glb(), "prop.glb");
    let prop = load(&path).unwrap();
    assert_eq!(prop.skeleton.bone_count(), 1);
    assert!(prop.clips.is_empty());
    assert_eq!(prop.mesh.triangle_count(), original.mesh.triangle_count());
    assert!(
        prop.mesh
            .influences
            .iter()
            .all(|i| i.bone == 0 && i.weight == 1.0)
    );
    // Turned a quarter about y: the strip's x extent became its z extent.
    let extent = |m: &lodlab::model::Model| {
        let b = lodlab::model::Bounds::of(m.mesh.positions.iter().copied()).unwrap();
        b.size()
    };
    let (a, b) = (extent(&original), extent(&prop));
    assert!((a.x / a.y - b.z / b.y).abs() < 1e-3, "{a} {b}");
    let lods = lodlab::bake::character::lod::bake_lods(
        &prop,
        lodlab::bake::character::simplify::Method::AnimationSpace,
        &lodlab::runtime::levels::runtime_options(&prop, None),
        &|_| {},
    );
    assert!(!lods.levels.is_empty());
    let png = dir.path().join("prop.png");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args([
            "shot", "--scene", "study", "--count", "1", "--size", "96x96", "--frames", "1",
        ])
        .args(["--method", "as", "--model"])
        .arg(&path)
        .arg("--out")
        .arg(&png)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(json["triangles"].as_u64().unwrap() > 0);
}

/// Morph targets are left out with a warning; the base shape loads.
#[test]
fn morph_targets_are_left_out_with_a_warning() {
    let glb = edit_glb(&to_glb(&tiny_model()), |j| {
        let p = &mut j["meshes"][0]["primitives"][0];
        let position = p["attributes"]["POSITION"].clone();
        p["targets"] = serde_json::json!([{ "POSITION": position }]);
        j["meshes"][0]["weights"] = serde_json::json!([0.0]);
    });
    let (_dir, path) = write(&glb, "morphs.glb");
    let m = load(&path).unwrap();
    assert_eq!(m.mesh.triangle_count(), tiny_model().mesh.triangle_count());
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args(["bake", "--methods", "as"])
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("morphs.glb") && err.contains("morph targets are left out"),
        "{err}"
    );
}

/// Two skins: the second mesh's skin lists the same joints in reverse order. Both meshes load,
/// their joints merged (the same node with the same bind matrix is one bone), each vertex on
/// the bone its own skin names.
#[test]
fn several_skins_load_with_their_joints_merged() {
    let original = tiny_model();
    let glb = edit_glb(&to_glb(&original), |j| {
        let mut skin = j["skins"][0].clone();
        let joints: Vec<serde_json::Value> = skin["joints"]
            .as_array()
            .unwrap()
            .iter()
            .rev()
            .cloned()
            .collect();
        skin["joints"] = joints.into();
        // No inverse bind matrices in the copy: identities, unlike the first skin's.
        skin.as_object_mut().unwrap().remove("inverseBindMatrices");
        j["skins"].as_array_mut().unwrap().push(skin);
        let mesh_node = j["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .find(|n| n.get("mesh").is_some())
            .unwrap()
            .clone();
        let mut second = mesh_node.clone();
        second["skin"] = 1.into();
        // A mesh of its own (a mesh is read once however many nodes use it).
        let mesh = j["meshes"][0].clone();
        j["meshes"].as_array_mut().unwrap().push(mesh);
        second["mesh"] = 1.into();
        let nodes = j["nodes"].as_array_mut().unwrap();
        nodes.push(second);
        let index = nodes.len() - 1;
        j["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(index.into());
    });
    let (_dir, path) = write(&glb, "two-skins.glb");
    let m = load(&path).unwrap();
    assert_eq!(m.mesh.triangle_count(), 2 * original.mesh.triangle_count());
    let joints = original.skeleton.joints.len();
    // The second skin's identity bind matrices differ from the first skin's except where
    // those are identities already: only the differing joints become bones of their own.
    let differing = original
        .skeleton
        .inverse_bind
        .iter()
        .filter(|m| !m.abs_diff_eq(glam::Mat4::IDENTITY, 1e-5))
        .count();
    assert!(differing > 0);
    assert_eq!(m.skeleton.joints.len(), joints + differing);
    let n = original.mesh.vertex_count();
    for v in 0..n {
        let (a, b) = (m.mesh.influences_of(v), m.mesh.influences_of(v + n));
        assert_eq!(a.len(), b.len());
        for x in a {
            // The same JOINTS index names, in the reversed skin, the mirrored joint's node,
            // with the second skin's (identity) bind matrix.
            let node = m.skeleton.joints[joints - 1 - x.bone as usize];
            let y = b
                .iter()
                .find(|y| m.skeleton.joints[y.bone as usize] == node)
                .expect("the second mesh's vertex follows the reversed joint");
            assert_eq!(y.weight, x.weight);
            assert!(
                m.skeleton.inverse_bind[y.bone as usize].abs_diff_eq(glam::Mat4::IDENTITY, 1e-5)
            );
        }
    }
}

/// A part without a skin hanging from a joint (a helmet on the head bone) follows that joint
/// rigidly: one influence, weight 1, on the joint's bone, placed where the joint carries it.
#[test]
fn an_unskinned_part_below_a_joint_follows_it() {
    let original = tiny_model();
    let glb = edit_glb(&to_glb(&original), |j| {
        let joint = j["skins"][0]["joints"][1].as_u64().unwrap() as usize;
        let mut mesh = j["meshes"][0].clone();
        for p in mesh["primitives"].as_array_mut().unwrap() {
            let a = p["attributes"].as_object_mut().unwrap();
            a.retain(|k, _| !k.starts_with("JOINTS_") && !k.starts_with("WEIGHTS_"));
        }
        j["meshes"].as_array_mut().unwrap().push(mesh);
        let mesh_index = j["meshes"].as_array().unwrap().len() - 1;
        let nodes = j["nodes"].as_array_mut().unwrap();
        nodes.push(serde_json::json!({ "name": "helmet", "mesh": mesh_index, "translation": [0.0, 0.5, 0.0] }));
        let part = nodes.len() - 1;
        let children = nodes[joint]
            .as_object_mut()
            .unwrap()
            .entry("children")
            .or_insert(serde_json::json!([]));
        children.as_array_mut().unwrap().push(part.into());
    });
    let (_dir, path) = write(&glb, "helmet.glb");
    let m = load(&path).unwrap();
    let n = original.mesh.vertex_count();
    assert_eq!(m.mesh.triangle_count(), 2 * original.mesh.triangle_count());
    assert_eq!(m.skeleton.bone_count(), original.skeleton.bone_count());
    let bone = m.mesh.influences_of(n)[0].bone;
    for v in n..2 * n {
        let inf = m.mesh.influences_of(v);
        assert_eq!(inf.len(), 1);
        assert_eq!((inf[0].bone, inf[0].weight), (bone, 1.0));
    }
    // The joint's node, as the file's skin names it.
    assert_eq!(bone, 1);
    // Carried rigidly: every vertex of the part is its original's position moved by one
    // offset (the joints only translate), half a metre (scaled) above the joint.
    let offset = m.mesh.positions[n] - m.mesh.positions[0];
    assert!(offset.length() > 0.1, "{offset}");
    for v in 0..n {
        let d = m.mesh.positions[n + v] - m.mesh.positions[v];
        assert!(d.distance(offset) < 1e-4, "{d} vs {offset}");
    }
}

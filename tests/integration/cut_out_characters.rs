//! Characters with cut-out parts (issue "real assets, third round"): a skinned, animated model
//! whose materials all blend, as an exported bird's feathers do, stays a character: mesh
//! levels, never billboard clouds, its feathers drawn two-sided with their alpha.

use crate::common::{lodlab, ok};
use lodlab::bake::foliage::classify::{
    CHARACTER_MOTION, FOLIAGE_AREA_SHARE, clip_motion, cut_out_share, is_tree,
};
use lodlab::generate::wild::feathers::feathered;
use lodlab::import::load_model;
use lodlab::model::Model;
use std::path::Path;

/// The robot with 400 feathers: two thirds of its surface cut out, every material `BLEND`.
fn bird() -> Model {
    feathered(&load_model("robot").unwrap(), 400)
}

fn write(model: &Model, dir: &Path, name: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, lodlab::generate::glb::to_glb(model)).unwrap();
    path.to_str().unwrap().to_string()
}

/// `lodlab shot` of `count` copies of the model in `file` by `method`, 160 × 120, from
/// `camera`: the picture and the JSON line.
fn shot(
    file: &str,
    dir: &Path,
    count: &str,
    method: &str,
    camera: &str,
) -> (image::RgbaImage, serde_json::Value) {
    let stem = Path::new(file).file_stem().unwrap().to_str().unwrap();
    let out = dir.join(format!("{stem}-{method}-{count}.png"));
    let o = lodlab(&[
        "shot",
        "--scene",
        "study",
        "--model",
        file,
        "--count",
        count,
        "--method",
        method,
        "--size",
        "160x120",
        "--camera",
        camera,
        "--cache",
        dir.join("cache").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    ok(&o);
    let line = String::from_utf8_lossy(&o.stdout);
    let report = serde_json::from_str(line.lines().last().unwrap()).unwrap();
    (image::open(&out).unwrap().to_rgba8(), report)
}

/// The pixels that show a feather: orange, lit or in shade.
fn feather_pixels(img: &image::RgbaImage) -> Vec<bool> {
    img.pixels()
        .map(|p| {
            let [r, g, b, _] = p.0.map(f32::from);
            r >= 60.0 && r > 1.4 * g && g > 1.5 * b
        })
        .collect()
}

fn count(mask: &[bool]) -> usize {
    mask.iter().filter(|&&m| m).count()
}

const NEAR: &str = "30,10,3,0,1,0";

#[test]
fn a_feathered_character_stays_a_character_and_draws_its_feathers_cut_out() {
    let dir = tempfile::tempdir().unwrap();
    let model = bird();
    let file = write(&model, dir.path(), "bird.glb");

    // Read back as a user's file is: all cut out by area, but it moves as a character.
    let read = load_model(&file).unwrap();
    let cut: Vec<bool> = read.materials.iter().map(|m| m.cuts_out()).collect();
    assert!(cut_out_share(&read, &cut) >= FOLIAGE_AREA_SHARE);
    assert!(clip_motion(&read) >= CHARACTER_MOTION);
    assert!(!is_tree(&read));

    // Full detail, close: a mesh, its feathers orange.
    let (full, report) = shot(&file, dir.path(), "1", "none", NEAR);
    assert_eq!(report["level_kinds"], serde_json::json!({"mesh": 1}));
    let feathers = feather_pixels(&full);
    let plain = feather_pixels(
        &shot(
            &write(&load_model("robot").unwrap(), dir.path(), "robot.glb"),
            dir.path(),
            "1",
            "none",
            NEAR,
        )
        .0,
    );
    assert!(
        count(&feathers) > 800,
        "{} feather pixels",
        count(&feathers)
    );
    assert!(count(&plain) * 20 < count(&feathers), "{}", count(&plain));

    // The texture's alpha is read: feathers whose alpha is zero everywhere draw nothing.
    let mut bare = model.clone();
    let texture = bare.materials.last_mut().unwrap().texture.as_mut().unwrap();
    texture.pixels.chunks_exact_mut(4).for_each(|p| p[3] = 0);
    let (gone, _) = shot(
        &write(&bare, dir.path(), "bare.glb"),
        dir.path(),
        "1",
        "none",
        NEAR,
    );
    assert!(
        count(&feather_pixels(&gone)) * 20 < count(&feathers),
        "{} feather pixels with nothing to show",
        count(&feather_pixels(&gone))
    );

    // Both sides are drawn: with every card's winding turned, the same pixels are feathers.
    let mut turned = model.clone();
    let first_card = 3 * load_model("robot").unwrap().mesh.triangle_count();
    turned.mesh.indices[first_card..]
        .chunks_exact_mut(3)
        .for_each(|t| t.swap(1, 2));
    let (back, _) = shot(
        &write(&turned, dir.path(), "turned.glb"),
        dir.path(),
        "1",
        "none",
        NEAR,
    );
    let back = feather_pixels(&back);
    let both = feathers
        .iter()
        .zip(&back)
        .filter(|(a, b)| **a && **b)
        .count();
    let either = feathers
        .iter()
        .zip(&back)
        .filter(|(a, b)| **a || **b)
        .count();
    assert!(
        both as f32 >= 0.9 * either as f32,
        "{both} of {either} feather pixels shared"
    );

    // Its as+is levels, at every distance: meshes, feathers still orange.
    let (crowd, report) = shot(&file, dir.path(), "9", "as+is", "20,12,9,0,1,0");
    let kinds = report["level_kinds"].as_object().unwrap();
    assert_eq!(kinds.keys().collect::<Vec<_>>(), ["mesh"], "{kinds:?}");
    let levels: Vec<u64> = report["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_u64().unwrap())
        .collect();
    assert!(levels.iter().skip(1).sum::<u64>() > 0, "{levels:?}");
    assert!(count(&feather_pixels(&crowd)) > 60);
}

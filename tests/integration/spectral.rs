//! Spectral clouds on the GPU (Aalborg thesis §6.2.1 and §6.4): the vertex shader's spectral
//! offsets and wind strength against their CPU reference, and billboards that stay rigid.

use glam::{Affine3A, Quat, Vec3, Vec4};
use lodlab::bake::foliage::billboard::chain::{CloudKind, CloudLevel, cloud_level};
use lodlab::bake::foliage::billboard::cloud::CloudParams;
use lodlab::bake::foliage::billboard::{foliage, tree_height};
use lodlab::bake::foliage::spectral::cloud::SpectralParams;
use lodlab::bake::gpu_data::drawable::Drawable;
use lodlab::bake::gpu_data::spectra::NO_ROW;
use lodlab::render::Gpu;
use lodlab::render::atlas::AtlasRasterizer;
use lodlab::render::capture::capture_skinned_in_wind;
use lodlab::render::targets::OFFSCREEN_FORMAT;
use lodlab::runtime::spec::Loaded;
use lodlab::runtime::world::World;

/// The sapling's foliage as a spectral cloud of 6 motion clusters at ε = 0.08 h.
fn spectral_level(gpu: &Gpu) -> CloudLevel {
    let tree = lodlab::generate::tree::sapling();
    let f = foliage(&tree).unwrap();
    let h = tree_height(&tree);
    let params = CloudParams {
        epsilon: 0.08 * h,
        ..Default::default()
    };
    let kind = CloudKind::Spectral(SpectralParams {
        clusters: 6,
        ..Default::default()
    });
    cloud_level(
        &AtlasRasterizer::new(gpu),
        &tree,
        &f,
        &params,
        &kind,
        64.0 / h,
        &tree,
        None,
    )
    .unwrap()
}

/// GPU = CPU for the spectral offset: every vertex the vertex shader skins, billboards moved by
/// their spectra and the wood by its bones, at several times and wind strengths, matches
/// `Drawable::evaluate`. The offsets are not nothing: without them the billboards would
/// be elsewhere, and a weaker wind moves them less.
#[test]
fn gpu_spectral_offsets_match_the_cpu_reference() {
    let gpu = crate::common::gpu().clone();
    let level = spectral_level(&gpu);
    let motion = level.motion.as_ref().expect("a spectral level has motion");
    assert_eq!(motion.spectra.rows as usize, level.billboards);
    let world = World::new(
        &gpu,
        Loaded::forest_of(&level.model, Some(motion), 1).unwrap(),
        OFFSCREEN_FORMAT,
        1,
    )
    .unwrap();
    let bake = &world.bakes[0];
    let bones_only = Drawable::new(&level.model).unwrap();
    let size = bake.bounds.diagonal();
    let place =
        Affine3A::from_rotation_translation(Quat::from_rotation_y(0.4), Vec3::new(2.0, 0.0, 1.0));
    let mut moved_by_spectra = 0.0f32;
    for wind in [1.0f32, 0.6, 1.4] {
        for time in [0.0f32, 0.83, 2.71] {
            let gpu_pos =
                capture_skinned_in_wind(&gpu, &world.renderer, 0, 0, time, place, wind).unwrap();
            let (cpu, _) = bake.evaluate(0, time, wind);
            let (plain, _) = bones_only.evaluate(0, time, wind);
            assert_eq!(gpu_pos.len(), cpu.len());
            for (v, (g, c)) in gpu_pos.iter().zip(&cpu).enumerate() {
                let want = place.transform_point3(*c);
                let err = g.truncate().distance(want);
                assert!(
                    err <= 1e-4 * size,
                    "wind {wind} t={time} vertex {v}: GPU {} CPU {want}",
                    g.truncate()
                );
            }
            // The bones-only bake orders its vertices the same way (same mesh).
            let spectral = cpu
                .iter()
                .zip(&plain)
                .map(|(a, b)| a.distance(*b))
                .fold(0.0f32, f32::max);
            moved_by_spectra = moved_by_spectra.max(spectral);
        }
    }
    assert!(
        moved_by_spectra > 1e-3 * size,
        "spectral offsets move billboards by at most {moved_by_spectra}"
    );
    // Wind strength scales the motion about rest.
    let rest = capture_skinned_in_wind(&gpu, &world.renderer, 0, 0, 0.9, place, 0.0).unwrap();
    let full = capture_skinned_in_wind(&gpu, &world.renderer, 0, 0, 0.9, place, 1.0).unwrap();
    let half = capture_skinned_in_wind(&gpu, &world.renderer, 0, 0, 0.9, place, 0.5).unwrap();
    let spread = |a: &[Vec4], b: &[Vec4]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| p.truncate().distance(q.truncate()))
            .fold(0.0f32, f32::max)
    };
    let (d_full, d_half) = (spread(&rest, &full), spread(&rest, &half));
    assert!(d_full > 1e-3 * size, "the wind moves the tree: {d_full}");
    assert!(
        (d_half / d_full - 0.5).abs() < 0.1,
        "half the wind, half the sway: {d_half} of {d_full}"
    );
}

/// The rigid-motion invariant (thesis §2.2): every billboard keeps its shape while its bone
/// and its spectrum move it, on the GPU.
#[test]
fn spectral_billboards_stay_rigid() {
    let gpu = crate::common::gpu().clone();
    let level = spectral_level(&gpu);
    let world = World::new(
        &gpu,
        Loaded::forest_of(&level.model, level.motion.as_ref(), 1).unwrap(),
        OFFSCREEN_FORMAT,
        1,
    )
    .unwrap();
    let am = &world.bakes[0].animation_space;
    // The four corners of every billboard, found by their spectra row.
    let mut corners: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
    for (v, &row) in am.spectral_rows.iter().enumerate() {
        if row != NO_ROW {
            corners.entry(row).or_default().push(v);
        }
    }
    assert_eq!(corners.len(), level.billboards);
    assert!(corners.values().all(|c| c.len() == 4));
    let shape = |pos: &[Vec4], c: &[usize]| -> Vec<f32> {
        let mut d = Vec::new();
        for i in 0..4 {
            for j in i + 1..4 {
                d.push(pos[c[i]].truncate().distance(pos[c[j]].truncate()));
            }
        }
        d
    };
    let at = |t: f32| {
        capture_skinned_in_wind(&gpu, &world.renderer, 0, 0, t, Affine3A::IDENTITY, 1.0).unwrap()
    };
    let rest = at(0.0);
    let mut worst = 0.0f32;
    for t in [0.4f32, 1.3, 2.2, 3.9] {
        let pos = at(t);
        for c in corners.values() {
            for (a, b) in shape(&rest, c).iter().zip(shape(&pos, c)) {
                worst = worst.max((a - b).abs() / a.max(1e-3));
            }
        }
    }
    // Bone matrices blended between two animation frames are rigid to within the blend's
    // chord error; nothing else may change a billboard's shape.
    assert!(worst < 2e-3, "a billboard changed shape by {worst}");
}

//! Levels of detail on models with the properties of assets made elsewhere: `split-tube`
//! (indexed, split along hard edges and a UV seam, texture coordinates mostly of zero area),
//! `armour` (57 separate closed parts, no texture coordinates) and `patchwork` (a texture in a
//! couple of hundred small charts). For every method, every level is drawn against full detail
//! where the renderer switches to it and its silhouette must stay within the tolerance; the
//! surface must stay closed; errors must be true and growing; and the coarsest level must reach
//! a tenth of the source's triangles, or 300.

use lodlab::bake::character::lod::{LodLevel, bake_lods};
use lodlab::bake::character::silhouette::distance;
use lodlab::bake::character::simplify::{Method, SimplifyInput, pose_samples};
use lodlab::import::load_model;
use lodlab::runtime::levels::runtime_options;
use std::collections::HashMap;

/// The tolerance the silhouettes are checked at, in pixels.
const TOLERANCE_PX: f32 = 4.0;
/// Drawings of full detail are at most this many pixels on a side (finer levels are checked
/// to a drawn pixel of this size).
const MAX_SIDE: u32 = 320;

/// Edges of a level by welded rest position, with how many triangles use each.
fn position_edges(model: &lodlab::model::Model, level: &LodLevel) -> HashMap<(u32, u32), u32> {
    let rest_bones = SimplifyInput::rest_bones(&model.skeleton);
    let rest = level.mesh.rest_positions(&rest_bones);
    let tolerance = lodlab::geometry::weld::tolerance_for(&rest) * 10.0;
    let groups = lodlab::geometry::weld::position_groups(&rest, tolerance);
    let mut edges = HashMap::new();
    for t in level.mesh.indices.chunks_exact(3) {
        for k in 0..3 {
            let a = groups[t[k] as usize];
            let b = groups[t[(k + 1) % 3] as usize];
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    edges
}

fn check(name: &str) {
    let model = load_model(name).unwrap();
    let source = model.mesh.triangle_count();
    let poses = pose_samples(&model, 2);
    let opts = runtime_options(&model, None);
    for method in Method::ALL {
        let lods = bake_lods(&model, method, &opts, &|_| {});
        let levels = &lods.levels;
        // meshoptimizer stops where its seams and borders lock (patchwork's couple of hundred
        // charts at 660 of 2,928 triangles): its levels must hold, not reach as far.
        if method != Method::Meshopt {
            assert!(
                levels.len() >= 4,
                "{name} {method}: {} levels",
                levels.len()
            );
            let coarsest = levels.last().unwrap().triangles();
            assert!(
                coarsest <= (source / 10).max(300),
                "{name} {method}: the coarsest level keeps {coarsest} of {source} triangles"
            );
        } else {
            assert!(
                levels.len() >= 2,
                "{name} {method}: {} levels",
                levels.len()
            );
        }
        for (k, pair) in levels.windows(2).enumerate() {
            // Coarser: fewer triangles, or (influence simplification alone) fewer influences.
            let coarser = pair[1].triangles() < pair[0].triangles()
                || pair[1].influences() < pair[0].influences();
            assert!(
                pair[1].error > pair[0].error && coarser,
                "{name} {method}: level {} is no coarser than level {k}",
                k + 1
            );
        }
        for (k, level) in levels.iter().enumerate().skip(1) {
            assert!(
                level.error >= level.bound,
                "{name} {method} level {k}: error below the bound"
            );
            // The source is closed, and so is every level: no holes, no slits. meshoptimizer
            // may press a thin part flat into two sheets back to back (an edge of four
            // triangles, 42 of them on the armour's level 4): closed still, but not manifold.
            let edges = position_edges(&model, level);
            let open = edges
                .values()
                .filter(|&&n| n != 2 && (method != Method::Meshopt || n % 2 == 1))
                .count();
            assert_eq!(open, 0, "{name} {method} level {k}: {open} open edges");
            let d = distance(
                &levels[0].mesh,
                &level.mesh,
                level.error,
                TOLERANCE_PX,
                &poses,
                MAX_SIDE,
            );
            // The masks are drawn conservatively (every pixel a triangle touches), so a thin
            // feature can stand up to about a pixel off in either: the distance is exact to a
            // pixel and a half, or to one drawn pixel where the drawing was capped.
            assert!(
                d.px <= TOLERANCE_PX + d.pixel.max(1.5),
                "{name} {method} level {k} ({} triangles, error {:.1} mm): the silhouette is \
                 {:.2} px off at {TOLERANCE_PX} px",
                level.triangles(),
                level.error * 1000.0,
                d.px
            );
        }
    }
}

#[test]
fn split_tube_levels_hold() {
    check("split-tube");
}

#[test]
fn armour_levels_hold() {
    check("armour");
}

#[test]
fn patchwork_levels_hold() {
    check("patchwork");
}

#[test]
fn the_models_have_the_properties_they_stand_for() {
    // split-tube: indexed, positions split two or three ways, mostly zero-area texture
    // coordinates, and copies of a position that differ by a rounding error.
    let tube = load_model("split-tube").unwrap();
    let m = &tube.mesh;
    let groups = lodlab::geometry::weld::position_groups(
        &m.positions,
        lodlab::geometry::weld::tolerance_for(&m.positions),
    );
    let positions = groups.iter().max().unwrap() + 1;
    let mut copies = vec![0u32; positions as usize];
    groups.iter().for_each(|&g| copies[g as usize] += 1);
    assert!(m.vertex_count() as f32 > 1.5 * positions as f32);
    assert!((3..=4).contains(copies.iter().max().unwrap()));
    let uv_area = |t: &[u32]| {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.uvs[i as usize]);
        (b - a).perp_dot(c - a).abs()
    };
    let with_area = m
        .indices
        .chunks_exact(3)
        .filter(|t| uv_area(t) > 0.0)
        .count();
    assert!(
        with_area * 5 < m.triangle_count(),
        "{with_area} with texture area"
    );
    let exact = m.positions.iter().collect::<Vec<_>>();
    let distinct_bits: std::collections::HashSet<[u32; 3]> = exact
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect();
    assert!(
        distinct_bits.len() > positions as usize,
        "the copies are bit-identical"
    );

    // armour: dozens of separate parts, no texture coordinates at all.
    let armour = load_model("armour").unwrap();
    let pieces = lodlab::geometry::connected_pieces(
        armour.mesh.vertex_count(),
        armour.mesh.indices.chunks_exact(3),
    );
    let parts: std::collections::HashSet<u32> = pieces.into_iter().collect();
    assert!(parts.len() >= 50, "{} parts", parts.len());
    assert!(armour.mesh.uvs.iter().all(|&uv| uv == glam::Vec2::ZERO));

    // patchwork: a texture in many charts, most positions on a chart outline.
    let patchwork = load_model("patchwork").unwrap();
    assert!(patchwork.materials[0].texture.is_some());
    let charts = lodlab::geometry::connected_pieces(
        patchwork.mesh.vertex_count(),
        patchwork.mesh.indices.chunks_exact(3),
    );
    let charts: std::collections::HashSet<u32> = charts.into_iter().collect();
    assert!(charts.len() >= 150, "{} charts", charts.len());
}

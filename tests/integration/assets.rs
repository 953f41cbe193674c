//! The project's own demo creatures: what `lodlab gen-assets` writes is what is committed, and
//! the creatures are the closed, smooth, properly weighted meshes later issues simplify.

use lodlab::assets::{BUILTINS, Kind};
use lodlab::generate::{generate, glb::to_glb};
use lodlab::model::Model;
use std::collections::HashMap;

/// The generated creatures (the trees have tests of their own in tests/integration/trees.rs).
fn generated() -> Vec<Model> {
    BUILTINS
        .iter()
        .filter(|b| b.kind == Kind::Creature)
        .map(|b| generate(b.name).expect("every built-in has a generator"))
        .collect()
}

#[test]
fn committed_assets_are_what_the_generator_writes() {
    for b in BUILTINS {
        let fresh = lodlab::generate::file(b.name).unwrap();
        let path = b.committed_path();
        let committed = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            fresh == committed && b.bytes == committed,
            "{} differs from what the generator writes ({} vs {} bytes): run `lodlab gen-assets --out assets`",
            path.display(),
            fresh.len(),
            committed.len()
        );
    }
}

#[test]
fn generation_is_deterministic() {
    let a = to_glb(&generate("walker").unwrap());
    let b = to_glb(&generate("walker").unwrap());
    assert!(a == b);
}

/// Edges by welded position: every one must be shared by exactly two triangles.
fn position_edges(m: &Model) -> HashMap<(u32, u32), u32> {
    let groups = lodlab::geometry::weld::position_groups(&m.mesh.positions, 1e-7);
    let mut edges = HashMap::new();
    for t in m.mesh.indices.chunks_exact(3) {
        for k in 0..3 {
            let a = groups[t[k] as usize];
            let b = groups[t[(k + 1) % 3] as usize];
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    edges
}

#[test]
fn creatures_are_closed_manifold_meshes_of_the_right_size() {
    for m in generated() {
        let tris = m.mesh.triangle_count();
        assert!(
            (8_000..=20_000).contains(&tris),
            "{}: {tris} triangles",
            m.name
        );
        assert!(
            m.skeleton.bone_count() >= 20,
            "{}: {} bones",
            m.name,
            m.skeleton.bone_count()
        );
        let edges = position_edges(&m);
        let bad = edges.values().filter(|&&c| c != 2).count();
        assert_eq!(
            bad, 0,
            "{}: {bad} edges not shared by exactly two triangles",
            m.name
        );
        // Closed: Euler characteristic of a sphere.
        let groups = lodlab::geometry::weld::position_groups(&m.mesh.positions, 1e-7);
        let v = *groups.iter().max().unwrap() as i64 + 1;
        let chi = v - edges.len() as i64 + tris as i64;
        assert_eq!(chi, 2, "{}: Euler characteristic {chi}", m.name);
        assert!(
            m.mesh
                .uvs
                .iter()
                .all(|uv| uv.x >= 0.0 && uv.y >= 0.0 && uv.x <= 1.0 && uv.y <= 1.0)
        );
        assert!(
            m.mesh
                .normals
                .iter()
                .all(|n| (n.length() - 1.0).abs() < 1e-4)
        );
        let clip_names: Vec<&str> = m.clips.iter().map(|c| c.name.as_str()).collect();
        let expected: &[&str] = if m.name == "horse" {
            &["walk", "gallop"]
        } else {
            &["walk", "wave"]
        };
        assert_eq!(clip_names, expected);
    }
}

#[test]
fn every_joint_blends_two_to_four_bones() {
    for m in generated() {
        for v in 0..m.mesh.vertex_count() {
            let inf = m.mesh.influences_of(v);
            assert!(
                (1..=4).contains(&inf.len()),
                "{} vertex {v}: {} influences",
                m.name,
                inf.len()
            );
            let sum: f32 = inf.iter().map(|i| i.weight).sum();
            assert!((sum - 1.0).abs() < 1e-5);
        }
        for (b, node) in m.skeleton.nodes.iter().enumerate() {
            let Some(p) = node.parent else { continue };
            // Vertices where parent and child share the load evenly: the joint bends smoothly
            // instead of creasing.
            let blended = (0..m.mesh.vertex_count())
                .filter(|&v| {
                    let inf = m.mesh.influences_of(v);
                    let w = |bone: u32| {
                        inf.iter()
                            .find(|i| i.bone == bone)
                            .map_or(0.0, |i| i.weight)
                    };
                    w(b as u32) >= 0.25 && w(p) >= 0.25
                })
                .count();
            assert!(
                blended >= 10,
                "{}: joint {} -> {} has only {blended} blended vertices",
                m.name,
                m.skeleton.nodes[p as usize].name,
                node.name
            );
        }
    }
}

#[test]
fn seams_cannot_open_under_skinning() {
    // Vertices split at a UV seam share their position; they must share their influences too,
    // or skinning would tear the seam open into a crack.
    for m in generated() {
        let groups = lodlab::geometry::weld::position_groups(&m.mesh.positions, 1e-7);
        let mut first: HashMap<u32, usize> = HashMap::new();
        for (v, &g) in groups.iter().enumerate() {
            let f = *first.entry(g).or_insert(v);
            assert_eq!(
                m.mesh.influences_of(f),
                m.mesh.influences_of(v),
                "{} vertex {v}",
                m.name
            );
        }
    }
}

#[test]
fn importer_reads_back_what_was_generated() {
    // The models made as a `Model` (the files laid out by `generate::wild` have tests of their
    // own in tests/integration/field_models.rs).
    for b in BUILTINS {
        let Some(g) = generate(b.name) else { continue };
        let m = lodlab::import::load_model(b.name).expect("committed asset loads");
        assert_eq!(m.name, b.name);
        assert_eq!(m.mesh.vertex_count(), g.mesh.vertex_count());
        assert_eq!(m.mesh.indices, g.mesh.indices);
        assert_eq!(m.skeleton.bone_count(), g.skeleton.bone_count());
        assert_eq!(m.clips.len(), g.clips.len());
        for (a, c) in m.clips.iter().zip(&g.clips) {
            assert_eq!(a.name, c.name);
            assert!((a.duration - c.duration).abs() < 1e-6);
            assert!((a.ground_speed - c.ground_speed).abs() < 1e-6);
        }
        // Textured, except the test models that stand for untextured assets; plain colours
        // of several materials come back as one palette texture.
        let plain = g.materials.iter().filter(|m| m.texture.is_none()).count();
        if plain >= 2 {
            assert_eq!(
                m.materials.len(),
                g.materials.len() - plain + 1,
                "{}",
                b.name
            );
            assert_eq!(
                m.materials.last().unwrap().name,
                lodlab::import::palette::PALETTE_MATERIAL
            );
        } else {
            assert_eq!(
                m.materials[0].texture.is_some(),
                g.materials[0].texture.is_some(),
                "{}",
                b.name
            );
        }
        // Metric models stand on the ground as generated: the importer only shifts them.
        let s = m.skeleton.root_transform.matrix3;
        assert!((s.x_axis.x - 1.0).abs() < 1e-6);
    }
}

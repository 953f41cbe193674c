//! The importer on models nobody on this project made (`../shared/models/`).

use crate::common::shared_model;
use lodlab::import::gltf::load;

#[test]
fn fox_is_welded_with_normals_and_three_clips() {
    let Some(fox) = shared_model("Fox.glb") else {
        return;
    };
    let m = load(&fox).expect("Fox loads");
    assert_eq!(m.skeleton.bone_count(), 24);
    assert_eq!(m.mesh.triangle_count(), 576);
    // 1,728 unshared corners weld down to a few hundred shared vertices (UV seams stay split).
    assert!(m.mesh.vertex_count() < 700, "{}", m.mesh.vertex_count());
    let names: Vec<&str> = m.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["Survey", "Walk", "Run"]);
    assert!((m.clips[0].duration - 3.42).abs() < 0.05);
    // Computed normals are unit length.
    assert!(
        m.mesh
            .normals
            .iter()
            .all(|n| (n.length() - 1.0).abs() < 1e-4)
    );
    assert!(m.materials[0].texture.is_some());
    // Most triangles share edges with neighbours now.
    let mut edges = std::collections::HashMap::new();
    for t in m.mesh.indices.chunks_exact(3) {
        for k in 0..3 {
            let (a, b) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
            *edges.entry((a, b)).or_insert(0) += 1;
        }
    }
    let shared_edges = edges.values().filter(|&&c| c == 2).count();
    assert!(
        shared_edges * 2 > edges.len(),
        "{shared_edges} of {}",
        edges.len()
    );
}

#[test]
fn simple_skin_loads() {
    let Some(path) = shared_model("SimpleSkin.gltf") else {
        return;
    };
    let m = load(&path).expect("SimpleSkin loads");
    assert_eq!(m.skeleton.bone_count(), 2);
    assert_eq!(m.mesh.vertex_count(), 10);
    assert_eq!(m.mesh.triangle_count(), 8);
    assert_eq!(m.clips.len(), 1);
    assert!((m.clips[0].duration - 5.5).abs() < 1e-4);
}

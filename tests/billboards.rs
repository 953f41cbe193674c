//! Billboard clouds of the demo trees (Aalborg thesis Ch. 3 and 7): validity, coverage,
//! determinism, rigid motion, and the fallbacks for foliage the method does not expect.

use glam::{Vec2, Vec3};
use lodlab::anim::bone_matrices;
use lodlab::bake::billboard::cloud::CloudParams;
use lodlab::bake::billboard::{SkeletonCloud, foliage, skeleton_cloud, tree_height};
use lodlab::import::load_model;
use lodlab::model::Model;

fn cloud(m: &Model, epsilon_of_height: f32, seed: u64) -> SkeletonCloud {
    let f = foliage(m).unwrap();
    skeleton_cloud(
        &f,
        &CloudParams {
            epsilon: epsilon_of_height * tree_height(m),
            seed,
            ..Default::default()
        },
    )
}

#[test]
fn every_leaf_is_on_exactly_one_billboard_within_epsilon() {
    for name in ["broadleaf", "conifer"] {
        let m = load_model(name).unwrap();
        let f = foliage(&m).unwrap();
        assert_eq!(
            f.rebound, 0,
            "{name}: the generator binds each leaf to one bone"
        );
        let mut counts = Vec::new();
        for e in [0.0, 0.005, 0.02, 0.05] {
            let eps = e * tree_height(&m);
            let c = cloud(&m, e, 7);
            let mut seen = vec![0u32; f.leaves.len()];
            for (b, bone) in c.billboards.iter().zip(&c.bones) {
                let (u, v) = b.plane.basis();
                let rect_u = (b.corners[1] - b.corners[0]).normalize();
                let rect_v = (b.corners[3] - b.corners[0]).normalize();
                let size = Vec2::new(
                    (b.corners[1] - b.corners[0]).length(),
                    (b.corners[3] - b.corners[0]).length(),
                );
                assert!(u.dot(b.plane.normal).abs() < 1e-5 && v.dot(b.plane.normal).abs() < 1e-5);
                for &i in &b.leaves {
                    seen[i as usize] += 1;
                    assert_eq!(
                        f.bones[i as usize], *bone,
                        "{name}: a leaf on another bone's cloud"
                    );
                    for &c in &f.leaves[i as usize].corners {
                        let d = b.plane.distance(c).abs();
                        assert!(
                            d <= eps * 1.001 + 1e-5,
                            "{name} ε {e}: corner {d} off its plane"
                        );
                        // Its projection lies on the billboard's rectangle.
                        let q = c - b.corners[0];
                        let (x, y) = (q.dot(rect_u), q.dot(rect_v));
                        let tol = 1e-3 * (1.0 + size.x.max(size.y));
                        assert!(
                            (-tol..=size.x + tol).contains(&x)
                                && (-tol..=size.y + tol).contains(&y),
                            "{name}: a leaf corner falls outside its billboard"
                        );
                    }
                }
            }
            assert!(
                seen.iter().all(|&n| n == 1),
                "{name} ε {e}: a leaf is not on exactly one billboard"
            );
            counts.push(c.billboards.len());
        }
        // More ε, fewer billboards; at ε = 0 about one per leaf (only exactly coplanar leaves merge).
        assert!(
            counts.windows(2).all(|w| w[1] <= w[0]),
            "{name}: {counts:?}"
        );
        assert!(
            counts[0] * 10 >= f.leaves.len() * 9,
            "{name}: {counts:?} of {}",
            f.leaves.len()
        );
        assert!(counts[3] * 4 < counts[0], "{name}: {counts:?}");
    }
}

#[test]
fn clouds_are_deterministic_for_a_seed() {
    let m = load_model("broadleaf").unwrap();
    assert_eq!(cloud(&m, 0.02, 3), cloud(&m, 0.02, 3));
    assert_ne!(cloud(&m, 0.02, 3), cloud(&m, 0.02, 4));
}

/// Skinned to one bone with weight 1, a billboard moves rigidly: the distances between its
/// corners stay what they were, all over the loop.
#[test]
fn a_billboard_moves_rigidly() {
    let m = load_model("conifer").unwrap();
    let c = cloud(&m, 0.02, 1);
    let clip = &m.clips[0];
    for k in 0..12 {
        let t = clip.duration * k as f32 / 12.0;
        let g = bone_matrices(&m.skeleton, Some(clip), t);
        for (b, &bone) in c.billboards.iter().zip(&c.bones).step_by(7) {
            let moved: Vec<Vec3> = b
                .corners
                .iter()
                .map(|&p| g[bone as usize].transform_point3(p))
                .collect();
            for i in 0..4 {
                for j in i + 1..4 {
                    let rest = b.corners[i].distance(b.corners[j]);
                    let now = moved[i].distance(moved[j]);
                    assert!(
                        (rest - now).abs() <= 1e-4 * (1.0 + rest),
                        "t {t}: {rest} became {now}"
                    );
                }
            }
        }
    }
}

#[test]
fn foliage_that_the_method_does_not_expect() {
    // A creature has no cut-out material: a one-line error, not a panic.
    let horse = load_model("horse").unwrap();
    let e = foliage(&horse).unwrap_err();
    assert!(e.contains("no foliage"), "{e}");
    assert!(!e.contains('\n'));
    // Leaves bound to several bones are rebound to the bone holding most of their weight.
    let mut m = load_model("broadleaf").unwrap();
    let mesh = &mut m.mesh;
    let leaf_vertex = (0..mesh.vertex_count())
        .find(|&v| mesh.materials[v] == 1)
        .unwrap();
    let a = mesh.influence_offsets[leaf_vertex] as usize;
    let bone = mesh.influences[a].bone;
    let other = (bone + 1) % m.skeleton.nodes.len() as u32;
    mesh.influences[a].weight = 0.7;
    // Split the vertex's single influence into 0.7 / 0.3 by appending one at the end of its
    // range (rebuilding the offsets).
    let mut infl = Vec::new();
    let mut offsets = vec![0u32];
    for v in 0..mesh.vertex_count() {
        infl.extend_from_slice(mesh.influences_of(v));
        if v == leaf_vertex {
            infl.push(lodlab::model::Influence {
                bone: other,
                weight: 0.3,
            });
        }
        offsets.push(infl.len() as u32);
    }
    mesh.influences = infl;
    mesh.influence_offsets = offsets;
    let f = foliage(&m).unwrap();
    assert_eq!(f.rebound, 1);
    assert!(f.bones.contains(&bone));
}

/// The colour metric (thesis §5.1.3, at its 800×600, 5 views, 5 frames): 0 for the tree against
/// itself, and at ε = 0 the atlas reproduces the foliage to within 2% (the thesis's baker
/// managed 7%).
#[test]
fn at_epsilon_zero_the_cloud_reproduces_the_foliage() {
    use lodlab::app::tree_levels::{cloud_level, colour_error};
    let gpu = lodlab::render::Gpu::headless().expect("a GPU adapter (lavapipe in CI)");
    for name in ["broadleaf", "conifer"] {
        let tree = load_model(name).unwrap();
        if name == "broadleaf" {
            assert_eq!(colour_error(&gpu, &tree, &tree, [800, 600]).unwrap(), 0.0);
        }
        let f = foliage(&tree).unwrap();
        let h = tree_height(&tree);
        let params = CloudParams {
            epsilon: 0.0,
            ..Default::default()
        };
        let (model, count, _) = cloud_level(&gpu, &tree, &f, &params, 800.0 / h).unwrap();
        assert_eq!(count, f.leaves.len());
        let e = colour_error(&gpu, &tree, &model, [800, 600]).unwrap();
        assert!(e <= 0.02, "{name}: colour error {e} at ε = 0");
        if name != "broadleaf" {
            continue;
        }
        // A coarse cloud is visibly worse, and still a tree.
        let coarse = CloudParams {
            epsilon: 0.05 * h,
            ..Default::default()
        };
        let (model, count, _) = cloud_level(&gpu, &tree, &f, &coarse, 800.0 / h).unwrap();
        assert!(count * 10 < f.leaves.len());
        let e2 = colour_error(&gpu, &tree, &model, [800, 600]).unwrap();
        assert!(
            e2 > e && e2 < 0.5,
            "{name}: colour error {e2} at ε = 0.05 h"
        );
    }
}

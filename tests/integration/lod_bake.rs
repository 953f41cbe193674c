//! The skinned LOD bake: progressive meshes by rest-pose, AS and AS+IS, the levels cut from
//! them, their geomorph maps, and meshes the simplifier must survive.

use glam::{Affine3A, Quat, Vec2, Vec3, Vec4};
use lodlab::bake::character::lod::{
    LevelProbes, LodLevel, LodOptions, bake_lods, choose_prefixes, cut_levels, extract,
    progressive_mesh,
};
use lodlab::bake::character::lod_error::ErrorProbe;
use lodlab::bake::character::simplify::expectation::ExpectationMatrix;
use lodlab::bake::character::simplify::{Method, Sequence, SimplifyInput, StepKind, simplify};
use lodlab::bake::gpu_data::animation_space::{AnimationSpaceMesh, AsInfluence};
use lodlab::generate::cylinder::bent_cylinder;
use std::collections::HashMap;

fn options(base_error: f32, floor: u32) -> LodOptions {
    LodOptions {
        base_error,
        floor_triangles: floor,
        budgets: None,
    }
}

/// A key for "same animation-space point": the influences' bits.
fn point_key(level: &LodLevel, v: usize) -> Vec<u32> {
    level
        .mesh
        .influences_of(v)
        .iter()
        .flat_map(|i| [i.bone, i.p.x.to_bits(), i.p.y.to_bits(), i.p.z.to_bits()])
        .collect()
}

/// Indices in range, no triangle repeating a point, no edge shared by more than two
/// triangles (edges taken between points, so UV seams count as joined), geomorph maps into
/// the next level.
fn check_levels(levels: &[LodLevel], manifold: bool) {
    assert!(!levels.is_empty());
    for (k, level) in levels.iter().enumerate() {
        let n = level.vertices();
        assert_eq!(level.source.len(), n);
        assert!(
            level.mesh.indices.iter().all(|&i| (i as usize) < n),
            "LOD {k}"
        );
        let keys: Vec<Vec<u32>> = (0..n).map(|v| point_key(level, v)).collect();
        let mut ids: HashMap<&Vec<u32>, usize> = HashMap::new();
        let id: Vec<usize> = keys
            .iter()
            .map(|key| {
                let len = ids.len();
                *ids.entry(key).or_insert(len)
            })
            .collect();
        let mut edges: HashMap<(usize, usize), u32> = HashMap::new();
        for t in level.mesh.indices.chunks_exact(3) {
            let p = [t[0], t[1], t[2]].map(|v| id[v as usize]);
            assert!(
                p[0] != p[1] && p[1] != p[2] && p[0] != p[2],
                "LOD {k}: degenerate triangle {t:?}"
            );
            for e in 0..3 {
                let (a, b) = (p[e], p[(e + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        if manifold {
            assert!(
                edges.values().all(|&c| c <= 2),
                "LOD {k}: a non-manifold edge"
            );
        }
        // Every vertex still a point: homogeneous parts summing to one.
        for v in 0..n {
            let w: f32 = level.mesh.influences_of(v).iter().map(|i| i.p.w).sum();
            assert!((w - 1.0).abs() < 1e-3, "LOD {k} vertex {v}: Σw = {w}");
        }
        match levels.get(k + 1) {
            Some(next) => {
                assert_eq!(level.geomorph.len(), n, "LOD {k} geomorph map size");
                for (v, &to) in level.geomorph.iter().enumerate() {
                    assert!((to as usize) < next.vertices(), "LOD {k}: map out of range");
                    // A vertex that survives into the next level maps onto itself there.
                    if let Some(same) = next.source.iter().position(|&s| s == level.source[v]) {
                        assert_eq!(to as usize, same, "LOD {k}: kept vertex moved");
                    }
                }
            }
            None => assert!(level.geomorph.is_empty()),
        }
    }
}

#[test]
fn cylinder_levels_are_valid_for_every_method() {
    let model = bent_cylinder(16, 12);
    for method in Method::ALL {
        let lods = bake_lods(&model, method, &options(2e-3, 20), &|_| {});
        // meshoptimizer may press a thin part flat into two sheets back to back (edges of
        // four triangles): the papers' simplifier keeps the link condition.
        check_levels(&lods.levels, method != Method::Meshopt);
        assert!(
            lods.levels.len() >= 3,
            "{method}: {} levels",
            lods.levels.len()
        );
        for w in lods.levels.windows(2) {
            assert!(w[1].triangles() <= w[0].triangles(), "{method}");
            assert!(w[1].influences() < w[0].influences(), "{method}");
            assert!(w[1].error >= w[0].error, "{method}");
        }
        assert_eq!(lods.levels[0].triangles(), model.mesh.triangle_count());
        // The running maximum is the error bound, and it never falls.
        let seq = &lods.sequence;
        assert!(seq.steps.windows(2).all(|w| w[1].max_cost >= w[0].max_cost));
        assert!(seq.steps.iter().all(|s| s.max_cost >= s.cost));
    }
}

/// `bake_lods` cuts levels on a second thread while the simplifier still runs; the levels
/// must be those cut from the finished sequence, by error and by budget.
#[test]
fn levels_cut_while_simplifying_match_those_cut_afterwards() {
    let model = bent_cylinder(24, 16);
    let mut budgets = options(1.0, 10);
    budgets.budgets = Some(vec![300, 120, 40]);
    for (method, opts) in [
        (Method::RestPose, options(1e-3, 20)),
        (Method::InfluenceSimplification, options(1e-3, 20)),
        (Method::AnimationSpace, budgets),
    ] {
        let lods = bake_lods(&model, method, &opts, &|_| {});
        let (base, seq, _) = progressive_mesh(&model, method, &|_| {});
        assert_eq!(lods.sequence.steps, seq.steps, "{method}");
        let probes = LevelProbes::new(&model, &base);
        let after = cut_levels(&base, &seq, &opts, &probes);
        assert!(after.len() >= 3, "{method}: {} levels", after.len());
        assert_eq!(lods.levels, after, "{method}");
    }
}

/// Bakes inside a parallel loop with more bakes than workers, as `lodlab bake` runs them: each
/// bake's level cut needs the pool while its simplifier waits for it, so a waiting worker must
/// keep working or every worker ends up waiting. Run on a thread, so that a deadlock fails the
/// test instead of hanging it.
#[test]
fn bakes_in_a_parallel_loop_finish() {
    use rayon::prelude::*;
    let (done_tx, done_rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let model = bent_cylinder(12, 10);
        let jobs = 3 * rayon::current_num_threads().max(2);
        let levels: Vec<usize> = (0..jobs)
            .into_par_iter()
            .map(|i| {
                let method = Method::ALL[i % 3];
                bake_lods(&model, method, &options(2e-3, 20), &|_| {})
                    .levels
                    .len()
            })
            .collect();
        let _ = done_tx.send(levels);
    });
    let levels = done_rx
        .recv_timeout(std::time::Duration::from_secs(300))
        .expect("bakes in a parallel loop deadlocked");
    assert!(levels.iter().all(|&n| n >= 2), "{levels:?}");
}

#[test]
fn levels_by_triangle_budget() {
    let model = bent_cylinder(16, 12);
    let mut opts = options(1.0, 10);
    opts.budgets = Some(vec![200, 100, 50]);
    let lods = bake_lods(&model, Method::AnimationSpace, &opts, &|_| {});
    check_levels(&lods.levels, true);
    let tris: Vec<usize> = lods.levels.iter().map(|l| l.triangles()).collect();
    assert_eq!(tris[0], 384);
    assert!(tris[1] <= 200 && tris[1] >= 190, "{tris:?}");
    assert!(tris[2] <= 100 && tris[3] <= 50, "{tris:?}");
}

/// A flat grid on z = 0 with texture coordinates equal to x, y, rigid to bone 0.
fn flat_grid(n: u32, bones: u32) -> AnimationSpaceMesh {
    let mut m = AnimationSpaceMesh {
        offsets: vec![0],
        ..Default::default()
    };
    for y in 0..=n {
        for x in 0..=n {
            let p = Vec3::new(x as f32, y as f32, 0.0) / n as f32;
            m.influences.push(AsInfluence {
                bone: (x * bones / (n + 1)).min(bones - 1),
                p: p.extend(1.0),
                n: Vec3::Z,
            });
            m.offsets.push(m.influences.len() as u32);
            m.uvs.push(p.truncate());
            m.materials.push(0);
        }
    }
    let row = n + 1;
    for y in 0..n {
        for x in 0..n {
            let a = y * row + x;
            m.indices
                .extend([a, a + 1, a + row + 1, a, a + row + 1, a + row]);
        }
    }
    m
}

/// Poses of `bones` bones swinging independently.
fn poses(bones: usize) -> ExpectationMatrix {
    let poses: Vec<Vec<Affine3A>> = (0..50)
        .map(|i| {
            (0..bones)
                .map(|b| {
                    Affine3A::from_rotation_translation(
                        Quat::from_rotation_x((i as f32 * 0.3 + b as f32).sin() * 0.5),
                        Vec3::new(0.0, b as f32 * 0.1, 0.0),
                    )
                })
                .collect()
        })
        .collect();
    ExpectationMatrix::from_poses(bones, &poses)
}

fn run(mesh: &AnimationSpaceMesh, bones: usize, method: Method) -> (Sequence, Vec<LodLevel>) {
    let rest = vec![Affine3A::IDENTITY; bones];
    let p = poses(bones);
    let input = SimplifyInput {
        mesh,
        rest_bones: &rest,
        expectation: &p,
        poses: &[],
        textured: &[true],
    };
    let seq = simplify(&input, method, &|_| {});
    let prefixes = choose_prefixes(&seq, &options(1e-4, 1));
    let levels = extract(mesh, &seq, &prefixes);
    (seq, levels)
}

#[test]
fn collapses_in_a_flat_region_cost_nothing() {
    let grid = flat_grid(6, 1);
    for method in [Method::RestPose, Method::AnimationSpace] {
        let (seq, levels) = run(&grid, 1, method);
        check_levels(&levels, true);
        // Every interior vertex and every border vertex on a straight side can go for free;
        // only cutting off one of the four corners changes the covered area, and costs.
        let free = seq.steps.iter().take_while(|s| s.cost <= 1e-6).count();
        assert_eq!(seq.triangles_after(free), 2, "{method}");
        assert!(
            seq.steps[free..].iter().all(|s| s.cost > 0.1),
            "{method}: a corner cut for nothing"
        );
    }
    // On a curved surface the same engine does charge for moving the surface.
    let model = bent_cylinder(8, 8);
    let (_, seq, _) = progressive_mesh(&model, Method::RestPose, &|_| {});
    assert!(seq.steps.iter().any(|s| s.cost > 1e-3));
}

#[test]
fn influence_simplification_goes_further_than_collapses_alone() {
    let model = bent_cylinder(16, 12);
    let (_, as_seq, _) = progressive_mesh(&model, Method::AnimationSpace, &|_| {});
    let (_, is_seq, _) = progressive_mesh(&model, Method::InfluenceSimplification, &|_| {});
    // At the same triangle count, from a quarter down to the coarsest both reach, AS+IS keeps fewer
    // influences. (Where each sequence ends is decided by the last legal collapses, not by
    // influence simplification, so the ends are not compared.)
    let influences_at = |s: &Sequence, triangles: u32| {
        (0..=s.steps.len())
            .find(|&p| s.triangles_after(p) <= triangles)
            .map(|p| s.influences_after(p))
    };
    let coarsest = is_seq
        .triangles_after(is_seq.steps.len())
        .max(as_seq.triangles_after(as_seq.steps.len()));
    let full = model.mesh.triangle_count() as u32;
    for triangles in [full / 4, full / 8, coarsest] {
        let (is, as_) = (
            influences_at(&is_seq, triangles).unwrap(),
            influences_at(&as_seq, triangles).unwrap(),
        );
        assert!(is < as_, "at {triangles} triangles: AS+IS {is} vs AS {as_}");
    }
    let removals = is_seq
        .steps
        .iter()
        .filter(|s| matches!(s.kind, StepKind::Influence { .. }))
        .count();
    assert!(removals > 0);
    assert!(
        !as_seq
            .steps
            .iter()
            .any(|s| matches!(s.kind, StepKind::Influence { .. }))
    );
    // Nearby vertices share influence sets, so the factor cache mostly hits.
    let rate = is_seq.stats.cache_hit_rate().expect("lookups");
    assert!(rate > 0.5, "hit rate {rate}");
}

#[test]
fn animation_space_beats_the_rest_pose_on_a_bending_joint() {
    let model = bent_cylinder(24, 16);
    let probe = ErrorProbe::new(
        &model,
        &AnimationSpaceMesh::from_skinned(&model.mesh, &model.skeleton).optimized_for_gpu(),
        3000,
    )
    .unwrap();
    let error_at = |method: Method, fraction: f64| {
        let (base, seq, _) = progressive_mesh(&model, method, &|_| {});
        let target = (seq.base_influences as f64 * fraction) as u32;
        let prefix = (0..=seq.steps.len())
            .find(|&p| seq.influences_after(p) <= target)
            .unwrap();
        let mut replay = lodlab::bake::character::lod::Replay::new(&base, &seq);
        replay.advance_to(&seq, prefix);
        let tris: Vec<[u32; 3]> = replay.triangles().collect();
        probe.measure(&tris, |r| replay.influences_of(r)).rms
    };
    for fraction in [0.5, 0.3] {
        let rest = error_at(Method::RestPose, fraction);
        let asm = error_at(Method::AnimationSpace, fraction);
        let asis = error_at(Method::InfluenceSimplification, fraction);
        assert!(asm <= rest, "at {fraction}: AS {asm} > rest-pose {rest}");
        assert!(asis <= asm, "at {fraction}: AS+IS {asis} > AS {asm}");
    }
}

#[test]
fn non_manifold_edges_are_left_alone() {
    let mut grid = flat_grid(4, 1);
    // A fin: a third triangle on the interior edge between vertices 6 and 12.
    let apex = grid.vertex_count() as u32;
    grid.influences.push(AsInfluence {
        bone: 0,
        p: Vec4::new(0.4, 0.4, 0.5, 1.0),
        n: Vec3::X,
    });
    grid.offsets.push(grid.influences.len() as u32);
    grid.uvs.push(Vec2::new(2.0, 2.0));
    grid.materials.push(0);
    grid.indices.extend([6, 12, apex]);
    for method in Method::ALL {
        let (_, levels) = run(&grid, 1, method);
        check_levels(&levels, false);
        // The fin's edge stays in every level.
        let last = levels.last().unwrap();
        for v in [6, 12, apex] {
            assert!(last.source.contains(&v), "{method}: vertex {v} went");
        }
    }
}

#[test]
fn degenerate_and_duplicate_triangles_are_dropped() {
    let mut grid = flat_grid(4, 1);
    let first: Vec<u32> = grid.indices[..3].to_vec();
    grid.indices.extend([3, 3, 4]); // repeats a vertex
    grid.indices.extend(&first); // duplicate
    grid.indices.extend([first[0], first[2], first[1]]); // the same, flipped
    for method in Method::ALL {
        let (seq, levels) = run(&grid, 1, method);
        assert_eq!(seq.stats.dropped_triangles, 3);
        check_levels(&levels, true);
        assert_eq!(levels[0].triangles(), 32);
    }
}

#[test]
fn unreferenced_vertices_are_ignored() {
    let mut grid = flat_grid(4, 1);
    for k in 0..3 {
        grid.influences.push(AsInfluence {
            bone: 0,
            p: Vec4::new(5.0 + k as f32, 0.0, 0.0, 1.0),
            n: Vec3::Z,
        });
        grid.offsets.push(grid.influences.len() as u32);
        grid.uvs.push(Vec2::splat(9.0));
        grid.materials.push(0);
    }
    let (_, levels) = run(&grid, 1, Method::AnimationSpace);
    check_levels(&levels, true);
    assert_eq!(levels[0].vertices(), 25);
    assert!(levels.iter().all(|l| l.source.iter().all(|&s| s < 25)));
}

#[test]
fn disconnected_parts_simplify_independently() {
    let a = flat_grid(4, 2);
    let mut m = a.clone();
    let offset = a.vertex_count() as u32;
    for v in 0..a.vertex_count() {
        for i in a.influences_of(v) {
            m.influences.push(AsInfluence {
                p: i.p + Vec4::new(3.0, 0.0, 0.0, 0.0),
                ..*i
            });
        }
        m.offsets.push(m.influences.len() as u32);
        m.uvs.push(a.uvs[v] + Vec2::new(2.0, 0.0));
        m.materials.push(0);
    }
    m.indices.extend(a.indices.iter().map(|i| i + offset));
    for method in Method::ALL {
        let (seq, levels) = run(&m, 2, method);
        check_levels(&levels, true);
        // In the rest pose each part goes down to its quad for free, on its own.
        if method == Method::RestPose {
            let free = seq.steps.iter().take_while(|s| s.cost <= 1e-6).count();
            assert_eq!(seq.triangles_after(free), 4, "{method}: two quads");
        }
        // Later one part is removed whole (never crushed into slivers); the last part left
        // stays.
        let prunes: Vec<&lodlab::bake::character::simplify::Step> = seq
            .steps
            .iter()
            .filter(|s| matches!(s.kind, StepKind::Prune { .. }))
            .collect();
        assert_eq!(prunes.len(), 1, "{method}");
        assert!(seq.steps.last().unwrap().triangles >= 1, "{method}");
        // Removing a part moves the surface by about the part's diameter (a unit square's
        // diagonal at most).
        let cost = prunes[0].cost;
        assert!((0.5..2.0).contains(&cost), "{method}: {cost}");
    }
}

#[test]
fn zero_area_texture_triangles_use_the_geometric_correspondence() {
    let mut grid = flat_grid(6, 1);
    // Squash the texture coordinates of a 2×2 block of vertices onto one point: the texture
    // is no parameterisation there, so their collapses are measured on the surface itself,
    // where the flat grid makes them free.
    let squashed = [8u32, 9, 15, 16];
    for &v in &squashed {
        grid.uvs[v as usize] = Vec2::splat(0.25);
    }
    for method in Method::ALL {
        let (seq, levels) = run(&grid, 1, method);
        check_levels(&levels, true);
        let last = levels.last().unwrap();
        assert!(
            squashed.iter().any(|v| !last.source.contains(v)),
            "{method}: the squashed vertices stayed"
        );
        let collapses = seq
            .steps
            .iter()
            .filter(|s| matches!(s.kind, StepKind::Collapse { .. }));
        assert!(collapses.clone().count() > 20, "{method}");
        // Moving a squashed vertex slides the texture: textured, that costs something, but
        // the geometry is flat.
        for s in collapses {
            assert!(s.cost.is_finite() && s.cost >= 0.0, "{method}: {}", s.cost);
        }
    }
}

#[test]
fn a_model_with_one_bone() {
    let mut model = bent_cylinder(8, 8);
    model.skeleton.joints.truncate(1);
    model.skeleton.inverse_bind.truncate(1);
    let mut offsets = vec![0u32];
    let mut influences = Vec::new();
    for _ in 0..model.mesh.vertex_count() {
        influences.push(lodlab::model::Influence {
            bone: 0,
            weight: 1.0,
        });
        offsets.push(influences.len() as u32);
    }
    model.mesh.influence_offsets = offsets;
    model.mesh.influences = influences;
    for method in Method::ALL {
        let lods = bake_lods(&model, method, &options(1e-3, 10), &|_| {});
        check_levels(&lods.levels, true);
        assert!(lods.levels.len() > 1, "{method}");
        assert!(
            lods.sequence
                .steps
                .iter()
                .all(|s| matches!(s.kind, StepKind::Collapse { .. }))
        );
    }
}

#[test]
fn a_bone_that_never_moves() {
    // A third bone, never animated, takes a share of the lower half: P is singular there.
    let mut model = bent_cylinder(8, 8);
    let skel = &mut model.skeleton;
    skel.nodes.push(lodlab::model::Node {
        name: "still".into(),
        parent: Some(0),
        rest: lodlab::model::Trs::IDENTITY,
    });
    skel.joints.push(2);
    skel.inverse_bind.push(glam::Mat4::IDENTITY);
    let mesh = &mut model.mesh;
    let mut offsets = vec![0u32];
    let mut influences = Vec::new();
    for v in 0..mesh.vertex_count() {
        let mut list = mesh.influences_of(v).to_vec();
        if mesh.positions[v].y < 0.8 {
            for i in &mut list {
                i.weight *= 0.7;
            }
            list.push(lodlab::model::Influence {
                bone: 2,
                weight: 0.3,
            });
        }
        influences.extend(list);
        offsets.push(influences.len() as u32);
    }
    mesh.influence_offsets = offsets;
    mesh.influences = influences;
    for method in Method::ALL {
        let lods = bake_lods(&model, method, &options(1e-3, 10), &|_| {});
        check_levels(&lods.levels, true);
        assert!(lods.sequence.steps.iter().all(|s| s.cost.is_finite()));
    }
}

//! Billboard clouds of the demo trees (Aalborg thesis Ch. 3 and 7): validity, coverage,
//! determinism, rigid motion, and the fallbacks for foliage the method does not expect.

use glam::{Vec2, Vec3};
use lodlab::anim::bone_matrices;
use lodlab::bake::foliage::billboard::cloud::CloudParams;
use lodlab::bake::foliage::billboard::{
    Grouping, SkeletonCloud, foliage, grouped_cloud, skeleton_cloud, tree_height,
};
use lodlab::import::load_model;
use lodlab::model::Model;
use lodlab::render::atlas::AtlasRasterizer;

fn cloud(m: &Model, epsilon_of_height: f32, seed: u64) -> SkeletonCloud {
    let f = foliage(m).unwrap();
    skeleton_cloud(
        &m.skeleton,
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

/// Coarser groups give fewer billboards; the whole crown as one group gets down to a handful,
/// each bound to the deepest bone its leaves share.
#[test]
fn grouping_subtrees_reaches_a_handful_of_billboards() {
    for name in ["broadleaf", "conifer"] {
        let m = load_model(name).unwrap();
        let f = foliage(&m).unwrap();
        let params = CloudParams {
            epsilon: 0.15 * tree_height(&m),
            ..Default::default()
        };
        let count = |g| grouped_cloud(&m.skeleton, &f, &params, g).billboards.len();
        let per_bone = count(Grouping::PerBone);
        let two = count(Grouping::Subtree { forks: 2 });
        let one = count(Grouping::Subtree { forks: 1 });
        let crown = grouped_cloud(&m.skeleton, &f, &params, Grouping::Subtree { forks: 0 });
        assert!(
            per_bone > two && two >= one && one >= crown.billboards.len(),
            "{name}: {per_bone} {two} {one} {}",
            crown.billboards.len()
        );
        assert!(
            crown.billboards.len() <= 10,
            "{name}: {}",
            crown.billboards.len()
        );
        // Each billboard's bone is an ancestor (or the bone) of every leaf on it.
        // (Bones are joints; walk the node hierarchy.)
        let node = |b: u32| m.skeleton.joints[b as usize];
        for (b, &bone) in crown.billboards.iter().zip(&crown.bones) {
            for &i in &b.leaves {
                let mut x = Some(node(f.bones[i as usize]));
                while x.is_some_and(|x| x != node(bone)) {
                    x = m.skeleton.nodes[x.unwrap() as usize].parent;
                }
                assert_eq!(
                    x,
                    Some(node(bone)),
                    "{name}: billboard bone is not above its leaves"
                );
            }
        }
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
    use lodlab::bake::foliage::billboard::chain::{CloudKind, CloudLevel, cloud_level};
    use lodlab::measure::colour_error::colour_error;
    let gpu = crate::common::gpu().clone();
    for name in ["broadleaf", "conifer"] {
        let tree = load_model(name).unwrap();
        if name == "broadleaf" {
            assert_eq!(
                colour_error(&gpu, &tree, &CloudLevel::full(&tree), [800, 600]).unwrap(),
                0.0
            );
        }
        let f = foliage(&tree).unwrap();
        let h = tree_height(&tree);
        let params = CloudParams {
            epsilon: 0.0,
            ..Default::default()
        };
        let level = cloud_level(
            &AtlasRasterizer::new(&gpu),
            &tree,
            &f,
            &params,
            &CloudKind::Skeleton(Grouping::PerBone),
            800.0 / h,
            &tree,
            None,
        )
        .unwrap();
        assert_eq!(level.billboards, f.leaves.len());
        let e = colour_error(&gpu, &tree, &level, [800, 600]).unwrap();
        assert!(e <= 0.02, "{name}: colour error {e} at ε = 0");
        if name != "broadleaf" {
            continue;
        }
        // A coarse cloud is visibly worse, and still a tree.
        let coarse = CloudParams {
            epsilon: 0.05 * h,
            ..Default::default()
        };
        let level = cloud_level(
            &AtlasRasterizer::new(&gpu),
            &tree,
            &f,
            &coarse,
            &CloudKind::Skeleton(Grouping::PerBone),
            800.0 / h,
            &tree,
            None,
        )
        .unwrap();
        assert!(level.billboards * 10 < f.leaves.len());
        let e2 = colour_error(&gpu, &tree, &level, [800, 600]).unwrap();
        assert!(
            e2 > e && e2 < 0.5,
            "{name}: colour error {e2} at ε = 0.05 h"
        );
    }
}

/// The chain of a tree: L0 the tree itself, then clouds for rising ε with falling billboard
/// counts, ending at ten billboards or fewer, each level's atlas within the texture limit.
#[test]
fn the_chain_falls_to_a_handful_of_billboards() {
    use lodlab::bake::foliage::billboard::chain::{ChainOptions, tree_chain};
    let gpu = crate::common::gpu().clone();
    let tree = load_model("broadleaf").unwrap();
    let f = foliage(&tree).unwrap();
    let chain = tree_chain(
        &AtlasRasterizer::new(&gpu),
        &tree,
        &f,
        &ChainOptions::default(),
        &|_| {},
    )
    .unwrap();
    assert!(chain.len() >= 5, "{} levels", chain.len());
    assert_eq!(chain[0].epsilon, 0.0);
    assert_eq!(chain[0].cloud.model, tree);
    for w in chain[1..].windows(2) {
        assert!(w[1].epsilon > w[0].epsilon);
        assert!(w[1].cloud.drawn_billboards() < w[0].cloud.drawn_billboards());
    }
    assert!(chain.last().unwrap().cloud.drawn_billboards() <= 10);
    // The coarse end is made of view-selected clumps, as many as its cloud had billboards,
    // each of whose leaves lie within the level's ε of every view's plane.
    let opts = ChainOptions::default();
    let clump_levels: Vec<_> = chain
        .iter()
        .filter_map(|l| match l.kind {
            Some(lodlab::bake::foliage::billboard::chain::CloudKind::Clumps { clumps, views }) => {
                Some((l, clumps, views))
            }
            _ => None,
        })
        .collect();
    assert!(
        clump_levels.len() >= 2,
        "{} clump levels",
        clump_levels.len()
    );
    for (l, clumps, views) in clump_levels {
        assert!(clumps <= opts.clumps_from);
        assert_eq!(views, opts.clump_views);
        assert_eq!(l.cloud.billboards, clumps * views);
        assert_eq!(l.cloud.drawn_billboards(), clumps);
        assert_eq!(l.cloud.view_windows.len(), l.cloud.billboards);
        assert!(l.cloud.view_windows.iter().all(|w| w.abs() > 0.1));
        let c = lodlab::bake::foliage::billboard::clumps::clump_cloud(
            &tree, &f, clumps, views, opts.seed,
        );
        assert!(
            c.epsilon() <= l.epsilon,
            "{clumps} clumps: ε bound {:.3} m over the level's {:.3} m",
            c.epsilon(),
            l.epsilon
        );
        // Its view windows reach the GPU on the billboards' corners.
        let bake = l.cloud.bake().unwrap();
        let windows = &bake.animation_space.view_windows;
        let corners: u32 = l.cloud.corners.iter().sum();
        assert_eq!(
            windows.iter().filter(|&&w| w != 0.0).count(),
            corners as usize
        );
    }
    for l in &chain[1..] {
        let materials = &l.cloud.model.materials;
        let a = lodlab::bake::gpu_data::materials::lit_atlas_material(materials).unwrap();
        let atlas = materials[a].texture.as_ref().unwrap();
        let lighting = materials[a + 1].texture.as_ref().unwrap();
        assert!(atlas.width <= 2048 && atlas.height <= 2048);
        assert_eq!(
            (lighting.width, lighting.height),
            (atlas.width, atlas.height)
        );
        // Colour and lighting, RGBA8 each.
        assert_eq!(
            l.cloud.texture_bytes,
            (2 * atlas.width * atlas.height * 4) as usize
        );
        // The foliage is billboards, each a fan of its outline's corners less two triangles
        // (two for a whole rectangle); the wood is simplified, never grown.
        let w = wood(&l.cloud.model);
        assert_eq!(l.cloud.corners.len(), l.cloud.billboards);
        let fans: u32 = l.cloud.corners.iter().map(|&c| c - 2).sum();
        assert_eq!(l.cloud.model.mesh.triangle_count(), w + fans as usize);
        assert!(w <= wood(&tree));
        // Its atlas is as sharp as docs/trees.md says: about two texels a pixel where the level
        // comes in (at least 8 a metre, at most 800 across the tree), and a clump level's never fewer than 256
        // across the tree, so that the coarse end looked at closer (forced, or with the
        // tolerance raised) still shows leaves; an atlas at the largest size may have been
        // drawn less sharp, to fit.
        let h = lodlab::bake::foliage::billboard::tree_height(&tree);
        let clumps = matches!(
            l.kind,
            Some(lodlab::bake::foliage::billboard::chain::CloudKind::Clumps { .. })
        );
        let floor = if clumps { 256.0 / h } else { 0.0 };
        let where_it_comes_in = (2.0 * opts.tolerance_px / l.epsilon)
            .max(8.0)
            .min(800.0 / h);
        let sharpest = atlas_texels_per_unit(&l.cloud.model, a, [atlas.width, atlas.height]);
        let full =
            atlas.width.max(atlas.height) >= lodlab::bake::foliage::billboard::atlas::MAX_ATLAS;
        let asked = if full {
            floor
        } else {
            where_it_comes_in.max(floor)
        };
        assert!(
            sharpest >= 0.99 * asked,
            "ε {:.3} m: {sharpest:.1} texels a metre, {asked:.1} asked",
            l.epsilon
        );
    }
    // The coarsest level draws a small fraction of the triangles of the full tree.
    let last = &chain.last().unwrap().cloud.model;
    assert!(last.mesh.triangle_count() * 20 < tree.mesh.triangle_count());
}

/// The fewest atlas texels a scene unit along any edge of the triangles of material
/// `material` of `m`, whose texture is `size` texels.
fn atlas_texels_per_unit(m: &Model, material: usize, size: [u32; 2]) -> f32 {
    let mesh = &m.mesh;
    let texels = |a: usize, b: usize| {
        let d = (mesh.uvs[b] - mesh.uvs[a]) * Vec2::new(size[0] as f32, size[1] as f32);
        d.length() / (mesh.positions[b] - mesh.positions[a]).length().max(1e-9)
    };
    mesh.indices
        .chunks_exact(3)
        .filter(|t| mesh.materials[t[0] as usize] as usize == material)
        .flat_map(|t| {
            let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
            [texels(a, b), texels(b, c), texels(c, a)]
        })
        .fold(f32::INFINITY, f32::min)
}

/// Triangles of a tree's wood (material 0).
fn wood(m: &Model) -> usize {
    m.mesh
        .indices
        .chunks_exact(3)
        .filter(|t| m.mesh.materials[t[0] as usize] == 0)
        .count()
}

/// The simplified wood is made of the tree's own vertices, influences and all (half-edge
/// collapses move no vertex), fewer of them as ε grows; pieces thinner than ε become
/// generalised cylinders whose vertices take their skin from one of the piece's own; the
/// trunk stays.
#[test]
fn simplified_wood_keeps_its_vertices() {
    use lodlab::bake::foliage::billboard::wood::{WoodChain, without_foliage};
    let tree = load_model("conifer").unwrap();
    let chain = WoodChain::new(&tree);
    let h = tree_height(&tree);
    let key = |p: glam::Vec3| p.to_array().map(f32::to_bits);
    let skin = |m: &lodlab::model::SkinnedMesh, v: usize| -> Vec<(u32, u32)> {
        m.influences_of(v)
            .iter()
            .map(|i| (i.bone, i.weight.to_bits()))
            .collect()
    };
    let original: std::collections::HashMap<[u32; 3], Vec<(u32, u32)>> =
        (0..tree.mesh.vertex_count())
            .map(|v| (key(tree.mesh.positions[v]), skin(&tree.mesh, v)))
            .collect();
    let skins: std::collections::HashSet<Vec<(u32, u32)>> = original.values().cloned().collect();
    let mut last = usize::MAX;
    let mut moved_at_fine = 0;
    for e in [0.002, 0.01, 0.05, 0.2] {
        let w = without_foliage(&chain.tree_at(&tree, e * h));
        let n = w.mesh.triangle_count();
        assert!(n <= last && n > 0, "ε {e}: {n} triangles after {last}");
        last = n;
        for v in 0..w.mesh.vertex_count() {
            let infl = skin(&w.mesh, v);
            match original.get(&key(w.mesh.positions[v])) {
                Some(o) => assert_eq!(o, &infl, "ε {e}: vertex {v} kept its place, not its skin"),
                None => {
                    assert!(
                        skins.contains(&infl),
                        "ε {e}: vertex {v} has a skin of its own"
                    );
                    moved_at_fine += (e == 0.002) as usize;
                }
            }
        }
    }
    assert!(last * 10 < wood(&tree));
    // At the finest ε most of the wood is thicker than ε: collapsed, its vertices in place.
    let fine = without_foliage(&chain.tree_at(&tree, 0.002 * h))
        .mesh
        .vertex_count();
    assert!(
        moved_at_fine * 2 < fine,
        "{moved_at_fine} of {fine} vertices moved"
    );
}

/// Coarse levels keep the wood that carries the crown (issue 23): the limbs and branches
/// become cylinders about as wide as they were, rather than slivers or nothing, so the
/// wood's surface, and with it (Cauchy) its average screen area, stays close to the
/// original's, while its triangles fall far below it.
#[test]
fn coarse_wood_holds_the_crown() {
    use lodlab::bake::foliage::billboard::wood::{WoodChain, without_foliage};
    for name in ["broadleaf", "sapling"] {
        let tree = load_model(name).unwrap();
        let chain = WoodChain::new(&tree);
        let h = tree_height(&tree);
        let full = without_foliage(&tree);
        let (full_area, full_box) = surface(&full.mesh);
        for e in [0.04, 0.16, 0.32] {
            let w = without_foliage(&chain.tree_at(&tree, e * h));
            let (area, bounds) = surface(&w.mesh);
            assert!(
                area > 0.5 * full_area,
                "{name} ε {e} h: the wood's surface fell to {area:.2} of {full_area:.2}"
            );
            // It still reaches out to where the crown is.
            let reach = |b: &lodlab::model::Bounds| b.size().x.max(b.size().z);
            assert!(
                reach(&bounds) > 0.6 * reach(&full_box),
                "{name} ε {e} h: the wood spans {:.2} across, the tree's {:.2}",
                reach(&bounds),
                reach(&full_box)
            );
            assert!(w.mesh.triangle_count() * 4 < full.mesh.triangle_count());
        }
    }
}

/// A tree whose file split every triangle's corners apart (hard normals everywhere, as some
/// exporters write flat-shaded wood): its wood is still found branch by branch, by position,
/// and holds the crown as the welded tree's does.
#[test]
fn wood_split_at_every_seam_still_holds_the_crown() {
    use lodlab::bake::foliage::billboard::wood::{WoodChain, without_foliage};
    let tree = load_model("broadleaf").unwrap();
    let mut split = tree.clone();
    let mut mesh = lodlab::model::SkinnedMesh::empty();
    for &v in &tree.mesh.indices {
        let k = mesh.copy_vertex_from(&tree.mesh, v as usize);
        mesh.indices.push(k);
    }
    split.mesh = mesh;
    let h = tree_height(&tree);
    let (welded, unwelded) = (WoodChain::new(&tree), WoodChain::new(&split));
    for e in [0.04, 0.16] {
        let (a, _) = surface(&without_foliage(&welded.tree_at(&tree, e * h)).mesh);
        let (b, _) = surface(&without_foliage(&unwelded.tree_at(&split, e * h)).mesh);
        assert!(
            b > 0.7 * a && b < 1.5 * a,
            "ε {e} h: split wood's surface {b:.2}, welded {a:.2}"
        );
    }
}

/// Total triangle area and the bounds of a mesh.
fn surface(m: &lodlab::model::SkinnedMesh) -> (f32, lodlab::model::Bounds) {
    let area = m
        .indices
        .chunks_exact(3)
        .map(|t| {
            let p = [0, 1, 2].map(|k| m.positions[t[k] as usize]);
            0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
        })
        .sum();
    let bounds = lodlab::model::Bounds::of(m.indices.iter().map(|&i| m.positions[i as usize]))
        .expect("wood");
    (area, bounds)
}

/// A tree's chain is cached: the second load reads the file, and a damaged file is reported in
/// one line and rebuilt, never trusted.
///
/// Named to sort first: libtest starts tests in name order, and this one (half a minute where
/// it bakes the broadleaf for the shared cache) started last ran alone at the end while the
/// other thread idled.
#[test]
fn a_tree_chain_comes_from_the_cache_and_survives_a_damaged_file() {
    use lodlab::bake::cache::{LodCache, Origin};
    use lodlab::bake::foliage::billboard::chain::{ChainOptions, load_or_build_chain};
    let gpu = crate::common::gpu().clone();
    let dir = tempfile::tempdir().unwrap();
    let cache = LodCache::new(Some(dir.path().to_path_buf()));
    // The broadleaf's chain is the default scene's: from the tests' shared cache, where the
    // scenes of other tests (and CI's look at the window) bake it once; the sapling's is baked
    // into this test's own folder, to see it baked, read and damaged.
    let shared = LodCache::new(Some(crate::common::shared_cache()));
    let tree_and_hash = |name: &str| {
        let tree = load_model(name).unwrap();
        let hash = lodlab::import::import(name, &Default::default())
            .unwrap()
            .source_hash;
        (tree, hash)
    };
    // The broadleaf's chain ends in its impostor, which is to be cached too; the sapling's
    // coarsest level, clouds or clumps, already beats its impostor where it comes in, so its
    // chain keeps all its levels, the impostor coming in further off (its clump levels are
    // cached below).
    let (tree, hash) = tree_and_hash("broadleaf");
    let opts = ChainOptions::default();
    let load_in =
        |cache: &LodCache, tree: &lodlab::model::Model, hash: &[u8; 32], opts: &ChainOptions| {
            load_or_build_chain(
                &AtlasRasterizer::new(&gpu),
                &lodlab::measure::colour_error::GpuColourError::new(&gpu),
                cache,
                tree,
                hash,
                opts,
                &|_| {},
            )
            .unwrap()
        };
    let load_with = |tree: &lodlab::model::Model, hash: &[u8; 32], opts: &ChainOptions| {
        load_in(&cache, tree, hash, opts)
    };
    let load = || load_in(&shared, &tree, &hash, &opts);
    let (built, origin) = load();
    assert!(
        matches!(origin, Origin::Baked { warning: None } | Origin::Cache),
        "{origin:?}"
    );
    // The chain ends with the impostor, which comes in where the level it stands for would
    // have: ε still grows level by level.
    let last = built.last().unwrap();
    assert!(
        matches!(
            last.kind,
            Some(lodlab::bake::foliage::billboard::chain::CloudKind::Impostor { .. })
        ),
        "{:?}",
        last.kind
    );
    assert!(last.cloud.impostor.is_some());
    assert!(built.windows(2).all(|w| w[1].epsilon > w[0].epsilon));
    let (cached, origin) = load();
    assert_eq!(origin, Origin::Cache);
    assert_eq!(cached.len(), built.len());
    assert!(cached[0].cloud.model == tree, "level 0 is the tree itself");
    for (a, b) in cached.iter().zip(&built).skip(1) {
        assert!(a.cloud.model == b.cloud.model);
        assert_eq!(a.kind, b.kind);
    }
    // A chain ending in clumps: their view windows come back from the cache.
    let (sapling, sapling_hash) = tree_and_hash("sapling");
    let (built, _) = load_with(&sapling, &sapling_hash, &ChainOptions::default());
    let (cached, origin) = load_with(&sapling, &sapling_hash, &ChainOptions::default());
    assert_eq!(origin, Origin::Cache);
    use lodlab::bake::foliage::billboard::chain::CloudKind;
    let kinds: Vec<_> = cached.iter().map(|l| l.kind).collect();
    let clumps = cached
        .iter()
        .rposition(|l| matches!(l.kind, Some(CloudKind::Clumps { .. })))
        .unwrap_or_else(|| panic!("no clump level: {kinds:?}"));
    // After the clumps, at most the impostor, at a larger error than theirs.
    match &cached[clumps + 1..] {
        [] => {}
        [imp] => {
            assert!(
                matches!(imp.kind, Some(CloudKind::Impostor { .. })),
                "{kinds:?}"
            );
            assert!(imp.epsilon > cached[clumps].epsilon);
        }
        _ => panic!("levels after the clumps: {kinds:?}"),
    }
    let last = &cached[clumps];
    assert!(!last.cloud.view_windows.is_empty());
    for (a, b) in cached.iter().zip(&built).skip(1) {
        assert_eq!(a.cloud.view_windows, b.cloud.view_windows);
        assert_eq!(a.cloud.views, b.cloud.views);
    }
    // A damaged file is baked again, with one line saying so, and stored again (the
    // sapling's: the cheaper tree to bake twice).
    let file = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| {
            let name = p.file_name().unwrap().to_string_lossy();
            name.starts_with("sapling-clouds-")
        })
        .expect("the sapling's chain is cached");
    let mut bytes = std::fs::read(&file).unwrap();
    let n = bytes.len();
    bytes[n - 100] ^= 0x5a;
    std::fs::write(&file, &bytes).unwrap();
    let (rebuilt, origin) = load_with(&sapling, &sapling_hash, &ChainOptions::default());
    match origin {
        Origin::Baked { warning: Some(w) } => {
            assert!(w.contains("corrupt") && !w.contains('\n'), "{w}")
        }
        o => panic!("a damaged file was used: {o:?}"),
    }
    assert_eq!(rebuilt.len(), built.len());
    assert_eq!(
        load_with(&sapling, &sapling_hash, &ChainOptions::default()).1,
        Origin::Cache,
        "the rebuilt chain is stored again"
    );
}

/// A cloud level's billboard outlines (the viewer's debug view) are the four sides of every
/// billboard: four lines each, every corner on exactly two of them, no diagonal; the full tree
/// has none.
#[test]
fn billboard_outlines_are_the_four_sides_of_every_billboard() {
    use lodlab::bake::foliage::billboard::{atlas, cloud_model};
    use lodlab::bake::gpu_data::drawable::Drawable;
    let m = load_model("sapling").unwrap();
    let c = cloud(&m, 0.08, 1);
    let layout = atlas::layout(&c.billboards, 64.0).unwrap();
    let image = lodlab::model::Rgba8Image {
        width: layout.width,
        height: layout.height,
        pixels: vec![200; (4 * layout.width * layout.height) as usize],
    };
    let level = cloud_model(&m, &c, &layout, image, &[], &[]);
    let bake = Drawable::new(&level).unwrap();
    let lines = &bake.outlines;
    assert_eq!(lines.len(), 8 * c.billboards.len());
    let mut degree = std::collections::HashMap::<u32, usize>::new();
    for &v in lines {
        *degree.entry(v).or_default() += 1;
    }
    assert_eq!(degree.len(), 4 * c.billboards.len());
    assert!(degree.values().all(|&d| d == 2));
    // Every corner on two lines, in cycles of four: each billboard's lines close round it
    // (its two triangles have no edge joining the other two corners).
    let mut adjacent = std::collections::HashMap::<u32, Vec<u32>>::new();
    for l in lines.chunks_exact(2) {
        adjacent.entry(l[0]).or_default().push(l[1]);
        adjacent.entry(l[1]).or_default().push(l[0]);
    }
    let mut seen = std::collections::HashSet::new();
    for &start in adjacent.keys() {
        let mut stack = vec![start];
        let mut size = 0;
        while let Some(v) = stack.pop() {
            if seen.insert(v) {
                size += 1;
                stack.extend(&adjacent[&v]);
            }
        }
        assert!(size == 0 || size == 4, "a loop of {size} corners");
    }
    // A side is shorter than the diagonal of its billboard: every line is a side.
    let (pos, _) = bake.evaluate(0, 0.0, 1.0);
    let longest_diagonal = c
        .billboards
        .iter()
        .map(|b| b.corners[0].distance(b.corners[2]))
        .fold(0.0f32, f32::max);
    let longest_side = c
        .billboards
        .iter()
        .flat_map(|b| (0..4).map(move |k| b.corners[k].distance(b.corners[(k + 1) % 4])))
        .fold(0.0f32, f32::max);
    assert!(longest_side < longest_diagonal);
    for l in lines.chunks_exact(2) {
        let d = pos[l[0] as usize].distance(pos[l[1] as usize]);
        assert!(d <= longest_side * 1.001 + 1e-4, "a line of {d} is no side");
    }
    assert!(Drawable::new(&m).unwrap().outlines.is_empty());
}

/// An octahedral impostor (issue 19) shows the tree it was baked from: its atlas holds every
/// view, upright and inside its cell; drawn through the renderer from round the tree, far off,
/// its coverage disagrees with the full tree's on far fewer pixels than the same impostor
/// with every view mirrored (each the silhouette from the opposite side), and one whose views
/// were left blank disagrees on all of them.
#[test]
fn an_impostor_shows_the_tree_it_was_baked_from() {
    use lodlab::bake::foliage::billboard::chain::CloudLevel;
    use lodlab::bake::impostor::octahedral::{ViewGrid, bake_impostor};
    use lodlab::measure::colour_error::whole_tree_error;
    let gpu = crate::common::gpu().clone();
    let tree = load_model("sapling").unwrap();
    let grid = ViewGrid {
        frames: 6,
        cell: 64,
    };
    let (model, frame) = bake_impostor(&AtlasRasterizer::new(&gpu), &tree, grid).unwrap();
    assert_eq!(frame.frames, 6);
    let colour = model.materials[0].texture.as_ref().unwrap();
    assert_eq!((colour.width, colour.height), (384, 384));
    // Every view shows some of the tree, none spills into its neighbours' cells (their
    // borders stay clear), and the side views stand upright: something covers the middle of
    // the cell's lower half (the trunk) in every view on the horizon (the grid's edge).
    let alpha = |x: u32, y: u32| colour.pixels[4 * (y * colour.width + x) as usize + 3];
    for j in 0..6 {
        for i in 0..6 {
            let (x0, y0) = (i * 64, j * 64);
            let covered = (0..64 * 64)
                .filter(|k| alpha(x0 + k % 64, y0 + k / 64) >= 128)
                .count();
            assert!(covered > 40, "view ({i}, {j}) is empty");
            let border = (0..64).any(|k| {
                alpha(x0 + k, y0) >= 128
                    || alpha(x0 + k, y0 + 63) >= 128
                    || alpha(x0, y0 + k) >= 128
                    || alpha(x0 + 63, y0 + k) >= 128
            });
            assert!(!border, "view ({i}, {j}) reaches its cell's border");
            if i == 0 || j == 0 || i == 5 || j == 5 {
                let trunk = (36..60).any(|y| (28..36).any(|x| alpha(x0 + x, y0 + y) >= 128));
                assert!(trunk, "side view ({i}, {j}) has no trunk below its middle");
            }
        }
    }
    let level = |model: lodlab::model::Model| CloudLevel {
        impostor: Some(frame),
        ..CloudLevel::full(&model)
    };
    let shown = whole_tree_error(&gpu, &tree, &level(model.clone()), 48.0).unwrap();
    // Every view mirrored left to right: the silhouettes seen from the opposite sides.
    let mut mirrored = model.clone();
    for m in &mut mirrored.materials {
        let t = m.texture.as_mut().unwrap();
        let w = t.width as usize;
        for row in t.pixels.chunks_exact_mut(4 * w) {
            for cell in row.chunks_exact_mut(4 * 64) {
                for x in 0..32 {
                    for c in 0..4 {
                        cell.swap(4 * x + c, 4 * (63 - x) + c);
                    }
                }
            }
        }
    }
    let wrong = whole_tree_error(&gpu, &tree, &level(mirrored), 48.0).unwrap();
    let mut blank = model;
    for m in &mut blank.materials {
        let t = m.texture.as_mut().unwrap();
        t.pixels.chunks_exact_mut(4).for_each(|p| p[3] = 0);
    }
    let none = whole_tree_error(&gpu, &tree, &level(blank), 48.0).unwrap();
    // A sparse sapling 48 pixels high: twigs a pixel wide are most of its outline.
    assert!(
        shown < 0.6,
        "the impostor disagrees on {shown:.3} of the tree"
    );
    assert!(
        shown < 0.6 * wrong,
        "views from the wrong side do about as well: {wrong:.3} against {shown:.3}"
    );
    assert!(none > 0.95, "a blank impostor disagrees on only {none:.3}");
}

/// The conifer's glTF file has a node rest pose 7% of its height away from its mesh's bind
/// pose. Its impostor must show the tree where the renderer draws it: baked from the bind pose
/// it disagreed on 0.53 of the conifer's pixels at 37.5 px, baked at rest on 0.20.
#[test]
fn an_impostor_stands_where_its_tree_is_drawn() {
    use lodlab::bake::foliage::billboard::chain::CloudLevel;
    use lodlab::bake::impostor::octahedral::{ViewGrid, bake_impostor};
    use lodlab::measure::colour_error::whole_tree_error;
    let gpu = crate::common::gpu().clone();
    let tree = load_model("conifer").unwrap();
    let grid = ViewGrid {
        frames: 6,
        cell: 64,
    };
    let (model, frame) = bake_impostor(&AtlasRasterizer::new(&gpu), &tree, grid).unwrap();
    let level = CloudLevel {
        impostor: Some(frame),
        ..CloudLevel::full(&model)
    };
    let error = whole_tree_error(&gpu, &tree, &level, 37.5).unwrap();
    assert!(
        error < 0.3,
        "the conifer's impostor disagrees on {error:.3} of its pixels at 37.5 px"
    );
}

/// Lighting in the atlas: every billboard texel keeps the normal the leaf drawn there is lit
/// by, and lit by them a coarse cloud is shaded more like the full tree than
/// lit by its planes, under the scene's sun and under a low sun from the other side.
#[test]
fn billboards_lit_through_their_atlas_shade_like_the_tree_under_two_suns() {
    use lodlab::bake::foliage::billboard::chain::{CloudKind, cloud_level};
    use lodlab::bake::foliage::billboard::occlusion::CrownDensity;
    use lodlab::bake::gpu_data::drawable::Drawable;
    use lodlab::bake::gpu_data::materials::{BILLBOARD_LIGHTING, lit_atlas_material};
    use lodlab::measure::foliage_lighting::foliage_lighting;
    let gpu = crate::common::gpu().clone();
    // Every other leaf wound the other way, its normal kept: files put normals and winding
    // each their own way, and the renderer lights a back face by the negated normal.
    let mut tree = load_model("sapling").unwrap();
    let leaves = foliage(&tree).unwrap();
    for (k, tris) in leaves.triangles.iter().enumerate() {
        if k % 2 == 0 {
            for &t in tris {
                tree.mesh
                    .indices
                    .swap(3 * t as usize + 1, 3 * t as usize + 2);
            }
        }
    }
    let f = foliage(&tree).unwrap();
    let h = tree_height(&tree);
    let crown = CrownDensity::of(&tree).unwrap();
    let level = cloud_level(
        &AtlasRasterizer::new(&gpu),
        &tree,
        &f,
        &CloudParams {
            epsilon: 0.08 * h,
            ..Default::default()
        },
        &CloudKind::Skeleton(Grouping::Siblings),
        200.0 / h,
        &tree,
        Some(&crown),
    )
    .unwrap();
    let atlas = lit_atlas_material(&level.model.materials).expect("a lit atlas");
    assert_eq!(
        Drawable::tree_level(&level.model, None, &level.occlusion, &[])
            .unwrap()
            .kind,
        lodlab::bake::gpu_data::drawable::DrawKind::Foliage { atlas_lit: true }
    );
    let colour = level.model.materials[atlas].texture.as_ref().unwrap();
    let lighting = &level.model.materials[atlas + 1];
    assert_eq!(lighting.name, BILLBOARD_LIGHTING);
    let lighting = lighting.texture.as_ref().unwrap();
    // Where a leaf is, a unit normal (mostly). The re-wound leaves' normals point against
    // their winding, so where a billboard's front sees one's front face it is lit by a normal
    // turned away from the billboard: the texels face both ways.
    let linear = |c: u8| (c as f32 / 255.0).powf(2.2) * 2.0 - 1.0;
    let (mut towards, mut away, mut short) = (0, 0, 0);
    for (c, l) in colour
        .pixels
        .chunks_exact(4)
        .zip(lighting.pixels.chunks_exact(4))
    {
        if c[3] < 128 {
            continue;
        }
        let m = glam::Vec3::new(linear(l[0]), linear(l[1]), linear(l[2]));
        // Where leaves facing different ways overlap (at their soft edges) the blend of their
        // normals is shorter.
        assert!(m.length() < 1.1, "normal {m}");
        short += (m.length() < 0.7) as usize;
        if m.z > 0.2 {
            towards += 1;
        } else if m.z < -0.2 {
            away += 1;
        }
    }
    assert!(
        towards > 500 && away > 100,
        "{towards} texels face the front, {away} away"
    );
    assert!(
        short * 4 < towards + away,
        "{short} texels of {} blend opposite normals",
        towards + away
    );
    // Lit per texel against lit by its plane, each beside the full tree.
    let measured = foliage_lighting(&gpu, &tree, &[(1, &level)], 160.0).unwrap();
    assert_eq!(measured.len(), 2);
    for m in &measured {
        assert!(
            m.atlas.shading < m.flat.shading,
            "sun {}: shading {:.4} lit through the atlas, {:.4} by the plane",
            m.sun,
            m.atlas.shading,
            m.flat.shading
        );
    }
}

/// The full tree is darkened inside its crown by the same term, per vertex; characters are not.
#[test]
fn a_tree_is_darker_inside_its_crown_and_a_character_is_not() {
    use lodlab::bake::gpu_data::drawable::Drawable;
    let tree = Drawable::new(&load_model("broadleaf").unwrap()).unwrap();
    let o = &tree.animation_space.crown_occlusion;
    assert_eq!(o.len(), tree.animation_space.vertex_count());
    let most = o.iter().copied().fold(0.0f32, f32::max);
    let open = o.iter().filter(|&&x| x < 0.05).count();
    assert!(most > 0.3, "the deepest leaf loses {most} of its light");
    assert!(
        open * 10 > o.len(),
        "{open} of {} vertices in the open",
        o.len()
    );
    let walker = Drawable::new(&load_model("walker").unwrap()).unwrap();
    assert!(walker.animation_space.crown_occlusion.is_empty());
}

/// View-selected clumps (src/bake/foliage/billboard/clumps.rs): drawn one plane a clump, chosen by the
/// view, a clump level covers the sapling's leaves as closely as the same planes all drawn at
/// once (the "star", which fills the crown's gaps) at a quarter of the billboards, and more
/// closely than a cloud drawing as many billboards, from the colour metric's views round the
/// tree and over its loop. (By the thesis's measure, which divides by the tree's pixels alone,
/// the star's filled gaps cost it more: 0.95 of its error was the bound then; by the pixels
/// either covers the two score alike, 0.247 against 0.244.)
#[test]
fn clumps_drawn_by_view_cover_the_tree_as_well_as_all_their_planes_and_better_than_a_cloud() {
    use lodlab::bake::foliage::billboard::chain::{CloudKind, cloud_level};
    use lodlab::measure::colour_error::colour_error;
    let gpu = crate::common::gpu().clone();
    let raster = AtlasRasterizer::new(&gpu);
    let tree = load_model("sapling").unwrap();
    let f = foliage(&tree).unwrap();
    let h = tree_height(&tree);
    let size = [640, 480];
    let level = |kind: &CloudKind, epsilon: f32| {
        cloud_level(
            &raster,
            &tree,
            &f,
            &CloudParams {
                epsilon,
                ..Default::default()
            },
            kind,
            200.0 / h,
            &tree,
            None,
        )
        .unwrap()
    };
    let cloud = level(
        &CloudKind::Skeleton(Grouping::Subtree { forks: 1 }),
        0.1 * h,
    );
    let n = cloud.billboards;
    assert!((4..=40).contains(&n), "{n} billboards");
    let clumps = level(
        &CloudKind::Clumps {
            clumps: n,
            views: 4,
        },
        0.1 * h,
    );
    assert_eq!(clumps.drawn_billboards(), n);
    let mut star = clumps.clone();
    star.view_windows.clear();
    let by_view = colour_error(&gpu, &tree, &clumps, size).unwrap();
    let all_planes = colour_error(&gpu, &tree, &star, size).unwrap();
    let as_cloud = colour_error(&gpu, &tree, &cloud, size).unwrap();
    eprintln!("{n} clumps by view {by_view:.3}, all planes {all_planes:.3}, cloud {as_cloud:.3}");
    assert!(
        by_view <= all_planes + 0.015,
        "by view {by_view:.3}, all planes {all_planes:.3}"
    );
    assert!(
        by_view < 0.8 * as_cloud,
        "by view {by_view:.3}, a cloud of {n} billboards {as_cloud:.3}"
    );
}

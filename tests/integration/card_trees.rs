//! The card trees (`lodlab::generate::wild::cards`): trees laid out as artists ship them,
//! through the billboard-cloud chain. A palm of curved fronds, a bush of leaf and flower cards
//! in two cut-out materials and no trunk, an oak of crossed normal-mapped cards with bent
//! normals under a stretched root, and a pine of 155 triangles: each must keep its look in its
//! clouds, and no level may cost more to draw than a finer one.

use lodlab::bake::cache::LodCache;
use lodlab::bake::foliage::billboard::chain::{
    ChainOptions, CloudKind, load_or_build_chains, load_or_choose, order,
};
use lodlab::model::Model;
use std::sync::OnceLock;

/// A card tree with its chain as the default options cut it (from the tests' shared cache)
/// and the cost order's choices.
struct Baked {
    tree: Model,
    chains: order::Chains,
    choices: Vec<order::CostChoice>,
}

const NAMES: [&str; 4] = ["card-palm", "card-bush", "card-oak", "card-pine"];

fn baked(name: &str) -> &'static Baked {
    static BAKED: [OnceLock<Baked>; 4] = [const { OnceLock::new() }; 4];
    let k = NAMES.iter().position(|n| *n == name).expect("a card tree");
    BAKED[k].get_or_init(|| {
        let gpu = crate::common::gpu();
        let cache = LodCache::new(Some(crate::common::shared_cache()));
        let raster = lodlab::render::atlas::AtlasRasterizer::new(gpu);
        let measure = lodlab::measure::colour_error::GpuColourError::new(gpu);
        let opts = ChainOptions::default();
        let tree = lodlab::import::load_model(name).unwrap();
        let source = lodlab::import::import(name, &Default::default())
            .unwrap()
            .source_hash;
        let (chains, _) =
            load_or_build_chains(&raster, &measure, &cache, &tree, &source, &opts, &|_| {})
                .unwrap();
        let (choices, _) =
            load_or_choose(&measure, &cache, &tree, &source, &opts, &chains).unwrap();
        Baked {
            tree,
            chains,
            choices,
        }
    })
}

/// The cloud levels of a chain (clouds and clumps: neither the tree nor its impostor), with
/// their indices among the candidates.
fn cloud_levels(b: &Baked) -> Vec<(usize, &lodlab::bake::foliage::billboard::chain::CloudLevel)> {
    b.chains
        .candidates
        .iter()
        .enumerate()
        .filter(|(_, l)| {
            matches!(
                l.kind,
                Some(CloudKind::Skeleton(_) | CloudKind::Spectral(_) | CloudKind::Clumps { .. })
            )
        })
        .map(|(k, l)| (k, &l.cloud))
        .collect()
}

/// The bush's flowers are a cut-out material of their own, with their own texture and
/// cutoff: every cloud level shows them (the atlas drew only the first cut-out material's
/// texture, and the flowers turned into leaves at every level).
#[test]
fn every_cut_out_material_stays_visible_at_every_cloud_level() {
    use lodlab::measure::material_share::{MaterialColours, material_shares};
    let b = baked("card-bush");
    let colours = MaterialColours::of(&b.tree);
    assert_eq!(colours.names, ["bush leaf", "blossom"]);
    let levels = cloud_levels(b);
    assert!(levels.len() >= 4, "{} cloud levels", levels.len());
    let shares = material_shares(crate::common::gpu(), &b.tree, &colours, &levels, 240.0).unwrap();
    let flowers = shares[0].full[1];
    assert!(
        (0.05..0.5).contains(&flowers),
        "the full bush's flowers: {flowers}"
    );
    for s in &shares {
        assert!(
            s.worst() <= 0.2,
            "level {}: {:?} against the full tree's {:?}",
            s.level,
            s.shares,
            s.full
        );
    }
}

/// Each card tree's finest cloud is close to it. The palm's fronds, bent at every segment,
/// are split at their bends instead of pressed flat onto one plane each (which shrank the
/// crown: the old finest cloud scored 0.62 by the thesis's measure); the oak's crossed cards
/// likewise; the pine's cards lie on planes of their own instead of tilted by the view penalty.
/// The palm's leaflets, 9 cm apart, shift by a leaflet where ε moves a frond a few
/// centimetres, and its figure is the highest (at ε → 0 it is 0.12 at 800×600: its texture's
/// floor).
#[test]
fn the_finest_cloud_of_each_card_tree_is_close_to_it() {
    let gpu = crate::common::gpu();
    for (name, most) in [
        ("card-bush", 0.1),
        ("card-oak", 0.1),
        ("card-pine", 0.1),
        ("card-palm", 0.35),
    ] {
        let b = baked(name);
        let (_, finest) = cloud_levels(b)[0];
        let e =
            lodlab::measure::colour_error::colour_error(gpu, &b.tree, finest, [800, 600]).unwrap();
        assert!(e <= most, "{name}: colour error {e:.3} at the finest cloud");
        // The crown keeps its reach: the billboards span what the leaves span, to within the
        // transparent margins of the leaf cards, which trimmed outlines leave out (the bush's
        // finest cloud spans 94–96% of its cards' extent, its colour error unchanged).
        let (foliage, _) = finest.foliage();
        let leaves = lodlab::bake::foliage::billboard::wood::only_foliage(&b.tree);
        let span = |m: &Model| {
            lodlab::model::Bounds::of(m.mesh.positions.iter().copied())
                .unwrap()
                .size()
        };
        let (cloud, tree) = (span(&foliage), span(&leaves));
        assert!(
            cloud.cmpge(tree * 0.92).all(),
            "{name}: the cloud spans {cloud}, the leaves {tree}"
        );
    }
}

/// The bush's billboards hold one or a few cards each, at an angle to their planes: drawn as
/// outlines trimmed round their leaves, the finest clouds cover well under their rectangles,
/// and every billboard's vertices are its outline's corners (at most eight).
#[test]
fn the_bushs_billboards_are_trimmed_round_their_leaves() {
    use lodlab::bake::foliage::billboard::trim::MAX_CORNERS;
    let b = baked("card-bush");
    let levels = cloud_levels(b);
    let (_, finest) = levels[0];
    let share = finest.drawn_area / finest.area;
    assert!(
        share < 0.85,
        "the finest cloud draws {share:.2} of its area"
    );
    assert_eq!(finest.corners.len(), finest.billboards);
    assert!(
        finest
            .corners
            .iter()
            .all(|&c| (3..=MAX_CORNERS as u32).contains(&c))
    );
    assert!(
        finest.corners.iter().any(|&c| c > 4),
        "some outlines beyond a quad"
    );
    let (foliage, _) = finest.foliage();
    let corners: u32 = finest.corners.iter().sum();
    assert_eq!(foliage.mesh.vertex_count() as u32, corners);
    // A fan a billboard: corners − 2 triangles each.
    assert_eq!(
        foliage.mesh.triangle_count() as u32,
        corners - 2 * finest.billboards as u32
    );
    for (_, l) in &levels {
        assert!(l.drawn_area <= l.area * 1.0001 && l.drawn_area > 0.0);
    }
}

/// No level costs more to draw than a finer one: the pine (155 triangles, its finest clouds
/// 93 billboards of two triangles each, larger than the cards they stand for) keeps its full
/// detail where its clouds would cost more, and every level drawn costs no more than the
/// full tree at its stretch.
#[test]
fn a_tree_lighter_than_its_clouds_keeps_its_full_detail_where_they_cost_more() {
    let b = baked("card-pine");
    let gpu = crate::common::gpu();
    let measure = lodlab::measure::colour_error::GpuColourError::new(gpu);
    let height = lodlab::bake::foliage::billboard::tree_height(&b.tree);
    let table = order::measure_costs(
        &measure,
        &b.tree,
        &b.chains,
        height,
        ChainOptions::default().tolerance_px,
    )
    .unwrap();
    assert!(
        table.costs[1][1] > table.costs[0][1],
        "the finest cloud costs more than the pine: {} against {}",
        table.costs[1][1],
        table.costs[0][1]
    );
    assert_eq!(b.choices[0].drawn_level, 0, "{:?}", b.choices[0]);
    for (k, c) in b.choices.iter().enumerate() {
        assert!(
            c.drawn_cost <= table.costs[0][k + 1],
            "stretch {}: {c:?} costs more than the full tree ({})",
            k + 1,
            table.costs[0][k + 1]
        );
    }
    // And the trees of thousands of cards still draw their clouds: the bush's finest
    // stretch is no full tree.
    let bush = baked("card-bush");
    assert!(
        bush.choices.iter().any(|c| c.drawn_level > 0),
        "{:?}",
        bush.choices
    );
}

/// Each file reads back as the tree it stands for: props of one bone and no clip, their
/// foliage cut out; the bush's two cut-out materials keep their own cutoffs; the oak, written
/// in centimetres with Z up and squashed under a root that stretches it, stands 1.3 times
/// as tall as it is wide, in metres; the pine has 155 triangles.
#[test]
fn card_trees_import_as_artists_laid_them_out() {
    for name in NAMES {
        let m = lodlab::import::load_model(name).unwrap();
        assert!(lodlab::bake::foliage::billboard::is_tree(&m), "{name}");
        assert_eq!(m.skeleton.bone_count(), 1, "{name}");
        assert!(m.clips.iter().all(|c| c.channels.is_empty()), "{name}");
        let cut: Vec<f32> = m
            .materials
            .iter()
            .filter(|x| x.cuts_out())
            .map(|x| x.alpha_cutoff)
            .collect();
        match name {
            "card-bush" => {
                assert_eq!(cut, [0.5, 0.3]);
                // No trunk: every triangle is a card.
                assert_eq!(m.materials.len(), 2);
            }
            "card-pine" => assert_eq!(m.mesh.triangle_count(), 155),
            "card-oak" => {
                let size = lodlab::model::Bounds::of(
                    m.mesh
                        .positions
                        .iter()
                        .map(|&p| m.skeleton.root_transform.transform_point3(p)),
                )
                .unwrap()
                .size();
                assert!((7.0..9.5).contains(&size.y), "{size}");
                assert!(size.y > size.x && size.y > size.z, "{size}");
            }
            _ => {}
        }
    }
}

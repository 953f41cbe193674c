//! Which of a tree's levels each screen size draws: by ε alone, as the thesis orders its
//! chain (each level in turn from where its ε projects to the tolerance), or by measured error
//! per cost.
//!
//! The ε-ordered chain draws level k between its switch size s_k (the tree's height in pixels
//! where ε_k projects to the tolerance) and s_{k+1}. Its levels are not equally good for what
//! they cost: a level of view-selected clumps draws a sixth of the billboards of the cloud
//! before it and can match the cloud's colour error, yet the ε order only reaches it past the
//! cloud. Ordered by cost, each stretch [s_{k+1}, s_k) draws the cheapest level whose colour
//! error measured at s_k (where the ε chain's own level k is closest, so errs most) is no
//! worse than level k's there. Cost is what the adapter pays for the level at that size:
//! the fragments it shades, measured, and its triangles at [`TRIANGLE_FRAGMENTS`] fragments
//! each. The levels drawn never get finer as the tree gets smaller: of the sequences that keep
//! both rules the cheapest in all is drawn (see [`choose`]). The result is again a chain of
//! levels with switch sizes (the stretches' ε), so selection and transitions treat it as they
//! treat the ε chain. (Issue 44: the clump levels matched the clouds' error at a sixth of
//! their billboards, and the ε chain never drew them in the default scene.)

pub use crate::bake::foliage::billboard::chain::levels::FoliageOrder;
use crate::bake::foliage::billboard::chain::levels::TreeLevel;
use crate::bake::gpu_products::MeasureColour;
use crate::model::Model;
use anyhow::{Result, anyhow};
use serde::{Deserialize, Serialize};

/// A triangle's cost in fragments on a CPU rasteriser: lavapipe on 2 cores draws about 9 M
/// triangles/s of the trees' shader and shades about 80 M foliage fragments/s (`lodlab
/// bench` on the default scene), so one triangle costs about what 9 fragments do.
pub const TRIANGLE_FRAGMENTS: f64 = 9.0;

/// A tree's levels as the orders choose among them: every level its bake made, finest
/// first (level 0 the tree; the clump levels past the impostor's place in the ε chain
/// included, the impostor last), and the ε chain, whose level k is `candidates[reference[k]]`.
pub struct Chains {
    pub candidates: Vec<TreeLevel>,
    pub epsilon: Vec<TreeLevel>,
    pub reference: Vec<usize>,
}

/// One stretch of sizes of a cost-ordered chain: what the ε chain draws there and what is
/// drawn instead, with the figures the choice was made on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CostChoice {
    /// The tree's height in pixels where the stretch begins (its largest size).
    pub px: f32,
    /// The ε chain's level there (an index into the ε chain), and the level drawn (an index
    /// into the candidates).
    pub epsilon_level: usize,
    pub drawn_level: usize,
    /// Colour errors at `px` of the ε chain's level and of the level drawn.
    pub epsilon_error: f32,
    pub drawn_error: f32,
    /// Costs at `px` (fragments plus [`TRIANGLE_FRAGMENTS`] a triangle).
    pub epsilon_cost: f64,
    pub drawn_cost: f64,
}

/// What a level costs at a size: fragments (None where the adapter cannot count them) and
/// triangles.
pub fn cost(fragments: Option<f64>, triangles: usize) -> f64 {
    fragments.unwrap_or(0.0) + TRIANGLE_FRAGMENTS * triangles as f64
}

/// The choice for each stretch k ≥ 1 of the ε chain (level 0, the full tree, keeps the sizes
/// above s_1). A stretch may draw candidate j when j is the full tree or no finer than the ε
/// chain's own level there (`reference[k]`), its error is no worse than that level's, and no
/// finer candidate the stretch may draw costs less there: a level never costs more to draw
/// than a finer one, and a tree lighter than its clouds (a few hundred triangles of cards,
/// whose clouds hold as many billboards) keeps its full detail for as long as that is
/// cheapest. And the levels drawn never get finer as the tree gets smaller, so that a tree
/// does not go from its impostor back to clumps further off (measured errors at a few pixels
/// are noisy enough to suggest it). Of the sequences that keep these rules (the ε chain's own
/// is one, where its levels get cheaper as they coarsen), the cheapest in all is chosen, by
/// dynamic programming over (stretch, level drawn); of equal costs the finer.
/// `errors[j][k]` is candidate j's colour error at stretch k's switch size `switch_px[k]`,
/// `costs[j][k]` its cost there (entries for 0 < j < `reference[k]` unused).
pub fn choose(
    switch_px: &[f32],
    reference: &[usize],
    errors: &[Vec<f32>],
    costs: &[Vec<f64>],
) -> Vec<CostChoice> {
    let (n, m) = (errors.len(), switch_px.len());
    if m < 2 {
        return Vec::new();
    }
    let may_stand_in = |j: usize, k: usize| {
        (j == 0 || j >= reference[k]) && errors[j][k] <= errors[reference[k]][k]
    };
    let allowed = |j: usize, k: usize| {
        may_stand_in(j, k) && (0..j).all(|i| !may_stand_in(i, k) || costs[i][k] >= costs[j][k])
    };
    // total[k][j]: the least cost of stretches 1..=k drawing j at k; from[k][j]: what k − 1 drew.
    let mut total = vec![vec![f64::INFINITY; n]; m];
    let mut from = vec![vec![0usize; n]; m];
    total[0][0] = 0.0;
    for k in 1..m {
        for j in (0..n).filter(|&j| allowed(j, k)) {
            let best = (0..=j)
                .filter(|&i| total[k - 1][i].is_finite())
                .min_by(|&a, &b| total[k - 1][a].total_cmp(&total[k - 1][b]).then(a.cmp(&b)));
            if let Some(i) = best {
                total[k][j] = total[k - 1][i] + costs[j][k];
                from[k][j] = i;
            }
        }
    }
    let last = (0..n)
        .filter(|&j| total[m - 1][j].is_finite())
        .min_by(|&a, &b| total[m - 1][a].total_cmp(&total[m - 1][b]).then(a.cmp(&b)))
        .unwrap_or(reference[m - 1]);
    let mut drawn = vec![0; m];
    drawn[m - 1] = last;
    for k in (1..m - 1).rev() {
        drawn[k] = from[k + 1][drawn[k + 1]];
    }
    (1..m)
        .map(|k| {
            let r = reference[k];
            CostChoice {
                px: switch_px[k],
                epsilon_level: k,
                drawn_level: drawn[k],
                epsilon_error: errors[r][k],
                drawn_error: errors[drawn[k]][k],
                epsilon_cost: costs[r][k],
                drawn_cost: costs[drawn[k]][k],
            }
        })
        .collect()
}

/// The chain the choices draw: level 0, then each stretch's level from the stretch's ε (the
/// ε chain's level there), a level drawn over several stretches in a row listed once.
pub fn chain_of(chains: &Chains, choices: &[CostChoice]) -> Vec<TreeLevel> {
    let mut out = vec![chains.candidates[0].clone()];
    let mut last = 0;
    for c in choices {
        if c.drawn_level != last {
            let mut level = chains.candidates[c.drawn_level].clone();
            level.epsilon = chains.epsilon[c.epsilon_level].epsilon;
            out.push(level);
            last = c.drawn_level;
        }
    }
    out
}

/// What the cost order is chosen from: each stretch's switch size, and each candidate's
/// colour error and cost there (infinite where it cannot stand in: finer than the stretch's
/// own level).
pub struct CostTable {
    pub switch_px: Vec<f32>,
    /// `errors[j][k]`, `costs[j][k]`: candidate j at stretch k's switch size.
    pub errors: Vec<Vec<f32>>,
    pub costs: Vec<Vec<f64>>,
}

/// Measures every candidate level of `chains` at the switch sizes of the ε chain's stretches
/// it could stand in (the full tree at all of them: its error is 0 by definition, its cost
/// measured), and chooses each stretch's level (see [`choose`]). The tree is
/// `height` high in scene units; `tolerance_px` sets the switch sizes.
pub fn by_cost(
    measure: &dyn MeasureColour,
    tree: &Model,
    chains: &Chains,
    height: f32,
    tolerance_px: f32,
) -> Result<Vec<CostChoice>> {
    let table = measure_costs(measure, tree, chains, height, tolerance_px)?;
    let choices = choose(
        &table.switch_px,
        &chains.reference,
        &table.errors,
        &table.costs,
    );
    for c in &choices {
        log::debug!(
            "{}: from {:.1} px the ε chain draws level {} (error {:.3}, cost {:.0}); by cost, \
             level {} of {} (error {:.3}, cost {:.0})",
            tree.name,
            c.px,
            c.epsilon_level,
            c.epsilon_error,
            c.epsilon_cost,
            c.drawn_level,
            chains.candidates.len() - 1,
            c.drawn_error,
            c.drawn_cost
        );
    }
    Ok(choices)
}

/// The [`CostTable`] of `chains`, measured through `measure` (see [`by_cost`]).
pub fn measure_costs(
    measure: &dyn MeasureColour,
    tree: &Model,
    chains: &Chains,
    height: f32,
    tolerance_px: f32,
) -> Result<CostTable> {
    let (n, m) = (chains.candidates.len(), chains.epsilon.len());
    let switch_px: Vec<f32> = chains
        .epsilon
        .iter()
        .map(|l| tolerance_px * height / l.epsilon.max(1e-9))
        .collect();
    let mut errors = vec![vec![f32::INFINITY; m]; n];
    let mut costs = vec![vec![f64::INFINITY; m]; n];
    for j in 0..n {
        // The stretches candidate j can stand in: those whose own level is j or finer; the
        // full tree, all.
        let stretches: Vec<usize> = (1..m)
            .filter(|&k| j == 0 || chains.reference[k] <= j)
            .collect();
        if stretches.is_empty() {
            continue;
        }
        let cloud = &chains.candidates[j].cloud;
        let bake = cloud
            .bake()
            .map_err(|e| anyhow!("{}: {e}", cloud.model.name))?;
        // A clump level draws, from each view, only its sector's planes.
        let triangles = crate::bake::gpu_data::view_subsets::mean_triangles(&bake).round() as usize;
        let sizes: Vec<f32> = stretches.iter().map(|&k| switch_px[k]).collect();
        let e = if j == 0 {
            vec![0.0; sizes.len()]
        } else {
            measure.colour_errors(tree, &cloud.model, bake.clone(), &sizes)?
        };
        let f = measure.fragments(tree, &cloud.model, bake, &sizes)?;
        for (i, &k) in stretches.iter().enumerate() {
            errors[j][k] = e[i];
            costs[j][k] = cost(f.as_ref().map(|f| f[i]), triangles);
        }
    }
    Ok(CostTable {
        switch_px,
        errors,
        costs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Candidates 1..5: clouds 1 and 2, clumps 3 and 4 (cut from the ε chain, which puts the
    /// impostor, candidate 5, from stretch 3 on). Clumps 3 is cheaper than the clouds and no
    /// worse at their sizes; the impostor is cheapest but worse until its own stretch.
    /// Switch sizes, references, errors and costs (as [`choose`] takes them).
    type Figures = (Vec<f32>, Vec<usize>, Vec<Vec<f32>>, Vec<Vec<f64>>);

    fn figures() -> Figures {
        let px = vec![f32::INFINITY, 300.0, 150.0, 75.0];
        let reference = vec![0, 1, 2, 5];
        let inf = f32::INFINITY;
        let errors = vec![
            vec![inf; 4],
            vec![inf, 0.10, inf, inf],
            vec![inf, 0.12, 0.12, inf],
            vec![inf, 0.09, 0.11, inf],
            vec![inf, 0.20, 0.13, inf],
            vec![inf, 0.30, 0.25, 0.20],
        ];
        let costs = vec![
            vec![f64::INFINITY; 4],
            vec![0.0, 900.0, 0.0, 0.0],
            vec![0.0, 700.0, 400.0, 0.0],
            vec![0.0, 300.0, 150.0, 0.0],
            vec![0.0, 200.0, 100.0, 0.0],
            vec![0.0, 50.0, 30.0, 20.0],
        ];
        (px, reference, errors, costs)
    }

    #[test]
    fn each_stretch_draws_the_cheapest_level_no_worse_than_the_epsilon_chains() {
        let (px, reference, errors, costs) = figures();
        let choices = choose(&px, &reference, &errors, &costs);
        let drawn: Vec<usize> = choices.iter().map(|c| c.drawn_level).collect();
        // Clumps past the impostor's place stand in for the clouds; the impostor keeps its
        // stretch.
        assert_eq!(drawn, [3, 3, 5]);
        for c in &choices {
            assert!(c.drawn_error <= c.epsilon_error, "{c:?}");
            assert!(c.drawn_cost <= c.epsilon_cost, "{c:?}");
        }
    }

    #[test]
    fn a_tree_lighter_than_its_clouds_keeps_its_full_detail_and_no_level_costs_more_than_a_finer_one()
     {
        let (px, reference, mut errors, mut costs) = figures();
        // A tree of a few cards: the full tree (error 0 everywhere) costs less than cloud 1
        // and clumps 3 at stretch 1, and less than every cloud at stretch 2; only the
        // impostor is cheaper, at its own stretch.
        errors[0] = vec![0.0; 4];
        costs[0] = vec![0.0, 250.0, 120.0, 60.0];
        let choices = choose(&px, &reference, &errors, &costs);
        let drawn: Vec<usize> = choices.iter().map(|c| c.drawn_level).collect();
        assert_eq!(drawn, [0, 0, 5]);
        for (k, c) in choices.iter().enumerate() {
            // Nothing finer that may stand in costs less than what is drawn.
            for j in 0..c.drawn_level {
                let may = j == 0 || j >= reference[k + 1];
                assert!(
                    !may || errors[j][k + 1] > c.epsilon_error || costs[j][k + 1] >= c.drawn_cost,
                    "{c:?} against {j}"
                );
            }
        }
        // The chain drawn: the tree, then the impostor from its stretch.
        assert_eq!(choices[2].drawn_error, 0.20);
        // Where the full tree is dearer than clumps 3 (as on a tree of thousands of leaves),
        // the clumps are drawn as before.
        costs[0] = vec![0.0, 5000.0, 4000.0, 3000.0];
        let drawn: Vec<usize> = choose(&px, &reference, &errors, &costs)
            .iter()
            .map(|c| c.drawn_level)
            .collect();
        assert_eq!(drawn, [3, 3, 5]);
    }

    #[test]
    fn a_level_no_other_beats_keeps_its_stretch() {
        let (px, reference, mut errors, costs) = figures();
        // Clumps 3 now worse than cloud 1 at its size, clumps 4 too.
        errors[3][1] = 0.2;
        let drawn: Vec<usize> = choose(&px, &reference, &errors, &costs)
            .iter()
            .map(|c| c.drawn_level)
            .collect();
        assert_eq!(drawn, [1, 3, 5]);
    }

    #[test]
    fn the_levels_drawn_never_get_finer_further_off() {
        let (mut px, mut reference, mut errors, mut costs) = figures();
        // A fourth stretch, the ε chain's clumps 4 (a level the impostor did not displace
        // here): the impostor is measured worse there than the clumps, which a level-by-level
        // choice would go back to after the impostor.
        px.push(37.0);
        reference[3] = 3;
        reference.push(4);
        for row in errors.iter_mut() {
            row.push(f32::INFINITY);
        }
        for row in costs.iter_mut() {
            row.push(f64::INFINITY);
        }
        errors[3][3] = 0.20;
        costs[3][3] = 60.0;
        errors[4][3] = 0.19;
        costs[4][3] = 40.0;
        errors[5][3] = 0.20;
        costs[5][3] = 20.0;
        errors[4][4] = 0.30;
        costs[4][4] = 30.0;
        errors[5][4] = 0.35;
        costs[5][4] = 10.0;
        let choices = choose(&px, &reference, &errors, &costs);
        let drawn: Vec<usize> = choices.iter().map(|c| c.drawn_level).collect();
        assert!(drawn.windows(2).all(|w| w[0] <= w[1]), "{drawn:?}");
        for c in &choices {
            assert!(c.drawn_error <= c.epsilon_error, "{c:?}");
        }
        // The impostor is cheapest at stretch 3 but too poor at stretch 4, which keeps the
        // clumps: so stretch 3 draws clumps too.
        assert_eq!(drawn, [3, 3, 4, 4]);
    }

    #[test]
    fn the_chain_lists_each_level_drawn_once_from_its_first_stretch() {
        use crate::bake::foliage::billboard::chain::levels::CloudLevel;
        let tree = crate::generate::tree::sapling();
        let level = |epsilon: f32, billboards: usize| {
            let mut cloud = CloudLevel::full(&tree);
            cloud.billboards = billboards;
            TreeLevel {
                epsilon,
                kind: None,
                cloud,
                bake_seconds: 0.0,
            }
        };
        let candidates: Vec<TreeLevel> =
            [(0.0, 0), (1.0, 1), (2.0, 2), (4.0, 3), (8.0, 4), (4.0, 5)]
                .iter()
                .map(|&(e, b)| level(e, b))
                .collect();
        let reference = vec![0, 1, 2, 5];
        let chains = Chains {
            epsilon: reference.iter().map(|&i| candidates[i].clone()).collect(),
            reference,
            candidates,
        };
        let (px, reference, errors, costs) = figures();
        let chain = chain_of(&chains, &choose(&px, &reference, &errors, &costs));
        let drawn: Vec<(f32, usize)> = chain
            .iter()
            .map(|l| (l.epsilon, l.cloud.billboards))
            .collect();
        // Clumps 3 from cloud 1's switch size, the impostor from its own (ε 4).
        assert_eq!(drawn, [(0.0, 0), (1.0, 3), (4.0, 5)]);
    }
}

//! The octahedral impostor at the end of a tree's chain: baked from the tree at rest, and
//! placed by the rule characters' impostors follow (`bake::impostor::placement`), measured
//! through the colour seam.

use crate::bake::foliage::billboard::chain::levels::{
    ChainOptions, CloudKind, CloudLevel, TreeLevel,
};
use crate::bake::gpu_data::drawable::Drawable;
use crate::bake::gpu_products::{MeasureColour, MeasureImpostor, RasterizeAtlas};
use crate::bake::impostor::octahedral::{self, ViewGrid};
use crate::bake::impostor::placement;
use crate::model::Model;
use anyhow::{Result, anyhow};

/// The impostor after a chain's clouds: the tree's octahedral impostor, placed by the rule
/// characters' impostors follow ([`placement`]): it takes the place of the finest level k,
/// from the coarse end on and never level 1, where its colour error at k's switch size is no
/// worse than level k's own; or, beating none there, comes in further off than the coarsest
/// cloud. So the impostor's error at its switch size stays within the chain's own, and
/// selection treats it like any level.
///
/// Returns the impostor level and the index it goes in at (the levels from there on give way
/// to it; the chain's length where it comes in further off), or `None` where it beats no cloud
/// level even two, four or eight times further off (it is then not part of the chain).
pub fn impostor_level(
    raster: &dyn RasterizeAtlas,
    measure: &dyn MeasureColour,
    tree: &Model,
    chain: &[TreeLevel],
    opts: &ChainOptions,
) -> Result<Option<(TreeLevel, usize)>> {
    let start = web_time::Instant::now();
    let grid = ViewGrid {
        frames: octahedral::FRAMES,
        cell: octahedral::CELL,
    };
    let (model, frame) = octahedral::bake_impostor(raster, tree, grid)?;
    log::debug!(
        "{}: impostor views baked in {:.2} s",
        tree.name,
        start.elapsed().as_secs_f64()
    );
    let level = CloudLevel::impostor(model, frame, 1);
    let mut fit = TreeFit {
        measure,
        tree,
        impostor: &level,
        impostor_bake: level
            .bake()
            .map_err(|e| anyhow!("{}: {e}", level.model.name))?,
        chain,
    };
    let errors: Vec<f32> = chain.iter().map(|l| l.epsilon).collect();
    let height = crate::bake::foliage::billboard::tree_height(tree);
    // Level 1 is the first cloud of the leaves, the finest step of foliage simplification the
    // chain has: the impostor stands only for coarser ones.
    let (placed, replaces) = placement::place(&errors, height, opts.tolerance_px, 2, &mut fit)?;
    for m in &placed.measured {
        log::debug!(
            "{}: at {:.1} px (level {}) the impostor's colour error is {:.3}, the level's {:.3}",
            tree.name,
            m.px,
            m.level,
            m.impostor,
            m.mesh
        );
    }
    log::debug!(
        "{}: impostor baked and placed in {:.2} s",
        tree.name,
        start.elapsed().as_secs_f64()
    );
    Ok(placed.epsilon.map(|epsilon| {
        let level = TreeLevel {
            epsilon,
            kind: Some(CloudKind::Impostor {
                frames: grid.frames,
            }),
            cloud: level,
            bake_seconds: start.elapsed().as_secs_f64(),
        };
        (level, replaces.unwrap_or(chain.len()))
    }))
}

/// A tree's impostor measured beside its chain's levels through the colour seam: each drawn
/// whole, wood and all, against the full tree.
pub(crate) struct TreeFit<'a> {
    measure: &'a dyn MeasureColour,
    tree: &'a Model,
    impostor: &'a CloudLevel,
    /// The impostor baked for the GPU once (its views' mipmaps), for every size it is
    /// measured at.
    impostor_bake: Drawable,
    chain: &'a [TreeLevel],
}

impl MeasureImpostor for TreeFit<'_> {
    fn errors(&mut self, level: usize, px: f32) -> Result<(f32, f32)> {
        let impostor = self.measure.colour_errors(
            self.tree,
            &self.impostor.model,
            self.impostor_bake.clone(),
            &[px],
        )?[0];
        let cloud = &self.chain[level].cloud;
        let bake = cloud
            .bake()
            .map_err(|e| anyhow!("{}: {e}", cloud.model.name))?;
        let own = self
            .measure
            .colour_errors(self.tree, &cloud.model, bake, &[px])?[0];
        Ok((impostor, own))
    }
}

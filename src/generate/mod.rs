//! The project's own demo creatures, generated procedurally: box-modelled control cages smoothed
//! by Catmull–Clark subdivision, automatic skin weights, painted textures and keyframed clips;
//! and the demo trees ([`tree`]): branching skeletons, tube wood, leaf quads and a wind loop.
//! `lodlab gen-assets` writes them to `assets/` as `.glb`; everything else reads those files.

pub mod armour;
pub mod build;
pub mod cage;
pub mod cylinder;
pub mod facets;
pub mod finish;
pub mod glb;
pub mod horse;
pub mod rig;
pub mod split_tube;
pub mod tree;
pub mod walker;
pub mod wild;

use crate::model::Model;

/// Generates a built-in creature by asset name.
pub fn generate(name: &str) -> Option<Model> {
    match name {
        "horse" => Some(horse::horse()),
        "walker" => Some(walker::walker()),
        "broadleaf" => Some(tree::broadleaf()),
        "conifer" => Some(tree::conifer()),
        "sapling" => Some(tree::sapling()),
        "split-tube" => Some(split_tube::split_tube()),
        "armour" => Some(armour::armour()),
        "patchwork" => Some(walker::patchwork()),
        "lowpoly" => Some(walker::lowpoly()),
        _ => None,
    }
}

/// The `.glb` bytes of a built-in asset by name: a generated model as [`glb::to_glb`] writes
/// it, or one of the [`wild`] files as its document lays it out.
pub fn file(name: &str) -> Option<Vec<u8>> {
    match name {
        "robot" => Some(wild::robot::robot().to_glb()),
        "mocap" => Some(wild::mocap::mocap().to_glb()),
        "mocap-walk" => Some(wild::mocap::mocap_walk().to_glb()),
        "knight" => Some(wild::knight::knight().to_glb()),
        "card-palm" => Some(wild::cards::card_palm().to_glb()),
        "card-bush" => Some(wild::cards::card_bush().to_glb()),
        "card-oak" => Some(wild::cards::card_oak().to_glb()),
        "card-pine" => Some(wild::cards::card_pine().to_glb()),
        _ => generate(name).map(|m| glb::to_glb(&m)),
    }
}

//! How trees are shown: the foliage panel's level policy and view settings, the same on the
//! command line.

use crate::bake::foliage::billboard::chain::{ChainOptions, ChainStyle};

crate::choice! {
    own_values;
    /// What trees become under a simplified method: the foliage panel's level policy.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
    pub enum FoliagePolicy {
        /// Skeleton clouds near, spectral clouds far, view-selected clumps farthest
        /// ([`ChainStyle::Automatic`]).
        #[default]
        Automatic => "automatic",
        /// The skeleton-cloud chain ([`ChainStyle::Skeleton`]).
        Skeleton => "skeleton clouds",
        /// The spectral-cloud chain ([`ChainStyle::Spectral`]).
        Spectral => "spectral clouds",
        /// Trees keep every leaf (level 0) at every distance.
        Full => "full",
    }
}

impl FoliagePolicy {
    /// The chain the trees switch along; None: they stay full.
    pub fn chain_style(self) -> Option<ChainStyle> {
        match self {
            FoliagePolicy::Full => None,
            FoliagePolicy::Skeleton => Some(ChainStyle::Skeleton),
            FoliagePolicy::Spectral => Some(ChainStyle::Spectral),
            FoliagePolicy::Automatic => Some(ChainStyle::Automatic),
        }
    }
}

/// On the command line a policy is the first word of its name (`full`, `skeleton`,
/// `spectral`, `automatic`); the whole name is an alias.
impl clap::ValueEnum for FoliagePolicy {
    fn value_variants<'a>() -> &'a [Self] {
        &FoliagePolicy::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        let name = self.name();
        let word = name.split(' ').next().unwrap_or(name);
        let value = clap::builder::PossibleValue::new(word);
        Some(if word == name {
            value
        } else {
            value.alias(name)
        })
    }
}

/// How trees are shown: the foliage panel's choices, and the same on the command line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FoliageView {
    pub policy: FoliagePolicy,
    /// How the trees' chains are cut; its style follows the policy.
    pub chain: ChainOptions,
    /// Scales every tree's own wind strength (0: still air).
    pub wind: f32,
    /// Draw the billboards' outlines over them.
    pub outlines: bool,
    /// Colour trees by level (the characters keep their colours).
    pub tint: bool,
    /// Light billboards per texel through their atlases by the leaves' normals; off, by their
    /// planes, as the thesis did (the crown's occlusion is in their colour either way). None:
    /// by adapter (see `Gpu::atlas_lighting`).
    pub atlas_lighting: Option<bool>,
    /// Draw plain foliage's depth before its colour (see the renderer's `FoliagePhase`).
    pub prepass: bool,
    /// Far trees drawn as forest patches, a card per layout cell (see
    /// `bake::foliage::patch`).
    pub patches: bool,
}

impl Default for FoliageView {
    fn default() -> Self {
        FoliageView {
            policy: FoliagePolicy::default(),
            chain: ChainOptions::default(),
            wind: 1.0,
            outlines: false,
            tint: false,
            atlas_lighting: None,
            prepass: false,
            patches: false,
        }
    }
}

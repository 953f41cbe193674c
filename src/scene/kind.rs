//! Which scene a world shows, and every scene's defaults in one place.

use serde::{Deserialize, Serialize};

crate::choice! {
    own_values;
    /// The scenes lodlab knows.
    #[derive(
        Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum,
    )]
    #[serde(rename_all = "lowercase")]
    pub enum SceneKind {
        /// The crowd walking round a clearing in the forest.
        #[default]
        Mixed => "mixed",
        /// Characters alone.
        Crowd => "crowd",
        /// Trees alone.
        Forest => "forest",
        /// Copies of one model (Merry et al. §6.2: by default 100 horses).
        Study => "study",
    }
}

/// Characters in a crowd unless told.
pub const DEFAULT_CHARACTERS: usize = 300;

/// Trees round the mixed scene's clearing unless told.
pub const DEFAULT_MIXED_TREES: usize = 500;

/// Models of the default crowd.
pub const DEFAULT_MODELS: &[&str] = &["horse", "walker"];

/// Trees of the default forest.
pub const DEFAULT_TREES: &[&str] = &["broadleaf", "conifer"];

impl SceneKind {
    /// How many instances the scene shows unless told: characters, or trees in the forest.
    pub fn default_count(self) -> usize {
        match self {
            SceneKind::Forest => 500,
            SceneKind::Study => 100,
            SceneKind::Mixed | SceneKind::Crowd => DEFAULT_CHARACTERS,
        }
    }

    /// The built-in models the scene shows unless told.
    pub fn default_models(self) -> Vec<&'static str> {
        match self {
            SceneKind::Forest => DEFAULT_TREES.to_vec(),
            SceneKind::Mixed => [DEFAULT_MODELS, DEFAULT_TREES].concat(),
            SceneKind::Study => DEFAULT_MODELS[..1].to_vec(),
            SceneKind::Crowd => DEFAULT_MODELS.to_vec(),
        }
    }
}

//! Mesh helpers shared by the import and the bake.

pub mod weld;

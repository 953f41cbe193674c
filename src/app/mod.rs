//! Front ends: the command-line tools and the viewer.

pub mod bake;
pub mod bench;
pub mod cli;
pub mod export;
pub mod gen_assets;
pub mod plotting;
pub mod record;
pub mod report;
pub mod shot;
pub mod soak;
pub mod study;
pub mod tree_report;
pub mod video;
pub mod viewer;
pub mod window;

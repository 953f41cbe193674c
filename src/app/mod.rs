//! Front ends: the command line ([`cli`] parses it, [`commands`] runs each command), the
//! viewer, user studies, and the window and video helpers they share.

pub mod cli;
pub mod commands;
pub mod json;
pub mod panel_image;
pub mod plotting;
pub mod progress;
pub mod shard;
pub mod study;
pub mod video;
pub mod viewer;
pub mod window;

//! Front ends: the command line ([`cli`] parses it, [`commands`] runs each command), the
//! viewer, user studies, and the window and video helpers they share. The web build (wasm32)
//! has the viewer and the window alone: the commands, studies, plots and video are native.

pub mod cli;
#[cfg(not(target_arch = "wasm32"))]
pub mod commands;
pub mod json;
pub mod panel_image;
#[cfg(not(target_arch = "wasm32"))]
pub mod plotting;
#[cfg(not(target_arch = "wasm32"))]
pub mod progress;
pub mod shard;
pub mod site;
#[cfg(not(target_arch = "wasm32"))]
pub mod study;
#[cfg(not(target_arch = "wasm32"))]
pub mod video;
pub mod viewer;
pub mod window;

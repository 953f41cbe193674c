//! Front ends: the command-line tools and the viewer.

pub mod shot;
pub mod world;

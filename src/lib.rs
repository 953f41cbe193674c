//! lodlab: a real-time viewer for comparing level-of-detail methods on animated crowds.
//!
//! Data flows through the modules in this order:
//! - [`import`]: glTF files and the project's own generators ([`generate`]) → [`model::Model`];
//! - [`bake`]: pure CPU code → animation textures, vertex textures (plain data);
//! - [`scene`]: instances, cameras, paths;
//! - [`render`]: wgpu;
//! - [`app`]: the front ends (viewer, `shot`, `gen-assets`).

pub mod anim;
pub mod app;
pub mod assets;
pub mod bake;
pub mod error;
pub mod generate;
pub mod import;
pub mod model;
pub mod render;
pub mod scene;

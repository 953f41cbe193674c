//! lodlab: a real-time viewer for comparing level-of-detail methods on animated crowds.
//!
//! Data flows through the modules in this order, each using only those before it
//! (`tests/integration/layout.rs` checks it):
//!
//! 1. [`model`], [`anim`], [`geometry`]: the data a model is, keyframes and poses, welding;
//! 2. [`import`]: glTF files, and the project's own generators ([`generate`]), to
//!    [`model::Model`];
//! 3. [`bake`]: pure CPU code, sorted by subject (character levels, foliage, impostors), to
//!    plain data the GPU uploads ([`bake::gpu_data`]), cached by [`bake::cache`]; what it
//!    needs drawn it asks for through the traits of [`bake::gpu_products`];
//! 4. [`scene`]: instances, cameras, paths, level selection;
//! 5. [`render`]: everything wgpu;
//! 6. [`runtime`]: what runs a scene (its spec loaded, the world drawn each frame, levels
//!    installed and baked in the background, headless frames);
//! 7. [`measure`]: measurements that draw worlds and compare pictures (colour error, an
//!    impostor's fit, shading error, SSIM);
//! 8. [`app`]: the front ends: the command line and its commands, the viewer, user studies.

pub mod anim;
pub mod app;
pub mod assets;
pub mod atomic;
pub mod bake;
pub mod choice;
pub mod error;
pub mod generate;
pub mod geometry;
pub mod import;
pub mod measure;
pub mod model;
pub mod render;
pub mod runtime;
pub mod scene;

//! lodlab: a real-time viewer for comparing level-of-detail methods on animated crowds.
//!
//! Data flows through the modules in this order:
//!
//! 1. [`import`]: glTF files and the project's own generators ([`generate`]) to
//!    [`model::Model`];
//! 2. [`bake`]: pure CPU code to animation textures and vertex textures (plain data);
//! 3. [`scene`]: instances, cameras, paths;
//! 4. [`render`]: everything wgpu;
//! 5. [`runtime`]: what runs a scene (its spec loaded, the world drawn each frame, levels
//!    installed and baked in the background, headless frames and the measurements that draw
//!    worlds);
//! 6. [`app`]: the front ends (viewer, `shot`, `bake`, `bench`, `record`, `study`, …).

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

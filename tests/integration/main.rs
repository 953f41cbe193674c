//! The integration tests, one binary: the crate and its dependencies are linked once for all
//! of them (a binary a file took minutes of a fresh build), and what the modules share (a
//! device, the bake cache, generated models) is made once per run. `cargo test --test
//! integration NAME` runs the tests whose path contains NAME (a module, `trees::`, or a test).

mod common;

mod animation_space;
mod assets;
mod bad_input;
mod bench;
mod billboards;
mod browser;
mod card_trees;
mod cut_out_characters;
mod docs;
mod export;
mod field_models;
mod gltfpack;
mod gpu;
mod import_features;
mod import_models;
mod impostors;
mod layout;
mod lod_bake;
mod lod_commands;
mod lod_real_world;
mod lod_render;
mod lod_runtime;
mod malformed;
mod normal_maps;
mod options;
mod orders;
mod patches;
mod record;
mod root_motion;
mod shaders;
mod shared_skeletons;
mod soak;
mod spectral;
mod study;
mod third_party;
mod trees;
mod window;

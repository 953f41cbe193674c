//! Test models whose awkward properties live in the file, as files from elsewhere have them:
//! several meshes and skins, unskinned parts on nodes, an armature node that scales and turns
//! the skeleton, joints named and oriented as a rigging service names them, hundreds of plain
//! materials, morph targets, debris in the index buffers, clips sent without a mesh. Each is
//! written as a [`file::Document`], byte for byte the same on every run, and committed under
//! `assets/` like the other models ([`super::file`]).

pub mod file;
pub mod knight;
pub mod mocap;
pub mod random;
pub mod robot;
pub mod structure;

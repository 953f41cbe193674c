//! The plain data the bake hands the renderer: textures of texels, animation and vertex
//! textures, material layers, animation-space meshes, level packs and the drawable they make.

pub mod anim_texture;
pub mod animation_space;
pub mod drawable;
pub mod impostor_frames;
pub mod lod_pack;
pub mod materials;
pub mod root_motion;
pub mod spectra;
pub mod texels;
pub mod vertex_texture;
pub mod view_subsets;

//! Bake: pure CPU code that turns an imported [`Model`](crate::model::Model) into the plain
//! data the renderer uploads, sorted by subject:
//!
//! - [`character`]: Merry, Marais & Gain's progressive meshes in animation space (the
//!   simplifier, its levels and their measured errors), normal maps for coarse levels;
//! - [`foliage`]: Bennett-Therkildsen, Carlsen & Schmid's animated billboard clouds
//!   ([`foliage::billboard`]) and the DFT spectra that move them ([`foliage::spectral`]);
//! - [`impostor`]: the last levels of both, a picture of the model: octahedral impostors of
//!   trees and animated impostors of characters;
//! - [`gpu_data`]: the plain data all of them hand the renderer (animation, vertex and
//!   material textures, level packs, [`gpu_data::drawable::Drawable`]);
//! - [`gpu_products`]: the traits through which the bake asks the GPU for pictures, which the
//!   renderer implements;
//! - [`cache`]: the versioned, content-keyed cache of bake products.
//!
//! Nothing here touches the GPU; everything is testable headless.

pub mod cache;
pub mod character;
pub mod foliage;
pub mod gpu_data;
pub mod gpu_products;
pub mod impostor;

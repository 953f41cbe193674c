//! Render: everything that talks to wgpu. It sees the bake's outputs only as plain data.

pub mod atlas;
pub mod capture;
pub mod character;
pub mod gpu;
pub mod memory;
mod pipelines;
pub mod renderer;
pub mod shaders;
pub mod targets;
pub mod timer;
pub mod uniforms;

pub use gpu::Gpu;
pub use renderer::{CharacterShader, DebugView, FrameStats, Region, SceneRenderer, Side};
pub use uniforms::{FrameView, Lighting};

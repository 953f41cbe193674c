//! WGSL sources, compiled into the binary. Each pipeline's module is its own file with the shared
//! pieces it uses composed in front (WGSL has no includes). `tests/shaders.rs` validates every
//! composed module with naga.

const COMMON: &str = include_str!("../../shaders/common.wgsl");
const SKINNING: &str = include_str!("../../shaders/skinning.wgsl");
const MATERIAL: &str = include_str!("../../shaders/material.wgsl");
const CHARACTER: &str = include_str!("../../shaders/character.wgsl");
const PLAIN: &str = include_str!("../../shaders/plain.wgsl");
const CAPTURE: &str = include_str!("../../shaders/capture.wgsl");
const ENVIRONMENT: &str = include_str!("../../shaders/environment.wgsl");
const SHADOW: &str = include_str!("../../shaders/shadow.wgsl");
const ATLAS: &str = include_str!("../../shaders/atlas.wgsl");

/// A composed shader module: a name for labels and errors, and its full source.
pub struct ShaderSource {
    pub name: &'static str,
    pub parts: &'static [&'static str],
}

impl ShaderSource {
    pub fn source(&self) -> String {
        self.parts.concat()
    }

    pub fn create(&self, device: &wgpu::Device) -> wgpu::ShaderModule {
        device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(self.name),
            source: wgpu::ShaderSource::Wgsl(self.source().into()),
        })
    }
}

pub const CHARACTER_SHADER: ShaderSource = ShaderSource {
    name: "character",
    parts: &[COMMON, SKINNING, MATERIAL, CHARACTER],
};
pub const PLAIN_SHADER: ShaderSource = ShaderSource {
    name: "plain",
    parts: &[COMMON, SKINNING, MATERIAL, PLAIN],
};
pub const CAPTURE_SHADER: ShaderSource = ShaderSource {
    name: "capture",
    parts: &[COMMON, SKINNING, CAPTURE],
};
pub const ENVIRONMENT_SHADER: ShaderSource = ShaderSource {
    name: "environment",
    parts: &[COMMON, ENVIRONMENT],
};
pub const SHADOW_SHADER: ShaderSource = ShaderSource {
    name: "shadow",
    parts: &[COMMON, SKINNING, SHADOW],
};

pub const ATLAS_SHADER: ShaderSource = ShaderSource {
    name: "atlas",
    parts: &[ATLAS],
};

/// Every module the renderer builds.
pub const ALL: &[&ShaderSource] = &[
    &ATLAS_SHADER,
    &CHARACTER_SHADER,
    &PLAIN_SHADER,
    &CAPTURE_SHADER,
    &ENVIRONMENT_SHADER,
    &SHADOW_SHADER,
];

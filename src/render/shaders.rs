//! WGSL sources, compiled into the binary. Each pipeline's module is its own file with the shared
//! pieces it uses composed in front (WGSL has no includes). `tests/integration/shaders.rs` validates every
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
const IMPOSTOR: &str = include_str!("../../shaders/impostor.wgsl");
const IMPOSTOR_BAKE: &str = include_str!("../../shaders/impostor_bake.wgsl");
const PANEL_IMAGE: &str = include_str!("../../shaders/panel_image.wgsl");

/// Colours of the levels of detail, finest first, as the `lod` debug view paints them and the
/// viewer's panel shows them: the one copy, which WGSL gets as `level_palette`.
pub const LEVEL_COLORS: [[f32; 3]; 12] = [
    [0.20, 0.75, 0.30],
    [0.60, 0.85, 0.20],
    [0.95, 0.85, 0.15],
    [0.98, 0.62, 0.12],
    [0.92, 0.38, 0.12],
    [0.85, 0.15, 0.15],
    [0.85, 0.20, 0.55],
    [0.70, 0.25, 0.85],
    [0.42, 0.32, 0.92],
    [0.18, 0.45, 0.95],
    [0.15, 0.75, 0.90],
    [0.55, 0.55, 0.55],
];

/// [`LEVEL_COLORS`] as WGSL: `LEVEL_COUNT` and `level_palette(i)`, a chain of `select`s
/// (vertex shaders call it; see `debug_color` in shaders/character.wgsl for why without
/// branches).
fn level_palette_wgsl() -> String {
    let colour = |[r, g, b]: &[f32; 3]| format!("vec3<f32>({r:?}, {g:?}, {b:?})");
    let steps: Vec<String> = LEVEL_COLORS
        .iter()
        .enumerate()
        .skip(1)
        .map(|(i, c)| format!("    c = select(c, {}, i >= {i}u);\n", colour(c)))
        .collect();
    format!(
        "const LEVEL_COUNT: u32 = {n}u;\n\
         fn level_palette(i: u32) -> vec3<f32> {{\n\
         \x20   var c = {first};\n{steps}    return c;\n\
         }}\n",
        n = LEVEL_COLORS.len(),
        first = colour(&LEVEL_COLORS[0]),
        steps = steps.concat()
    )
}

/// A composed shader module: a name for labels and errors, and its full source.
pub struct ShaderSource {
    pub name: &'static str,
    pub parts: &'static [&'static str],
}

impl ShaderSource {
    pub fn source(&self) -> String {
        let mut source = self.parts.concat();
        if self.parts.contains(&CHARACTER) {
            source.push_str(&level_palette_wgsl());
        }
        source
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
    parts: &[COMMON, SKINNING, MATERIAL, CHARACTER, IMPOSTOR],
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
pub const IMPOSTOR_BAKE_SHADER: ShaderSource = ShaderSource {
    name: "impostor views",
    parts: &[IMPOSTOR_BAKE],
};
/// The viewer's panel, drawn once into a texture, copied onto each frame.
pub const PANEL_IMAGE_SHADER: ShaderSource = ShaderSource {
    name: "panel image",
    parts: &[PANEL_IMAGE],
};

/// Every module the renderer and the viewer build.
pub const ALL: &[&ShaderSource] = &[
    &ATLAS_SHADER,
    &IMPOSTOR_BAKE_SHADER,
    &CHARACTER_SHADER,
    &PLAIN_SHADER,
    &CAPTURE_SHADER,
    &ENVIRONMENT_SHADER,
    &SHADOW_SHADER,
    &PANEL_IMAGE_SHADER,
];

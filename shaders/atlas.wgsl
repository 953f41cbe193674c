// Billboard textures: every leaf a billboard shows, drawn orthographically onto the billboard's
// rectangle in the atlas (see src/bake/foliage/billboard/atlas.rs), each textured by its own
// material's layer (leaves, needles, flowers). Unlit base colour, blended over
// what is there with the leaf texture's own (soft) alpha, so that the atlas keeps the leaf
// contour to a fraction of a texel and the renderer's alpha test at one half finds it again.
// The colour comes out multiplied by alpha; the caller divides it out.
//
// The colour is darkened by the light the crown leaves the leaf (1 − occlusion). The second
// target is the lighting, blended the same way: the normal the leaf is lit by, in the
// billboard's frame (`billboard_frame`, x/2 + 1/2).

struct Atlas {
    // xy: atlas size in pixels.
    size: vec4<f32>,
};

@group(0) @binding(0) var<uniform> atlas: Atlas;
@group(0) @binding(1) var leaf_tex: texture_2d_array<f32>;
@group(0) @binding(2) var leaf_sampler: sampler;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) light: f32,
    @location(3) @interpolate(flat) layer: u32,
};

@vertex
fn vs_main(
    @location(0) pixel: vec2<f32>,
    @location(1) depth: f32,
    @location(2) uv: vec2<f32>,
    @location(3) normal: vec3<f32>,
    @location(4) light: f32,
    @location(5) layer: u32,
) -> VsOut {
    var out: VsOut;
    out.clip = vec4<f32>(pixel.x / atlas.size.x * 2.0 - 1.0, 1.0 - pixel.y / atlas.size.y * 2.0, depth, 1.0);
    out.uv = uv;
    out.normal = normal;
    out.light = light;
    out.layer = layer;
    return out;
}

struct Targets {
    @location(0) colour: vec4<f32>,
    @location(1) lighting: vec4<f32>,
};

@fragment
fn fs_main(in: VsOut) -> Targets {
    let texel = textureSample(leaf_tex, leaf_sampler, in.uv, in.layer);
    var out: Targets;
    out.colour = vec4<f32>(texel.rgb * in.light, texel.a);
    out.lighting = vec4<f32>(clamp(normalize(in.normal) * 0.5 + 0.5, vec3<f32>(0.0), vec3<f32>(1.0)), texel.a);
    return out;
}

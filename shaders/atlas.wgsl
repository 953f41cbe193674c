// Billboard textures: every leaf a billboard shows, drawn orthographically onto the billboard's
// rectangle in the atlas (see src/bake/billboard/atlas.rs). Unlit base colour, blended over
// what is there with the leaf texture's own (soft) alpha, so that the atlas keeps the leaf
// contour to a fraction of a texel and the renderer's alpha test at one half finds it again.
// The colour comes out multiplied by alpha; the caller divides it out.

struct Atlas {
    // xy: atlas size in pixels.
    size: vec4<f32>,
};

@group(0) @binding(0) var<uniform> atlas: Atlas;
@group(0) @binding(1) var leaf_tex: texture_2d<f32>;
@group(0) @binding(2) var leaf_sampler: sampler;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

@vertex
fn vs_main(@location(0) pixel: vec2<f32>, @location(1) depth: f32, @location(2) uv: vec2<f32>) -> VsOut {
    var out: VsOut;
    out.clip = vec4<f32>(pixel.x / atlas.size.x * 2.0 - 1.0, 1.0 - pixel.y / atlas.size.y * 2.0, depth, 1.0);
    out.uv = uv;
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let texel = textureSample(leaf_tex, leaf_sampler, in.uv);
    return texel;
}

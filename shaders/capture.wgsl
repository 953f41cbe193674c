// Debug pass: writes every GPU-skinned vertex position into one texel of an Rgba32Float target
// (vertex i at pixel (i % width, i / width)), so tests can read back exactly what the character
// vertex shader computes and compare it with the CPU reference.

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) position: vec4<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, inst: Instance) -> VsOut {
    let s = skin_vertex(vi, instance_frames(inst));
    let size = vec2<f32>(frame.views.zw);
    let px = vec2<f32>(f32(vi % u32(size.x)), f32(vi / u32(size.x))) + 0.5;
    var out: VsOut;
    out.clip = vec4<f32>(px.x / size.x * 2.0 - 1.0, 1.0 - px.y / size.y * 2.0, 0.5, 1.0);
    out.position = vec4<f32>(instance_point(inst, s.position), f32(s.influences));
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    return in.position;
}

// Skinned characters: GPU skinning from the animation and vertex textures, lit base colour.

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) @interpolate(flat) material: u32,
    @location(4) tint: vec4<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, inst: Instance) -> VsOut {
    let s = skin_vertex(vi, instance_frames(inst));
    let world = instance_point(inst, s.position);
    var out: VsOut;
    out.clip = frame.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    out.normal = instance_vector(inst, s.normal);
    out.uv = s.uv;
    out.material = s.material;
    out.tint = inst.tint;
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let base = textureSample(material_tex, material_sampler, in.uv, in.material) * in.tint;
    let n = normalize(in.normal);
    var c = shade(base.rgb, n);
    // A touch of rim light separates figures from the ground at a distance.
    let v = normalize(frame.camera_pos.xyz - in.world);
    c += frame.sky_horizon.rgb * pow(1.0 - max(dot(n, v), 0.0), 3.0) * 0.12;
    return vec4<f32>(apply_fog(c, in.world), 1.0);
}

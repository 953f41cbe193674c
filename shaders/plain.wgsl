// The trivial unskinned shader: the same triangles from a plain vertex buffer (one fixed pose),
// only the instance transform applied. It measures the machine's raw triangle throughput, the
// baseline skinning is compared against.

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tint: vec4<f32>,
};

@vertex
fn vs_main(
    @location(7) position: vec3<f32>,
    @location(8) normal: vec3<f32>,
    @location(9) uv: vec2<f32>,
    inst: Instance,
) -> VsOut {
    let world = instance_point(inst, position);
    var out: VsOut;
    out.clip = frame.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    out.normal = instance_vector(inst, normal);
    out.uv = uv;
    out.tint = inst.tint;
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let base = textureSample(material_tex, material_sampler, in.uv, 0) * in.tint;
    let c = shade(base.rgb, normalize(in.normal));
    return vec4<f32>(apply_fog(c, in.world), 1.0);
}

// Blob shadows: a soft dark ellipse on the ground under every instance, drawn between the ground
// and the characters. Cheap contact shadows that keep a crowd standing on the plane.

struct Shadow {
    // xy: centre offset in model x/z; zw: radii in model x/z.
    ellipse: vec4<f32>,
};

@group(1) @binding(4) var<uniform> shadow: Shadow;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) local: vec2<f32>,
    @location(1) world: vec3<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, inst: Instance) -> VsOut {
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(1.0, -1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(-1.0, 1.0), vec2<f32>(1.0, 1.0),
    );
    let c = corners[vi];
    // Under the body, where its clip has carried it (root motion; `GpuInstance` in
    // src/render/uniforms.rs: x in timing.w, z in fade.w).
    let centre = shadow.ellipse.xy + vec2<f32>(inst.timing.w, inst.fade.w);
    let local = centre + c * shadow.ellipse.zw * 1.35;
    var world = instance_point(inst, vec3<f32>(local.x, 0.0, local.y));
    // Sit just above the ground, whatever the instance's height.
    world.y = 0.004;
    var out: VsOut;
    out.clip = frame.view_proj * vec4<f32>(world, 1.0);
    out.local = c * 1.35;
    out.world = world;
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let r = length(in.local);
    let a = (1.0 - smoothstep(0.35, 1.3, r)) * 0.55;
    let fade = exp(-max(distance(in.world, frame.camera_pos.xyz) - frame.fog.y, 0.0) * frame.fog.x);
    return vec4<f32>(0.0, 0.0, 0.0, a * fade);
}

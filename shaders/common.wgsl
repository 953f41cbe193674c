// Per-frame uniforms and lighting shared by every pass. Composed in front of the other shader
// files by `render::shaders`.

struct Frame {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    // xyz: eye position.
    camera_pos: vec4<f32>,
    // xyz: unit vector towards the sun; w: sun intensity.
    sun_dir: vec4<f32>,
    sun_color: vec4<f32>,
    sky_zenith: vec4<f32>,
    sky_horizon: vec4<f32>,
    // rgb: ambient bounce from the ground.
    ground_bounce: vec4<f32>,
    // x: fog density per metre; y: fog start distance.
    fog: vec4<f32>,
    // x: scene time in seconds.
    time: vec4<f32>,
    // x: the debug view of everything (`DebugView::shader_mode`); y: that of foliage (the level
    // tint where trees are tinted, else 0); zw: the capture pass's target size in pixels.
    views: vec4<u32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;

// Lambert sun plus a sky/ground hemisphere ambient.
fn shade(albedo: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return albedo * sun_and_sky(max(dot(n, frame.sun_dir.xyz), 0.0), n.y);
}

// The light on a surface whose normal has cosine `sun` (already clamped) with the sun and
// cosine `up` with the up axis: the sun's share plus the hemisphere ambient.
fn sun_and_sky(sun: f32, up: f32) -> vec3<f32> {
    let hemi = mix(frame.ground_bounce.rgb, frame.sky_zenith.rgb * 0.9 + vec3<f32>(0.08), up * 0.5 + 0.5);
    return frame.sun_color.rgb * sun * frame.sun_dir.w + hemi;
}

// The rim light's scale (times the horizon colour) on a surface of normal `n` seen along `v`
// (towards the eye): a touch that separates figures from the ground at a distance.
fn rim(n: vec3<f32>, v: vec3<f32>) -> f32 {
    return pow(1.0 - max(dot(n, v), 0.0), 3.0) * 0.12;
}

// Exponential distance fog towards the horizon colour.
fn apply_fog(color: vec3<f32>, world: vec3<f32>) -> vec3<f32> {
    return mix(color, frame.sky_horizon.rgb, fog_factor(world));
}

// How much of the horizon colour the fog lays over a point, 0..1.
fn fog_factor(world: vec3<f32>) -> f32 {
    let d = max(distance(world, frame.camera_pos.xyz) - frame.fog.y, 0.0);
    return clamp(1.0 - exp(-d * frame.fog.x), 0.0, 1.0);
}

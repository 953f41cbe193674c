// Sky (a full-screen triangle at the far plane) and the ground plane with a metre grid.

struct SkyOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) ndc: vec2<f32>,
};

@vertex
fn vs_sky(@builtin(vertex_index) vi: u32) -> SkyOut {
    let xy = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u)) * 2.0 - 1.0;
    var out: SkyOut;
    out.clip = vec4<f32>(xy, 1.0, 1.0);
    out.ndc = xy;
    return out;
}

@fragment
fn fs_sky(in: SkyOut) -> @location(0) vec4<f32> {
    let far = frame.inv_view_proj * vec4<f32>(in.ndc, 1.0, 1.0);
    let dir = normalize(far.xyz / far.w - frame.camera_pos.xyz);
    return vec4<f32>(sky_color(dir), 1.0);
}

struct GroundOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

// Half the side of the ground square, centred under the camera, in metres.
const GROUND_EXTENT: f32 = 1500.0;

@vertex
fn vs_ground(@builtin(vertex_index) vi: u32) -> GroundOut {
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(1.0, -1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(-1.0, 1.0), vec2<f32>(1.0, 1.0),
    );
    let c = corners[vi] * GROUND_EXTENT + floor(frame.camera_pos.xz / 10.0) * 10.0;
    let world = vec3<f32>(c.x, 0.0, c.y);
    var out: GroundOut;
    out.clip = frame.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    return out;
}

// Anti-aliased grid lines: `width` metres wide every `spacing` metres, fading out where they
// would get denser than the pixels.
fn grid(p: vec2<f32>, spacing: f32, width: f32) -> f32 {
    let q = p / spacing;
    let fw = max(fwidth(q), vec2<f32>(1e-6));
    let d = abs(fract(q - 0.5) - 0.5);
    let half = vec2<f32>(0.5 * width / spacing);
    let a = 1.0 - smoothstep(half, half + fw, d);
    let fade = 1.0 - clamp(max(fw.x, fw.y) * 2.5, 0.0, 1.0);
    return max(a.x, a.y) * fade;
}

@fragment
fn fs_ground(in: GroundOut) -> @location(0) vec4<f32> {
    let p = in.world.xz;
    // Low-contrast checker of 10 m tiles, grid lines every metre and every 10 m.
    let tile = (i32(floor(p.x / 10.0)) + i32(floor(p.y / 10.0))) & 1;
    var albedo = select(vec3<f32>(0.33, 0.37, 0.25), vec3<f32>(0.30, 0.34, 0.23), tile == 1);
    albedo = mix(albedo, vec3<f32>(0.24, 0.27, 0.19), grid(p, 1.0, 0.02) * 0.45);
    albedo = mix(albedo, vec3<f32>(0.19, 0.21, 0.15), grid(p, 10.0, 0.06) * 0.7);
    let c = shade(albedo, vec3<f32>(0.0, 1.0, 0.0));
    return vec4<f32>(apply_fog(c, in.world), 1.0);
}

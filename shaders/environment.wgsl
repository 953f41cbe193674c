// Sky (a full-screen triangle at the far plane) and the ground plane with a metre grid.
//
// Both cover most of the screen every frame, so on a software rasteriser (lavapipe) their
// per-pixel cost sets the floor of every frame: what can be worked out per vertex or once is,
// and the rest uses squarings and linear ramps in place of pow, smoothstep and repeated
// derivatives.

struct SkyOut {
    @builtin(position) clip: vec4<f32>,
    // The view ray through the pixel, unnormalised.
    @location(0) ray: vec3<f32>,
};

@vertex
fn vs_sky(@builtin(vertex_index) vi: u32) -> SkyOut {
    let xy = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u)) * 2.0 - 1.0;
    var out: SkyOut;
    out.clip = vec4<f32>(xy, 1.0, 1.0);
    // The point of the far plane under the vertex, in homogeneous world coordinates, minus
    // the eye scaled alike: linear in the screen position, so it interpolates exactly and the
    // pixels need no matrix product (w keeps one sign over the far plane of a perspective).
    let far = frame.inv_view_proj * vec4<f32>(xy, 1.0, 1.0);
    out.ray = (far.xyz - frame.camera_pos.xyz * far.w) * sign(far.w);
    return out;
}

// `x` raised to 2^n by n squarings.
fn pow2n(x: f32, n: i32) -> f32 {
    var y = x;
    for (var i = 0; i < n; i++) {
        y = y * y;
    }
    return y;
}

// Sky colour seen along a unit direction: zenith to horizon, a haze below the horizon, the
// sun's glow (cosine to the 12th) and its disc (to the 1024th).
fn sky_color(dir: vec3<f32>) -> vec3<f32> {
    let up = clamp(dir.y, -1.0, 1.0);
    var c = mix(frame.sky_horizon.rgb, frame.sky_zenith.rgb, sqrt(max(up, 0.0)));
    c = mix(c, frame.sky_horizon.rgb * 0.9, clamp(-up * 4.0, 0.0, 1.0));
    let sun = max(dot(dir, frame.sun_dir.xyz), 0.0);
    let s4 = pow2n(sun, 2);
    let glow = s4 * s4 * s4;
    let disc = pow2n(sun, 10);
    return c + frame.sun_color.rgb * (disc * 6.0 + glow * 0.12);
}

@fragment
fn fs_sky(in: SkyOut) -> @location(0) vec4<f32> {
    return vec4<f32>(sky_color(normalize(in.ray)), 1.0);
}

struct GroundOut {
    @builtin(position) clip: vec4<f32>,
    // World x and z.
    @location(0) xz: vec2<f32>,
    // The sun and sky light on the flat ground: the same at every pixel.
    @location(1) @interpolate(flat) light: vec3<f32>,
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
    var out: GroundOut;
    out.clip = frame.view_proj * vec4<f32>(c.x, 0.0, c.y, 1.0);
    out.xz = c;
    out.light = shade(vec3<f32>(1.0), vec3<f32>(0.0, 1.0, 0.0));
    return out;
}

// How much of a grid line covers a pixel, from its distance `d` to the line's centre and the
// line's half width, both in the grid's units, and the pixel's reciprocal size `inv_fw` in
// them: 1 on the line, falling linearly to 0 one pixel off it.
fn line_cover(d: vec2<f32>, half: f32, inv_fw: vec2<f32>) -> f32 {
    let a = clamp(1.0 - (d - vec2<f32>(half)) * inv_fw, vec2<f32>(0.0), vec2<f32>(1.0));
    return max(a.x, a.y);
}

@fragment
fn fs_ground(in: GroundOut) -> @location(0) vec4<f32> {
    let p = in.xz;
    // Low-contrast checker of 10 m tiles, grid lines 2 cm wide every metre and 6 cm wide every
    // 10 m, each fading out where it would get denser than the pixels.
    let q = p * 0.1;
    let cell = floor(q);
    let tile = fract((cell.x + cell.y) * 0.5) * 2.0;
    var albedo = mix(vec3<f32>(0.33, 0.37, 0.25), vec3<f32>(0.30, 0.34, 0.23), tile);
    let fw = max(fwidth(p), vec2<f32>(1e-6));
    let inv_fw = 1.0 / fw;
    let density = max(fw.x, fw.y);
    let metre = line_cover(abs(fract(p - 0.5) - 0.5), 0.01, inv_fw)
        * (1.0 - clamp(density * 2.5, 0.0, 1.0));
    let ten = line_cover(abs(fract(q - 0.5) - 0.5), 0.003, inv_fw * 10.0)
        * (1.0 - clamp(density * 0.25, 0.0, 1.0));
    albedo = mix(albedo, vec3<f32>(0.24, 0.27, 0.19), metre * 0.45);
    albedo = mix(albedo, vec3<f32>(0.19, 0.21, 0.15), ten * 0.7);
    let world = vec3<f32>(p.x, 0.0, p.y);
    return vec4<f32>(apply_fog(albedo * in.light, world), 1.0);
}

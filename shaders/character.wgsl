// Skinned characters: GPU skinning from the animation and vertex textures, lit base colour.
//
// `vs_main` draws a level of detail as it is. `vs_morph` draws the finer level of a transition
// geomorphed towards the coarser one (Merry et al. §6.4, Houle & Poulin §5.1): every vertex is
// skinned twice, as itself and as its geomorph target `hops` levels coarser, each with its own
// animation-space influences (after influence simplification the two may differ), and the
// skinned results are blended, v = (1 − t)·Σ G_i p_i(fine) + t·Σ G_j p_j(coarse). The blend is
// written as two products rather than `mix`, so that t = 0 gives exactly the finer vertex and
// t = 1 exactly the coarser one: the fine triangles then coincide with the coarse ones (the
// collapsed ones have no area) and the endpoints render as the levels themselves.
//
// The clip position is `@invariant`: the alpha-blend transition draws the fading level twice
// (depth, then colour with an equal depth test) and needs both passes to compute identical depth.

struct VsOut {
    @invariant @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) @interpolate(flat) material: u32,
    @location(4) tint: vec4<f32>,
    // x: level coordinate (level + t · hops); y: transition t, or −1 outside transitions;
    // z: opacity.
    @location(5) @interpolate(flat) lod: vec4<f32>,
    @location(6) influences: f32,
};

fn lod_varying(inst: Instance) -> vec4<f32> {
    let t = inst.lod.x;
    return vec4<f32>(inst.lod.w + max(t, 0.0) * inst.lod.y, t, inst.lod.z, 0.0);
}

fn finish(inst: Instance, position: vec3<f32>, normal: vec3<f32>, uv: vec2<f32>, material: u32, influences: f32) -> VsOut {
    let world = instance_point(inst, position);
    var out: VsOut;
    out.clip = frame.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    out.normal = instance_vector(inst, normal);
    out.uv = uv;
    out.material = material;
    out.tint = inst.tint;
    out.lod = lod_varying(inst);
    out.influences = influences;
    return out;
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, inst: Instance) -> VsOut {
    let s = skin_vertex(vi, instance_frames(inst));
    return finish(inst, s.position, s.normal, s.uv, s.material, f32(s.influences));
}

@vertex
fn vs_morph(@builtin(vertex_index) vi: u32, inst: Instance) -> VsOut {
    let frames = instance_frames(inst);
    let t = clamp(inst.lod.x, 0.0, 1.0);
    let u = 1.0 - t;
    var coarse_vi = vi;
    for (var h = 0u; h < u32(inst.lod.y); h = h + 1u) {
        coarse_vi = geomorph_target(coarse_vi);
    }
    let fine = skin_vertex(vi, frames);
    let coarse = skin_vertex(coarse_vi, frames);
    let material = select(fine.material, coarse.material, t >= 0.5);
    return finish(
        inst,
        u * fine.position + t * coarse.position,
        u * fine.normal + t * coarse.normal,
        u * fine.uv + t * coarse.uv,
        material,
        u * f32(fine.influences) + t * f32(coarse.influences),
    );
}

// Billboard outlines (the foliage panel's debug view): the billboards' sides as lines, skinned
// like the billboards and pulled a little towards the eye so that they are not lost in the
// billboard's own depth.
@vertex
fn vs_outline(@builtin(vertex_index) vi: u32, inst: Instance) -> VsOut {
    let s = skin_vertex(vi, instance_frames(inst));
    var out = finish(inst, s.position, s.normal, s.uv, s.material, f32(s.influences));
    out.world = mix(out.world, frame.camera_pos.xyz, 0.004);
    out.clip = frame.view_proj * vec4<f32>(out.world, 1.0);
    return out;
}

@fragment
fn fs_outline(in: VsOut) -> @location(0) vec4<f32> {
    return vec4<f32>(apply_fog(vec3<f32>(1.0, 0.25, 0.85), in.world), 0.6);
}

// Debug colours: one per level of detail (level coordinates between two levels blend).
fn level_color(level: f32) -> vec3<f32> {
    var palette = array<vec3<f32>, 12>(
        vec3<f32>(0.20, 0.75, 0.30), vec3<f32>(0.60, 0.85, 0.20), vec3<f32>(0.95, 0.85, 0.15),
        vec3<f32>(0.98, 0.62, 0.12), vec3<f32>(0.92, 0.38, 0.12), vec3<f32>(0.85, 0.15, 0.15),
        vec3<f32>(0.85, 0.20, 0.55), vec3<f32>(0.70, 0.25, 0.85), vec3<f32>(0.42, 0.32, 0.92),
        vec3<f32>(0.18, 0.45, 0.95), vec3<f32>(0.15, 0.75, 0.90), vec3<f32>(0.55, 0.55, 0.55),
    );
    let l = clamp(level, 0.0, 11.0);
    let a = u32(floor(l));
    let b = min(a + 1u, 11u);
    return mix(palette[a], palette[b], l - f32(a));
}

// Blue (cold) through green and yellow to red (hot) over 0..1.
fn heat(x: f32) -> vec3<f32> {
    let v = clamp(x, 0.0, 1.0);
    return clamp(vec3<f32>(1.5 - abs(4.0 * v - 3.0), 1.5 - abs(4.0 * v - 2.0), 1.5 - abs(4.0 * v - 1.0)), vec3<f32>(0.0), vec3<f32>(1.0));
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let texel = textureSample(material_tex, material_sampler, in.uv, in.material);
    return vec4<f32>(lit(in, texel.rgb, normalize(in.normal)), in.lod.z);
}

// Interleaved gradient noise (Jimenez 2014): a threshold in [0, 1) per pixel, evenly spread
// over any small block of pixels.
fn pixel_threshold(pixel: vec2<f32>) -> f32 {
    return fract(52.9829189 * fract(dot(floor(pixel), vec2<f32>(0.06711056, 0.00583715))));
}

// The screen-door cross-dissolve of a tree changing level (see `LodDraw::Dissolve` and the
// comment at the top of src/render/renderer.rs): lod.z ≥ 0 keeps the pixels whose threshold lies
// below it (1, outside dissolves, keeps all), lod.z < 0 those whose threshold is at or above
// −lod.z − 1, so the incoming and outgoing halves of one dissolve cover complementary pixels.
fn dissolved(in: VsOut) -> bool {
    let x = pixel_threshold(in.clip.xy);
    return select(x >= in.lod.z, x < -in.lod.z - 1.0, in.lod.z < 0.0);
}

// Foliage without multisampling: the texture's alpha cuts the leaf shape out; both sides are
// drawn, lit from the side that faces the viewer.
@fragment
fn fs_foliage(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let texel = textureSample(material_tex, material_sampler, in.uv, in.material);
    if (texel.a < 0.5 || dissolved(in)) {
        discard;
    }
    let n = normalize(in.normal) * select(-1.0, 1.0, front);
    return vec4<f32>(lit_as(in, texel.rgb, n, foliage_view()), 1.0);
}

// Foliage with multisampling and alpha to coverage: the alpha is sharpened to about a pixel
// around the 0.5 contour, so the cut edge is antialiased but does not dissolve into a dither.
@fragment
fn fs_foliage_coverage(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let texel = textureSample(material_tex, material_sampler, in.uv, in.material);
    let a = clamp((texel.a - 0.5) / max(fwidth(texel.a), 1e-4) + 0.5, 0.0, 1.0);
    if (dissolved(in)) {
        discard;
    }
    let n = normalize(in.normal) * select(-1.0, 1.0, front);
    return vec4<f32>(lit_as(in, texel.rgb, n, foliage_view()), a);
}

// The debug view of foliage: the foliage tint (frame.time.z, the level tint or 0) where it is
// on, else the view of everything (frame.time.y).
fn foliage_view() -> u32 {
    return max(u32(frame.time.y), u32(frame.time.z));
}

// The character's colour: material (or a debug view's colour), sun and sky light, rim, fog.
fn lit(in: VsOut, albedo: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    // frame.time.y: the debug view (see `DebugView` in src/render/renderer.rs).
    return lit_as(in, albedo, n, u32(frame.time.y));
}

fn lit_as(in: VsOut, albedo: vec3<f32>, n: vec3<f32>, view: u32) -> vec3<f32> {
    var base = albedo * in.tint.rgb;
    if (view == 1u) {
        base = level_color(in.lod.x);
    } else if (view == 2u) {
        base = select(vec3<f32>(0.55), heat(in.lod.y), in.lod.y >= 0.0);
    } else if (view == 3u) {
        // One influence is cold, eight or more hot.
        base = heat((in.influences - 1.0) / 7.0);
    }
    var c = shade(base, n);
    // A touch of rim light separates figures from the ground at a distance.
    let v = normalize(frame.camera_pos.xyz - in.world);
    c += frame.sky_horizon.rgb * pow(1.0 - max(dot(n, v), 0.0), 3.0) * 0.12;
    return apply_fog(c, in.world);
}

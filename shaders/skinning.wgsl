// Animation-space skinning from textures (Merry, Marais & Gain §2.1.2 and §6.4).
//
// v = Σ_i G_i p_i and n = Σ_i G_i n_i, where the p_i / n_i of a vertex come from the vertex
// texture (read by vertex_index) and the bone matrices G_i from the animation texture, blended
// between the two frames around the current time. Layouts are documented in
// src/bake/anim_texture.rs and src/bake/vertex_texture.rs; `AnimationTexture::sample` is the CPU
// mirror of `clip_frames` below.

@group(1) @binding(0) var anim_tex: texture_2d<f32>;
@group(1) @binding(1) var vertex_tex: texture_2d<f32>;

// Addressing of a data texture whose width is a power of two: texel i is at
// (i & mask, i >> shift). Worked out once per vertex, not once per load.
struct Layout {
    mask: u32,
    shift: u32,
};

fn layout_of(t: texture_2d<f32>) -> Layout {
    let w = textureDimensions(t).x;
    return Layout(w - 1u, countTrailingZeros(w));
}

fn texel(t: texture_2d<f32>, l: Layout, i: u32) -> vec4<f32> {
    return textureLoad(t, vec2<u32>(i & l.mask, i >> l.shift), 0);
}

struct ClipFrames {
    anim: Layout,
    // Texel index of bone 0, row 0 of the earlier and the later frame.
    row0: u32,
    row1: u32,
    // Blend factor towards the later frame.
    blend: f32,
};

// `clip`: texel of the clip's first frame, frame count, duration, texels per frame (see
// `AnimationTexture::clip_rows`).
fn clip_frames(clip: vec4<f32>, time: f32) -> ClipFrames {
    let first = u32(clip.x);
    let count = u32(clip.y);
    let duration = clip.z;
    let stride = u32(clip.w);
    var f0 = 0u;
    var f1 = 0u;
    var a = 0.0;
    if (count > 1u && duration > 0.0) {
        let f = fract(time / duration) * f32(count - 1u);
        f0 = min(u32(floor(f)), count - 1u);
        f1 = min(f0 + 1u, count - 1u);
        a = f - f32(f0);
    }
    var out: ClipFrames;
    out.anim = layout_of(anim_tex);
    out.row0 = first + f0 * stride;
    out.row1 = first + f1 * stride;
    out.blend = a;
    return out;
}

struct SkinnedVertex {
    position: vec3<f32>,
    normal: vec3<f32>,
    uv: vec2<f32>,
    material: u32,
    influences: u32,
};

fn skin_vertex(vertex_index: u32, frames: ClipFrames) -> SkinnedVertex {
    let vl = layout_of(vertex_tex);
    let al = frames.anim;
    let header = texel(vertex_tex, vl, 2u * vertex_index);
    let first = u32(header.x);
    let packed = u32(header.y);
    let count = packed % 256u;
    var pos = vec3<f32>(0.0);
    var nrm = vec3<f32>(0.0);
    for (var i = 0u; i < count; i = i + 1u) {
        let p = texel(vertex_tex, vl, first + 2u * i);
        let nb = texel(vertex_tex, vl, first + 2u * i + 1u);
        let bone = 3u * u32(nb.w);
        let a = frames.row0 + bone;
        let b = frames.row1 + bone;
        let r0 = mix(texel(anim_tex, al, a), texel(anim_tex, al, b), frames.blend);
        let r1 = mix(texel(anim_tex, al, a + 1u), texel(anim_tex, al, b + 1u), frames.blend);
        let r2 = mix(texel(anim_tex, al, a + 2u), texel(anim_tex, al, b + 2u), frames.blend);
        pos += vec3<f32>(dot(r0, p), dot(r1, p), dot(r2, p));
        nrm += vec3<f32>(dot(r0.xyz, nb.xyz), dot(r1.xyz, nb.xyz), dot(r2.xyz, nb.xyz));
    }
    var out: SkinnedVertex;
    out.position = pos;
    out.normal = nrm;
    out.uv = header.zw;
    out.material = packed / 256u;
    out.influences = count;
    return out;
}

// The vertex a vertex morphs into at the next coarser level (see src/bake/vertex_texture.rs);
// a vertex of the coarsest level is its own target.
fn geomorph_target(vertex_index: u32) -> u32 {
    return u32(texel(vertex_tex, layout_of(vertex_tex), 2u * vertex_index + 1u).x);
}

// Per-instance data: a 3x4 transform (rows), the clip, its timing, a tint and its level of
// detail.
struct Instance {
    @location(0) row0: vec4<f32>,
    @location(1) row1: vec4<f32>,
    @location(2) row2: vec4<f32>,
    // The clip as a frame range of the animation texture (see `clip_frames`).
    @location(3) clip: vec4<f32>,
    // x: time offset in seconds; y: playback speed.
    @location(4) timing: vec4<f32>,
    @location(5) tint: vec4<f32>,
    // x: transition t (geomorph: 0 the drawn level, 1 its target hops levels coarser), −1 when
    // not in a transition; y: hops;
    // z: opacity (below 1 only while an alpha transition fades the level); w: the level.
    @location(6) lod: vec4<f32>,
};

fn instance_point(inst: Instance, p: vec3<f32>) -> vec3<f32> {
    let h = vec4<f32>(p, 1.0);
    return vec3<f32>(dot(inst.row0, h), dot(inst.row1, h), dot(inst.row2, h));
}

fn instance_vector(inst: Instance, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(inst.row0.xyz, v), dot(inst.row1.xyz, v), dot(inst.row2.xyz, v));
}

fn instance_frames(inst: Instance) -> ClipFrames {
    return clip_frames(inst.clip, frame.time.x * inst.timing.y + inst.timing.x);
}

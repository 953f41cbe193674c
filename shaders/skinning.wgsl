// Animation-space skinning from textures (Merry, Marais & Gain §2.1.2 and §6.4).
//
// v = Σ_i G_i p_i and n = Σ_i G_i n_i, where the p_i / n_i of a vertex come from the vertex
// texture (read by vertex_index) and the bone matrices G_i from the animation texture, blended
// between the two frames around the current time. Layouts are documented in
// src/bake/gpu_data/anim_texture.rs and src/bake/gpu_data/vertex_texture.rs; `AnimationTexture::sample_with` is the
// CPU mirror of `clip_frames` below, and `CharacterBake::evaluate` of `skin_vertex`.
//
// A cross-fade between two clips (a walker stopping to wave) blends the two clips' bone
// matrices by the fade's weight, each at its own time, before they skin the vertex.
//
// Wind strength s (per instance, 1 for characters) scales the motion about the rest pose, frame 0
// of the animation texture: G = Ĝ + s (G(t) − Ĝ). Billboards of a spectral cloud
// (Bennett-Therkildsen, Carlsen & Schmid's thesis "Animated Billboard Clouds for Foliage
// Simplification" (2007) §6.2.1 and §6.4) add their spectral offset Δ(τ), scaled by s, in their
// bone's space: v = G (p + w Δ(τ)); the offset is the same for all four corners, so the billboard
// stays rigid.

@group(1) @binding(0) var anim_tex: texture_2d<f32>;
@group(1) @binding(1) var vertex_tex: texture_2d<f32>;
// Spectra texture (src/bake/gpu_data/spectra.rs): one row per billboard, texel axis·K + j holding
// line j of that axis as (cycles, amplitude, phase, 0); one empty texel (K = 0) where nothing
// moves by spectra.
@group(1) @binding(5) var spectra_tex: texture_2d<f32>;

// Addressing of a data texture whose width is a power of two: texel i is at
// (i & mask, i >> shift). Worked out once per vertex, not once per load.
struct Layout {
    mask: u32,
    shift: u32,
};

fn layout_of(t: texture_2d<f32>) -> Layout {
    let w = textureDimensions(t).x;
    // log2 of a power of two, exact in f32 (WebGL2's GLSL has no countTrailingZeros).
    return Layout(w - 1u, u32(log2(f32(w)) + 0.5));
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
    // Loop time in [0, 1), for spectral offsets.
    tau: f32,
    // Wind strength: 1 plays the clip as it is.
    wind: f32,
    // A cross-fade to a second clip: its earlier and later frames and the blend between them
    // (as row0, row1 and blend), and its weight (0: the first clip alone).
    row0b: u32,
    row1b: u32,
    blendb: f32,
    fade: f32,
};

// `clip`: texel of the clip's first frame, frame count, duration, texels per frame (see
// `AnimationTexture::clip_rows`).
fn clip_frames(clip: vec4<f32>, time: f32, wind: f32) -> ClipFrames {
    let first = u32(clip.x);
    let count = u32(clip.y);
    let duration = clip.z;
    let stride = u32(clip.w);
    var f0 = 0u;
    var f1 = 0u;
    var a = 0.0;
    var tau = 0.0;
    if (duration > 0.0) {
        let u = time / duration;
        tau = u - floor(u);
    }
    if (count > 1u && duration > 0.0) {
        let f = tau * f32(count - 1u);
        f0 = min(u32(floor(f)), count - 1u);
        f1 = min(f0 + 1u, count - 1u);
        a = f - f32(f0);
    }
    var out: ClipFrames;
    out.anim = layout_of(anim_tex);
    out.row0 = first + f0 * stride;
    out.row1 = first + f1 * stride;
    out.blend = a;
    out.tau = tau;
    out.wind = wind;
    out.row0b = out.row0;
    out.row1b = out.row1;
    out.blendb = a;
    out.fade = 0.0;
    return out;
}

// Bone `bone`'s rows (texels bone, bone + 1, bone + 2 of a frame) at the time `frames` holds:
// blended between the two frames round it, and towards the second clip's by the cross-fade's
// weight (Σ of matrices, as between frames: linear blend of the two clips' poses).
struct BoneRows {
    r0: vec4<f32>,
    r1: vec4<f32>,
    r2: vec4<f32>,
};

// Bone `bone`'s rows at frames `row0` and `row1` (texel of bone 0, row 0), blended by `blend`.
fn frame_rows(al: Layout, row0: u32, row1: u32, blend: f32, bone: u32) -> BoneRows {
    let a = row0 + bone;
    let b = row1 + bone;
    return BoneRows(
        mix(texel(anim_tex, al, a), texel(anim_tex, al, b), blend),
        mix(texel(anim_tex, al, a + 1u), texel(anim_tex, al, b + 1u), blend),
        mix(texel(anim_tex, al, a + 2u), texel(anim_tex, al, b + 2u), blend),
    );
}

fn bone_rows(frames: ClipFrames, bone: u32) -> BoneRows {
    let m = frame_rows(frames.anim, frames.row0, frames.row1, frames.blend, bone);
    if (frames.fade <= 0.0) {
        return m;
    }
    let n = frame_rows(frames.anim, frames.row0b, frames.row1b, frames.blendb, bone);
    return BoneRows(mix(m.r0, n.r0, frames.fade), mix(m.r1, n.r1, frames.fade), mix(m.r2, n.r2, frames.fade));
}

// The offset of spectra row `row` at loop time `tau`: Σ_axes Σ_j a cos(2π m τ + φ). Mirror of
// `SpectraTexture::offset`.
fn spectral_offset(row: u32, bins: u32, tau: f32) -> vec3<f32> {
    var d = vec3<f32>(0.0);
    for (var axis = 0u; axis < 3u; axis = axis + 1u) {
        var s = 0.0;
        for (var j = 0u; j < bins; j = j + 1u) {
            let line = textureLoad(spectra_tex, vec2<u32>(axis * bins + j, row), 0);
            s += line.y * cos(6.283185307 * line.x * tau + line.z);
        }
        d[axis] = s;
    }
    return d;
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
    // A billboard of a spectral cloud: its row's offset, in its bone's space.
    var offset = vec3<f32>(0.0);
    let bins = textureDimensions(spectra_tex).x / 3u;
    if (bins > 0u) {
        let row = u32(texel(vertex_tex, vl, 2u * vertex_index + 1u).y);
        if (row > 0u) {
            offset = frames.wind * spectral_offset(row - 1u, bins, frames.tau);
        }
    }
    var pos = vec3<f32>(0.0);
    var nrm = vec3<f32>(0.0);
    for (var i = 0u; i < count; i = i + 1u) {
        let stored = texel(vertex_tex, vl, first + 2u * i);
        let p = stored + vec4<f32>(offset * stored.w, 0.0);
        let nb = texel(vertex_tex, vl, first + 2u * i + 1u);
        let bone = 3u * u32(nb.w);
        let g = bone_rows(frames, bone);
        var r0 = g.r0;
        var r1 = g.r1;
        var r2 = g.r2;
        if (frames.wind != 1.0) {
            // The rest pose is frame 0: bone b's rows are texels 3b, 3b + 1, 3b + 2.
            let q0 = texel(anim_tex, al, bone);
            let q1 = texel(anim_tex, al, bone + 1u);
            let q2 = texel(anim_tex, al, bone + 2u);
            r0 = q0 + (r0 - q0) * frames.wind;
            r1 = q1 + (r1 - q1) * frames.wind;
            r2 = q2 + (r2 - q2) * frames.wind;
        }
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

// The normal-map layer that lights a vertex plus one, 0 for none (see
// src/bake/gpu_data/vertex_texture.rs and src/bake/character/normal_map.rs).
fn normal_layer(vertex_index: u32) -> f32 {
    return texel(vertex_tex, layout_of(vertex_tex), 2u * vertex_index + 1u).z;
}

// The vertex a vertex morphs into at the next coarser level (see src/bake/gpu_data/vertex_texture.rs);
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
    // x: time offset in seconds; y: playback speed; z: wind strength (1: the clip as it is);
    // w: x of where its clip has carried it (root motion, for the blob shadow).
    @location(4) timing: vec4<f32>,
    @location(5) tint: vec4<f32>,
    // x: transition t (geomorph: 0 the drawn level, 1 its target hops levels coarser), −1 when
    // not in a transition; y: hops;
    // z: cover (`Cover` in src/render/uniforms.rs): an opacity below 1 only while an alpha
    // transition fades the level, a signed screen-door coverage for a dissolve's or dithered
    // cross-fade's half, else 1; w: the level.
    @location(6) lod: vec4<f32>,
    // A cross-fade to a second clip: that clip as a frame range (see `clip_frames`), and its
    // time offset (x), playback speed (y) and weight (z, 0: no cross-fade); w: z of where its
    // clip has carried it.
    @location(10) clip2: vec4<f32>,
    @location(11) fade: vec4<f32>,
};

fn instance_point(inst: Instance, p: vec3<f32>) -> vec3<f32> {
    let h = vec4<f32>(p, 1.0);
    return vec3<f32>(dot(inst.row0, h), dot(inst.row1, h), dot(inst.row2, h));
}

fn instance_vector(inst: Instance, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(inst.row0.xyz, v), dot(inst.row1.xyz, v), dot(inst.row2.xyz, v));
}

fn instance_frames(inst: Instance) -> ClipFrames {
    var f = clip_frames(inst.clip, frame.time.x * inst.timing.y + inst.timing.x, inst.timing.z);
    if (inst.fade.z > 0.0) {
        let g = clip_frames(inst.clip2, frame.time.x * inst.fade.y + inst.fade.x, inst.timing.z);
        f.row0b = g.row0;
        f.row1b = g.row1;
        f.blendb = g.blend;
        f.fade = inst.fade.z;
    }
    return f;
}

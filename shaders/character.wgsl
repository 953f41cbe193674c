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
    // z: the instance's cover (`Cover` in src/render/uniforms.rs: an opacity in the faded
    // pass, a signed screen-door coverage in the dithered ones, 1 when whole); w: a clump
    // billboard's view coverage (see `view_coverage`), else 1.
    @location(5) @interpolate(flat) lod: vec4<f32>,
    @location(6) influences: f32,
    // The normal-map layers plus one (0: vertex normals) of the vertex drawn (x) and, in a
    // geomorph, of its target (y); set by the `_mapped` vertex shaders only.
    @location(7) @interpolate(flat) normal_layer: vec2<f32>,
};

// The normal maps of the set's coarse levels (see src/bake/character/normal_map.rs).
@group(1) @binding(7) var normal_tex: texture_2d_array<f32>;

fn lod_varying(inst: Instance) -> vec4<f32> {
    let t = inst.lod.x;
    return vec4<f32>(inst.lod.w + max(t, 0.0) * inst.lod.y, t, inst.lod.z, 1.0);
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
    out.normal_layer = vec2<f32>(0.0);
    return out;
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, inst: Instance) -> VsOut {
    return skinned(vi, inst);
}

@vertex
fn vs_morph(@builtin(vertex_index) vi: u32, inst: Instance) -> VsOut {
    return morphed(vi, inst);
}

// `vs_main` and `vs_morph` for the levels lit through normal maps: they also read the
// vertices' layers (the plain ones skip that read, the vertex shader's share of a crowd's frame
// being large on a software rasteriser).
@vertex
fn vs_main_mapped(@builtin(vertex_index) vi: u32, inst: Instance) -> VsOut {
    var out = skinned(vi, inst);
    let layer = normal_layer(vi);
    out.normal_layer = vec2<f32>(layer, layer);
    return out;
}

@vertex
fn vs_morph_mapped(@builtin(vertex_index) vi: u32, inst: Instance) -> VsOut {
    let coarse_vi = morph_target(vi, inst);
    var out = morphed_to(vi, coarse_vi, inst);
    out.normal_layer = vec2<f32>(normal_layer(vi), normal_layer(coarse_vi));
    return out;
}

fn skinned(vi: u32, inst: Instance) -> VsOut {
    let s = skin_vertex(vi, instance_frames(inst));
    return finish(inst, s.position, s.normal, s.uv, s.material, f32(s.influences));
}

// The vertex `vi` morphs into `lod.y` levels coarser, following the geomorph targets hop by hop.
fn morph_target(vi: u32, inst: Instance) -> u32 {
    var coarse_vi = vi;
    for (var h = 0u; h < u32(inst.lod.y); h = h + 1u) {
        coarse_vi = geomorph_target(coarse_vi);
    }
    return coarse_vi;
}

fn morphed(vi: u32, inst: Instance) -> VsOut {
    return morphed_to(vi, morph_target(vi, inst), inst);
}

fn morphed_to(vi: u32, coarse_vi: u32, inst: Instance) -> VsOut {
    let frames = instance_frames(inst);
    let t = clamp(inst.lod.x, 0.0, 1.0);
    let u = 1.0 - t;
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

// Clump billboards are drawn by view (src/bake/foliage/billboard/clumps.rs): a billboard whose header
// holds a view window w ≠ 0 (where other billboards hold 0, and leaves and wood their crown
// occlusion) is drawn only from views within |w| radians of its normal, horizontally, either
// side, seen from the instance's origin, so that all four corners agree; the windows of one
// clump tile the circle. In a band at the window's edge it cross-fades with its neighbour
// through complementary halves of the screen door (odd planes, w < 0, take the other half).
// The result is a coverage as `screened_out` takes it: 1 drawn whole, 0 (or −2 for an odd
// plane) not at all; anything else goes to the fragment shader.
const VIEW_FADE: f32 = 0.25;

// The way from the instance's origin to the eye, horizontally: what chooses a clump's plane
// and faces its flat normal, the same for every vertex of a tree.
fn view_from_origin(inst: Instance) -> vec2<f32> {
    return frame.camera_pos.xz - instance_point(inst, vec3<f32>(0.0)).xz;
}

// `header` is the vertex's second header texel (see src/bake/gpu_data/vertex_texture.rs): the foliage
// shaders fetch it once for this, the flat normal and the crown's light.
fn view_coverage(header: vec4<f32>, inst: Instance, normal: vec3<f32>) -> f32 {
    let w = select(0.0, header.w, header.z > 0.5);
    let h = abs(w);
    let v = view_from_origin(inst);
    let n = normal.xz;
    let lengths = length(n) * length(v);
    // Straight above the tree every plane is as good: all are drawn.
    let c = select(1.0, abs(dot(n, v)) / max(lengths, 1e-12), lengths > 1e-8);
    let off = acos(clamp(c, 0.0, 1.0));
    // The band is VIEW_FADE of the half window either side of its edge; a plane's share falls
    // from 1 to 0 across it as its neighbour's rises from 0 to 1.
    let band = max(VIEW_FADE * h, 1e-6);
    let share = clamp((h + band - off) / (2.0 * band), 0.0, 1.0);
    return select(select(share, share - 2.0, w < 0.0), 1.0, w == 0.0);
}

// Is a coverage from `view_coverage` nothing at all? The vertex is then moved out of the clip
// volume, with the rest of its billboard, and costs no pixels.
fn out_of_view(coverage: f32) -> bool {
    return coverage == 0.0 || coverage == -2.0;
}

// A clump billboard lit by its plane would change its shade as the view hands the clump from
// one plane to the next. Lit flat, it takes the normal of a plane facing the viewer square on
// (horizontally, on the face the viewer sees): the same for every plane of every clump of a
// tree, so that only the atlas's texels (the crown's occlusion) shade one clump apart from the
// next. (The normal halfway between the view and the sun, which leaves facing every way
// average to more nearly, made the tree's coarse levels far too bright beside the full tree:
// tone error 0.12 against 0.03 in the report's lighting.md.)
fn flat_normal(header: vec4<f32>, inst: Instance, o: VsOut) -> VsOut {
    var out = o;
    let v = view_from_origin(inst);
    let facing = vec3<f32>(v.x, 0.0, v.y) * select(1.0, -1.0, dot(o.normal.xz, v) < 0.0);
    let windowed = header.z > 0.5 && header.w != 0.0 && dot(v, v) > 1e-12;
    out.normal = select(o.normal, facing, windowed);
    return out;
}

// `o` with its billboard's view coverage in lod.w (1 outside clump levels), and dropped where
// it is out of view.
fn in_view(header: vec4<f32>, inst: Instance, o: VsOut) -> VsOut {
    var out = o;
    out.lod.w = view_coverage(header, inst, o.normal);
    if (out_of_view(out.lod.w)) {
        out.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
    }
    return out;
}

// Billboard outlines (the foliage panel's debug view): the billboards' sides as lines, skinned
// like the billboards and pulled a little towards the eye so that they are not lost in the
// billboard's own depth.
@vertex
fn vs_outline(@builtin(vertex_index) vi: u32, inst: Instance) -> VsOut {
    var out = skinned(vi, inst);
    out.world = mix(out.world, frame.camera_pos.xyz, 0.004);
    out.clip = frame.view_proj * vec4<f32>(out.world, 1.0);
    return in_view(vertex_header(vi), inst, out);
}

// The second header texel of vertex `vi`.
fn vertex_header(vi: u32) -> vec4<f32> {
    return texel(vertex_tex, layout_of(vertex_tex), 2u * vi + 1u);
}

@fragment
fn fs_outline(in: VsOut) -> @location(0) vec4<f32> {
    return vec4<f32>(apply_fog(vec3<f32>(1.0, 0.25, 0.85), in.world), 0.6);
}

// Debug colours: one per level of detail (level coordinates between two levels blend).
fn level_color(level: f32) -> vec3<f32> {
    // `level_palette` is generated from `render::shaders::LEVEL_COLORS`, which the viewer's
    // panel shows too.
    let last = f32(LEVEL_COUNT - 1u);
    let l = clamp(level, 0.0, last);
    let a = u32(floor(l));
    let b = min(a + 1u, LEVEL_COUNT - 1u);
    return mix(level_palette(a), level_palette(b), l - f32(a));
}

// Blue (cold) through green and yellow to red (hot) over 0..1.
fn heat(x: f32) -> vec3<f32> {
    let v = clamp(x, 0.0, 1.0);
    return clamp(vec3<f32>(1.5 - abs(4.0 * v - 3.0), 1.5 - abs(4.0 * v - 2.0), 1.5 - abs(4.0 * v - 1.0)), vec3<f32>(0.0), vec3<f32>(1.0));
}

// A mesh's triangles of cut-out materials (a character's hair cards, feathers, lace): the
// pipelines that draw them (`PipelineKey::cut` in src/render/pipelines.rs) set this, draw
// both sides and have the fragment shaders below drop what the texture's alpha cuts out at
// one half (the material layers hold an opaque material's alpha at one). Everywhere else it
// is false and the tests fold away.
override cut_out: bool = false;

// Whether a cut-out triangle's texture cuts this fragment away. The colour is worked out
// before any discard (see `fs_dither`).
fn cut_away(in: VsOut) -> bool {
    let alpha = textureSample(material_tex, material_sampler, in.uv, in.material).a;
    return cut_out && alpha < 0.5;
}

// The normal of the side the eye sees: a cut-out card is lit on either side.
fn facing(in: VsOut, n: vec3<f32>) -> vec3<f32> {
    return select(n, -n, cut_out && dot(n, frame.camera_pos.xyz - in.world) < 0.0);
}

// Characters shaded by their materials. The debug views are `fs_debug`, a pipeline of their
// own: a branch on the view here would cost every pixel on a software rasteriser.
@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let colour = shaded(in);
    if (cut_away(in)) {
        discard;
    }
    return colour;
}

fn shaded(in: VsOut) -> vec4<f32> {
    return shaded_with(in, normalize(in.normal));
}

// The normal of a coarse level's fragment lit through its normal map: the stored normal
// (full detail's, see src/bake/character/normal_map.rs) in the frame of the triangle, rebuilt here from
// the derivatives of the skinned position and of the texture coordinate, as the bake built it
// in the rest pose: n the interpolated normal, t = ∂P/∂u made orthogonal to n, b = ±n × t by
// the triangle's handedness in texture space. Where the texture coordinates give no frame (no
// area), the vertex normal stays. The map is read with explicit gradients: llvmpipe's implicit
// ones take a slow path.
struct TangentFrame {
    t: vec3<f32>,
    b: vec3<f32>,
    n: vec3<f32>,
    // The texture coordinate's screen derivatives.
    duv1: vec2<f32>,
    duv2: vec2<f32>,
    // The texture coordinates span the triangle.
    ok: bool,
};

fn tangent_frame(in: VsOut) -> TangentFrame {
    var f: TangentFrame;
    f.n = normalize(in.normal);
    let dp1 = dpdx(in.world);
    let dp2 = dpdy(in.world);
    f.duv1 = dpdx(in.uv);
    f.duv2 = dpdy(in.uv);
    let det = f.duv1.x * f.duv2.y - f.duv2.x * f.duv1.y;
    let s = select(-1.0, 1.0, det >= 0.0);
    let dpdu = (dp1 * f.duv2.y - dp2 * f.duv1.y) * s;
    let dpdv = (dp2 * f.duv1.x - dp1 * f.duv2.x) * s;
    let t_raw = dpdu - f.n * dot(f.n, dpdu);
    let tl = length(t_raw);
    f.t = t_raw / max(tl, 1e-20);
    f.b = select(-1.0, 1.0, dot(cross(dpdu, dpdv), f.n) >= 0.0) * cross(f.n, f.t);
    f.ok = tl > 1e-12 && det != 0.0;
    return f;
}

// The stored normal of layer `layer` plus one at the fragment, (0, 0, 1) for none.
fn stored_normal(in: VsOut, f: TangentFrame, layer: f32) -> vec3<f32> {
    // Stored as 128 + 127·x (see `encode` in src/bake/character/normal_map.rs).
    let m = (textureSampleGrad(normal_tex, material_sampler, in.uv, u32(max(layer - 1.0, 0.0)), f.duv1, f.duv2).xyz * 255.0 - 128.0) / 127.0;
    return select(vec3<f32>(0.0, 0.0, 1.0), m, layer > 0.5);
}

// The stored normal `m` in the frame `f`.
fn framed(f: TangentFrame, m: vec3<f32>) -> vec3<f32> {
    return select(f.n, normalize(m.x * f.t + m.y * f.b + m.z * f.n), f.ok);
}

fn shaded_with(in: VsOut, n: vec3<f32>) -> vec4<f32> {
    let texel = textureSample(material_tex, material_sampler, in.uv, in.material);
    return vec4<f32>(lit(in, texel.rgb * in.tint.rgb, facing(in, n)), in.lod.z);
}

fn shaded_mapped(in: VsOut) -> vec4<f32> {
    let f = tangent_frame(in);
    return shaded_with(in, framed(f, stored_normal(in, f, in.normal_layer.x)));
}

// `fs_main` and `fs_dither` for the levels lit through normal maps.
@fragment
fn fs_mapped(in: VsOut) -> @location(0) vec4<f32> {
    let colour = shaded_mapped(in);
    if (cut_away(in)) {
        discard;
    }
    return colour;
}

@fragment
fn fs_dither_mapped(in: VsOut) -> @location(0) vec4<f32> {
    let colour = shaded_mapped(in);
    if (cut_away(in) || dithered_out(in)) {
        discard;
    }
    return colour;
}

// A geomorph lit through its two levels' maps, blended by the transition's t (lod.y).
@fragment
fn fs_morph_mapped(in: VsOut) -> @location(0) vec4<f32> {
    let f = tangent_frame(in);
    let fine = stored_normal(in, f, in.normal_layer.x);
    let coarse = stored_normal(in, f, in.normal_layer.y);
    let colour = shaded_with(in, framed(f, mix(fine, coarse, clamp(in.lod.y, 0.0, 1.0))));
    if (cut_away(in)) {
        discard;
    }
    return colour;
}

// Characters painted by the debug view (frame.views.x): by level, by transition, by
// influences; the material where the view keeps it.
@fragment
fn fs_debug(in: VsOut) -> @location(0) vec4<f32> {
    let colour = painted(in);
    if (cut_away(in)) {
        discard;
    }
    return colour;
}

fn painted(in: VsOut) -> vec4<f32> {
    let texel = textureSample(material_tex, material_sampler, in.uv, in.material);
    let d = debug_color(in.lod, in.influences, frame.views.x);
    let base = select(texel.rgb * in.tint.rgb, d.rgb, d.a > 0.5);
    return vec4<f32>(lit(in, base, facing(in, normalize(in.normal))), in.lod.z);
}

// One half of a dithered cross-fade (`LodDraw::Dither`): lod.z is the half's coverage, read as
// `dissolved` reads a tree's. Pipelines of their own, so that no other character pays for the
// test.
fn dithered_out(in: VsOut) -> bool {
    return screened_out(in.clip.xy, in.lod.z);
}

// The colour is worked out before the discard: on llvmpipe a texture read after it, with
// some pixels of a block gone, runs pixel by pixel.
@fragment
fn fs_dither(in: VsOut) -> @location(0) vec4<f32> {
    let colour = shaded(in);
    if (cut_away(in) || dithered_out(in)) {
        discard;
    }
    return colour;
}

@fragment
fn fs_debug_dither(in: VsOut) -> @location(0) vec4<f32> {
    let colour = painted(in);
    if (cut_away(in) || dithered_out(in)) {
        discard;
    }
    return colour;
}

// Interleaved gradient noise (Jimenez 2014): a threshold in [0, 1) per pixel, evenly spread
// over any small block of pixels.
fn pixel_threshold(pixel: vec2<f32>) -> f32 {
    return fract(52.9829189 * fract(dot(floor(pixel), vec2<f32>(0.06711056, 0.00583715))));
}

// The screen door of every dissolve and dithered cross-fade (see `LodDraw::Dissolve` and the
// comment at the top of src/render/renderer.rs): is `pixel` out of a half of coverage
// `coverage`? A coverage c ≥ 0 keeps the pixels whose threshold lies below it (1, outside
// dissolves, keeps all), c < 0 those whose threshold is at or above −c − 1, so the incoming
// and outgoing halves of one dissolve cover complementary pixels.
fn screened_out(pixel: vec2<f32>, coverage: f32) -> bool {
    return screened_out_at(pixel_threshold(pixel), coverage);
}

// `screened_out` at a pixel whose threshold is `x`.
fn screened_out_at(x: f32, coverage: f32) -> bool {
    return select(x >= coverage, x < -coverage - 1.0, coverage < 0.0);
}

// Out of either of two screen doors at one pixel of threshold `x`: a dissolve's and a clump
// billboard's cross-fade.
fn screened_out_by(x: f32, a: f32, b: f32) -> bool {
    return screened_out_at(x, a) || screened_out_at(x, b);
}

// A tree changing level, or a clump billboard cross-fading with its neighbour.
fn dissolved(in: FoliageOut) -> bool {
    return screened_out_by(pixel_threshold(in.clip.xy), in.coverage, in.view);
}

// Foliage is lit per vertex: leaves are flat, so sun, sky and rim light are the same at every
// pixel of one; branches are thin. A forest is drawn as millions of small alpha-tested
// triangles, and on a software rasterizer the per-pixel lighting was about two fifths of the
// frame. Both faces are lit (foliage is two-sided) and the fragment picks the one it sees; the
// debug view's colour and the fog factor come along. All light is scaled by the crown's
// occlusion at the vertex (src/bake/foliage/billboard/occlusion.rs; 0 for everything but trees).
// Billboards lit through their atlas (a normal per texel) have a pipeline of their own,
// `vs_foliage_lit` below.
struct FoliageOut {
    // Invariant: the depth pre-pass and the colour pass after it must agree to the bit.
    @invariant @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) material: u32,
    @location(2) tint: vec3<f32>,
    // Light on the front and on the back face: rgb multiplies the base colour, w scales the
    // rim light (the horizon colour).
    @location(3) front: vec4<f32>,
    @location(4) back: vec4<f32>,
    // The debug view's colour (a = 1) in place of the texture's, or a = 0.
    @location(5) debug: vec4<f32>,
    @location(6) fog: f32,
    // The dissolve's coverage (lod.z of the instance), and a clump billboard's view coverage
    // (see `view_coverage`; 1 for everything else).
    @location(7) @interpolate(flat) coverage: f32,
    @location(8) @interpolate(flat) view: f32,
};

fn side_light(n: vec3<f32>, v: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(shade(vec3<f32>(1.0), n), rim(n, v));
}

// The light the crown leaves a vertex of second header texel `header`: 1 − its occlusion (see
// src/bake/gpu_data/vertex_texture.rs); a billboard's is in its atlas (its slot holds its view window).
fn crown_light(header: vec4<f32>) -> f32 {
    return select(1.0 - header.w, 1.0, header.z > 0.5);
}

// A foliage vertex as the fragment shader takes it: `skinned_vertex` through `in_view`, lit per
// vertex with its flat normal (`flat_normal`), by the crown's light of its `header`.
fn foliage_out(skinned_vertex: VsOut, inst: Instance, header: vec4<f32>) -> FoliageOut {
    let o = flat_normal(header, inst, in_view(header, inst, skinned_vertex));
    let crown = crown_light(header);
    let n = normalize(o.normal);
    let v = normalize(frame.camera_pos.xyz - o.world);
    var out: FoliageOut;
    out.clip = o.clip;
    out.uv = o.uv;
    out.material = o.material;
    out.tint = o.tint.rgb;
    out.front = side_light(n, v) * crown;
    out.back = side_light(-n, v) * crown;
    out.debug = debug_color(o.lod, o.influences, foliage_view());
    out.fog = fog_factor(o.world);
    out.coverage = o.lod.z;
    out.view = o.lod.w;
    return out;
}

@vertex
fn vs_foliage(@builtin(vertex_index) vi: u32, inst: Instance) -> FoliageOut {
    return foliage_out(skinned(vi, inst), inst, vertex_header(vi));
}

@vertex
fn vs_foliage_morph(@builtin(vertex_index) vi: u32, inst: Instance) -> FoliageOut {
    return foliage_out(morphed(vi, inst), inst, vertex_header(vi));
}

// The lit colour of a foliage fragment of texture colour `texel` (see `lit`, per vertex).
fn foliage_color(in: FoliageOut, texel: vec3<f32>, front: bool) -> vec3<f32> {
    let base = select(texel * in.tint, in.debug.rgb, in.debug.a > 0.5);
    let l = select(in.back, in.front, front);
    let c = base * l.rgb + frame.sky_horizon.rgb * l.w;
    return mix(c, frame.sky_horizon.rgb, in.fog);
}

// Foliage without multisampling: the texture's alpha cuts the leaf shape out; both sides are
// drawn, lit from the side that faces the viewer.
@fragment
fn fs_foliage(in: FoliageOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let texel = textureSample(material_tex, material_sampler, in.uv, in.material);
    if (texel.a < 0.5 || dissolved(in)) {
        discard;
    }
    return vec4<f32>(foliage_color(in, texel.rgb, front), 1.0);
}

// The foliage depth pre-pass (without multisampling): depth only, where the texture's alpha
// keeps the leaf. One texture read a layer; the colour pass after it shades each pixel once.
@fragment
fn fs_foliage_depth(in: FoliageOut) {
    let alpha = textureSample(material_tex, material_sampler, in.uv, in.material).a;
    if (alpha < 0.5 || dissolved(in)) {
        discard;
    }
}

// The colour pass after the depth pre-pass: drawn where the depth equals the pre-pass's, so
// only the nearest leaf's fragment at each pixel passes, and without a discard, so that the
// rasteriser's early depth test holds.
@fragment
fn fs_foliage_equal(in: FoliageOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let texel = textureSample(material_tex, material_sampler, in.uv, in.material);
    return vec4<f32>(foliage_color(in, texel.rgb, front), 1.0);
}

// Foliage with multisampling and alpha to coverage: the alpha is sharpened to about a pixel
// around the 0.5 contour, so the cut edge is antialiased but does not dissolve into a dither.
@fragment
fn fs_foliage_coverage(in: FoliageOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let texel = textureSample(material_tex, material_sampler, in.uv, in.material);
    let a = clamp((texel.a - 0.5) / max(fwidth(texel.a), 1e-4) + 0.5, 0.0, 1.0);
    if (dissolved(in)) {
        discard;
    }
    return vec4<f32>(foliage_color(in, texel.rgb, front), a);
}

// A billboard cloud lit through its atlas (src/bake/foliage/billboard/atlas.rs): the billboards'
// texels hold the normal m the leaf drawn there is lit by, in the billboard's frame (t, b, n),
// in the material layer after the atlas's (the crown's occlusion is in the atlas's colour);
// each pixel is lit by it, as the leaves it stands for were lit per vertex, under whatever
// sun. The frame is rebuilt per vertex from the skinned normal, as `billboard_frame` built it,
// and the sun and the up axis go to the fragment in it, so that the pixel's lighting is a few
// dot products (`sun_and_sky` of common.wgsl with n = m). The wood drawn with it takes
// m = (0, 0, 1): lit by its vertex normal. Both faces as for all foliage: the back face sees
// −m.
struct LitFoliageOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) material: u32,
    @location(2) tint: vec3<f32>,
    // The unit vector towards the sun and the up axis in the frame (t, b, n).
    @location(3) sun: vec3<f32>,
    @location(4) up: vec3<f32>,
    // x: the crown's light at the vertex; y: 1 on a billboard lit through its atlas, else 0;
    // z, w: the rim light's scale on the front and on the back face.
    @location(5) light: vec4<f32>,
    @location(6) debug: vec4<f32>,
    @location(7) fog: f32,
    @location(8) @interpolate(flat) coverage: f32,
    @location(9) @interpolate(flat) view: f32,
};

@vertex
fn vs_foliage_lit(@builtin(vertex_index) vi: u32, inst: Instance) -> LitFoliageOut {
    let s = skin_vertex(vi, instance_frames(inst));
    let header = vertex_header(vi);
    let o = in_view(header, inst, finish(inst, s.position, s.normal, s.uv, s.material, f32(s.influences)));
    // The frame in model space (mirror of `billboard_frame`), then in the world.
    let nm = normalize(s.normal);
    let reference = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(nm.y) < 0.99);
    let tm = normalize(cross(reference, nm));
    let t = normalize(instance_vector(inst, tm));
    let b = normalize(instance_vector(inst, cross(nm, tm)));
    let n = normalize(o.normal);
    let v = normalize(frame.camera_pos.xyz - o.world);
    let sun = frame.sun_dir.xyz;
    var out: LitFoliageOut;
    out.clip = o.clip;
    out.uv = o.uv;
    out.material = o.material;
    out.tint = o.tint.rgb;
    out.sun = vec3<f32>(dot(sun, t), dot(sun, b), dot(sun, n));
    out.up = vec3<f32>(t.y, b.y, n.y);
    out.light = vec4<f32>(
        crown_light(header),
        select(0.0, 1.0, header.z > 0.5),
        rim(n, v),
        rim(-n, v),
    );
    out.debug = debug_color(o.lod, o.influences, foliage_view());
    out.fog = fog_factor(o.world);
    out.coverage = o.lod.z;
    out.view = o.lod.w;
    return out;
}

struct LitTexels {
    colour: vec4<f32>,
    lit: vec3<f32>,
};

// The texture colour of a lit foliage fragment and its lit colour; both texture reads come
// before any discard.
fn lit_foliage(in: LitFoliageOut, front: bool) -> LitTexels {
    let texel = textureSample(material_tex, material_sampler, in.uv, in.material);
    // A billboard's lighting is the layer after its atlas; elsewhere the same texel again.
    let lighting = textureSample(material_tex, material_sampler, in.uv, in.material + u32(in.light.y + 0.5));
    let atlas = in.light.y > 0.5;
    // Filtered over leaves facing several ways the stored normal is their mean, shorter than
    // one: its length is how alike they face. The sun term takes it as that share facing the
    // mean way and the rest spread evenly over all directions (each lit a quarter on average);
    // the sky term is linear in the normal, so the mean is exact there.
    let m = select(vec3<f32>(0.0, 0.0, 1.0), lighting.xyz * 2.0 - 1.0, atlas);
    let face = select(-m, m, front);
    let spread = 0.25 * (1.0 - min(length(m), 1.0));
    let light = sun_and_sky(max(dot(face, in.sun), 0.0) + spread, dot(face, in.up));
    let crown = in.light.x;
    let base = select(texel.rgb * in.tint, in.debug.rgb, in.debug.a > 0.5);
    let rim_scale = select(in.light.w, in.light.z, front);
    let c = (base * light + frame.sky_horizon.rgb * rim_scale) * crown;
    var out: LitTexels;
    out.colour = texel;
    out.lit = mix(c, frame.sky_horizon.rgb, in.fog);
    return out;
}

// `dissolved` for the per-pixel foliage path.
fn lit_dissolved(in: LitFoliageOut) -> bool {
    return screened_out_by(pixel_threshold(in.clip.xy), in.coverage, in.view);
}

@fragment
fn fs_foliage_lit(in: LitFoliageOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let t = lit_foliage(in, front);
    if (t.colour.a < 0.5 || lit_dissolved(in)) {
        discard;
    }
    return vec4<f32>(t.lit, 1.0);
}

@fragment
fn fs_foliage_lit_coverage(in: LitFoliageOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let t = lit_foliage(in, front);
    let a = clamp((t.colour.a - 0.5) / max(fwidth(t.colour.a), 1e-4) + 0.5, 0.0, 1.0);
    if (lit_dissolved(in)) {
        discard;
    }
    return vec4<f32>(t.lit, a);
}

// The debug view of foliage: the foliage tint (frame.views.y, the level tint or 0) where it is
// on, else the view of everything (frame.views.x).
fn foliage_view() -> u32 {
    return max(frame.views.x, frame.views.y);
}

// The colour debug view `view` (see `DebugView` in src/render/renderer.rs) paints a surface
// with (a = 1), or a = 0 where it keeps the material's.
fn debug_color(lod: vec4<f32>, influences: f32, view: u32) -> vec4<f32> {
    // Without branches: the foliage and impostor vertex shaders call this, and llvmpipe (Mesa
    // 22.3) leaked about half a megabyte a draw of a vertex shader that returned from inside
    // this if/else chain (found by `lodlab soak`).
    let level = level_color(lod.x);
    let transition = select(vec3<f32>(0.55), heat(lod.y), lod.y >= 0.0);
    // One influence is cold, eight or more hot.
    let spread = heat((influences - 1.0) / 7.0);
    var c = vec3<f32>(0.0);
    c = select(c, level, view == 1u);
    c = select(c, transition, view == 2u);
    c = select(c, spread, view == 3u);
    return vec4<f32>(c, select(0.0, 1.0, view >= 1u && view <= 3u));
}


// The character's colour from its base colour (material or debug view): sun and sky light,
// rim, fog.
fn lit(in: VsOut, base: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    var c = shade(base, n);
    let v = normalize(frame.camera_pos.xyz - in.world);
    c += frame.sky_horizon.rgb * rim(n, v);
    return apply_fog(c, in.world);
}

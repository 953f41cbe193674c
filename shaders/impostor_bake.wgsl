// Impostor views (src/bake/impostor/octahedral.rs): the tree at rest drawn orthographically
// from every view of the grid into that view's cell of one target, depth-tested. Instance i is
// view i. The colour target takes the unlit material colour darkened by the crown's occlusion
// (src/bake/foliage/billboard/occlusion.rs: the tree's own leaves are darkened by it when drawn, and
// it scales all their light) (its alpha marks what is covered),
// the second target the model-space normal turned towards the eye, as n / 2 + 1/2, and in its
// alpha the point's height towards the eye (mirror of `encode_height`).

struct Bake {
    // xy: target size in pixels.
    size: vec4<f32>,
    // xyz: the centre of the views' sphere, model space.
    centre: vec4<f32>,
};

@group(0) @binding(0) var<uniform> bake: Bake;
@group(0) @binding(1) var layers: texture_2d_array<f32>;
@group(0) @binding(2) var layer_sampler: sampler;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) layer: u32,
    @location(2) @interpolate(flat) cut_out: u32,
    @location(3) normal: vec3<f32>,
    @location(4) @interpolate(flat) toward: vec3<f32>,
    @location(5) light: f32,
};

@vertex
fn vs_view(
    @location(0) position: vec3<f32>,
    @location(1) layer: u32,
    @location(2) normal: vec3<f32>,
    @location(3) cut_out: u32,
    @location(4) uv: vec2<f32>,
    // The view: its cell (x, y, size), and its axes scaled by 1 / radius.
    @location(5) cell: vec4<f32>,
    @location(6) right: vec4<f32>,
    @location(7) up: vec4<f32>,
    @location(8) toward: vec4<f32>,
    @location(9) light: f32,
) -> VsOut {
    let q = position - bake.centre.xyz;
    // The square [−radius, radius]² about the centre fills the cell; nearer the eye is nearer.
    let st = vec2<f32>(0.5 + 0.5 * dot(q, right.xyz), 0.5 - 0.5 * dot(q, up.xyz));
    let pixel = cell.xy + st * cell.z;
    var out: VsOut;
    out.clip = vec4<f32>(
        pixel.x / bake.size.x * 2.0 - 1.0,
        1.0 - pixel.y / bake.size.y * 2.0,
        clamp(0.5 - 0.5 * dot(q, toward.xyz), 0.0, 1.0),
        1.0,
    );
    out.uv = uv;
    out.layer = layer;
    out.cut_out = cut_out;
    out.normal = normal;
    out.toward = toward.xyz;
    out.light = light;
    return out;
}

struct Views {
    @location(0) colour: vec4<f32>,
    @location(1) normal: vec4<f32>,
};

@fragment
fn fs_view(in: VsOut) -> Views {
    let texel = textureSample(layers, layer_sampler, in.uv, in.layer);
    if (in.cut_out == 1u && texel.a < 0.5) {
        discard;
    }
    // Foliage is two-sided: the face the eye sees is lit.
    var n = normalize(in.normal);
    if (dot(n, in.toward) < 0.0) {
        n = -n;
    }
    var out: Views;
    out.colour = vec4<f32>(texel.rgb * in.light, 1.0);
    // Depth 0 is a radius in front of the centre, 1 a radius behind it.
    let height = 1.0 - in.clip.z;
    out.normal = vec4<f32>(n * 0.5 + vec3<f32>(0.5), (128.0 + round(127.0 * height)) / 255.0);
    return out;
}

// Octahedral impostors (src/bake/impostor/octahedral.rs): a tree's far level, one quad facing the
// eye that shows the tree as baked from the three grid views round the direction it is seen
// from, blended by their barycentric weights, so that walking round a tree never pops.
//
// The quad lies in the plane through the views' sphere centre across the line of sight and
// spans the sphere. A point of it is found in view k's cell by projecting it along view k's
// direction (an orthographic reprojection, affine over the quad, so it is worked out per
// vertex). The quad's rows sway like the slabs of the tree at their heights: each row of the
// impostor's mesh is a pair of vertices skinned like that slab, and a point of the quad moves
// as the skinned rows round its height moved from the rest pose.
//
// Colour and normal (model space, n / 2 + 1/2) are layers 0 and 1 of the material texture. The
// normals light the impostor like the tree: sun, sky, rim and fog per pixel.
//
// Parallax: the normal layer's alpha holds each texel's height towards its view's eye (see
// `encode_height`). A point of the quad shows the surface where the eye's ray through it meets
// the tree, at height h over the quad's plane; the view nearest the line of sight, whose ray
// through the point is almost the eye's, tells h, and every view is read where that surface
// point projects in its cell: its place for the quad's point, moved by h along the line of
// sight as that view sees it. The three views then show the same leaves at the same place,
// instead of three copies side by side that only half agree (which thinned fine foliage under
// the alpha test and blurred the rest).

struct ImpostorFrame {
    // The blob shadow's ellipse (see shadow.wgsl): the same uniform.
    ellipse: vec4<f32>,
    // xyz: the centre of the views' sphere, model space; w: its radius.
    sphere: vec4<f32>,
    // x: views on a side of the grid; y: rows of the quad; z: the lowest row's height; w: the
    // rows' height span. An animated impostor's: views, page columns, page rows, and w 1
    // where `impostor_rects` holds each page's travel after the views.
    grid: vec4<f32>,
    // x: a texel's share of a view's cell.
    cell: vec4<f32>,
    // The tree's bounds at rest, model space (xyz of each): the quad covers their outline.
    lo: vec4<f32>,
    hi: vec4<f32>,
};

// The quad's extent round the sphere's centre, in radii along the view's axes (x0, x1, y0,
// y1): the outline of the bounds seen along `d`, a little wider, within the sphere's square.
// A point of the tree lands on the quad where it projects along `d` (the parallax of the
// views is undone by their heights), so nothing drawn lies outside; a tall tree's quad is
// a crown wide instead of a tree high, and a forest patch's is its trees high.
fn quad_extent(axes: ViewAxes, centre: vec3<f32>, radius: f32) -> vec4<f32> {
    var e = vec4<f32>(1e9, -1e9, 1e9, -1e9);
    for (var k = 0u; k < 8u; k = k + 1u) {
        let corner = vec3<f32>(
            select(impostor.lo.x, impostor.hi.x, (k & 1u) != 0u),
            select(impostor.lo.y, impostor.hi.y, (k & 2u) != 0u),
            select(impostor.lo.z, impostor.hi.z, (k & 4u) != 0u),
        ) - centre;
        let x = dot(corner, axes.right) / radius;
        let y = dot(corner, axes.up) / radius;
        e = vec4<f32>(min(e.x, x), max(e.y, x), min(e.z, y), max(e.w, y));
    }
    let margin = QUAD_MARGIN;
    return clamp(e + vec4<f32>(-margin, margin, -margin, margin), vec4<f32>(-1.0), vec4<f32>(1.0));
}

// The margin round the outline, in radii: filtering and the views' blend reach a little
// beyond it.
const QUAD_MARGIN: f32 = 0.06;

// An animated impostor's rectangle of each view's cell that any frame covers (s0, t0, s1, t1),
// texel k for view k, row by row (`AnimatedFrame::rects`).
@group(1) @binding(6) var impostor_rects: texture_2d<f32>;

@group(1) @binding(4) var<uniform> impostor: ImpostorFrame;

// Mirrors of `hemi_oct_encode`, `hemi_oct_decode` and `ViewGrid::view_axes`.
fn hemi_oct_encode(d: vec3<f32>) -> vec2<f32> {
    let a = vec3<f32>(d.x, abs(d.y), d.z);
    let p = a.xz / max(abs(a.x) + a.y + abs(a.z), 1e-12);
    return vec2<f32>(p.x + p.y, p.x - p.y);
}

fn hemi_oct_decode(s: vec2<f32>) -> vec3<f32> {
    let p = vec2<f32>(s.x + s.y, s.x - s.y) * 0.5;
    let y = 1.0 - abs(p.x) - abs(p.y);
    return normalize(vec3<f32>(p.x, max(y, 0.0), p.y));
}

struct ViewAxes {
    right: vec3<f32>,
    up: vec3<f32>,
};

fn view_axes(d: vec3<f32>) -> ViewAxes {
    let reference = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, -1.0), d.y > 0.999);
    let right = normalize(cross(reference, d));
    return ViewAxes(right, cross(d, right));
}

struct ImpostorOut {
    @builtin(position) clip: vec4<f32>,
    // The point's place in the cells of views 0 and 1 (xy, zw) and 2, each 0..1 over its cell.
    @location(0) st01: vec4<f32>,
    // xy: view 2's place; zw: how view 2's place moves per unit of height (a radius).
    @location(1) st2: vec4<f32>,
    // The cells (column, row) of views 0 and 1.
    @location(2) @interpolate(flat) cells01: vec4<f32>,
    // xy: view 2's cell; z: views on a side; w: a texel's share of a cell (the inset that
    // keeps filtering inside the cell).
    @location(3) @interpolate(flat) cell2: vec4<f32>,
    // xyz: the views' weights; w: the dissolve's coverage.
    @location(4) @interpolate(flat) weights: vec4<f32>,
    // The instance's rotation (rows), for the normals.
    @location(5) @interpolate(flat) row0: vec3<f32>,
    @location(6) @interpolate(flat) row1: vec3<f32>,
    @location(7) @interpolate(flat) row2: vec3<f32>,
    // rgb: tint; w: fog.
    @location(8) tint: vec4<f32>,
    // The debug view's colour (a = 1) in place of the texture's, or a = 0.
    @location(9) @interpolate(flat) debug: vec4<f32>,
    // Towards the eye, world space.
    @location(10) @interpolate(flat) to_eye: vec3<f32>,
    // How the places of views 0 (xy) and 1 (zw) move per unit of height.
    @location(11) @interpolate(flat) shift01: vec4<f32>,
};

// How far row pair `a` of the quad's mesh has moved from the rest pose (their midpoint).
fn row_sway(a: u32, now: ClipFrames) -> vec3<f32> {
    var rest = now;
    rest.wind = 0.0;
    let moved = skin_vertex(2u * a, now).position + skin_vertex(2u * a + 1u, now).position;
    let still = skin_vertex(2u * a, rest).position + skin_vertex(2u * a + 1u, rest).position;
    return 0.5 * (moved - still);
}

// Where the quad point `offset` (from the sphere's centre) lies in view `cell`'s cell (xy),
// and how far that place moves when the point rises a radius along `d` towards the eye (zw).
fn cell_point(cell: vec2<f32>, n: f32, offset: vec3<f32>, radius: f32, d: vec3<f32>) -> vec4<f32> {
    let axes = view_axes(hemi_oct_decode(cell / n * 2.0 - vec2<f32>(1.0)));
    let st = vec2<f32>(0.5 + 0.5 * dot(offset, axes.right) / radius, 0.5 - 0.5 * dot(offset, axes.up) / radius);
    return vec4<f32>(st, 0.5 * dot(d, axes.right), -0.5 * dot(d, axes.up));
}

@vertex
fn vs_impostor(@builtin(vertex_index) vi: u32, inst: Instance) -> ImpostorOut {
    let centre = impostor.sphere.xyz;
    let radius = impostor.sphere.w;
    let frames = impostor.grid.x;
    let rows = u32(impostor.grid.y);
    // The eye as seen from the tree, model space: the instance's transform is a rotation and
    // a uniform scale, so its transpose turns world directions back into model ones.
    let v = frame.camera_pos.xyz - instance_point(inst, centre);
    let d = normalize(inst.row0.xyz * v.x + inst.row1.xyz * v.y + inst.row2.xyz * v.z);
    let axes = view_axes(d);
    let extent = select(vec4<f32>(-1.0, 1.0, -1.0, 1.0), quad_extent(axes, centre, radius), impostor.hi.w > 0.5);
    let q = vec2<f32>(
        mix(extent.x, extent.y, f32(vi & 1u)),
        mix(extent.z, extent.w, f32(vi >> 1u) / f32(rows)),
    );
    let offset = radius * (q.x * axes.right + q.y * axes.up);
    let rest = centre + offset;
    // Sway with the rows round this point's height.
    let now = instance_frames(inst);
    let h = clamp((rest.y - impostor.grid.z) / max(impostor.grid.w, 1e-6), 0.0, 1.0) * f32(rows);
    let a = min(u32(floor(h)), rows - 1u);
    let sway = mix(row_sway(a, now), row_sway(a + 1u, now), h - f32(a));
    let world = instance_point(inst, rest + sway);

    // The three views round d and their weights (mirror of `ViewGrid::blend`).
    let n = frames - 1.0;
    let g = clamp((hemi_oct_encode(d) + vec2<f32>(1.0)) * 0.5 * n, vec2<f32>(0.0), vec2<f32>(n));
    let base = min(floor(g), vec2<f32>(n - 1.0));
    let f = g - base;
    var c1 = base + vec2<f32>(0.0, 1.0);
    var w = vec3<f32>(1.0 - f.y, f.y - f.x, f.x);
    if (f.x >= f.y) {
        c1 = base + vec2<f32>(1.0, 0.0);
        w = vec3<f32>(1.0 - f.x, f.x - f.y, f.y);
    }
    let c2 = base + vec2<f32>(1.0);

    var out: ImpostorOut;
    out.clip = frame.view_proj * vec4<f32>(world, 1.0);
    let p0 = cell_point(base, n, offset, radius, d);
    let p1 = cell_point(c1, n, offset, radius, d);
    out.st01 = vec4<f32>(p0.xy, p1.xy);
    out.st2 = cell_point(c2, n, offset, radius, d);
    out.shift01 = vec4<f32>(p0.zw, p1.zw);
    out.cells01 = vec4<f32>(base, c1);
    out.cell2 = vec4<f32>(c2, frames, impostor.cell.x);
    out.weights = vec4<f32>(w, inst.lod.z);
    out.row0 = inst.row0.xyz;
    out.row1 = inst.row1.xyz;
    out.row2 = inst.row2.xyz;
    out.tint = vec4<f32>(inst.tint.rgb, fog_factor(world));
    out.debug = debug_color(lod_varying(inst), 1.0, foliage_view());
    out.to_eye = normalize(v);
    return out;
}

// Where the three views are read for one pixel, with the texture-space gradients of the
// quad's own places (the parallax shift jumps at a view's edges, and must not pick a mip).
struct ImpostorTaps {
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    uv2: vec2<f32>,
    gx: vec2<f32>,
    gy: vec2<f32>,
};

// A view's place in the atlas: `st` in `cell`, kept a texel inside it so filtering never
// reaches the neighbouring view.
fn impostor_uv(in: ImpostorOut, cell: vec2<f32>, st: vec2<f32>) -> vec2<f32> {
    let inset = in.cell2.w;
    return (cell + clamp(st, vec2<f32>(inset), vec2<f32>(1.0 - inset))) / in.cell2.z;
}

fn impostor_taps(in: ImpostorOut) -> ImpostorTaps {
    var taps: ImpostorTaps;
    taps.gx = dpdx(in.st01.xy) / in.cell2.z;
    taps.gy = dpdy(in.st01.xy) / in.cell2.z;
    // The height of the surface under this point, from the view nearest the line of sight.
    let w = in.weights.xyz;
    let one = w.y > w.x && w.y >= w.z;
    let two = w.z > w.x && w.z > w.y;
    let cell = select(select(in.cells01.xy, in.cells01.zw, one), in.cell2.xy, two);
    let st = select(select(in.st01.xy, in.st01.zw, one), in.st2.xy, two);
    let probe = textureSampleGrad(material_tex, material_sampler, impostor_uv(in, cell, st), 1, taps.gx, taps.gy).a;
    let h = (probe * 255.0 - 128.0) / 127.0 * 2.0 - 1.0;
    taps.uv0 = impostor_uv(in, in.cells01.xy, in.st01.xy + h * in.shift01.xy);
    taps.uv1 = impostor_uv(in, in.cells01.zw, in.st01.zw + h * in.shift01.zw);
    taps.uv2 = impostor_uv(in, in.cell2.xy, in.st2.xy + h * in.st2.zw);
    return taps;
}

fn impostor_tap(taps: ImpostorTaps, uv: vec2<f32>, layer: i32) -> vec4<f32> {
    return textureSampleGrad(material_tex, material_sampler, uv, layer, taps.gx, taps.gy);
}

// The views' colour blended (premultiplied by their coverage), and each view's share.
struct ImpostorTexel {
    colour: vec3<f32>,
    alpha: f32,
    shares: vec3<f32>,
};

fn impostor_colour(in: ImpostorOut, taps: ImpostorTaps) -> ImpostorTexel {
    let a = impostor_tap(taps, taps.uv0, 0);
    let b = impostor_tap(taps, taps.uv1, 0);
    let c = impostor_tap(taps, taps.uv2, 0);
    let w = in.weights.xyz * vec3<f32>(a.a, b.a, c.a);
    let alpha = w.x + w.y + w.z;
    return ImpostorTexel((w.x * a.rgb + w.y * b.rgb + w.z * c.rgb) / max(alpha, 1e-4), alpha, w);
}

// The three views' normals, read before any pixel is discarded (see `animated_normals`).
struct ImpostorNormals {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
};

fn impostor_normals(taps: ImpostorTaps) -> ImpostorNormals {
    return ImpostorNormals(
        impostor_tap(taps, taps.uv0, 1),
        impostor_tap(taps, taps.uv1, 1),
        impostor_tap(taps, taps.uv2, 1),
    );
}

// The lit colour of an impostor pixel: the views' normals blended as their colours were,
// turned into the world, and lit like foliage (sun and sky, rim, fog).
fn impostor_lit(in: ImpostorOut, normals: ImpostorNormals, texel: ImpostorTexel) -> vec3<f32> {
    let a = normals.a;
    let b = normals.b;
    let c = normals.c;
    let w = texel.shares;
    let m = (w.x * a.rgb + w.y * b.rgb + w.z * c.rgb) * 2.0 - vec3<f32>(w.x + w.y + w.z);
    let rows = mat3x3<f32>(in.row0, in.row1, in.row2);
    return impostor_light(texel.colour, in.tint, in.debug, m * rows, in.to_eye);
}

// An impostor pixel lit: `colour` tinted (or the debug view's colour, where it has one), with
// `world_normal` (a blend of normals turned into the world, not normalised), sun and sky, rim
// and `tint.w` of fog.
fn impostor_light(colour: vec3<f32>, tint: vec4<f32>, debug: vec4<f32>, world_normal: vec3<f32>, to_eye: vec3<f32>) -> vec3<f32> {
    let nrm = normalize(world_normal + vec3<f32>(0.0, 1e-6, 0.0));
    let base = select(colour * tint.rgb, debug.rgb, debug.a > 0.5);
    var lit = shade(base, nrm);
    lit += frame.sky_horizon.rgb * rim(nrm, to_eye);
    return mix(lit, frame.sky_horizon.rgb, tint.w);
}

// The dissolve of a tree changing level (see `dissolved` in character.wgsl).
fn impostor_dissolved(in: ImpostorOut) -> bool {
    return screened_out(in.clip.xy, in.weights.w);
}

// Without multisampling: the blended alpha cuts the tree out at one half, as foliage.
@fragment
fn fs_impostor(in: ImpostorOut) -> @location(0) vec4<f32> {
    let taps = impostor_taps(in);
    let texel = impostor_colour(in, taps);
    let normals = impostor_normals(taps);
    if (texel.alpha < 0.5 || impostor_dissolved(in)) {
        discard;
    }
    return vec4<f32>(impostor_lit(in, normals, texel), 1.0);
}

// With multisampling: alpha to coverage, the alpha sharpened to about a pixel round the
// contour (as `fs_foliage_coverage`).
@fragment
fn fs_impostor_coverage(in: ImpostorOut) -> @location(0) vec4<f32> {
    let taps = impostor_taps(in);
    let texel = impostor_colour(in, taps);
    let normals = impostor_normals(taps);
    let a = clamp((texel.alpha - 0.5) / max(fwidth(texel.alpha), 1e-4) + 0.5, 0.0, 1.0);
    if (impostor_dissolved(in)) {
        discard;
    }
    return vec4<f32>(impostor_lit(in, normals, texel), a);
}

// A tree impostor far enough off that the view its blend weighs most, alone, is within the
// screen tolerance (`shows_nearest_view` in src/render/renderer/keys.rs): that view's colour
// and normal, one read each, no parallax probe, instead of the blend's seven reads. On a
// software rasteriser the impostors of a 10,000-tree forest spent most of their time in those
// reads.
struct NearestTexel {
    colour: vec4<f32>,
    normal: vec4<f32>,
};

fn impostor_nearest(in: ImpostorOut) -> NearestTexel {
    let w = in.weights.xyz;
    let one = w.y > w.x && w.y >= w.z;
    let two = w.z > w.x && w.z > w.y;
    let cell = select(select(in.cells01.xy, in.cells01.zw, one), in.cell2.xy, two);
    let st = select(select(in.st01.xy, in.st01.zw, one), in.st2.xy, two);
    let gx = dpdx(in.st01.xy) / in.cell2.z;
    let gy = dpdy(in.st01.xy) / in.cell2.z;
    let uv = impostor_uv(in, cell, st);
    return NearestTexel(
        textureSampleGrad(material_tex, material_sampler, uv, 0, gx, gy),
        textureSampleGrad(material_tex, material_sampler, uv, 1, gx, gy),
    );
}

fn impostor_nearest_lit(in: ImpostorOut, t: NearestTexel) -> vec3<f32> {
    let rows = mat3x3<f32>(in.row0, in.row1, in.row2);
    let m = t.normal.rgb * 2.0 - vec3<f32>(1.0);
    return impostor_light(t.colour.rgb, in.tint, in.debug, m * rows, in.to_eye);
}

@fragment
fn fs_impostor_nearest(in: ImpostorOut) -> @location(0) vec4<f32> {
    let t = impostor_nearest(in);
    if (t.colour.a < 0.5 || impostor_dissolved(in)) {
        discard;
    }
    return vec4<f32>(impostor_nearest_lit(in, t), 1.0);
}

@fragment
fn fs_impostor_nearest_coverage(in: ImpostorOut) -> @location(0) vec4<f32> {
    let t = impostor_nearest(in);
    let a = clamp((t.colour.a - 0.5) / max(fwidth(t.colour.a), 1e-4) + 0.5, 0.0, 1.0);
    if (impostor_dissolved(in)) {
        discard;
    }
    return vec4<f32>(impostor_nearest_lit(in, t), a);
}

// Animated impostors (src/bake/impostor/animated.rs): a character's last level, one quad that shows
// the view of the grid nearest the line of sight (the heaviest of the three a tree blends,
// mirror of `nearest_view`) at the two baked frames round the instance's time, cross-faded. The
// quad is square to that view, through the sphere's centre, and covers only the rectangle of
// the view's cell that any frame covers. The frames are the impostor's own animation texture's: `instance_frames` gives
// their texels; frame g ≥ 1 (frame 0 is the rest pose) is page g − 1 of the sheets, at column
// (g − 1) mod columns and row (g − 1) / columns; layer 0 is the colour sheet, layer 1 the
// model-space normals'. The uniform's grid holds the views on a side, the columns and the rows
// of pages; cell.x a texel's share of a cell.
struct AnimatedOut {
    @builtin(position) clip: vec4<f32>,
    // The point's place in its view's cell, 0..1.
    @location(0) st: vec2<f32>,
    // xy: the earlier frame's view cell in the sheet, in cells; zw: the later frame's.
    @location(1) @interpolate(flat) cells: vec4<f32>,
    // x: the blend towards the later frame; y: the dissolve's coverage; z: a texel's share of
    // a cell; w: unused.
    @location(2) @interpolate(flat) blend: vec4<f32>,
    // The sheet's size in cells.
    @location(9) @interpolate(flat) sheet: vec2<f32>,
    @location(3) @interpolate(flat) row0: vec3<f32>,
    @location(4) @interpolate(flat) row1: vec3<f32>,
    @location(5) @interpolate(flat) row2: vec3<f32>,
    // rgb: tint; w: fog.
    @location(6) tint: vec4<f32>,
    @location(7) @interpolate(flat) debug: vec4<f32>,
    @location(8) @interpolate(flat) to_eye: vec3<f32>,
};

@vertex
fn vs_animated_impostor(@builtin(vertex_index) vi: u32, inst: Instance) -> AnimatedOut {
    // The frames round the instance's time, in the clip that weighs more.
    let now = instance_frames(inst);
    let stride = max(u32(inst.clip.w), 1u);
    var f0 = now.row0 / stride;
    var f1 = now.row1 / stride;
    var blend = now.blend;
    if (now.fade > 0.5) {
        f0 = now.row0b / stride;
        f1 = now.row1b / stride;
        blend = now.blendb;
    }
    let p0 = max(f0, 1u) - 1u;
    let p1 = max(f1, 1u) - 1u;

    let views = impostor.grid.x;
    // Where the clip has carried the body (root motion): the pages draw it where it stands,
    // and each page's travel follows the views in `impostor_rects` where grid.w is set
    // (`AnimatedFrame::travel`), blended as the two pages are.
    var travel = vec3<f32>(0.0);
    if (impostor.grid.w > 0.5) {
        let first = u32(views * views);
        let t0 = textureLoad(impostor_rects, vec2<u32>(first + p0, 0u), 0).xyz;
        let t1 = textureLoad(impostor_rects, vec2<u32>(first + p1, 0u), 0).xyz;
        travel = mix(t0, t1, blend);
    }
    let centre = impostor.sphere.xyz + travel;
    let radius = impostor.sphere.w;
    let v = frame.camera_pos.xyz - instance_point(inst, centre);
    let d = normalize(inst.row0.xyz * v.x + inst.row1.xyz * v.y + inst.row2.xyz * v.z);

    // The heaviest of the three views round d (see `vs_impostor`).
    let n = views - 1.0;
    let g = clamp((hemi_oct_encode(d) + vec2<f32>(1.0)) * 0.5 * n, vec2<f32>(0.0), vec2<f32>(n));
    let base = min(floor(g), vec2<f32>(n - 1.0));
    let f = g - base;
    var c1 = base + vec2<f32>(0.0, 1.0);
    var w = vec3<f32>(1.0 - f.y, f.y - f.x, f.x);
    if (f.x >= f.y) {
        c1 = base + vec2<f32>(1.0, 0.0);
        w = vec3<f32>(1.0 - f.x, f.x - f.y, f.y);
    }
    var cell = base;
    if (w.y > w.x && w.y >= w.z) {
        cell = c1;
    } else if (w.z > w.x && w.z > w.y) {
        cell = base + vec2<f32>(1.0);
    }

    let columns = max(u32(impostor.grid.y), 1u);
    let page0 = vec2<f32>(f32(p0 % columns), f32(p0 / columns)) * views;
    let page1 = vec2<f32>(f32(p1 % columns), f32(p1 / columns)) * views;

    // The quad faces the eye, and a point of it shows what lies behind it along the view
    // drawn: `offset` (a share of the radius along the eye's axes q) reads the view's cell at
    // st, where (2 st.x − 1, 1 − 2 st.y) = (offset · right_k, offset · up_k) / radius = M q.
    // It spans only the rectangle of the cell that any frame covers: its corners are M⁻¹ of
    // the rectangle's. (Square to the eye, st is affine on the screen; a quad square to the
    // view drawn instead made llvmpipe's texture reads five times slower.)
    let eye = view_axes(d);
    let drawn = view_axes(hemi_oct_decode(cell / n * 2.0 - vec2<f32>(1.0)));
    let rect = textureLoad(impostor_rects, vec2<u32>(u32(cell.y * views + cell.x), 0u), 0);
    let st = mix(rect.xy, rect.zw, vec2<f32>(f32(vi & 1u), f32(vi >> 1u)));
    let a = vec2<f32>(2.0 * st.x - 1.0, 1.0 - 2.0 * st.y);
    let m00 = dot(eye.right, drawn.right);
    let m01 = dot(eye.up, drawn.right);
    let m10 = dot(eye.right, drawn.up);
    let m11 = dot(eye.up, drawn.up);
    let det = m00 * m11 - m01 * m10;
    let q = vec2<f32>(m11 * a.x - m01 * a.y, m00 * a.y - m10 * a.x) / select(det, 1e-4, abs(det) < 1e-4);
    let offset = radius * (q.x * eye.right + q.y * eye.up);
    let world = instance_point(inst, centre + offset);

    var out: AnimatedOut;
    out.clip = frame.view_proj * vec4<f32>(world, 1.0);
    out.st = st;
    out.cells = vec4<f32>(page0 + cell, page1 + cell);
    out.blend = vec4<f32>(blend, inst.lod.z, impostor.cell.x, 0.0);
    out.sheet = vec2<f32>(f32(columns), impostor.grid.z) * views;
    out.row0 = inst.row0.xyz;
    out.row1 = inst.row1.xyz;
    out.row2 = inst.row2.xyz;
    out.tint = vec4<f32>(inst.tint.rgb, fog_factor(world));
    out.debug = debug_color(lod_varying(inst), 1.0, frame.views.x);
    out.to_eye = normalize(v);
    return out;
}

// The two frames' colour (premultiplied by coverage and blended), alpha, and each one's share.
struct AnimatedTexel {
    colour: vec3<f32>,
    alpha: f32,
    shares: vec2<f32>,
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    gx: vec2<f32>,
    gy: vec2<f32>,
};

fn animated_texel(in: AnimatedOut) -> AnimatedTexel {
    let inset = in.blend.z;
    let st = clamp(in.st, vec2<f32>(inset), vec2<f32>(1.0 - inset));
    let uv0 = (in.cells.xy + st) / in.sheet;
    let uv1 = (in.cells.zw + st) / in.sheet;
    // Explicit gradients (llvmpipe's implicit ones took a path five times slower here),
    // halved: a mipmap finer than the pixel keeps thin limbs over the alpha test, where the
    // filtered coverage of the matching one thinned and thickened them (the impostor's colour
    // error at its switch size fell from 0.17 to 0.11 with it).
    let gx = 0.5 * dpdx(in.st) / in.sheet;
    let gy = 0.5 * dpdy(in.st) / in.sheet;
    let a = textureSampleGrad(material_tex, material_sampler, uv0, 0, gx, gy);
    let b = textureSampleGrad(material_tex, material_sampler, uv1, 0, gx, gy);
    let t = in.blend.x;
    let w = vec2<f32>((1.0 - t) * a.a, t * b.a);
    let alpha = w.x + w.y;
    return AnimatedTexel((w.x * a.rgb + w.y * b.rgb) / max(alpha, 1e-4), alpha, w, uv0, uv1, gx, gy);
}

// The two frames' normals, read before any pixel is discarded: on llvmpipe a texture read
// after a discard, with some pixels of a block gone, runs pixel by pixel (it made the 10,000
// crowd's impostors five times slower once their quads were cut down to what they cover).
struct AnimatedNormals {
    a: vec4<f32>,
    b: vec4<f32>,
};

fn animated_normals(texel: AnimatedTexel) -> AnimatedNormals {
    return AnimatedNormals(
        textureSampleGrad(material_tex, material_sampler, texel.uv0, 1, texel.gx, texel.gy),
        textureSampleGrad(material_tex, material_sampler, texel.uv1, 1, texel.gx, texel.gy),
    );
}

// Lit as the mesh levels are (`lit` in character.wgsl): the frames' normals blended as their
// colours were, turned into the world; sun and sky, rim, fog.
fn animated_lit(in: AnimatedOut, texel: AnimatedTexel, normals: AnimatedNormals) -> vec3<f32> {
    let a = normals.a;
    let b = normals.b;
    let w = texel.shares;
    let m = (w.x * a.rgb + w.y * b.rgb) * 2.0 - vec3<f32>(w.x + w.y);
    let rows = mat3x3<f32>(in.row0, in.row1, in.row2);
    return impostor_light(texel.colour, in.tint, in.debug, m * rows, in.to_eye);
}

// The dissolve between the coarsest mesh and the impostor (see `dithered_out`).
fn animated_dissolved(in: AnimatedOut) -> bool {
    return screened_out(in.clip.xy, in.blend.y);
}

@fragment
fn fs_animated_impostor(in: AnimatedOut) -> @location(0) vec4<f32> {
    let texel = animated_texel(in);
    let normals = animated_normals(texel);
    if (texel.alpha < 0.5 || animated_dissolved(in)) {
        discard;
    }
    return vec4<f32>(animated_lit(in, texel, normals), 1.0);
}

// With multisampling: alpha to coverage, sharpened to about a pixel round the outline.
@fragment
fn fs_animated_impostor_coverage(in: AnimatedOut) -> @location(0) vec4<f32> {
    let texel = animated_texel(in);
    let normals = animated_normals(texel);
    let a = clamp((texel.alpha - 0.5) / max(fwidth(texel.alpha), 1e-4) + 0.5, 0.0, 1.0);
    if (animated_dissolved(in)) {
        discard;
    }
    return vec4<f32>(animated_lit(in, texel, normals), a);
}

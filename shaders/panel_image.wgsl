// The viewer's panel as an image: egui draws the panel into a texture when it changes, and
// every frame copies that texture's pixels over the frame inside the panel's rectangles (the
// scissor rectangles), which costs a software rasteriser a fraction of egui's own shading.
// The texture holds premultiplied colour, drawn "over" what is there.

@group(0) @binding(0) var panel: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let xy = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u)) * 2.0 - 1.0;
    return vec4<f32>(xy, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(panel, vec2<i32>(pixel.xy), 0);
}

// Where the device cannot read the image through an sRGB view (WebGL2), the image is a plain
// texture and this decodes its sRGB colour (premultiplied: the colour channels only, as an
// sRGB texture's read does).
fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}

@fragment
fn fs_decode(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let p = textureLoad(panel, vec2<i32>(pixel.xy), 0);
    return vec4<f32>(srgb_to_linear(p.rgb), p.a);
}

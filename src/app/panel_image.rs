//! The viewer's panel as an image. egui's shader converts colours with `pow` at every fragment
//! and blends every layer of the panel (its fill, frames, text), which costs lavapipe about
//! 10 ms a frame at 1280×720; yet the panel changes a few times a second at most. So egui draws
//! it into a texture when it changes ([`PanelImage::refresh`]), and each frame copies that
//! texture onto the frame inside the few rectangles the panel covers ([`PanelImage::draw`]).

use crate::render::shaders::PANEL_IMAGE_SHADER;

/// The panel's last drawing, and what copies it onto a frame.
pub struct PanelImage {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    format: wgpu::TextureFormat,
    /// Whether the device can view a texture in another format (WebGL2 cannot): else the image
    /// is a plain texture and the copy decodes its sRGB in the shader.
    view_formats: bool,
    /// The texture egui draws the panel into, the view egui draws through (without sRGB
    /// encoding: egui blends in gamma space), and the bind group that reads it (decoding sRGB,
    /// as the frame is linear); `None` before the first drawing.
    image: Option<(wgpu::Texture, wgpu::TextureView, wgpu::BindGroup)>,
    /// The rectangles (x, y, width, height in pixels) the panel's meshes cover, none inside
    /// another: where the image is copied.
    rects: Vec<[u32; 4]>,
    /// Whether the image shows the panel's current meshes.
    fresh: bool,
}

impl PanelImage {
    /// A panel image for frames of `format` (the window's surface format), on a device that
    /// can or cannot view a texture in another format (`view_formats`).
    pub fn new(
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        view_formats: bool,
    ) -> PanelImage {
        // Where the image cannot be an sRGB texture read as one, the shader decodes.
        let decode = format.is_srgb() && !view_formats;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("panel image"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("panel image"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = PANEL_IMAGE_SHADER.create(device);
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("panel image"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(if decode { "fs_decode" } else { "fs_main" }),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        PanelImage {
            pipeline,
            layout,
            format,
            view_formats,
            image: None,
            rects: Vec::new(),
            fresh: false,
        }
    }

    /// The panel's meshes changed (or egui's buffers were filled again): draw them again
    /// before the next copy.
    pub fn stale(&mut self) {
        self.fresh = false;
    }

    /// Whether the image must be drawn again for frames of `size` pixels.
    pub fn needs_refresh(&self, size: [u32; 2]) -> bool {
        !self.fresh || self.image.as_ref().map(|(t, ..)| [t.width(), t.height()]) != Some(size)
    }

    /// Draws `primitives` (already uploaded to `renderer`) into the image at `screen`, in
    /// `encoder`, writing the beginning timestamp of `timestamps` where given.
    pub fn refresh(
        &mut self,
        device: &wgpu::Device,
        renderer: &egui_wgpu::Renderer,
        encoder: &mut wgpu::CommandEncoder,
        primitives: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let [w, h] = screen.size_in_pixels;
        if self.image.as_ref().map(|(t, ..)| [t.width(), t.height()]) != Some([w, h]) {
            let plain = self.format.remove_srgb_suffix();
            let views: Vec<wgpu::TextureFormat> = (self.format.is_srgb() && self.view_formats)
                .then_some(plain)
                .into_iter()
                .collect();
            let format = if self.view_formats {
                self.format
            } else {
                plain
            };
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("panel image"),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &views,
            });
            let read = texture.create_view(&Default::default());
            let drawn = texture.create_view(&wgpu::TextureViewDescriptor {
                format: Some(plain),
                ..Default::default()
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("panel image"),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&read),
                }],
            });
            self.image = Some((texture, drawn, bind_group));
        }
        let (_, view, _) = self.image.as_ref().expect("just made");
        crate::app::window::draw_panel(
            renderer,
            encoder,
            view,
            primitives,
            screen,
            "panel image",
            Some(wgpu::Color::TRANSPARENT),
            timestamps.map(|t| wgpu::RenderPassTimestampWrites {
                end_of_pass_write_index: None,
                ..t
            }),
        );
        self.rects = covered(primitives, screen.pixels_per_point, [w, h]);
        self.fresh = true;
    }

    /// Whether the panel's last drawing covers `pixel` (in pixels).
    pub fn covers(&self, pixel: egui::Pos2) -> bool {
        self.rects.iter().any(|&[x, y, w, h]| {
            let (px, py) = (pixel.x, pixel.y);
            px >= x as f32 && py >= y as f32 && px < (x + w) as f32 && py < (y + h) as f32
        })
    }

    /// Copies the image onto `view` inside the panel's rectangles, writing the end timestamp
    /// of `timestamps` where given (and the beginning too where `begins`: the image was not
    /// drawn this frame).
    pub fn draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        view: &wgpu::TextureView,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
        begins: bool,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("panel"),
            timestamp_writes: timestamps.map(|t| wgpu::RenderPassTimestampWrites {
                beginning_of_pass_write_index: t.beginning_of_pass_write_index.filter(|_| begins),
                ..t
            }),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        let Some((texture, _, bind_group)) = &self.image else {
            return;
        };
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        for &[x, y, w, h] in &self.rects {
            // The image was drawn for this frame's size; a rectangle is cut to it all the same.
            let (x1, y1) = ((x + w).min(texture.width()), (y + h).min(texture.height()));
            if x1 > x && y1 > y {
                pass.set_scissor_rect(x, y, x1 - x, y1 - y);
                pass.draw(0..3, 0..1);
            }
        }
    }
}

/// The rectangles (x, y, width, height in pixels of a `size` screen) that `primitives` cover
/// at `pixels_per_point`: each mesh's bounds cut to its clip rectangle, overlapping ones
/// merged into their bounds until none overlap.
pub fn covered(
    primitives: &[egui::ClippedPrimitive],
    pixels_per_point: f32,
    size: [u32; 2],
) -> Vec<[u32; 4]> {
    let mut rects: Vec<egui::Rect> = Vec::new();
    for p in primitives {
        let bounds = match &p.primitive {
            egui::epaint::Primitive::Mesh(mesh) => {
                if mesh.indices.is_empty() {
                    continue;
                }
                mesh.calc_bounds().intersect(p.clip_rect)
            }
            egui::epaint::Primitive::Callback(_) => p.clip_rect,
        };
        if bounds.is_positive() {
            rects.push(bounds);
        }
    }
    // Merge until no two overlap: a panel is one rectangle (its fill under all of it), and
    // a label or a pop-up over the view one more.
    let mut merged = true;
    while merged {
        merged = false;
        'outer: for i in 0..rects.len() {
            for j in i + 1..rects.len() {
                if rects[i].intersects(rects[j]) {
                    rects[i] = rects[i].union(rects[j]);
                    rects.swap_remove(j);
                    merged = true;
                    break 'outer;
                }
            }
        }
    }
    rects
        .into_iter()
        .filter_map(|r| {
            let x0 = ((r.min.x * pixels_per_point).floor().max(0.0) as u32).min(size[0]);
            let y0 = ((r.min.y * pixels_per_point).floor().max(0.0) as u32).min(size[1]);
            let x1 = ((r.max.x * pixels_per_point).ceil().max(0.0) as u32).min(size[0]);
            let y1 = ((r.max.y * pixels_per_point).ceil().max(0.0) as u32).min(size[1]);
            (x1 > x0 && y1 > y0).then_some([x0, y0, x1 - x0, y1 - y0])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui::{Color32, Pos2, Rect, epaint::Mesh};

    fn quad(min: (f32, f32), max: (f32, f32), clip: Rect) -> egui::ClippedPrimitive {
        let mut mesh = Mesh::default();
        mesh.add_colored_rect(
            Rect::from_min_max(Pos2::new(min.0, min.1), Pos2::new(max.0, max.1)),
            Color32::WHITE,
        );
        egui::ClippedPrimitive {
            clip_rect: clip,
            primitive: egui::epaint::Primitive::Mesh(mesh),
        }
    }

    #[test]
    fn a_panel_and_a_label_are_two_rectangles_cut_to_their_clips() {
        let screen = Rect::from_min_max(Pos2::ZERO, Pos2::new(640.0, 360.0));
        let primitives = [
            // The panel's fill, and a text row inside it.
            quad((0.0, 0.0), (270.0, 360.0), screen),
            quad((8.0, 10.0), (200.0, 24.0), screen),
            // A label over the view, its clip cutting it.
            quad((400.0, 20.0), (700.0, 40.0), screen),
            // A text row scrolled out of its clip: not drawn at all.
            quad(
                (8.0, 400.0),
                (200.0, 420.0),
                Rect::from_min_max(Pos2::ZERO, Pos2::new(270.0, 360.0)),
            ),
        ];
        let mut rects = covered(&primitives, 2.0, [1280, 720]);
        rects.sort();
        assert_eq!(rects, vec![[0, 0, 540, 720], [800, 40, 480, 40]]);
    }
}

//! The products the bake asks the GPU for: the bake is plain CPU code, but a few of its
//! products are pictures, drawn or measured on the GPU. It asks for them through these traits,
//! which `render` and `measure` implement (a test may implement them on the CPU), and the
//! messages they carry are plain data defined here, so that the bake's subjects (foliage,
//! impostors) share them without naming each other.
//!
//! - [`RasterizeAtlas`] draws billboard atlases (thesis §3.3) and impostor views;
//! - [`MeasureColour`] measures a tree level's colour error (thesis §5.1.3);
//! - [`MeasureImpostor`] measures an impostor's colour error beside a level's, where it would
//!   switch in (see [`crate::bake::impostor::placement`]).

use crate::bake::gpu_data::drawable::Drawable;
use crate::bake::gpu_data::materials::MaterialLayers;
use crate::model::{Model, Rgba8Image};
use anyhow::Result;
use glam::{Vec2, Vec3};

/// Where every billboard's texture lies in the atlas.
#[derive(Clone, Debug, PartialEq)]
pub struct AtlasLayout {
    pub width: u32,
    pub height: u32,
    /// Texels per scene unit actually used (less than asked for where the atlas would not
    /// fit otherwise).
    pub texels_per_unit: f32,
    /// Per billboard, the texels its rectangle maps onto: x, y, width, height (without the
    /// gutter).
    pub rects: Vec<[u32; 4]>,
    /// Texels of gutter round every rectangle.
    pub gutter: u32,
}

impl AtlasLayout {
    /// Texture coordinates of a billboard's four corners, in the order of
    /// [`Billboard::corners`](crate::bake::foliage::billboard::cloud::Billboard::corners).
    pub fn corner_uvs(&self, b: usize) -> [Vec2; 4] {
        let [x, y, w, h] = self.rects[b];
        let (aw, ah) = (self.width as f32, self.height as f32);
        let (x0, y0) = (x as f32 / aw, y as f32 / ah);
        let (x1, y1) = ((x + w) as f32 / aw, (y + h) as f32 / ah);
        [
            Vec2::new(x0, y1),
            Vec2::new(x1, y1),
            Vec2::new(x1, y0),
            Vec2::new(x0, y0),
        ]
    }
}

/// A vertex of a leaf triangle as drawn into the atlas.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct AtlasVertex {
    /// Atlas pixels (x right, y down).
    pub pixel: [f32; 2],
    /// Depth in 0..1: leaves on the billboard's front side (along its normal) win.
    pub depth: f32,
    /// The leaf texture coordinate.
    pub uv: [f32; 2],
    /// The normal the leaf is lit by seen from the billboard's front, in the billboard's
    /// [`billboard_frame`](crate::bake::foliage::billboard::atlas::billboard_frame) (t, b, n): its vertex normal, negated where the billboard's front
    /// sees the leaf's back face (the renderer lights a back face by the negated normal).
    pub normal: [f32; 3],
    /// The light the crown leaves the leaf here, 1 − occlusion.
    pub light: f32,
    /// The leaf's material: its layer of the tree's materials (each cut-out material with
    /// its own texture, cutoff and colour).
    pub layer: u32,
}

/// What an atlas's render gives: the colour darkened by the crown (sRGB, straight alpha) and
/// the lighting (linear bytes: rgb the normal in the billboard's frame as x/2 + 1/2; alpha
/// the coverage),
/// both transparent where no leaf is.
#[derive(Clone, Debug)]
pub struct AtlasImages {
    pub colour: Rgba8Image,
    pub lighting: Rgba8Image,
}

/// A vertex of the tree as the view bake draws it (`shaders/impostor_bake.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ViewVertex {
    /// Rest position, model space.
    pub position: [f32; 3],
    /// Material layer.
    pub layer: u32,
    pub normal: [f32; 3],
    /// 1 where the material cuts its shape out with alpha (foliage).
    pub cut_out: u32,
    pub uv: [f32; 2],
    /// The light the crown leaves it, 1 − occlusion ([`crate::bake::foliage::billboard::occlusion`]): the views' colour
    /// is darkened by it, as the tree's own leaves are when drawn.
    pub light: f32,
}

/// One view of the bake: its cell's corner in the target (pixels), the cell's size, and the
/// orthographic camera's axes (right, up, towards the eye), each scaled by 1 / radius.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ViewCamera {
    pub cell: [f32; 4],
    pub right: [f32; 4],
    pub up: [f32; 4],
    pub toward: [f32; 4],
}

/// What the view bake draws: every triangle of the tree (as a list of vertices, three a
/// triangle) from every view, into a `size` × `size` target, about `centre`.
#[derive(Clone, Debug)]
pub struct ViewRequest {
    pub size: u32,
    pub centre: Vec3,
    pub vertices: Vec<ViewVertex>,
    pub views: Vec<ViewCamera>,
}

/// The drawn views: unlit colour (sRGB, alpha 255 where the tree covers a texel, else 0) and
/// the model-space normal turned towards the eye (n / 2 + 1/2 as unsigned bytes), its alpha
/// the covered point's height towards the eye (see [`encode_height`](crate::bake::impostor::octahedral::encode_height)).
#[derive(Clone, Debug)]
pub struct ViewImages {
    pub colour: Rgba8Image,
    pub normal: Rgba8Image,
}

/// What draws an atlas: the one GPU-made part of a billboard cloud, behind a narrow seam so
/// that the bake stays plain CPU code (`render::atlas` implements it; a test may rasterise on
/// the CPU).
pub trait RasterizeAtlas {
    /// `vertices` (triangles in atlas pixels, see [`atlas_triangles`](crate::bake::foliage::billboard::atlas::atlas_triangles)) each textured by its layer
    /// of `leaves` (mipmapped), into two `layout`-sized images (see [`AtlasImages`]),
    /// straight (not premultiplied) alpha, transparent where no leaf is; each leaf blended
    /// over what is there by its texture's alpha in both.
    fn rasterize(
        &self,
        layout: &AtlasLayout,
        vertices: &[AtlasVertex],
        leaves: &MaterialLayers,
    ) -> Result<AtlasImages>;

    /// The views of an octahedral impostor ([`view_request`](crate::bake::impostor::octahedral::view_request)): every
    /// triangle drawn from every view into its cell, textured by its layer of `materials`,
    /// depth-tested, cut out where a cut-out layer's alpha is below one half; unlit colour
    /// and the normal facing the eye, see [`ViewImages`].
    fn rasterize_views(
        &self,
        request: &ViewRequest,
        materials: &MaterialLayers,
    ) -> Result<ViewImages>;
}

/// Measures a level's colour error against the full tree (thesis §5.1.3), both drawn whole,
/// wood and all, `height_px` pixels high: the one step of a chain's bake that draws animated
/// trees (`measure::colour_error` implements it).
pub trait MeasureColour {
    /// The error of `level` (drawn as `bake`) at each of `heights_px` (a level is uploaded
    /// once for all of them).
    fn colour_errors(
        &self,
        tree: &Model,
        level: &Model,
        bake: Drawable,
        heights_px: &[f32],
    ) -> Result<Vec<f32>>;

    /// The fragments `level` (drawn as `bake`) shades when drawn `heights_px` high, a mean over
    /// the metric's views; None where the adapter cannot count fragments.
    fn fragments(
        &self,
        tree: &Model,
        level: &Model,
        bake: Drawable,
        heights_px: &[f32],
    ) -> Result<Option<Vec<f64>>>;
}

/// Measures, for placing an impostor, its colour error and a level's, both against full
/// detail, with the model drawn a given height in pixels (`measure` implements it for
/// characters and trees).
pub trait MeasureImpostor {
    /// The colour errors against full detail of the impostor and of level `level` (finest
    /// first, 0 full detail), the model drawn `px` pixels high.
    fn errors(&mut self, level: usize, px: f32) -> Result<(f32, f32)>;
}

//! The frames impostors are drawn by, as the renderer's uniforms carry them: plain data,
//! kept here beside the rest of a drawable so that [`super::drawable`] names no bake.
//! [`crate::bake::impostor::octahedral`] (trees) and [`crate::bake::impostor::animated`]
//! (characters) make them.

use serde::{Deserialize, Serialize};

/// Where an impostor's views lie and how its quad is placed: what the renderer reads (the
/// character's uniform, `shaders/impostor.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImpostorFrame {
    /// Views on a side of the atlas's grid.
    pub frames: u32,
    /// The centre of the sphere the views were drawn round, model space, and its radius: a
    /// view's cell shows the square [−radius, radius]² about the centre.
    pub centre: [f32; 3],
    pub radius: f32,
    /// The heights of the quad's lowest and highest rows, model space.
    pub base: f32,
    pub height: f32,
    /// Rows of the quad (its vertices are `rows + 1` pairs, bottom up).
    pub rows: u32,
    /// The tree's bounds at rest, model space: what culling and the blob shadow use (the
    /// quad's own mesh is only as wide as a card).
    pub bounds: [[f32; 3]; 2],
}

/// Where an animated impostor's views lie: what the renderer's uniform carries (mirror of
/// `ImpostorFrame` in `shaders/impostor.wgsl`, read by `vs_animated_impostor`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AnimatedFrame {
    /// Views on a side of the grid.
    pub views: u32,
    /// Texels on a side of a view's cell.
    pub cell: u32,
    /// Pages on a row of the sheets, and rows of pages: frame f's page is at column
    /// f mod `columns`, row f / `columns`.
    pub columns: u32,
    pub rows: u32,
    /// The sphere every view is framed on (model space), over every frame of every clip.
    pub centre: [f32; 3],
    pub radius: f32,
    /// Per view (row by row), the part of its cell any frame covers: s0, t0, s1, t1 in 0..1
    /// of the cell, a texel wider all round. The renderer's quad spans only that: a walker
    /// covers a fifth of its view sphere's square, and on a software rasteriser every
    /// fragment of the quad costs, kept or cut out.
    pub rects: Vec<[f32; 4]>,
    /// Per page, where the character's clip has carried it (root motion): the page draws the
    /// body moved back by it, and the renderer moves the quad by it again, blended between
    /// the two pages as the pages are. Empty where no clip carries it.
    #[serde(default)]
    pub travel: Vec<[f32; 3]>,
}

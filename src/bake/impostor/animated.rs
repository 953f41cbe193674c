//! Animated impostors: a character's last level of detail, below its coarsest mesh, as one
//! quad showing the character drawn beforehand from a grid of view directions at a few frames
//! of every clip. This is the image-based crowd of Tecchia, Loscos & Chrysanthou, "Image-based
//! crowd rendering" (2002), with the normal maps of Dobbyn et al.'s geopostors ("Geopostors",
//! 2005) so that the sun lights it as it lights the meshes.
//!
//! Views. The directions are the hemi-octahedral grid of the trees' impostors
//! ([`crate::bake::impostor::octahedral::ViewGrid`]): `views` × `views` directions over the upper
//! hemisphere, each drawn orthographically into a `cell` × `cell` texel cell of a page. A far
//! character is a few dozen pixels high, so the renderer reads only the view nearest the line
//! of sight (the heaviest of [`ViewGrid::blend`]), on a quad square to that view and only as
//! large as what the view ever covers ([`AnimatedFrame::rects`]), and pays four texture reads
//! a pixel where the trees' three-view blend pays seven.
//!
//! Frames. Every clip is sampled at `frames` times over its length (the ends included, as the
//! animation texture samples it), and each sample is one page: all its views. The pages lie
//! side by side in two sheets, one layer of the material array each: colour, and the
//! model-space normal. (One page a layer would be simpler, but a layer index that varies from
//! pixel to pixel takes a software rasteriser's slow path: on llvmpipe it made the impostors
//! of a 1,000-character crowd cost five times what their meshes did.) The impostor's own
//! animation texture holds the same frames ([`AnimationTexture::bake_frames`]), so the
//! renderer's clip timing hands the shader the two frames round the instance's time and the
//! blend between them, as for skinning; a clip cross-fade shows the clip that weighs more.
//!
//! Error. Where the impostor joins a method's chain is measured by its colour error against
//! full detail (`measure::impostor_fit`). The bake also bounds how far a point of it can
//! land off its place ([`ImpostorError`]), the worst case: its depth off the quad's plane
//! times sin δ plus the radius times 1 − cos δ, when the line of sight is δ away from the view
//! drawn; half the farthest a vertex moves between two frames (the blend cross-fades them);
//! and half a texel. That bound says which option to raise (views, frames or cell) when the
//! impostor comes in late.

use crate::bake::gpu_data::anim_texture::{self, AnimationTexture};
use crate::bake::gpu_data::materials::{MaterialLayers, dilate, preserve_coverage};
use crate::bake::gpu_products::{RasterizeAtlas, ViewImages};
use crate::bake::impostor::octahedral::{
    SUPERSAMPLE, ViewGrid, average_down, dilate_cells, encode_height, posed, view_sphere,
    views_about,
};
use crate::model::{Influence, Material, Model, Rgba8Image, SkinnedMesh};
use anyhow::{Result, anyhow};
use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

pub use super::sheet::{
    CELL, FRAMES, ImpostorOptions, SHEET_SIZE, VIEWS, clip_frames, page_times, sheet_layout,
};
pub use crate::bake::gpu_data::impostor_frames::AnimatedFrame;

/// The part of each view's cell that any page covers (see [`AnimatedFrame::rects`]), from the
/// colour sheet of `pages` pages laid out `columns` a row.
pub fn covered_rects(
    colour: &Rgba8Image,
    options: &ImpostorOptions,
    pages: u32,
    columns: u32,
) -> Vec<[f32; 4]> {
    let (views, cell) = (options.views as usize, options.cell as usize);
    let side = views * cell;
    let mut rects = vec![[f32::MAX, f32::MAX, f32::MIN, f32::MIN]; views * views];
    for page in 0..pages as usize {
        let (px, py) = (
            page % columns as usize * side,
            page / columns as usize * side,
        );
        for y in 0..side {
            for x in 0..side {
                let k = 4 * ((py + y) * colour.width as usize + px + x);
                if colour.pixels[k + 3] == 0 {
                    continue;
                }
                let r = &mut rects[(y / cell) * views + x / cell];
                let (u, v) = ((x % cell) as f32, (y % cell) as f32);
                *r = [
                    r[0].min(u),
                    r[1].min(v),
                    r[2].max(u + 1.0),
                    r[3].max(v + 1.0),
                ];
            }
        }
    }
    let c = cell as f32;
    rects
        .into_iter()
        .map(|r| {
            if r[0] > r[2] {
                // Nothing covered: an empty quad.
                return [0.5; 4];
            }
            [
                ((r[0] - 1.0) / c).max(0.0),
                ((r[1] - 1.0) / c).max(0.0),
                ((r[2] + 1.0) / c).min(1.0),
                ((r[3] + 1.0) / c).min(1.0),
            ]
        })
        .collect()
}

/// The parts of an impostor's worst-case error bound, scene units (see the module comment).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ImpostorError {
    /// From the line of sight falling between views: the worst angle to the view drawn is
    /// `view_angle` (degrees), the character's depth off the quad's plane `depth`.
    pub view: f32,
    pub view_angle: f32,
    pub depth: f32,
    /// The farthest the character between two frames strays from the nearer of them.
    pub frame: f32,
    /// Half a texel.
    pub texel: f32,
}

impl ImpostorError {
    pub fn total(&self) -> f32 {
        self.view + self.frame + self.texel
    }
}

/// A character's animated impostor, as cached: the quad model (its materials the two
/// sheets, colour and normal), its frame and its error.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AnimatedImpostor {
    pub model: Model,
    pub frame: AnimatedFrame,
    pub options: ImpostorOptions,
    pub error: ImpostorError,
    /// Frames over all clips (pages are twice as many).
    pub frames: u32,
}

impl AnimatedImpostor {
    /// Bytes of its pages, without mipmaps.
    pub fn texture_bytes(&self) -> u64 {
        self.model
            .materials
            .iter()
            .filter_map(|m| m.texture.as_ref())
            .map(|t| t.pixels.len() as u64)
            .sum()
    }

    /// The impostor baked for the GPU: the quad (vertices in order: the shader makes its
    /// corners from their indices), the pages as its material layers, the clips resampled at
    /// the impostor's frames, and the character's own bounds and travel (`full`'s: culling and
    /// the blob shadow) in place of the quad's.
    pub fn bake(
        &self,
        full: &crate::bake::gpu_data::drawable::Drawable,
    ) -> Result<crate::bake::gpu_data::drawable::Drawable, String> {
        let mut bake = crate::bake::gpu_data::drawable::Drawable::in_order(&self.model)?;
        let counts = clip_frames(&self.model, &self.options)?;
        bake.animation = AnimationTexture::bake_frames_each(&self.model, &counts);
        bake.bounds = full.bounds;
        // The character's travel at the impostor's own frames: a world of the impostor alone
        // (the fit's) moves its sphere and shadow as the character's does.
        bake.travel = if full.travel.is_empty() {
            Vec::new()
        } else {
            (bake.animation.clips.iter().enumerate())
                .map(|(c, clip)| {
                    (0..clip.frame_count)
                        .map(|f| {
                            let t = anim_texture::frame_time(clip.duration, clip.frame_count, f);
                            full.travel_within(c, t)
                        })
                        .collect()
                })
                .collect()
        };
        // Its pages' alpha is coverage, not a cut-out material: it is a character, drawn in
        // the characters' pass by its own shader.
        bake.kind =
            crate::bake::gpu_data::drawable::DrawKind::CharacterImpostor(self.frame.clone());
        Ok(bake)
    }
}

/// The view the renderer reads for direction `d`: the heaviest of the three round it
/// (mirror of the choice in `vs_animated_impostor`).
pub fn nearest_view(grid: &ViewGrid, d: Vec3) -> (u32, u32) {
    let blend = grid.blend(d);
    let mut best = blend[0];
    for b in &blend[1..] {
        if b.1 > best.1 {
            best = *b;
        }
    }
    best.0
}

/// The widest angle (degrees) between a line of sight over the hemisphere and the view
/// [`nearest_view`] takes for it, over a fine grid of lines of sight.
pub fn worst_view_angle(grid: &ViewGrid) -> f32 {
    let n = 96;
    let mut worst = 0.0f32;
    for j in 0..=n {
        for i in 0..=n {
            let s = Vec2::new(i as f32, j as f32) / n as f32 * 2.0 - Vec2::ONE;
            let d = crate::bake::impostor::octahedral::hemi_oct_decode(s);
            let (a, b) = nearest_view(grid, d);
            let angle = grid.direction(a, b).dot(d).clamp(-1.0, 1.0).acos();
            worst = worst.max(angle.to_degrees());
        }
    }
    worst
}

/// Where a character's clip has carried its body `t` seconds into clip `clip` (root motion,
/// see [`crate::bake::gpu_data::root_motion`]): zero for one that stays put.
pub type Travel<'a> = &'a dyn Fn(usize, f32) -> Vec3;

/// No root motion: every pose where the clip has it.
pub fn no_travel(_: usize, _: f32) -> Vec3 {
    Vec3::ZERO
}

/// `model` posed `t` seconds into `clip` and moved back by where the clip has carried it
/// (`travel`): the body where it stands, which the pages draw; the renderer moves the quad
/// by the travel again.
fn body_pose(model: &Model, travel: Travel, clip: Option<&crate::model::Clip>, t: f32) -> Model {
    let mut pose = posed(model, clip, t);
    let index = clip.and_then(|c| model.clips.iter().position(|k| std::ptr::eq(k, c)));
    if let Some(moved) = index.map(|c| travel(c, t)).filter(|m| *m != Vec3::ZERO) {
        pose.mesh.positions.iter_mut().for_each(|p| *p -= moved);
    }
    pose
}

/// `options` with the cell a character's clips are best drawn at. Where every clip gets the
/// frames asked for, the cell asked for. Else its sheet trades texels for frames: of the
/// cells from the one asked for down (each a fifth smaller, to [`CELL`]'s least), the one
/// whose two traded errors sum least, half a texel of the view sphere and the frame error of
/// the clips at the frames its sheet then allows ([`clip_frames`], [`frame_error`]).
fn cell_for_clips(model: &Model, travel: Travel, options: ImpostorOptions) -> ImpostorOptions {
    let clips = model.clips.len().max(1) as u32;
    let most = |o: &ImpostorOptions| (SHEET_SIZE / o.page_side().max(1)).max(1).pow(2);
    if clips * options.frames.max(2) <= most(&options) {
        return options;
    }
    let mut best: Option<(f32, ImpostorOptions)> = None;
    let mut radius = None;
    let mut cell = options.cell;
    while cell >= *CELL.start() {
        let o = ImpostorOptions { cell, ..options };
        if let Ok(counts) = clip_frames(model, &o) {
            let times = page_times(model, &counts);
            let poses: Vec<Model> = times
                .iter()
                .map(|&(c, t)| body_pose(model, travel, c, t))
                .collect();
            let r = *radius.get_or_insert_with(|| {
                let all: Vec<Vec3> = poses
                    .iter()
                    .flat_map(|p| p.mesh.positions.clone())
                    .collect();
                view_sphere(&all).map_or(1.0, |(_, r)| r)
            });
            let error = r / cell as f32 + frame_error(model, travel, &poses, &times);
            if best.is_none_or(|(e, _)| error < e) {
                best = Some((error, o));
            }
            if clips * o.frames.max(2) <= most(&o) {
                break;
            }
        }
        cell = cell * 4 / 5;
    }
    best.map_or(options, |(_, o)| o)
}

/// How far the character between two frames of a clip strays from the nearer of them (`model`
/// posed as `poses` at `times`): the farthest any vertex of the poses a third, half and two
/// thirds of the way between lies from where the nearer frame has it. Two frames alike (a cycle's first and last) with
/// a stride between them still count the stride; frames of different clips are not compared.
fn frame_error(
    model: &Model,
    travel: Travel,
    poses: &[Model],
    times: &[(Option<&crate::model::Clip>, f32)],
) -> f32 {
    let mut most = 0.0f32;
    for (k, pair) in poses.windows(2).enumerate() {
        let (Some(clip), Some(next)) = (times[k].0, times[k + 1].0) else {
            continue;
        };
        if !std::ptr::eq(clip, next) {
            continue;
        }
        let (t0, t1) = (times[k].1, times[k + 1].1);
        for s in [1.0 / 3.0, 0.5, 2.0 / 3.0] {
            let between = body_pose(model, travel, Some(clip), t0 + s * (t1 - t0));
            for ((p, a), b) in between
                .mesh
                .positions
                .iter()
                .zip(&pair[0].mesh.positions)
                .zip(&pair[1].mesh.positions)
            {
                most = most.max(p.distance(*a).min(p.distance(*b)));
            }
        }
    }
    most
}

/// The most triangles an impostor is drawn from. Its views are a few dozen pixels across, and
/// every page draws the model once a view (144 views by default): a 2-million-triangle
/// character is thousands of triangles a pixel there, and hours of a software rasteriser's
/// time for pictures no different. A larger mesh is simplified to this many first
/// ([`drawn_for_impostor`]). Every built-in model is under it, drawn as it is.
pub const IMPOSTOR_TRIANGLES: usize = 32_768;

/// `model`, or where it has more than [`IMPOSTOR_TRIANGLES`] triangles, a copy whose mesh
/// meshoptimizer has simplified to that many (by position; the vertices it keeps keep their
/// skin weights, texture coordinates and materials).
pub fn drawn_for_impostor(model: &Model) -> std::borrow::Cow<'_, Model> {
    if model.mesh.triangle_count() <= IMPOSTOR_TRIANGLES {
        return std::borrow::Cow::Borrowed(model);
    }
    simplified_for_impostor(model)
}

/// The web build has no meshoptimizer (C++) and bakes nothing: a model is drawn whole.
#[cfg(target_arch = "wasm32")]
fn simplified_for_impostor(model: &Model) -> std::borrow::Cow<'_, Model> {
    std::borrow::Cow::Borrowed(model)
}

/// `model` simplified by meshoptimizer to [`IMPOSTOR_TRIANGLES`] (see [`drawn_for_impostor`]).
#[cfg(not(target_arch = "wasm32"))]
fn simplified_for_impostor(model: &Model) -> std::borrow::Cow<'_, Model> {
    let adapter =
        meshopt::VertexDataAdapter::new(bytemuck::cast_slice(&model.mesh.positions), 12, 0)
            .expect("tightly packed positions");
    // No error bound: at this count the error is far under a texel of the views anyway.
    let indices = meshopt::simplify(
        &model.mesh.indices,
        &adapter,
        IMPOSTOR_TRIANGLES * 3,
        1.0,
        meshopt::SimplifyOptions::empty(),
        None,
    );
    let mut coarse = model.clone();
    coarse.mesh.indices = indices;
    coarse.mesh.drop_unused();
    log::info!(
        "{}: impostor drawn from {} of its {} triangles",
        model.name,
        coarse.mesh.triangle_count(),
        model.mesh.triangle_count()
    );
    std::borrow::Cow::Owned(coarse)
}

/// Bakes the animated impostor of `model`: every page's views drawn through `raster` at
/// twice the cell size, averaged down and dilated, and the error bound measured on the way.
/// Where its clips carry it (`travel`), each page draws the body moved back to where it
/// stands, and the frame keeps each page's travel for the renderer to move the quad by.
pub fn bake_animated_impostor(
    raster: &dyn RasterizeAtlas,
    model: &Model,
    travel: Travel,
    options: ImpostorOptions,
) -> Result<AnimatedImpostor> {
    // Whether its pages can fit a sheet at all (at the least cell) is known from its clips
    // alone: asked before the mesh is simplified (seconds on a large character), so that a
    // character whose impostor cannot be made costs nothing to find out. The cell is then
    // chosen on the mesh the pages draw, not the full one: it poses the model at every page.
    let least = ImpostorOptions {
        cell: *CELL.start(),
        ..options
    };
    clip_frames(model, &least).map_err(|e| anyhow!("{}: {e}", model.name))?;
    let model = &*drawn_for_impostor(model);
    let name = &model.name;
    let options = cell_for_clips(model, travel, options);
    let side = options.page_side();
    let counts = clip_frames(model, &options).map_err(|e| anyhow!("{name}: {e}"))?;
    let times = page_times(model, &counts);
    let (columns, rows) =
        sheet_layout(times.len() as u32, side).map_err(|e| anyhow!("{name}: {e}"))?;
    let poses: Vec<Model> = times
        .iter()
        .map(|&(c, t)| body_pose(model, travel, c, t))
        .collect();
    let page_travel: Vec<[f32; 3]> = times
        .iter()
        .map(|&(c, t)| {
            let index = c.and_then(|c| model.clips.iter().position(|k| std::ptr::eq(k, c)));
            index.map_or(Vec3::ZERO, |c| travel(c, t)).to_array()
        })
        .collect();
    let all: Vec<Vec3> = poses
        .iter()
        .flat_map(|p| p.mesh.positions.iter().copied())
        .collect();
    let (centre, radius) =
        view_sphere(&all).ok_or_else(|| anyhow!("{name}: no vertices to draw an impostor of"))?;
    let frame_error = frame_error(model, travel, &poses, &times);
    let grid = options.grid();
    let materials = MaterialLayers::bake(&model.materials);
    let sheet = || Rgba8Image {
        width: columns * side,
        height: rows * side,
        pixels: vec![0; (4 * columns * side * rows * side) as usize],
    };
    let (mut colour, mut normal) = (sheet(), sheet());
    let mut depth = 0.0f32;
    for (k, pose) in poses.iter().enumerate() {
        let request = views_about(pose, grid, SUPERSAMPLE, centre, radius);
        let drawn = raster.rasterize_views(&request, &materials)?;
        let page = finish_page(&drawn, grid, &mut depth);
        let at = (k as u32 % columns * side, k as u32 / columns * side);
        paste(&mut colour, &page.colour, at);
        paste(&mut normal, &page.normal, at);
    }
    let angle = worst_view_angle(&grid);
    let depth = depth * radius;
    let error = ImpostorError {
        view: depth * angle.to_radians().sin() + radius * (1.0 - angle.to_radians().cos()),
        view_angle: angle,
        depth,
        frame: frame_error,
        texel: radius / options.cell as f32,
    };
    let frames = poses.len() as u32;
    let rects = covered_rects(&colour, &options, frames, columns);
    Ok(AnimatedImpostor {
        model: quad_model(model, vec![colour, normal]),
        frame: AnimatedFrame {
            views: options.views,
            cell: options.cell,
            columns,
            rows,
            centre: centre.to_array(),
            radius,
            rects,
            travel: if page_travel.iter().all(|t| *t == [0.0; 3]) {
                Vec::new()
            } else {
                page_travel
            },
        },
        options,
        error,
        frames,
    })
}

/// One page pair from its drawn views: averaged down, coverage kept under the alpha test and
/// thin parts kept whole ([`keep_thin_parts`]), colour dilated round the outlines, normals
/// filled over each whole cell (they are filtered as data). `depth` grows to the largest
/// height off the quad's plane of a covered texel, as a share of the radius.
fn finish_page(drawn: &ViewImages, grid: ViewGrid, depth: &mut f32) -> ViewImages {
    let mut images = average_down(drawn, SUPERSAMPLE);
    let px = &drawn.colour.pixels;
    let covered = px.chunks_exact(4).filter(|p| p[3] >= 128).count();
    preserve_coverage(
        &mut images.colour.pixels,
        covered as f32 / (px.len() / 4).max(1) as f32,
    );
    keep_thin_parts(&mut images.colour);
    let middle = encode_height(0.0) as f32;
    for (n, c) in images
        .normal
        .pixels
        .chunks_exact_mut(4)
        .zip(images.colour.pixels.chunks_exact(4))
    {
        if c[3] > 0 {
            *depth = depth.max((n[3] as f32 - middle).abs() / 63.5);
        }
        n[3] = c[3];
    }
    let (w, h) = (images.colour.width, images.colour.height);
    dilate(&mut images.colour.pixels, w, h, 2);
    dilate_cells(&mut images.normal.pixels, w, h, grid.cell);
    for n in images.normal.pixels.chunks_exact_mut(4) {
        n[3] = 255;
    }
    images
}

/// Texels a part thinner than a texel only grazes, covered. A character's arms are about a
/// texel thick in a 24-texel view (8 cm of a 1.9 m sphere), and a hand seen edge-on less:
/// where they cross texel boundaries, each texel holds under half of one, and under the alpha
/// test (coverage kept to the drawing's share, as the trees' leaves keep theirs) the arms of a
/// T-pose broke into dashes and lost their hands in some views. A texel that something covers
/// but not enough to pass, with at most two passing neighbours of its eight, lies on such a
/// part, not on a solid outline (every outline texel of a body has three or more): it passes.
/// Covering every grazed texel instead fattened the whole figure, and raised the walker's
/// colour error at 48 px from 0.15 to 0.22.
fn keep_thin_parts(colour: &mut Rgba8Image) {
    let (w, h) = (colour.width as i64, colour.height as i64);
    let alpha = |x: i64, y: i64| -> u8 {
        if x < 0 || y < 0 || x >= w || y >= h {
            0
        } else {
            colour.pixels[(4 * (y * w + x) + 3) as usize]
        }
    };
    let mut rescue = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let a = alpha(x, y);
            if a == 0 || a >= 128 {
                continue;
            }
            let passing = (-1..=1)
                .flat_map(|dy| (-1..=1).map(move |dx| (dx, dy)))
                .filter(|&(dx, dy)| (dx, dy) != (0, 0) && alpha(x + dx, y + dy) >= 128)
                .count();
            if passing <= 2 {
                rescue.push((4 * (y * w + x) + 3) as usize);
            }
        }
    }
    for i in rescue {
        colour.pixels[i] = 128;
    }
}

/// Copies `page` into `sheet` with its top left corner at `at`.
fn paste(sheet: &mut Rgba8Image, page: &Rgba8Image, at: (u32, u32)) {
    let row = 4 * page.width as usize;
    for y in 0..page.height as usize {
        let to = 4 * ((at.1 as usize + y) * sheet.width as usize + at.0 as usize);
        sheet.pixels[to..to + row].copy_from_slice(&page.pixels[y * row..(y + 1) * row]);
    }
}

/// The impostor's model: a quad of four vertices on bone 0 (the shader places it facing the
/// eye; only the indices matter), the character's skeleton and clips (its animation texture
/// is resampled at the impostor's frames), and the two sheets as materials.
fn quad_model(model: &Model, sheets: Vec<Rgba8Image>) -> Model {
    let mut mesh = SkinnedMesh::default();
    for v in 0..4u32 {
        let (x, y) = ((v & 1) as f32, (v >> 1) as f32);
        mesh.positions.push(Vec3::new(x - 0.5, y, 0.0));
        mesh.normals.push(Vec3::Z);
        mesh.uvs.push(Vec2::new(x, 1.0 - y));
        mesh.materials.push(0);
        mesh.influence_offsets.push(v);
        mesh.influences.push(Influence {
            bone: 0,
            weight: 1.0,
        });
    }
    mesh.influence_offsets.push(4);
    mesh.indices = vec![0, 1, 3, 0, 3, 2];
    let materials = sheets
        .into_iter()
        .zip(["impostor colour", "impostor normals"])
        .map(|(texture, name)| Material::cut_out(name, [1.0; 4], Some(texture)))
        .collect();
    Model {
        name: format!("{} impostor", model.name),
        mesh,
        skeleton: model.skeleton.clone(),
        clips: model.clips.clone(),
        materials,
    }
}

/// The cache key of `model`'s impostor (its source hashing to `source`) baked with `options`.
pub fn impostor_key(source: &[u8; 32], options: &ImpostorOptions) -> [u8; 32] {
    crate::bake::cache::keys::impostor_key(source, options.views, options.frames, options.cell)
}

/// `model`'s impostor from `cache` where a good one is there, else baked now and stored (a
/// model with no source, an all-zero hash, is baked and not cached).
pub fn load_or_bake_impostor(
    raster: &dyn RasterizeAtlas,
    cache: &crate::bake::cache::LodCache,
    model: &Model,
    source: &[u8; 32],
    travel: Travel,
    options: ImpostorOptions,
) -> Result<(AnimatedImpostor, crate::bake::cache::Origin)> {
    let build = || {
        let start = web_time::Instant::now();
        let impostor = bake_animated_impostor(raster, model, travel, options)?;
        let e = impostor.error;
        log::info!(
            "{}: impostor {} (asked {options}) baked in {:.2} s: {} frames, {:.1} MB of pages; error {:.0} mm (view {:.0} mm at {:.1}° over a depth of {:.0} mm, frames {:.0} mm, texel {:.0} mm)",
            model.name,
            impostor.options,
            start.elapsed().as_secs_f64(),
            impostor.frames,
            impostor.texture_bytes() as f64 / 1e6,
            e.total() * 1e3,
            e.view * 1e3,
            e.view_angle,
            e.depth * 1e3,
            e.frame * 1e3,
            e.texel * 1e3,
        );
        Ok(impostor)
    };
    if source == &[0; 32] {
        return Ok((
            build()?,
            crate::bake::cache::Origin::Baked { warning: None },
        ));
    }
    let key = impostor_key(source, &options);
    let path = cache.file(
        &model.name,
        crate::bake::cache::keys::CacheKind::Impostor,
        &key,
    );
    cache.load_or_build(&path, &key, build)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_parse_check_and_print() {
        let o: ImpostorOptions = "8x12x32".parse().unwrap();
        assert_eq!((o.views, o.frames, o.cell), (8, 12, 32));
        assert_eq!(o.to_string(), "8x12x32");
        assert_eq!(
            ImpostorOptions::default().to_string().parse(),
            Ok(ImpostorOptions::default())
        );
        assert!("8x12".parse::<ImpostorOptions>().is_err());
        assert!("1x12x32".parse::<ImpostorOptions>().is_err());
        assert!("8x12x3".parse::<ImpostorOptions>().is_err());
        assert!("16x12x256".parse::<ImpostorOptions>().is_err());
        // Pages lie in as square a sheet as fits, or not at all.
        assert_eq!(sheet_layout(24, 256), Ok((5, 5)));
        assert_eq!(sheet_layout(1, 256), Ok((1, 1)));
        assert_eq!(sheet_layout(64, 256), Ok((8, 8)));
        assert!(sheet_layout(65, 256).is_err());
        assert!("8xtwelvex32".parse::<ImpostorOptions>().is_err());
        // Two pages of 256² texels a frame, 12 frames, 2 clips, with mipmaps.
        assert_eq!(o.bytes(2), 2 * 12 * 2 * 256 * 256 * 4 * 4 / 3);
    }

    #[test]
    fn each_views_rectangle_holds_what_any_frame_covers_there() {
        // Two views a side of 4-texel cells, two pages side by side: view (1, 0) is covered
        // at texel (1, 1) on page 0 and (2, 3) on page 1; nothing else is covered.
        let options = ImpostorOptions {
            views: 2,
            frames: 2,
            cell: 4,
        };
        let mut sheet = Rgba8Image {
            width: 16,
            height: 8,
            pixels: vec![0; 16 * 8 * 4],
        };
        for (x, y) in [(4 + 1, 1), (8 + 4 + 2, 3)] {
            sheet.pixels[4 * (y * 16 + x) + 3] = 255;
        }
        let rects = covered_rects(&sheet, &options, 2, 2);
        assert_eq!(rects.len(), 4);
        // Texels 1..3 across and 1..4 down, a texel wider all round, within the cell.
        assert_eq!(rects[1], [0.0, 0.0, 1.0, 1.0]);
        let only_one = ImpostorOptions { cell: 8, ..options };
        let mut big = Rgba8Image {
            width: 32,
            height: 16,
            pixels: vec![0; 32 * 16 * 4],
        };
        big.pixels[4 * (3 * 32 + 8 + 4) + 3] = 255;
        let rects = covered_rects(&big, &only_one, 1, 2);
        assert_eq!(rects[1], [3.0 / 8.0, 2.0 / 8.0, 6.0 / 8.0, 5.0 / 8.0]);
        // An empty view gets an empty quad.
        assert_eq!(rects[0], [0.5; 4]);
    }

    #[test]
    fn the_nearest_view_is_near() {
        for views in [4, 8, 12] {
            let grid = ViewGrid {
                frames: views,
                cell: 8,
            };
            let worst = worst_view_angle(&grid);
            // The grid's spacing at the horizon is 360° over 4 (views − 1) views; between
            // views, up to twice that where the map stretches the cells.
            let spacing = 360.0 / (4 * (views - 1)) as f32;
            assert!(
                worst > 1.2 * spacing && worst < 2.0 * spacing,
                "{views}: {worst}°"
            );
            // Every grid direction is its own nearest view.
            for (i, j) in [(0, 0), (views - 1, 0), (views / 2, views / 2)] {
                assert_eq!(nearest_view(&grid, grid.direction(i, j)), (i, j));
            }
        }
    }

    /// A walker with `n` clips: its own, again and again, of growing durations.
    fn many_clips(n: usize) -> Model {
        let mut m = crate::import::load_model("walker").unwrap();
        let first = m.clips[0].clone();
        m.clips = (0..n)
            .map(|k| crate::model::Clip {
                name: format!("clip{k}"),
                duration: first.duration * (1.0 + 0.25 * k as f32),
                ..first.clone()
            })
            .collect();
        m
    }

    #[test]
    fn many_clips_share_one_sheet_by_duration() {
        let options = ImpostorOptions::default();
        let most = (SHEET_SIZE / options.page_side()).pow(2);
        // Few clips: every one gets the frames asked for.
        let walker = crate::import::load_model("walker").unwrap();
        let n = walker.clips.len();
        assert_eq!(clip_frames(&walker, &options), Ok(vec![options.frames; n]));
        for clips in [11, 22] {
            let m = many_clips(clips);
            let counts = clip_frames(&m, &options).unwrap();
            assert_eq!(counts.len(), clips);
            let pages: u32 = counts.iter().sum();
            assert!(pages <= most && pages + 2 > most, "{counts:?} in {most}");
            assert!(counts.iter().all(|&c| (2..=options.frames).contains(&c)));
            // Longer clips never get fewer frames.
            assert!(counts.windows(2).all(|w| w[0] <= w[1]), "{counts:?}");
            assert!(sheet_layout(pages, options.page_side()).is_ok());
            // The impostor's own animation texture samples them so, page for page.
            let anim = AnimationTexture::bake_frames_each(&m, &counts);
            let frames: Vec<u32> = anim.clips.iter().map(|c| c.frame_count).collect();
            assert_eq!(frames, counts);
            assert_eq!(page_times(&m, &counts).len() as u32, pages);
        }
        // More clips than two frames each can hold: said in one line.
        let e = clip_frames(&many_clips(30), &options).unwrap_err();
        assert!(e.contains("30 clips") && e.contains("--impostors"), "{e}");
    }

    #[test]
    fn pages_follow_the_animation_textures_frames() {
        let walker = crate::import::load_model("walker").unwrap();
        let times = page_times(&walker, &[5]);
        let anim = AnimationTexture::bake_frames(&walker, 5);
        // Frame 0 of the texture is the rest pose; page pair p shows texture frame p + 1.
        let frames: u32 = anim.clips.iter().map(|c| c.frame_count).sum();
        assert_eq!(times.len() as u32, frames);
        for (c, clip) in anim.clips.iter().enumerate() {
            assert_eq!(clip.frame_count, 5);
            let first = (clip.first_frame - 1) as usize;
            assert_eq!(times[first].0.unwrap().name, walker.clips[c].name);
            assert_eq!(times[first].1, 0.0);
            let last = times[first + 4].1;
            assert!((last - walker.clips[c].duration).abs() < 1e-5);
        }
    }
}

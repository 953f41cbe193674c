//! Forest patches: hierarchical levels of detail for far trees. Beyond where a tree's own
//! octahedral impostor comes in (the last level of its chain, see
//! [`crate::bake::foliage::billboard::chain::impostor`]), the trees of one cell of the forest's
//! layout share one impostor card, as Unreal's HLOD and Nanite's assemblies merge far
//! neighbours: one quad and one texture fetch per pixel instead of a card per tree, and no
//! overlap between neighbouring trees' cards.
//!
//! - [`cells`] cuts a layout into square cells of about [`CELL_TREES`]² trees.
//! - [`compose`] makes a cell's views from its trees' impostor views, on the CPU: for every
//!   view of the patch's grid, each tree shows the blend of the three views of its own grid
//!   nearest the direction it is seen from (turned by its heading), placed and scaled where
//!   it stands, tinted as it is drawn, and the trees are laid over each other nearest first.
//!   The views keep, per texel, the nearest tree's normal and its height towards the eye, so
//!   the impostor shader's parallax works across the cell as it does across one tree.
//! - The card is skinned like the cell's commonest tree ([`octahedral::impostor_model`]): it
//!   sways with the mean wind of the cell's trees, one bending card.
//! - [`place`] puts the patches where they are no worse than what the trees' chains draw
//!   there: at each size from where the trees' impostors come in, halving, a sample cell's
//!   patch is measured against its full trees (the colour metric of the thesis of
//!   Bennett-Therkildsen, Carlsen & Schmid, §5.1.3) beside the trees' own impostors against
//!   each tree, and the patches come in at the first size where the patch is no worse.

use crate::bake::foliage::billboard::chain::levels::CloudLevel;
use crate::bake::gpu_products::{MeasureColour, ViewImages};
use crate::bake::impostor::octahedral::{
    self, ImpostorFrame, ROWS, ViewGrid, encode_height, finish_views,
};
use crate::model::{
    Bounds, Influence, Model, Node, Rgba8Image, Skeleton, SkinnedMesh, Trs, linear_to_srgb,
    srgb_to_linear,
};
use anyhow::{Result, anyhow};
use glam::{Affine3A, Mat4, Vec2, Vec3, Vec4};
use serde::{Deserialize, Serialize};

/// Trees on a side of a layout cell: a patch stands for about this many squared.
pub const CELL_TREES: f32 = 4.0;
/// The patches' view grid: as many views as a tree's impostor (a cell is wider than a tree,
/// so its views differ more from one to the next, and fewer would show it doubled), at a
/// quarter of the texels a view (a patch comes in where its trees are a few pixels high).
pub const PATCH_GRID: ViewGrid = ViewGrid {
    frames: octahedral::FRAMES,
    cell: 64,
};
/// The sizes [`place`] tries, from where the trees' impostors come in: each half the last.
pub const PLACEMENT_STEPS: usize = 4;

/// One tree of a forest as its patch sees it: which of the forest's models it is and the
/// instance that stands it in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchTree {
    pub model: usize,
    /// Model space to the world: turned about +y, scaled, placed on the ground.
    pub transform: Affine3A,
    pub tint: Vec4,
    pub wind: f32,
    pub time_offset: f32,
    pub speed: f32,
}

/// A tree model's impostor as patches compose it: its frame and its finished views (colour,
/// normals with the height towards the eye in alpha).
#[derive(Clone, Copy, Debug)]
pub struct TreeViews<'a> {
    pub frame: &'a ImpostorFrame,
    pub colour: &'a Rgba8Image,
    pub normal: &'a Rgba8Image,
}

impl<'a> TreeViews<'a> {
    /// The views of a tree's impostor level (None for any other level).
    pub fn of(level: &'a CloudLevel) -> Option<TreeViews<'a>> {
        let frame = level.impostor.as_ref()?;
        let colour = level.model.materials.first()?.texture.as_ref()?;
        let normal = level.model.materials.get(1)?.texture.as_ref()?;
        Some(TreeViews {
            frame,
            colour,
            normal,
        })
    }

    fn cell(&self) -> u32 {
        (self.colour.width / self.frame.frames.max(1)).max(1)
    }
}

/// A forest patch: the card that stands for the trees `members` (indices into the layout's
/// trees) and how it is drawn.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ForestPatch {
    pub members: Vec<u32>,
    /// Where the card's model space stands in the world (the cell's trees' mean position on
    /// the ground); it is neither turned nor scaled.
    pub origin: [f32; 3],
    /// The card: an impostor level (its model, frame and texture bytes).
    pub level: CloudLevel,
    /// The instance's wind (the mean of its trees'), clip time offset and speed (its first
    /// tree's: the card sways as one).
    pub wind: f32,
    pub time_offset: f32,
    pub speed: f32,
    /// The mean height of its trees, scene units: the size selection projects.
    pub tree_height: f32,
}

/// The sizes a patch was measured at and what was found.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchMeasure {
    /// The trees' height in pixels.
    pub px: f32,
    /// The colour error of the patch against the cell's full trees, and of the trees'
    /// impostors (what their chains draw there) against each tree, weighted by count.
    pub patch: f32,
    pub trees: f32,
}

/// A layout's patches and where they come in.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ForestPatches {
    pub patches: Vec<ForestPatch>,
    /// The trees' height in pixels below which a patch is drawn (None: the patches never
    /// beat the trees' impostors, and are not drawn), at `tolerance_px`.
    pub switch_px: Option<f32>,
    pub tolerance_px: f32,
    /// The cells measured and their figures, size by size.
    pub measured: Vec<(u32, Vec<PatchMeasure>)>,
}

impl ForestPatches {
    /// The error, in scene units of a tree `height` high, that selection projects for a
    /// patch: the patch is drawn where it projects within the tolerance, as any level is.
    pub fn epsilon(&self, height: f32) -> Option<f32> {
        self.switch_px
            .map(|px| self.tolerance_px * height / px.max(1e-3))
    }
}

/// The layout's trees in square cells `side` wide (on the ground, from the layout's corner),
/// each cell's trees in layout order; cells of one tree are left out (its own impostor is as
/// cheap).
pub fn cells(trees: &[PatchTree], side: f32) -> Vec<Vec<usize>> {
    let at = |t: &PatchTree| {
        let p = t.transform.translation;
        Vec2::new(p.x, p.z)
    };
    let Some(min) = trees.iter().map(at).reduce(Vec2::min) else {
        return Vec::new();
    };
    let side = side.max(1e-3);
    let mut by_cell: std::collections::BTreeMap<(i64, i64), Vec<usize>> = Default::default();
    for (i, t) in trees.iter().enumerate() {
        let c = ((at(t) - min) / side).floor();
        by_cell.entry((c.y as i64, c.x as i64)).or_default().push(i);
    }
    by_cell.into_values().filter(|m| m.len() > 1).collect()
}

/// A member tree as the composition places it: its instance relative to the patch's origin,
/// its impostor's views and sphere there.
struct Placed<'a> {
    views: TreeViews<'a>,
    to_patch: Affine3A,
    /// Its turn alone (heading), patch to model space, for directions.
    to_model: glam::Mat3A,
    centre: Vec3,
    radius: f32,
    tint: Vec3,
}

/// The card of the trees `members` of `trees`: their views composed from `views` (per
/// model; every member's model must have one), skinned like `rep` (at rest, see
/// [`octahedral::at_rest`]), on `grid`.
pub fn compose(
    trees: &[PatchTree],
    members: &[usize],
    views: &[Option<TreeViews>],
    rep: &Model,
    grid: ViewGrid,
) -> Result<ForestPatch> {
    if members.is_empty() {
        return Err(anyhow!("a forest patch needs trees"));
    }
    let n = members.len() as f32;
    let mean = members
        .iter()
        .map(|&i| Vec3::from(trees[i].transform.translation))
        .sum::<Vec3>()
        / n;
    let origin = Vec3::new(mean.x, 0.0, mean.z);
    let mut placed = Vec::with_capacity(members.len());
    let mut bounds: Option<Bounds> = None;
    for &i in members {
        let t = &trees[i];
        let v =
            views.get(t.model).copied().flatten().ok_or_else(|| {
                anyhow!("tree model {} has no impostor to make a patch of", t.model)
            })?;
        let to_patch = Affine3A::from_translation(-origin) * t.transform;
        let scale = to_patch.matrix3.x_axis.length().max(1e-6);
        let corners = corner_points(v.frame.bounds).map(|p| to_patch.transform_point3(p));
        bounds = Bounds::of(
            corners
                .into_iter()
                .chain(bounds.iter().flat_map(|b| [b.min, b.max])),
        );
        placed.push(Placed {
            views: v,
            to_patch,
            to_model: (to_patch.matrix3 / scale).transpose(),
            centre: to_patch.transform_point3(Vec3::from(v.frame.centre)),
            radius: v.frame.radius * scale,
            tint: t.tint.truncate(),
        });
    }
    let bounds = bounds.expect("members");
    let (centre, radius) = enclosing(&placed);
    let frame = ImpostorFrame {
        frames: grid.frames,
        centre: centre.to_array(),
        radius,
        base: bounds.min.y,
        height: bounds.size().y.max(1e-4),
        rows: ROWS,
        bounds: [bounds.min.to_array(), bounds.max.to_array()],
    };
    let mut images = compose_views(&placed, centre, radius, grid);
    finish_views(&mut images, grid.cell);
    let model = octahedral::impostor_model(rep, &frame, images);
    let first = &trees[members[0]];
    Ok(ForestPatch {
        members: members.iter().map(|&i| i as u32).collect(),
        origin: origin.to_array(),
        level: CloudLevel::impostor(model, frame, members.len()),
        wind: members.iter().map(|&i| trees[i].wind).sum::<f32>() / n,
        time_offset: first.time_offset,
        speed: first.speed,
        tree_height: placed
            .iter()
            .map(|p| p.views.frame.height * p.to_patch.matrix3.y_axis.length())
            .sum::<f32>()
            / n,
    })
}

fn corner_points(b: [[f32; 3]; 2]) -> [Vec3; 8] {
    std::array::from_fn(|k| Vec3::new(b[k & 1][0], b[(k >> 1) & 1][1], b[(k >> 2) & 1][2]))
}

/// The sphere round every member's view sphere: about the middle of their bounds, through
/// the farthest, with the margin [`octahedral::view_sphere`] leaves.
fn enclosing(placed: &[Placed]) -> (Vec3, f32) {
    let lo = placed
        .iter()
        .map(|p| p.centre - Vec3::splat(p.radius))
        .reduce(Vec3::min)
        .unwrap_or(Vec3::ZERO);
    let hi = placed
        .iter()
        .map(|p| p.centre + Vec3::splat(p.radius))
        .reduce(Vec3::max)
        .unwrap_or(Vec3::ZERO);
    let centre = (lo + hi) * 0.5;
    let reach = placed
        .iter()
        .map(|p| p.centre.distance(centre) + p.radius)
        .fold(0.0f32, f32::max);
    (centre, (reach * 1.02).max(1e-4))
}

/// One texel of composition: premultiplied linear colour and coverage, laid over nearest
/// first, and the nearest covering tree's normal and height.
#[derive(Clone, Copy, Default)]
struct Texel {
    colour: Vec4,
    normal: Option<(Vec3, f32)>,
}

/// The patch's views: every view of `grid` on the sphere (`centre`, `radius`), each tree
/// drawn from its own views (see the module comment).
fn compose_views(placed: &[Placed], centre: Vec3, radius: f32, grid: ViewGrid) -> ViewImages {
    let size = grid.atlas_size();
    let cell = grid.cell as usize;
    let mut colour = vec![0u8; (size * size * 4) as usize];
    let mut normal = vec![0u8; (size * size * 4) as usize];
    let mut texels = vec![Texel::default(); cell * cell];
    for j in 0..grid.frames {
        for i in 0..grid.frames {
            let d = grid.direction(i, j);
            let (right, up) = ViewGrid::view_axes(d);
            texels.fill(Texel::default());
            // Nearest the eye first.
            let mut order: Vec<&Placed> = placed.iter().collect();
            order.sort_by(|a, b| {
                (b.centre - centre)
                    .dot(d)
                    .total_cmp(&(a.centre - centre).dot(d))
            });
            for p in order {
                lay_tree(p, &mut texels, grid.cell, [d, right, up], centre, radius);
            }
            for y in 0..cell {
                for x in 0..cell {
                    let t = texels[y * cell + x];
                    let at = 4 * ((j as usize * cell + y) * size as usize + i as usize * cell + x);
                    let a = t.colour.w.clamp(0.0, 1.0);
                    let rgb = t.colour.truncate() / a.max(1e-6);
                    colour[at..at + 4].copy_from_slice(&[
                        linear_to_srgb(rgb.x),
                        linear_to_srgb(rgb.y),
                        linear_to_srgb(rgb.z),
                        (a * 255.0).round() as u8,
                    ]);
                    let (n, h) = t.normal.unwrap_or((d, 0.0));
                    let e = n * 0.5 + Vec3::splat(0.5);
                    normal[at..at + 4].copy_from_slice(&[
                        linear_to_srgb(e.x),
                        linear_to_srgb(e.y),
                        linear_to_srgb(e.z),
                        encode_height(h),
                    ]);
                }
            }
        }
    }
    let image = |pixels| Rgba8Image {
        width: size,
        height: size,
        pixels,
    };
    ViewImages {
        colour: image(colour),
        normal: image(normal),
    }
}

/// Lays tree `p` under what `texels` (one view's cell, `cell` texels a side, looking along
/// `axes` = [towards the eye, right, up] at the sphere (`centre`, `radius`)) already holds.
fn lay_tree(
    p: &Placed,
    texels: &mut [Texel],
    cell: u32,
    axes: [Vec3; 3],
    centre: Vec3,
    radius: f32,
) {
    let [d, right, up] = axes;
    let c = cell as f32;
    // The tree's own three views of the direction it is seen from, their axes in the patch.
    let own = ViewGrid {
        frames: p.views.frame.frames,
        cell: p.views.cell(),
    };
    let seen = (p.to_model * glam::Vec3A::from(d)).normalize_or_zero();
    let views: Vec<((u32, u32), f32, Vec3, Vec3)> = own
        .blend(Vec3::from(seen))
        .into_iter()
        .filter(|&(_, w)| w > 1e-4)
        .map(|((a, b), w)| {
            let (r, u) = ViewGrid::view_axes(own.direction(a, b));
            let to_patch = p.to_model.transpose();
            (
                (a, b),
                w,
                Vec3::from(to_patch * glam::Vec3A::from(r)),
                Vec3::from(to_patch * glam::Vec3A::from(u)),
            )
        })
        .collect();
    // The tree's square in this view's cell.
    let o = p.centre - centre;
    let (uc, vc, half) = (o.dot(right) / radius, o.dot(up) / radius, p.radius / radius);
    let x0 = (((0.5 + 0.5 * (uc - half)) * c).floor().max(0.0)) as usize;
    let x1 = (((0.5 + 0.5 * (uc + half)) * c).ceil().min(c)) as usize;
    let y0 = (((0.5 - 0.5 * (vc + half)) * c).floor().max(0.0)) as usize;
    let y1 = (((0.5 - 0.5 * (vc - half)) * c).ceil().min(c)) as usize;
    let depth = o.dot(d);
    let from_model = p.to_model.transpose();
    for y in y0..y1 {
        for x in x0..x1 {
            let u = (x as f32 + 0.5) / c * 2.0 - 1.0;
            let v = 1.0 - (y as f32 + 0.5) / c * 2.0;
            // The patch pixel's line of sight where it crosses the tree's middle plane (the
            // plane through its centre facing the eye), from the tree's centre.
            let q = (right * u + up * v) * radius - (o - d * depth);
            let st_of = |r: Vec3, up_k: Vec3| {
                Vec2::new(
                    0.5 + 0.5 * q.dot(r) / p.radius,
                    0.5 - 0.5 * q.dot(up_k) / p.radius,
                )
            };
            // As the impostor shader does: the height of the surface under the pixel from the
            // heaviest view, then every view read where that surface point falls in it.
            let &(heaviest, _, r0, u0) = views
                .iter()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .expect("a blend has a view");
            let probe = sample_view(&p.views, own.cell, heaviest, st_of(r0, u0)).1.w;
            let mut sample = Vec4::ZERO;
            let mut n = Vec3::ZERO;
            let mut h = 0.0;
            for &((a, b), w, r, up_k) in &views {
                let st = st_of(r, up_k) + probe * 0.5 * Vec2::new(d.dot(r), -d.dot(up_k));
                let (col, nor) = sample_view(&p.views, own.cell, (a, b), st);
                sample += col * w;
                n += nor.truncate() * w;
                h += nor.w * w;
            }
            if sample.w <= 1e-4 {
                continue;
            }
            let tinted = (sample.truncate() * p.tint).extend(sample.w);
            let t = &mut texels[y * cell as usize + x];
            t.colour += tinted * (1.0 - t.colour.w);
            if t.normal.is_none() && sample.w >= 0.5 {
                let n = Vec3::from(from_model * glam::Vec3A::from(n)).normalize_or(d);
                t.normal = Some((n, (depth + h * p.radius) / radius));
            }
        }
    }
}

/// Tree view `view`'s texels at `st` (0..1 over its cell), bilinear within the cell: the
/// colour premultiplied in linear light with its coverage, and the model-space normal with
/// the height towards the eye (in the tree's radii).
fn sample_view(v: &TreeViews, cell: u32, view: (u32, u32), st: Vec2) -> (Vec4, Vec4) {
    if !(0.0..=1.0).contains(&st.x) || !(0.0..=1.0).contains(&st.y) {
        return (Vec4::ZERO, Vec4::ZERO);
    }
    let c = cell as f32;
    let p = st * c - Vec2::splat(0.5);
    let base = p.floor();
    let f = p - base;
    let (mut col, mut nor) = (Vec4::ZERO, Vec4::ZERO);
    let width = v.colour.width as usize;
    for (dx, dy, w) in [
        (0, 0, (1.0 - f.x) * (1.0 - f.y)),
        (1, 0, f.x * (1.0 - f.y)),
        (0, 1, (1.0 - f.x) * f.y),
        (1, 1, f.x * f.y),
    ] {
        let x = (base.x as i64 + dx).clamp(0, cell as i64 - 1) as usize + (view.0 * cell) as usize;
        let y = (base.y as i64 + dy).clamp(0, cell as i64 - 1) as usize + (view.1 * cell) as usize;
        let at = 4 * (y * width + x);
        let (cp, np) = (&v.colour.pixels[at..at + 4], &v.normal.pixels[at..at + 4]);
        let a = cp[3] as f32 / 255.0;
        col += Vec4::new(
            srgb_to_linear(cp[0]) * a,
            srgb_to_linear(cp[1]) * a,
            srgb_to_linear(cp[2]) * a,
            a,
        ) * w;
        let n = Vec3::new(
            srgb_to_linear(np[0]),
            srgb_to_linear(np[1]),
            srgb_to_linear(np[2]),
        ) * 2.0
            - Vec3::ONE;
        nor += n.extend(decode_height(np[3])) * w;
    }
    (col, nor)
}

/// The inverse of [`encode_height`].
fn decode_height(b: u8) -> f32 {
    ((b as f32 - 128.0) / 127.0 - 0.5) * 2.0
}

/// The full trees `members` of `trees` as one still model, about the patch's `origin`: each
/// tree at rest (`at_rest[model]`) where it stands, one bone that never moves. What a patch
/// is measured against.
pub fn cell_model(
    name: &str,
    trees: &[PatchTree],
    members: &[usize],
    at_rest: &[&Model],
    origin: Vec3,
) -> Model {
    let mut mesh = SkinnedMesh::default();
    let mut materials = Vec::new();
    let mut first_material = vec![None; at_rest.len()];
    for &i in members {
        let t = &trees[i];
        let m = at_rest[t.model];
        let offset = *first_material[t.model].get_or_insert_with(|| {
            let at = materials.len();
            materials.extend(m.materials.iter().cloned());
            at
        });
        let to_patch = Affine3A::from_translation(-origin) * t.transform;
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(
            m.mesh
                .positions
                .iter()
                .map(|&p| to_patch.transform_point3(p)),
        );
        mesh.normals.extend(
            m.mesh
                .normals
                .iter()
                .map(|&n| to_patch.transform_vector3(n).normalize_or(n)),
        );
        mesh.uvs.extend_from_slice(&m.mesh.uvs);
        mesh.materials
            .extend(m.mesh.materials.iter().map(|&k| k + offset as u16));
        mesh.indices
            .extend(m.mesh.indices.iter().map(|&k| k + base));
    }
    let vertices = mesh.positions.len();
    mesh.influence_offsets = (0..=vertices as u32).collect();
    mesh.influences = vec![
        Influence {
            bone: 0,
            weight: 1.0,
        };
        vertices
    ];
    Model {
        name: name.to_string(),
        mesh,
        skeleton: Skeleton {
            nodes: vec![Node {
                name: "cell".into(),
                parent: None,
                rest: Trs::IDENTITY,
            }],
            joints: vec![0],
            inverse_bind: vec![Mat4::IDENTITY],
            root_transform: Affine3A::IDENTITY,
        },
        clips: Vec::new(),
        materials,
    }
}

/// What [`place`] measures a sample cell with: the cell's full trees as one model, and per
/// member model its full tree and its impostor level.
pub struct PlacementInputs<'a> {
    pub cell: &'a Model,
    /// Per model of the layout: the tree and its impostor level (None for models the cell
    /// lacks).
    pub impostors: Vec<Option<(&'a Model, &'a CloudLevel)>>,
}

/// The colour error, at trees `px` pixels high, of `patch` against its cell's full trees, and
/// of the members' impostors against their trees (a mean over the members).
pub fn errors_at(
    measure: &dyn MeasureColour,
    patch: &ForestPatch,
    trees: &[PatchTree],
    inputs: &PlacementInputs,
    px: f32,
) -> Result<PatchMeasure> {
    // The metric frames a model by its height or its span across, whichever is larger: the
    // cell's trees stand `px` high where the cell is drawn this much larger.
    let b = Bounds::of(inputs.cell.mesh.positions.iter().copied())
        .ok_or_else(|| anyhow!("{}: no trees", inputs.cell.name))?;
    let framed = b.size().y.max(Vec2::new(b.size().x, b.size().z).length());
    let cell_px = px * framed / patch.tree_height.max(1e-3);
    let bake = patch
        .level
        .bake()
        .map_err(|e| anyhow!("{}: {e}", patch.level.model.name))?;
    let own = measure.colour_errors(inputs.cell, &patch.level.model, bake, &[cell_px])?[0];
    // Each model once, weighted by its trees in the cell.
    let mut count: std::collections::BTreeMap<usize, usize> = Default::default();
    for &m in &patch.members {
        *count.entry(trees[m as usize].model).or_default() += 1;
    }
    let mut sum = 0.0;
    for (&model, &n) in &count {
        let (tree, impostor) = inputs
            .impostors
            .get(model)
            .copied()
            .flatten()
            .ok_or_else(|| anyhow!("tree model {model} has no impostor"))?;
        let bake = impostor
            .bake()
            .map_err(|e| anyhow!("{}: {e}", impostor.model.name))?;
        sum += n as f32 * measure.colour_errors(tree, &impostor.model, bake, &[px])?[0];
    }
    Ok(PatchMeasure {
        px,
        patch: own,
        trees: sum / patch.members.len().max(1) as f32,
    })
}

/// Where the patches come in: the first of `PLACEMENT_STEPS` sizes from `from_px` (where the
/// trees' impostors are drawn), each half the last, at which `measure_at` finds the patch no
/// worse than the trees' impostors; None where it is worse at every one. Returns the size and
/// the figures.
pub fn place(
    from_px: f32,
    mut measure_at: impl FnMut(f32) -> Result<PatchMeasure>,
) -> Result<(Option<f32>, Vec<PatchMeasure>)> {
    let mut measured = Vec::new();
    let mut px = from_px;
    for _ in 0..PLACEMENT_STEPS {
        let m = measure_at(px)?;
        measured.push(m);
        if m.patch <= m.trees {
            return Ok((Some(px), measured));
        }
        px *= 0.5;
    }
    Ok((None, measured))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree_at(x: f32, z: f32, model: usize) -> PatchTree {
        PatchTree {
            model,
            transform: Affine3A::from_translation(Vec3::new(x, 0.0, z)),
            tint: Vec4::ONE,
            wind: 1.0,
            time_offset: 0.0,
            speed: 1.0,
        }
    }

    /// A tree impostor on a 2 × 2 grid (views along −x, +z, −z, +x) whose every view is a
    /// disc, red on its left half and green on its right, but for the view from −z, which
    /// sees the other side: red on its right.
    fn disc_views(cell: u32) -> (ImpostorFrame, Rgba8Image, Rgba8Image) {
        let side = 2 * cell;
        let mut colour = vec![0u8; (side * side * 4) as usize];
        let mut normal = vec![0u8; (side * side * 4) as usize];
        for y in 0..side {
            for x in 0..side {
                let st = Vec2::new(
                    ((x % cell) as f32 + 0.5) / cell as f32,
                    ((y % cell) as f32 + 0.5) / cell as f32,
                );
                let at = 4 * (y * side + x) as usize;
                let inside = st.distance(Vec2::splat(0.5)) < 0.45;
                // The view from −z, view (0, 1), has its red on the right: it sees the tree's
                // back.
                let back = x / cell == 0 && y / cell == 1;
                let c = if (st.x < 0.5) != back {
                    [255, 0, 0]
                } else {
                    [0, 255, 0]
                };
                colour[at..at + 4].copy_from_slice(&[
                    c[0],
                    c[1],
                    c[2],
                    if inside { 255 } else { 0 },
                ]);
                normal[at..at + 4].copy_from_slice(&[188, 188, 255, encode_height(0.0)]);
            }
        }
        let frame = ImpostorFrame {
            frames: 2,
            centre: [0.0, 1.0, 0.0],
            radius: 1.0,
            base: 0.0,
            height: 2.0,
            rows: ROWS,
            bounds: [[-1.0, 0.0, -1.0], [1.0, 2.0, 1.0]],
        };
        let image = |pixels| Rgba8Image {
            width: side,
            height: side,
            pixels,
        };
        (frame, image(colour), image(normal))
    }

    /// Two trees 6 m apart, the second turned half round: seen from +z, each stands where it
    /// is, with a gap between them. The first shows its +z view; the turned one its own −z
    /// view (its back), whose right is its −x, which its turn brings round to the world's
    /// +x: red on the right.
    #[test]
    fn a_patch_view_places_and_turns_each_tree() {
        let (frame, colour, normal) = disc_views(16);
        let views = [Some(TreeViews {
            frame: &frame,
            colour: &colour,
            normal: &normal,
        })];
        let mut trees = vec![tree_at(-3.0, 0.0, 0), tree_at(3.0, 0.0, 0)];
        trees[1].transform = Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_y(std::f32::consts::PI),
            Vec3::new(3.0, 0.0, 0.0),
        );
        let rep = crate::generate::tree::sapling();
        let grid = ViewGrid {
            frames: 2,
            cell: 32,
        };
        let patch = compose(&trees, &[0, 1], &views, &rep, grid).unwrap();
        assert_eq!(patch.origin, [0.0, 0.0, 0.0]);
        let frame = patch.level.impostor.unwrap();
        assert!((frame.radius - 4.0 * 1.02).abs() < 1e-3, "{}", frame.radius);
        let img = patch.level.model.materials[0].texture.as_ref().unwrap();
        // View (1, 0) looks along +z: its cell is the grid's second column, first row.
        assert!((grid.direction(1, 0) - Vec3::Z).length() < 1e-5);
        let texel = |x: u32, y: u32| {
            let at = 4 * ((y * img.width) + 32 + x) as usize;
            [
                img.pixels[at],
                img.pixels[at + 1],
                img.pixels[at + 2],
                img.pixels[at + 3],
            ]
        };
        // Tree centres at x = (0.5 ± 0.5 · 3 / 4.08) · 32 = 4.2 and 27.8; the middle row is
        // the trees' centre height, the patch's too.
        let y = 16;
        for (x, red) in [(2, true), (6, false), (26, false), (30, true)] {
            let t = texel(x, y);
            assert!(t[3] > 128, "texel {x} is covered: {t:?}");
            assert_eq!(t[0] > t[1], red, "texel {x}: {t:?}");
        }
        assert_eq!(texel(16, y)[3], 0, "the gap between the trees is empty");
        assert!(patch.tree_height > 1.9 && patch.tree_height < 2.1);
    }

    #[test]
    fn cells_group_neighbours_and_leave_lone_trees_out() {
        let trees: Vec<PatchTree> = (0..10)
            .map(|i| tree_at((i % 5) as f32 * 2.0, (i / 5) as f32 * 2.0, 0))
            .chain([tree_at(100.0, 100.0, 0)])
            .collect();
        let c = cells(&trees, 4.0);
        // Columns 0-1, 2-3 and 4 of two rows: three cells; the lone tree far off none.
        assert_eq!(c.len(), 3, "{c:?}");
        let all: Vec<usize> = c.iter().flatten().copied().collect();
        assert_eq!(all.len(), 10);
        assert!(!all.contains(&10));
        for cell in &c {
            let xs: Vec<f32> = cell
                .iter()
                .map(|&i| trees[i].transform.translation.x)
                .collect();
            let spread = xs.iter().cloned().fold(f32::MIN, f32::max)
                - xs.iter().cloned().fold(f32::MAX, f32::min);
            assert!(spread < 4.0, "{xs:?}");
        }
    }

    #[test]
    fn heights_decode_as_they_were_encoded() {
        for h in [-1.0f32, -0.4, 0.0, 0.3, 1.0] {
            assert!((decode_height(encode_height(h)) - h).abs() < 0.02, "{h}");
        }
    }

    #[test]
    fn placement_takes_the_first_size_where_the_patch_is_no_worse() {
        let (px, m) = place(40.0, |px| {
            Ok(PatchMeasure {
                px,
                patch: 0.5 - 0.01 * (40.0 - px),
                trees: 0.3,
            })
        })
        .unwrap();
        // 40: 0.5 > 0.3; 20: 0.3 <= 0.3.
        assert_eq!(px, Some(20.0));
        assert_eq!(m.len(), 2);
        let (never, m) = place(40.0, |px| {
            Ok(PatchMeasure {
                px,
                patch: 0.9,
                trees: 0.3,
            })
        })
        .unwrap();
        assert_eq!((never, m.len()), (None, PLACEMENT_STEPS));
    }
}

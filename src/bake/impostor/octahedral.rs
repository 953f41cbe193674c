//! The view sphere of an octahedral impostor: the far level of a tree after its coarsest
//! billboard cloud, one quad showing the tree as seen from the nearest of a grid of directions
//! over the upper hemisphere (the views are baked into the cells of an atlas).
//!
//! The directions are laid out by the hemi-octahedral map (as in Ryan Brucks' octahedral
//! impostors and Shopf's "Mixed resolution rendering"): a unit vector with y ≥ 0 goes to the
//! octahedron |x| + |y| + |z| = 1, whose upper half, seen from above and turned by 45°, is
//! the square [−1, 1]². A regular `frames` × `frames` grid on the square then spreads the
//! views evenly enough over the hemisphere, its edge is the horizon, and any direction falls in
//! one grid cell: the renderer blends the three views of the cell's triangle it falls in,
//! weighted by its barycentric coordinates, so that turning round a tree never pops.
//!
//! The bake ([`bake_impostor`]) draws the tree at rest from every view of the grid through the
//! atlas seam ([`RasterizeAtlas::rasterize_views`]), colour and normal, at twice the cell size,
//! and averages each 2×2 block down: the atlas keeps the coverage of thin twigs as a soft
//! alpha. The impostor's model is a quad of a few rows, each row skinned like the slab of the
//! tree at its height (the mean of that slab's influences), so the renderer sways the quad
//! with the tree's wind as one bending card. `shaders/impostor.wgsl` mirrors [`hemi_oct_encode`],
//! [`ViewGrid::blend`] and [`ViewGrid::view_axes`].

use crate::bake::gpu_data::materials::{MaterialLayers, dilate, preserve_coverage};
use crate::bake::gpu_products::{RasterizeAtlas, ViewCamera, ViewImages, ViewRequest, ViewVertex};
use crate::model::{
    Bounds, Influence, Material, Model, Rgba8Image, SkinnedMesh, linear_to_srgb, srgb_to_linear,
};
use anyhow::{Result, anyhow};
use glam::{Vec2, Vec3};

/// The point of the square [−1, 1]² where the hemi-octahedral map puts direction `d`
/// (y up; a direction below the horizon is taken as its mirror above it).
pub fn hemi_oct_encode(d: Vec3) -> Vec2 {
    let d = Vec3::new(d.x, d.y.abs(), d.z);
    let p = Vec2::new(d.x, d.z) / (d.x.abs() + d.y + d.z.abs()).max(1e-12);
    Vec2::new(p.x + p.y, p.x - p.y)
}

/// The unit direction at point `s` of the square [−1, 1]² (the inverse of [`hemi_oct_encode`]).
pub fn hemi_oct_decode(s: Vec2) -> Vec3 {
    let p = Vec2::new(s.x + s.y, s.x - s.y) * 0.5;
    let y = 1.0 - p.x.abs() - p.y.abs();
    Vec3::new(p.x, y.max(0.0), p.y).normalize()
}

/// The views of an impostor: a `frames` × `frames` grid over the hemi-octahedral square, each
/// view drawn into a `cell` × `cell` texel cell of the atlas, row by row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ViewGrid {
    pub frames: u32,
    pub cell: u32,
}

impl ViewGrid {
    /// The direction from the tree towards the eye of view (i, j): grid points at the square's
    /// corners and edges look along the horizon, the middle one straight down.
    pub fn direction(&self, i: u32, j: u32) -> Vec3 {
        let n = (self.frames.max(2) - 1) as f32;
        hemi_oct_decode(Vec2::new(i as f32, j as f32) / n * 2.0 - Vec2::ONE)
    }

    /// The three views whose blend shows direction `d` and their weights (summing to 1): the
    /// corners of the half of the grid cell `d` falls in, by barycentric coordinates.
    pub fn blend(&self, d: Vec3) -> [((u32, u32), f32); 3] {
        let n = (self.frames.max(2) - 1) as f32;
        let g = ((hemi_oct_encode(d) + Vec2::ONE) * 0.5 * n).clamp(Vec2::ZERO, Vec2::splat(n));
        let base = g.floor().min(Vec2::splat(n - 1.0));
        let f = g - base;
        let (i, j) = (base.x as u32, base.y as u32);
        // Split the cell along its diagonal from (0, 0) to (1, 1).
        if f.x >= f.y {
            [
                ((i, j), 1.0 - f.x),
                ((i + 1, j), f.x - f.y),
                ((i + 1, j + 1), f.y),
            ]
        } else {
            [
                ((i, j), 1.0 - f.y),
                ((i, j + 1), f.y - f.x),
                ((i + 1, j + 1), f.x),
            ]
        }
    }

    /// The side of the square atlas that holds every view.
    pub fn atlas_size(&self) -> u32 {
        self.frames * self.cell
    }

    /// An orthographic view's axes for eye direction `d`: right and up on the screen, both
    /// unit and perpendicular to `d`. Up follows the world's up where it can (so a tree stands
    /// upright in its side views) and the world's −z when looking straight down.
    pub fn view_axes(d: Vec3) -> (Vec3, Vec3) {
        let d = d.normalize();
        let reference = if d.y > 0.999 { Vec3::NEG_Z } else { Vec3::Y };
        let right = reference.cross(d).normalize();
        let up = d.cross(right);
        (right, up)
    }
}

/// Views on a side of the grid: 8 × 8 views put a view within 22° of any direction.
pub const FRAMES: u32 = 8;
/// Texels on a side of a view's cell. An impostor comes in where a tree is a few dozen
/// pixels high, so 128 texels keep about two texels a pixel there.
pub const CELL: u32 = 128;
/// The views are drawn this many times larger, then averaged down.
pub(crate) const SUPERSAMPLE: u32 = 2;
/// Rows of the impostor's quad: where it bends.
pub const ROWS: u32 = 4;
/// Texels of dilated colour round the tree in every view.
const DILATE_RINGS: u32 = 4;

pub use crate::bake::gpu_data::impostor_frames::ImpostorFrame;

/// The view bake's input for `tree` at rest seen from every view of `grid`, each drawn
/// `supersample` times larger than its cell; and the sphere the views are framed on.
pub fn view_request(tree: &Model, grid: ViewGrid, supersample: u32) -> Result<(ViewRequest, f32)> {
    let (centre, radius) = view_sphere(&tree.mesh.positions)
        .ok_or_else(|| anyhow!("{}: no vertices to draw an impostor of", tree.name))?;
    Ok((views_about(tree, grid, supersample, centre, radius), radius))
}

/// The sphere every view is framed on: round the bounds' centre of `points`, through the
/// farthest of them, with a little margin that keeps filtering off the neighbouring views.
pub fn view_sphere(points: &[Vec3]) -> Option<(Vec3, f32)> {
    let centre = Bounds::of(points.iter().copied())?.center();
    let reach = points
        .iter()
        .map(|p| p.distance(centre))
        .fold(0.0f32, f32::max);
    Some((centre, (reach * 1.04).max(1e-4)))
}

/// The view bake's input for `model` as it stands, seen from every view of `grid` on the
/// sphere (`centre`, `radius`), each drawn `supersample` times larger than its cell.
pub fn views_about(
    model: &Model,
    grid: ViewGrid,
    supersample: u32,
    centre: Vec3,
    radius: f32,
) -> ViewRequest {
    let (tree, mesh) = (model, &model.mesh);
    let cut_out: Vec<bool> = tree
        .materials
        .iter()
        .map(crate::bake::foliage::billboard::is_cut_out)
        .collect();
    let occlusion = crate::bake::foliage::billboard::occlusion::CrownDensity::of(model)
        .map(|c| c.occlusions(&mesh.positions))
        .unwrap_or_default();
    let vertices = mesh
        .indices
        .iter()
        .map(|&i| {
            let v = i as usize;
            let layer = mesh.materials[v] as usize;
            ViewVertex {
                position: mesh.positions[v].to_array(),
                layer: layer as u32,
                normal: mesh.normals[v].to_array(),
                cut_out: cut_out.get(layer).copied().unwrap_or(false) as u32,
                uv: mesh.uvs[v].to_array(),
                light: 1.0 - occlusion.get(v).copied().unwrap_or(0.0),
            }
        })
        .collect();
    let cell = (grid.cell * supersample) as f32;
    let mut views = Vec::with_capacity((grid.frames * grid.frames) as usize);
    for j in 0..grid.frames {
        for i in 0..grid.frames {
            let d = grid.direction(i, j);
            let (right, up) = ViewGrid::view_axes(d);
            let axis = |a: Vec3| (a / radius).extend(0.0).to_array();
            views.push(ViewCamera {
                cell: [i as f32 * cell, j as f32 * cell, cell, 0.0],
                right: axis(right),
                up: axis(up),
                toward: axis(d),
            });
        }
    }
    ViewRequest {
        size: grid.atlas_size() * supersample,
        centre,
        vertices,
        views,
    }
}

/// Averages each `factor` × `factor` block of drawn views into one texel: colour in linear
/// light over the covered texels, alpha the share covered, the normal the covered texels'
/// mean (renormalised), and their mean height. The normal comes out sRGB-encoded, so that the
/// renderer's sRGB material texture hands the shader n / 2 + 1/2 again.
pub fn average_down(images: &ViewImages, factor: u32) -> ViewImages {
    let (w, h) = (images.colour.width / factor, images.colour.height / factor);
    let lut: Vec<f32> = (0..=255u8).map(srgb_to_linear).collect();
    let mut colour = vec![0u8; (w * h * 4) as usize];
    let mut normal = vec![0u8; (w * h * 4) as usize];
    let sw = images.colour.width as usize;
    for y in 0..h as usize {
        for x in 0..w as usize {
            let (mut c, mut n, mut height, mut covered) = ([0.0f32; 3], Vec3::ZERO, 0u32, 0u32);
            for dy in 0..factor as usize {
                for dx in 0..factor as usize {
                    let i = 4 * ((y * factor as usize + dy) * sw + x * factor as usize + dx);
                    if images.colour.pixels[i + 3] < 128 {
                        continue;
                    }
                    covered += 1;
                    for k in 0..3 {
                        c[k] += lut[images.colour.pixels[i + k] as usize];
                    }
                    let q = &images.normal.pixels[i..i + 3];
                    n += Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) / 127.5 - Vec3::ONE;
                    height += images.normal.pixels[i + 3] as u32;
                }
            }
            if covered == 0 {
                continue;
            }
            let o = 4 * (y * w as usize + x);
            let alpha = (255 * covered).div_ceil(factor * factor) as u8;
            for k in 0..3 {
                colour[o + k] = linear_to_srgb(c[k] / covered as f32);
            }
            colour[o + 3] = alpha;
            let n = n.normalize_or(Vec3::Y) * 0.5 + Vec3::splat(0.5);
            normal[o..o + 3].copy_from_slice(&n.to_array().map(linear_to_srgb));
            normal[o + 3] = ((height + covered / 2) / covered) as u8;
        }
    }
    let image = |pixels| Rgba8Image {
        width: w,
        height: h,
        pixels,
    };
    ViewImages {
        colour: image(colour),
        normal: image(normal),
    }
}

/// The normal layer's alpha: a covered point's height `h` towards the eye above the plane
/// through the sphere's centre, as a share of the radius (−1 … 1), stored as
/// 128 + 127 · (h / 2 + 1/2). It never falls under the alpha test's cut-off, so the
/// material's mipmaps average it as plain data, and the renderer shifts each view's lookup by
/// it (parallax, `shaders/impostor.wgsl`). Mirrored by `fs_view` in `impostor_bake.wgsl`.
pub fn encode_height(h: f32) -> u8 {
    128 + (127.0 * (0.5 * h.clamp(-1.0, 1.0) + 0.5)).round() as u8
}

/// The impostor's quad as a model: `rows + 1` pairs of vertices up the tree's height, a crown's
/// width apart, each pair skinned with the mean influences of the tree's vertices round its
/// height (their four heaviest bones), so that row by row the quad follows how that slab of the
/// tree sways. Layer 0 of its materials is the views' colour, layer 1 their normals.
///
/// `tree` and `frame` are at rest ([`at_rest`]); each row vertex is stored where the rest
/// pose's skinning takes it to its place on the quad, so the renderer's skinned rows stand
/// there at rest and move from there with the wind.
pub fn impostor_model(tree: &Model, frame: &ImpostorFrame, images: ViewImages) -> Model {
    let mesh = &tree.mesh;
    let skinning = rest_skinning(tree);
    let rows = frame.rows.max(1);
    let spacing = frame.height / rows as f32;
    let half_width = frame.radius * 0.5;
    let mut out = SkinnedMesh::default();
    let mut last: Vec<Influence> = vec![Influence {
        bone: 0,
        weight: 1.0,
    }];
    for r in 0..=rows {
        let y = frame.base + spacing * r as f32;
        let mut weights: std::collections::BTreeMap<u32, f32> = Default::default();
        for v in 0..mesh.vertex_count() {
            if (mesh.positions[v].y - y).abs() <= spacing {
                for inf in mesh.influences_of(v) {
                    *weights.entry(inf.bone).or_default() += inf.weight;
                }
            }
        }
        let mut heaviest: Vec<(u32, f32)> = weights.into_iter().collect();
        heaviest.sort_by(|a, b| b.1.total_cmp(&a.1));
        heaviest.truncate(4);
        let sum: f32 = heaviest.iter().map(|(_, w)| w).sum();
        // An empty slab (a gap in the tree) moves as the one below it.
        if sum > 0.0 {
            last = heaviest
                .iter()
                .map(|&(bone, w)| Influence {
                    bone,
                    weight: w / sum,
                })
                .collect();
        }
        let rest: glam::Mat4 = last
            .iter()
            .map(|inf| inf.weight * skinning[inf.bone as usize])
            .fold(glam::Mat4::ZERO, |a, m| a + m);
        // A blend of bones that squashes space flat (a zero scale at rest) has no inverse:
        // the row is then stored where it stands, and sways from a little off its place.
        let to_bind = if crate::model::keeps_every_direction(&rest) {
            rest.inverse()
        } else {
            log::warn!(
                "{}: the impostor's row {r} hangs from bones whose rest pose has no inverse",
                tree.name
            );
            glam::Mat4::IDENTITY
        };
        for side in [-1.0f32, 1.0] {
            let at = Vec3::new(frame.centre[0] + side * half_width, y, frame.centre[2]);
            out.positions.push(to_bind.transform_point3(at));
            out.normals.push(Vec3::Z);
            out.uvs
                .push(Vec2::new(0.5 + 0.5 * side, 1.0 - r as f32 / rows as f32));
            out.materials.push(0);
            out.influence_offsets.push(out.influences.len() as u32);
            out.influences.extend_from_slice(&last);
        }
    }
    out.influence_offsets.push(out.influences.len() as u32);
    for r in 0..rows {
        let (a, b, c, d) = (2 * r, 2 * r + 1, 2 * r + 3, 2 * r + 2);
        out.indices.extend_from_slice(&[a, b, c, a, c, d]);
    }
    Model {
        name: format!("{} impostor", tree.name),
        mesh: out,
        skeleton: tree.skeleton.clone(),
        clips: tree.clips.clone(),
        materials: vec![
            Material::cut_out("impostor colour", [1.0; 4], Some(images.colour)),
            Material::cut_out("impostor normals", [1.0; 4], Some(images.normal)),
        ],
    }
}

/// The skinning matrices `G_i Ĝ_i⁻¹` of `tree`'s rest pose (see [`at_rest`]).
fn rest_skinning(tree: &Model) -> Vec<glam::Mat4> {
    crate::anim::bone_matrices(&tree.skeleton, None, 0.0)
        .iter()
        .zip(&tree.skeleton.inverse_bind)
        .map(|(g, inv)| glam::Mat4::from(*g) * *inv)
        .collect()
}

/// `tree` posed as the renderer shows it without wind: its nodes' own transforms, no clip
/// (frame 0 of the animation texture, the pose `skin_vertex` scales the wind about). That is
/// not the bind pose its mesh is stored in: a root node's translation alone moved the conifer
/// by 7% of its height, and an impostor drawn from the bind pose stood that far off its tree.
pub fn at_rest(tree: &Model) -> Model {
    posed(tree, None, 0.0)
}

/// `model` posed `t` seconds into `clip` (or at rest, for none): positions and normals
/// skinned on the CPU as the vertex shader would.
pub fn posed(model: &Model, clip: Option<&crate::model::Clip>, t: f32) -> Model {
    let tree = model;
    let g = crate::anim::bone_matrices(&tree.skeleton, clip, t);
    let skinning: Vec<glam::Mat4> = g
        .iter()
        .zip(&tree.skeleton.inverse_bind)
        .map(|(g, inv)| glam::Mat4::from(*g) * *inv)
        .collect();
    let mesh = &tree.mesh;
    let mut posed = tree.clone();
    posed.mesh.positions = crate::anim::linear_blend_skinning(mesh, &tree.skeleton, &g);
    posed.mesh.normals = (0..mesh.vertex_count())
        .map(|v| {
            let n = mesh.normals[v].extend(0.0);
            mesh.influences_of(v)
                .iter()
                .map(|inf| inf.weight * (skinning[inf.bone as usize] * n))
                .sum::<glam::Vec4>()
                .truncate()
                .normalize_or(mesh.normals[v])
        })
        .collect();
    posed
}

/// Fills every `cell` × `cell` block of an atlas `width` texels wide from its own covered
/// texels ([`dilate`] block by block, as far as the block reaches): a view's empty margin takes
/// its own outline's values, never those of the neighbouring view.
pub(crate) fn dilate_cells(pixels: &mut [u8], width: u32, height: u32, cell: u32) {
    let (w, c) = (width as usize, cell as usize);
    let mut block = vec![0u8; 4 * c * c];
    for j in 0..(height / cell) as usize {
        for i in 0..(width / cell) as usize {
            let row = |y: usize| 4 * ((j * c + y) * w + i * c)..4 * ((j * c + y) * w + i * c + c);
            for y in 0..c {
                block[4 * y * c..4 * (y + 1) * c].copy_from_slice(&pixels[row(y)]);
            }
            dilate(&mut block, cell, cell, 2 * cell);
            for y in 0..c {
                pixels[row(y)].copy_from_slice(&block[4 * y * c..4 * (y + 1) * c]);
            }
        }
    }
}

/// The last step of an impostor's views (a tree's, or a forest patch's composed from its
/// trees'): `images` as drawn and averaged (colour alpha the coverage, the normal's alpha the
/// height towards the eye) dilated so that filtering never pulls in an unset texel: the
/// colour round each outline, the normals and heights over whole `cell`-texel cells.
pub(crate) fn finish_views(images: &mut ViewImages, cell: u32) {
    // Heights of the covered texels, uncovered ones at the centre plane, then spread out
    // from the silhouettes: a parallax probe that lands just off a view's outline moves with
    // the edge next to it, and filtering never mixes in a height from nowhere.
    let mut heights: Vec<u8> = images
        .normal
        .pixels
        .chunks_exact(4)
        .zip(images.colour.pixels.chunks_exact(4))
        .flat_map(|(n, c)| {
            let h = if c[3] > 0 { n[3] } else { encode_height(0.0) };
            [h, h, h, c[3]]
        })
        .collect();
    for (n, c) in images
        .normal
        .pixels
        .chunks_exact_mut(4)
        .zip(images.colour.pixels.chunks_exact(4))
    {
        n[3] = c[3];
    }
    let (w, h) = (images.colour.width, images.colour.height);
    dilate(&mut images.colour.pixels, w, h, DILATE_RINGS);
    // Normals and heights fill whole cells: their layer is filtered as plain data (its alpha
    // never falls under the cut-off), so no texel may hold an unset one.
    dilate_cells(&mut images.normal.pixels, w, h, cell);
    dilate_cells(&mut heights, w, h, cell);
    for (n, h) in images
        .normal
        .pixels
        .chunks_exact_mut(4)
        .zip(heights.chunks_exact(4))
    {
        n[3] = h[0];
    }
}

/// The octahedral impostor of `tree`: its views drawn through `raster` of the tree at rest
/// ([`at_rest`]), averaged down and dilated, and the quad model that shows them.
pub fn bake_impostor(
    raster: &dyn RasterizeAtlas,
    tree: &Model,
    grid: ViewGrid,
) -> Result<(Model, ImpostorFrame)> {
    let posed = at_rest(tree);
    let tree = &posed;
    let (request, radius) = view_request(tree, grid, SUPERSAMPLE)?;
    let materials = MaterialLayers::bake(&tree.materials);
    let drawn = raster.rasterize_views(&request, &materials)?;
    let mut images = average_down(&drawn, SUPERSAMPLE);
    // The alpha test at one half would drop the twigs and leaf edges that cover less than
    // half a texel: scale alpha so that as many texels pass as the drawn views covered
    // (coverage-preserving, as the material mipmaps are).
    let drawn_px = &drawn.colour.pixels;
    let covered = drawn_px.chunks_exact(4).filter(|p| p[3] >= 128).count();
    preserve_coverage(
        &mut images.colour.pixels,
        covered as f32 / (drawn_px.len() / 4) as f32,
    );
    finish_views(&mut images, grid.cell);
    let bounds = Bounds::of(tree.mesh.positions.iter().copied())
        .ok_or_else(|| anyhow!("{}: no vertices", tree.name))?;
    let frame = ImpostorFrame {
        frames: grid.frames,
        centre: request.centre.to_array(),
        radius,
        base: bounds.min.y,
        height: bounds.size().y.max(1e-4),
        rows: ROWS,
        bounds: [bounds.min.to_array(), bounds.max.to_array()],
    };
    Ok((impostor_model(tree, &frame, images), frame))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_map_is_inverted_by_its_decode() {
        let mut rng = fastrand::Rng::with_seed(3);
        for _ in 0..2000 {
            let d = Vec3::new(rng.f32() * 2.0 - 1.0, rng.f32(), rng.f32() * 2.0 - 1.0);
            if d.length() < 1e-3 {
                continue;
            }
            let d = d.normalize();
            let s = hemi_oct_encode(d);
            assert!(s.x.abs() <= 1.0 + 1e-5 && s.y.abs() <= 1.0 + 1e-5, "{s}");
            let back = hemi_oct_decode(s);
            assert!(back.distance(d) < 1e-4, "{d} -> {s} -> {back}");
        }
        // Straight down onto the tree is the middle, the horizon the square's edge.
        assert!(hemi_oct_encode(Vec3::Y).length() < 1e-6);
        for d in [
            Vec3::X,
            Vec3::Z,
            Vec3::NEG_X,
            Vec3::new(1.0, 0.0, 1.0).normalize(),
        ] {
            let s = hemi_oct_encode(d);
            assert!((s.x.abs().max(s.y.abs()) - 1.0).abs() < 1e-5, "{d}: {s}");
        }
    }

    #[test]
    fn grid_views_cover_the_hemisphere_evenly_enough() {
        let grid = ViewGrid {
            frames: 8,
            cell: 64,
        };
        let views: Vec<Vec3> = (0..8)
            .flat_map(|j| (0..8).map(move |i| (i, j)))
            .map(|(i, j)| grid.direction(i, j))
            .collect();
        assert!(
            views
                .iter()
                .all(|v| v.y >= -1e-6 && (v.length() - 1.0).abs() < 1e-5)
        );
        // Every direction over the hemisphere has a view within 22°.
        let mut rng = fastrand::Rng::with_seed(4);
        let mut worst = 0.0f32;
        for _ in 0..4000 {
            let d = Vec3::new(rng.f32() * 2.0 - 1.0, rng.f32(), rng.f32() * 2.0 - 1.0);
            if d.length() < 1e-3 {
                continue;
            }
            let d = d.normalize();
            let nearest = views.iter().map(|v| v.dot(d)).fold(-1.0f32, f32::max);
            worst = worst.max(nearest.clamp(-1.0, 1.0).acos().to_degrees());
        }
        assert!(worst < 22.0, "{worst}°");
        assert_eq!(grid.atlas_size(), 512);
    }

    #[test]
    fn a_blend_uses_the_views_round_the_direction() {
        let grid = ViewGrid {
            frames: 6,
            cell: 32,
        };
        let mut rng = fastrand::Rng::with_seed(5);
        for _ in 0..1000 {
            let d = Vec3::new(rng.f32() * 2.0 - 1.0, rng.f32(), rng.f32() * 2.0 - 1.0);
            if d.length() < 1e-3 {
                continue;
            }
            let d = d.normalize();
            let blend = grid.blend(d);
            let sum: f32 = blend.iter().map(|(_, w)| w).sum();
            assert!((sum - 1.0).abs() < 1e-5);
            assert!(blend.iter().all(|&(_, w)| w >= -1e-5));
            // The heaviest view is close to the direction.
            let &((i, j), _) = blend.iter().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
            let angle = grid
                .direction(i, j)
                .dot(d)
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees();
            assert!(angle < 30.0, "{angle}°");
        }
        // A grid direction is its own view, alone.
        let at = grid.blend(grid.direction(2, 3));
        let own = at.iter().find(|((i, j), _)| (*i, *j) == (2, 3)).unwrap();
        assert!((own.1 - 1.0).abs() < 1e-3, "{at:?}");
    }

    #[test]
    fn view_axes_are_upright_and_orthonormal() {
        for d in [
            Vec3::X,
            Vec3::Y,
            Vec3::new(0.3, 0.5, -0.8).normalize(),
            Vec3::new(-1.0, 0.01, 0.0).normalize(),
        ] {
            let (r, u) = ViewGrid::view_axes(d);
            assert!((r.length() - 1.0).abs() < 1e-5 && (u.length() - 1.0).abs() < 1e-5);
            assert!(r.dot(u).abs() < 1e-5 && r.dot(d).abs() < 1e-5 && u.dot(d).abs() < 1e-5);
            if d.y < 0.99 {
                assert!(u.y > 0.0, "{d}: up {u}");
            }
        }
    }

    #[test]
    fn cells_are_filled_from_their_own_view_only() {
        // Two 4×4 cells side by side, one covered texel in each: red on the left, blue on
        // the right. Every texel of a cell takes its own cell's colour.
        let (w, h, c) = (8u32, 4u32, 4u32);
        let mut px = vec![0u8; (4 * w * h) as usize];
        px[0..4].copy_from_slice(&[255, 0, 0, 255]);
        let right = (4 * (3 * w + 7)) as usize;
        px[right..right + 4].copy_from_slice(&[0, 0, 255, 255]);
        dilate_cells(&mut px, w, h, c);
        for y in 0..h {
            for x in 0..w {
                let p = &px[(4 * (y * w + x)) as usize..][..3];
                let want = if x < c { [255, 0, 0] } else { [0, 0, 255] };
                assert_eq!(p, want, "texel ({x}, {y})");
            }
        }
    }

    #[test]
    fn averaging_down_keeps_coverage_colour_normals_and_heights_of_what_is_covered() {
        // One 2×2 block: two texels covered (red and blue, normals +x and +y, heights 200
        // and 210), two empty (white, normal −z: never counted).
        let colour = Rgba8Image {
            width: 2,
            height: 2,
            pixels: vec![
                255, 0, 0, 255, 255, 255, 255, 0, //
                0, 0, 255, 255, 255, 255, 255, 0,
            ],
        };
        let normal = Rgba8Image {
            width: 2,
            height: 2,
            pixels: vec![
                255, 128, 128, 200, 128, 128, 0, 0, //
                128, 255, 128, 210, 128, 128, 0, 0,
            ],
        };
        let out = average_down(&ViewImages { colour, normal }, 2);
        assert_eq!((out.colour.width, out.colour.height), (1, 1));
        let c = &out.colour.pixels;
        // Half covered; red and blue averaged in linear light, no white.
        assert_eq!(c[3], 128);
        assert_eq!(
            (c[0], c[1], c[2]),
            (linear_to_srgb(0.5), 0, linear_to_srgb(0.5))
        );
        // The normal is the mean of +x and +y, renormalised, sRGB-encoded.
        let n: Vec<f32> = out.normal.pixels[..3]
            .iter()
            .map(|&b| srgb_to_linear(b) * 2.0 - 1.0)
            .collect();
        let h = std::f32::consts::FRAC_1_SQRT_2;
        assert!((n[0] - h).abs() < 0.03 && (n[1] - h).abs() < 0.03 && n[2].abs() < 0.03);
        // The height is the covered texels' mean.
        assert_eq!(out.normal.pixels[3], 205);
    }

    #[test]
    fn the_quad_rows_are_skinned_like_the_tree_at_their_height() {
        // The built-in conifer as its glTF file has it: its nodes' rest pose stands away from
        // the bind pose of its mesh, as in many files users bring.
        let bind = crate::import::load_model("conifer").unwrap();
        let tree = at_rest(&bind);
        let bounds = Bounds::of(tree.mesh.positions.iter().copied()).unwrap();
        let frame = ImpostorFrame {
            frames: 4,
            centre: bounds.center().to_array(),
            radius: bounds.diagonal() * 0.5,
            base: bounds.min.y,
            height: bounds.size().y,
            rows: ROWS,
            bounds: [bounds.min.to_array(), bounds.max.to_array()],
        };
        let blank = Rgba8Image {
            width: 4,
            height: 4,
            pixels: vec![0; 64],
        };
        let model = impostor_model(
            &tree,
            &frame,
            ViewImages {
                colour: blank.clone(),
                normal: blank,
            },
        );
        let mesh = &model.mesh;
        assert_eq!(mesh.vertex_count(), 2 * (ROWS as usize + 1));
        assert_eq!(mesh.triangle_count(), 2 * ROWS as usize);
        // The renderer finds the rows by vertex index (the bake keeps them in order), and at
        // rest (no wind) its skinning puts them on the quad: the conifer's rest pose stands
        // away from its bind pose, so this fails if the rows were stored in the wrong one.
        let bake = crate::bake::gpu_data::drawable::Drawable::in_order(&model).unwrap();
        let (rest, _) = bake.evaluate(0, 0.0, 0.0);
        for r in 0..=ROWS as usize {
            let (l, rt) = (2 * r, 2 * r + 1);
            // A pair shares its influences; rows climb evenly, a crown's width apart.
            assert_eq!(mesh.influences_of(l), mesh.influences_of(rt));
            let y = frame.base + frame.height * r as f32 / ROWS as f32;
            for (v, side) in [(l, -1.0), (rt, 1.0)] {
                let want = Vec3::new(
                    frame.centre[0] + side * frame.radius * 0.5,
                    y,
                    frame.centre[2],
                );
                assert!(rest[v].distance(want) < 1e-3, "{} != {want}", rest[v]);
            }
            let infl = mesh.influences_of(l);
            assert!(!infl.is_empty() && infl.len() <= 4);
            let sum: f32 = infl.iter().map(|i| i.weight).sum();
            assert!((sum - 1.0).abs() < 1e-5);
        }
        // The foot and the top sway differently; the top row hangs from bones out in the
        // crown.
        assert_ne!(mesh.influences_of(0), mesh.influences_of(2 * ROWS as usize));
        assert!(
            mesh.influences_of(2 * ROWS as usize)
                .iter()
                .all(|i| i.bone != 0)
        );
        // The conifer's rest pose is not its bind pose: a test of the bind pose would pass
        // without [`at_rest`].
        let moved = bind
            .mesh
            .positions
            .iter()
            .zip(&tree.mesh.positions)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0f32, f32::max);
        assert!(moved > 0.01 * frame.height, "moved {moved}");
    }
}

//! Normal maps for the coarse levels: full detail's shading on fewer triangles.
//!
//! Merry, Marais & Gain ("Analytic simplification of animated characters") base their
//! simplification on appearance-preserving simplification (Cohen, Olano & Manocha 1998):
//! half-edge collapses keep the remaining vertices' texture coordinates, so a point of a coarse
//! level corresponds to the point of full detail with the same coordinate, and full detail's
//! normals can be sampled into a map that lights the coarse level (their §2 and §3; their
//! renderer uses tangent-space normal maps, §6.4). This module bakes those maps.
//!
//! - **Correspondence.** A texel of level k lies in one of k's triangles (in texture space); its
//!   rest-pose point there corresponds to full detail's point at the same texture coordinate. Where
//!   several full-detail triangles hold that coordinate (a chart wrapped round, a tiled texture)
//!   the one nearest in space is taken.
//! - **Tangent space.** The stored normal is full detail's interpolated vertex normal in the
//!   frame of k's triangle: the interpolated normal n, the tangent t = ∂P/∂u made orthogonal to
//!   n, and b = ±n × t, with the sign of the triangle's handedness in texture space. The
//!   fragment shader rebuilds exactly that frame from the screen derivatives of the skinned
//!   position and of the texture coordinate (`mapped_normal` in shaders/character.wgsl), so the
//!   frame follows the skin and the vertex data carries no tangents (Merry et al. keep two per
//!   influence in their vertex textures; deriving the frame costs a few derivatives instead).
//! - **Where it cannot work.** A material whose triangles have no area in texture space (no or
//!   zero texture coordinates) or whose charts overlap one another (mirrored halves, tiling:
//!   one texel, two places) gets no map: its vertices keep their vertex normals, and the reason
//!   is kept for the viewer's panel ([`UvProblem`]).
//!
//! - **Never worse than the vertex normals, tile by tile.** The map is right where the point of
//!   full detail with a texel's texture coordinate is where the level's surface is. Where a
//!   collapse let the texture slide (priced, at coarse levels), it is elsewhere, and its normal
//!   lights the level with a crease or a dark streak that the level's own vertex normals do
//!   not have. So every [`TILE`]-texel tile of a layer is judged against full detail's normal at
//!   the nearest point of its surface (where the renderer's comparison finds full detail): a
//!   tile whose stored normals are further from those than the interpolated vertex normals are
//!   gets the vertex normals ((0, 0, 1) in the frame), and a map never makes a tile worse.
//!
//! Each level that gets a map has one layer per mapped material, `size`² texels of RGB8 (the
//! unit vector's coordinates in the frame, as 128 + 127·x), with mipmaps, in one texture array.
//! Full detail gets none: its vertex normals are full detail's own.

use super::lod_error::Surface;
use super::uv_grid::UvGrid;
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use glam::{Affine3A, DVec2, Vec2, Vec3};
use rayon::prelude::*;

/// Texels on a side of every layer.
pub const NORMAL_MAP_SIZE: u32 = 256;

/// A material whose charts cover more than this share of their texels twice has no map.
const MAX_OVERLAP: f32 = 0.02;
/// A material covering fewer texels than this has no usable texture coordinates.
const MIN_TEXELS: usize = 16;
/// Rings of texels filled round every chart, so that filtering and mipmaps do not mix in the
/// empty texels between charts.
const DILATION: u32 = 3;
/// The encoding of the unperturbed normal (0, 0, 1): what texels no triangle covers hold.
const FLAT: [u8; 4] = [128, 128, 255, 0];
/// Texels on a side of the tiles a layer is judged by against the vertex normals.
pub const TILE: u32 = 8;

/// Why a material's vertices keep their vertex normals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UvProblem {
    /// Its triangles have (next to) no area in texture space.
    NoTexCoords,
    /// Its charts overlap: this share of the texels they cover is covered twice.
    Overlapping(f32),
    /// A triangle spans more than the whole texture (it tiles it): every texel it covers is
    /// more than one place.
    Tiled,
}

impl std::fmt::Display for UvProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            UvProblem::NoTexCoords => write!(f, "no texture coordinates"),
            UvProblem::Tiled => write!(f, "texture coordinates tile the texture"),
            UvProblem::Overlapping(share) => write!(
                f,
                "texture coordinates overlap ({:.0}% of texels twice)",
                share * 100.0
            ),
        }
    }
}

/// The normal maps of a set of levels.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMaps {
    pub size: u32,
    pub layer_count: u32,
    /// RGBA8 (linear) texels, mip 0 of every layer first, then mip 1 of every layer, and so on.
    pub mips: Vec<Vec<u8>>,
    /// For every level given, for every material: its layer, or `None` (vertex normals).
    pub layers: Vec<Vec<Option<u32>>>,
    /// For every material, why it has no map (`None`: it has one).
    pub problems: Vec<Option<UvProblem>>,
}

impl NormalMaps {
    /// Bytes of all layers with their mipmaps.
    pub fn bytes(&self) -> usize {
        self.mips.iter().map(Vec::len).sum()
    }

    /// Whether level `k` is drawn with a map.
    pub fn maps_level(&self, k: usize) -> bool {
        self.layers
            .get(k)
            .is_some_and(|l| l.iter().any(Option::is_some))
    }

    /// The reason no material of these levels has a map, if none has: the first material's.
    pub fn unmapped_reason(&self) -> Option<UvProblem> {
        if self.problems.iter().any(Option::is_none) {
            None
        } else {
            self.problems.iter().flatten().next().copied()
        }
    }

    /// The unit normal stored at texel (x, y) of `layer`'s full-size map, in its triangle's
    /// frame (t, b, n).
    pub fn texel(&self, layer: u32, x: u32, y: u32) -> Vec3 {
        let i = (((layer * self.size + y) * self.size + x) * 4) as usize;
        decode(&self.mips[0][i..i + 3])
    }
}

/// A unit vector as texels: x ↦ 128 + 127·x, so that 0 (most of a map: the flat normal's x
/// and y) is exact; the shader decodes as [`decode`] does.
fn encode(v: Vec3) -> [u8; 4] {
    let c = |x: f32| (128.0 + 127.0 * x.clamp(-1.0, 1.0)).round() as u8;
    [c(v.x), c(v.y), c(v.z), 255]
}

fn decode(c: &[u8]) -> Vec3 {
    (Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) - Vec3::splat(128.0)) / 127.0
}

/// A mesh posed at rest, its triangles by material.
struct Posed<'a> {
    mesh: &'a AnimationSpaceMesh,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
}

impl<'a> Posed<'a> {
    fn new(mesh: &'a AnimationSpaceMesh, rest_bones: &[Affine3A]) -> Self {
        let (positions, normals) = mesh.evaluate(rest_bones);
        let normals = normals.into_iter().map(|n| n.normalize_or_zero()).collect();
        Posed {
            mesh,
            positions,
            normals,
        }
    }

    /// Triangles (as vertex triples) of material `m`: a triangle's material is its first
    /// vertex's, as the shader's flat `material` is.
    fn triangles_of(&self, m: u16) -> Vec<[u32; 3]> {
        self.mesh
            .indices
            .chunks_exact(3)
            .filter(|t| self.mesh.materials[t[0] as usize] == m)
            .map(|t| [t[0], t[1], t[2]])
            .collect()
    }
}

/// The texel centres of one texture-space triangle, in map texels (`size` per unit of texture
/// coordinate, not wrapped), with their barycentric weights; centres on an edge count for both
/// triangles that share it.
fn texels_of(uv: [Vec2; 3], size: u32, mut each: impl FnMut(i64, i64, [f64; 3])) {
    let q = uv.map(|u| u.as_dvec2() * size as f64);
    let lo = q[0].min(q[1]).min(q[2]);
    let hi = q[0].max(q[1]).max(q[2]);
    // A triangle larger than the map is not a chart (`check_uvs` finds it first): leave it
    // out, so that the cost is bounded by the map's texels, not by the texture coordinates'
    // extent (coordinates up to 1000 made it a million maps a triangle).
    if !(lo.is_finite() && hi.is_finite()) || (hi - lo).max_element() > 2.0 * size as f64 {
        return;
    }
    for y in (lo.y - 0.5).ceil() as i64..=(hi.y - 0.5).floor() as i64 {
        for x in (lo.x - 0.5).ceil() as i64..=(hi.x - 0.5).floor() as i64 {
            let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            let w = super::simplify::collapse::barycentric(p, q[0], q[1], q[2]);
            if w.iter().all(|&x| x >= -1e-9) {
                each(x, y, w);
            }
        }
    }
}

/// The texel index of unwrapped texel (x, y): the sampler repeats.
fn wrap(x: i64, y: i64, size: u32) -> usize {
    let s = size as i64;
    (y.rem_euclid(s) * s + x.rem_euclid(s)) as usize
}

/// Whether the triangles `tris` of full detail give material one place per texel.
fn check_uvs(full: &Posed, tris: &[[u32; 3]], size: u32) -> Option<UvProblem> {
    let uvs = &full.mesh.uvs;
    let mut first: Vec<u32> = vec![u32::MAX; (size * size) as usize];
    let (mut covered, mut twice) = (0usize, 0usize);
    let texels = (size * size) as usize;
    for (i, t) in tris.iter().enumerate() {
        let uv = t.map(|v| uvs[v as usize]);
        let extent = uv[0].max(uv[1]).max(uv[2]) - uv[0].min(uv[1]).min(uv[2]);
        if extent.max_element() > 1.0 + 1.0 / size as f32 {
            return Some(UvProblem::Tiled);
        }
        // Texels covered again more often than the map has texels: overlapping whatever
        // follows, so the rest need not be rasterised (the share of texels twice is all).
        if twice > texels {
            return Some(UvProblem::Overlapping(1.0));
        }
        texels_of(uv, size, |x, y, _| {
            let slot = &mut first[wrap(x, y, size)];
            if *slot == u32::MAX {
                *slot = i as u32;
                covered += 1;
            } else if *slot != i as u32 {
                // Neighbours in one chart share a vertex, and an edge's texels count for
                // both; triangles that share none are two places on one texel.
                let other = tris[*slot as usize];
                if !t.iter().any(|v| other.contains(v)) {
                    twice += 1;
                }
            }
        });
    }
    if covered < MIN_TEXELS {
        return Some(UvProblem::NoTexCoords);
    }
    let share = twice as f32 / covered as f32;
    (share > MAX_OVERLAP).then_some(UvProblem::Overlapping(share))
}

/// Full detail's normal at texture coordinate `uv`: of the triangles holding it, the one
/// nearest `near`; `None` where none holds it (a chart whose outline the level simplified).
fn full_normal(
    full: &Posed,
    tris: &[[u32; 3]],
    grid: &UvGrid,
    uv: DVec2,
    near: Vec3,
) -> Option<Vec3> {
    let uvs = &full.mesh.uvs;
    let mut best: Option<(f32, Vec3)> = None;
    for &t in grid.candidates(uv) {
        let tri = tris[t as usize];
        let [a, b, c] = tri.map(|v| uvs[v as usize].as_dvec2());
        let w = super::simplify::collapse::barycentric(uv, a, b, c);
        if w.iter().any(|&x| x < -1e-6) {
            continue;
        }
        let w = w.map(|x| x as f32);
        let at = |f: &[Vec3]| (0..3).map(|k| f[tri[k] as usize] * w[k]).sum::<Vec3>();
        let d = at(&full.positions).distance_squared(near);
        if best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, at(&full.normals)));
        }
    }
    best.and_then(|(_, n)| n.try_normalize())
}

/// One level's layer of material `tris`: full detail's normals in the frames of the level's
/// triangles `coarse`. Texels no triangle covers hold the flat normal, dilated from the charts.
fn bake_layer(
    full: &Posed,
    full_tris: &[[u32; 3]],
    grid: &UvGrid,
    surface: &Surface,
    level: &Posed,
    coarse: &[[u32; 3]],
    size: u32,
) -> Vec<u8> {
    let mut pixels: Vec<u8> = FLAT.repeat((size * size) as usize);
    // Per tile: how far the stored normals and the vertex normals are from full detail's
    // nearest (1 − cos, summed over its texels).
    let tiles = size.div_ceil(TILE) as usize;
    let mut off = vec![(0.0f64, 0.0f64); tiles * tiles];
    let tile_of = |i: usize| {
        let (x, y) = (i % size as usize, i / size as usize);
        (y / TILE as usize) * tiles + x / TILE as usize
    };
    let nearest_normal = |p: Vec3| -> Option<Vec3> {
        let (t, w) = surface.closest(p.as_dvec3())?;
        (0..3)
            .map(|k| full.normals[t[k] as usize] * w[k] as f32)
            .sum::<Vec3>()
            .try_normalize()
    };
    let uvs = &level.mesh.uvs;
    for t in coarse {
        let uv = t.map(|v| uvs[v as usize]);
        let p = t.map(|v| level.positions[v as usize]);
        let n = t.map(|v| level.normals[v as usize]);
        // ∂P/∂u and ∂P/∂v of the flat triangle: the tangent frame the shader derives.
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
        let det = d1.x * d2.y - d2.x * d1.y;
        if det.abs() < 1e-12 {
            // No area in texture space: the shader falls back to the vertex normal.
            continue;
        }
        let dpdu = (e1 * d2.y - e2 * d1.y) / det;
        let dpdv = (e2 * d1.x - e1 * d2.x) / det;
        texels_of(uv, size, |x, y, w| {
            let w = w.map(|x| x as f32);
            let Some(nc) = (n[0] * w[0] + n[1] * w[1] + n[2] * w[2]).try_normalize() else {
                return;
            };
            let Some(tangent) = (dpdu - nc * nc.dot(dpdu)).try_normalize() else {
                return;
            };
            let hand = if dpdu.cross(dpdv).dot(nc) >= 0.0 {
                1.0
            } else {
                -1.0
            };
            let bitangent = nc.cross(tangent) * hand;
            let at = p[0] * w[0] + p[1] * w[1] + p[2] * w[2];
            let centre = DVec2::new(x as f64 + 0.5, y as f64 + 0.5) / size as f64;
            let nf = full_normal(full, full_tris, grid, centre, at).unwrap_or(nc);
            let local = Vec3::new(nf.dot(tangent), nf.dot(bitangent), nf.dot(nc));
            let texel = wrap(x, y, size);
            let i = 4 * texel;
            let code = encode(local.normalize_or(Vec3::Z));
            pixels[i..i + 4].copy_from_slice(&code);
            if let Some(truth) = nearest_normal(at) {
                // The normal as the shader reads it back, eight bits a coordinate: where the
                // level is as good as full detail, that rounding is all a map adds.
                let q = decode(&code);
                let stored = (tangent * q.x + bitangent * q.y + nc * q.z).normalize_or(nc);
                let o = &mut off[tile_of(texel)];
                o.0 += (1.0 - stored.dot(truth)) as f64;
                o.1 += (1.0 - nc.dot(truth)) as f64;
            }
        });
    }
    // A tile the map lights worse than the vertex normals do keeps the vertex normals.
    for (texel, px) in pixels.chunks_exact_mut(4).enumerate() {
        let (map, vertex) = off[tile_of(texel)];
        if px[3] == 255 && map > vertex {
            px.copy_from_slice(&[FLAT[0], FLAT[1], FLAT[2], 255]);
        }
    }
    crate::bake::gpu_data::materials::dilate(&mut pixels, size, size, DILATION);
    pixels
}

/// The mip chain of one layer: each texel the mean of its four.
fn mip_chain(base: Vec<u8>, size: u32) -> Vec<Vec<u8>> {
    let mut chain = vec![base];
    let mut s = size as usize;
    while s > 1 {
        let prev = chain.last().expect("non-empty");
        let h = s / 2;
        let mut next = Vec::with_capacity(h * h * 4);
        for y in 0..h {
            for x in 0..h {
                for c in 0..4 {
                    let at =
                        |dx: usize, dy: usize| prev[((2 * y + dy) * s + 2 * x + dx) * 4 + c] as u32;
                    let sum = at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1);
                    next.push(((sum + 2) / 4) as u8);
                }
            }
        }
        chain.push(next);
        s = h;
    }
    chain
}

/// Normal maps for `levels` (finest first; `None` for a level drawn without one, full detail)
/// against `full`, the full-detail mesh whose vertices the levels keep, both posed by
/// `rest_bones`. `materials` is the model's material count; `size` must be a power of two.
pub fn bake(
    full: &AnimationSpaceMesh,
    levels: &[Option<&AnimationSpaceMesh>],
    rest_bones: &[Affine3A],
    materials: usize,
    size: u32,
) -> NormalMaps {
    assert!(
        size.is_power_of_two(),
        "normal map size {size} is not a power of two"
    );
    let full = Posed::new(full, rest_bones);
    // Full detail's surface, for the normal where the renderer's comparison finds it.
    let all: Vec<[u32; 3]> = full
        .mesh
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    let surface = Surface::new(&all, |v| full.positions[v as usize].as_dvec3());
    let per_material: Vec<(Vec<[u32; 3]>, Option<UvProblem>)> = (0..materials)
        .map(|m| {
            let tris = full.triangles_of(m as u16);
            let problem = check_uvs(&full, &tris, size);
            (tris, problem)
        })
        .collect();
    let grids: Vec<Option<UvGrid>> = per_material
        .iter()
        .map(|(tris, problem)| (problem.is_none()).then(|| UvGrid::new(tris, &full.mesh.uvs)))
        .collect();
    // Layers in order: level by level, mapped materials in order.
    let mut layers = Vec::with_capacity(levels.len());
    let mut jobs: Vec<(usize, usize)> = Vec::new();
    for (k, level) in levels.iter().enumerate() {
        let mut of_level = vec![None; materials];
        if level.is_some() {
            for (m, slot) in of_level.iter_mut().enumerate() {
                if grids[m].is_some() {
                    *slot = Some(jobs.len() as u32);
                    jobs.push((k, m));
                }
            }
        }
        layers.push(of_level);
    }
    let posed: Vec<Option<Posed>> = levels
        .par_iter()
        .map(|l| l.map(|mesh| Posed::new(mesh, rest_bones)))
        .collect();
    let chains: Vec<Vec<Vec<u8>>> = jobs
        .par_iter()
        .map(|&(k, m)| {
            let level = posed[k].as_ref().expect("a level with layers is posed");
            let (full_tris, _) = &per_material[m];
            let grid = grids[m].as_ref().expect("a mapped material has a grid");
            let base = bake_layer(
                &full,
                full_tris,
                grid,
                &surface,
                level,
                &level.triangles_of(m as u16),
                size,
            );
            mip_chain(base, size)
        })
        .collect();
    let mip_count = size.trailing_zeros() as usize + 1;
    let mips = (0..mip_count)
        .map(|i| chains.iter().flat_map(|c| c[i].iter().copied()).collect())
        .collect();
    NormalMaps {
        size,
        layer_count: jobs.len() as u32,
        mips,
        layers,
        problems: per_material.into_iter().map(|(_, p)| p).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::gpu_data::animation_space::AsInfluence;
    use glam::Vec4;

    /// The bump's height over the unit square, and its normal.
    fn bump(x: f32, y: f32) -> (f32, Vec3) {
        let r2 = (x - 0.5).powi(2) + (y - 0.5).powi(2);
        let h = 0.2 * (-r2 / 0.02).exp();
        let d = -h / 0.02 * 2.0;
        (
            h,
            Vec3::new(-d * (x - 0.5), -d * (y - 0.5), 1.0).normalize(),
        )
    }

    /// A mesh of one bone from vertices (position, normal, uv) and triangles.
    fn mesh(vertices: &[(Vec3, Vec3, Vec2)], indices: Vec<u32>) -> AnimationSpaceMesh {
        AnimationSpaceMesh {
            offsets: (0..=vertices.len() as u32).collect(),
            influences: vertices
                .iter()
                .map(|&(p, n, _)| AsInfluence {
                    bone: 0,
                    p: Vec4::new(p.x, p.y, p.z, 1.0),
                    n,
                })
                .collect(),
            uvs: vertices.iter().map(|v| v.2).collect(),
            materials: vec![0; vertices.len()],
            indices,
            spectral_rows: Vec::new(),
            crown_occlusion: Vec::new(),
            view_windows: Vec::new(),
        }
    }

    /// A bumpy square as a `cells`² grid (full detail) and as its two corner triangles (the
    /// coarse level), texture coordinates `uv(x, y)` of the square's point (x, y).
    fn bumpy_square(
        cells: u32,
        uv: impl Fn(f32, f32) -> Vec2,
    ) -> (AnimationSpaceMesh, AnimationSpaceMesh) {
        let mut vertices = Vec::new();
        for j in 0..=cells {
            for i in 0..=cells {
                let (x, y) = (i as f32 / cells as f32, j as f32 / cells as f32);
                let (h, n) = bump(x, y);
                vertices.push((Vec3::new(x, y, h), n, uv(x, y)));
            }
        }
        let mut indices = Vec::new();
        let at = |i: u32, j: u32| j * (cells + 1) + i;
        for j in 0..cells {
            for i in 0..cells {
                indices.extend([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                indices.extend([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        let corner = |x: f32, y: f32| (Vec3::new(x, y, 0.0), Vec3::Z, uv(x, y));
        let coarse = mesh(
            &[
                corner(0.0, 0.0),
                corner(1.0, 0.0),
                corner(1.0, 1.0),
                corner(0.0, 1.0),
            ],
            vec![0, 1, 2, 0, 2, 3],
        );
        (mesh(&vertices, indices), coarse)
    }

    #[test]
    fn a_coarse_level_gets_full_details_normals_in_its_frame() {
        // The square fills most of the map, once as it is and once mirrored in u: the frame's
        // handedness must bring the mirrored x back.
        for mirrored in [false, true] {
            let uv = move |x: f32, y: f32| {
                let u = if mirrored { 1.0 - x } else { x };
                Vec2::new(0.05 + 0.9 * u, 0.05 + 0.9 * y)
            };
            let (full, coarse) = bumpy_square(64, uv);
            let maps = bake(&full, &[None, Some(&coarse)], &[Affine3A::IDENTITY], 1, 64);
            assert_eq!(maps.problems, vec![None]);
            assert_eq!(maps.layers, vec![vec![None], vec![Some(0)]]);
            assert!(!maps.maps_level(0) && maps.maps_level(1));
            assert_eq!(maps.mips.len(), 7);
            let mut worst = 0.0f32;
            let mut tilted = 0;
            for (x, y) in [
                (0.5, 0.5),
                (0.45, 0.5),
                (0.5, 0.4),
                (0.6, 0.55),
                (0.3, 0.7),
                (0.1, 0.1),
            ] {
                let p = uv(x, y) * 64.0;
                let stored = maps.texel(0, p.x as u32, p.y as u32);
                // The texel centre's point of the square.
                let centre = (p.floor() + Vec2::splat(0.5)) / 64.0;
                let u = (centre.x - 0.05) / 0.9;
                let sx = if mirrored { 1.0 - u } else { u };
                let (_, n) = bump(sx, (centre.y - 0.05) / 0.9);
                // The coarse frame is (x, y, z); mirrored, t = ∂P/∂u is −x, the handedness
                // −1 and b = −(z × −x) = y.
                let expected = Vec3::new(if mirrored { -n.x } else { n.x }, n.y, n.z);
                worst = worst.max(stored.distance(expected));
                tilted += (stored.z < 0.99) as usize;
            }
            // Interpolated over the grid's triangles and stored in 8 bits.
            assert!(worst < 0.03, "mirrored {mirrored}: off by {worst}");
            assert!(tilted >= 3, "the bump must show in the map");
        }
    }

    #[test]
    fn a_texture_that_slid_keeps_the_vertex_normals_where_the_map_would_be_worse() {
        // The coarse level's corners read the texture of the square's lower left quarter: its
        // texels find full detail's normals half the square away from where they are, the
        // bump where the level is flat and flat where the bump is.
        let uv = |x: f32, y: f32| Vec2::new(0.05 + 0.9 * x, 0.05 + 0.9 * y);
        let (full, mut coarse) = bumpy_square(64, uv);
        for (k, (x, y)) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .into_iter()
            .enumerate()
        {
            coarse.uvs[k] = uv(0.5 * x, 0.5 * y);
        }
        let maps = bake(&full, &[None, Some(&coarse)], &[Affine3A::IDENTITY], 1, 64);
        assert!(maps.maps_level(1));
        let (mut covered, mut tilted) = (0, 0);
        for y in 4..30 {
            for x in 4..30 {
                covered += 1;
                tilted += (maps.texel(0, x, y).z < 0.99) as usize;
            }
        }
        assert!(
            tilted * 20 < covered,
            "{tilted} of {covered} texels keep normals from the wrong place"
        );
        // Where the texture did not slide, the map stays (the test above checks its normals).
        let (full, coarse) = bumpy_square(64, uv);
        let maps = bake(&full, &[None, Some(&coarse)], &[Affine3A::IDENTITY], 1, 64);
        let tilted = (20..44)
            .flat_map(|y| (20..44).map(move |x| (x, y)))
            .filter(|&(x, y)| maps.texel(0, x, y).z < 0.99)
            .count();
        assert!(tilted > 100, "only {tilted} texels show the bump");
    }

    #[test]
    fn overlapping_or_missing_texture_coordinates_keep_vertex_normals() {
        // Two squares side by side on one chart (a mirrored pair, say): every texel twice.
        let (a, _) = bumpy_square(16, |x, y| Vec2::new(x, y) * 0.9);
        let mut b = a.clone();
        for inf in &mut b.influences {
            inf.p.x += 2.0;
        }
        let mut both = a.clone();
        let n = a.vertex_count() as u32;
        both.offsets = (0..=2 * n).collect();
        both.influences.extend(b.influences);
        both.uvs.extend(b.uvs);
        both.materials.extend(b.materials);
        both.indices.extend(b.indices.iter().map(|i| i + n));
        let maps = bake(&both, &[None, Some(&both)], &[Affine3A::IDENTITY], 1, 64);
        assert!(matches!(maps.problems[0], Some(UvProblem::Overlapping(s)) if s > 0.9));
        assert_eq!(maps.layer_count, 0);
        assert!(!maps.maps_level(1));
        assert!(maps.unmapped_reason().is_some());

        // No texture coordinates (a glTF without TEXCOORD_0 imports them as zero).
        let (full, coarse) = bumpy_square(16, |_, _| Vec2::ZERO);
        let maps = bake(&full, &[None, Some(&coarse)], &[Affine3A::IDENTITY], 1, 64);
        assert_eq!(maps.unmapped_reason(), Some(UvProblem::NoTexCoords));
        assert_eq!(maps.layers[1], vec![None]);
    }

    #[test]
    fn mipmaps_average_and_the_flat_normal_is_exact() {
        assert_eq!(decode(&encode(Vec3::Z)), Vec3::Z);
        assert_eq!(decode(&FLAT), Vec3::Z);
        let chain = mip_chain([10u8, 20, 30, 255, 30, 40, 50, 255].repeat(8), 4);
        assert_eq!(chain.len(), 3);
        assert_eq!(&chain[2][..3], &[20, 30, 40]);
    }
}

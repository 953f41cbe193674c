//! From a subdivided cage to a skinned mesh with a painted texture: charts packed into an atlas,
//! quads split into triangles, weights pruned to four influences, and the base colour painted
//! by rasterising every triangle in texture space with a colour function of the rest-pose
//! surface point.

use super::cage::Cage;
use crate::model::{Influence, Rgba8Image, SkinnedMesh};
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// Texels of empty border around every chart, so mip levels do not bleed between charts.
const PADDING: i32 = 4;
/// At most this many influences per vertex.
pub const MAX_INFLUENCES: usize = 4;
/// Influences below this weight are dropped before renormalising.
const MIN_WEIGHT: f32 = 0.02;

/// Where each chart went in the atlas.
#[derive(Clone, Debug)]
struct Placement {
    min: Vec2,
    origin: Vec2,
}

/// Packs all charts into a `size`² atlas at the highest texel density that fits.
fn pack(cage: &Cage, size: u32) -> (Vec<Placement>, f32) {
    let charts = cage.chart_parts.len();
    let mut lo = vec![Vec2::splat(f32::MAX); charts];
    let mut hi = vec![Vec2::splat(f32::MIN); charts];
    for f in cage.live_faces() {
        for uv in f.uv {
            lo[f.chart as usize] = lo[f.chart as usize].min(uv);
            hi[f.chart as usize] = hi[f.chart as usize].max(uv);
        }
    }
    let extent: Vec<Vec2> = (0..charts)
        .map(|c| {
            if lo[c].x <= hi[c].x {
                hi[c] - lo[c]
            } else {
                Vec2::ZERO
            }
        })
        .collect();
    // Tallest first packs shelves well; index breaks ties so the result is deterministic.
    let mut order: Vec<usize> = (0..charts).filter(|&c| extent[c] != Vec2::ZERO).collect();
    order.sort_by(|&a, &b| extent[b].y.total_cmp(&extent[a].y).then(a.cmp(&b)));
    let try_pack = |density: f32| -> Option<Vec<Vec2>> {
        let mut alloc = etagere::AtlasAllocator::new(etagere::size2(size as i32, size as i32));
        let mut origins = vec![Vec2::ZERO; charts];
        for &c in &order {
            let w = (extent[c].x * density).ceil() as i32 + 2 * PADDING;
            let h = (extent[c].y * density).ceil() as i32 + 2 * PADDING;
            let a = alloc.allocate(etagere::size2(w, h))?;
            origins[c] = Vec2::new(
                (a.rectangle.min.x + PADDING) as f32,
                (a.rectangle.min.y + PADDING) as f32,
            );
        }
        Some(origins)
    };
    let (mut lo_d, mut hi_d) = (1.0f32, 8192.0f32);
    let mut best = try_pack(lo_d).expect("charts fit at one texel per metre");
    for _ in 0..24 {
        let mid = 0.5 * (lo_d + hi_d);
        match try_pack(mid) {
            Some(o) => {
                best = o;
                lo_d = mid;
            }
            None => hi_d = mid,
        }
    }
    let placements = (0..charts)
        .map(|c| Placement {
            min: lo[c],
            origin: best[c],
        })
        .collect();
    (placements, lo_d)
}

/// The finished surface: mesh, the part of each triangle, and the atlas texel density.
pub struct Finished {
    pub mesh: SkinnedMesh,
    pub triangle_parts: Vec<u32>,
    pub texels_per_metre: f32,
}

/// Builds the triangle mesh of a (subdivided) cage with UVs in a `size`² atlas.
pub fn finish(cage: &Cage, size: u32) -> Finished {
    let (placements, density) = pack(cage, size);
    let mut vertex_of: HashMap<(u32, u32, u32), u32> = HashMap::new();
    let mut mesh = SkinnedMesh::default();
    let mut position_of: Vec<u32> = Vec::new();
    let mut triangle_parts = Vec::new();
    for f in cage.live_faces() {
        let place = &placements[f.chart as usize];
        let mut corner = [0u32; 4];
        for (k, slot) in corner.iter_mut().enumerate() {
            let texel = place.origin + (f.uv[k] - place.min) * density;
            let uv = texel / size as f32;
            let key = (f.v[k], uv.x.to_bits(), uv.y.to_bits());
            *slot = *vertex_of.entry(key).or_insert_with(|| {
                mesh.positions.push(cage.positions[f.v[k] as usize]);
                mesh.uvs.push(uv);
                position_of.push(f.v[k]);
                (mesh.positions.len() - 1) as u32
            });
        }
        // Split along the shorter diagonal.
        let p = corner.map(|i| mesh.positions[i as usize]);
        let tris = if p[0].distance(p[2]) <= p[1].distance(p[3]) {
            [[0, 1, 2], [0, 2, 3]]
        } else {
            [[0, 1, 3], [1, 2, 3]]
        };
        for t in tris {
            mesh.indices.extend(t.map(|k| corner[k]));
            triangle_parts.push(cage.chart_parts[f.chart as usize]);
        }
    }
    // Normals per cage position, so both sides of a UV seam light the same.
    let mut sums = vec![Vec3::ZERO; cage.positions.len()];
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            sums[position_of[i as usize] as usize] += n;
        }
    }
    mesh.normals = position_of
        .iter()
        .map(|&p| sums[p as usize].normalize_or(Vec3::Y))
        .collect();
    mesh.materials = vec![0; mesh.positions.len()];
    mesh.influence_offsets.push(0);
    for &p in &position_of {
        let mut w = cage.weights[p as usize].clone();
        w.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        w.truncate(MAX_INFLUENCES);
        w.retain(|e| e.1 >= MIN_WEIGHT);
        let total: f32 = w.iter().map(|e| e.1).sum();
        w.sort_by_key(|e| e.0);
        mesh.influences
            .extend(w.iter().map(|&(bone, weight)| Influence {
                bone,
                weight: weight / total,
            }));
        mesh.influence_offsets.push(mesh.influences.len() as u32);
    }
    Finished {
        mesh,
        triangle_parts,
        texels_per_metre: density,
    }
}

/// Paints a `size`² sRGB texture: every texel covered by a triangle gets
/// `color(part, rest position, normal)`; the rest is filled outwards from the charts so that
/// filtering and mipmaps never pull a background colour into a seam.
pub fn paint(
    finished: &Finished,
    size: u32,
    color: &dyn Fn(u32, Vec3, Vec3) -> Vec3,
) -> Rgba8Image {
    let n = size as usize;
    let mut rgb = vec![Vec3::ZERO; n * n];
    let mut filled = vec![false; n * n];
    let m = &finished.mesh;
    for (t, tri) in m.indices.chunks_exact(3).enumerate() {
        let part = finished.triangle_parts[t];
        let idx = [tri[0], tri[1], tri[2]].map(|i| i as usize);
        let q = idx.map(|i| m.uvs[i] * size as f32);
        let lo = q[0].min(q[1]).min(q[2]).floor().max(Vec2::ZERO);
        let hi = q[0]
            .max(q[1])
            .max(q[2])
            .ceil()
            .min(Vec2::splat(size as f32));
        let area = (q[1] - q[0]).perp_dot(q[2] - q[0]);
        if area.abs() < 1e-12 {
            continue;
        }
        for y in lo.y as usize..hi.y as usize {
            for x in lo.x as usize..hi.x as usize {
                let c = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let w0 = (q[1] - c).perp_dot(q[2] - c) / area;
                let w1 = (q[2] - c).perp_dot(q[0] - c) / area;
                let w2 = 1.0 - w0 - w1;
                // A little slack covers texel centres just outside shared edges.
                let eps = 0.02;
                if w0 < -eps || w1 < -eps || w2 < -eps {
                    continue;
                }
                let pos =
                    m.positions[idx[0]] * w0 + m.positions[idx[1]] * w1 + m.positions[idx[2]] * w2;
                let nrm =
                    (m.normals[idx[0]] * w0 + m.normals[idx[1]] * w1 + m.normals[idx[2]] * w2)
                        .normalize_or(Vec3::Y);
                rgb[y * n + x] = color(part, pos, nrm);
                filled[y * n + x] = true;
            }
        }
    }
    // Grow the charts outwards until the whole atlas is covered, so no mip level ever averages
    // in a background colour along a seam.
    for _ in 0..n {
        if filled.iter().all(|&f| f) {
            break;
        }
        let mut next_fill = Vec::new();
        for y in 0..n {
            for x in 0..n {
                if filled[y * n + x] {
                    continue;
                }
                let mut acc = Vec3::ZERO;
                let mut count = 0;
                for (dx, dy) in [(-1i32, 0i32), (1, 0), (0, -1), (0, 1)] {
                    let (sx, sy) = (x as i32 + dx, y as i32 + dy);
                    if sx >= 0 && sy >= 0 && (sx as usize) < n && (sy as usize) < n {
                        let j = sy as usize * n + sx as usize;
                        if filled[j] {
                            acc += rgb[j];
                            count += 1;
                        }
                    }
                }
                if count > 0 {
                    next_fill.push((y * n + x, acc / count as f32));
                }
            }
        }
        for (j, c) in next_fill {
            rgb[j] = c;
            filled[j] = true;
        }
    }
    let mut pixels = Vec::with_capacity(n * n * 4);
    for (c, f) in rgb.iter().zip(&filled) {
        let c = if *f { *c } else { Vec3::ZERO };
        let to8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
        pixels.extend_from_slice(&[to8(c.x), to8(c.y), to8(c.z), 255]);
    }
    Rgba8Image {
        width: size,
        height: size,
        pixels,
    }
}

/// Smooth value noise in [0, 1], deterministic, for fur and cloth variation.
pub fn noise(p: Vec3) -> f32 {
    fn hash(x: i32, y: i32, z: i32) -> f32 {
        let mut h = (x as u32).wrapping_mul(0x8da6_b343)
            ^ (y as u32).wrapping_mul(0xd816_3841)
            ^ (z as u32).wrapping_mul(0xcb1a_b31f);
        h ^= h >> 13;
        h = h.wrapping_mul(0x5bd1_e995);
        h ^= h >> 15;
        (h & 0xffff) as f32 / 65535.0
    }
    let i = p.floor();
    let f = p - i;
    let s = f * f * (Vec3::splat(3.0) - 2.0 * f);
    let (x, y, z) = (i.x as i32, i.y as i32, i.z as i32);
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let c = |dx, dy, dz| hash(x + dx, y + dy, z + dz);
    lerp(
        lerp(
            lerp(c(0, 0, 0), c(1, 0, 0), s.x),
            lerp(c(0, 1, 0), c(1, 1, 0), s.x),
            s.y,
        ),
        lerp(
            lerp(c(0, 0, 1), c(1, 0, 1), s.x),
            lerp(c(0, 1, 1), c(1, 1, 1), s.x),
            s.y,
        ),
        s.z,
    )
}

/// Three octaves of [`noise`].
pub fn fbm(p: Vec3) -> f32 {
    (noise(p) * 4.0 + noise(p * 2.03) * 2.0 + noise(p * 4.11)) / 7.0
}

/// `smoothstep(e0, e1, x)`.
pub fn smooth(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

//! A clump level's planes by view sector: the triangles each sector of view directions can
//! show, so that a tree drawn at a clump level sends the vertex shader only those.
//!
//! A clump level ([`crate::bake::foliage::billboard::clumps`]) has several upright planes a
//! clump, of which the vertex shader keeps, per view, the one or two whose view window holds
//! the line of sight from the tree's origin (`view_coverage` in `shaders/character.wgsl`), and
//! moves the others out of the clip volume. On a software rasteriser the vertex shading, the
//! clipping and the binning run on one thread, and three planes in four went through them for
//! nothing. Here the horizontal directions (undirected: a plane shows both faces) are cut into
//! [`SECTORS`] sectors, and each sector gets the triangles of the planes whose window, widened
//! by its cross-fade band and [`SWAY_MARGIN`], reaches into it: the renderer draws the sector
//! the eye is in ([`sector_of`]), and the shader still decides the rest, pixel by pixel.

use glam::Vec3;

/// Sectors of horizontal view directions, over half a turn.
pub const SECTORS: usize = 16;
/// The share of a half window its cross-fade band reaches either side of its edge
/// (`VIEW_FADE` in `shaders/character.wgsl`).
pub const VIEW_FADE: f32 = 0.25;
/// The least margin, radians, a plane's window is widened by for its branch's sway: about 6°.
pub const SWAY_MARGIN: f32 = 0.1;
/// The wind strength the margin covers: a tree's own wind goes up to 1.4 of the scene's
/// (`Agent::wind`), and the scene's is 1 unless the viewer turns it up. An instance whose
/// wind turns its planes further than the margin is drawn whole.
pub const WIND_COVERED: f32 = 1.5;

/// The margin, radians, a level's planes are filed into sectors with, where they turn by
/// `sway` radians over their clip at wind strength 1 ([`sway`]).
pub fn margin(sway: f32) -> f32 {
    SWAY_MARGIN.max(WIND_COVERED * sway)
}

/// The triangles a view of `bake` draws on average over the sectors: all of them for a
/// level without view windows.
pub fn mean_triangles(bake: &crate::bake::gpu_data::drawable::Drawable) -> f64 {
    let am = &bake.animation_space;
    let all = am.indices.len() as f64 / 3.0;
    if am.view_windows.is_empty() {
        return all;
    }
    let (_, normals) = bake.evaluate(0, 0.0, 0.0);
    let m = margin(sway(bake, &normals));
    match view_subsets(&am.indices, &am.view_windows, &normals, m) {
        Some((subsets, _)) => subsets.len() as f64 / 3.0 / SECTORS as f64,
        None => all,
    }
}

/// Times over its first clip at which [`sway`] poses a level.
const SWAY_SAMPLES: usize = 16;

/// The most any windowed vertex's normal of `bake` turns horizontally (radians, as a line)
/// from its rest direction `rest` (per vertex) over its first clip at wind strength 1.
pub fn sway(bake: &crate::bake::gpu_data::drawable::Drawable, rest: &[Vec3]) -> f32 {
    let windows = &bake.animation_space.view_windows;
    let duration = bake.animation.clips.first().map_or(0.0, |c| c.duration);
    let azimuth = |n: Vec3| n.z.atan2(n.x);
    let mut most = 0.0f32;
    for k in 0..SWAY_SAMPLES {
        let t = duration * k as f32 / SWAY_SAMPLES as f32;
        let (_, normals) = bake.evaluate(0, t, 1.0);
        for ((&w, &n), &r) in windows.iter().zip(&normals).zip(rest) {
            if w == 0.0 || glam::Vec2::new(n.x, n.z).length_squared() < 1e-8 {
                continue;
            }
            let d = (azimuth(n) - azimuth(r)).rem_euclid(std::f32::consts::PI);
            most = most.max(d.min(std::f32::consts::PI - d));
        }
    }
    most
}

/// The sector of the eye at `eye` (model space, y up, seen from the model's origin), or None
/// looking from (nearly) straight above the origin, where every plane may be drawn.
pub fn sector_of(eye: Vec3) -> Option<u32> {
    let h = glam::Vec2::new(eye.x, eye.z);
    if !h.is_finite() || h.length_squared() <= 1e-10 * eye.length_squared().max(1e-20) {
        return None;
    }
    let a = h.y.atan2(h.x).rem_euclid(std::f32::consts::PI);
    let s = (a / std::f32::consts::PI * SECTORS as f32) as usize;
    Some(s.min(SECTORS - 1) as u32)
}

/// The triangles of `indices` each sector shows, sector after sector, and each sector's range
/// (first index, count) in that list; None where no vertex has a view window. `windows` and
/// `normals` are per vertex: a vertex's view window (0: drawn from every view) and its rest
/// normal. A triangle whose first vertex has no window is in every sector.
pub fn view_subsets(
    indices: &[u32],
    windows: &[f32],
    normals: &[Vec3],
    margin: f32,
) -> Option<(Vec<u32>, Vec<[u32; 2]>)> {
    if windows.iter().all(|&w| w == 0.0) {
        return None;
    }
    let half_turn = std::f32::consts::PI;
    let step = half_turn / SECTORS as f32;
    let mut out = Vec::new();
    let mut ranges = Vec::with_capacity(SECTORS);
    for s in 0..SECTORS {
        let first = out.len() as u32;
        let (lo, hi) = (s as f32 * step, (s + 1) as f32 * step);
        for t in indices.chunks_exact(3) {
            let v = t[0] as usize;
            let w = windows.get(v).copied().unwrap_or(0.0).abs();
            let n = normals.get(v).copied().unwrap_or(Vec3::ZERO);
            let shown = w == 0.0 || {
                let reach = w * (1.0 + VIEW_FADE) + margin;
                let horizontal = glam::Vec2::new(n.x, n.z);
                // A plane lying flat faces every view alike: always drawn.
                horizontal.length_squared() < 1e-8 || {
                    let a = horizontal.y.atan2(horizontal.x).rem_euclid(half_turn);
                    line_distance_to(a, lo, hi) <= reach
                }
            };
            if shown {
                out.extend_from_slice(t);
            }
        }
        ranges.push([first, out.len() as u32 - first]);
    }
    Some((out, ranges))
}

/// The angle between the line at `a` (radians, mod π) and the nearest line of the sector
/// [lo, hi] ⊂ [0, π), both undirected.
fn line_distance_to(a: f32, lo: f32, hi: f32) -> f32 {
    if (lo..=hi).contains(&a) {
        return 0.0;
    }
    let pi = std::f32::consts::PI;
    let d = |x: f32| {
        let d = (a - x).rem_euclid(pi);
        d.min(pi - d)
    };
    d(lo).min(d(hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shader's coverage of a plane of window `w` and normal azimuth `phi` seen along
    /// horizontal direction `view` (mirror of `view_coverage` in `shaders/character.wgsl`):
    /// non-zero where it draws any of it.
    fn coverage(w: f32, phi: f32, view: f32) -> f32 {
        let c = (phi - view).cos().abs();
        let off = c.clamp(0.0, 1.0).acos();
        let band = (VIEW_FADE * w).max(1e-6);
        ((w + band - off) / (2.0 * band)).clamp(0.0, 1.0)
    }

    #[test]
    fn every_plane_a_view_draws_is_in_that_views_sector() {
        // Clumps of four planes (windows of a quarter of a half turn), at many azimuths,
        // each plane two triangles over its own four vertices.
        let w = std::f32::consts::PI / 8.0;
        let mut indices = Vec::new();
        let mut windows = Vec::new();
        let mut normals = Vec::new();
        let mut planes = Vec::new();
        for clump in 0..13 {
            for k in 0..4 {
                let phi = clump as f32 * 0.37 + k as f32 * std::f32::consts::FRAC_PI_4;
                let first = windows.len() as u32;
                for _ in 0..4 {
                    windows.push(if k % 2 == 0 { w } else { -w });
                    normals.push(Vec3::new(phi.cos(), 0.0, phi.sin()));
                }
                indices.extend([first, first + 1, first + 2, first, first + 2, first + 3]);
                planes.push((first, phi));
            }
        }
        // The wood: no window, in every sector.
        let wood = windows.len() as u32;
        windows.extend([0.0; 3]);
        normals.extend([Vec3::Y; 3]);
        indices.extend([wood, wood + 1, wood + 2]);
        let (subsets, ranges) = view_subsets(&indices, &windows, &normals, SWAY_MARGIN).unwrap();
        assert_eq!(ranges.len(), SECTORS);
        let mut drawn = 0usize;
        for view_step in 0..720 {
            let view = view_step as f32 / 720.0 * std::f32::consts::TAU;
            let eye = Vec3::new(view.cos(), 0.3, view.sin()) * 10.0;
            let [first, count] = ranges[sector_of(eye).unwrap() as usize];
            let subset = &subsets[first as usize..(first + count) as usize];
            assert!(subset.chunks(3).any(|t| t[0] == wood), "the wood at {view}");
            for &(v, phi) in &planes {
                if coverage(w, phi, view) > 0.0 {
                    assert!(
                        subset.chunks(3).any(|t| t[0] == v),
                        "the plane at {phi} seen along {view}"
                    );
                }
            }
            drawn += subset.len();
        }
        // A sector draws well under all four planes of a clump.
        let mean = drawn as f32 / 720.0 / indices.len() as f32;
        assert!(mean < 0.6, "{mean:.2} of the triangles a view");
        // From straight above: no sector (all drawn).
        assert_eq!(sector_of(Vec3::new(0.0, 5.0, 0.0)), None);
        assert_eq!(
            view_subsets(&indices[..6], &[0.0; 4], &normals[..4], SWAY_MARGIN),
            None
        );
        assert_eq!(margin(0.0), SWAY_MARGIN);
        assert_eq!(margin(0.2), WIND_COVERED * 0.2);
    }
}

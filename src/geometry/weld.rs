//! Welding unindexed meshes by position, and computing normals where a file has none.
//!
//! Unindexed glTF (the Khronos Fox, for one) gives every triangle its own three vertices. Nothing
//! can be simplified or smoothly lit until corners that coincide are shared, so vertices at the
//! same position are merged when they also agree on everything else: a UV seam keeps its split
//! vertices, because the two sides map to different places in the texture.

use crate::model::SkinnedMesh;
use glam::Vec3;
use rustc_hash::FxHashMap;

/// Positions closer than this fraction of the bounding-box diagonal count as the same point.
pub const WELD_TOLERANCE: f32 = 1e-6;

/// Assigns every position a group id; positions within `tolerance` of a group's first member
/// join that group. Ids are dense and numbered in order of first appearance.
pub fn position_groups(positions: &[Vec3], tolerance: f32) -> Vec<u32> {
    let tol = tolerance.max(f32::MIN_POSITIVE);
    let cell = |p: Vec3| {
        let c = (p / tol).floor();
        (c.x as i64, c.y as i64, c.z as i64)
    };
    // Fx hashing: the keys are plain integers, and this runs for every vertex of a model
    // several times in a bake.
    let mut grid: rustc_hash::FxHashMap<(i64, i64, i64), Vec<u32>> = Default::default();
    let mut group_of_rep = vec![u32::MAX; positions.len()];
    let mut groups = Vec::with_capacity(positions.len());
    let mut next = 0u32;
    for (i, &p) in positions.iter().enumerate() {
        let (cx, cy, cz) = cell(p);
        let mut found = None;
        'search: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(reps) = grid.get(&(cx + dx, cy + dy, cz + dz)) {
                        for &r in reps {
                            if positions[r as usize].distance(p) <= tol {
                                found = Some(group_of_rep[r as usize]);
                                break 'search;
                            }
                        }
                    }
                }
            }
        }
        let g = match found {
            Some(g) => g,
            None => {
                let g = next;
                next += 1;
                grid.entry((cx, cy, cz)).or_default().push(i as u32);
                group_of_rep[i] = g;
                g
            }
        };
        groups.push(g);
    }
    groups
}

/// Tolerance for a set of positions: [`WELD_TOLERANCE`] of their bounding-box diagonal.
pub fn tolerance_for(positions: &[Vec3]) -> f32 {
    crate::model::Bounds::of(positions.iter().copied())
        .map(|b| b.diagonal() * WELD_TOLERANCE)
        .unwrap_or(0.0)
}

/// Welds vertices: returns, for every vertex, the index of the first vertex at the same position
/// for which `same(first, v)` holds (itself if none).
pub fn weld_map(positions: &[Vec3], same: impl Fn(usize, usize) -> bool) -> Vec<u32> {
    let groups = position_groups(positions, tolerance_for(positions));
    let mut members: FxHashMap<u32, Vec<u32>> = FxHashMap::default();
    let mut rep = Vec::with_capacity(positions.len());
    for (v, &g) in groups.iter().enumerate() {
        let list = members.entry(g).or_default();
        let r = list
            .iter()
            .copied()
            .find(|&m| same(m as usize, v))
            .unwrap_or(v as u32);
        if r == v as u32 {
            list.push(r);
        }
        rep.push(r);
    }
    rep
}

/// Computes area-weighted vertex normals for the vertices flagged in `needs`. Normals are
/// accumulated per position, not per vertex, so the two sides of a UV seam get the same normal
/// and the seam does not show in the lighting.
pub fn compute_normals(mesh: &mut SkinnedMesh, needs: &[bool]) {
    let groups = position_groups(&mesh.positions, tolerance_for(&mesh.positions));
    let group_count = groups.iter().copied().max().map_or(0, |m| m as usize + 1);
    let mut sum = vec![Vec3::ZERO; group_count];
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
        // The cross product's length is twice the area: area weighting for free.
        let n = (b - a).cross(c - a);
        for &i in t {
            sum[groups[i as usize] as usize] += n;
        }
    }
    for (v, &need) in needs.iter().enumerate() {
        if need {
            mesh.normals[v] = sum[groups[v] as usize].normalize_or(Vec3::Y);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_merge_near_points_only() {
        let p = [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1e-9, 0.0, 0.0),
            Vec3::new(1.0, 1e-9, 0.0),
            Vec3::new(0.5, 0.0, 0.0),
        ];
        assert_eq!(position_groups(&p, 1e-6), vec![0, 1, 0, 1, 2]);
    }

    #[test]
    fn weld_keeps_seams_split() {
        let p = [Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::X];
        let uv = [0.0, 0.0, 1.0, 0.0];
        let rep = weld_map(&p, |a, b| uv[a] == uv[b]);
        assert_eq!(rep, vec![0, 0, 2, 3]);
    }
}

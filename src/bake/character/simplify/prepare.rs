//! What every method's simplifier of one model starts from, made once: welded positions, the
//! mesh's topology and kinds, texture charts, posed positions and parts.

use super::influence::Influence64;
use super::mesh::{Kind, Mesh};
use super::metric::influences64;
use super::metric::rest_position;
use super::posed::Posed;
use super::sequence::Stats;
use crate::bake::gpu_data::animation_space::AnimationSpaceMesh;
use glam::{Affine3A, DVec2, DVec3};
use rstar::RTree;
use rstar::primitives::GeomWithData;

/// A position in the index the pruning looks for anchors in.
pub(crate) type Located = GeomWithData<[f64; 3], u32>;

/// What the simplifier makes of a character before its first step, whatever the method: the
/// mesh's topology and kinds, its welded positions, texture charts, posed positions and
/// connected parts. On a 2-million-triangle model that is about five seconds and half a
/// gigabyte, which each of the three methods made again; a bake of several methods makes it
/// once and each method's simplifier starts from it ([`simplify_prepared`](super::simplify_prepared)).
pub struct Prepared {
    pub(crate) rest_bones: Vec<Affine3A>,
    pub(crate) poses: Vec<Vec<Affine3A>>,
    pub(crate) materials: Vec<u16>,
    pub(crate) textured: Vec<bool>,
    pub(crate) infl: Vec<Vec<Influence64>>,
    pub(crate) rest: Vec<DVec3>,
    pub(crate) normals: Vec<DVec3>,
    pub(crate) positions: Vec<u32>,
    pub(crate) mesh: Mesh,
    pub(crate) uv: Vec<DVec2>,
    pub(crate) charts: TextureCharts,
    pub(crate) posed: Posed,
    pub(crate) influences: u64,
    pub(crate) parts: Vec<Vec<u32>>,
    pub(crate) part_of: Vec<u32>,
    pub(crate) located: RTree<Located>,
    pub(crate) stats: Stats,
    pub(crate) diagonal: f64,
    /// Per position: its rank when positions are sorted by what they are (see
    /// [`content_order`]); `u32::MAX` for ids that are not positions.
    pub(crate) content_rank: Vec<u32>,
}

impl Prepared {
    /// Prepares `am` (a character's full-detail mesh) with its rest-pose bone matrices, sampled
    /// poses and which materials are textured (as [`SimplifyInput`](super::input::SimplifyInput) has them).
    pub fn new(
        am: &AnimationSpaceMesh,
        rest_bones: &[Affine3A],
        poses: &[Vec<Affine3A>],
        textured: &[bool],
    ) -> Prepared {
        let start = web_time::Instant::now();
        let n = am.vertex_count();
        let infl = influences64(am);
        let rest: Vec<DVec3> = infl.iter().map(|i| rest_position(rest_bones, i)).collect();
        let normals: Vec<DVec3> = (0..n)
            .map(|v| {
                am.influences_of(v)
                    .iter()
                    .map(|i| {
                        let m = rest_bones[i.bone as usize].matrix3;
                        (m * i.n).as_dvec3()
                    })
                    .sum::<DVec3>()
                    .normalize_or_zero()
            })
            .collect();
        let positions = super::mesh::weld_positions(&rest, &infl);
        let diagonal = rest
            .iter()
            .fold(None, |b: Option<(DVec3, DVec3)>, &p| {
                Some(b.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))))
            })
            .map_or(0.0, |(lo, hi)| (hi - lo).length());
        let mut mesh = Mesh::new(&am.indices, positions.clone());
        mesh.classify_all();
        let uv: Vec<DVec2> = am.uvs.iter().map(|u| u.as_dvec2()).collect();
        let charts = TextureCharts::measure(&mesh, &uv, &rest);
        let posed = Posed::new(n, poses.len(), |v, s| {
            rest_position(&poses[s], &infl[v]).as_vec3()
        });
        let influences: u64 = (0..n)
            .filter(|&v| mesh.refs[v] > 0)
            .map(|v| infl[mesh.pos(v as u32) as usize].len() as u64)
            .sum();
        let parts = mesh.components();
        let mut part_of = vec![u32::MAX; n];
        for (i, part) in parts.iter().enumerate() {
            for &u in part {
                part_of[u as usize] = i as u32;
            }
        }
        let located = RTree::bulk_load(
            parts
                .iter()
                .flatten()
                .map(|&u| Located::new(rest[u as usize].to_array(), u))
                .collect(),
        );
        let stats = Stats {
            dropped_triangles: mesh.dropped_triangles as u32,
            locked_positions: (0..n)
                .filter(|&u| mesh.alive[u] && matches!(mesh.kind[u], Kind::Complex | Kind::Locked))
                .count() as u32,
            texture_parameterisation: charts.valid.iter().any(|&v| v),
            parts: parts.len() as u32,
            ..Stats::default()
        };
        let content_rank = content_order(&mesh, &rest, &infl, &uv, &normals, &am.materials);
        log::debug!(
            "the simplifier's preparation of {n} vertices took {:.2} s",
            start.elapsed().as_secs_f64()
        );
        Prepared {
            rest_bones: rest_bones.to_vec(),
            poses: poses.to_vec(),
            materials: am.materials.clone(),
            textured: textured.to_vec(),
            infl,
            rest,
            normals,
            positions,
            mesh,
            uv,
            charts,
            posed,
            influences,
            parts,
            part_of,
            located,
            stats,
            diagonal,
            content_rank,
        }
    }

    /// The tie order numbered `order` of this character's positions (see [`Ties`]).
    pub fn ties(&self, order: u32) -> Ties {
        Ties::new(&self.content_rank, order)
    }
}

/// The order in which the simplifier breaks the ties left between steps of equal cost and
/// equal edge length (on the cost grid, a flat region's free collapses are many, and a
/// mirror-symmetric character's edges come in equal pairs): a rank per position.
///
/// The rank is made from what each position is, never from where the file lists it, so that
/// the same mesh in any vertex and triangle order simplifies alike (issue: comparisons with
/// error bars). Ranked by vertex index instead, a walker listed backwards took its flat
/// regions' free collapses in another order and its coarse levels' errors moved 1.2–1.8×.
/// Order 0 is the content order itself: positions by rest position, then skinning, then
/// wedges. Order k > 0 is a fixed pseudo-random permutation of it, what another file order
/// would have done to an index tie-break: the spread of a method's error over several orders
/// is how much its greedy choices among equals matter, `report`'s band.
pub struct Ties {
    pub(crate) order: u32,
    pub(crate) rank: Vec<u32>,
}

impl Ties {
    fn new(content_rank: &[u32], order: u32) -> Ties {
        if order == 0 {
            return Ties {
                order,
                rank: content_rank.to_vec(),
            };
        }
        let mut ids: Vec<u32> = (0..content_rank.len() as u32)
            .filter(|&u| content_rank[u as usize] != u32::MAX)
            .collect();
        let key = |u: u32| {
            let c = content_rank[u as usize];
            (splitmix64((u64::from(order) << 32) | u64::from(c)), c)
        };
        ids.sort_unstable_by_key(|&u| key(u));
        let mut rank = vec![u32::MAX; content_rank.len()];
        for (i, &u) in ids.iter().enumerate() {
            rank[u as usize] = i as u32;
        }
        Ties { order, rank }
    }
}

/// A 64-bit mix (Steele et al.'s SplitMix64 finaliser): a fixed permutation of ranks per order
/// without a random-number crate.
fn splitmix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// Every position's rank in the order of what it is: rest position, then skinning (bones and
/// their `p_i`, by bone), then its wedges' texture coordinates, normals and materials (each
/// position's wedges sorted by those first). Two positions equal in all of that are copies of
/// one point and either may go first; only they are ranked by index.
fn content_order(
    mesh: &Mesh,
    rest: &[DVec3],
    infl: &[Vec<Influence64>],
    uv: &[DVec2],
    normals: &[DVec3],
    materials: &[u16],
) -> Vec<u32> {
    use std::cmp::Ordering;
    let n = mesh.position.len();
    let vec3 = super::mesh::point_order;
    let wedge = |a: u32, b: u32| -> Ordering {
        let (a, b) = (a as usize, b as usize);
        (uv[a].x.total_cmp(&uv[b].x))
            .then(uv[a].y.total_cmp(&uv[b].y))
            .then_with(|| vec3(normals[a], normals[b]))
            .then_with(|| materials.get(a).cmp(&materials.get(b)))
    };
    let skin = |a: &[Influence64], b: &[Influence64]| -> Ordering {
        a.len().cmp(&b.len()).then_with(|| {
            a.iter()
                .zip(b)
                .map(|(x, y)| {
                    x.bone.cmp(&y.bone).then_with(|| {
                        x.p.iter()
                            .zip(&y.p)
                            .map(|(s, t)| s.total_cmp(t))
                            .find(|o| o.is_ne())
                            .unwrap_or(Ordering::Equal)
                    })
                })
                .find(|o| o.is_ne())
                .unwrap_or(Ordering::Equal)
        })
    };
    let wedges: Vec<super::mesh::Wedges> = mesh
        .wedges
        .iter()
        .map(|w| {
            let mut w = w.clone();
            w.sort_by(|&a, &b| wedge(a, b));
            w
        })
        .collect();
    let mut ids: Vec<u32> = (0..n as u32)
        .filter(|&u| mesh.alive[u as usize] && mesh.pos(u) == u)
        .collect();
    ids.sort_by(|&a, &b| {
        let (ai, bi) = (a as usize, b as usize);
        vec3(rest[ai], rest[bi])
            .then_with(|| skin(&infl[ai], &infl[bi]))
            .then_with(|| {
                let (wa, wb) = (&wedges[ai], &wedges[bi]);
                wa.len().cmp(&wb.len()).then_with(|| {
                    wa.iter()
                        .zip(wb.iter())
                        .map(|(&x, &y)| wedge(x, y))
                        .find(|o| o.is_ne())
                        .unwrap_or(Ordering::Equal)
                })
            })
            .then(a.cmp(&b))
    });
    let mut rank = vec![u32::MAX; n];
    for (i, &u) in ids.iter().enumerate() {
        rank[u as usize] = i as u32;
    }
    rank
}

/// Where a model's texture coordinates are a parameterisation.
pub(crate) struct TextureCharts {
    /// Per triangle: its texture coordinates span area, at least a thousandth of what the
    /// model's usual texel density gives a triangle of its size.
    pub(crate) valid: Vec<bool>,
    /// Metres of surface per texture unit: the median over triangles with texture area.
    pub(crate) metres_per_unit: f64,
    /// How far off its outline's line a chart outline vertex may lie and still slide along it.
    pub(crate) tolerance: f64,
}

impl TextureCharts {
    pub(crate) fn measure(mesh: &Mesh, uv: &[DVec2], rest: &[DVec3]) -> TextureCharts {
        let areas: Vec<(f64, f64)> = mesh
            .tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|r| uv[r as usize]);
                let [x, y, z] = t.map(|r| rest[mesh.pos(r) as usize]);
                (
                    0.5 * (b - a).perp_dot(c - a).abs(),
                    0.5 * (y - x).cross(z - x).length(),
                )
            })
            .collect();
        let mut scales: Vec<f64> = areas
            .iter()
            .filter(|(uv, xyz)| *uv > 0.0 && *xyz > 0.0)
            .map(|(uv, xyz)| (xyz / uv).sqrt())
            .collect();
        scales.sort_by(f64::total_cmp);
        let metres_per_unit = scales.get(scales.len() / 2).copied().unwrap_or(0.0);
        let valid = areas
            .iter()
            .map(|&(uv, xyz)| {
                metres_per_unit > 0.0 && uv * metres_per_unit * metres_per_unit >= 1e-3 * xyz
            })
            .collect();
        let (lo, hi) = uv.iter().fold(
            (DVec2::splat(f64::MAX), DVec2::splat(f64::MIN)),
            |(lo, hi), &u| (lo.min(u), hi.max(u)),
        );
        TextureCharts {
            valid,
            metres_per_unit,
            tolerance: 1e-5 * (hi - lo).length().max(1e-6),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every tie order ranks each position once; an order is the same every time it is made,
    /// and orders other than the content order shuffle it.
    #[test]
    fn a_tie_order_is_a_fixed_permutation_of_the_positions() {
        let content: Vec<u32> = vec![3, u32::MAX, 0, 2, 1, u32::MAX, 4, 5, 6, 7];
        let zero = Ties::new(&content, 0);
        assert_eq!(zero.rank, content);
        for order in 1..4 {
            let ties = Ties::new(&content, order);
            let mut ranks: Vec<u32> = ties
                .rank
                .iter()
                .copied()
                .filter(|&r| r != u32::MAX)
                .collect();
            ranks.sort_unstable();
            assert_eq!(ranks, (0..8).collect::<Vec<u32>>());
            assert_eq!(ties.rank[1], u32::MAX);
            assert_eq!(ties.rank, Ties::new(&content, order).rank);
            assert_ne!(ties.rank, content, "order {order}");
        }
    }
}

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
        }
    }
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

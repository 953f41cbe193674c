//! Meshes written the way exporters write them, for the test models with real-world
//! properties ([`super::split_tube`], [`super::armour`]).
//!
//! A DCC tool stores positions once and gives each face corner a smoothing group and a texture
//! coordinate; the exporter then writes one indexed render vertex per distinct (position,
//! smoothing group, texture coordinate). So a position on a hard edge or a UV seam is split into
//! several render vertices. Those copies are rarely bit-identical after the exporter's
//! transforms and weight normalisation: [`FacetBuilder::build`] can perturb them by a rounding
//! error, so the importer and simplifier meet what they meet in the field.

use super::cage::Weights;
use crate::model::{Influence, SkinnedMesh};
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// One triangle: three positions, its smoothing group and its corners' texture coordinates.
#[derive(Clone, Copy, Debug)]
struct Facet {
    p: [u32; 3],
    group: u32,
    uv: [Vec2; 3],
}

/// Positions with their skin weights, and triangles over them.
#[derive(Clone, Debug, Default)]
pub struct FacetBuilder {
    pub positions: Vec<Vec3>,
    weights: Vec<Weights>,
    facets: Vec<Facet>,
}

impl FacetBuilder {
    /// A position skinned by `weights` (bone, weight), returned as its id.
    pub fn point(&mut self, p: Vec3, weights: Weights) -> u32 {
        self.positions.push(p);
        self.weights.push(weights);
        (self.positions.len() - 1) as u32
    }

    /// A triangle, counter-clockwise seen from outside.
    pub fn triangle(&mut self, p: [u32; 3], group: u32, uv: [Vec2; 3]) {
        self.facets.push(Facet { p, group, uv });
    }

    /// A quad `a b c d` (counter-clockwise) as two triangles split along `a c`.
    pub fn quad(&mut self, p: [u32; 4], group: u32, uv: [Vec2; 4]) {
        self.triangle([p[0], p[1], p[2]], group, [uv[0], uv[1], uv[2]]);
        self.triangle([p[0], p[2], p[3]], group, [uv[0], uv[2], uv[3]]);
    }

    pub fn triangle_count(&self) -> usize {
        self.facets.len()
    }

    /// The centre of facet `i` (in the order added), at rest.
    pub fn facet_centre(&self, i: usize) -> Vec3 {
        self.facets[i]
            .p
            .iter()
            .map(|&p| self.positions[p as usize])
            .sum::<Vec3>()
            / 3.0
    }

    /// The indexed mesh: one render vertex per distinct (position, smoothing group, texture
    /// coordinate), normals averaged (area-weighted) over the faces of one smoothing group at
    /// a position. With `rounding > 0`, every copy of a position after the first is moved by up
    /// to `rounding` (a fraction of the bounding-box diagonal) and its weights by up to
    /// `rounding` before renormalising, deterministically.
    pub fn build(&self, rounding: f32) -> SkinnedMesh {
        self.build_coloured(rounding, |_, _| 0)
    }

    /// [`Self::build`], every triangle in the material `material(group, facet)` gives it (by
    /// its smoothing group and its index in the order added): a corner where two materials
    /// meet is split like one on a hard edge.
    pub fn build_coloured(
        &self,
        rounding: f32,
        mut material: impl FnMut(u32, usize) -> u16,
    ) -> SkinnedMesh {
        let mut vertex_of: HashMap<(u32, u32, u32, u32, u16), u32> = HashMap::new();
        let mut mesh = SkinnedMesh::default();
        let mut normal_sum: HashMap<(u32, u32), Vec3> = HashMap::new();
        for f in &self.facets {
            let [a, b, c] = f.p.map(|i| self.positions[i as usize]);
            let n = (b - a).cross(c - a);
            for &p in &f.p {
                *normal_sum.entry((p, f.group)).or_insert(Vec3::ZERO) += n;
            }
        }
        let diagonal =
            crate::model::Bounds::of(self.positions.iter().copied()).map_or(1.0, |b| b.diagonal());
        let mut rng = fastrand::Rng::with_seed(0x5eed);
        let mut copies = vec![0u32; self.positions.len()];
        mesh.influence_offsets.push(0);
        for (i, f) in self.facets.iter().enumerate() {
            let m = material(f.group, i);
            for k in 0..3 {
                let (p, uv) = (f.p[k], f.uv[k]);
                let key = (p, f.group, uv.x.to_bits(), uv.y.to_bits(), m);
                let v = *vertex_of.entry(key).or_insert_with(|| {
                    let copy = copies[p as usize];
                    copies[p as usize] += 1;
                    let jitter = |rng: &mut fastrand::Rng| {
                        if copy == 0 {
                            0.0
                        } else {
                            (rng.f32() * 2.0 - 1.0) * rounding
                        }
                    };
                    let offset = Vec3::new(jitter(&mut rng), jitter(&mut rng), jitter(&mut rng));
                    mesh.positions
                        .push(self.positions[p as usize] + offset * diagonal);
                    mesh.normals
                        .push(normal_sum[&(p, f.group)].normalize_or(Vec3::Y));
                    mesh.uvs.push(uv);
                    mesh.materials.push(m);
                    let w: Vec<(u32, f32)> = self.weights[p as usize]
                        .iter()
                        .map(|&(bone, w)| (bone, (w + jitter(&mut rng) * w).max(1e-6)))
                        .collect();
                    let total: f32 = w.iter().map(|e| e.1).sum();
                    mesh.influences
                        .extend(w.iter().map(|&(bone, weight)| Influence {
                            bone,
                            weight: weight / total,
                        }));
                    mesh.influence_offsets.push(mesh.influences.len() as u32);
                    (mesh.positions.len() - 1) as u32
                });
                mesh.indices.push(v);
            }
        }
        mesh
    }
}

/// Weights from a chain coordinate list, renormalised and sorted by bone.
pub fn normalised(mut w: Weights) -> Weights {
    w.retain(|e| e.1 > 1e-6);
    let total: f32 = w.iter().map(|e| e.1).sum();
    for e in &mut w {
        e.1 /= total;
    }
    w.sort_by_key(|e| e.0);
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hard_edges_and_seams_split_render_vertices() {
        let mut b = FacetBuilder::default();
        let p: Vec<u32> = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::Y,
            Vec3::new(2.0, 0.0, 1.0),
        ]
        .into_iter()
        .map(|x| b.point(x, vec![(0, 1.0)]))
        .collect();
        // Two faces of one group share an edge: 4 vertices. A third face in another group
        // splits positions 1 and 2.
        b.quad([p[0], p[1], p[2], p[3]], 0, [Vec2::ZERO; 4]);
        b.triangle([p[1], p[4], p[2]], 1, [Vec2::ZERO; 3]);
        let m = b.build(0.0);
        assert_eq!(m.vertex_count(), 7);
        assert_eq!(m.triangle_count(), 3);
        // Exact copies without rounding; perturbed copies with it.
        assert_eq!(m.positions[m.indices[6] as usize], m.positions[1]);
        let r = b.build(1e-6);
        assert_ne!(r.positions[r.indices[6] as usize], r.positions[1]);
        assert!(r.positions[r.indices[6] as usize].distance(r.positions[1]) < 1e-5);
    }
}

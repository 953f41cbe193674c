//! Animation space (Merry et al. §2.1.2) equals classic linear blend skinning, to 1e-5 of the
//! model's size, on every model lodlab ships or is tested with, at several times of every clip.

use lodlab::anim::linear_blend_skinning;
use lodlab::bake::gpu_data::animation_space::AnimationSpaceMesh;
use lodlab::model::{Bounds, Model};

fn models() -> Vec<Model> {
    let mut models = vec![
        lodlab::import::load_model("horse").unwrap(),
        lodlab::import::load_model("walker").unwrap(),
    ];
    for name in ["Fox.glb", "SimpleSkin.gltf"] {
        if let Some(path) = crate::common::shared_model(name) {
            models.push(lodlab::import::gltf::load(&path).unwrap());
        }
    }
    models
}

#[test]
fn animation_space_equals_linear_blend_skinning() {
    for m in models() {
        let am = AnimationSpaceMesh::from_skinned(&m.mesh, &m.skeleton);
        let mut checked = 0;
        for clip in &m.clips {
            for k in 0..6 {
                let t = clip.duration * k as f32 / 5.0 + 0.013;
                let g = lodlab::anim::bone_matrices(&m.skeleton, Some(clip), t);
                let (as_positions, as_normals) = am.evaluate(&g);
                let lbs = linear_blend_skinning(&m.mesh, &m.skeleton, &g);
                let size = Bounds::of(lbs.iter().copied()).unwrap().diagonal();
                for (v, (a, b)) in as_positions.iter().zip(&lbs).enumerate() {
                    assert!(
                        (*a - *b).length() <= 1e-5 * size,
                        "{} {} t={t} vertex {v}: {a} vs {b}",
                        m.name,
                        clip.name
                    );
                }
                // Normals go through the vector parts: the same direction as blending the
                // normal with the skinning matrices.
                for (v, n) in as_normals.iter().enumerate() {
                    let lbs_n: glam::Vec3 = m
                        .mesh
                        .influences_of(v)
                        .iter()
                        .map(|i| {
                            let skin = glam::Mat4::from(g[i.bone as usize])
                                * m.skeleton.inverse_bind[i.bone as usize];
                            i.weight * skin.transform_vector3(m.mesh.normals[v])
                        })
                        .sum();
                    let cos = n.normalize_or_zero().dot(lbs_n.normalize_or_zero());
                    assert!(
                        cos > 0.99999,
                        "{} vertex {v}: normals differ ({cos})",
                        m.name
                    );
                }
                checked += 1;
            }
        }
        assert!(checked >= 6, "{}: no clips checked", m.name);
        // And the clips really move the mesh.
        let c = &m.clips[0];
        let a = am
            .evaluate(&lodlab::anim::bone_matrices(&m.skeleton, Some(c), 0.0))
            .0;
        let b = am
            .evaluate(&lodlab::anim::bone_matrices(
                &m.skeleton,
                Some(c),
                c.duration * 0.37,
            ))
            .0;
        assert!(
            a.iter().zip(&b).any(|(x, y)| x.distance(*y) > 1e-3),
            "{} does not animate",
            m.name
        );
    }
}

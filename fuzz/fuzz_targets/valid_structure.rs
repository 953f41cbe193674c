//! Every stage on valid files of random structure: the bytes describe a node graph, skins,
//! rigid parts, clips and materials around small random meshes
//! (`lodlab::generate::wild::structure`), written as glTF that glTF-Validator passes. Under
//! small limits (what the generator makes fits them; a fuzzer-grown file past them is refused
//! in one line), it must load or be refused in one line, bake (by one method, chosen by the
//! input's length) with levels cut by small triangle budgets, and every level `lodlab export`
//! writes, and the file holding them all under MSFT_lod, must read back.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodlab::app::export::level_meshes;
use lodlab::bake::character::lod::{LodOptions, bake_lods, model_height};
use lodlab::bake::character::simplify::Method;
use lodlab::generate::glb::{to_glb, to_lod_glb};
use lodlab::generate::wild::structure::structure_file;
use lodlab::import::gltf::from_bytes;
use lodlab::import::validate::Limits;
use lodlab::model::{Model, SkinnedMesh};

fuzz_target!(|data: &[u8]| {
    let base = std::path::Path::new("/nonexistent-lodlab-fuzz");
    let limits = Limits {
        vertices: 2_000,
        triangles: 2_000,
        joints: 16,
        clips_seconds: 30.0,
        texture_mb: 1,
        decoded_mb: 4,
        ..Limits::DEFAULT
    };
    let (model, _) = match from_bytes("fuzz", structure_file(data), base, &limits) {
        Ok(m) => m,
        Err(e) => {
            assert!(!e.contains('\n'), "{e}");
            return;
        }
    };
    let triangles = model.mesh.triangle_count() as u32;
    let options = LodOptions {
        budgets: Some(vec![(triangles * 2 / 3).max(1), (triangles / 3).max(1), 1]),
        ..LodOptions::from_pixels(1.5, model_height(&model))
    };
    // One method an input, by its length (the mutator changes lengths all the time): a third
    // of the work an execution, so a run reaches a million executions in an hour on two
    // cores, and every method still meets every kind of input.
    for method in [Method::ALL[data.len() % Method::ALL.len()]] {
        let lods = bake_lods(&model, method, &options, &|_| {});
        assert!(!lods.levels.is_empty());
        assert!(lods.levels[0].mesh.draws(), "full detail draws");
        // What `lodlab export` writes.
        let meshes = level_meshes(&model, &lods);
        for mesh in &meshes {
            let bytes = to_glb(&Model {
                mesh: mesh.clone(),
                ..model.clone()
            });
            let (back, _) = from_bytes("level", bytes, base, &limits)
                .expect("an exported level reads back");
            assert!(back.mesh.triangle_count() <= mesh.triangle_count());
        }
        let refs: Vec<&SkinnedMesh> = meshes.iter().collect();
        let coverage: Vec<f32> = (0..refs.len()).map(|k| 0.5f32.powi(k as i32 + 1)).collect();
        let all = to_lod_glb(&model, &refs, &coverage, "fuzz");
        from_bytes("levels", all, base, &limits).expect("the MSFT_lod file reads back");
    }
});

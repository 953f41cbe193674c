//! Every stage on valid files of random meshes: the bytes describe a mesh
//! (`lodlab::generate::wild::random`: coincident points, degenerate and repeated triangles,
//! unused vertices, several skins), written as a glTF file the Khronos validator passes. It
//! must load (or be refused in one line where nothing in it draws), bake by every method
//! without a panic, and every level it exports must read back with the level's triangles.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodlab::bake::character::lod::bake_lods;
use lodlab::bake::character::simplify::Method;
use lodlab::generate::glb::to_glb;
use lodlab::generate::wild::random::random_file;
use lodlab::import::gltf::from_bytes;
use lodlab::import::validate::Limits;
use lodlab::model::Model;

fuzz_target!(|data: &[u8]| {
    let base = std::path::Path::new("/nonexistent-lodlab-fuzz");
    let limits = Limits::default();
    let Ok((model, _)) = from_bytes("fuzz", random_file(data), base, &limits) else {
        return;
    };
    let options = lodlab::runtime::levels::runtime_options(&model);
    for method in Method::ALL {
        let lods = bake_lods(&model, method, &options, &|_| {});
        for mesh in lodlab::app::export::level_meshes(&model, &lods) {
            let triangles = mesh.triangle_count();
            let bytes = to_glb(&Model {
                mesh,
                ..model.clone()
            });
            let (back, _) = from_bytes("level", bytes, base, &limits)
                .expect("an exported level reads back");
            assert!(back.mesh.triangle_count() <= triangles);
        }
    }
});

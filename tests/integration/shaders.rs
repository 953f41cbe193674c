//! Every WGSL module the renderer builds parses and validates with naga, without a GPU.

#[test]
fn every_shader_module_validates() {
    for shader in lodlab::render::shaders::ALL {
        let source = shader.source();
        let module = naga::front::wgsl::parse_str(&source)
            .unwrap_or_else(|e| panic!("{}: {}", shader.name, e.emit_to_string(&source)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{}: {e:?}", shader.name));
        assert!(
            !module.entry_points.is_empty(),
            "{} has no entry points",
            shader.name
        );
    }
}

#[test]
fn shader_files_are_all_used() {
    // Every file under shaders/ is composed into at least one module.
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let all: String = lodlab::render::shaders::ALL
        .iter()
        .map(|s| s.source())
        .collect();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(all.contains(&text), "{} is not compiled in", path.display());
    }
}

//! `lodlab export`: a character's levels of detail by one method as glTF, for other engines:
//! one `.glb` per level (skin, clips, materials and textures with each), and one `.glb` holding
//! every level under `MSFT_lod`, with `MSFT_screencoverage` switching hints. A tree's chain of
//! billboard clouds goes out the same way ([`tree`]).
//!
//! glTF skins by linear blending, so each level goes back from animation space to joint weights
//! ([`AnimationSpaceMesh::to_skinned`]): exact for `rest-pose` and `as`, whose levels keep their
//! vertices as they were; for `as+is` exact in the rest pose and an approximation elsewhere,
//! since influence simplification gives a vertex a position per bone. A vertex with more than
//! four influences gets several `JOINTS_n`/`WEIGHTS_n` sets, four influences a set.
//!
//! [`AnimationSpaceMesh::to_skinned`]: crate::bake::gpu_data::animation_space::AnimationSpaceMesh::to_skinned

use crate::app::cli::ExportArgs;
use std::process::ExitCode;

pub mod exported;
pub mod tree;

use exported::{Exported, ExportedLevel, coverage_hints, file_stem, switch_px};

use crate::bake::cache::{LodCache, Origin};
use crate::bake::character::lod::{SkinnedLods, model_height};
use crate::generate::glb::{to_glb, to_lod_glb};
use crate::import::{Imported, import};
use crate::model::{Model, SkinnedMesh};
use anyhow::Result;

/// `model` with `mesh` in place of its own.
fn with_mesh(model: &Model, mesh: SkinnedMesh) -> Model {
    Model {
        mesh,
        ..model.clone()
    }
}

/// The meshes `export` writes for `lods`' levels: each level skinned as glTF skins
/// (linear blend skinning), finest first, down to the coarsest that still draws. Animation
/// space holds more than a skin does: after influence simplification two vertices at one rest
/// point can move apart in animation space and not as a skin, so a coarse level of a few
/// triangles can draw nothing once skinned (found by the `valid_structure` fuzzer); such a
/// level, and any after it, is left out.
pub fn level_meshes(model: &Model, lods: &SkinnedLods) -> Vec<SkinnedMesh> {
    let mut meshes: Vec<SkinnedMesh> = Vec::with_capacity(lods.levels.len());
    for level in &lods.levels {
        let mesh = level.mesh.to_skinned(&model.skeleton);
        if !meshes.is_empty() && !mesh.draws() {
            break;
        }
        meshes.push(mesh);
    }
    meshes
}

/// Writes the levels `lodlab export` is asked for by `opts`.
pub fn run(opts: &ExportArgs, inputs: &crate::runtime::spec::BakeInputs) -> Result<Exported> {
    let Some(name) = opts.model.as_deref().or(opts.model_flag.as_deref()) else {
        anyhow::bail!("export needs a model: lodlab export --model NAME|PATH --out DIR");
    };
    let Imported { model, source_hash } = import(name, &inputs.import)?;
    let hash = source_hash;
    crate::atomic::make_folder(&opts.out)?;
    let cache = LodCache::new(opts.cache.clone());
    if crate::bake::foliage::billboard::is_tree(&model) {
        let (levels, left_out, from_cache) = tree::tree_levels(&model, &hash, &cache)?;
        let (levels, lod_file, lod_bytes) =
            tree::write_tree(&model, &levels, &opts.out, opts.tolerance)?;
        return Ok(Exported {
            model: model.name.clone(),
            method: "billboard clouds".into(),
            levels,
            lod_file,
            lod_bytes,
            from_cache,
            left_out,
        });
    }
    let options = crate::runtime::levels::runtime_options(&model, inputs.level_budgets.as_deref());
    let (lods, origin) = crate::bake::character::lod::cached::load_or_bake(
        &cache,
        &model,
        &hash,
        opts.method,
        &options,
        &|_| {},
    );
    if let Origin::Baked { warning: Some(w) } = &origin {
        log::warn!("{w}");
    }
    // The bounding box seen from the side, in the scene's units (the importer's).
    let rest = crate::bake::character::simplify::SimplifyInput::rest_bones(&model.skeleton);
    let bounds = crate::model::Bounds::of(lods.levels[0].mesh.rest_positions(&rest))
        .ok_or_else(|| anyhow::anyhow!("{}: an empty mesh", name))?;
    let height = model_height(&model);
    let aspect = bounds.size().x.max(bounds.size().z) / height.max(1e-6);
    let meshes = level_meshes(&model, &lods);
    let kept = &lods.levels[..meshes.len()];
    let stem = file_stem(&model.name);
    let errors: Vec<f32> = kept.iter().map(|l| l.error).collect();
    let hints = coverage_hints(&switch_px(&errors, opts.tolerance, height), aspect);
    let mut levels = Vec::with_capacity(meshes.len());
    for (k, (level, mesh)) in kept.iter().zip(&meshes).enumerate() {
        let next = hints[k];
        let bytes = to_glb(&with_mesh(&model, mesh.clone()));
        let file = opts
            .out
            .join(format!("{stem}-{}-lod{k}.glb", opts.method.name()));
        crate::atomic::write(&file, &bytes)?;
        levels.push(ExportedLevel::written(
            k,
            mesh,
            (level.error, next),
            file,
            bytes.len(),
        ));
    }
    let refs: Vec<&SkinnedMesh> = meshes.iter().collect();
    let generator = format!("lodlab export ({} levels)", opts.method.name());
    let lod_bytes = to_lod_glb(&model, &refs, &hints, &generator);
    let lod_file = opts
        .out
        .join(format!("{stem}-{}-lods.glb", opts.method.name()));
    crate::atomic::write(&lod_file, &lod_bytes)?;
    Ok(Exported {
        model: model.name.clone(),
        method: opts.method.name().to_string(),
        levels,
        lod_file,
        lod_bytes: lod_bytes.len(),
        from_cache: origin == Origin::Cache,
        left_out: Vec::new(),
    })
}

/// The table `lodlab export` prints.
pub fn table(e: &Exported) -> String {
    let mut out = format!(
        "{} by {}: {} levels{}\n{:<5} {:>9} {:>8} {:>14} {:>11} {:>10} {:>10} {:>8}  file\n",
        e.model,
        e.method,
        e.levels.len(),
        if e.from_cache {
            " (from the cache)"
        } else {
            ""
        },
        "LOD",
        "triangles",
        "vertices",
        "influences/v",
        "weight sets",
        "error (mm)",
        "coverage",
        "KB"
    );
    for l in &e.levels {
        out += &format!(
            "{:<5} {:>9} {:>8} {:>14} {:>11} {:>10.3} {:>10.6} {:>8}  {}{}\n",
            l.level,
            l.triangles,
            l.vertices,
            l.max_influences,
            l.weight_sets,
            l.error * 1000.0,
            l.coverage,
            l.bytes / 1024,
            l.file.display(),
            l.kind.as_ref().map_or(String::new(), |k| format!(" ({k})"))
        );
    }
    for line in &e.left_out {
        out += &format!("{line}\n");
    }
    out += &format!(
        "all levels under MSFT_lod: {} ({} KB)\n",
        e.lod_file.display(),
        e.lod_bytes / 1024
    );
    out
}

/// `lodlab export`: a character's levels as glTF files.
pub fn command(
    a: ExportArgs,
    inputs: &crate::runtime::spec::BakeInputs,
) -> anyhow::Result<ExitCode> {
    if let Some(file) = crate::app::json::json_file(&a.json) {
        crate::atomic::check_target(file)?;
    }
    let exported = run(&a, inputs)?;
    crate::app::json::emit(&a.json, &exported, &table(&exported))?;
    Ok(ExitCode::SUCCESS)
}

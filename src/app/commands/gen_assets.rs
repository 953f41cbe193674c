//! `lodlab gen-assets --out DIR`: the built-in models, written afresh by their generators.

use crate::app::cli::GenAssetsArgs;
use std::process::ExitCode;

use crate::assets::BUILTINS;
use crate::generate::file;
use anyhow::{Result, anyhow};
use std::path::Path;

/// One written asset, for the summary line.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Written {
    pub name: String,
    pub path: String,
    pub bytes: usize,
    pub vertices: usize,
    pub triangles: usize,
    pub bones: usize,
    pub clips: Vec<String>,
}

/// Generates the named assets (all if `only` is empty) into `dir`.
pub fn run(
    dir: &Path,
    only: &[String],
    limits: &crate::import::validate::Limits,
) -> Result<Vec<Written>> {
    for name in only {
        if !BUILTINS.iter().any(|b| b.name == name) {
            let names: Vec<&str> = BUILTINS.iter().map(|b| b.name).collect();
            return Err(anyhow!(
                "unknown asset '{name}' (assets: {})",
                names.join(", ")
            ));
        }
    }
    crate::atomic::make_folder(dir)?;
    let mut written = Vec::new();
    for b in BUILTINS
        .iter()
        .filter(|b| only.is_empty() || only.iter().any(|o| o == b.name))
    {
        let bytes = file(b.name).ok_or_else(|| anyhow!("no generator for {}", b.name))?;
        let path = dir.join(b.file_name);
        crate::atomic::write(&path, &bytes)?;
        // What the file holds, as lodlab reads it (a file of clips alone has no model).
        let read = crate::import::gltf::from_bytes(b.name, bytes.clone(), dir, limits)
            .ok()
            .map(|(m, _)| m);
        written.push(Written {
            name: b.name.to_string(),
            path: path.display().to_string(),
            bytes: bytes.len(),
            vertices: read.as_ref().map_or(0, |m| m.mesh.vertex_count()),
            triangles: read.as_ref().map_or(0, |m| m.mesh.triangle_count()),
            bones: read.as_ref().map_or(0, |m| m.skeleton.bone_count()),
            clips: read.as_ref().map_or_else(Vec::new, |m| {
                m.clips.iter().map(|c| c.name.clone()).collect()
            }),
        });
    }
    Ok(written)
}

/// `lodlab gen-assets`: the built-in models as .glb files.
pub fn command(
    a: GenAssetsArgs,
    limits: &crate::import::validate::Limits,
) -> anyhow::Result<ExitCode> {
    for w in run(&a.out, &a.only, limits)? {
        println!("{}", serde_json::to_string(&w)?);
    }
    Ok(ExitCode::SUCCESS)
}

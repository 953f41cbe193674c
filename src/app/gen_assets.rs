//! `lodlab gen-assets`: regenerate the demo creatures under `assets/`.

use crate::assets::BUILTINS;
use crate::generate::{generate, glb::to_glb};
use anyhow::{Context, Result, anyhow};
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
pub fn run(dir: &Path, only: &[String]) -> Result<Vec<Written>> {
    for name in only {
        if !BUILTINS.iter().any(|b| b.name == name) {
            let names: Vec<&str> = BUILTINS.iter().map(|b| b.name).collect();
            return Err(anyhow!(
                "unknown asset '{name}' (assets: {})",
                names.join(", ")
            ));
        }
    }
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let mut written = Vec::new();
    for b in BUILTINS
        .iter()
        .filter(|b| only.is_empty() || only.iter().any(|o| o == b.name))
    {
        let model = generate(b.name).ok_or_else(|| anyhow!("no generator for {}", b.name))?;
        let bytes = to_glb(&model);
        let path = dir.join(b.file_name);
        crate::atomic::write(&path, &bytes)?;
        written.push(Written {
            name: b.name.to_string(),
            path: path.display().to_string(),
            bytes: bytes.len(),
            vertices: model.mesh.vertex_count(),
            triangles: model.mesh.triangle_count(),
            bones: model.skeleton.bone_count(),
            clips: model.clips.iter().map(|c| c.name.clone()).collect(),
        });
    }
    Ok(written)
}

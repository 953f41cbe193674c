//! Import: turning glTF files into [`crate::model::Model`]s.

pub mod clips;
pub mod container;
pub mod gltf;
pub mod gltfpack;
pub mod nodes;
pub mod palette;
pub mod primitives;
pub mod source;
pub mod sources;
pub mod validate;

use crate::error::InputError;
use crate::model::Model;
use std::path::{Path, PathBuf};
use std::sync::RwLock;

pub use source::{Source, source};

/// Files whose clips every model loaded by [`load_model`] gets (the command line's
/// `--clips`), in order.
static EXTRA_CLIPS: RwLock<Vec<PathBuf>> = RwLock::new(Vec::new());

/// Sets the files of clips [`load_model`] adds to every model, for the rest of the process.
pub fn set_extra_clips(files: Vec<PathBuf>) {
    *EXTRA_CLIPS.write().unwrap_or_else(|e| e.into_inner()) = files;
}

/// The files of clips [`load_model`] adds to every model (a bake's cache key holds them).
pub fn extra_clips() -> Vec<PathBuf> {
    EXTRA_CLIPS
        .read()
        .unwrap_or_else(|e| e.into_inner())
        .clone()
}

/// Loads a model given on the command line: the name of a built-in asset (`horse`, `walker`)
/// or a path to a glTF file, with the clips of [`extra_clips`] added by joint name.
pub fn load_model(name_or_path: &str) -> Result<Model, InputError> {
    let mut model = load_file(name_or_path)?;
    for file in extra_clips() {
        // A built-in's name (`mocap-walk`) or a path.
        let from = source(&file.to_string_lossy());
        let added = gltf::add_clips_from(&mut model, &from)?;
        log::info!(
            "{}: {added} clip(s) added to {}",
            from.label().display(),
            model.name
        );
    }
    Ok(model)
}

/// [`load_model`] without the extra clips.
fn load_file(name_or_path: &str) -> Result<Model, InputError> {
    if let Some(asset) = crate::assets::builtin(name_or_path) {
        let mut model = match source(name_or_path) {
            Source::File(path) => gltf::load(&path)?,
            Source::Builtin(b) => gltf::load_builtin(b)?,
        };
        model.name = asset.name.to_string();
        return Ok(model);
    }
    let path = Path::new(name_or_path);
    // A bare name that is neither a file nor a built-in: most likely a misspelt built-in, so
    // say which there are.
    let bare = path.components().count() == 1 && path.extension().is_none();
    if bare && !path.exists() {
        let names: Vec<&str> = crate::assets::BUILTINS.iter().map(|b| b.name).collect();
        return Err(InputError::new(
            path,
            format!(
                "no such file, and no built-in model of that name (built-in: {})",
                names.join(", ")
            ),
        ));
    }
    gltf::load(path)
}

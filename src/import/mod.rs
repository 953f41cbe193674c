//! Import: turning glTF files into [`crate::model::Model`]s.

pub mod gltf;
pub mod gltfpack;
pub mod validate;
pub mod weld;

use crate::error::InputError;
use crate::model::Model;
use std::path::{Path, PathBuf};

/// Loads a model given on the command line: the name of a built-in asset (`horse`, `walker`)
/// or a path to a glTF file.
pub fn load_model(name_or_path: &str) -> Result<Model, InputError> {
    match crate::assets::builtin(name_or_path) {
        Some(asset) => gltf::load(&asset.path()).map(|mut m| {
            m.name = asset.name.to_string();
            m
        }),
        None => {
            let path = Path::new(name_or_path);
            // A bare name that is neither a file nor a built-in: most likely a misspelt
            // built-in, so say which there are.
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
    }
}

/// The file a model name or path given on the command line refers to.
pub fn source_path(name_or_path: &str) -> PathBuf {
    match crate::assets::builtin(name_or_path) {
        Some(asset) => asset.path(),
        None => PathBuf::from(name_or_path),
    }
}

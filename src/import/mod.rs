//! Import: turning glTF files into [`crate::model::Model`]s.

pub mod clips;
pub mod container;
pub mod gltf;
pub mod gltfpack;
pub mod limits;
pub mod nodes;
pub mod palette;
pub mod primitives;
pub mod source;
pub mod sources;
pub mod validate;

use crate::error::InputError;
use crate::model::Model;
use std::path::{Path, PathBuf};

pub use source::{Source, source};

/// What an import is told, from the command line down: the bounds a file may expand to, and
/// the files whose clips every model gets. Plain values: two imports in one process may ask
/// for different ones.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImportOptions {
    /// What one file may expand to (`--limit`, `--allow-outside-files`).
    pub limits: validate::Limits,
    /// Files whose clips are added to every model, bound by joint name (`--clips`), in order:
    /// built-in names (`mocap-walk`) or paths.
    pub extra_clips: Vec<PathBuf>,
}

/// A model as [`import`] made it, and the key its bakes are cached under.
#[derive(Clone, Debug)]
pub struct Imported {
    pub model: Model,
    /// A hash of every byte the import read: the file, its external buffers and images, and
    /// the files its extra clips came from. The same bytes give the same hash; nothing is read
    /// twice for it.
    pub source_hash: [u8; 32],
}

/// Imports a model given on the command line: the name of a built-in asset (`horse`,
/// `walker`) or a path to a glTF file, with the clips of `options.extra_clips` added by joint
/// name.
pub fn import(name_or_path: &str, options: &ImportOptions) -> Result<Imported, InputError> {
    let read = load_file(name_or_path, &options.limits)?;
    let mut model = read.model;
    let mut hash = blake3::Hasher::new();
    hash.update(&read.digest);
    for file in &options.extra_clips {
        // A built-in's name (`mocap-walk`) or a path.
        let from = source(&file.to_string_lossy());
        let (added, digest) = gltf::add_clips_from(&mut model, &from, &options.limits)?;
        // Clips added from other files change what the metric is estimated from.
        hash.update(b"clips");
        hash.update(&digest);
        log::info!(
            "{}: {added} clip(s) added to {}",
            from.label().display(),
            model.name
        );
    }
    Ok(Imported {
        model,
        source_hash: *hash.finalize().as_bytes(),
    })
}

/// The model of [`import`] with the default options (the default limits, no extra clips).
pub fn load_model(name_or_path: &str) -> Result<Model, InputError> {
    import(name_or_path, &ImportOptions::default()).map(|i| i.model)
}

/// [`import`] without the extra clips.
fn load_file(name_or_path: &str, limits: &validate::Limits) -> Result<gltf::Read, InputError> {
    if let Some(asset) = crate::assets::builtin(name_or_path) {
        let mut read = match source(name_or_path) {
            Source::File(path) => gltf::read(&path, limits)?,
            Source::Builtin(b) => gltf::read_builtin(b, limits)?,
        };
        read.model.name = asset.name.to_string();
        return Ok(read);
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
    gltf::read(path, limits)
}

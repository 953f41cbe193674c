//! Where a model named on the command line comes from: a built-in (the copy compiled into the
//! binary, or `$LODLAB_ASSETS`) or a file.

use std::path::{Path, PathBuf};

/// Where a model named on the command line comes from: a built-in (from the copy built into
/// the binary, or from `$LODLAB_ASSETS`) or a file.
#[derive(Clone, Debug)]
pub enum Source {
    Builtin(&'static crate::assets::Builtin),
    File(PathBuf),
}

/// The source a model name or path given on the command line refers to.
pub fn source(name_or_path: &str) -> Source {
    match crate::assets::builtin(name_or_path) {
        Some(asset) => match asset.file() {
            Some(file) => Source::File(file),
            None => Source::Builtin(asset),
        },
        None => Source::File(PathBuf::from(name_or_path)),
    }
}

impl Source {
    /// What an error names: the file, or the built-in's name.
    pub fn label(&self) -> PathBuf {
        match self {
            Source::Builtin(b) => b.label(),
            Source::File(p) => p.clone(),
        }
    }

    /// The folder a `.gltf`'s buffers and images are read from (none for a built-in: they are
    /// `.glb`s with everything inside).
    pub fn folder(&self) -> &Path {
        match self {
            Source::Builtin(_) => Path::new("."),
            Source::File(p) => p.parent().unwrap_or(Path::new(".")),
        }
    }

    /// Its bytes, read as the import reads files ([`crate::import::sources::read_regular`]).
    pub fn read(
        &self,
        limits: &crate::import::validate::Limits,
    ) -> Result<std::borrow::Cow<'static, [u8]>, String> {
        match self {
            Source::Builtin(b) => Ok(std::borrow::Cow::Borrowed(b.bytes)),
            Source::File(p) => {
                crate::import::sources::read_regular(p, limits).map(std::borrow::Cow::Owned)
            }
        }
    }
}

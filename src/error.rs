//! Errors that reach the user: one line naming the file and the problem.

use std::path::{Path, PathBuf};

/// A problem with something the user gave us (a model file, a cache, an output path).
///
/// Its `Display` is the single line the command-line front ends print before exiting with
/// code 1: `PATH: PROBLEM`.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", path.display())]
pub struct InputError {
    pub path: PathBuf,
    pub problem: String,
}

impl InputError {
    pub fn new(path: impl AsRef<Path>, problem: impl std::fmt::Display) -> Self {
        // Keep it to one line whatever the underlying library printed.
        let problem = problem
            .to_string()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        InputError {
            path: path.as_ref().to_path_buf(),
            problem,
        }
    }
}

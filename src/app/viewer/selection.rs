//! What the viewer keeps about looking closely (see `select`): the instance picked, whether the
//! camera follows it, the camera's bookmark, the last command line, the recent files.

use crate::scene::Camera;
use glam::Vec3;
use std::path::{Path, PathBuf};

/// Recent files kept.
const RECENT: usize = 8;

#[derive(Default)]
pub struct Selection {
    /// The instance selected (an index into the world's instances).
    pub picked: Option<usize>,
    /// Picked since the panel last ran (its section opens).
    pub just_picked: bool,
    /// Where the camera's target was put to follow it last frame; None: not following.
    pub following: Option<Vec3>,
    /// The camera bookmarked with B.
    pub bookmark: Option<Camera>,
    /// The last "copy as command", shown in the panel.
    pub command: Option<String>,
    /// Models opened at run time, newest first (kept in the config folder between runs).
    pub recent: Vec<PathBuf>,
    /// The system clipboard, made on first use and kept (on X11 the text lives as long as it).
    pub clipboard: Option<super::clipboard::Clipboard>,
}

/// `$XDG_CONFIG_HOME/lodlab/recent-files` (one path a line, newest first).
fn recent_file() -> Option<PathBuf> {
    dirs::config_dir().map(|d| d.join("lodlab").join("recent-files"))
}

impl Selection {
    /// A selection with the recent files of earlier runs, those that still exist.
    pub fn load() -> Selection {
        let recent = recent_file()
            .and_then(|f| std::fs::read_to_string(f).ok())
            .map(|text| {
                text.lines()
                    .map(PathBuf::from)
                    .filter(|p| p.is_file())
                    .take(RECENT)
                    .collect()
            })
            .unwrap_or_default();
        Selection {
            recent,
            ..Default::default()
        }
    }

    /// `path` was opened: first in the list, saved for the next run.
    pub fn opened(&mut self, path: &Path) {
        let path = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        self.recent.retain(|p| p != &path);
        self.recent.insert(0, path);
        self.recent.truncate(RECENT);
        if let Some(file) = recent_file() {
            let text: String = self
                .recent
                .iter()
                .map(|p| format!("{}\n", p.display()))
                .collect();
            let saved = file
                .parent()
                .map_or(Ok(()), crate::atomic::make_folder)
                .and_then(|_| crate::atomic::write(&file, text.as_bytes()));
            if let Err(e) = saved {
                log::warn!("{}: recent files not kept: {e:#}", file.display());
            }
        }
    }
}

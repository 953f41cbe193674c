//! The web viewer's folder, as `lodlab web` writes it and the page reads it:
//!
//! - `index.html`, the page (compiled in from `assets/web/viewer/`);
//! - `lodlab.js` and `lodlab_bg.wasm`, this crate built for `wasm32-unknown-unknown` and bound
//!   by `wasm-bindgen --target web` (`tools/web/build-wasm.sh`);
//! - `lodlab-web.json`, the [`SiteManifest`]: the view the page opens with, as `lodlab view`'s
//!   options, and the cache files it needs;
//! - `levels/`, those cache files, byte for byte as the desktop's cache holds them (the
//!   page hands them to `bake::cache::memory`, so the same code reads them as on the desktop,
//!   and bakes nothing).

use crate::app::cli::{Cli, Command};
use crate::app::viewer::ViewOptions;
use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};

pub const MANIFEST: &str = "lodlab-web.json";
pub const LEVELS: &str = "levels";
pub const PAGE: &str = include_str!("../../assets/web/viewer/index.html");

/// `lodlab-web.json`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SiteManifest {
    /// The lodlab that wrote it: its cache files are read by the same version's page only.
    pub lodlab: String,
    /// `lodlab view`'s options the page opens with, e.g. `["--scene", "forest"]`.
    pub view: Vec<String>,
    /// The cache files in `levels/`, each with its size in bytes.
    pub files: Vec<SiteFile>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SiteFile {
    pub name: String,
    pub bytes: u64,
}

impl SiteManifest {
    /// The bytes of every cache file together.
    pub fn total_bytes(&self) -> u64 {
        self.files.iter().map(|f| f.bytes).sum()
    }
}

/// What `lodlab view WORDS` would open.
pub fn view_options(words: &[String]) -> Result<ViewOptions> {
    let all = ["lodlab".to_string(), "view".to_string()]
        .into_iter()
        .chain(words.iter().cloned());
    let cli = <Cli as clap::Parser>::try_parse_from(all).map_err(|e| {
        let text = e.to_string();
        anyhow::anyhow!(
            "the view's options {words:?}: {}",
            text.lines().next().unwrap_or_default()
        )
    })?;
    let inputs = cli.bake_inputs();
    match cli.command {
        Some(Command::View(args)) => Ok(ViewOptions::from_args(args, &inputs)),
        _ => bail!("the view's options {words:?} are not lodlab view's"),
    }
}

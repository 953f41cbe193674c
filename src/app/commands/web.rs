//! `lodlab web --out DIR`: the web viewer's folder ([`crate::app::site`]). The page bakes
//! nothing: this command builds the page's scene headless under each simplified method, with
//! the cache noting every file it reads ([`crate::bake::cache::memory`]; levels missing from
//! the cache are baked first), and copies exactly those files beside the page.

use crate::app::cli::WebArgs;
use crate::app::site::{self, LEVELS, MANIFEST, SiteFile, SiteManifest};
use crate::bake::character::simplify::Method;
use crate::runtime::headless::Headless;
use crate::scene::LodMethod;
use anyhow::{Context, Result, bail};
use std::path::Path;
use std::process::ExitCode;

/// The files wasm-bindgen writes for the viewer (`--target web`).
pub const WASM_FILES: [&str; 2] = ["lodlab.js", "lodlab_bg.wasm"];

/// `lodlab web`: the page, its scene's levels and the viewer beside it. The page reads no
/// files, so the global options' clips and budgets (`inputs`) must be in its view words.
pub fn command(a: WebArgs, inputs: &crate::runtime::spec::BakeInputs) -> Result<ExitCode> {
    if !inputs.import.extra_clips.is_empty() || inputs.level_budgets.is_some() {
        bail!(
            "--clips and --levels go among the page's view options (lodlab web --out DIR -- --clips NAME), \
             which the page reads too"
        );
    }
    let options = site::view_options(&a.view)?;
    // The page has no files: it shows built-in models, as the browser build holds them.
    if let Some(m) = options
        .spec
        .models
        .iter()
        .find(|m| crate::assets::builtin(m).is_none())
    {
        bail!("--model {m}: the web page shows built-in models only (it reads no files)");
    }
    if let Some(dir) = crate::assets::override_dir() {
        bail!(
            "LODLAB_ASSETS={}: the web page shows the built-in models as built in; unset it",
            dir.display()
        );
    }
    check_folder(&a.out)?;
    if let Some(dir) = &a.wasm {
        for f in WASM_FILES {
            if !dir.join(f).is_file() {
                bail!(
                    "{}: no {f} (build it with tools/web/build-wasm.sh {})",
                    dir.display(),
                    dir.display()
                );
            }
        }
    }
    let mut spec = options.spec.clone();
    if a.cache.is_some() {
        spec.cache_dir = a.cache.clone();
    }
    // The scene under every simplified method, as the page's panel and its M key offer them.
    let cache = crate::bake::cache::LodCache::new(spec.cache_dir.clone());
    cache.memory.record_reads();
    let loaded = crate::runtime::spec::Loaded::new(spec)?.with_cache(cache.clone());
    let mut scene = Headless::of(loaded, 64, 64, Some(1), &crate::measure::GpuMeasurer)?;
    for method in Method::ALL {
        let mut lod = options.lod;
        lod.method = LodMethod::Simplified(method);
        lod.compare = None;
        eprintln!("levels by {method}");
        scene.show(&lod)?;
    }
    let reads = cache.memory.take_reads();
    let levels = a.out.join(LEVELS);
    crate::atomic::make_folder(&levels)?;
    let mut files = Vec::new();
    for path in &reads {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .context("a cache file without a name")?
            .to_string();
        let bytes =
            std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
        crate::atomic::write(&levels.join(&name), &bytes)?;
        files.push(SiteFile {
            name,
            bytes: bytes.len() as u64,
        });
    }
    // Levels an earlier run of this folder left that this scene does not read.
    for entry in
        std::fs::read_dir(&levels).with_context(|| format!("{}: cannot read", levels.display()))?
    {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.ends_with(".lods") && !files.iter().any(|f| f.name == name) {
            std::fs::remove_file(entry.path())
                .with_context(|| format!("{}: cannot remove", entry.path().display()))?;
        }
    }
    let manifest = SiteManifest {
        lodlab: env!("CARGO_PKG_VERSION").to_string(),
        view: a.view.clone(),
        files,
    };
    crate::atomic::write(
        &a.out.join(MANIFEST),
        crate::app::json::pretty(&manifest)?.as_bytes(),
    )?;
    crate::atomic::write(&a.out.join("index.html"), site::PAGE.as_bytes())?;
    if let Some(dir) = &a.wasm {
        for f in WASM_FILES {
            let bytes = std::fs::read(dir.join(f))
                .with_context(|| format!("{}: cannot read", dir.join(f).display()))?;
            crate::atomic::write(&a.out.join(f), &bytes)?;
        }
    }
    let wasm_there = WASM_FILES.iter().all(|f| a.out.join(f).is_file());
    println!(
        "{}: {} levels files ({:.1} MB){}; serve the folder over HTTP (e.g. `python3 -m \
         http.server -d {}`) and open it in a browser with WebGPU",
        a.out.display(),
        manifest.files.len(),
        manifest.total_bytes() as f64 / 1e6,
        if wasm_there {
            ", the page and the viewer"
        } else {
            ", the page; the viewer itself is missing: build it with \
             tools/web/build-wasm.sh DIR and pass --wasm DIR"
        },
        a.out.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// Writes only into a new or empty folder, or one `lodlab web` wrote (whose files it
/// replaces; a run that stopped before its manifest left only its own files): nothing else is
/// overwritten.
fn check_folder(out: &Path) -> Result<()> {
    let ours = |name: &std::ffi::OsStr| {
        name == LEVELS
            || name == MANIFEST
            || name == "index.html"
            || WASM_FILES.iter().any(|f| name == *f)
    };
    if out.is_dir()
        && !out.join(MANIFEST).is_file()
        && std::fs::read_dir(out)
            .with_context(|| format!("{}: cannot read", out.display()))?
            .filter_map(|e| e.ok())
            .any(|e| !ours(&e.file_name()))
    {
        bail!(
            "{}: not empty and not a lodlab web folder; write the page into a new or empty one",
            out.display()
        );
    }
    crate::atomic::make_folder(out)
}

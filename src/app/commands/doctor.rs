//! `lodlab doctor`: what lodlab finds on this machine (the adapter and its driver, the defaults
//! it picks there, the cache, the models, the tests' checkers) and the problems it can see in
//! the environment, each with its remedy. What a newcomer runs first when something is off.

use crate::app::cli::DoctorArgs;
use crate::bake::cache::LodCache;
use crate::import::validate::Limits;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The libraries the window loads at run time (winit, the Vulkan loader), by file name, with
/// the Debian package that has each.
const WINDOW_LIBRARIES: &[(&str, &str)] = &[
    ("libvulkan.so.1", "libvulkan1"),
    ("libX11.so.6", "libx11-6"),
    ("libX11-xcb.so.1", "libx11-xcb1"),
    ("libXcursor.so.1", "libxcursor1"),
    ("libXi.so.6", "libxi6"),
    ("libxkbcommon.so.0", "libxkbcommon0"),
    ("libxkbcommon-x11.so.0", "libxkbcommon-x11-0"),
    ("libwayland-client.so.0", "libwayland-client0"),
];

/// One finding: what it is and what it is.
struct Line(&'static str, String);

/// `lodlab doctor`: prints the findings, then the problems with their remedies. Exits with 1
/// where no adapter could be had (nothing but `gen-assets` runs then), else 0.
pub fn command(a: DoctorArgs, current: &Limits) -> anyhow::Result<ExitCode> {
    let mut lines = Vec::new();
    let mut problems = Vec::new();
    lines.push(Line(
        "lodlab",
        format!(
            "{} ({} built-in models inside the binary{})",
            env!("CARGO_PKG_VERSION"),
            crate::assets::BUILTINS.len(),
            crate::assets::override_dir()
                .map(|d| format!("; read from {} (LODLAB_ASSETS)", d.display()))
                .unwrap_or_default()
        ),
    ));
    let adapter_found = adapter(&mut lines, &mut problems);
    environment(&mut problems);
    lines.push(Line("cache", cache(a.cache.clone())));
    lines.push(Line("shared models", shared_models()));
    lines.push(Line("checkers", checkers()));
    lines.push(Line("limits", limits(current)));
    let width = lines.iter().map(|l| l.0.len()).max().unwrap_or(0);
    for Line(what, text) in &lines {
        println!("{what:width$}  {text}");
    }
    if problems.is_empty() {
        println!("\nno problems found");
    } else {
        println!("\nproblems:");
        for p in &problems {
            println!("- {p}");
        }
    }
    Ok(if adapter_found {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// The adapter lodlab would draw with, its driver and the defaults chosen for it; false where
/// there is none.
fn adapter(lines: &mut Vec<Line>, problems: &mut Vec<String>) -> bool {
    let gpu = match crate::render::Gpu::headless() {
        Ok(gpu) => gpu,
        Err(e) => {
            lines.push(Line("adapter", format!("none ({e:#})")));
            problems.push(
                "no adapter: install a Vulkan driver (on Debian or Ubuntu: sudo apt-get install mesa-vulkan-drivers libvulkan1; lavapipe renders in software where there is no GPU)"
                    .into(),
            );
            return false;
        }
    };
    let info = &gpu.info;
    lines.push(Line("adapter", gpu.describe()));
    lines.push(Line(
        "driver",
        format!("{} {}", info.driver, info.driver_info),
    ));
    let (samples, lighting) = if gpu.is_cpu() {
        ("1×", "one normal a billboard")
    } else {
        ("4×", "per texel through their atlases")
    };
    lines.push(Line(
        "defaults",
        format!(
            "multisampling {samples} (--msaa), billboards lit {lighting} (--billboard-lighting)"
        ),
    ));
    if info.backend == wgpu::Backend::Gl {
        problems.push(
            "the adapter is OpenGL, a fallback (Vulkan failed or is missing): install mesa-vulkan-drivers and libvulkan1, and set WGPU_BACKEND=vulkan to insist on it"
                .into(),
        );
    }
    if gpu.is_cpu() {
        lines.push(Line(
            "note",
            "a CPU adapter: the default scene runs at about 10 frames a second on 2 cores; \
             --count and --trees make it lighter, LP_NUM_THREADS sets lavapipe's threads"
                .into(),
        ));
    }
    true
}

/// Problems of the environment: variables, the display, the window's libraries.
fn environment(problems: &mut Vec<String>) {
    let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
    if var("WGPU_BACKEND").is_none() {
        problems.push(
            "WGPU_BACKEND is not set: where Vulkan fails wgpu quietly falls back to OpenGL; export WGPU_BACKEND=vulkan to insist on Vulkan (lavapipe included)"
                .into(),
        );
    }
    if !var("XDG_RUNTIME_DIR").is_some_and(|d| Path::new(&d).is_dir()) {
        problems.push(
            "XDG_RUNTIME_DIR is not set or not a folder (a container or an ssh session): a Wayland window needs it, and other Vulkan programs print four lines about it; export XDG_RUNTIME_DIR=$(mktemp -d)"
                .into(),
        );
    }
    if var("DISPLAY").is_none() && var("WAYLAND_DISPLAY").is_none() {
        problems.push(
            "no display (DISPLAY and WAYLAND_DISPLAY are unset): `lodlab view` cannot open a window; run it under Xvfb (xvfb-run -a lodlab view --screenshot FILE.png --frames 30) or use `lodlab shot`"
                .into(),
        );
    }
    for (file, package) in WINDOW_LIBRARIES {
        // SAFETY: loading a system library runs its initialisers; these are the libraries
        // the window loads anyway, and the handle is dropped at once.
        if unsafe { libloading::Library::new(file) }.is_err() {
            problems.push(format!(
                "{file} cannot be loaded: the window needs it (sudo apt-get install {package})"
            ));
        }
    }
}

/// The cache folder, what it holds, and how to clear it.
fn cache(dir: Option<PathBuf>) -> String {
    let dir = LodCache::new(dir).dir;
    let (files, bytes) = folder_size(&dir);
    if files == 0 {
        format!(
            "{} (empty: the first run bakes levels of detail, a minute or two on 2 cores, and keeps them here)",
            dir.display()
        )
    } else {
        format!(
            "{}: {:.1} MB in {files} files (clear it: rm -r {}; or --cache DIR for another)",
            dir.display(),
            bytes as f64 / 1e6,
            dir.display()
        )
    }
}

/// Files under `dir` and their bytes, recursively; (0, 0) where it is missing.
fn folder_size(dir: &Path) -> (u64, u64) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return (0, 0);
    };
    let mut total = (0, 0);
    for entry in entries.flatten() {
        let Ok(meta) = entry.metadata() else { continue };
        if meta.is_dir() {
            let (f, b) = folder_size(&entry.path());
            total = (total.0 + f, total.1 + b);
        } else if meta.is_file() {
            total = (total.0 + 1, total.1 + meta.len());
        }
    }
    total
}

/// The checkout this binary was built from, where it still exists.
fn checkout() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    dir.join("Cargo.toml").is_file().then_some(dir)
}

/// The models from elsewhere some tests read, beside the checkout.
fn shared_models() -> String {
    let Some(root) = checkout() else {
        return "only the tests read them, from beside the checkout (not found here)".into();
    };
    let dir = root.join("../shared/models");
    let dir = dir.canonicalize().unwrap_or(dir);
    let found: Vec<&str> = ["Fox.glb", "SimpleSkin.gltf"]
        .into_iter()
        .filter(|f| dir.join(f).is_file())
        .collect();
    if found.len() == 2 {
        format!("{}: Fox.glb, SimpleSkin.gltf", dir.display())
    } else {
        format!(
            "{}: {} of Fox.glb, SimpleSkin.gltf (tests that read the others skip with one line)",
            dir.display(),
            if found.is_empty() {
                "none".to_string()
            } else {
                found.join(", ")
            }
        )
    }
}

/// The external checkers the tests run where installed.
fn checkers() -> String {
    let node = std::process::Command::new("node")
        .arg("--version")
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string());
    let tools = checkout().map(|r| r.join("tools/gltf/node_modules"));
    let has = |name: &str| tools.as_ref().is_some_and(|t| t.join(name).is_dir());
    let mark = |on: bool| if on { "found" } else { "missing" };
    let mut text = format!(
        "node {}, glTF-Validator {}, gltfpack {}",
        node.as_deref().unwrap_or("missing"),
        mark(has("gltf-validator")),
        mark(has("gltfpack")),
    );
    if !(has("gltf-validator") && has("gltfpack")) {
        text.push_str(" (tests that run them skip; npm ci --prefix tools/gltf installs them)");
    }
    text
}

/// The import limits in force, as `--limit NAME=VALUE` sets them.
fn limits(current: &Limits) -> String {
    Limits::NAMES
        .iter()
        .filter_map(|(name, _)| current.value(name).map(|v| format!("{name}={v}")))
        .collect::<Vec<_>>()
        .join(" ")
}

//! The `lodlab` command line: parses the arguments (`lodlab::app::cli`) and runs the command
//! (`lodlab::app::commands`), printing a failure as one line.

#[cfg(not(target_arch = "wasm32"))]
use clap::Parser;
#[cfg(not(target_arch = "wasm32"))]
use lodlab::app::cli::Cli;
#[cfg(not(target_arch = "wasm32"))]
use std::process::ExitCode;

/// In the browser: the web viewer (see `lodlab::app::viewer::web`).
#[cfg(target_arch = "wasm32")]
fn main() {
    lodlab::app::viewer::web::start();
}

#[cfg(not(target_arch = "wasm32"))]
fn main() -> ExitCode {
    quiet_device_select();
    // Diagnostics (`RUST_LOG=debug`: the bake and the cache's decisions) go to stderr beside
    // the user-facing lines, which stay plain `eprintln!`s.
    // rfd's own lines about a missing file dialog are left out: the panel says it in one.
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn,rfd=off"))
        .format_timestamp(None)
        .init();
    // Ctrl-C says so and leaves no half-written file (see `lodlab::atomic`).
    lodlab::atomic::remove_pending_on_interrupt();
    match lodlab::app::commands::run(Cli::parse()) {
        Ok(code) => code,
        Err(e) => {
            // One line: the whole context chain joined.
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}

/// Mesa's device-select Vulkan layer looks for a Wayland compositor whenever a Vulkan instance
/// is made, and where `XDG_RUNTIME_DIR` is unset or no folder (containers, ssh sessions)
/// libwayland prints "error: XDG_RUNTIME_DIR is invalid or not set in the environment." four
/// times: lines on stderr that read as lodlab's own errors, on every command. There is no
/// compositor to find there, so the layer is switched off (its `NODEVICE_SELECT`) unless the
/// user set it up or chose a device through it. What the layer does besides is put the boot
/// display's GPU first; on a headless machine with several, `WGPU_ADAPTER_NAME` or
/// `WGPU_POWER_PREF` choose (see `render::gpu`).
#[cfg(not(target_arch = "wasm32"))]
fn quiet_device_select() {
    let runtime_dir = std::env::var_os("XDG_RUNTIME_DIR");
    let no_compositor = runtime_dir.is_none_or(|d| !std::path::Path::new(&d).is_dir());
    let chosen = ["NODEVICE_SELECT", "MESA_VK_DEVICE_SELECT", "DRI_PRIME"]
        .iter()
        .any(|v| std::env::var_os(v).is_some());
    if no_compositor && !chosen {
        // SAFETY: the first statement of main, before any thread is started.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}

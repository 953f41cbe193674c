//! `lodlab soak`: many frames headless through every setting a user may switch, watching
//! memory for growth and the GPU for errors.
//!
//! The frames run as a fixed cycle of [`CYCLE`] phases of `--phase-frames` frames each. Every
//! phase changes the method, the transition, the trees' foliage policy, the number of
//! characters and the frame's size; a size of 0×0 stands for a minimised window (nothing is
//! drawn, time goes on). Memory is read every `--every` frames: the process's resident set,
//! and what wgpu's allocator holds. When a cycle's frames divide `--every`, every reading
//! falls at the same point of the cycle, so after the first cycle (which bakes and installs
//! every method's levels) the GPU figures must repeat exactly and the resident set must stay
//! within `--max-growth-mb`.

use crate::app::cli::SoakArgs;
pub use crate::app::cli::values::Setting;
use std::process::ExitCode;

use crate::render::Gpu;
use crate::render::memory::{resident_bytes, return_freed_memory};
use crate::render::targets::Offscreen;
use crate::runtime::headless::{Headless, ShotLod};
use crate::scene::foliage::FoliagePolicy;
use crate::scene::{LodMethod, Transition};

use anyhow::{Result, bail};
use std::io::Write;
use std::time::Instant;

/// Phases in one cycle of settings.
pub const CYCLE: usize = 20;

/// The settings of one phase.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Phase {
    method: LodMethod,
    transition: Transition,
    foliage: FoliagePolicy,
    count: usize,
    size: [u32; 2],
}

/// Phase `k` of the cycle: each setting in `vary` steps at its own rate, so the cycle meets
/// many combinations, and comes back to phase 0 after [`CYCLE`] phases.
fn phase(k: usize, count: usize, size: [u32; 2], vary: &[Setting]) -> Phase {
    let k = k % CYCLE;
    let at = |s: Setting| if vary.contains(&s) { k } else { 0 };
    let [w, h] = size;
    let sizes = [
        [w, h],
        [0, 0],
        [(w / 2).max(1), (h / 2).max(1)],
        [(w * 3 / 4) | 1, (h * 3 / 4) | 1],
        [1, 1],
    ];
    let t = at(Setting::Transition);
    Phase {
        method: LodMethod::ALL[at(Setting::Method) % LodMethod::COUNT],
        transition: Transition::ALL[(t / 4 + t) % Transition::ALL.len()],
        foliage: FoliagePolicy::ALL[(at(Setting::Foliage) / 5) % FoliagePolicy::ALL.len()],
        count: [count, count.div_ceil(3), 1][at(Setting::Count) % 3],
        size: sizes[at(Setting::Size) % sizes.len()],
    }
}

/// One reading of memory.
#[derive(Clone, Debug, PartialEq)]
pub struct Reading {
    pub frame: usize,
    pub resident_mb: Option<f64>,
    /// What wgpu's allocator holds, and in how many allocations (`None` where the backend
    /// does not say).
    pub gpu_mb: Option<f64>,
    pub gpu_allocations: Option<usize>,
}

fn read_memory(gpu: &Gpu, frame: usize) -> Reading {
    // Freed heap goes back to the system first (as the viewer does after loading levels), so
    // the resident set follows what is live rather than what glibc keeps for reuse.
    return_freed_memory();
    let report = gpu.device.generate_allocator_report();
    Reading {
        frame,
        resident_mb: resident_bytes().map(|b| b as f64 / 1e6),
        gpu_mb: report
            .as_ref()
            .map(|r| r.total_allocated_bytes as f64 / 1e6),
        gpu_allocations: report.as_ref().map(|r| r.allocations.len()),
    }
}

/// What the soak found.
#[derive(Clone, Debug)]
pub struct SoakReport {
    pub readings: Vec<Reading>,
    /// Resident growth from the first reading after the first cycle to the last, MB.
    pub growth_mb: Option<f64>,
    /// Whether the GPU figures repeated at every reading after the first cycle (`None`: too
    /// few readings, or no figures).
    pub gpu_steady: Option<bool>,
    pub seconds: f64,
}

/// Runs `lodlab soak` as its arguments `o` ask.
pub fn run(o: &SoakArgs, inputs: &crate::runtime::spec::BakeInputs) -> Result<SoakReport> {
    if o.phase_frames == 0 || o.every == 0 {
        bail!("--phase-frames and --every must be at least 1");
    }
    let mut csv = match &o.csv {
        Some(path) => {
            crate::atomic::check_target(path)?;
            Some(csv::Writer::from_writer(Vec::new()))
        }
        None => None,
    };
    let started = Instant::now();
    let spec = o.scene.spec(inputs);
    let (width, height) = o.size;
    let mut h = Headless::new(&spec, width, height, o.msaa, &crate::measure::GpuMeasurer)?;
    let mut lod = ShotLod {
        settle_seconds: 0.0,
        ..ShotLod::default()
    };
    let mut target: Option<Offscreen> = None;
    let mut current: Option<Phase> = None;
    let dt = 1.0 / 30.0;
    let mut readings = Vec::new();
    println!(
        "frame  method     transition  foliage    count  size        resident MB  GPU MB  GPU allocations"
    );
    for frame in 0..o.frames {
        let p = phase(frame / o.phase_frames, spec.count, [width, height], &o.vary);
        if current != Some(p) {
            lod.method = p.method;
            lod.policy.transition = p.transition;
            lod.foliage.policy = p.foliage;
            if current.is_none_or(|c| c.count != p.count) {
                h.world.relayout(None, p.count, None);
            }
            h.show(&lod)?;
            if current.is_none_or(|c| c.size != p.size) {
                // The old target goes before the new one is made, as a resized window's do.
                target = None;
                if p.size[0] > 0 && p.size[1] > 0 {
                    target = Some(Offscreen::new(&h.gpu, p.size[0], p.size[1], h.samples));
                }
            }
            current = Some(p);
        }
        let time = frame as f32 * dt;
        match &target {
            Some(t) => {
                h.world.prepare(&h.gpu, p.size, time, dt);
                h.world.renderer.render_to(&h.gpu, &t.targets, &t.view)?;
                h.gpu.wait()?;
            }
            // Minimised: the scene's time runs on, nothing is drawn.
            None => h.world.select(height, time, dt),
        }
        if (frame + 1) % o.every == 0 {
            let r = read_memory(&h.gpu, frame + 1);
            let size = format!("{}x{}", p.size[0], p.size[1]);
            let figure = |x: Option<f64>| x.map_or("-".into(), |x| format!("{x:.1}"));
            println!(
                "{:>5}  {:<9}  {:<10}  {:<9}  {:>5}  {:<10}  {:>11}  {:>6}  {:>15}",
                r.frame,
                p.method.name(),
                p.transition.name(),
                p.foliage.name(),
                p.count,
                size,
                figure(r.resident_mb),
                figure(r.gpu_mb),
                r.gpu_allocations.map_or("-".into(), |n| n.to_string()),
            );
            std::io::stdout().flush().ok();
            if let Some(w) = &mut csv {
                w.write_record([
                    r.frame.to_string(),
                    r.resident_mb.map_or(String::new(), |x| format!("{x:.3}")),
                    r.gpu_mb.map_or(String::new(), |x| format!("{x:.3}")),
                    r.gpu_allocations.map_or(String::new(), |n| n.to_string()),
                ])?;
            }
            readings.push(r);
        }
    }
    if let (Some(w), Some(path)) = (csv, &o.csv) {
        let mut out = b"frame,resident_mb,gpu_mb,gpu_allocations\n".to_vec();
        out.extend(w.into_inner()?);
        crate::atomic::write(path, &out)?;
    }
    let cycle_frames = CYCLE * o.phase_frames;
    let steady: Vec<&Reading> = readings
        .iter()
        .filter(|r| r.frame >= cycle_frames)
        .collect();
    let growth_mb = match (steady.first(), steady.last()) {
        (Some(a), Some(b)) if steady.len() >= 2 => {
            b.resident_mb.zip(a.resident_mb).map(|(b, a)| b - a)
        }
        _ => None,
    };
    let aligned = o.every.is_multiple_of(cycle_frames);
    let gpu_steady = match steady.first() {
        Some(first) if aligned && steady.len() >= 2 && first.gpu_mb.is_some() => Some(
            steady
                .iter()
                .all(|r| (r.gpu_mb, r.gpu_allocations) == (first.gpu_mb, first.gpu_allocations)),
        ),
        _ => None,
    };
    Ok(SoakReport {
        readings,
        growth_mb,
        gpu_steady,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// `lodlab soak`: frames through every setting, memory read as they go; exit 1 on growth.
pub fn command(a: SoakArgs, inputs: &crate::runtime::spec::BakeInputs) -> anyhow::Result<ExitCode> {
    let r = run(&a, inputs)?;
    let max_growth_mb = a.max_growth_mb as f64;
    let growth = r.growth_mb.map_or(
        "not measured (fewer than two readings after the first cycle)".into(),
        |g| format!("{g:+.1} MB"),
    );
    let gpu = match r.gpu_steady {
        Some(true) => "the same at every reading after the first cycle",
        Some(false) => "NOT the same at every reading after the first cycle",
        None => "not compared (readings not aligned with the cycle, or no figures)",
    };
    println!(
        "lodlab soak: {} frames in {:.0} s; resident growth after the first cycle {growth}; GPU memory {gpu}",
        a.frames, r.seconds
    );
    if r.growth_mb.is_some_and(|g| g > max_growth_mb) || r.gpu_steady == Some(false) {
        eprintln!(
            "error: memory grew (limit {} MB resident, GPU figures must repeat)",
            max_growth_mb
        );
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One cycle meets every method, transition and foliage policy, a minimised (0×0) and a
    /// 1×1 frame and three character counts, and the next starts where it started.
    #[test]
    fn the_cycle_meets_every_setting() {
        let all = [
            Setting::Method,
            Setting::Transition,
            Setting::Foliage,
            Setting::Count,
            Setting::Size,
        ];
        let phases: Vec<Phase> = (0..CYCLE).map(|k| phase(k, 30, [320, 180], &all)).collect();
        for m in LodMethod::ALL {
            assert!(phases.iter().any(|p| p.method == m), "{m:?}");
        }
        for t in Transition::ALL {
            assert!(phases.iter().any(|p| p.transition == t), "{t:?}");
        }
        for f in FoliagePolicy::ALL {
            assert!(phases.iter().any(|p| p.foliage == f), "{f:?}");
        }
        for size in [[0, 0], [1, 1], [320, 180]] {
            assert!(phases.iter().any(|p| p.size == size), "{size:?}");
        }
        for count in [30, 10, 1] {
            assert!(phases.iter().any(|p| p.count == count), "{count}");
        }
        assert_eq!(phase(CYCLE, 30, [320, 180], &all), phases[0]);
        // A setting left out of `vary` stays put.
        let fixed: Vec<Phase> = (0..CYCLE)
            .map(|k| phase(k, 30, [320, 180], &[Setting::Size]))
            .collect();
        assert!(
            fixed
                .iter()
                .all(|p| p.method == LodMethod::None && p.count == 30)
        );
    }
}

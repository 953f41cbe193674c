//! Progress of a long job counted in steps: indicatif's bar where stderr is a terminal, and
//! where it is not (a log, CI, `2> file`) a plain line every few seconds, so that a job of
//! minutes never runs silent.

use indicatif::ProgressBar;
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::Instant;

/// Seconds between lines where stderr is not a terminal.
const EVERY: f32 = 5.0;

pub struct Progress {
    label: String,
    total: u64,
    bar: Option<ProgressBar>,
    /// Lines where there is no bar: steps done and when the last line was said; None when
    /// nothing is shown.
    lines: Option<Mutex<(u64, Instant)>>,
    start: Instant,
}

impl Progress {
    /// Progress of `total` steps of `label`, shown where `show`.
    pub fn new(show: bool, label: impl Into<String>, total: u64) -> Progress {
        let label = label.into();
        let terminal = std::io::stderr().is_terminal();
        let bar = (show && terminal).then(|| {
            let bar = ProgressBar::new(total);
            bar.set_style(crate::app::commands::bake::bar_style());
            bar.set_prefix(label.clone());
            bar
        });
        Progress {
            lines: (show && !terminal).then(|| Mutex::new((0, Instant::now()))),
            label,
            total,
            bar,
            start: Instant::now(),
        }
    }

    /// One more step done.
    pub fn inc(&self) {
        if let Some(bar) = &self.bar {
            bar.inc(1);
        }
        if let Some(lines) = &self.lines
            && let Ok(mut state) = lines.lock()
        {
            state.0 += 1;
            if state.1.elapsed().as_secs_f32() >= EVERY {
                state.1 = Instant::now();
                eprintln!(
                    "lodlab: {}: {}/{} after {:.0} s",
                    self.label,
                    state.0,
                    self.total,
                    self.start.elapsed().as_secs_f32()
                );
            }
        }
    }

    /// The job is over: the bar goes.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

//! Progress of a long job counted in steps: indicatif's bar where stderr is a terminal, and
//! where it is not (a log, CI, `2> file`) a plain line every few seconds, so that a job of
//! minutes never runs silent.

use indicatif::ProgressBar;
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::Instant;

/// Seconds between lines where stderr is not a terminal.
const EVERY: f32 = 5.0;

/// Steps done, when the last line was said, the stage named last and every stage said.
type Lines = (u64, Instant, String, Vec<String>);

pub struct Progress {
    label: String,
    total: u64,
    bar: Option<ProgressBar>,
    /// Lines where there is no bar: steps done, when the last line was said, the stage named
    /// last and every stage said so far; None when nothing is shown.
    lines: Option<Mutex<Lines>>,
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
            lines: (show && !terminal)
                .then(|| Mutex::new((0, Instant::now(), String::new(), Vec::new()))),
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
        self.advance(|done| *done += 1);
    }

    /// `f` (0 to 1) of the job done, for jobs measured in fractions (`total` then counts
    /// thousandths).
    pub fn set_fraction(&self, f: f32) {
        let steps = (f.clamp(0.0, 1.0) as f64 * self.total as f64) as u64;
        if let Some(bar) = &self.bar {
            bar.set_position(steps);
        }
        self.advance(|done| *done = steps);
    }

    /// The job has come to a stage of its own (`measuring`, a method's name): on the bar, or
    /// said at once on a line the first time it comes (stages that take turns, as a bench's
    /// methods do, are then named in the lines every few seconds).
    pub fn set_stage(&self, stage: &str) {
        if let Some(bar) = &self.bar {
            bar.set_message(stage.to_string());
        }
        if let Some(lines) = &self.lines
            && let Ok(mut state) = lines.lock()
            && state.2 != stage
        {
            state.2 = stage.to_string();
            if state.3.iter().any(|s| s == stage) {
                return;
            }
            state.3.push(stage.to_string());
            state.1 = Instant::now();
            eprintln!(
                "lodlab: {}: {stage} after {:.0} s",
                self.label,
                self.start.elapsed().as_secs_f32()
            );
        }
    }

    /// Where there is no bar: moves the count by `step`, and says it every [`EVERY`] seconds.
    fn advance(&self, step: impl FnOnce(&mut u64)) {
        if let Some(lines) = &self.lines
            && let Ok(mut state) = lines.lock()
        {
            step(&mut state.0);
            if state.1.elapsed().as_secs_f32() >= EVERY {
                state.1 = Instant::now();
                let stage = if state.2.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", state.2)
                };
                eprintln!(
                    "lodlab: {}{stage}: {}/{} after {:.0} s",
                    self.label,
                    state.0,
                    self.total,
                    self.start.elapsed().as_secs_f32()
                );
            }
        }
    }

    /// The job is over, and `message` says how it went: kept on the bar's line, or said.
    pub fn finish_with(&self, message: String) {
        if let Some(bar) = &self.bar {
            bar.finish_with_message(message);
        } else if self.lines.is_some() {
            eprintln!("lodlab: {}: {message}", self.label);
        }
    }

    /// The job is over: the bar goes.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

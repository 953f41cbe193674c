//! The study's plan (`plan.toml`) and its manifest (`study.json`): what `study make` reads and
//! writes, and what the sessions, the analysis and the proxy read back.

use crate::app::commands::record::RecordReport;
use crate::scene::camera_path::PathKind;
use crate::scene::{LodMethod, Transition};
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The study's description, as `plan.toml` holds it (see docs/study-plan.toml).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    /// Models shown, one per clip (built-in names or glTF paths).
    pub models: Vec<String>,
    /// Method pairs compared, e.g. [["rest-pose", "as"], ["as", "as+is"]].
    pub pairs: Vec<[LodMethod; 2]>,
    /// Pixel tolerances the methods run at.
    pub tolerances: Vec<f32>,
    pub participants: usize,
    /// Copies of the model in every clip.
    #[serde(default = "default_count")]
    pub count: usize,
    #[serde(default = "default_seconds")]
    pub seconds: f32,
    #[serde(default = "default_fps")]
    pub fps: u32,
    /// "WIDTHxHEIGHT".
    #[serde(default = "default_size")]
    pub size: String,
    #[serde(default = "default_transition")]
    pub transition: Transition,
    #[serde(default = "default_path")]
    pub path: PathKind,
    /// Seeds the participants' orders.
    #[serde(default)]
    pub seed: u64,
    /// A training block before the test (answers discarded).
    #[serde(default = "default_training")]
    pub training: bool,
}

fn default_count() -> usize {
    100
}
fn default_seconds() -> f32 {
    8.0
}
fn default_fps() -> u32 {
    30
}
fn default_size() -> String {
    "1280x720".into()
}
fn default_transition() -> Transition {
    Transition::Morph
}
fn default_path() -> PathKind {
    PathKind::Spiral
}
fn default_training() -> bool {
    true
}

/// One comparison: a model, two methods at one tolerance.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Condition {
    pub model: String,
    pub method_a: LodMethod,
    pub method_b: LodMethod,
    pub tolerance_px: f32,
}

impl Condition {
    /// "horse, rest-pose vs as, 1.5 px".
    pub fn label(&self) -> String {
        format!(
            "{}, {} vs {}, {} px",
            self.model, self.method_a, self.method_b, self.tolerance_px
        )
    }
}

/// A rendered clip of the study.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Clip {
    pub model: String,
    pub method: LodMethod,
    pub tolerance_px: f32,
    /// Relative to the study folder.
    pub file: String,
    pub record: Option<RecordReport>,
}

/// `DIR/study.json`: the plan, its conditions and its clips.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    pub plan: Plan,
    pub conditions: Vec<Condition>,
    pub clips: Vec<Clip>,
    pub participants: Vec<String>,
}

pub const MANIFEST: &str = "study.json";
/// `DIR/making.json`: while `study make` runs, the plan and the clips recorded so far (a
/// [`Manifest`] without conditions or participants), so that a run that was interrupted (even
/// by SIGKILL) is resumed by the next, and a folder holding it is known to be this study's.
pub const MAKING: &str = "making.json";
pub const ANSWERS: &str = "answers.csv";
pub const SESSIONS: &str = "sessions";
pub const CLIPS: &str = "clips";

/// The example plan (docs/study-plan.toml), compiled in: `--plan example` works from any
/// folder.
pub const EXAMPLE_PLAN: &str = include_str!("../../../docs/study-plan.toml");

impl Plan {
    /// The plan in the file `path`, or the example plan for `example` (where no such file
    /// is in the working folder).
    pub fn read(path: &Path) -> Result<Plan> {
        let text = if path == Path::new("example") && !path.exists() {
            EXAMPLE_PLAN.to_string()
        } else {
            std::fs::read_to_string(path)
                .with_context(|| format!("{}: cannot read", path.display()))?
        };
        let plan: Plan = toml::from_str(&text).map_err(|e| {
            let msg = e.message().replace('\n', " ");
            anyhow::anyhow!("{}: not a study plan: {}", path.display(), msg.trim())
        })?;
        plan.check()
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        Ok(plan)
    }

    /// Everything a study needs to make sense, said in one line where it does not.
    pub fn check(&self) -> std::result::Result<(), String> {
        if self.models.is_empty() || self.pairs.is_empty() || self.tolerances.is_empty() {
            return Err("a plan needs models, pairs and tolerances".into());
        }
        if self.participants == 0 {
            return Err("a plan needs at least one participant".into());
        }
        if let Some([a, b]) = self.pairs.iter().find(|[a, b]| a == b) {
            return Err(format!("pair {a} vs {b} compares a method with itself"));
        }
        if let Some(t) = self.tolerances.iter().find(|t| !(0.25..=16.0).contains(*t)) {
            return Err(format!("tolerance {t} must be between 0.25 and 16 pixels"));
        }
        self.size()?;
        if !(self.seconds.is_finite() && self.seconds > 0.0) || self.fps == 0 || self.count == 0 {
            return Err("seconds, fps and count must be positive".into());
        }
        Ok(())
    }

    pub fn size(&self) -> std::result::Result<(u32, u32), String> {
        let bad = || format!("size '{}' is not WIDTHxHEIGHT", self.size);
        let (w, h) = self.size.split_once(['x', 'X']).ok_or_else(bad)?;
        let w: u32 = w.trim().parse().map_err(|_| bad())?;
        let h: u32 = h.trim().parse().map_err(|_| bad())?;
        if w < 16 || h < 16 || w > 8192 || h > 8192 {
            return Err(bad());
        }
        Ok((w, h))
    }

    /// Every (model, pair, tolerance), in plan order.
    pub fn conditions(&self) -> Vec<Condition> {
        let mut out = Vec::new();
        for model in &self.models {
            for [a, b] in &self.pairs {
                for &t in &self.tolerances {
                    out.push(Condition {
                        model: model.clone(),
                        method_a: *a,
                        method_b: *b,
                        tolerance_px: t,
                    });
                }
            }
        }
        out
    }

    /// The distinct clips the conditions need, each once.
    pub fn clips(&self) -> Vec<Clip> {
        let mut out: Vec<Clip> = Vec::new();
        for c in self.conditions() {
            for m in [c.method_a, c.method_b] {
                if out.iter().any(|k| {
                    k.model == c.model && k.method == m && k.tolerance_px == c.tolerance_px
                }) {
                    continue;
                }
                out.push(Clip {
                    model: c.model.clone(),
                    method: m,
                    tolerance_px: c.tolerance_px,
                    file: clip_file(&c.model, m, c.tolerance_px),
                    record: None,
                });
            }
        }
        out
    }

    /// Participant ids: P01, P02, …
    pub fn participant_ids(&self) -> Vec<String> {
        let width = self.participants.to_string().len().max(2);
        (1..=self.participants)
            .map(|k| format!("P{k:0width$}"))
            .collect()
    }
}

/// `clips/horse-as-is-1.5px.mp4`: the model's file stem, the method with '+' spelled out.
pub(crate) fn clip_file(model: &str, method: LodMethod, tolerance: f32) -> String {
    format!(
        "{CLIPS}/{}-{}-{}px.mp4",
        model_stem(model),
        file_safe(method.name()),
        tolerance
    )
}

/// A model's name as clip files start with it: its file stem, made [`file_safe`].
pub(crate) fn model_stem(model: &str) -> String {
    let stem = Path::new(model)
        .file_stem()
        .map_or_else(|| model.to_string(), |s| s.to_string_lossy().into_owned());
    file_safe(&stem)
}

/// `s` with '+' spelled '-' and anything but ASCII letters, digits, '-' and '.' made '_'.
fn file_safe(s: &str) -> String {
    s.replace('+', "-")
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Reads `DIR/study.json`.
pub fn read_manifest(dir: &Path) -> Result<Manifest> {
    let path = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    serde_json::from_str(&text)
        .map_err(|e| anyhow::anyhow!("{}: not a study manifest: {e}", path.display()))
}

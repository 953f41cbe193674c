//! `lodlab study`: a perceptual study of level-of-detail methods run the way Merry, Marais &
//! Gain §6.2 ran theirs.
//!
//! - [`make`]: a plan (models, method pairs, pixel tolerances, participants) becomes one clip
//!   per distinct (model, method, tolerance), rendered once by `record`, and one session list per
//!   participant: every pair in both orders (to cancel ordering bias), shuffled per participant,
//!   after a training block of one sample per condition in a random order whose answers are
//!   discarded (the paper found a learning effect in its pilot).
//! - [`session`]: a participant's run: each pair's clips one after the other, never side by
//!   side, then a forced choice; every answer appended to `answers.csv` and flushed at once, so
//!   that a crash loses nothing and a session resumes where it stopped.
//! - [`analyze`]: per condition, the preference counts and share, and a two-sided binomial (sign)
//!   test, training answers excluded; a Markdown table and a bar chart.

pub mod analyze;
pub mod plan;
pub mod proxy;
pub mod session;
pub mod window;

use crate::app::commands::record::{self, RecordOptions};
use crate::atomic::write as write_atomic;
use crate::runtime::headless::ShotLod;
use crate::runtime::spec::SceneSpec;
use crate::scene::{LodMethod, LodPolicy};
use anyhow::{Context, Result, bail};
use plan::{
    ANSWERS, CLIPS, Clip, Condition, MAKING, MANIFEST, Manifest, Plan, SESSIONS, read_manifest,
};
use std::path::{Path, PathBuf};

/// Options of `study make` beyond the plan.
#[derive(Clone, Debug)]
pub struct MakeOptions {
    pub plan: PathBuf,
    pub out: PathBuf,
    pub cache_dir: Option<PathBuf>,
    pub samples: u32,
    pub progress: bool,
}

/// Renders the plan's clips (those not already there from an earlier run of the same plan)
/// and writes the manifest and every participant's session list.
pub fn make(o: &MakeOptions) -> Result<Manifest> {
    let plan = Plan::read(&o.plan)?;
    let manifest_path = o.out.join(MANIFEST);
    let making_path = o.out.join(MAKING);
    let earlier = earlier_clips(o, &plan, &manifest_path, &making_path)?;
    crate::atomic::make_folder(&o.out.join(CLIPS))?;
    let mut clips = plan.clips();
    record_clips(o, &plan, &mut clips, earlier, &manifest_path, &making_path)?;
    let manifest = Manifest {
        conditions: plan.conditions(),
        participants: plan.participant_ids(),
        plan,
        clips,
    };
    write_study(o, &manifest, &manifest_path, &making_path)?;
    Ok(manifest)
}

/// Planning: what the output folder already holds of this plan. The clips of a study in the
/// making that was interrupted, or of a finished study (whose clips are then all reused);
/// nothing for a new or empty folder. Fails rather than overwrite a folder holding another
/// plan's study or anything else.
fn earlier_clips(
    o: &MakeOptions,
    plan: &Plan,
    manifest_path: &Path,
    making_path: &Path,
) -> Result<Vec<Clip>> {
    // A folder already holding another study (or answers) is not overwritten.
    let mut earlier = Vec::new();
    if !manifest_path.exists() && making_path.exists() {
        let text = std::fs::read_to_string(making_path)
            .with_context(|| format!("{}: cannot read", making_path.display()))?;
        let old: Manifest = serde_json::from_str(&text).map_err(|e| {
            anyhow::anyhow!("{}: not a study in the making: {e}", making_path.display())
        })?;
        if old.plan != *plan {
            bail!(
                "{}: holds an interrupted study of another plan; make the new one in another \
                 folder",
                o.out.display()
            );
        }
        eprintln!(
            "{}: resuming a study interrupted after {} clip(s)",
            o.out.display(),
            old.clips.len()
        );
        earlier = old.clips;
    } else if manifest_path.exists() {
        let old: Manifest = read_manifest(&o.out)?;
        earlier = old.clips.clone();
        if old.plan != *plan {
            bail!(
                "{}: holds a study of another plan; make the new one in another folder",
                o.out.display()
            );
        }
    } else if o.out.is_dir()
        && std::fs::read_dir(&o.out)
            .with_context(|| format!("{}: cannot read", o.out.display()))?
            .next()
            .is_some()
    {
        bail!(
            "{}: not empty and not a study; make the study in a new or empty folder",
            o.out.display()
        );
    }
    Ok(earlier)
}

/// Recording: renders each of `clips` not already there (from `earlier`), noting its record
/// in it. Until the study is finished, the clips recorded so far are written to the
/// in-the-making manifest after each, so that an interrupted run resumes where it stopped.
fn record_clips(
    o: &MakeOptions,
    plan: &Plan,
    clips: &mut [Clip],
    earlier: Vec<Clip>,
    manifest_path: &Path,
    making_path: &Path,
) -> Result<()> {
    let total = clips.len();
    // Clips recorded so far, written after each: what a resumed run starts from.
    let mut making = Manifest {
        plan: plan.clone(),
        conditions: Vec::new(),
        clips: earlier.clone(),
        participants: Vec::new(),
    };
    if !manifest_path.exists() {
        write_atomic(
            making_path,
            serde_json::to_string_pretty(&making)?.as_bytes(),
        )?;
    }
    for (k, clip) in clips.iter_mut().enumerate() {
        let file = o.out.join(&clip.file);
        // A clip file an interrupted run left is complete (written atomically) but has no
        // record unless the run got to note it: such a one is recorded again.
        let noted = earlier
            .iter()
            .any(|c| c.file == clip.file && c.record.is_some());
        if file.exists() && (noted || manifest_path.exists()) {
            eprintln!("clip {}/{total}: {} (there already)", k + 1, clip.file);
            clip.record = earlier
                .iter()
                .find(|c| c.file == clip.file)
                .and_then(|c| c.record.clone());
            continue;
        }
        eprintln!("clip {}/{total}: {}", k + 1, clip.file);
        let report = record::run(&clip_options(
            plan,
            &clip.model,
            clip.method,
            clip.tolerance_px,
            file,
            o.cache_dir.clone(),
            o.samples,
            o.progress,
        )?)?;
        clip.record = Some(report);
        if !manifest_path.exists() {
            making.clips.retain(|c| c.file != clip.file);
            making.clips.push(clip.clone());
            write_atomic(
                making_path,
                serde_json::to_string_pretty(&making)?.as_bytes(),
            )?;
        }
    }
    Ok(())
}

/// Writing files: every participant's session list, then the manifest, and last the
/// in-the-making manifest goes, so that a study with a manifest is a finished one.
fn write_study(
    o: &MakeOptions,
    manifest: &Manifest,
    manifest_path: &Path,
    making_path: &Path,
) -> Result<()> {
    let sessions = o.out.join(SESSIONS);
    crate::atomic::make_folder(&sessions)?;
    for id in &manifest.participants {
        let trials = session::plan_session(manifest, id);
        write_atomic(
            &sessions.join(format!("{id}.json")),
            serde_json::to_string_pretty(&trials)?.as_bytes(),
        )?;
    }
    write_atomic(
        manifest_path,
        serde_json::to_string_pretty(manifest)?.as_bytes(),
    )?;
    if making_path.exists() {
        std::fs::remove_file(making_path)
            .with_context(|| format!("{}: cannot remove", making_path.display()))?;
    }
    Ok(())
}

/// How a plan's clip of `model` drawn by `method` at `tolerance` is recorded into `out`: the
/// plan's crowd, size, frame rate, length, camera path and transition. `make` records the
/// study's clips with it, `proxy` the full-detail references, so the two match frame by frame.
#[allow(clippy::too_many_arguments)]
pub fn clip_options(
    plan: &Plan,
    model: &str,
    method: LodMethod,
    tolerance: f32,
    out: PathBuf,
    cache_dir: Option<PathBuf>,
    samples: u32,
    progress: bool,
) -> Result<RecordOptions> {
    let (width, height) = plan.size().map_err(anyhow::Error::msg)?;
    Ok(RecordOptions {
        spec: SceneSpec {
            scene: crate::scene::SceneKind::Study,
            models: vec![model.to_string()],
            count: plan.count,
            cache_dir,
            ..Default::default()
        },
        lod: ShotLod {
            method,
            policy: LodPolicy {
                tolerance_px: tolerance,
                transition: plan.transition,
                ..Default::default()
            },
            ..Default::default()
        },
        width,
        height,
        samples,
        fps: plan.fps,
        seconds: plan.seconds,
        path: plan.path,
        out,
        frames_dir: None,
        progress,
    })
}

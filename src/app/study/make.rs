//! `study make`: a plan's clips, each rendered once, and every participant's session list;
//! or, with `--shard K/N`, one batch job's share of the clips ([`super::shards`]).

use super::plan::{CLIPS, Clip, MAKING, MANIFEST, Manifest, Plan, SESSIONS, read_manifest};
use super::shards::{SHARDS, ShardRecord, check_record, read_record, recorded_clips};
use crate::app::commands::record::{self, RecordOptions};
use crate::app::shard::Shard;
use crate::atomic::write as write_atomic;
use crate::runtime::headless::ShotLod;
use crate::runtime::spec::SceneSpec;
use crate::scene::{LodMethod, LodPolicy};
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};

/// How a study's clips are rendered: what `make` and `proxy` share, so that the clips and
/// their full-detail references match.
#[derive(Clone, Debug)]
pub struct ClipRendering {
    pub cache_dir: Option<PathBuf>,
    /// Multisampling.
    pub samples: u32,
    /// Progress lines on stderr.
    pub progress: bool,
    /// How the clips' models are read and their levels cut (the global options).
    pub inputs: crate::runtime::spec::BakeInputs,
}

/// Options of `study make` beyond the plan.
#[derive(Clone, Debug)]
pub struct MakeOptions {
    pub plan: PathBuf,
    pub out: PathBuf,
    pub rendering: ClipRendering,
    /// Merge only: every clip must be there already (made by the shards); fail naming the
    /// missing ones instead of rendering them.
    pub merge: bool,
}

/// Renders the plan's clips (those not already there from an earlier run of the same plan,
/// or from its shards) and writes the manifest and every participant's session list.
pub fn make(o: &MakeOptions) -> Result<Manifest> {
    let plan = Plan::read(&o.plan)?;
    let manifest_path = o.out.join(MANIFEST);
    let making_path = o.out.join(MAKING);
    let mut earlier = earlier_clips(o, &plan, &manifest_path, &making_path)?;
    // Shards count until they are merged; a finished study's clips are in its manifest.
    if !manifest_path.exists() {
        earlier.extend(recorded_clips(&o.out, &plan, o.rendering.samples)?);
    }
    crate::atomic::make_folder(&o.out.join(CLIPS))?;
    let mut clips = plan.clips();
    if o.merge {
        let missing: Vec<&str> = clips
            .iter()
            .filter(|c| !o.out.join(&c.file).exists() || !noted(&earlier, &c.file))
            .map(|c| c.file.as_str())
            .collect();
        if !missing.is_empty() {
            bail!(
                "{}: {} of {} clips are not made yet: {}",
                o.out.display(),
                missing.len(),
                clips.len(),
                missing.join(", ")
            );
        }
    }
    let finished = manifest_path.exists();
    // Clips recorded so far, written after each: what a resumed run starts from.
    let mut making = Manifest {
        plan: plan.clone(),
        conditions: Vec::new(),
        clips: earlier.clone(),
        participants: Vec::new(),
    };
    if !finished {
        write_atomic(
            &making_path,
            serde_json::to_string_pretty(&making)?.as_bytes(),
        )?;
    }
    record_clips(
        o,
        &plan,
        &mut clips,
        &earlier,
        finished,
        |_| true,
        |clip| {
            if finished {
                return Ok(());
            }
            making.clips.retain(|c| c.file != clip.file);
            making.clips.push(clip.clone());
            write_atomic(
                &making_path,
                serde_json::to_string_pretty(&making)?.as_bytes(),
            )
        },
    )?;
    let manifest = Manifest {
        conditions: plan.conditions(),
        participants: plan.participant_ids(),
        plan,
        clips,
    };
    write_study(o, &manifest, &manifest_path, &making_path)?;
    Ok(manifest)
}

/// Whether `earlier` notes clip `file` with its record.
fn noted(earlier: &[Clip], file: &str) -> bool {
    earlier.iter().any(|c| c.file == file && c.record.is_some())
}

/// Planning: what the output folder already holds of this plan. The clips of a study in the
/// making that was interrupted, or of a finished study (whose clips are then all reused);
/// nothing for a new or empty folder, or one holding only shards' clips. Fails rather than
/// overwrite a folder holding another plan's study or anything else.
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
        if !old.clips.is_empty() {
            eprintln!(
                "{}: resuming a study interrupted after {} clip(s)",
                o.out.display(),
                old.clips.len()
            );
        }
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
            .filter_map(|e| e.ok())
            // Shards of a study (checked against the plan later) and their clips; clips
            // without the shards' records are not ours to overwrite.
            .any(|e| {
                !(e.file_name() == SHARDS
                    || (e.file_name() == CLIPS && o.out.join(SHARDS).is_dir()))
            })
    {
        bail!(
            "{}: not empty and not a study; make the study in a new or empty folder",
            o.out.display()
        );
    }
    Ok(earlier)
}

/// Recording: renders each of `clips` that `take` picks (by its index) and that is not
/// already there (from `earlier`), and calls `note` with it once recorded, so that an
/// interrupted run resumes where it stopped.
fn record_clips(
    o: &MakeOptions,
    plan: &Plan,
    clips: &mut [Clip],
    earlier: &[Clip],
    finished: bool,
    take: impl Fn(usize) -> bool,
    mut note: impl FnMut(&Clip) -> Result<()>,
) -> Result<()> {
    let total = clips.len();
    for (k, clip) in clips.iter_mut().enumerate() {
        if !take(k) {
            continue;
        }
        let file = o.out.join(&clip.file);
        // A clip file an interrupted run left is complete (written atomically) but has no
        // record unless the run got to note it: such a one is recorded again.
        if file.exists() && (noted(earlier, &clip.file) || finished) {
            eprintln!("clip {}/{total}: {} (there already)", k + 1, clip.file);
            clip.record = earlier
                .iter()
                .find(|c| c.file == clip.file && c.record.is_some())
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
            &o.rendering,
        )?)?;
        clip.record = Some(report);
        note(clip)?;
    }
    Ok(())
}

/// What one shard's run did.
pub struct ShardMade {
    pub record: ShardRecord,
    /// Clips of the whole study.
    pub total: usize,
    /// Clips this shard rendered now (the rest of its share was there already).
    pub rendered: usize,
}

/// Renders shard `shard`'s share of the plan's clips into `o.out` (those not there already)
/// and notes each in the shard's file.
pub fn make_shard(o: &MakeOptions, shard: Shard) -> Result<ShardMade> {
    let plan = Plan::read(&o.plan)?;
    let earlier = earlier_clips(o, &plan, &o.out.join(MANIFEST), &o.out.join(MAKING))?;
    let folder = o.out.join(SHARDS);
    crate::atomic::make_folder(&o.out.join(CLIPS))?;
    crate::atomic::make_folder(&folder)?;
    let path = folder.join(format!("{}.json", shard.file_stem()));
    let mut record = match read_record(&path)? {
        Some(r) => {
            check_record(&path, &r, &plan, o.rendering.samples)?;
            r
        }
        None => ShardRecord {
            shard,
            plan: plan.clone(),
            samples: o.rendering.samples,
            version: env!("CARGO_PKG_VERSION").to_string(),
            clips: Vec::new(),
        },
    };
    let mut known = earlier;
    known.extend(record.clips.iter().cloned());
    let mut clips = plan.clips();
    let total = clips.len();
    let mut rendered = 0;
    write_atomic(&path, serde_json::to_string_pretty(&record)?.as_bytes())?;
    record_clips(
        o,
        &plan,
        &mut clips,
        &known,
        false,
        |k| shard.takes(k),
        |clip| {
            rendered += 1;
            record.clips.retain(|c| c.file != clip.file);
            record.clips.push(clip.clone());
            write_atomic(&path, serde_json::to_string_pretty(&record)?.as_bytes())
        },
    )?;
    // Clips of the share that were there already (from a finished study, say) are noted too.
    for (k, clip) in clips.iter().enumerate() {
        if shard.takes(k) && clip.record.is_some() && !noted(&record.clips, &clip.file) {
            record.clips.push(clip.clone());
        }
    }
    write_atomic(&path, serde_json::to_string_pretty(&record)?.as_bytes())?;
    Ok(ShardMade {
        record,
        total,
        rendered,
    })
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
        let trials = super::session::plan_session(manifest, id);
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
pub fn clip_options(
    plan: &Plan,
    model: &str,
    method: LodMethod,
    tolerance: f32,
    out: PathBuf,
    rendering: &ClipRendering,
) -> Result<RecordOptions> {
    let ClipRendering {
        cache_dir,
        samples,
        progress,
        inputs,
    } = rendering.clone();
    let (width, height) = plan.size().map_err(anyhow::Error::msg)?;
    Ok(RecordOptions {
        spec: SceneSpec {
            scene: crate::scene::SceneKind::Study,
            models: vec![model.to_string()],
            count: plan.count,
            cache_dir,
            inputs,
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

//! `study make --shard K/N`: one batch job's share of a study's clips. Clip `i` of the plan
//! (in [`Plan::clips`] order) is shard `i mod N + 1`'s ([`Shard`]). Each shard notes what it
//! recorded, and with which options, in `DIR/shards/K-of-N.json` (its own file, so shards on
//! other machines writing into one shared folder never touch each other's); it writes no
//! manifest and no sessions. `study make` without `--shard` over the same folder is the merge:
//! it takes every shard's clips whose plan and options match its own (failing on one that does
//! not), renders what is missing (or, with `--merge`, fails naming it), and writes the study.

use super::plan::{Clip, Plan};
use crate::app::shard::Shard;
use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::path::Path;

pub const SHARDS: &str = "shards";

/// `DIR/shards/K-of-N.json`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardRecord {
    pub shard: Shard,
    pub plan: Plan,
    /// `--msaa` of the clips: the one option of `make` that changes a clip beyond the plan.
    pub samples: u32,
    /// The lodlab that made them.
    pub version: String,
    /// The shard's clips recorded so far, each with its record.
    pub clips: Vec<Clip>,
}

/// Every clip the shards in `DIR/shards/` recorded (with their records), after checking that
/// each shard was made from `plan` with the same `samples`; nothing where there are no shards.
pub fn recorded_clips(dir: &Path, plan: &Plan, samples: u32) -> Result<Vec<Clip>> {
    let folder = dir.join(SHARDS);
    let entries = match std::fs::read_dir(&folder) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e).with_context(|| format!("{}: cannot read", folder.display())),
    };
    let mut paths: Vec<_> = entries
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    paths.sort();
    let mut clips = Vec::new();
    for path in paths {
        let Some(r) = read_record(&path)? else {
            continue;
        };
        check_record(&path, &r, plan, samples)?;
        for clip in r.clips {
            if !dir.join(&clip.file).exists() {
                bail!(
                    "{}: notes {} but the file is missing",
                    path.display(),
                    clip.file
                );
            }
            clips.push(clip);
        }
    }
    Ok(clips)
}

pub(super) fn read_record(path: &Path) -> Result<Option<ShardRecord>> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e).with_context(|| format!("{}: cannot read", path.display())),
    };
    serde_json::from_str(&text)
        .map(Some)
        .map_err(|e| anyhow::anyhow!("{}: not a shard's record: {e}", path.display()))
}

/// A shard's clips join a study only if made from the same plan, with the same options, by the
/// same lodlab.
pub(super) fn check_record(path: &Path, r: &ShardRecord, plan: &Plan, samples: u32) -> Result<()> {
    if r.plan != *plan {
        bail!(
            "{}: made from another plan; make the new study in another folder",
            path.display()
        );
    }
    let version = env!("CARGO_PKG_VERSION");
    if r.version != version {
        bail!(
            "{}: its clips were made by lodlab {}, this is {version}",
            path.display(),
            r.version
        );
    }
    if r.samples != samples {
        bail!(
            "{}: its clips were made with --msaa {}, this run asks for {samples}",
            path.display(),
            r.samples
        );
    }
    Ok(())
}

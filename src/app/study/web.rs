//! `lodlab study web`: a study as a static site that runs online, where participants install
//! nothing. The clips are `study make`'s (H.264 MP4, which every current browser plays); the
//! page (`index.html`, `study.js`, compiled in from `assets/web/study/`) runs one
//! participant's session exactly as `study run` does, with the same trials in the same order,
//! the same wording, grey gap and keys, and keeps each answer in the browser's storage at once
//! so that a reload resumes. At the end it downloads the answers as `answers-ID.csv`, in the
//! columns of `answers.csv`, and POSTs them to the researcher's URL where one is given;
//! `study analyze` reads those files beside the desktop's.
//!
//! A runner of our own rather than a jsPsych timeline (jsPsych is MIT-licensed and would fit):
//! the session is four screens, and a page with no third-party code works from any static host
//! and from `file://`, offline, with nothing fetched from elsewhere.

use super::plan::{Condition, Manifest};
use super::session::{CHOICES, GAP, HEADER, INSTRUCTIONS, QUESTION, THANKS, Trial, plan_session};
use crate::atomic::write as write_atomic;
use anyhow::{Result, bail};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

const PAGE: &str = include_str!("../../../assets/web/study/index.html");
const RUNNER: &str = include_str!("../../../assets/web/study/study.js");
/// What the page reads: `window.LODLAB_STUDY` (a script, not JSON fetched, so that the page
/// works from `file://` too).
pub const DATA: &str = "study-data.js";

/// Everything the page needs, as `study-data.js` holds it.
#[derive(Serialize)]
struct SiteData<'a> {
    /// Names this study in the browser's storage, so two studies on one host never share
    /// answers.
    study: String,
    gap_ms: u64,
    texts: Texts,
    /// The answer files' columns, in order.
    header: Vec<&'a str>,
    conditions: &'a [Condition],
    sessions: BTreeMap<String, Vec<Trial>>,
    post_url: Option<&'a str>,
}

#[derive(Serialize)]
struct Texts {
    instructions: &'static str,
    question: &'static str,
    choices: &'static str,
    thanks: &'static str,
}

/// The identity of a study: its plan and conditions, hashed.
fn study_id(m: &Manifest) -> Result<String> {
    let key = serde_json::to_vec(&(&m.plan, &m.conditions))?;
    Ok(blake3::hash(&key).to_hex()[..16].to_string())
}

/// The URL answers are POSTed to must be one a page can POST to.
pub fn check_post_url(post_url: Option<&str>) -> Result<()> {
    if let Some(url) = post_url
        && !(url.starts_with("https://") || url.starts_with("http://"))
    {
        bail!("--post '{url}' is not an http:// or https:// URL");
    }
    Ok(())
}

/// The folder of the study folder that holds the site: only what a participant's browser
/// fetches. The study folder beside it also holds the lossless reference frames, the image
/// metrics' verdict (`proxy.md`, `proxy.json`) and the answers collected, none of which a
/// participant should read.
pub const SITE: &str = "site";

/// Writes the site into `SITE` in the study folder `dir` (made by `study make`), for the
/// participants of `m`: the page, its script, the study's data and the clips the sessions
/// play (hard links to the study's where the file system allows, else copies); answers are
/// POSTed to `post_url` where given. Returns the site's folder and the files written in it.
pub fn write_site(
    dir: &Path,
    m: &Manifest,
    post_url: Option<&str>,
) -> Result<(std::path::PathBuf, Vec<String>)> {
    check_post_url(post_url)?;
    let data = SiteData {
        study: study_id(m)?,
        gap_ms: GAP.as_millis() as u64,
        texts: Texts {
            instructions: INSTRUCTIONS,
            question: QUESTION,
            choices: CHOICES,
            thanks: THANKS,
        },
        header: HEADER.split(',').collect(),
        conditions: &m.conditions,
        sessions: m
            .participants
            .iter()
            .map(|id| (id.clone(), plan_session(m, id)))
            .collect(),
        post_url,
    };
    let script = format!(
        "// Written by `lodlab study web`: the study the page runs.\nwindow.LODLAB_STUDY = {};\n",
        serde_json::to_string(&data)?
    );
    let site = dir.join(SITE);
    crate::atomic::make_folder(&site)?;
    let files = [
        ("index.html", PAGE),
        ("study.js", RUNNER),
        (DATA, script.as_str()),
    ];
    for (name, text) in files {
        write_atomic(&site.join(name), text.as_bytes())?;
    }
    let mut written: Vec<String> = files.iter().map(|(n, _)| n.to_string()).collect();
    let clips: std::collections::BTreeSet<&str> = data
        .sessions
        .values()
        .flatten()
        .flat_map(|t| [t.first_clip.as_str(), t.second_clip.as_str()])
        .collect();
    for clip in clips {
        link_or_copy(&dir.join(clip), &site.join(clip))?;
        written.push(clip.to_string());
    }
    Ok((site, written))
}

/// `to` as the same file as `from`: a hard link where the file system allows (a clip is
/// megabytes), else a copy; whatever stood at `to` is replaced.
fn link_or_copy(from: &Path, to: &Path) -> Result<()> {
    use anyhow::Context;
    if let Some(parent) = to.parent() {
        crate::atomic::make_folder(parent)?;
    }
    if std::fs::remove_file(to).is_err() && to.exists() {
        bail!("{}: cannot replace it", to.display());
    }
    if std::fs::hard_link(from, to).is_err() {
        let bytes = std::fs::read(from).with_context(|| format!("{}", from.display()))?;
        write_atomic(to, &bytes)?;
    }
    Ok(())
}

//! A participant's session: the trials in their order, the answers file, and resuming.

use super::plan::{ANSWERS, Manifest, SESSIONS};
use crate::scene::LodMethod;
use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Training answers are collected exactly like the others and discarded (Merry et al. §6.2).
pub const TRAINING: &str = "training";
pub const TEST: &str = "test";

/// What a participant sees and does, the same in the window (`study run`) and online (`study
/// web`): a grey screen of [`GAP`] before each clip, the clips one after the other, then the
/// question, answered with the keys 1 and 2.
pub const GAP: std::time::Duration = std::time::Duration::from_millis(800);
pub const INSTRUCTIONS: &str = "You will see pairs of short clips, one after the other.\n\
     After each pair, press 1 if the first looked better, 2 if the second did.";
pub const QUESTION: &str = "Which clip looked better?";
pub const CHOICES: &str = "1: the first      2: the second";
pub const THANKS: &str = "Thank you: the session is complete.";

/// One sample: a condition's two clips in the order shown.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Trial {
    /// 1-based, in the order the participant sees them.
    pub trial: usize,
    pub block: String,
    /// Index into the manifest's conditions.
    pub condition: usize,
    /// Methods of the first and the second clip shown.
    pub first: LodMethod,
    pub second: LodMethod,
    /// Clip files, relative to the study folder.
    pub first_clip: String,
    pub second_clip: String,
}

/// The trials of participant `id`: a training block of one sample per condition, each in a
/// random order (when the plan has training), then every condition in both orders; each block
/// shuffled. Seeded by the plan's seed and the participant id, so `make` always writes the
/// same lists.
pub fn plan_session(m: &Manifest, id: &str) -> Vec<Trial> {
    let seed = m.plan.seed
        ^ u64::from_le_bytes(
            blake3::hash(id.as_bytes()).as_bytes()[..8]
                .try_into()
                .expect("8 bytes"),
        );
    let mut rng = fastrand::Rng::with_seed(seed);
    let clip = |model: &str, method: LodMethod, t: f32| {
        m.clips
            .iter()
            .find(|c| c.model == model && c.method == method && c.tolerance_px == t)
            .map(|c| c.file.clone())
            .expect("every condition's clips are in the manifest")
    };
    let make = |block: &str, orders: &[(usize, bool)]| -> Vec<Trial> {
        orders
            .iter()
            .map(|&(k, a_first)| {
                let c = &m.conditions[k];
                let (first, second) = if a_first {
                    (c.method_a, c.method_b)
                } else {
                    (c.method_b, c.method_a)
                };
                Trial {
                    trial: 0,
                    block: block.into(),
                    condition: k,
                    first,
                    second,
                    first_clip: clip(&c.model, first, c.tolerance_px),
                    second_clip: clip(&c.model, second, c.tolerance_px),
                }
            })
            .collect()
    };
    let n = m.conditions.len();
    let mut training: Vec<(usize, bool)> = if m.plan.training {
        (0..n).map(|k| (k, rng.bool())).collect()
    } else {
        Vec::new()
    };
    rng.shuffle(&mut training);
    let mut test: Vec<(usize, bool)> = (0..n).flat_map(|k| [(k, true), (k, false)]).collect();
    rng.shuffle(&mut test);
    let mut trials = make(TRAINING, &training);
    trials.extend(make(TEST, &test));
    for (i, t) in trials.iter_mut().enumerate() {
        t.trial = i + 1;
    }
    trials
}

/// One line of `answers.csv`, its fields in this order under [`HEADER`]'s names.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Answer {
    pub participant: String,
    pub trial: usize,
    pub block: String,
    pub model: String,
    pub method_a: LodMethod,
    pub method_b: LodMethod,
    pub tolerance_px: f32,
    pub first: LodMethod,
    pub second: LodMethod,
    /// 1: the first clip shown looked better; 2: the second.
    pub choice: u8,
    /// The method of the clip chosen.
    pub preferred: LodMethod,
    /// Seconds since the Unix epoch.
    #[serde(rename = "unix_time")]
    pub time: u64,
}

pub const HEADER: &str = "participant,trial,block,model,method_a,method_b,tolerance_px,first,second,choice,preferred,unix_time";

/// Every complete answer in `DIR/answers.csv` (none when there is no file yet), and how many
/// lines could not be read (a line cut short by a crash mid-write, say).
pub fn read_answers(dir: &Path) -> Result<(Vec<Answer>, usize)> {
    read_answers_file(&dir.join(ANSWERS))
}

/// Every complete answer in the answers file `path` (none when there is no such file), and
/// how many lines could not be read.
pub fn read_answers_file(path: &Path) -> Result<(Vec<Answer>, usize)> {
    let file = match std::fs::File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok((Vec::new(), 0)),
        Err(e) => return Err(e).with_context(|| format!("{}: cannot read", path.display())),
    };
    let mut reader = csv::ReaderBuilder::new().flexible(true).from_reader(file);
    let mut answers = Vec::new();
    let mut bad = 0;
    for record in reader.deserialize::<Answer>() {
        match record {
            Ok(a) if a.choice == 1 || a.choice == 2 => answers.push(a),
            Ok(_) | Err(_) => bad += 1,
        }
    }
    Ok((answers, bad))
}

/// The answers of a study from every file that holds them: the desktop's `answers.csv` and
/// the files the online study's page downloads (`answers-P01.csv`, …, copied into the folder).
pub struct Answers {
    pub answers: Vec<Answer>,
    /// Each file read, with the answers it added.
    pub files: Vec<(String, usize)>,
    /// Lines that could not be read, per file.
    pub unreadable: Vec<(String, usize)>,
    /// Answers to a trial already answered in a file read earlier (the same participant
    /// answering on the desktop and online, or one file copied twice): the first is kept.
    pub repeated: usize,
}

/// Reads `DIR/answers.csv`, then every `DIR/answers-*.csv` in name order (see [`Answers`]).
pub fn read_all_answers(dir: &Path) -> Result<Answers> {
    let mut paths = vec![dir.join(ANSWERS)];
    let mut online: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot read", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("answers-") && n.ends_with(".csv"))
        })
        .collect();
    online.sort();
    paths.extend(online);
    let mut all = Answers {
        answers: Vec::new(),
        files: Vec::new(),
        unreadable: Vec::new(),
        repeated: 0,
    };
    let mut seen = std::collections::HashSet::new();
    for path in paths {
        if !path.exists() {
            continue;
        }
        let name = path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let (answers, bad) = read_answers_file(&path)?;
        if bad > 0 {
            all.unreadable.push((name.clone(), bad));
        }
        let mut added = 0;
        for a in answers {
            if seen.insert((a.participant.clone(), a.trial)) {
                all.answers.push(a);
                added += 1;
            } else {
                all.repeated += 1;
            }
        }
        all.files.push((name, added));
    }
    Ok(all)
}

/// Appends one answer and makes it durable before returning: the line is written whole, then
/// flushed and synced to the disk.
pub fn append_answer(dir: &Path, answer: &Answer) -> Result<()> {
    let path = dir.join(ANSWERS);
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .with_context(|| format!("{}: cannot write", path.display()))?;
    // The line is encoded whole first, so that it reaches the file in one write.
    let first = file.metadata().map(|m| m.len() == 0).unwrap_or(true);
    let mut writer = csv::WriterBuilder::new()
        .has_headers(first)
        .from_writer(Vec::new());
    writer
        .serialize(answer)
        .with_context(|| format!("{}: cannot encode the answer", path.display()))?;
    let text = writer
        .into_inner()
        .map_err(|e| anyhow::anyhow!("{}: cannot encode the answer: {e}", path.display()))?;
    file.write_all(&text)
        .and_then(|_| file.flush())
        .and_then(|_| file.sync_data())
        .with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(())
}

/// A participant's place in their session.
pub struct Session {
    pub dir: PathBuf,
    pub participant: String,
    pub manifest: Manifest,
    pub trials: Vec<Trial>,
    /// Trials answered so far, by their number.
    answered: Vec<bool>,
}

impl Session {
    /// Opens participant `id`'s session in study folder `dir`, with the answers already given.
    pub fn open(dir: &Path, id: &str) -> Result<Session> {
        let manifest = super::plan::read_manifest(dir)?;
        if !manifest.participants.iter().any(|p| p == id) {
            bail!(
                "{}: no participant '{id}' in this study (participants: {})",
                dir.display(),
                manifest.participants.join(", ")
            );
        }
        let path = dir.join(SESSIONS).join(format!("{id}.json"));
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        let trials: Vec<Trial> = serde_json::from_str(&text)
            .map_err(|e| anyhow::anyhow!("{}: not a session list: {e}", path.display()))?;
        let (answers, bad) = read_answers(dir)?;
        if bad > 0 {
            eprintln!(
                "warning: {}: {bad} line(s) could not be read and are ignored",
                dir.join(ANSWERS).display()
            );
        }
        let mut answered = vec![false; trials.len() + 1];
        for a in answers.iter().filter(|a| a.participant == id) {
            if let Some(slot) = answered.get_mut(a.trial) {
                *slot = true;
            }
        }
        Ok(Session {
            dir: dir.to_path_buf(),
            participant: id.to_string(),
            manifest,
            trials,
            answered,
        })
    }

    /// The next trial without an answer.
    pub fn current(&self) -> Option<&Trial> {
        self.trials.iter().find(|t| !self.answered[t.trial])
    }

    pub fn answered(&self) -> usize {
        self.answered.iter().filter(|&&a| a).count()
    }

    pub fn total(&self) -> usize {
        self.trials.len()
    }

    /// A clip's file.
    pub fn clip(&self, file: &str) -> PathBuf {
        self.dir.join(file)
    }

    /// Records the participant's choice (1 or 2) for the current trial, durably.
    pub fn answer(&mut self, choice: u8) -> Result<()> {
        if choice != 1 && choice != 2 {
            bail!("a choice is 1 or 2, not {choice}");
        }
        let Some(t) = self.current().cloned() else {
            bail!("the session is complete");
        };
        let c = &self.manifest.conditions[t.condition];
        let answer = Answer {
            participant: self.participant.clone(),
            trial: t.trial,
            block: t.block.clone(),
            model: c.model.clone(),
            method_a: c.method_a,
            method_b: c.method_b,
            tolerance_px: c.tolerance_px,
            first: t.first,
            second: t.second,
            choice,
            preferred: if choice == 1 { t.first } else { t.second },
            time: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs()),
        };
        append_answer(&self.dir, &answer)?;
        self.answered[t.trial] = true;
        Ok(())
    }
}

/// Runs a session without a window, the answers given in advance (`1` or `2` each): every clip
/// is still decoded frame by frame at its own rate, as the window would play it. Stops when
/// the session is complete or the answers run out. Returns the answers recorded.
pub fn run_scripted(session: &mut Session, answers: &[u8]) -> Result<usize> {
    let mut given = 0;
    for &choice in answers {
        let Some(t) = session.current().cloned() else {
            break;
        };
        for file in [&t.first_clip, &t.second_clip] {
            play_paced(&session.clip(file))?;
        }
        session.answer(choice)?;
        given += 1;
    }
    Ok(given)
}

/// Decodes a clip frame by frame, one frame per 1 / fps seconds.
fn play_paced(path: &Path) -> Result<()> {
    let mut clip = crate::app::video::ClipReader::open(path)?;
    let period = std::time::Duration::from_secs_f64(1.0 / clip.fps.max(1.0));
    let start = std::time::Instant::now();
    let mut k = 0u32;
    while clip.next_frame()?.is_some() {
        k += 1;
        let due = start + period * k;
        if let Some(wait) = due.checked_duration_since(std::time::Instant::now()) {
            std::thread::sleep(wait);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::character::simplify::Method;

    fn answer(participant: &str, choice: u8) -> Answer {
        Answer {
            participant: participant.into(),
            trial: 3,
            block: "test".into(),
            model: "horse".into(),
            method_a: LodMethod::Simplified(Method::RestPose),
            method_b: LodMethod::AS_IS,
            tolerance_px: 1.5,
            first: LodMethod::AS_IS,
            second: LodMethod::Simplified(Method::RestPose),
            choice,
            preferred: LodMethod::AS_IS,
            time: 1_700_000_000,
        }
    }

    #[test]
    fn answers_round_trip_through_the_file_quoted_where_needed() {
        let dir = tempfile::tempdir().unwrap();
        let odd = answer("Smith, J. \"JS\"", 2);
        append_answer(dir.path(), &answer("P01", 1)).unwrap();
        append_answer(dir.path(), &odd).unwrap();
        let text = std::fs::read_to_string(dir.path().join(ANSWERS)).unwrap();
        assert_eq!(text.lines().next(), Some(HEADER), "one header, first");
        assert_eq!(text.lines().filter(|l| *l == HEADER).count(), 1);
        let (answers, bad) = read_answers(dir.path()).unwrap();
        assert_eq!(bad, 0);
        assert_eq!(answers, vec![answer("P01", 1), odd]);
    }

    #[test]
    fn a_line_cut_short_is_counted_not_read() {
        let dir = tempfile::tempdir().unwrap();
        append_answer(dir.path(), &answer("P01", 1)).unwrap();
        let path = dir.path().join(ANSWERS);
        let mut text = std::fs::read_to_string(&path).unwrap();
        text.push_str("P02,4,test,horse,rest-pose");
        std::fs::write(&path, text).unwrap();
        let (answers, bad) = read_answers(dir.path()).unwrap();
        assert_eq!((answers.len(), bad), (1, 1));
    }
}

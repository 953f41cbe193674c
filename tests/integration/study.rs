//! `lodlab study make → run → analyze` end to end on a small plan (lavapipe in CI): balanced
//! sessions, answers that survive a killed process, a session resumed where it stopped, and the
//! analysis of what was answered.

use crate::common::{lodlab, ok};
use lodlab::app::study::analyze::binomial_two_sided;
use lodlab::app::study::session::{Trial, read_answers};
use lodlab::app::video::probe;
use lodlab::generate::cylinder::bent_cylinder;
use lodlab::generate::glb::to_glb;
use std::collections::HashMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn session(dir: &Path, id: &str) -> Vec<Trial> {
    let text = std::fs::read_to_string(dir.join("sessions").join(format!("{id}.json"))).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Answers that always prefer the pair's second method (the plan lists the newer one second).
fn prefer_b(trials: &[Trial], pairs: &[(&str, &str)]) -> String {
    trials
        .iter()
        .map(|t| {
            let b = pairs[t.condition].1;
            if t.first.name() == b { "1" } else { "2" }
        })
        .collect::<Vec<_>>()
        .join(",")
}

fn answers_of(dir: &Path, id: &str) -> usize {
    read_answers(dir)
        .map(|(a, _)| a.iter().filter(|a| a.participant == id).count())
        .unwrap_or(0)
}

#[test]
fn a_study_is_made_run_and_analyzed() {
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("cylinder.glb");
    std::fs::write(&model, to_glb(&bent_cylinder(24, 16))).unwrap();
    let pairs = [("rest-pose", "as"), ("as", "as+is"), ("rest-pose", "as+is")];
    let plan = tmp.path().join("plan.toml");
    std::fs::write(
        &plan,
        format!(
            "models = [\"{}\"]\npairs = [{}]\ntolerances = [2.0]\nparticipants = 2\n\
             count = 6\nseconds = 0.5\nfps = 10\nsize = \"64x48\"\nseed = 3\n",
            model.display(),
            pairs
                .iter()
                .map(|(a, b)| format!("[\"{a}\", \"{b}\"]"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    )
    .unwrap();
    let dir = tmp.path().join("study");
    let d = dir.display().to_string();
    let cache = tmp.path().join("cache").display().to_string();
    let plan_s = plan.display().to_string();
    ok(&lodlab(&[
        "study", "make", "--plan", &plan_s, "--out", &d, "--cache", &cache, "--msaa", "1",
    ]));

    // No answers yet: analyze says so in one line and writes nothing (not "share B 50%").
    let o = lodlab(&["study", "analyze", &d]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no answers yet"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!dir.join("analysis.md").exists());

    // Every distinct clip once: three methods at one tolerance, 5 frames each.
    let clips: Vec<_> = std::fs::read_dir(dir.join("clips")).unwrap().collect();
    assert_eq!(clips.len(), 3);
    for c in clips {
        let info = probe(&c.unwrap().path()).unwrap();
        assert_eq!((info.frames, info.decoded), (5, 5));
    }

    // Balanced sessions: training first, one sample per condition; then every condition in
    // both orders exactly once; orders differ between participants.
    let sessions: Vec<Vec<Trial>> = ["P01", "P02"].iter().map(|id| session(&dir, id)).collect();
    for trials in &sessions {
        assert_eq!(trials.len(), 3 + 6);
        assert!(trials[..3].iter().all(|t| t.block == "training"));
        assert!(trials[3..].iter().all(|t| t.block == "test"));
        let mut training: Vec<usize> = trials[..3].iter().map(|t| t.condition).collect();
        training.sort();
        assert_eq!(training, vec![0, 1, 2]);
        let mut orders: HashMap<(usize, String), usize> = HashMap::new();
        for t in &trials[3..] {
            let (a, b) = pairs[t.condition];
            assert!(
                (t.first.name() == a && t.second.name() == b)
                    || (t.first.name() == b && t.second.name() == a),
                "{t:?}"
            );
            assert!(t.first_clip.contains(&t.first.name().replace('+', "-")));
            *orders
                .entry((t.condition, t.first.to_string()))
                .or_default() += 1;
        }
        assert_eq!(orders.len(), 6, "each condition in both orders");
        assert!(orders.values().all(|&n| n == 1));
        for (k, t) in trials.iter().enumerate() {
            assert_eq!(t.trial, k + 1);
        }
    }
    let order = |s: &[Trial]| s.iter().map(|t| (t.condition, t.first)).collect::<Vec<_>>();
    assert_ne!(order(&sessions[0]), order(&sessions[1]));
    // Making it again from the same plan keeps everything; another plan is refused.
    ok(&lodlab(&[
        "study", "make", "--plan", &plan_s, "--out", &d, "--cache", &cache, "--msaa", "1",
    ]));
    assert_eq!(session(&dir, "P01"), sessions[0]);
    let other = tmp.path().join("other.toml");
    std::fs::write(
        &other,
        std::fs::read_to_string(&plan)
            .unwrap()
            .replace("participants = 2", "participants = 3"),
    )
    .unwrap();
    let o = lodlab(&[
        "study",
        "make",
        "--plan",
        &other.display().to_string(),
        "--out",
        &d,
    ]);
    assert_eq!(o.status.code(), Some(1));

    // A make interrupted after two of its three clips (killed: no manifest, no sessions, the
    // clips so far noted in making.json) is resumed by the next run of the same plan.
    let resumed = tmp.path().join("resumed");
    std::fs::create_dir_all(resumed.join("clips")).unwrap();
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("study.json")).unwrap()).unwrap();
    let mut making = manifest.clone();
    let clips = making["clips"].as_array_mut().unwrap();
    let dropped = clips.pop().unwrap();
    for c in clips.iter() {
        let file = c["file"].as_str().unwrap();
        std::fs::copy(dir.join(file), resumed.join(file)).unwrap();
    }
    making["conditions"] = serde_json::json!([]);
    making["participants"] = serde_json::json!([]);
    std::fs::write(resumed.join("making.json"), making.to_string()).unwrap();
    let r = resumed.display().to_string();
    let o = lodlab(&[
        "study", "make", "--plan", &plan_s, "--out", &r, "--cache", &cache, "--msaa", "1",
    ]);
    ok(&o);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("resuming"), "{stderr}");
    assert!(resumed.join(dropped["file"].as_str().unwrap()).is_file());
    assert!(!resumed.join("making.json").exists());
    assert_eq!(session(&resumed, "P01"), sessions[0]);
    // A folder of clips without making.json is still not taken for a study.
    let stray = tmp.path().join("stray");
    std::fs::create_dir_all(&stray).unwrap();
    std::fs::write(stray.join("notes.txt"), "mine").unwrap();
    let o = lodlab(&[
        "study",
        "make",
        "--plan",
        &plan_s,
        "--out",
        &stray.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        std::fs::read_to_string(stray.join("notes.txt")).unwrap(),
        "mine"
    );

    // Participant 1 answers everything in one go.
    let script1 = prefer_b(&sessions[0], &pairs);
    ok(&lodlab(&[
        "study",
        "run",
        &d,
        "--participant",
        "P01",
        "--script",
        &script1,
    ]));
    assert_eq!(answers_of(&dir, "P01"), 9);

    // Participant 2's session is killed part-way: the answers given survive whole.
    let script2 = prefer_b(&sessions[1], &pairs);
    let mut child = Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args([
            "study",
            "run",
            &d,
            "--participant",
            "P02",
            "--script",
            &script2,
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while answers_of(&dir, "P02") < 2 {
        assert!(start.elapsed() < Duration::from_secs(120), "no answers");
        assert!(child.try_wait().unwrap().is_none(), "ended before the kill");
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let (answers, bad) = read_answers(&dir).unwrap();
    assert_eq!(bad, 0, "no line cut short");
    let given = answers.iter().filter(|a| a.participant == "P02").count();
    assert!((2..9).contains(&given), "{given}");
    // Resumed: only the trials left are played and answered.
    let left: Vec<&str> = script2.split(',').skip(given).collect();
    ok(&lodlab(&[
        "study",
        "run",
        &d,
        "--participant",
        "P02",
        "--script",
        &left.join(","),
    ]));
    let (answers, _) = read_answers(&dir).unwrap();
    let mut p2: Vec<usize> = answers
        .iter()
        .filter(|a| a.participant == "P02")
        .map(|a| a.trial)
        .collect();
    p2.sort();
    assert_eq!(p2, (1..=9).collect::<Vec<_>>(), "every trial once");
    // A finished session records nothing more.
    ok(&lodlab(&[
        "study",
        "run",
        &d,
        "--participant",
        "P02",
        "--script",
        "1,1",
    ]));
    assert_eq!(answers_of(&dir, "P02"), 9);
    // An unknown participant is one line, exit 1.
    let o = lodlab(&["study", "run", &d, "--participant", "P09", "--script", "1"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(String::from_utf8_lossy(&o.stderr).trim().lines().count(), 1);

    // Analysis: training left out; every test answer preferred B: 4 of 4 per condition.
    let o = lodlab(&["study", "analyze", &d]);
    ok(&o);
    let a: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("analysis.json")).unwrap()).unwrap();
    assert_eq!(a["participants"], 2);
    assert_eq!(a["training_answers_left_out"], 6);
    let conditions = a["conditions"].as_array().unwrap();
    assert_eq!(conditions.len(), 3);
    for (c, (ma, mb)) in conditions.iter().zip(pairs) {
        assert_eq!(c["condition"]["method_a"], ma);
        assert_eq!(c["condition"]["method_b"], mb);
        assert_eq!(c["answers"], 4);
        assert_eq!(c["prefer_b"], 4);
        assert_eq!(c["share_b"], 1.0);
        let p = c["p_value"].as_f64().unwrap();
        assert!((p - binomial_two_sided(4, 4)).abs() < 1e-12 && (p - 0.125).abs() < 1e-12);
    }
    let md = std::fs::read_to_string(dir.join("analysis.md")).unwrap();
    assert_eq!(String::from_utf8_lossy(&o.stdout), md);
    assert!(
        md.contains("| rest-pose vs as |") || md.contains("rest-pose vs as |"),
        "{md}"
    );
    let chart = image::open(dir.join("preferences.png")).unwrap().to_rgb8();
    // The bars are drawn: some pixels in the bars' blue or grey.
    let bars = chart
        .pixels()
        .filter(|p| p.0 == [170, 180, 195] || p.0 == [40, 110, 200])
        .count();
    assert!(bars > 500, "{bars}");
}

/// `study proxy` scores every clip against a full-detail clip of its model recorded the same
/// way: the study's own full-detail clip matches it frame for frame (SSIM 1), simplified ones
/// score no higher; `analyze` then sets the scores against the answers.
#[test]
fn a_study_proxy_scores_clips_against_full_detail() {
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("cylinder.glb");
    std::fs::write(&model, to_glb(&bent_cylinder(24, 16))).unwrap();
    // meshoptimizer's levels stand in a plan as any method's.
    let pairs = [("none", "as"), ("meshopt", "as")];
    let plan = tmp.path().join("plan.toml");
    std::fs::write(
        &plan,
        format!(
            "models = [\"{}\"]\npairs = [[\"none\", \"as\"], [\"meshopt\", \"as\"]]\n\
             tolerances = [8.0]\nparticipants = 1\ncount = 6\nseconds = 0.5\nfps = 10\n\
             size = \"64x48\"\nseed = 3\ntraining = false\n",
            model.display()
        ),
    )
    .unwrap();
    let dir = tmp.path().join("study");
    let d = dir.display().to_string();
    let cache = tmp.path().join("cache").display().to_string();
    ok(&lodlab(&[
        "study",
        "make",
        "--plan",
        &plan.display().to_string(),
        "--out",
        &d,
        "--cache",
        &cache,
        "--msaa",
        "1",
    ]));
    let o = lodlab(&["study", "proxy", &d, "--cache", &cache, "--msaa", "1"]);
    ok(&o);
    assert!(dir.join("clips/cylinder-reference.mp4").exists());
    let proxy: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("proxy.json")).unwrap()).unwrap();
    let clips = proxy["clips"].as_array().unwrap();
    assert_eq!(clips.len(), 3);
    let mean = |method: &str| {
        clips
            .iter()
            .find(|c| c["method"] == method)
            .map(|c| {
                assert_eq!(c["ssim"].as_array().unwrap().len(), 5, "a score per frame");
                c["mean"].as_f64().unwrap()
            })
            .unwrap()
    };
    // Frames are scored before encoding: full detail against its reference is the same
    // picture, exactly.
    assert!(mean("none") > 1.0 - 1e-9, "{}", mean("none"));
    let reference_frames = std::fs::read_dir(dir.join("clips/cylinder-reference-frames"))
        .unwrap()
        .count();
    assert_eq!(reference_frames, 5);
    // The codec's own loss is measured on the reference and said beside the scores.
    let codec = &proxy["codec"][0];
    assert_eq!(codec["model"], model.display().to_string());
    let codec_mean = codec["mean"].as_f64().unwrap();
    assert!((0.5..1.0).contains(&codec_mean), "{codec}");
    assert!(codec["lowest"].as_f64().unwrap() <= codec_mean);
    for m in ["as", "meshopt"] {
        assert!(
            (-1.0..=mean("none") + 1e-9).contains(&mean(m)),
            "{m}: {}",
            mean(m)
        );
    }
    // ꟻLIP: no error where the frames are the same, some at most where they are not.
    let flip = |method: &str| {
        clips.iter().find(|c| c["method"] == method).unwrap()["flip_mean"]
            .as_f64()
            .unwrap()
    };
    assert!(flip("none") < 1e-6, "{}", flip("none"));
    for m in ["as", "meshopt"] {
        assert!((0.0..=1.0).contains(&flip(m)), "{m}: {}", flip(m));
    }
    let md = std::fs::read_to_string(dir.join("proxy.md")).unwrap();
    assert_eq!(String::from_utf8_lossy(&o.stdout), md);
    assert!(md.contains("The codec's own loss"), "{md}");
    assert!(
        md.contains("| none vs as | 8 |") && md.contains("| meshopt vs as | 8 |"),
        "{md}"
    );
    let frames = std::fs::read_to_string(dir.join("proxy-frames.csv")).unwrap();
    assert_eq!(frames.lines().count(), 1 + 3 * 5);
    assert!(image::open(dir.join("proxy.png")).is_ok());
    // Scoring again keeps the reference and gives the same scores.
    ok(&lodlab(&[
        "study", "proxy", &d, "--cache", &cache, "--msaa", "1",
    ]));
    let again: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("proxy.json")).unwrap()).unwrap();
    assert_eq!(again, proxy);

    // The participant prefers B each time; analyze reports the proxy beside the answers.
    let trials = session(&dir, "P01");
    ok(&lodlab(&[
        "study",
        "run",
        &d,
        "--participant",
        "P01",
        "--script",
        &prefer_b(&trials, &pairs),
    ]));
    ok(&lodlab(&["study", "analyze", &d]));
    let a: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("analysis.json")).unwrap()).unwrap();
    let metrics = a["proxy"].as_array().unwrap();
    assert_eq!(metrics.len(), 2, "SSIM and ꟻLIP");
    let p = &metrics[0];
    assert_eq!(p["differences"].as_array().unwrap().len(), 2);
    let diff0 = p["differences"][0].as_f64().unwrap();
    assert!((diff0 - (mean("as") - mean("none"))).abs() < 1e-12);
    for p in metrics {
        assert_eq!(p["decided"], 2);
        // Two conditions: too few for a rank correlation.
        assert!(p["rho"].is_null());
    }
    let md = std::fs::read_to_string(dir.join("analysis.md")).unwrap();
    assert!(md.contains("Image-metric proxy"), "{md}");
}

/// A plan made in two shards into one folder, then merged: each shard renders only its share
/// (clip i goes to shard i mod N + 1) and writes no sessions; the merge refuses while a clip is
/// missing and a shard made with other options, then writes the study without rendering again.
/// `bake --shard` bakes only its share of the models.
#[test]
fn a_study_is_made_in_shards_and_merged() {
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("cylinder.glb");
    std::fs::write(&model, to_glb(&bent_cylinder(16, 8))).unwrap();
    let plan = tmp.path().join("plan.toml");
    std::fs::write(
        &plan,
        format!(
            "models = [\"{}\"]\npairs = [[\"rest-pose\", \"as\"], [\"as\", \"as+is\"]]\n\
             tolerances = [2.0]\nparticipants = 2\ncount = 2\nseconds = 0.3\nfps = 10\n\
             size = \"48x32\"\n",
            model.display()
        ),
    )
    .unwrap();
    let dir = tmp.path().join("study");
    let (d, plan_s) = (dir.display().to_string(), plan.display().to_string());
    let cache = tmp.path().join("cache").display().to_string();
    let make = |extra: &[&str]| {
        let mut args = vec![
            "study", "make", "--plan", &plan_s, "--out", &d, "--cache", &cache, "--msaa", "1",
        ];
        args.extend_from_slice(extra);
        lodlab(&args)
    };
    let clips = || -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir.join("clips"))
            .map(|r| {
                r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                    .collect()
            })
            .unwrap_or_default();
        v.sort();
        v
    };
    // Plan order of the clips: rest-pose, as, as+is. Shard 2/2 takes the second.
    let o = make(&["--shard", "2/2"]);
    ok(&o);
    assert_eq!(clips(), ["cylinder-as-2px.mp4"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("--merge"));
    assert!(!dir.join("sessions").exists() && !dir.join("study.json").exists());
    let o = make(&["--merge"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("2 of 3 clips are not made yet") && err.contains("cylinder-rest-pose-2px"),
        "{err}"
    );
    // A shard made with other options does not join.
    let o = lodlab(&[
        "study", "make", "--plan", &plan_s, "--out", &d, "--cache", &cache, "--msaa", "4",
        "--shard", "2/2",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--msaa 1"));
    let o = make(&["--shard", "1/2"]);
    ok(&o);
    // The merge line the shard prints: the same plan, folder, cache and --msaa.
    let stdout = String::from_utf8_lossy(&o.stdout);
    let merge: Vec<String> = stdout
        .split("merge them with: ")
        .nth(1)
        .expect("the shard says how to merge")
        .split_whitespace()
        .map(|w| w.trim_matches('\'').to_string())
        .collect();
    assert_eq!(merge[..3], ["lodlab", "study", "make"]);
    assert!(
        merge.ends_with(&["--msaa".into(), "1".into(), "--merge".into()]),
        "{merge:?}"
    );
    assert!(merge.contains(&cache), "{merge:?}");
    assert_eq!(
        clips(),
        [
            "cylinder-as-2px.mp4",
            "cylinder-as-is-2px.mp4",
            "cylinder-rest-pose-2px.mp4"
        ]
    );
    // Nor does a shard made by another lodlab.
    let record = dir.join("shards/2-of-2.json");
    let text = std::fs::read_to_string(&record).unwrap();
    let version = format!("\"version\": \"{}\"", env!("CARGO_PKG_VERSION"));
    assert!(text.contains(&version), "{text}");
    std::fs::write(
        &record,
        text.replace(&version, "\"version\": \"0.0.1-old\""),
    )
    .unwrap();
    let o = make(&["--merge"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("made by lodlab 0.0.1-old"));
    std::fs::write(&record, text).unwrap();
    // When each clip file was last written.
    let written = || -> Vec<_> {
        clips()
            .iter()
            .map(|c| {
                std::fs::metadata(dir.join("clips").join(c))
                    .unwrap()
                    .modified()
                    .unwrap()
            })
            .collect()
    };
    let before = written();
    // The merge with other options than the shards' is refused, naming a shard's record.
    let o = lodlab(&[
        "study", "make", "--plan", &plan_s, "--out", &d, "--cache", &cache, "--merge",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("1-of-2.json") && err.contains("--msaa 1"),
        "{err}"
    );
    let words: Vec<&str> = merge[1..].iter().map(String::as_str).collect();
    let o = lodlab(&words);
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.matches("(there already)").count(), 3, "{err}");
    let after = written();
    assert_eq!(before, after, "the merge rendered nothing again");
    let manifest = lodlab::app::study::plan::read_manifest(&dir).unwrap();
    assert!(manifest.clips.iter().all(|c| c.record.is_some()));
    assert_eq!(session(&dir, "P02").len(), 2 + 4);

    // bake --shard: model i to shard i mod N + 1.
    let other = tmp.path().join("other.glb");
    std::fs::write(&other, to_glb(&bent_cylinder(12, 8))).unwrap();
    let o = lodlab(&[
        "bake",
        &model.display().to_string(),
        &other.display().to_string(),
        "--methods",
        "as",
        "--cache",
        &cache,
        "--shard",
        "2/2",
        "--json",
    ]);
    ok(&o);
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let baked: Vec<&str> = json["characters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["model"].as_str().unwrap())
        .collect();
    assert_eq!(baked, ["other"], "{json}");
}

/// `study web` writes its site into a folder of its own holding only what a participant's
/// browser fetches: the page, its script and data, and the clips the sessions play (the same
/// bytes as the study's); not the sessions' files, the reference frames, the image metrics'
/// verdict or any answers, which stay in the study folder beside it.
#[test]
fn a_study_site_holds_only_what_the_page_loads() {
    let tmp = tempfile::tempdir().unwrap();
    let plan = crate::common::cylinder_plan(
        tmp.path(),
        "pairs = [[\"rest-pose\", \"as+is\"]]\ntolerances = [2.0]\n\
         participants = 2\ncount = 3\nseconds = 0.4\nfps = 10\nsize = \"64x48\"\n",
    );
    let dir = tmp.path().join("study");
    let cache = tmp.path().join("cache");
    let o = lodlab(&[
        "study",
        "web",
        plan.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
        "--msaa",
        "1",
    ]);
    ok(&o);
    let site = dir.join("site");
    assert!(String::from_utf8_lossy(&o.stdout).contains(site.to_str().unwrap()));
    let mut clips: Vec<String> = ["P01", "P02"]
        .iter()
        .flat_map(|p| session(&dir, p))
        .flat_map(|t| [t.first_clip, t.second_clip])
        .collect();
    clips.sort();
    clips.dedup();
    let mut expected: Vec<String> = ["index.html", "study.js", "study-data.js"]
        .iter()
        .map(|s| s.to_string())
        .chain(clips.iter().cloned())
        .collect();
    expected.sort();
    let mut found: Vec<String> = Vec::new();
    let mut stack = vec![site.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(&site).unwrap().to_string_lossy().to_string();
                found.push(rel);
            }
        }
    }
    found.sort();
    assert_eq!(found, expected);
    for clip in &clips {
        assert_eq!(
            std::fs::read(site.join(clip)).unwrap(),
            std::fs::read(dir.join(clip)).unwrap(),
            "{clip}"
        );
    }
    // Made again over the same folder: the site is rewritten in place.
    ok(&lodlab(&[
        "study",
        "web",
        plan.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
        "--msaa",
        "1",
    ]));
    assert!(site.join("index.html").is_file());
}

// lodlab's online study: one participant's session in the browser, as `lodlab study run` runs
// it in a window (Merry et al. §6.2): each trial's two clips one after the other, full size on
// black after a grey screen, never side by side, then a forced choice with the keys 1 and 2.
// Every answer is kept in the browser's storage at once, so a reload resumes at the first trial
// without one; at the end the answers download as answers-ID.csv (the columns of the desktop's
// answers.csv, which `lodlab study analyze` reads beside it) and, where the researcher gave a
// URL, are POSTed there as text/csv.
//
// `lodlab study web` writes study-data.js (window.LODLAB_STUDY: the conditions, every
// participant's trials, the wording and the timing) beside this file. The page opens as
// index.html?participant=P01.
"use strict";

(function () {
  const study = window.LODLAB_STUDY;
  const screen = document.getElementById("screen");
  const videos = [document.getElementById("clip1"), document.getElementById("clip2")];
  const params = new URLSearchParams(location.search);
  const participant = params.get("participant");
  const trials =
    study && participant && Object.hasOwn(study.sessions, participant)
      ? study.sessions[participant]
      : undefined;
  const storageKey = study ? `lodlab-study/${study.study}/${participant}` : "";
  let answers = [];
  let stage = "loading";
  // Every stage in order, for the tests (and a researcher's console).
  const history = [];
  // A clip that is due once its gap is over and it can play through.
  let pending = null;

  // What the tests (and a curious researcher) can read: the stage and the progress.
  window.lodlabStudy = {
    get stage() { return stage; },
    history,
    get answered() { return answers.length; },
    get total() { return trials ? trials.length : 0; },
    csv: () => csv(answers),
  };

  function enter(s) {
    stage = s;
    history.push(s);
    document.body.dataset.stage = s;
  }

  function setStage(s, text, buttons) {
    enter(s);
    screen.textContent = text;
    if (buttons && buttons.length) {
      const row = document.createElement("div");
      row.className = "buttons";
      for (const [label, action] of buttons) {
        const b = document.createElement("button");
        b.textContent = label;
        b.addEventListener("click", action);
        row.appendChild(b);
      }
      screen.appendChild(row);
    }
  }

  function progress() {
    return `${answers.length} of ${trials.length} answered`;
  }

  function current() {
    const done = new Set(answers.map((a) => a.trial));
    return trials.find((t) => !done.has(t.trial));
  }

  function load() {
    try {
      const saved = JSON.parse(localStorage.getItem(storageKey) || "[]");
      if (Array.isArray(saved)) answers = saved;
    } catch (e) {
      answers = [];
    }
  }

  // Where the browser keeps nothing (storage blocked or full) the session goes on: the answers
  // are still downloaded and sent at the end, only a reload would lose them.
  let unsaved = false;
  function save() {
    try {
      localStorage.setItem(storageKey, JSON.stringify(answers));
    } catch (e) {
      if (!unsaved) console.warn(`lodlab study: answers not kept in the browser (${e})`);
      unsaved = true;
    }
  }

  // One field of a CSV line, quoted where it must be (RFC 4180, as the csv crate writes).
  function field(v) {
    const s = String(v);
    return /[",\r\n]/.test(s) ? `"${s.replace(/"/g, '""')}"` : s;
  }

  function csv(rows) {
    const lines = [study.header.join(",")];
    for (const r of rows) lines.push(study.header.map((h) => field(r[h])).join(","));
    return lines.join("\n") + "\n";
  }

  function welcome() {
    const t = current();
    if (!t) return finish();
    const resumed = answers.length > 0 ? "Welcome back: you go on where you stopped.\n\n" : "";
    setStage(
      "welcome",
      `Participant ${participant}\n\n${resumed}${study.texts.instructions}\n\n` +
        `Press space to start.\nYou can close the page and come back later.\n\n${progress()}`,
      [["Start", begin]],
    );
  }

  function begin() {
    if (stage !== "welcome") return;
    playTrial();
  }

  // Both clips of the trial start loading at once; each plays after its grey screen.
  function playTrial() {
    const t = current();
    if (!t) return finish();
    [t.first_clip, t.second_clip].forEach((file, k) => {
      const v = videos[k];
      if (v.getAttribute("src") !== file) {
        v.src = file;
        v.load();
      }
    });
    gap(1);
  }

  function gap(which) {
    setStage("gap", `Clip ${which}`);
    const v = videos[which - 1];
    if (v.error) return fail(`${v.getAttribute("src")} could not be loaded`);
    const due = { which, timeUp: false, ready: v.readyState >= 4 };
    pending = due;
    setTimeout(() => {
      due.timeUp = true;
      maybePlay(due);
    }, study.gap_ms);
    if (!due.ready) {
      const ready = () => {
        v.removeEventListener("canplaythrough", ready);
        due.ready = true;
        maybePlay(due);
      };
      v.addEventListener("canplaythrough", ready);
    }
  }

  function maybePlay(due) {
    if (stage === "error" || pending !== due || !due.timeUp || !due.ready) return;
    pending = null;
    const v = videos[due.which - 1];
    enter("playing");
    screen.textContent = "";
    v.currentTime = 0;
    v.classList.add("shown");
    v.onended = () => {
      v.classList.remove("shown");
      v.onended = null;
      if (stage === "error") return;
      if (due.which === 1) gap(2);
      else ask();
    };
    v.play().catch((e) => fail(`the clip could not be played (${e.message})`));
  }

  function ask() {
    setStage("ask", `${study.texts.question}\n\n${study.texts.choices}\n\n${progress()}`, [
      ["1", () => answer(1)],
      ["2", () => answer(2)],
    ]);
  }

  function answer(choice) {
    if (stage !== "ask") return;
    const t = current();
    const c = study.conditions[t.condition];
    answers.push({
      participant,
      trial: t.trial,
      block: t.block,
      model: c.model,
      method_a: c.method_a,
      method_b: c.method_b,
      tolerance_px: c.tolerance_px,
      first: t.first,
      second: t.second,
      choice,
      preferred: choice === 1 ? t.first : t.second,
      unix_time: Math.floor(Date.now() / 1000),
    });
    save();
    if (current()) playTrial();
    else finish();
  }

  function download() {
    const blob = new Blob([csv(answers)], { type: "text/csv" });
    const a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = `answers-${participant}.csv`;
    document.body.appendChild(a);
    a.click();
    a.remove();
  }

  function finish(retry = false) {
    const buttons = [["Download your answers", download]];
    if (!study.post_url) {
      setStage("done", `${study.texts.thanks}\n\nPlease download your answers and send the ` +
        `file to the researcher.`, buttons);
      return;
    }
    // Sent once: a reload of a finished session offers the download and a resend only.
    const sentKey = `${storageKey}/sent`;
    if (!retry && localStorage.getItem(sentKey)) {
      setStage("done", `${study.texts.thanks}\n\nYour answers were sent.`,
        buttons.concat([["Send them again", () => finish(true)]]));
      return;
    }
    setStage("sending", `${study.texts.thanks}\n\nSending your answers…`);
    fetch(study.post_url, {
      method: "POST",
      headers: { "Content-Type": "text/csv" },
      body: csv(answers),
    })
      .then((r) => {
        if (!r.ok) throw new Error(`the server answered ${r.status}`);
        try {
          localStorage.setItem(sentKey, "1");
        } catch (e) {
          // Not kept: a reload sends again.
        }
        setStage("done", `${study.texts.thanks}\n\nYour answers were sent.`, buttons);
      })
      .catch((e) => {
        setStage("done", `${study.texts.thanks}\n\nYour answers could not be sent ` +
          `(${e.message}): please download them and send the file to the researcher.`,
          buttons.concat([["Try sending again", () => finish(true)]]));
      });
  }

  function fail(why) {
    pending = null;
    for (const v of videos) {
      v.onended = null;
      v.pause();
      v.classList.remove("shown");
    }
    setStage("error", `Sorry: ${why}. Reload the page to go on; your answers are kept.`);
  }

  document.addEventListener("keydown", (e) => {
    if (e.repeat) return;
    if (stage === "welcome" && e.key === " ") {
      e.preventDefault();
      begin();
    } else if (stage === "ask" && (e.key === "1" || e.key === "2")) {
      answer(Number(e.key));
    }
  });
  videos.forEach((v) =>
    v.addEventListener("error", () => {
      if (stage === "gap" || stage === "playing") fail(`${v.getAttribute("src")} could not be loaded`);
    }),
  );

  if (!study) {
    setStage("error", "study-data.js is missing: write this folder with `lodlab study web`.");
  } else if (!trials) {
    // No participant in the address: the researcher's page, one link per participant.
    setStage("pick", participant ? `No participant '${participant}' in this study.\n\n` : "");
    const list = document.createElement("div");
    list.textContent = "Send each participant their own link:";
    for (const id of Object.keys(study.sessions)) {
      const a = document.createElement("a");
      a.href = `?participant=${encodeURIComponent(id)}`;
      a.textContent = id;
      list.appendChild(document.createElement("br"));
      list.appendChild(a);
    }
    screen.appendChild(list);
  } else {
    load();
    welcome();
  }
})();

// Plays one participant's whole online session (the site `lodlab study web` writes) in
// Debian's Chromium, headless, as a participant would: space to start, the clips play, the keys
// 1 and 2 answer; the page is reloaded halfway to check that it resumes; at the end the answers
// are downloaded (and POSTed, where the study was written with --post to this server).
//
//   node study-check.mjs --site DIR --participant P01 --answers 1,2,2 --reload-after 1 \
//        --port 8123 --out DIR
//
// Serves DIR on 127.0.0.1:PORT, takes POST /answers into OUT/posted.csv, downloads into OUT,
// and prints one JSON line of what it saw. Exits 1 with one line on stderr when anything is
// not as it should be.
import fs from "node:fs";
import path from "node:path";
import { parseArgs } from "node:util";
import { launch, chromiumArgs, serve } from "./browser.mjs";

const { values: o } = parseArgs({
  options: {
    site: { type: "string" },
    participant: { type: "string", default: "P01" },
    answers: { type: "string" },
    "reload-after": { type: "string", default: "1" },
    port: { type: "string", default: "0" },
    out: { type: "string" },
  },
});
const answers = o.answers.split(",").map(Number);
const reloadAfter = Number(o["reload-after"]);
fs.mkdirSync(o.out, { recursive: true });

let posted = null;
const server = await serve(o.site, Number(o.port), (req, res) => {
  if (req.method !== "POST" || req.url !== "/answers") return false;
  let body = "";
  req.on("data", (d) => (body += d));
  req.on("end", () => {
    posted = body;
    fs.writeFileSync(path.join(o.out, "posted.csv"), body);
    res.writeHead(200, { "Access-Control-Allow-Origin": "*" });
    res.end("ok");
  });
  return true;
});
const base = `http://127.0.0.1:${server.address().port}`;
const browser = await launch(chromiumArgs.video);
const report = { stages: [], frames: [], resumed: null };
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 480, height: 320 });
  const cdp = await page.createCDPSession();
  await cdp.send("Browser.setDownloadBehavior", { behavior: "allow", downloadPath: path.resolve(o.out) });
  const url = `${base}/index.html?participant=${encodeURIComponent(o.participant)}`;
  await page.goto(url);
  const waitStage = (s, ms = 60000) =>
    page.waitForFunction((s) => window.lodlabStudy && window.lodlabStudy.stage === s, { timeout: ms }, s);
  const text = () => page.$eval("#screen", (e) => e.textContent);
  // Every stage the page passed through, in order, across reloads.
  const stages = async () => report.stages.push(...(await page.evaluate(() => window.lodlabStudy.history)));

  await waitStage("welcome");
  if (!(await text()).includes(`Participant ${o.participant}`)) throw new Error(`welcome: ${await text()}`);
  await page.keyboard.press("Space");
  for (let k = 0; k < answers.length; k++) {
    // One frame of each clip as it plays: its size and how bright it is (a black or missing
    // video is caught here).
    for (const which of [1, 2]) {
      await page.waitForFunction((w) => {
        const v = document.querySelector("video.shown");
        return v && v.id === `clip${w}` && v.currentTime > 0.05;
      }, { timeout: 60000 }, which);
      report.frames.push(await page.evaluate(() => {
        const v = document.querySelector("video.shown");
        const c = document.createElement("canvas");
        [c.width, c.height] = [v.videoWidth, v.videoHeight];
        const g = c.getContext("2d");
        g.drawImage(v, 0, 0);
        const px = g.getImageData(0, 0, c.width, c.height).data;
        let sum = 0;
        for (let i = 0; i < px.length; i += 4) sum += 0.299 * px[i] + 0.587 * px[i + 1] + 0.114 * px[i + 2];
        return { clip: v.id, width: v.videoWidth, height: v.videoHeight, mean_luma: sum / (px.length / 4) };
      }));
    }
    await waitStage("ask");
    await page.keyboard.press(String(answers[k]));
    if (k + 1 === reloadAfter && k + 1 < answers.length) {
      await stages();
      await page.reload();
      await waitStage("welcome");
      const t = await text();
      report.resumed = t;
      if (!t.includes(`${k + 1} of`)) throw new Error(`after the reload the page says: ${t}`);
      await page.keyboard.press("Space");
    }
  }
  await waitStage("done");
  await stages();
  report.done = await text();
  await page.click("button");
  const file = path.join(o.out, `answers-${o.participant}.csv`);
  for (let i = 0; i < 100 && !fs.existsSync(file); i++) await new Promise((r) => setTimeout(r, 100));
  if (!fs.existsSync(file)) throw new Error(`no ${file} was downloaded`);
  report.download = file;
  report.posted = posted !== null && posted === fs.readFileSync(file, "utf8");
  console.log(JSON.stringify(report));
} catch (e) {
  console.error(`study-check: ${e.message} (stages so far: ${report.stages.join(" ")})`);
  process.exitCode = 1;
} finally {
  await browser.close();
  server.close();
}

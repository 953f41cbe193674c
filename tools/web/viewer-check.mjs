// Opens the web viewer (the folder `lodlab web` writes) in Debian's Chromium, headless, on
// WebGPU over SwiftShader (or WebGL2 with --webgl), waits for frames, takes a screenshot, drags
// over the view with the mouse and then a finger and waits for the camera to orbit, then presses
// M (the next method) and waits for the triangle count the page shows to change.
//
//   node viewer-check.mjs --site DIR --out DIR [--webgl] [--frames 5] [--size 960x540]
//
// Prints one JSON line: load and frame figures, the adapter, the triangles under each method,
// and the console's errors. Exits 1 with one line on stderr when the page fails.
import fs from "node:fs";
import path from "node:path";
import { parseArgs } from "node:util";
import { launch, chromiumArgs, serve } from "./browser.mjs";

const { values: o } = parseArgs({
  options: {
    site: { type: "string" },
    out: { type: "string" },
    webgl: { type: "boolean", default: false },
    frames: { type: "string", default: "5" },
    size: { type: "string", default: "960x540" },
    timeout: { type: "string", default: "240" },
  },
});
fs.mkdirSync(o.out, { recursive: true });
const [width, height] = o.size.split("x").map(Number);
const timeout = Number(o.timeout) * 1000;
const server = await serve(o.site, 0);
const browser = await launch(o.webgl ? chromiumArgs.webgl : chromiumArgs.webgpu);
const report = { errors: [], methods: [] };
try {
  const page = await browser.newPage();
  page.on("console", (m) => {
    if (m.type() === "error") report.errors.push(m.text());
    if (process.env.LODLAB_CONSOLE) console.error(`console: ${m.text().slice(0, 300)}`);
  });
  page.on("pageerror", (e) => report.errors.push(String(e)));
  await page.setViewport({ width, height });
  const opened = Date.now();
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html`);
  const data = () => page.evaluate(() => ({ ...document.body.dataset, status: document.getElementById("status").textContent }));
  const waitFor = async (test, what) => {
    const until = Date.now() + timeout;
    for (;;) {
      const d = await data();
      if (test(d)) return d;
      if (d.status.startsWith("lodlab")) throw new Error(d.status);
      if (Date.now() > until) throw new Error(`timed out waiting for ${what}: ${JSON.stringify(d)}`);
      await new Promise((r) => setTimeout(r, 250));
    }
  };
  let d = await waitFor((d) => Number(d.frames || 0) >= 1, "the first frame");
  report.first_frame_s = (Date.now() - opened) / 1000;
  report.first_frame_ms_page = Number(d.firstFrameMs);
  d = await waitFor((d) => Number(d.frames || 0) >= Number(o.frames), `${o.frames} frames`);
  report.adapter = d.adapter;
  report.methods.push({ method: d.method, triangles: Number(d.triangles), fps: Number(d.fps) });
  await page.screenshot({ path: path.join(o.out, "viewer.png") });
  // Orbiting: a mouse drag over the 3D view, then a finger's.
  const yaw = (d) => Number(d.camera.split(" ")[0]);
  const dragged = async (what, drag) => {
    // The page writes its figures every half second: let the last move's reach them first.
    await new Promise((r) => setTimeout(r, 1200));
    const start = await data();
    await drag();
    // The yaw wraps round a turn: the change is taken the short way.
    const turn = (d) => {
      const t = 2 * Math.PI;
      return ((((yaw(d) - yaw(start) + Math.PI) % t) + t) % t) - Math.PI;
    };
    const d = await waitFor((d) => Math.abs(turn(d)) > 0.05, `the camera to orbit by ${what}`);
    report.orbit = { ...report.orbit, [what]: turn(d) };
  };
  await dragged("mouse", async () => {
    await page.mouse.move(width * 0.6, height * 0.5);
    await page.mouse.down();
    for (let k = 1; k <= 10; k++) await page.mouse.move(width * 0.6 + 15 * k, height * 0.5);
    await page.mouse.up();
  });
  await dragged("touch", async () => {
    await page.touchscreen.touchStart(width * 0.6, height * 0.5);
    for (let k = 1; k <= 10; k++) await page.touchscreen.touchMove(width * 0.6 - 15 * k, height * 0.5);
    await page.touchscreen.touchEnd();
  });
  // M over the 3D view (the canvas has the keyboard once clicked), twice: each method the
  // page offers after the first draws.
  await page.mouse.click(width * 0.75, height * 0.5);
  for (let k = 1; k <= 2; k++) {
    const before = d.method;
    await page.keyboard.press("KeyM");
    d = await waitFor((d) => d.method !== before, "the next method");
    const frames = Number(d.frames);
    d = await waitFor((d) => Number(d.frames) >= frames + 3, "frames under the next method");
    report.methods.push({ method: d.method, triangles: Number(d.triangles), fps: Number(d.fps) });
  }
  await page.screenshot({ path: path.join(o.out, "viewer-next-method.png") });
  report.frames = Number(d.frames);
  report.fps = Number(d.fps);
  console.log(JSON.stringify(report));
} catch (e) {
  console.error(`viewer-check: ${e.message} (console errors: ${report.errors.slice(0, 5).join(" | ")})`);
  process.exitCode = 1;
} finally {
  await browser.close();
  server.close();
}

// What the browser checks share: Debian's Chromium launched headless through puppeteer-core,
// and a static file server on 127.0.0.1.
import http from "node:http";
import fs from "node:fs";
import path from "node:path";
import puppeteer from "puppeteer-core";

const executablePath = process.env.LODLAB_CHROMIUM || "/usr/bin/chromium";

export const chromiumArgs = {
  // Clips play without a click (the participant's space bar is the gesture a real page gets).
  video: ["--autoplay-policy=no-user-gesture-required"],
  // WebGPU on SwiftShader, Chromium's software Vulkan: what a machine without a GPU has. The
  // compositor on Vulkan (through ANGLE) too: otherwise the canvas's frames never reach the
  // page (a screenshot shows it blank).
  webgpu: [
    "--enable-unsafe-webgpu",
    "--use-webgpu-adapter=swiftshader",
    "--enable-unsafe-swiftshader",
    "--enable-features=Vulkan",
    "--use-angle=vulkan",
    "--use-vulkan=swiftshader",
  ],
  // WebGL2 on SwiftShader through ANGLE, where WebGPU is left out.
  webgl: ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--disable-features=WebGPU"],
};

export function launch(args) {
  if (process.env.LODLAB_CHROMIUM_ARGS) args = args.concat(process.env.LODLAB_CHROMIUM_ARGS.split(" "));
  return puppeteer.launch({
    executablePath,
    headless: true,
    // A page building its scene keeps its thread for a while on a software GPU.
    protocolTimeout: 600000,
    // The browser's own output (a crashed GPU process says why there).
    dumpio: Boolean(process.env.LODLAB_CONSOLE),
    // As root (CI's containers) Chromium refuses to start sandboxed.
    args: ["--no-sandbox", "--disable-dev-shm-usage", ...args],
  });
}

const types = {
  ".html": "text/html; charset=utf-8",
  ".js": "text/javascript; charset=utf-8",
  ".mjs": "text/javascript; charset=utf-8",
  ".wasm": "application/wasm",
  ".json": "application/json",
  ".mp4": "video/mp4",
  ".png": "image/png",
  ".csv": "text/csv",
};

// Serves `root` on 127.0.0.1:`port` (0: any free port), with byte ranges (video seeks use
// them); `extra(req, res)` may take a request first by returning true.
export function serve(root, port, extra = () => false) {
  const server = http.createServer((req, res) => {
    if (extra(req, res)) return;
    const rel = decodeURIComponent(new URL(req.url, "http://x").pathname).replace(/^\/+/, "");
    const file = path.join(root, rel || "index.html");
    if (!path.resolve(file).startsWith(path.resolve(root))) {
      res.writeHead(403).end();
      return;
    }
    fs.stat(file, (err, st) => {
      if (err || !st.isFile()) {
        res.writeHead(404).end();
        return;
      }
      const type = types[path.extname(file)] || "application/octet-stream";
      const range = /bytes=(\d*)-(\d*)/.exec(req.headers.range || "");
      if (range) {
        const start = range[1] ? Number(range[1]) : 0;
        const end = range[2] ? Number(range[2]) : st.size - 1;
        res.writeHead(206, {
          "Content-Type": type,
          "Content-Range": `bytes ${start}-${end}/${st.size}`,
          "Content-Length": end - start + 1,
          "Accept-Ranges": "bytes",
        });
        fs.createReadStream(file, { start, end }).pipe(res);
      } else {
        res.writeHead(200, { "Content-Type": type, "Content-Length": st.size, "Accept-Ranges": "bytes" });
        fs.createReadStream(file).pipe(res);
      }
    });
  });
  return new Promise((resolve) => server.listen(port, "127.0.0.1", () => resolve(server)));
}

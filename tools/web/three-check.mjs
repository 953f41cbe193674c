// Opens glTF files with three.js's own GLTFLoader in Debian's Chromium (headless, WebGL2 on
// SwiftShader): a client lodlab did not write. Each file's first clip is played to a fixed
// time, the scene drawn from a fixed camera on transparent black, and the picture written as a
// PNG, to be compared with `lodlab shot` of the same view (tests/integration/export.rs).
//
//   node three-check.mjs --out DIR [--size 256x256] [--camera YAW,PITCH,DISTANCE,X,Y,Z]
//                        [--time SECONDS] [--no-normal-maps] [--place] FILE.glb...
//
// --place stands every file where lodlab's importer stands the first (src/import/nodes.rs,
// place_in_scene): its rest pose's bounds centred over the origin, their bottom on the ground.
// The files keep their source's space (an engine puts its own asset's levels where the asset
// was), and a file's levels share one placement.
//
// The camera is lodlab's (`shot --camera`): yaw about +y (0 looks along -z), pitch above the
// horizon, distance from the point looked at, a vertical field of view of 50°. The lights are
// lodlab's sun and sky (`render::uniforms::Lighting`) as three.js's physical lights: a
// directional light and a hemisphere light, each π times lodlab's colour, since three.js's
// Lambert term divides by π where lodlab's does not.
//
// Prints one JSON line a file: the PNG, the meshes, skinned meshes and clips three.js found,
// the vertices it drew, and the console's errors. Exits 1 with one line on stderr when the
// page fails.
import fs from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { parseArgs } from "node:util";
import { launch, chromiumArgs, serve } from "./browser.mjs";

const { values: o, positionals: files } = parseArgs({
  allowPositionals: true,
  options: {
    out: { type: "string" },
    size: { type: "string", default: "256x256" },
    camera: { type: "string", default: "0,10,10,0,1,0" },
    time: { type: "string", default: "1" },
    "no-normal-maps": { type: "boolean", default: false },
    place: { type: "boolean", default: false },
  },
});
fs.mkdirSync(o.out, { recursive: true });
const [width, height] = o.size.split("x").map(Number);
const camera = o.camera.split(",").map(Number);
if (camera.length !== 6 || camera.some((x) => !Number.isFinite(x))) {
  console.error(`three-check: --camera wants YAW,PITCH,DISTANCE,X,Y,Z, not ${o.camera}`);
  process.exit(1);
}
const here = path.dirname(fileURLToPath(import.meta.url));
const three = path.join(here, "node_modules/three");
if (!fs.existsSync(path.join(three, "build/three.module.js"))) {
  console.error("three-check: three.js is not installed (npm ci --prefix tools/web)");
  process.exit(1);
}

// lodlab's light (src/render/uniforms.rs, Lighting::default), linear RGB.
const sun = { dir: [-0.45, 0.75, 0.5], colour: [1.0 * 1.15, 0.93 * 1.15, 0.82 * 1.15] };
const skyZenith = [0.2, 0.4, 0.74];
const ground = [0.22, 0.21, 0.18];
// The hemisphere's sky end as lodlab's shader mixes it (shaders/common.wgsl, sun_and_sky).
const sky = skyZenith.map((c) => c * 0.9 + 0.08);

const page = `<!doctype html><html><body style="margin:0;background:#000">
<script type="importmap">{"imports":{"three":"/three/build/three.module.js","three/addons/":"/three/examples/jsm/"}}</script>
<script type="module">
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
const linear = (c) => new THREE.Color().setRGB(c[0], c[1], c[2], THREE.LinearSRGBColorSpace);
window.draw = async (url, o) => {
  const renderer = new THREE.WebGLRenderer({ antialias: false, alpha: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(o.width, o.height);
  renderer.setClearColor(0x000000, 0);
  renderer.toneMapping = THREE.NoToneMapping;
  renderer.outputColorSpace = THREE.SRGBColorSpace;
  document.body.replaceChildren(renderer.domElement);
  const scene = new THREE.Scene();
  const sunLight = new THREE.DirectionalLight(linear(o.sun.colour), Math.PI);
  sunLight.position.set(...o.sun.dir);
  scene.add(sunLight);
  scene.add(new THREE.HemisphereLight(linear(o.sky), linear(o.ground), Math.PI));
  const gltf = await new GLTFLoader().loadAsync(url);
  scene.add(gltf.scene);
  if (o.place) {
    gltf.scene.updateMatrixWorld(true);
    if (!window.anchor) {
      const box = new THREE.Box3().setFromObject(gltf.scene, true);
      window.anchor = [(box.min.x + box.max.x) / 2, box.min.y, (box.min.z + box.max.z) / 2];
    }
    gltf.scene.position.set(-window.anchor[0], -window.anchor[1], -window.anchor[2]);
  }
  gltf.scene.traverse((n) => {
    if (!n.isMesh) return;
    if (o.noNormalMaps) n.material.normalMap = null;
  });
  const mixer = new THREE.AnimationMixer(gltf.scene);
  if (gltf.animations.length > 0) {
    mixer.clipAction(gltf.animations[0]).play();
    mixer.setTime(o.time % gltf.animations[0].duration);
  }
  gltf.scene.updateMatrixWorld(true);
  const [yaw, pitch, distance, x, y, z] = o.camera;
  const r = Math.PI / 180;
  const target = new THREE.Vector3(x, y, z);
  const eye = new THREE.Vector3(
    Math.sin(yaw * r) * Math.cos(pitch * r),
    Math.sin(pitch * r),
    Math.cos(yaw * r) * Math.cos(pitch * r),
  ).multiplyScalar(distance).add(target);
  const near = Math.min(Math.max(distance * 0.01, 0.02), 0.5);
  const cam = new THREE.PerspectiveCamera(50, o.width / o.height, near, 3000);
  cam.position.copy(eye);
  cam.lookAt(target);
  renderer.render(scene, cam);
  let meshes = 0, skinned = 0;
  gltf.scene.traverse((n) => {
    if (n.isMesh) meshes++;
    if (n.isSkinnedMesh) skinned++;
  });
  return {
    png: renderer.domElement.toDataURL("image/png"),
    meshes,
    skinned,
    clips: gltf.animations.map((a) => a.name),
    vertices: renderer.info.render.triangles,
  };
};
window.ready = true;
</script></body></html>`;

const byUrl = new Map(files.map((f, i) => [`/files/${i}.glb`, f]));
const server = await serve(path.dirname(three), 0, (req, res) => {
  const url = new URL(req.url, "http://x").pathname;
  if (url === "/" || url === "/index.html") {
    res.writeHead(200, { "Content-Type": "text/html; charset=utf-8" }).end(page);
    return true;
  }
  if (url === "/favicon.ico") {
    res.writeHead(204).end();
    return true;
  }
  const file = byUrl.get(url);
  if (file) {
    res.writeHead(200, { "Content-Type": "model/gltf-binary" }).end(fs.readFileSync(file));
    return true;
  }
  return false;
});
const browser = await launch(chromiumArgs.webgl);
let failed = false;
try {
  const tab = await browser.newPage();
  const errors = [];
  tab.on("console", (m) => {
    if (m.type() === "error") errors.push(m.text());
  });
  tab.on("pageerror", (e) => errors.push(String(e)));
  await tab.setViewport({ width, height });
  await tab.goto(`http://127.0.0.1:${server.address().port}/index.html`);
  await tab.waitForFunction(() => window.ready === true, { timeout: 60000 });
  for (const [url, file] of byUrl) {
    const r = await tab.evaluate(
      (url, opts) => window.draw(url, opts),
      url,
      { width, height, camera, time: Number(o.time), sun, sky, ground, noNormalMaps: o["no-normal-maps"], place: o.place },
    );
    const png = path.join(o.out, path.basename(file, path.extname(file)) + ".png");
    fs.writeFileSync(png, Buffer.from(r.png.split(",")[1], "base64"));
    console.log(JSON.stringify({ file, png, meshes: r.meshes, skinned: r.skinned, clips: r.clips, triangles: r.vertices, errors: errors.splice(0) }));
  }
} catch (e) {
  console.error(`three-check: ${String(e.message || e).split("\n")[0]}`);
  failed = true;
} finally {
  await browser.close();
  server.close();
}
process.exit(failed ? 1 : 0);

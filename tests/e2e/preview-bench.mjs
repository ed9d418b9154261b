#!/usr/bin/env node
// Orbit frame times of the 3D preview at growing segment counts, as tubes and as lines, in
// headless Chromium with SwiftShader (the software WebGL of the tests): the measurement behind
// TUBE_LIMIT in www/preview.js. A synthetic result (a stack of concentric rings, like a sliced
// part's perimeters and infill) is shown in the page's Preview; each frame turns the camera
// 2° round the part and is timed up to a readPixels (the GPU, here the CPU, finishes it).
//
//   node tests/e2e/preview-bench.mjs [segments …]   (default 50k 100k 200k 400k 800k 1.6M 2M)
// Environment: FRAMES (per count and style, default 12), VIEWPORT (default 1280x800), CHROMIUM.
import { ROOT, serve } from "./server.mjs";
import { launchChromium, waitReady } from "./page-helpers.mjs";

const counts = process.argv.slice(2).map(Number).filter((n) => n > 0);
const sizes = counts.length ? counts : [50e3, 100e3, 200e3, 400e3, 800e3, 1.6e6, 2e6];
const frames = Number(process.env.FRAMES ?? 12);
const [width, height] = (process.env.VIEWPORT ?? "1280x800").split("x").map(Number);

const server = await serve({ root: ROOT });
const browser = await launchChromium();
try {
  const page = await (await browser.newContext({ viewport: { width, height } })).newPage();
  await page.goto(`${server.url}/www/`);
  await waitReady(page);
  await page.waitForFunction(() => window.weft.preview);
  console.log(`viewport ${width}x${height}, ${frames} frames each; median / max ms per orbit frame`);
  console.log("segments   | tubes median | tubes max | lines median | lines max");
  for (const n of sizes) {
    const r = await page.evaluate(async ({ n, frames }) => {
      // n segments: layers of concentric rings, 400 segments a ring, 0.2 mm layers, radius 40 mm.
      const perRing = 400, ringsPerLayer = Math.max(1, Math.round(Math.sqrt(n / perRing / 2)));
      const perLayer = perRing * ringsPerLayer, layers = Math.ceil(n / perLayer);
      const positions = new Float32Array(n * 6);
      const layerStart = new Uint32Array(layers + 1);
      const layerZ = new Float32Array(layers);
      const feature = new Uint8Array(n), path = new Uint32Array(n), flow = new Float32Array(n), width = new Float32Array(n).fill(0.45);
      let i = 0;
      for (let l = 0; l < layers; l++) {
        layerStart[l] = Math.min(i, n);
        const z = 0.2 * (l + 1);
        layerZ[l] = z;
        for (let k = 0; k < ringsPerLayer && i < n; k++) {
          const rad = 40 * (1 - k / ringsPerLayer) * Math.sqrt(Math.max(0.05, 1 - ((z - 0.1 * layers) / (0.1 * layers)) ** 2));
          for (let s = 0; s < perRing && i < n; s++, i++) {
            const a0 = (s / perRing) * 2 * Math.PI, a1 = ((s + 1) / perRing) * 2 * Math.PI;
            positions.set([100 + rad * Math.cos(a0), 100 + rad * Math.sin(a0), z, 100 + rad * Math.cos(a1), 100 + rad * Math.sin(a1), z], i * 6);
            feature[i] = k === 0 ? 0 : 4;
            path[i] = l * ringsPerLayer + k;
            flow[i] = 2 + k % 3;
          }
        }
      }
      layerStart[layers] = n;
      const p = window.weft.preview;
      p.setResult({
        positions, feature, path, flow, width, layerStart, layerZ, travel: new Float32Array(0),
        travelLayerStart: new Uint32Array(0), bedSize: new Float64Array([220, 220, 250]), axis: new Float32Array(0),
        segmentMove: new Uint32Array(0), travelMove: new Uint32Array(0),
      });
      const gl = p.renderer.getContext();
      const px = new Uint8Array(4);
      const out = {};
      for (const style of ["tubes", "lines"]) {
        p.setStyle(style);
        const target = p.controls.target;
        const times = [];
        for (let f = -2; f < frames; f++) { // two frames to upload the buffers and compile
          const off = p.camera.position.clone().sub(target).applyAxisAngle(p.camera.up, (2 * Math.PI) / 180);
          p.camera.position.copy(target).add(off);
          p.camera.lookAt(target);
          const t0 = performance.now();
          p.updateClipping();
          p.renderer.render(p.scene, p.camera);
          gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
          if (f >= 0) times.push(performance.now() - t0);
        }
        times.sort((a, b) => a - b);
        out[style] = [times[times.length >> 1], times[times.length - 1]];
      }
      p.setStyle("auto");
      p.setResult(null);
      return out;
    }, { n, frames });
    const f = (v) => v.toFixed(0).padStart(8);
    console.log(`${String(n).padStart(10)} | ${f(r.tubes[0])}     | ${f(r.tubes[1])}  | ${f(r.lines[0])}     | ${f(r.lines[1])}`);
  }
} finally {
  await browser.close();
  await server.close();
}

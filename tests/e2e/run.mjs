#!/usr/bin/env node
// End-to-end test of the browser app: system Chromium driven by playwright-core against a
// static server of the repository root on localhost. Prints one line per check and ends with
// "<n> passed, <m> failed"; exits non-zero when a check fails.
//
//   node tests/e2e/run.mjs
// Environment:
//   WEFT_BIN       native CLI for cross-checks (default ./target/release/weft)
//   CHROMIUM       browser executable (default /usr/bin/chromium)
//   WEFT_PKG_DIR   serve this directory as /pkg/ instead of ./pkg (test another wasm build)
//   E2E_TIMEOUT_S  per-job timeout in seconds (default 120)
//   E2E_HEADED=1   show the browser
import { existsSync, mkdirSync, readFileSync, writeFileSync } from "node:fs";
import { createHash } from "node:crypto";
import { execFileSync } from "node:child_process";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { chromium } from "playwright-core";
import { serve } from "./server.mjs";
import { latticeChecks } from "./lattice-checks.mjs";
import { colouredPixels, downloadGcode, waitReady, waitResult as waitResultWithin } from "./page-helpers.mjs";

const ROOT = resolve(dirname(fileURLToPath(import.meta.url)), "../..");
const OUT = join(ROOT, "tests/e2e/out");
const WEFT_BIN = resolve(ROOT, process.env.WEFT_BIN ?? "target/release/weft");
const CHROMIUM = process.env.CHROMIUM ?? "/usr/bin/chromium";
const PKG_DIR = process.env.WEFT_PKG_DIR ? resolve(process.env.WEFT_PKG_DIR) : join(ROOT, "pkg");
const JOB_TIMEOUT = Number(process.env.E2E_TIMEOUT_S ?? 120) * 1000;
const VIEWPORT = { width: 1400, height: 900 };
mkdirSync(OUT, { recursive: true });

// ---------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------
const sha256 = (buf) => createHash("sha256").update(buf).digest("hex");

/** A binary STL of an axis-aligned cube (12 triangles). */
function cubeStl(size = 20) {
  const v = (i) => [(i & 1) * size, ((i >> 1) & 1) * size, ((i >> 2) & 1) * size];
  const faces = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
  const tris = faces.flatMap(([a, b, c, d]) => [[a, b, c], [a, c, d]]);
  const buf = Buffer.alloc(84 + 50 * tris.length);
  buf.write("weft e2e cube", 0);
  buf.writeUInt32LE(tris.length, 80);
  tris.forEach((t, i) => {
    const o = 84 + i * 50;
    const [p, q, r] = t.map(v);
    const u = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
    const w = [r[0] - p[0], r[1] - p[1], r[2] - p[2]];
    const n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
    const len = Math.hypot(...n) || 1;
    n.forEach((x, k) => buf.writeFloatLE(x / len, o + 4 * k));
    [p, q, r].forEach((pt, j) => pt.forEach((x, k) => buf.writeFloatLE(x, o + 12 + 12 * j + 4 * k)));
  });
  return buf;
}

function fixtureCube() {
  const fixture = join(ROOT, "tests/fixtures/cube.stl");
  if (existsSync(fixture)) return { path: fixture, name: "cube.stl", bytes: readFileSync(fixture) };
  const path = join(OUT, "cube.stl");
  const bytes = cubeStl();
  writeFileSync(path, bytes);
  return { path, name: "cube.stl", bytes };
}

function cli(args) {
  if (!existsSync(WEFT_BIN)) {
    throw new Error(`native CLI ${WEFT_BIN} not found: build it with \`cargo build --release\` or set WEFT_BIN`);
  }
  try {
    return execFileSync(WEFT_BIN, args, { cwd: ROOT, encoding: "utf8", stdio: ["ignore", "pipe", "pipe"], timeout: 300000 });
  } catch (err) {
    throw new Error(`\`weft ${args.join(" ")}\` failed: ${(err.stderr || err.message || "").toString().trim()}`);
  }
}

const waitResult = (page, before, what) => waitResultWithin(page, before, what, JOB_TIMEOUT);
const download = (page, what) => downloadGcode(page, join(OUT, what));

async function dropFile(page, name, buffer, mimeType = "application/octet-stream") {
  await page.setInputFiles("#file", { name, mimeType, buffer });
}

// ---------------------------------------------------------------------------------------
// Checks
// ---------------------------------------------------------------------------------------
const results = [];
async function check(n, title, fn) {
  const t0 = Date.now();
  try {
    const detail = await fn();
    results.push(true);
    console.log(`PASS ${n}. ${title}${detail ? ` (${detail})` : ""} [${((Date.now() - t0) / 1000).toFixed(1)} s]`);
  } catch (err) {
    results.push(false);
    console.log(`FAIL ${n}. ${title}: ${err.message.split("\n").join("\n       ")}`);
  }
}

// Static server of the repository root, localhost only (tests/e2e/server.mjs).
const server = await serve({ root: ROOT, pkgDir: PKG_DIR });
const base = server.url;
const browser = await chromium.launch({
  executablePath: CHROMIUM,
  headless: !process.env.E2E_HEADED,
  args: [
    "--headless", "--no-sandbox", "--disable-background-networking", "--disable-component-update",
    "--disable-sync", "--disable-gpu-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
  ].filter((a) => !(process.env.E2E_HEADED && a === "--headless")),
});
const newPage = async () => {
  const context = await browser.newContext({ viewport: VIEWPORT, acceptDownloads: true });
  // Nothing may leave the origin.
  await context.route(/^(?!http:\/\/127\.0\.0\.1:\d+\/|blob:|data:)/, (route) => {
    offOrigin.push(route.request().url());
    return route.abort();
  });
  const page = await context.newPage();
  const errors = [];
  page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });
  page.on("pageerror", (e) => errors.push(`uncaught: ${e.message}`));
  return { context, page, errors };
};
const offOrigin = [];

const cube = fixtureCube();
const main = await newPage();
const { page } = main;
let webGcode = null;
let changed = null;

await check(1, "page loads without console errors; canvas exists", async () => {
  const res = await page.goto(`${base}/www/`);
  if (!res.ok()) throw new Error(`GET /www/ → ${res.status()}`);
  await waitReady(page);
  if (!(await page.$("canvas#preview"))) throw new Error("no canvas#preview");
  for (const id of ["error", "stats", "download", "share", "examples", "color-by", "show-travel", "layer-min", "layer-max"]) {
    if (!(await page.$(`#${id}`))) throw new Error(`#${id} missing`);
  }
  await page.waitForTimeout(500);
  if (main.errors.length) throw new Error(`console errors:\n${main.errors.join("\n")}`);
  if (offOrigin.length) throw new Error(`requests left the origin: ${offOrigin.join(", ")}`);
  const err = await page.$eval("#error", (e) => (e.hidden ? "" : e.textContent.trim()));
  if (err) throw new Error(`error panel shows: ${err}`);
});

await check(2, "drop an STL → result drawn in the preview", async () => {
  const before = await page.evaluate(() => window.weft.resultCount);
  await dropFile(page, cube.name, cube.bytes, "model/stl");
  try {
    await waitResult(page, before, `slicing ${cube.name}`);
  } finally {
    await page.screenshot({ path: join(ROOT, "tests/e2e/screenshot.png") });
  }
  const px = await colouredPixels(page);
  const segs = await page.evaluate(() => (window.weft.result?.gcode?.byteLength ?? 0));
  if (px < 1500) throw new Error(`only ${px} toolpath-coloured pixels in the preview (G-code ${segs} bytes); the preview did not draw a toolpath`);
  return `${px} coloured pixels`;
});

await check(3, "Download G-code → native `weft analyze` finds layers and extrusion", async () => {
  const dl = await download(page, "web.gcode");
  if (!dl.bytes.length) throw new Error("the downloaded G-code is empty");
  if (!dl.name.endsWith(".gcode")) throw new Error(`download named ${dl.name}`);
  webGcode = dl.bytes;
  const report = JSON.parse(cli(["analyze", dl.path, "--json"]));
  const a = report.analysis ?? report;
  if (!(a.layers > 0)) throw new Error(`weft analyze: layers = ${a.layers}`);
  if (!(a.extruded_mm > 0)) throw new Error(`weft analyze: extruded_mm = ${a.extruded_mm}`);
  return `${dl.name}: ${a.layers} layers, ${a.extruded_mm.toFixed(1)} mm extruded`;
});

await check(4, "Share link reproduces the G-code in a fresh browser and matches the CLI byte for byte", async () => {
  if (!webGcode) throw new Error("no G-code from check 3 to compare with");
  await page.click("#share");
  await page.waitForFunction(() => location.hash.startsWith("#d="), null, { timeout: 10000 });
  const url = page.url();
  const designJson = await page.evaluate(() => window.weft.design);
  const designPath = join(OUT, "design.json");
  writeFileSync(designPath, designJson);

  const other = await newPage();
  try {
    await other.page.goto(url);
    await waitReady(other.page);
    await waitResult(other.page, 0, "auto-run of the shared design");
    const dl = await download(other.page, "shared.gcode");
    if (sha256(dl.bytes) !== sha256(webGcode)) {
      throw new Error(`G-code from the share link differs from the original (${dl.bytes.length} vs ${webGcode.length} bytes)`);
    }
    if (other.errors.length) throw new Error(`console errors in the shared page:\n${other.errors.join("\n")}`);
  } finally {
    await other.context.close();
  }
  const cliOut = join(OUT, "cli.gcode");
  cli(["run", designPath, "--out", cliOut, "--input", cube.path]);
  const cliBytes = readFileSync(cliOut);
  if (sha256(cliBytes) !== sha256(webGcode)) {
    throw new Error(`native CLI G-code differs from the browser's (${cliBytes.length} vs ${webGcode.length} bytes): ` +
      `compare ${cliOut} with ${join(OUT, "web.gcode")}`);
  }
  return `sha256 ${sha256(webGcode).slice(0, 12)}…, ${url.length}-character URL`;
});

await check(5, "corrupt STL → #error names the file and line; design and preview are kept", async () => {
  // Change a field first so we can see it survives.
  changed = await page.evaluate(() => {
    const inputs = [...document.querySelectorAll("#schema-fields input[type=number]")];
    const pick = inputs.find((i) => /perimeters$/.test(i.dataset.path)) ??
      inputs.find((i) => i.step === "1") ?? inputs[0];
    if (!pick) return null;
    const cur = Number(pick.value);
    const step = Number(pick.step) || 0;
    const candidates = step >= 1 ? [cur + 1, cur - 1] : [cur * 1.1, cur * 0.9].map((v) => Number(v.toPrecision(3)));
    for (const v of candidates) {
      const before = window.weft.design;
      pick.value = String(v);
      pick.dispatchEvent(new Event("change", { bubbles: true }));
      if (window.weft.design !== before) return { id: pick.id, path: pick.dataset.path, value: String(v) };
    }
    return { id: pick.id, path: pick.dataset.path, value: null };
  });
  if (!changed || changed.value === null) throw new Error(`could not change a form field (${JSON.stringify(changed)})`);
  const pxBefore = await colouredPixels(page);
  await dropFile(page, "corrupt.stl", Buffer.from("solid x\nfacet normal 0 0 1\nouter loop\nvertex 1 2\n"), "model/stl");
  await page.waitForSelector("#error:not([hidden])", { timeout: JOB_TIMEOUT });
  const message = (await page.textContent("#error-text")).trim();
  if (!message.includes("corrupt.stl")) throw new Error(`error does not name the file: ${message}`);
  if (!/line\s*\d+|:\d+/i.test(message)) throw new Error(`error does not name a line: ${message}`);
  const still = await page.evaluate(({ id, path }) => ({
    input: document.getElementById(id)?.value,
    design: path.split(".").reduce((o, k) => o?.[k], JSON.parse(window.weft.design)),
    files: window.weft.files,
  }), changed);
  if (String(still.design) !== changed.value && Number(still.design) !== Number(changed.value)) {
    throw new Error(`design field ${changed.path} is ${still.design}, expected ${changed.value}`);
  }
  if (Number(still.input) !== Number(changed.value)) throw new Error(`form shows ${still.input} for ${changed.path}`);
  if (still.files.includes("corrupt.stl")) throw new Error("the corrupt file was kept");
  const px = await colouredPixels(page);
  if (px < Math.min(1500, pxBefore * 0.5)) throw new Error(`preview lost: ${px} coloured pixels (was ${pxBefore})`);
  return `"${message.split("\n")[0].slice(0, 90)}"`;
});

await check(6, "damaged share fragment #d=!!!! → clear error, page still works", async () => {
  const fresh = await newPage();
  try {
    const p = fresh.page;
    await p.goto(`${base}/www/#d=!!!!`);
    await waitReady(p);
    await p.waitForSelector("#error:not([hidden])", { timeout: 10000 });
    const message = (await p.textContent("#error-text")).trim();
    if (!/share|link|fragment/i.test(message)) throw new Error(`unclear message: ${message}`);
    if (!(await p.evaluate(() => JSON.parse(window.weft.design).version))) throw new Error("no design shown");
    if ((await p.$$("#schema-fields input")).length === 0) throw new Error("the form is empty");
    await p.click("#slice");
    await waitResult(p, 0, "slicing the default design after the damaged link");
    return `"${message.split("\n")[0].slice(0, 90)}"`;
  } finally {
    await fresh.context.close();
  }
});

await check(7, "Cancel stops a long job, restarts the worker, and a short run works after", async () => {
  const fresh = await newPage();
  try {
    const p = fresh.page;
    await p.goto(`${base}/www/`);
    await waitReady(p);
    const short = await p.evaluate(() => window.weft.design);
    const long = JSON.parse(short);
    long.name = "long-sphere";
    long.job.input = { builtin: { shape: "sphere", radius: 60, segments: 128 } };
    long.job.slice.layer_height_mm = 0.05;
    await dropFile(p, "long.json", Buffer.from(JSON.stringify(long)), "application/json");
    await p.waitForFunction(() => JSON.parse(window.weft.design).name === "long-sphere", null, { timeout: 10000 })
      .catch(async () => { throw new Error(`the long design was not accepted: ${await p.textContent("#error-text")}`); });
    const gen = await p.evaluate(() => window.weft.workerGeneration);
    const t0 = Date.now();
    await p.click("#slice");
    const shown = await p.waitForSelector("#progress:not([hidden])", { timeout: 15000 }).catch(() => null);
    if (!shown) {
      const count = await p.evaluate(() => window.weft.resultCount);
      const error = await p.evaluate(() => (document.getElementById("error").hidden ? "" : document.getElementById("error-text").textContent));
      throw new Error(`no progress bar: the long job ${count ? `finished in ${Date.now() - t0} ms` : error ? `failed: ${error}` : "did not start"}; nothing to cancel`);
    }
    await p.waitForTimeout(300);
    await p.click("#cancel");
    await p.waitForSelector("#progress", { state: "hidden", timeout: 5000 });
    const after = await p.evaluate(() => ({ gen: window.weft.workerGeneration, busy: window.weft.busy, count: window.weft.resultCount }));
    if (after.gen !== gen + 1) throw new Error(`worker generation ${gen} → ${after.gen}; expected a restart`);
    if (after.busy) throw new Error("still busy after Cancel");
    await dropFile(p, "short.json", Buffer.from(short), "application/json");
    await p.waitForFunction((s) => window.weft.design === s, short, { timeout: 10000 });
    const t1 = Date.now();
    await p.click("#slice");
    await waitResult(p, after.count, "short run after Cancel");
    const count = await p.evaluate(() => window.weft.resultCount);
    if (count !== after.count + 1) throw new Error("the cancelled job delivered a result");
    if (fresh.errors.length) throw new Error(`console errors:\n${fresh.errors.join("\n")}`);
    return `cancelled after ${((t1 - t0) / 1000).toFixed(1)} s; short run took ${((Date.now() - t1) / 1000).toFixed(1)} s`;
  } finally {
    await fresh.context.close();
  }
});

await latticeChecks({ browser, baseUrl: base, weftBin: WEFT_BIN, check, newPage, outDir: OUT, first: 8 });

if (main.errors.length) console.log(`note: console errors in the main page:\n  ${main.errors.join("\n  ")}`);
if (offOrigin.length) console.log(`note: blocked requests leaving the origin:\n  ${[...new Set(offOrigin)].join("\n  ")}`);
await browser.close();
server.close();
const passed = results.filter(Boolean).length;
const failed = results.length - passed;
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);

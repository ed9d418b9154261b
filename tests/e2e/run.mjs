#!/usr/bin/env node
// End-to-end test of the browser app: system Chromium driven by playwright-core against a
// static server of the repository root on localhost, cross-origin isolated as scripts/serve.py
// serves it (so the worker computes on its thread pool; threads-checks.mjs also runs a plain
// host). Prints one line per check and ends with
// "<n> passed, <m> failed"; exits non-zero when a check fails.
//
//   node tests/e2e/run.mjs
// Environment:
//   WEFT_BIN       native CLI for cross-checks (default ./target/release/weft)
//   CHROMIUM       browser executable (default /usr/bin/chromium)
//   WEFT_PKG_DIR   serve this directory as /pkg/ instead of ./pkg (test another wasm build)
//   E2E_TIMEOUT_S  per-job timeout in seconds (default 120)
//   E2E_HEADED=1   show the browser
import { closeSync, existsSync, ftruncateSync, mkdirSync, openSync, readFileSync, unlinkSync, writeFileSync, writeSync } from "node:fs";
import { createHash } from "node:crypto";
import { execFileSync } from "node:child_process";
import { deflateRawSync } from "node:zlib";
import { join, resolve } from "node:path";
import { ROOT, serve } from "./server.mjs";
import { axisymChecks } from "./axisym-checks.mjs";
import { foamChecks } from "./foam-checks.mjs";
import { freeformChecks } from "./freeform-checks.mjs";
import { gradedChecks } from "./graded-checks.mjs";
import { latticeChecks } from "./lattice-checks.mjs";
import { newcomerChecks } from "./newcomer-checks.mjs";
import { previewChecks } from "./preview-checks.mjs";
import { threadsChecks } from "./threads-checks.mjs";
import { hostsFromEnv, sendChecks } from "./send-checks.mjs";
import { supportChecks } from "./support-checks.mjs";
import { stepsChecks } from "./steps-checks.mjs";
import { picturesChecks } from "./pictures-checks.mjs";
import {
  boxStl, checker, collectErrors, colouredPixels, confirmBigJobs, downloadGcode, launchChromium, stageMarks, waitReady, waitResult as waitResultWithin, watchAfterCancel,
} from "./page-helpers.mjs";

const OUT = join(ROOT, "tests/e2e/out");
const WEFT_BIN = resolve(ROOT, process.env.WEFT_BIN ?? "target/release/weft");
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
  return boxStl([0, 0, 0], [size, size, size], "weft e2e cube");
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
const { results, check } = checker();

// Static server of the repository root, localhost only (tests/e2e/server.mjs).
const server = await serve({ root: ROOT, pkgDir: PKG_DIR });
const base = server.url;
const browser = await launchChromium();
const newPage = async () => {
  const context = await browser.newContext({ viewport: VIEWPORT, acceptDownloads: true });
  // Checks run what they mean to run: no live re-run of light jobs after an edit (check 18
  // switches it on to test it).
  await context.addInitScript(() => {
    if (localStorage.getItem("weft.autoRun") === null) localStorage.setItem("weft.autoRun", "0");
  });
  // Nothing may leave the origin.
  await context.route(/^(?!http:\/\/127\.0\.0\.1:\d+\/|blob:|data:)/, (route) => {
    offOrigin.push(route.request().url());
    return route.abort();
  });
  const page = await context.newPage();
  return { context, page, errors: collectErrors(page) };
};
const offOrigin = [];

/** Runs `fn(page, errors)` in a fresh browser context opened at `path` of the server, then closes it. */
async function inFreshPage(path, fn) {
  const { context, page: p, errors } = await newPage();
  try {
    await p.goto(`${base}${path}`);
    await waitReady(p);
    return await fn(p, errors);
  } finally {
    await context.close();
  }
}

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
  for (const id of ["error", "stats", "download", "share", "examples", "color-by", "show-travel", "layer-min", "layer-max", "move-max", "slots", "report", "views"]) {
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
  // The dropped file was imported when it was read, before the run: the run counts that work.
  const timings = await page.evaluate(() => window.weft.result.report.timings);
  const imported = timings.find((t) => t.stage === "import");
  if (!imported || imported.cached || !(imported.ms >= 0)) throw new Error(`the run's timings do not count the dropped file's import: ${JSON.stringify(timings)}`);
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
  // The same file dropped on the page: the worker reads it from its Blob and analyses it; its
  // report is the CLI's and the page's G-code is the file, byte for byte.
  const before = await page.evaluate(() => window.weft.resultCount);
  await page.setInputFiles("#file", dl.path);
  await waitResult(page, before, `analysing ${dl.name} on the page`);
  const shown = await page.evaluate(async () => {
    const r = window.weft.result;
    const digest = new Uint8Array(await crypto.subtle.digest("SHA-256", r.gcode));
    return { a: r.report.analysis, sha: [...digest].map((b) => b.toString(16).padStart(2, "0")).join("") };
  });
  for (const key of ["layers", "extrusion_paths", "retractions", "extruded_mm", "travel_mm", "overlap_mm", "gippo_score", "estimated_time_s"]) {
    if (shown.a[key] !== a[key]) throw new Error(`the page's analysis of ${dl.name}: ${key} = ${shown.a[key]}, the CLI's ${a[key]}`);
  }
  if (shown.sha !== sha256(dl.bytes)) throw new Error(`the page's G-code after analysing ${dl.name} is not the file`);
  return `${dl.name}: ${a.layers} layers, ${a.extruded_mm.toFixed(1)} mm extruded; the page's analysis of the dropped file equals the CLI's`;
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

await check(52, "a mesh or G-code over the limits (a 100M-triangle binary STL of 5 GB, a 5 GiB OBJ, 2 GiB of G-code: sparse files) is refused from its head and size before a copy is made: #error names the file, the count or size, the limit and the fix; the worker is not restarted and the design is kept", async () => {
  const designBefore = await page.evaluate(() => window.weft.design);
  const stlHead = Buffer.alloc(84);
  stlHead.writeUInt32LE(100_000_000, 80);
  const cases = [
    ["huge-100m.stl", stlHead, 84 + 50 * 100_000_000, ["100,000,000 triangles", "limit 5,000,000", "decimate"]],
    ["huge-5g.obj", Buffer.from("v 0 0 0\n"), 5 * 2 ** 30, ["5,120 MiB", "1,024 MiB", "decimate"]],
    // G-code to analyse: refused from the Blob's size in the worker, before it is read.
    ["huge-2g.gcode", Buffer.from("G1 X0\n"), 2 * 2 ** 30, ["2,048 MiB", "1,024 MiB", "split"]],
  ];
  const seen = [];
  for (const [name, head, size, words] of cases) {
    // Sparse: a head and a length, no disk. Without the head check the worker would try to
    // copy gigabytes into its memory (wasm32 holds at most 4 GiB) and stop.
    const path = join(OUT, name);
    const fd = openSync(path, "w");
    writeSync(fd, head);
    ftruncateSync(fd, size);
    closeSync(fd);
    try {
      await page.setInputFiles("#file", path);
      await page.waitForFunction((n) => !document.getElementById("error").hidden && document.getElementById("error-text").textContent.includes(n), name, { timeout: JOB_TIMEOUT });
      const message = (await page.textContent("#error-text")).trim();
      for (const w of words) if (!message.includes(w)) throw new Error(`${name}: the message lacks "${w}": ${message}`);
      if (/worker stopped|restarted/i.test(message)) throw new Error(`${name}: the worker stopped: ${message}`);
      seen.push(message.split(";")[0].slice(0, 80));
    } finally {
      unlinkSync(path);
    }
  }
  const after = await page.evaluate(() => ({ design: window.weft.design, files: window.weft.files }));
  if (after.design !== designBefore) throw new Error("the design changed");
  if (after.files.some((f) => f.startsWith("huge-"))) throw new Error(`a refused file was kept: ${after.files}`);
  return seen.join(" | ");
});

await check(6, "damaged share fragment #d=!!!! → clear error, page still works", () => inFreshPage("/www/#d=!!!!", async (p) => {
  await p.waitForSelector("#error:not([hidden])", { timeout: 10000 });
  const message = (await p.textContent("#error-text")).trim();
  if (!/share|link|fragment/i.test(message)) throw new Error(`unclear message: ${message}`);
  if (!(await p.evaluate(() => JSON.parse(window.weft.design).version))) throw new Error("no design shown");
  if ((await p.$$("#schema-fields input")).length === 0) throw new Error("the form is empty");
  await p.click("#slice");
  await waitResult(p, 0, "slicing the default design after the damaged link");
  // A link whose design lacks its job: the message's `quoted` command is shown as code, as
  // text, without the backticks.
  const noJob = deflateRawSync(JSON.stringify({ version: 1, name: "no job" })).toString("base64url");
  await p.goto(`${base}/www/#d=${noJob}`);
  await p.waitForSelector("#error:not([hidden])", { timeout: 10000 });
  const missing = await p.evaluate(() => ({
    text: document.getElementById("error-text").textContent,
    code: [...document.querySelectorAll("#error-text code")].map((c) => c.textContent),
  }));
  if (!/job/.test(missing.text) || missing.text.includes("`") || missing.code.join("|") !== "weft new") {
    throw new Error(`the missing job's message is not shown with its command as code: ${JSON.stringify(missing)}`);
  }
  return `"${message.split("\n")[0].slice(0, 90)}"; "${missing.text.slice(0, 90)}" (code: ${missing.code.join(", ")})`;
}));

await check(7, "Cancel stops a long job: the worker and its pool end, nothing of the run shows after; the worker restarts and a short run works after", () => inFreshPage("/www/", async (p, errors) => {
  const short = await p.evaluate(() => window.weft.design);
  const long = JSON.parse(short);
  long.name = "long-sphere";
  long.job.input = { builtin: { shape: "sphere", radius: 60, segments: 128 } };
  // 0.02 mm layers: 2.9M segments, about 6 s on 2 threads natively; a big job, asked about
  // first (at 0.05 mm it was not asked about once the estimates counted threads, and it could
  // end while the test waited for a question).
  long.job.slice.layer_height_mm = 0.02;
  await dropFile(p, "long.json", Buffer.from(JSON.stringify(long)), "application/json");
  await p.waitForFunction(() => JSON.parse(window.weft.design).name === "long-sphere", null, { timeout: JOB_TIMEOUT })
    .catch(async () => { throw new Error(`the long design was not accepted: ${await p.textContent("#error-text")}`); });
  const gen = await p.evaluate(() => window.weft.workerGeneration);
  const before = await p.evaluate(() => window.weft.resultCount);
  const t0 = Date.now();
  // The page answers "Run anyway" itself whenever it asks (no wait of the test's to race).
  await confirmBigJobs(p);
  await p.click("#slice");
  // Cancel once the worker reports progress inside the slicing stage: the job is computing.
  const running = await p.waitForFunction((k) => {
    if (!document.getElementById("progress").hidden && document.getElementById("progress-label").dataset.stage === "slice") return "running";
    const err = document.getElementById("error");
    if (window.weft.resultCount > k || (!err.hidden && !window.weft.busy)) return "ended";
    return false;
  }, before, { timeout: JOB_TIMEOUT, polling: 20 }).then((h) => h.jsonValue()).catch(() => "timed out");
  if (running !== "running") {
    const count = await p.evaluate(() => window.weft.resultCount);
    const error = await p.evaluate(() => (document.getElementById("error").hidden ? "" : document.getElementById("error-text").textContent));
    throw new Error(`no progress of the slicing stage: the long job ${count > before ? `finished in ${Date.now() - t0} ms` : error ? `failed: ${error}` : "did not start"}; nothing to cancel`);
  }
  const old = p.workers();
  const closed = Promise.all(old.map((w) => new Promise((r) => w.once("close", r))));
  // From the moment Cancel has been handled (a listener after the page's own), anything the
  // page shows of a run is recorded: the cancelled worker may report nothing more.
  await watchAfterCancel(p);
  const t1 = Date.now();
  await p.click("#cancel");
  await p.waitForSelector("#progress", { state: "hidden", timeout: 10000 });
  // Every worker of the run ends (Chromium ends a busy one 2 s after terminate() at the
  // latest; the bound only keeps a broken run from hanging, and allows for a loaded machine).
  if (!await Promise.race([closed.then(() => true), new Promise((r) => setTimeout(() => r(false), 60000))])) {
    throw new Error(`not every one of the run's ${old.length} workers ended within 60 s of Cancel`);
  }
  const endedMs = Date.now() - t1;
  const after = await p.evaluate(() => {
    window.__stopWatch?.();
    return { gen: window.weft.workerGeneration, busy: window.weft.busy, count: window.weft.resultCount, shown: window.__afterCancel };
  });
  if (after.shown === null) throw new Error("the Cancel click never reached the page");
  if (after.shown.length) throw new Error(`after Cancel the page still showed the cancelled run: ${[...new Set(after.shown)].join(", ")}`);
  if (after.gen !== gen + 1) throw new Error(`worker generation ${gen} → ${after.gen}; expected a restart`);
  if (after.busy) throw new Error("still busy after Cancel");
  if (after.count !== before) throw new Error("the cancelled job delivered a result");
  await dropFile(p, "short.json", Buffer.from(short), "application/json");
  await p.waitForFunction((s) => window.weft.design === s, short, { timeout: JOB_TIMEOUT });
  const t2 = Date.now();
  await p.click("#slice");
  await waitResult(p, after.count, "short run after Cancel");
  const count = await p.evaluate(() => window.weft.resultCount);
  if (count !== after.count + 1) throw new Error("the cancelled job delivered a result");
  if (errors.length) throw new Error(`console errors:\n${errors.join("\n")}`);
  return `cancelled ${((t1 - t0) / 1000).toFixed(1)} s after Run; its ${old.length} workers ended ${(endedMs / 1000).toFixed(1)} s after Cancel, nothing shown after; short run took ${((Date.now() - t2) / 1000).toFixed(1)} s`;
}));

await check(8, "input slots: one drop zone per schema slot for every job kind (labels, extensions)", () => inFreshPage("/www/", async (p, errors) => {
  const kinds = await p.evaluate(() => window.weft.schema.job_kinds.map((k) => ({
    name: k.name, slots: k.slots.map((s) => ({ name: s.name, label: s.label, accept: s.accept, multiple: Boolean(s.multiple) })),
  })));
  if (!kinds.some((k) => k.name === "slice") || !kinds.some((k) => k.name === "lattice")) {
    throw new Error(`schema job kinds: ${kinds.map((k) => k.name).join(", ")}`);
  }
  const seen = [];
  for (const kind of kinds) {
    const problem = await p.evaluate((k) => {
      const sel = document.getElementById("f-job-kind");
      if (!sel) return "no job selector (#f-job-kind)";
      sel.value = JSON.stringify(k);
      sel.dispatchEvent(new Event("change"));
      return JSON.parse(window.weft.design).job.kind === k ? null : `the job kind did not change to ${k}`;
    }, kind.name);
    if (problem) throw new Error(problem);
    const zones = await p.$$eval("#slots .slot", (els) => els.map((el) => ({
      name: el.dataset.slot, label: el.querySelector(".slot-label")?.textContent ?? "",
      accept: el.querySelector("input[type=file]")?.accept ?? "", multiple: el.querySelector("input[type=file]")?.multiple ?? false,
    })));
    const want = kind.slots.map((s) => ({ name: s.name, label: s.label, accept: s.accept.join(","), multiple: s.multiple }));
    if (JSON.stringify(zones) !== JSON.stringify(want)) {
      throw new Error(`${kind.name}: drop zones ${JSON.stringify(zones)}, schema slots ${JSON.stringify(want)}`);
    }
    seen.push(`${kind.name}: ${zones.map((z) => z.name).join("+") || "none"}`);
  }
  if (errors.length) throw new Error(`console errors:\n${errors.join("\n")}`);
  return seen.join("; ");
}));

await check(9, "temperature change → re-run reuses every stage before gcode; G-code differs only in temperature lines", async () => {
  // A baseline run of the design as it is now.
  let before = await page.evaluate(() => window.weft.resultCount);
  await page.click("#slice");
  await waitResult(page, before, "baseline run");
  const a = await download(page, "temp-a.gcode");
  const field = "#f-material-nozzle_temp_c";
  if (!(await page.$(field))) throw new Error(`no ${field} in the form`);
  await page.click("#machine > summary"); // the machine's settings are folded under the job's
  const old = Number(await page.inputValue(field));
  await page.fill(field, String(old + 7));
  await page.dispatchEvent(field, "change");
  const temp = await page.evaluate(() => JSON.parse(window.weft.design).material.nozzle_temp_c);
  if (temp !== old + 7) throw new Error(`the design's nozzle temperature is ${temp}, expected ${old + 7}`);
  before = await page.evaluate(() => window.weft.resultCount);
  await page.click("#slice");
  await waitResult(page, before, "re-run after the temperature change");
  // The stages that run before the G-code writer, in the job kind's order (the report may
  // leave out the writer's own stages).
  const { stages: all, order } = await page.evaluate(() => {
    const d = JSON.parse(window.weft.design);
    const kind = window.weft.schema.job_kinds.find((k) => k.name === d.job.kind);
    return {
      stages: window.weft.result.report.stages.map((s) => ({ stage: s.stage, cached: s.cached })),
      order: kind.stages.map((s) => s.name),
    };
  });
  const writer = order.indexOf("gcode");
  const stages = all.filter((s) => order.indexOf(s.stage) >= 0 && (writer < 0 || order.indexOf(s.stage) < writer));
  if (!stages.length) throw new Error(`no stages before gcode in the report: ${JSON.stringify(all)} (job stages ${order.join(", ")})`);
  const recomputed = stages.filter((s) => !s.cached).map((s) => s.stage);
  if (recomputed.length) throw new Error(`recomputed although only the temperature changed: ${recomputed.join(", ")} (${JSON.stringify(stages)})`);
  const cards = await page.evaluate(() => window.weft.reportCards);
  const badges = cards.filter((c) => c.cached).map((c) => c.stage);
  const shouldShow = stages.map((s) => s.stage).filter((st) => cards.some((c) => c.stage === st));
  if (shouldShow.some((st) => !badges.includes(st))) throw new Error(`cards without the reused badge: ${JSON.stringify(cards)}`);
  // The worker marks each stage of the run in its performance timeline, a reused one as such
  // (DevTools shows the marks; threads-bench places its stages by them).
  const marks = (await stageMarks(page)).map((m) => m.name);
  const ends = marks.flatMap((n, k) => (n === null ? [k] : []));
  const runMarks = marks.slice((ends.at(-2) ?? -1) + 1, ends.at(-1));
  const timings = await page.evaluate(() => window.weft.result.report.timings);
  const expected = timings.map((t) => `${t.stage}${t.cached ? " (reused)" : ""}`);
  if (JSON.stringify(runMarks) !== JSON.stringify(expected)) throw new Error(`the worker's stage marks ${JSON.stringify(runMarks)} are not the run's timings ${JSON.stringify(expected)}`);
  const b = await download(page, "temp-b.gcode");
  const la = a.bytes.toString("utf8").split("\n");
  const lb = b.bytes.toString("utf8").split("\n");
  if (la.length !== lb.length) throw new Error(`line count ${la.length} → ${lb.length}`);
  const diff = [];
  for (let i = 0; i < la.length; i++) if (la[i] !== lb[i]) diff.push([la[i], lb[i]]);
  if (!diff.length) throw new Error("the G-code did not change");
  const other = diff.filter(([x, y]) => !(/^M10[49]\b/.test(x) && /^M10[49]\b/.test(y)) && !/temp/i.test(x + y));
  if (other.length) throw new Error(`non-temperature lines differ: ${JSON.stringify(other.slice(0, 3))}`);
  return `${stages.map((s) => s.stage).join(", ")} reused; ${diff.length} line(s) differ, e.g. ${diff[0][1]}`;
});

await check(10, "print-order slider hides later moves (fewer segments drawn); the full range draws them all again", async () => {
  const r = await page.evaluate(async () => {
    const el = document.getElementById("move-max");
    const wrap = el.closest("[data-moves]");
    if (!wrap || wrap.hidden || el.disabled) return { error: "the print-order slider is hidden or disabled" };
    const all = window.weft.preview.drawn.extrusion;
    el.value = String(Math.floor(Number(el.max) / 3));
    el.dispatchEvent(new Event("input"));
    const part = window.weft.preview.drawn.extrusion;
    const label = document.getElementById("move-label").textContent;
    el.value = el.max;
    el.dispatchEvent(new Event("input"));
    return { all, part, back: window.weft.preview.drawn.extrusion, label, max: Number(el.max) };
  });
  if (r.error) throw new Error(r.error);
  if (!(r.part < r.all) || !(r.part > 0)) throw new Error(`segments drawn: all ${r.all}, at a third of the moves ${r.part}`);
  if (r.back !== r.all) throw new Error(`back to the last move draws ${r.back}, not ${r.all}`);
  const axis = await page.$eval("#show-axis", (el) => el.closest("label").hidden);
  if (!axis) throw new Error("the tool-axis toggle shows for a planar print with no tool axis");
  return `${r.all} → ${r.part} segments at "${r.label}" (${r.max + 1} moves)`;
});

await latticeChecks({ browser, baseUrl: base, weftBin: WEFT_BIN, check, newPage, outDir: OUT, first: 11 });

await check(16, "every example run in Chromium gives the G-code recorded in tests/golden/gcode.sha256 (the native golden test's bytes)", async () => {
  const golden = new Map(readFileSync(join(ROOT, "tests/golden/gcode.sha256"), "utf8").trim().split("\n")
    .map((l) => l.split(/\s+/)).map(([h, n]) => [n.replace(/\.gcode$/, ""), h]));
  const { page: p, context } = await newPage();
  // Each example is also kept as a screenshot at 1280 × 800 (tests/e2e/out/examples/), to look at.
  await p.setViewportSize({ width: 1280, height: 800 });
  mkdirSync(join(OUT, "examples"), { recursive: true });
  await p.goto(`${base}/www/`);
  await waitReady(p);
  await p.waitForFunction(() => document.querySelectorAll("#examples option[value]:not([value=''])").length > 0);
  const files = await p.$$eval("#examples option", (os) => os.map((o) => o.value).filter(Boolean));
  const wrong = [];
  for (const file of files) {
    const name = file.replace(/\.json$/, "");
    if (!golden.has(name)) throw new Error(`${file} has no recorded G-code hash`);
    const before = await p.evaluate(() => window.weft.resultCount);
    await p.selectOption("#examples", file);
    await p.waitForFunction((n) => window.weft.resultCount > n && !window.weft.busy, before, { timeout: 120000 });
    const hash = await p.evaluate(async () => {
      const d = await crypto.subtle.digest("SHA-256", window.weft.result.gcode);
      return [...new Uint8Array(d)].map((b) => b.toString(16).padStart(2, "0")).join("");
    });
    if (hash !== golden.get(name)) wrong.push(`${name}: ${hash.slice(0, 12)}… ≠ ${golden.get(name).slice(0, 12)}…`);
    await p.screenshot({ path: join(OUT, "examples", `${name}.png`) });
  }
  await context.close();
  if (wrong.length) throw new Error(wrong.join("; "));
  return `${files.length} examples byte-identical to the native golden hashes`;
});

await check(17, "hostile share links: a name of HTML stays text and runs nothing; a big job opens without running (Run anyway asks); one over a budget is refused before running", async () => {
  const design = JSON.parse(cli(["new"]));
  design.name = "<img src=x onerror=alert(1)>";
  design.job.input = { builtin: { shape: "cube", size: [200, 200, 200] } };
  // 0.02 mm layers: 2.7M segments, 77 MiB of G-code (over the soft thresholds, in the budgets).
  design.job.slice.layer_height_mm = 0.02;
  design.job.slice.first_layer_height_mm = 0.02;
  const bigPath = join(OUT, "hostile-big.json");
  writeFileSync(bigPath, JSON.stringify(design));
  const big = cli(["share", bigPath]).trim();
  design.job.slice.layer_height_mm = 0.01;
  design.job.slice.first_layer_height_mm = 0.01;
  design.job.slice.infill_density = 1;
  writeFileSync(bigPath, JSON.stringify(design));
  const huge = cli(["share", bigPath]).trim();
  const seen = [];
  const { page: p, context, errors } = await newPage();
  try {
    p.on("dialog", (d) => { seen.push(d.message()); d.dismiss().catch(() => {}); });
    await p.goto(`${base}/www/${big.slice(big.indexOf("#"))}`);
    await waitReady(p);
    await p.waitForSelector("#notice:not([hidden]) .notice-action", { timeout: 20000 });
    const notice = await p.textContent("#notice-text");
    if (!/without running/.test(notice)) throw new Error(`unclear notice: ${notice}`);
    const state = await p.evaluate(() => ({
      name: JSON.parse(window.weft.design).name, count: window.weft.resultCount, busy: window.weft.busy,
      imgs: document.querySelectorAll("img:not(#gallery img)").length, shown: document.querySelector("#name, [data-path='name']")?.value ?? null,
    }));
    if (state.name !== design.name) throw new Error(`the name was changed to ${state.name}`);
    if (state.count !== 0 || state.busy) throw new Error("the big shared design ran by itself");
    if (state.imgs) throw new Error(`${state.imgs} <img> elements appeared: a name became HTML`);
    await p.goto(`${base}/www/${huge.slice(huge.indexOf("#"))}`);
    await waitReady(p);
    await p.waitForSelector("#error:not([hidden])", { timeout: 20000 });
    const error = await p.textContent("#error-text");
    if (!/limit/.test(error) || !/Nothing was run/.test(error)) throw new Error(`unclear refusal: ${error}`);
    if (await p.evaluate(() => window.weft.resultCount)) throw new Error("the design over the budget ran");
    if (await p.evaluate(() => document.querySelectorAll("img:not(#gallery img)").length)) throw new Error("a name became HTML");
    if (seen.length) throw new Error(`a script ran: dialog "${seen[0]}"`);
    if (errors.length) throw new Error(`console errors:\n${errors.join("\n")}`);
    return `asked: "${notice.slice(0, 80)}…"; refused: "${error.split("\n")[0].slice(0, 100)}"`;
  } finally {
    await context.close();
  }
});

const next = await previewChecks({ baseUrl: base, check, newPage, first: 18, timeoutMs: JOB_TIMEOUT });
const afterNewcomer = await newcomerChecks({ base, check, newPage, outDir: OUT, first: typeof next === "number" ? next : 23, cube });
const afterAxisym = await axisymChecks({ baseUrl: base, weftBin: WEFT_BIN, check, newPage, outDir: OUT, first: typeof afterNewcomer === "number" ? afterNewcomer : 32, timeoutMs: JOB_TIMEOUT });
const afterGraded = await gradedChecks({ baseUrl: base, weftBin: WEFT_BIN, check, newPage, outDir: OUT, first: typeof afterAxisym === "number" ? afterAxisym : 36, timeoutMs: JOB_TIMEOUT });
const afterFoam = await foamChecks({ baseUrl: base, weftBin: WEFT_BIN, check, newPage, outDir: OUT, first: typeof afterGraded === "number" ? afterGraded : 39, timeoutMs: JOB_TIMEOUT });
const afterFreeform = await freeformChecks({ baseUrl: base, weftBin: WEFT_BIN, check, newPage, outDir: OUT, first: typeof afterFoam === "number" ? afterFoam : 42, timeoutMs: JOB_TIMEOUT });
await threadsChecks({ browser, baseUrl: base, weftBin: WEFT_BIN, check, outDir: OUT, first: typeof afterFreeform === "number" ? afterFreeform : 47, timeoutMs: JOB_TIMEOUT });

await check(53, "an open part (a box without one wall) is capped out loud: the file's line and the import card say which hole was capped, and the G-code is the CLI's and the closed box's (desktop and phone)", async () => {
  const open = boxStl([0, 0, 0], [20, 12, 8], "weft e2e open box", [2]);
  const closed = boxStl([0, 0, 0], [20, 12, 8], "weft e2e open box");
  const openPath = join(OUT, "open-box.stl");
  const closedPath = join(OUT, "closed-box.stl");
  writeFileSync(openPath, open);
  writeFileSync(closedPath, closed);
  const said = [];
  for (const viewport of [{ width: 1280, height: 800 }, { width: 390, height: 844 }]) {
    const { context, page: p } = await newPage();
    try {
      await p.setViewportSize(viewport);
      await p.goto(`${base}/www/`);
      await waitReady(p);
      const before = await p.evaluate(() => window.weft.resultCount);
      await p.setInputFiles("#file", { name: "open-box.stl", mimeType: "model/stl", buffer: open });
      await waitResultWithin(p, before, "slicing open-box.stl", JOB_TIMEOUT);
      const line = await p.$eval("#slots .file-summary", (e) => e.textContent);
      if (!/capped 1 flat hole of 4 edges, 160\.0 mm²/.test(line)) throw new Error(`the file's line does not say the hole was capped: ${line}`);
      const card = await p.$eval('.stage-card[data-stage="import"] .stage-notes', (e) => e.textContent).catch(() => "");
      if (!card.includes("capped 1 flat hole")) throw new Error(`the import card does not say it: "${card}"`);
      await p.$eval('.stage-card[data-stage="import"]', (e) => e.scrollIntoView());
      await p.screenshot({ path: join(OUT, `open-part-${viewport.width}.png`) });
      const web = await downloadGcode(p, join(OUT, `open-box-${viewport.width}.gcode`));
      const designPath = join(OUT, "open-box.json");
      writeFileSync(designPath, await p.evaluate(() => window.weft.design));
      const fromCli = join(OUT, "open-box-cli.gcode");
      const stderr = cli(["run", designPath, "--input", openPath, "--out", fromCli, "-q"]);
      const closedCli = join(OUT, "closed-box-cli.gcode");
      cli(["run", designPath, "--input", `mesh=${closedPath}`, "--out", closedCli, "-q"]);
      if (!web.bytes.equals(readFileSync(fromCli))) throw new Error(`the page's G-code differs from the CLI's for the same file ${stderr}`);
      if (!readFileSync(fromCli).equals(readFileSync(closedCli))) throw new Error("the capped box prints other G-code than the closed box");
      said.push(`${viewport.width}px: ${card.slice(0, 60)}…`);
    } finally {
      await context.close();
    }
  }
  return said.join("; ");
});

// Send to real print hosts (tests/hosts/hosts.py, started by scripts/test.sh: WEFT_HOSTS).
const afterSend = await sendChecks({ browser, baseUrl: base, hosts: hostsFromEnv(), check, outDir: OUT, first: 54, weftBin: existsSync(WEFT_BIN) ? WEFT_BIN : null });

// Supports switched on in the form for a dropped part (issue 44).
await supportChecks({ newPage, weftBin: existsSync(WEFT_BIN) ? WEFT_BIN : null, check, outDir: OUT, base, first: afterSend, timeoutMs: JOB_TIMEOUT });

// Teaching: "How it works" for every kind, the embedded weft driven by postMessage (issue 45).
await stepsChecks({ browser, newPage, weftBin: WEFT_BIN, check, outDir: OUT, base, first: afterSend + 1, timeoutMs: JOB_TIMEOUT });
// Pictures for slides (PNG/SVG of every view, plot and the preview) and comparing two results.
await picturesChecks({ newPage, weftBin: WEFT_BIN, check, outDir: OUT, base, first: afterSend + 3, timeoutMs: JOB_TIMEOUT });

if (main.errors.length) console.log(`note: console errors in the main page:\n  ${main.errors.join("\n  ")}`);
if (offOrigin.length) console.log(`note: blocked requests leaving the origin:\n  ${[...new Set(offOrigin)].join("\n  ")}`);
await browser.close();
server.close();
const passed = results.filter(Boolean).length;
const failed = results.length - passed;
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);

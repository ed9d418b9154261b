// Page helpers shared by the end-to-end checks (run.mjs, lattice-checks.mjs, ui-mock.mjs).
import { execFileSync, spawn } from "node:child_process";
import { readFileSync, rmSync } from "node:fs";
import { chromium } from "playwright-core";

/**
 * The system Chromium (CHROMIUM, default /usr/bin/chromium), headless unless E2E_HEADED=1,
 * with a software WebGL (SwiftShader) and a software compositor. The compositor flag matters on
 * a small machine: composited by SwiftShader's GL, every page frame (a progress label's
 * change) cost the GPU process about 80 ms of CPU at 1280×800, a whole core at 10 frames a
 * second taken from the worker's threads; the software compositor redraws only what changed,
 * as Chromium does on a machine without a usable GPU. `extraArgs` are added (bench.mjs: V8's
 * heap limit).
 */
export function launchChromium(extraArgs = []) {
  const headed = Boolean(process.env.E2E_HEADED);
  return chromium.launch({
    executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
    headless: !headed,
    args: [
      "--headless", "--no-sandbox", "--disable-background-networking", "--disable-component-update",
      "--disable-sync", "--disable-gpu-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
      "--disable-gpu-compositing",
      ...extraArgs,
    ].filter((a) => !(headed && a === "--headless")),
  });
}

/** Console errors and uncaught exceptions of `page`, collected from now on. */
export function collectErrors(page) {
  const errors = [];
  page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });
  page.on("pageerror", (e) => errors.push(`uncaught: ${e.message}`));
  return errors;
}

/**
 * Waits until the page has initialised, holds a design, and has finished what it does by
 * itself on opening (a first visit runs the default part).
 */
export async function waitReady(page) {
  await page.waitForFunction(() => window.weft && window.weft.design && !window.weft.busy, null, { timeout: 60000 });
}

/**
 * Types `value` into the form field `selector` and waits until the design holds it (`holds`
 * runs in the page on the parsed design). The form may be drawn again while a dropped file is
 * read, which loses an edit made on the old field, so the edit is made again until it holds.
 */
export async function setFieldUntil(page, selector, value, holds, what) {
  for (let attempt = 0; attempt < 6; attempt++) {
    await page.waitForSelector(selector, { state: "attached", timeout: 10000 });
    await page.evaluate((sel) => document.querySelector(sel)?.closest("details")?.setAttribute("open", ""), selector);
    await page.fill(selector, value);
    await page.dispatchEvent(selector, "change");
    const ok = await page
      .waitForFunction(`(${holds.toString()})(JSON.parse(window.weft.design))`, null, { timeout: 2000, polling: 50 })
      .then(() => true, () => false);
    if (ok) return;
  }
  throw new Error(`${what}: the design never took ${value} from ${selector}`);
}

/** Waits for the page to show one more result than `before`; fails on a visible error. */
export async function waitResult(page, before, what, timeout) {
  const handle = await page.waitForFunction(
    (n) => {
      if (window.weft.resultCount > n) return "ok";
      const err = document.getElementById("error");
      if (!err.hidden && !window.weft.busy) return `error: ${document.getElementById("error-text").textContent.trim()}`;
      return false;
    },
    before,
    { timeout, polling: 100 },
  ).catch(() => null);
  const state = handle ? await handle.jsonValue() : `no result within ${timeout / 1000} s`;
  if (state !== "ok") throw new Error(`${what}: ${state}`);
}

/** Pixels of the preview canvas that are toolpath-coloured (saturated), read after a frame. */
export async function colouredPixels(page) {
  return page.evaluate(async () => {
    await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
    const src = document.getElementById("preview");
    const c = document.createElement("canvas");
    c.width = src.width;
    c.height = src.height;
    const ctx = c.getContext("2d");
    ctx.drawImage(src, 0, 0);
    const d = ctx.getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) {
      const max = Math.max(d[i], d[i + 1], d[i + 2]);
      const min = Math.min(d[i], d[i + 1], d[i + 2]);
      if (max - min > 60 && max > 90) n++;
    }
    return n;
  });
}

/** Clicks "Download G-code" and saves the file to `path`. */
export async function downloadGcode(page, path) {
  if (await page.isDisabled("#download")) throw new Error("Download G-code is disabled: there is no result to download");
  const [dl] = await Promise.all([page.waitForEvent("download", { timeout: 30000 }), page.click("#download")]);
  await dl.saveAs(path);
  return { path, name: dl.suggestedFilename(), bytes: readFileSync(path) };
}

/**
 * Opens the page at `baseUrl`, picks `file` from the Examples menu and waits for its result;
 * returns the run report.
 */
export async function runExample(page, baseUrl, file, timeout, { confirm = false } = {}) {
  await page.goto(`${baseUrl}/www/`);
  await waitReady(page);
  // An example over the soft thresholds on this machine's threads is asked about first.
  if (confirm) await confirmBigJobs(page);
  await page.waitForSelector(`#examples option[value="${file}"]`, { state: "attached", timeout: 10000 }).catch(() => {});
  const before = await page.evaluate(() => window.weft.resultCount);
  await page.selectOption("#examples", file);
  await waitResult(page, before, `running ${file}`, timeout);
  return page.evaluate(() => window.weft.result?.report ?? null);
}

/** A binary STL of the axis-aligned box from corner `a` to corner `b` (mm), facing out, with normals. */
export function boxStl(a, b, header = "weft e2e box", omitFaces = []) {
  const v = (i) => [(i & 1 ? b : a)[0], (i & 2 ? b : a)[1], (i & 4 ? b : a)[2]];
  // Two triangles per face, counter-clockwise seen from outside (faces: bottom, top, y = a,
  // y = b, x = a, x = b; those in `omitFaces` are left out: an open box).
  const faces = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]].filter((_, k) => !omitFaces.includes(k));
  const tris = faces.flatMap(([p, q, r, s]) => [[p, q, r], [p, r, s]]);
  const buf = Buffer.alloc(84 + 50 * tris.length);
  buf.write(header, 0);
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

/**
 * From now on the page clicks "Run anyway" itself the moment a big job's ask shows (an
 * observer in the page: no polling from the test, which would load the page's main thread).
 */
export function confirmBigJobs(page) {
  return page.evaluate(() => {
    const notice = document.getElementById("notice");
    const answer = () => document.querySelector("#notice:not([hidden]) .notice-action")?.click();
    new MutationObserver(answer).observe(notice, { attributes: true, childList: true, subtree: true });
    answer();
  });
}

/**
 * Drops `file` (a path) on the page, or picks example `example` instead when `file` is null,
 * and waits for the result's first drawn frame (the benchmarks' timed unit). Returns the time
 * from the drop to that frame, the page's load marks ("load" → "loaded": reading a dropped
 * file before the run), the worker's run time and thread count, and the run report's stage
 * times (those not reused), ms.
 */
export async function dropAndTimeFirstFrame(page, file, example = null) {
  const before = await page.evaluate(() => {
    window.__t0 = null;
    const mark = () => { window.__t0 ??= performance.now(); };
    document.getElementById("file").addEventListener("change", mark, { capture: true, once: true });
    document.getElementById("examples").addEventListener("change", mark, { capture: true, once: true });
    return window.weft.resultCount;
  });
  await confirmBigJobs(page); // the times include no wait for the ask
  if (file) await page.setInputFiles("#file", file);
  else await page.selectOption("#examples", `${example}.json`);
  return page.waitForFunction((k) => {
    if (window.weft.resultCount <= k || window.weft.busy) return false;
    const f = window.weft.preview?.lastFrame;
    if (!f || f.segments === 0 || f.at < window.__t0) return false;
    const mark = (n) => performance.getEntriesByName(`weft:${n}`).filter((m) => m.startTime >= window.__t0 - 1)[0]?.startTime;
    const loadMs = mark("loaded") != null && mark("load") != null ? mark("loaded") - mark("load") : 0;
    return { frameMs: f.at - window.__t0, loadMs, ms: window.weft.result.ms, threads: window.weft.result.report.threads,
      stages: window.weft.result.report.timings.filter((t) => !t.cached).map((t) => ({ stage: t.stage, ms: t.ms })) };
  }, before, { timeout: 600000, polling: 20 }).then((h) => h.jsonValue());
}

/**
 * Starts sampling every core of the machine with Linux perf (`perf record -e cpu-clock -a`, as
 * root or with perf_event_paranoid ≤ 0) at `hz` a core, timestamps on `clock` ("CLOCK_REALTIME"
 * or "CLOCK_MONOTONIC"), into `path`. Resolves once sampling has begun to an object whose
 * `stop()` ends the recording, deletes `path` and resolves to every sample as
 * `{ comm, id, ms }`: the thread's name, its process id (`id: "pid"`) or thread id
 * (`id: "tid"`), and the time in milliseconds on `clock`.
 */
export async function recordCores(path, { hz, clock, id = "pid" }) {
  const perf = spawn("perf", ["record", "-q", "-e", "cpu-clock", "-F", String(hz), "-a", "-k", clock, "-o", path], { stdio: "ignore" });
  await new Promise((r) => setTimeout(r, 500)); // perf starts sampling
  return {
    async stop() {
      await new Promise((r) => { perf.on("exit", r); perf.kill("SIGINT"); });
      const text = execFileSync("perf", ["script", "-i", path, "-F", `comm,${id},time`], { encoding: "utf8", maxBuffer: 1 << 28, stdio: ["ignore", "pipe", "ignore"] });
      rmSync(path);
      const samples = [];
      for (const line of text.split("\n")) {
        const m = line.match(/^\s*(.*?)\s+(\d+)\s+([\d.]+):/);
        if (m) samples.push({ comm: m[1], id: m[2], ms: Number(m[3]) * 1000 });
      }
      return samples;
    },
  };
}

/**
 * The computing worker's stage marks (www/worker.js, `markStage`), oldest first:
 * `{ name, at }` with `name` the stage ("slice", "import (reused)") or null where the work
 * ended, and `at` in milliseconds since the epoch (performance.timeOrigin + the mark's time).
 */
export async function stageMarks(page) {
  const worker = page.workers().find((w) => /\/worker\.js/.test(w.url()));
  if (!worker) throw new Error("the page has no computing worker (www/worker.js)");
  return worker.evaluate(() => performance.getEntriesByType("mark")
    .filter((m) => m.name.startsWith("weft:stage"))
    .map((m) => ({ name: m.name === "weft:stage-end" ? null : m.name.slice("weft:stage:".length), at: performance.timeOrigin + m.startTime })));
}

/**
 * From the moment the page has handled a click on Cancel (a listener added after the page's
 * own), records every change to what shows a run: the progress bar, its label, the stats and
 * the report. `window.__stopWatch()` ends the recording; `window.__afterCancel` then lists the
 * changes (null: the click never reached the page).
 */
export async function watchAfterCancel(page) {
  await page.evaluate(() => {
    window.__afterCancel = null;
    document.getElementById("cancel").addEventListener("click", () => {
      window.__afterCancel = [];
      const seen = (ms) => { for (const m of ms) window.__afterCancel.push(`${m.target.id || m.target.parentElement?.closest("[id]")?.id}: ${m.type} ${m.attributeName ?? ""}`); };
      const watch = new MutationObserver(seen);
      for (const id of ["progress", "progress-label", "progress-bar", "progress-ahead", "stats", "report"]) {
        const el = document.getElementById(id);
        if (el) watch.observe(el, { attributes: true, childList: true, characterData: true, subtree: true });
      }
      window.__stopWatch = () => { seen(watch.takeRecords()); watch.disconnect(); };
    }, { once: true });
  });
}

/**
 * The checks' runner: `check(n, title, fn)` runs `fn`, prints `PASS n. title (detail) [s]` or
 * `FAIL n. title: message`, and records the outcome in `results` (true/false).
 */
export function checker() {
  const results = [];
  const check = async (n, title, fn) => {
    const t0 = Date.now();
    try {
      const detail = await fn();
      results.push(true);
      console.log(`PASS ${n}. ${title}${detail ? ` (${detail})` : ""} [${((Date.now() - t0) / 1000).toFixed(1)} s]`);
    } catch (err) {
      results.push(false);
      console.log(`FAIL ${n}. ${title}: ${err.message.split("\n").join("\n       ")}`);
    }
  };
  return { results, check };
}

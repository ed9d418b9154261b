#!/usr/bin/env node
// Browser benchmark: runs the `weft bench` workloads (src/bench.rs) inside a Web Worker in
// headless Debian Chromium (tests/e2e/bench-worker.js) and the native CLI's `weft bench`, and
// prints both side by side as Markdown. Not part of the test suite (timings depend on the
// machine); see BENCHMARKS.md and scripts/bench.sh.
//
//   node tests/e2e/bench.mjs
// Environment:
//   WEFT_BIN        native CLI (default ./target/release/weft; "" skips the native run)
//   CHROMIUM        browser executable (default /usr/bin/chromium)
//   WEFT_PKG_DIR    serve this directory as /pkg/ instead of ./pkg
//   BENCH_TRIANGLES triangles of the benchmark mesh (default 1000000)
//   BENCH_GCODE_MB  size of the analyzer workload, MB (default 100)
//   BENCH_TIMEOUT_S timeout of the browser job, s (default 900)
//   BENCH_LATTICE_ONLY=1  only the lattice path-optimisation benchmarks (`weft bench --lattice`)
//   BENCH_REPEATS   timed passes per lattice workload in the worker (default 3)
//   BENCH_DESIGNS   comma-separated design files: only time these designs stage by stage,
//                   in the worker (Session.run, fresh session per run, BENCH_REPEATS runs)
//                   and natively (`weft bench --design`), e.g. the axisymmetric examples
//   BENCH_PAIRING_ONLY=1  only the odd-node pairing benchmark (`weft bench --pairing`,
//                   src/bench/pairing.rs): heuristic vs exact per case, worker and native
//   BENCH_SCALING_ONLY=1  only the growth benchmark: every case of `weft bench --scaling`
//                   (src/bench/scaling.rs) at 1×, 4×, 16× in the worker (a fresh worker per
//                   case × scale; BENCH_REPEATS passes, best counts) and natively
//   BENCH_SCALING_CASES  comma-separated case names to run (default: all)
//   BENCH_CACHE_ONLY=1  only the stage-cache and big-input memory steps (`weft bench --cache`)
//   BENCH_CACHE=0   skip those steps in the full run
//   BENCH_BIG_TRIANGLES  triangles of the big-input memory step, tried in order until one
//                   works (default 4000000,3000000,2000000,1000000; 4M ≈ 200 MB of STL)
//   BENCH_GRADED_ONLY=1  only the graded job's benchmark (issue 11, src/bench/graded.rs): a
//                   182 × 197 × 107 DICOM series loaded and its surface extracted; a 50 MB
//                   G-code edited; each case in a fresh worker (BENCH_REPEATS passes, best
//                   counts), then natively (`weft bench --graded`)
//   BENCH_GRADED=0  skip the graded benchmark in the full run
import { execFileSync } from "node:child_process";
import { existsSync, readFileSync, writeFileSync } from "node:fs";
import { basename, join, resolve } from "node:path";
import { launchChromium } from "./page-helpers.mjs";
import { ROOT, serve } from "./server.mjs";

const WEFT_BIN = process.env.WEFT_BIN === "" ? null : resolve(ROOT, process.env.WEFT_BIN ?? "target/release/weft");
const PKG_DIR = process.env.WEFT_PKG_DIR ? resolve(process.env.WEFT_PKG_DIR) : join(ROOT, "pkg");
const TRIANGLES = Number(process.env.BENCH_TRIANGLES ?? 1_000_000);
const GCODE_MB = Number(process.env.BENCH_GCODE_MB ?? 100);
const TIMEOUT = Number(process.env.BENCH_TIMEOUT_S ?? 900) * 1000;
const LATTICE_ONLY = process.env.BENCH_LATTICE_ONLY === "1";
const REPEATS = Number(process.env.BENCH_REPEATS ?? 3);
const CACHE_ONLY = process.env.BENCH_CACHE_ONLY === "1";
const SCALING_ONLY = process.env.BENCH_SCALING_ONLY === "1";
const PAIRING_ONLY = process.env.BENCH_PAIRING_ONLY === "1";
const GRADED_ONLY = process.env.BENCH_GRADED_ONLY === "1";
const GRADED = GRADED_ONLY || process.env.BENCH_GRADED !== "0";
const DESIGNS = (process.env.BENCH_DESIGNS ?? "").split(",").map((s) => s.trim()).filter((s) => s !== "");
const SCALING_CASES = process.env.BENCH_SCALING_CASES ? process.env.BENCH_SCALING_CASES.split(",") : null;
const SCALES = [1, 4, 16]; // src/bench/scaling.rs SCALES
const CACHE = CACHE_ONLY || process.env.BENCH_CACHE !== "0";
const BIG_TRIANGLES = (process.env.BENCH_BIG_TRIANGLES ?? "4000000,3000000,2000000,1000000").split(",").map(Number);
const MB = 1e6;
const MiB = 1024 * 1024;

const log = (...a) => console.error("[bench]", ...a);
const f = (x, d = 3) => (x == null || Number.isNaN(x) ? "?" : x.toFixed(d));

/** VmHWM / VmRSS of a process, MiB (Linux). */
function procMem(pid) {
  try {
    const s = readFileSync(`/proc/${pid}/status`, "utf8");
    const kb = (k) => Number((s.match(new RegExp(`^${k}:\\s+(\\d+)`, "m")) ?? [])[1]) / 1024;
    return { hwm: kb("VmHWM"), rss: kb("VmRSS") };
  } catch {
    return null;
  }
}

/** Resets a process's peak RSS to its current RSS (Linux clear_refs 5); false if refused. */
function resetPeak(pid) {
  try {
    writeFileSync(`/proc/${pid}/clear_refs`, "5");
    return true;
  } catch {
    return false;
  }
}

// ---------------------------------------------------------------------------------------
// Native: `weft bench`
// ---------------------------------------------------------------------------------------
function runNative() {
  if (!WEFT_BIN) return null;
  if (!existsSync(WEFT_BIN)) throw new Error(`${WEFT_BIN} not found: cargo build --release (or set WEFT_BIN)`);
  const args = LATTICE_ONLY ? ["bench", "--lattice"] : ["bench", "--triangles", String(TRIANGLES), "--gcode-mb", String(GCODE_MB)];
  log(`native: ${WEFT_BIN} ${args.join(" ")}`);
  const text = execFileSync(WEFT_BIN, args, {
    cwd: ROOT, encoding: "utf8", maxBuffer: 1 << 24, timeout: TIMEOUT,
  });
  const stages = {};
  for (const m of text.matchAll(/^\| (\w+) \| ([\d.]+) \| ([\d.]+) \|$/gm)) stages[m[1]] = { plain: Number(m[2]), preview: Number(m[3]) };
  const total = text.match(/^\| \*\*total\*\* \| \*\*([\d.]+)\*\* \| \*\*([\d.]+)\*\* \|$/m);
  const analyze = text.match(/^## analyze: .*\*\*(\d+) MB\/s\*\*/m);
  const analyzePreview = text.match(/^## analyze with preview: .*\*\*(\d+) MB\/s\*\*/m);
  const lattice = {};
  for (const m of text.matchAll(/^\| ([\w-]+) \| (\w+) \| (\d+) \| (\d+) \| ([\d.]+) \| ([\d.]+) \| ([\d.]+) \| ([\d.]+) \|$/gm)) {
    lattice[m[1]] = { method: m[2], edges: Number(m[3]), paths: Number(m[4]), score: Number(m[5]), best: Number(m[6]), median: Number(m[7]) };
  }
  return {
    text,
    lattice,
    stages,
    total: total ? { plain: Number(total[1]), preview: Number(total[2]) } : null,
    analyzeMBs: analyze ? Number(analyze[1]) : null,
    analyzePreviewMBs: analyzePreview ? Number(analyzePreview[1]) : null,
  };
}

/** `weft bench --scaling`: { text, rows: { [case]: { unit, points: [{ size, s, mib }], t, m } } }.
 *  The command exits non-zero when an exponent is over 1.2; its table is read all the same. */
function runNativeScaling() {
  if (!WEFT_BIN) return null;
  log(`native: ${WEFT_BIN} bench --scaling`);
  let text;
  try {
    text = execFileSync(WEFT_BIN, ["bench", "--scaling"], { cwd: ROOT, encoding: "utf8", maxBuffer: 1 << 24, timeout: TIMEOUT * 4 });
  } catch (e) {
    if (!e.stdout) throw e;
    text = e.stdout + (e.stderr ? `\n${e.stderr}` : "");
  }
  const rows = {};
  const cell = String.raw`(\d+), ([\d.]+), ([\d.]+)`;
  const re = new RegExp(String.raw`^(\S+)\s+(.+?)\s+${cell}\s+${cell}\s+${cell}\s+(\S+)\s+(\S+)`, "gm");
  for (const m of text.matchAll(re)) {
    const points = [0, 1, 2].map((i) => ({ size: Number(m[3 + 3 * i]), s: Number(m[4 + 3 * i]), mib: Number(m[5 + 3 * i]) }));
    rows[m[1]] = { unit: m[2], points, t: Number(m[12]), m: Number(m[13]) };
  }
  return { text, rows };
}

/** Least-squares slope of log y over log x (src/bench/scaling.rs `exponent`), points with y > 0. */
function exponent(points) {
  const p = points.filter(([x, y]) => x > 0 && y > 0).map(([x, y]) => [Math.log(x), Math.log(y)]);
  if (p.length < 2) return NaN;
  const mx = p.reduce((a, q) => a + q[0], 0) / p.length;
  const my = p.reduce((a, q) => a + q[1], 0) / p.length;
  const sxx = p.reduce((a, q) => a + (q[0] - mx) ** 2, 0);
  const sxy = p.reduce((a, q) => a + (q[0] - mx) * (q[1] - my), 0);
  return sxy / sxx;
}

/** Every scaling case at every scale, each in a fresh worker (fresh wasm memory). */
async function scalingSteps(page) {
  const list = await inWorker(page, { cmd: "scaling-cases" });
  if (list.type !== "scaling-cases") throw new Error(`scaling cases: ${list.message}`);
  const names = SCALING_CASES ?? list.names;
  const rows = [];
  for (const name of names) {
    const points = [];
    for (const scale of SCALES) {
      log(`scaling: ${name} ×${scale} in a fresh worker`);
      const r = await inWorker(page, { cmd: "scaling", name, scale, repeats: REPEATS });
      if (r.type !== "scaling") throw new Error(`scaling ${name} ×${scale}: ${r.message}`);
      points.push(r);
    }
    rows.push({ name, unit: points[0].unit, points });
  }
  return rows;
}

function scalingReport(browserRun, native) {
  const out = [];
  const wide = (x) => (x == null || Number.isNaN(x) ? "?" : x.toFixed(2));
  const flag = (x) => (x > 1.2 ? ` ✗` : "");
  out.push(`## growth with input size: \`weft bench --scaling\` cases at 1×, 4×, 16×, worker and native`);
  out.push("");
  out.push(`Browser: Chromium ${browserRun.version}, module Web Worker, wasm (\`new BenchScaling(case, scale)\` prepares, untimed; \`run()\` timed with \`performance.now()\`, best of ${REPEATS}), a fresh worker per case × scale. ` +
    "Worker memory = wasm linear memory after the runs minus after init (`memory.buffer.byteLength`; it never shrinks, so this is the peak above the fresh module, prepared input included). " +
    "Native: `weft bench --scaling` (a child process per case × scale, best of 3, peak RSS above an idle process). Exponent = least-squares slope of log(time or memory) over log(size).");
  out.push("");
  out.push("| case | unit | sizes 1×, 4×, 16× | worker s 1×, 4×, 16× | **worker time exp.** | native s 1×, 4×, 16× | **native time exp.** | worker ÷ native at 16× | worker MiB 1×, 4×, 16× | **worker memory exp.** | native memory exp. |");
  out.push("|---|---|---|---|---|---|---|---|---|---|---|");
  const over = [];
  for (const r of browserRun.scaling) {
    const n = native?.rows?.[r.name];
    const best = r.points.map((p) => Math.min(...p.ms) / 1000);
    const mib = r.points.map((p) => (p.memory.run - p.memory.init) / MiB);
    const wt = exponent(r.points.map((p, i) => [p.size, best[i]]));
    const wm = exponent(r.points.map((p, i) => [p.size, mib[i]]));
    const sizes = r.points.map((p) => p.size);
    const same = !n || n.points.every((q, i) => Math.abs(q.size - sizes[i]) <= 0.5 + 1e-6 * sizes[i]) ? "" : " (native sizes differ!)";
    const ratio = n ? best[2] / n.points[2].s : NaN;
    if (wt > 1.2 || wm > 1.2) over.push(`worker ${r.name}`);
    if (n && (n.t > 1.2 || n.m > 1.2)) over.push(`native ${r.name}`);
    out.push(`| \`${r.name}\` | ${r.unit} | ${sizes.map((x) => x.toFixed(0)).join(", ")}${same} | ${best.map((x) => f(x)).join(", ")} | **${wide(wt)}**${flag(wt)} | ${n ? n.points.map((q) => f(q.s)).join(", ") : "?"} | **${wide(n?.t)}**${flag(n?.t)} | ${Number.isNaN(ratio) ? "?" : `${f(ratio, 2)}×`} | ${mib.map((x) => f(x, 1)).join(", ")} | **${wide(wm)}**${flag(wm)} | ${wide(n?.m)}${flag(n?.m)} |`);
  }
  out.push("");
  out.push(over.length ? `Over 1.2: ${over.join(", ")}.` : `Every exponent ≤ 1.2 (time and memory, worker${native ? " and native" : "; no native run"}).`);
  out.push("");
  out.push(`Worker passes (ms) and preparation (ms, untimed in the table): ${browserRun.scaling.map((r) => `${r.name} ${r.points.map((p) => `×${p.scale} [${p.ms.map((x) => f(x, 1)).join(", ")}] prep ${f(p.prepareMs, 0)}, wasm init ${f(p.memory.init / MiB, 1)} MiB`).join("; ")}`).join(" · ")}.`);
  out.push("");
  return out.join("\n");
}

/** `weft bench --cache`: rows { [workload]: { addFile, first, second, ratio, cached } }, s. */
function runNativeCache() {
  if (!WEFT_BIN || !CACHE) return null;
  const args = ["bench", "--cache", "--triangles", String(TRIANGLES)];
  log(`native: ${WEFT_BIN} ${args.join(" ")}`);
  const text = execFileSync(WEFT_BIN, args, { cwd: ROOT, encoding: "utf8", maxBuffer: 1 << 24, timeout: TIMEOUT });
  const rows = {};
  for (const m of text.matchAll(/^\| ([\w-]+) \| ([\d.]+|-) \| ([\d.]+) \| ([\d.]+) \| ([\d.]+) \| (.+) \|$/gm)) {
    rows[m[1].startsWith("mesh-") ? "mesh" : m[1]] = { addFile: m[2] === "-" ? null : Number(m[2]), first: Number(m[3]), second: Number(m[4]), cached: m[6] };
  }
  return { text, rows };
}

// ---------------------------------------------------------------------------------------
// Browser: the worker
// ---------------------------------------------------------------------------------------
async function runBrowser() {
  const server = await serve({ pkgDir: PKG_DIR });
  const browser = await launchChromium(["--js-flags=--max-old-space-size=4096"]);
  try {
    const version = browser.version();
    const context = await browser.newContext();
    const page = await context.newPage();
    const errors = [];
    page.on("pageerror", (e) => errors.push(e.message));
    page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });
    // A blank page of the server's origin (module workers must be same-origin), cross-origin
    // isolated (COOP + COEP on every response) so the worker may call
    // performance.measureUserAgentSpecificMemory (the big-input memory step).
    const isolation = {
      "cross-origin-opener-policy": "same-origin",
      "cross-origin-embedder-policy": "require-corp",
      "cross-origin-resource-policy": "same-origin",
    };
    await context.route(`${server.url}/**`, async (route) => {
      if (route.request().url() === `${server.url}/bench.html`) {
        return route.fulfill({ contentType: "text/html; charset=utf-8", headers: isolation, body: "<!doctype html><title>weft bench</title>" });
      }
      const response = await route.fetch();
      return route.fulfill({ response, headers: { ...response.headers(), ...isolation } });
    });
    await page.goto(`${server.url}/bench.html`);

    // Renderer processes (the worker runs in its page's renderer), for peak RSS.
    const cdp = await browser.newBrowserCDPSession();
    const renderers = async () => {
      try {
        const info = await cdp.send("SystemInfo.getProcessInfo");
        return info.processInfo.filter((p) => p.type === "renderer").map((p) => p.id);
      } catch {
        return [];
      }
    };

    if (CACHE_ONLY) return { version, ...(await cacheSteps(page, renderers)) };
    if (SCALING_ONLY) return { version, scaling: await scalingSteps(page) };
    if (PAIRING_ONLY) return { version, pairing: await workerStep(page, { cmd: "pairing" }, "pairing") };
    if (GRADED_ONLY) return { version, graded: await gradedSteps(page) };
    if (DESIGNS.length) {
      const designs = DESIGNS.map((file) => ({ name: basename(file, ".json"), json: readFileSync(resolve(ROOT, file), "utf8") }));
      return { version, designs: await workerStep(page, { cmd: "designs", designs, repeats: REPEATS }, "designs") };
    }

    // 0. Lattice path optimisation, in its own fresh worker.
    log(`browser ${version}: lattice path-optimisation workloads in a worker (${REPEATS} passes each)`);
    const lattice = await page.evaluate(async ({ repeats, timeout }) => {
      const w = new Worker("/tests/e2e/bench-worker.js", { type: "module" });
      try {
        return await new Promise((ok, fail) => {
          const timer = setTimeout(() => fail(new Error(`no lattice result within ${timeout / 1000} s`)), timeout);
          w.onmessage = ({ data }) => {
            clearTimeout(timer);
            if (data.type === "lattice") ok(data);
            else fail(new Error(data.message ?? JSON.stringify(data)));
          };
          w.onerror = (e) => { clearTimeout(timer); fail(new Error(e.message || "worker failed to start")); };
          w.postMessage({ cmd: "lattice", repeats });
        });
      } finally {
        w.terminate();
      }
    }, { repeats: REPEATS, timeout: TIMEOUT });
    if (LATTICE_ONLY) return { version, lattice };

    // 1. The STL, generated in a worker that is then terminated (not part of the job).
    log(`browser ${version}: generating the ${TRIANGLES}-triangle STL in a worker`);
    const gen = await page.evaluate(async (triangles) => {
      const w = new Worker("/tests/e2e/bench-worker.js", { type: "module" });
      const msg = await new Promise((ok, fail) => {
        w.onmessage = ({ data }) => ok(data);
        w.onerror = (e) => fail(new Error(e.message || "worker failed to start"));
        w.postMessage({ cmd: "stl", triangles });
      });
      w.terminate();
      if (msg.type !== "stl") throw new Error(msg.message ?? "no STL");
      window.__stl = msg.bytes;
      return { bytes: msg.bytes.byteLength, ms: msg.ms };
    }, TRIANGLES);

    // 2. The job, in a fresh worker (fresh wasm memory).
    const pids = await renderers();
    const peakReset = pids.length > 0 && pids.every(resetPeak);
    const before = Object.fromEntries(pids.map((p) => [p, procMem(p)]));
    log(`running the job in a fresh worker (renderer pids ${pids.join(", ") || "?"})`);
    const result = await page.evaluate(async ({ gcodeMb, timeout }) => {
      const w = new Worker("/tests/e2e/bench-worker.js", { type: "module" });
      const stl = window.__stl;
      window.__stl = null;
      try {
        return await new Promise((ok, fail) => {
          const timer = setTimeout(() => fail(new Error(`no result within ${timeout / 1000} s`)), timeout);
          w.onmessage = ({ data }) => {
            clearTimeout(timer);
            if (data.type === "result") ok(data);
            else fail(new Error(data.message ?? JSON.stringify(data)));
          };
          w.onerror = (e) => { clearTimeout(timer); fail(new Error(e.message || "worker error (out of memory?)")); };
          w.postMessage({ cmd: "run", stl, gcodeMb }, [stl]);
        });
      } finally {
        w.terminate();
      }
    }, { gcodeMb: GCODE_MB, timeout: TIMEOUT });
    const after = Object.fromEntries(pids.map((p) => [p, procMem(p)]));
    const rendererPeakMiB = Math.max(0, ...pids.map((p) => after[p]?.hwm ?? 0));
    const rendererBeforeMiB = Math.max(0, ...pids.map((p) => before[p]?.rss ?? 0));
    const cache = CACHE ? await cacheSteps(page, renderers) : {};
    const graded = GRADED ? await gradedSteps(page) : null;
    if (errors.length) log(`page errors: ${errors.join(" | ")}`);
    return { version, lattice, gen, result, rendererPeakMiB, rendererBeforeMiB, peakReset, ...cache, graded };
  } finally {
    await browser.close();
    await server.close();
  }
}

/** Runs `msg` in a worker that is then terminated (so making an input does not count in a
 *  timed worker's memory) and keeps its answer's `field` in the page as window[global];
 *  resolves with the rest of the answer and `size`, the kept ArrayBuffer's byteLength. */
async function keepInPage(page, msg, type, global, field) {
  return page.evaluate(async ({ msg, type, global, field }) => {
    const w = new Worker("/tests/e2e/bench-worker.js", { type: "module" });
    try {
      const data = await new Promise((ok, fail) => {
        w.onmessage = ({ data }) => ok(data);
        w.onerror = (e) => fail(new Error(e.message || "worker failed to start"));
        w.postMessage(msg);
      });
      if (data.type !== type) throw new Error(data.message ?? `no ${type}`);
      window[global] = data[field];
      const size = data[field]?.byteLength;
      delete data[field];
      return { ...data, size };
    } finally {
      w.terminate();
    }
  }, { msg, type, global, field });
}

/** Generates the benchmark STL in a worker that is then terminated; keeps it as window.__stl. */
async function genStl(page, triangles) {
  const r = await keepInPage(page, { cmd: "stl", triangles }, "stl", "__stl", "bytes");
  return { bytes: r.size, ms: r.ms };
}

/** Posts `msg` (with window.__stl as `stl`, transferred; with window[attach] as `inputs`,
 *  copied, so the page keeps it for the next worker) to a fresh worker; resolves with its
 *  answer, `{ type: "error", message }` included (a worker crash becomes one too). */
async function inWorker(page, msg, timeout = TIMEOUT, attach = null) {
  return page.evaluate(async ({ msg, timeout, attach }) => {
    const w = new Worker("/tests/e2e/bench-worker.js", { type: "module" });
    const stl = window.__stl;
    window.__stl = null;
    if (stl) msg.stl = stl;
    if (attach) msg.inputs = window[attach];
    try {
      return await new Promise((ok) => {
        const timer = setTimeout(() => ok({ type: "error", message: `no answer within ${timeout / 1000} s` }), timeout);
        w.onmessage = async ({ data }) => {
          if (data.type === "phase") {
            // The memory step's pauses: measure the agent cluster (page + worker) from here.
            let measured;
            if (!self.crossOriginIsolated) measured = "unavailable: not cross-origin isolated";
            else if (typeof performance.measureUserAgentSpecificMemory !== "function") measured = "unavailable: no such function";
            else {
              try {
                // Chromium answers at its next garbage collection (up to ~20 s); give up after 60 s.
                const late = new Promise((_, fail) => setTimeout(() => fail(new Error("no answer in 60 s")), 60_000));
                measured = (await Promise.race([performance.measureUserAgentSpecificMemory(), late])).bytes;
              } catch (e) {
                measured = `error: ${e.message}`;
              }
            }
            w.postMessage({ cmd: "continue", measured });
            return;
          }
          clearTimeout(timer);
          ok(data);
        };
        w.onerror = (e) => { clearTimeout(timer); ok({ type: "error", message: `worker error: ${e.message || "(no message: crashed or out of memory?)"}` }); };
        w.postMessage(msg, stl ? [stl] : []);
      });
    } finally {
      w.terminate();
    }
  }, { msg, timeout, attach });
}

/** The stage-cache step and the big-input memory step (each in fresh workers). */
async function cacheSteps(page, renderers) {
  const discJson = readFileSync(join(ROOT, "examples/ball-burst-disc-48mm.json"), "utf8");
  log(`cache: generating the ${TRIANGLES}-triangle STL, then full run + bed_temp_c +10 re-run (disc-48mm, mesh)`);
  const gen = await genStl(page, TRIANGLES);
  const cache = await inWorker(page, { cmd: "cache", discJson });
  if (cache.type !== "cache") throw new Error(`cache step: ${cache.message}`);
  cache.stlBytes = gen.bytes;
  const big = [];
  for (const triangles of BIG_TRIANGLES) {
    log(`memory: ${triangles} triangles: generating the STL`);
    let g;
    try {
      g = await genStl(page, triangles);
    } catch (e) {
      big.push({ triangles, type: "error", message: `STL generation: ${e.message}` });
      continue;
    }
    const pids = await renderers();
    const peakReset = pids.length > 0 && pids.every(resetPeak);
    log(`memory: ${triangles} triangles (${f(g.bytes / MB, 0)} MB): addFile + run in a fresh worker`);
    const r = await inWorker(page, { cmd: "memory" });
    const rendererPeakMiB = Math.max(0, ...pids.map((p) => procMem(p)?.hwm ?? 0));
    big.push({ triangles, stlBytes: g.bytes, rendererPeakMiB, peakReset, ...r });
    if (r.type === "memory") break;
    log(`memory: ${triangles} triangles failed: ${r.message}`);
  }
  return { cache, big };
}

function cacheReport(browserRun, nativeCache) {
  const out = [];
  const c = browserRun.cache;
  out.push(`## stage cache: full run, then a re-run after \`material.bed_temp_c\` +10 (edited in the design JSON)`);
  out.push("");
  out.push(`Browser: Chromium ${browserRun.version}, module Web Worker, one \`Session\` per workload (\`Session.run\`, preview on). Native: \`weft bench --cache\` (\`pipeline::run_in\` with one \`Cache\`, preview on). Mesh: ${TRIANGLES} triangles requested, ${f(c.stlBytes / MB, 1)} MB STL, \`addFile("mesh", "bench.stl", bytes)\` before the first run. Seconds.`);
  out.push("");
  out.push("| workload | | addFile | first run | re-run | re-run / first | stages before gcode cached on the re-run |");
  out.push("|---|---|---|---|---|---|---|");
  for (const r of c.rows) {
    const n = nativeCache?.rows?.[r.name];
    if (n) out.push(`| ${r.name} | native | ${n.addFile == null ? "-" : f(n.addFile)} | ${f(n.first)} | ${f(n.second)} | ${f(n.second / n.first, 3)} | ${n.cached} |`);
    const stages = r.stages.map((s) => `${s.stage}${s.cached ? " (cached)" : ""}`).join(", ");
    out.push(`| ${r.name} | worker | ${r.addFileMs == null ? "-" : f(r.addFileMs / 1000)} | ${f(r.firstMs / 1000)} | ${f(r.secondMs / 1000)} | ${f(r.secondMs / r.firstMs, 3)} | ${r.uncached.length ? `NOT: ${r.uncached.join(", ")}` : "all"} (${stages}) |`);
  }
  out.push("");
  out.push("## peak memory of a big input in the worker (`Session.addFile`, then `Session.run(benchDesign())`)");
  out.push("");
  out.push("wasm linear memory is `memory.buffer.byteLength` (it only grows: each value is the peak so far). × = multiple of the STL size.");
  out.push("");
  out.push("| triangles | STL MB | result | addFile s | run s | layers | wasm MiB after addFile | × | wasm MiB after run | × | measureUserAgentSpecificMemory | renderer peak RSS MiB |");
  out.push("|---|---|---|---|---|---|---|---|---|---|---|---|");
  for (const b of browserRun.big) {
    if (b.type === "memory") {
      const m = b.memory;
      const uaf = (x) => (typeof x === "number" ? `${f(x / MiB, 0)} MiB (${f(x / b.stlBytes, 2)}×)` : String(x));
      const ua = typeof b.uaMemory?.afterRun === "number" ? `after addFile ${uaf(b.uaMemory.afterAddFile)}, after run ${uaf(b.uaMemory.afterRun)}` : uaf(b.uaMemory?.afterRun);
      out.push(`| ${b.triangles} | ${f(b.stlBytes / MB, 1)} | ok | ${f(b.addFileMs / 1000)} | ${f(b.runMs / 1000)} | ${b.layers} | ${f(m.afterAddFile / MiB, 0)} | ${f(m.afterAddFile / b.stlBytes, 2)}× | ${f(m.afterRun / MiB, 0)} | ${f(m.afterRun / b.stlBytes, 2)}× | ${ua} | ${f(b.rendererPeakMiB, 0)}${b.peakReset ? "" : " (lifetime)"} |`);
    } else {
      const msg = String(b.message).split("\n")[0].replaceAll("|", "\\|");
      out.push(`| ${b.triangles} | ${f((b.stlBytes ?? 0) / MB, 1)} | **failed**: \`${msg}\` | | | | | | ${b.memory ? f(b.memory / MiB, 0) : "?"} (at failure) | | | ${f(b.rendererPeakMiB, 0)} |`);
    }
  }
  out.push("");
  return out.join("\n");
}

/** The graded job's two cases (src/bench/graded.rs), each in a fresh worker (fresh wasm
 *  memory, so each case's peak is its own); the inputs are made once in another worker. */
async function gradedSteps(page) {
  log("graded: making the series and the G-code in a worker (BenchGraded, not timed)");
  const gen = await keepInPage(page, { cmd: "graded-inputs" }, "graded-inputs", "__graded", "inputs");
  const info = await page.evaluate(() => {
    const g = window.__graded;
    return { files: g.files.length, seriesBytes: g.files.reduce((a, f) => a + f.bytes.byteLength, 0), gcodeBytes: g.gcode.bytes.byteLength, volumeBytes: g.volumeBytes };
  });
  const out = { genMs: gen.ms, ...info };
  for (const [key, cmd] of [["surface", "graded-surface"], ["edit", "graded-edit"]]) {
    log(`graded: ${cmd} in a fresh worker (${REPEATS} passes)`);
    const r = await inWorker(page, { cmd, repeats: REPEATS }, TIMEOUT, "__graded");
    if (r.type !== cmd) throw new Error(`${cmd}: ${r.message}`);
    out[key] = r;
  }
  await page.evaluate(() => { window.__graded = null; });
  return out;
}

/** `weft bench --graded`: { text, rows: { surface: { step: s }, edit: { step: s } }, peaks MB }. */
function runNativeGraded() {
  if (!WEFT_BIN) return null;
  log(`native: ${WEFT_BIN} bench --graded`);
  const text = execFileSync(WEFT_BIN, ["bench", "--graded"], { cwd: ROOT, encoding: "utf8", maxBuffer: 1 << 24, timeout: TIMEOUT });
  const rows = { surface: {}, edit: {} };
  for (const m of text.matchAll(/^\| (surface|edit) \| ([^|]+?) \| ([\d.]+) \|/gm)) rows[m[1]][m[2].replaceAll("**", "").replace(/ \(.*\)$/, "")] = Number(m[3]);
  const peaks = text.match(/surface ([\d.]+) MB, edit ([\d.]+) MB/);
  return { text, rows, peakMB: peaks ? { surface: Number(peaks[1]), edit: Number(peaks[2]) } : null, edited: Number(text.match(/edit: (\d+) moves edited/)?.[1]), triangles: Number(text.match(/surface: (\d+) triangles/)?.[1]) };
}

function gradedReport(browserRun, native) {
  const g = browserRun.graded;
  const n = native?.rows ?? { surface: {}, edit: {} };
  const out = [];
  const s = (ms) => f(ms / 1000);
  const ratio = (w, x) => (x ? `${f(w / 1000 / x, 2)}×` : "?");
  const met = (ok) => (ok ? "yes" : "**no**");
  out.push(`## CT-graded scaffolds (issue 11): load a 182 × 197 × 107 series and extract the surface; edit a 50 MB G-code`);
  out.push("");
  out.push(`Browser: Chromium ${browserRun.version}, module Web Worker, wasm; a fresh worker per case and a new \`Session\` per pass (best of ${REPEATS} passes by total; that pass's split shown). ` +
    `Inputs (src/bench/graded.rs, made by \`BenchGraded\` in a worker that is then terminated, ${f(g.genMs / 1000, 1)} s, and copied into each case's worker; not timed, not counted): ${g.files} DICOM files, ${f(g.seriesBytes / MB, 1)} MB (an f32 volume of ${f(g.volumeBytes / MB, 1)} MB); a PrusaSlicer-style G-code of ${f(g.gcodeBytes / MB, 1)} MB. ` +
    "Native: `weft bench --graded` (the same inputs through the same pipeline calls, best of 3). Seconds.");
  out.push("");
  out.push("| case | step | worker s | native s | worker ÷ native |");
  out.push("|---|---|---|---|---|");
  const sp = g.surface.passes;
  const sTotal = (p) => p.addFileMs + p.estimateMs + p.viewMs;
  const sb = sp.reduce((a, p) => (sTotal(p) < sTotal(a) ? p : a));
  const sRow = (label, ms, key, bold = "") => out.push(`| | ${label} | ${bold}${s(ms)}${bold} | ${bold}${f(n.surface[key])}${bold} | ${bold}${ratio(ms, n.surface[key])}${bold} |`);
  out.push(`| series → surface, as the page goes after a drop | \`addBlob("volume", path, blob)\` × ${g.files} | ${s(sb.addFileMs)} | ${f(n.surface.addFile)} | ${ratio(sb.addFileMs, n.surface.addFile)} |`);
  sRow("`estimate(design)` (runDesign asks it first: reads the volume, counts the surface's triangles, extracts it, estimates the slicing)", sb.estimateMs, "estimate");
  sRow(`surface view (\`inspect(design, "surface", 0)\`, from the cache: ${sb.triangles} triangles copied out${native?.triangles && native.triangles !== sb.triangles ? `; native ${native.triangles}!` : ""})`, sb.viewMs, "surface view");
  sRow("**addFile + estimate + view**", sTotal(sb), "addFile + estimate + view", "**");
  out.push(`| series → surface, the stages apart (a new Session) | volume stage (\`inspect(design, "axial", 0)\`) | ${s(sb.volumeMs)} | ${f(n.surface["volume stage"])} | ${ratio(sb.volumeMs, n.surface["volume stage"])} |`);
  sRow(`surface stage (\`inspect(design, "surface", 0)\`)`, sb.surfaceMs, "surface stage");
  n.surface.apart = n.surface.addFile + n.surface["volume stage"] + n.surface["surface stage"];
  sRow("addFile + volume + surface", sb.addFileMs2 + sb.volumeMs + sb.surfaceMs, "apart");
  const ep = g.edit.passes;
  const eTotal = (p) => p.addSeriesMs + p.addGcodeMs + p.runMs;
  const eb = ep.reduce((a, p) => (eTotal(p) < eTotal(a) ? p : a));
  const stage = (p, name) => p.stages.find((x) => x.stage === name)?.ms;
  out.push(`| edit | \`addBlob\`: series × ${g.files} + G-code (every line read in pieces, the part's box, as on the page) | ${s(eb.addSeriesMs + eb.addGcodeMs)} (G-code ${s(eb.addGcodeMs)}) | ${f(n.edit.addFile)} | ${ratio(eb.addSeriesMs + eb.addGcodeMs, n.edit.addFile)} |`);
  for (const st of eb.stages) {
    const label = st.stage === "volume" ? "volume (and the plan's surface estimate: classify, fill, count)" : st.stage === "edit" ? `**edit stage** (${eb.edited} moves edited${native?.edited && native.edited !== eb.edited ? `; native ${native.edited}!` : ""})` : st.stage === "analyze" ? "analyze (with preview, as Session.run)" : st.stage;
    const bold = st.stage === "edit" ? "**" : "";
    out.push(`| | ${label} | ${bold}${s(st.ms)}${bold} | ${bold}${f(n.edit[st.stage])}${bold} | ${ratio(st.ms, n.edit[st.stage])} |`);
  }
  out.push(`| | **Session.run** (all stages) | **${s(eb.runMs)}** | **${f(n.edit.run)}** | **${ratio(eb.runMs, n.edit.run)}** |`);
  out.push(`| | **addFile + run** | **${s(eTotal(eb))}** | **${f(n.edit["addFile + run"])}** | **${ratio(eTotal(eb), n.edit["addFile + run"])}** |`);
  out.push("");
  const editMs = stage(eb, "edit");
  out.push(`Targets (worker): load + surface ${s(sTotal(sb))} s < 3 s (addFile + estimate + view): ${met(sTotal(sb) < 3000)}; edit ${s(editMs)} s < 3 s: ${met(editMs < 3000)} (the whole run with its analysis ${s(eb.runMs)} s, with the G-code's addFile ${s(eTotal(eb))} s). ` +
    `Worker passes (s): surface ${sp.map((p) => s(sTotal(p))).join(", ")}; edit stage ${ep.map((p) => s(stage(p, "edit"))).join(", ")}; edit addFile + run ${ep.map((p) => s(eTotal(p))).join(", ")}.`);
  out.push("");
  // Memory: wasm memory.buffer.byteLength only grows, so a reading is the peak so far.
  const tS = 3 * g.volumeBytes;
  const tE = 3 * g.volumeBytes + g.gcodeBytes;
  const ms = g.surface.memory;
  const me = g.edit.memory;
  const marks = g.edit.marks;
  const lastEdit = marks.map((m) => m.stage).lastIndexOf("edit");
  const throughEdit = lastEdit >= 0 && lastEdit + 1 < marks.length ? marks[lastEdit + 1].memory : me.afterRun;
  const mb = (b) => f(b / MB, 1);
  out.push("Worker memory: wasm linear memory (`memory.buffer.byteLength`, MB = 10⁶ bytes; it only grows, so a reading is the peak so far), first pass of each case's fresh worker. Target: 3 × the volume's bytes (+ the G-code's).");
  out.push("");
  out.push("| case | at init | after addFile | peak of the target's work | target | peak ÷ target | met | end of the case | native peak RSS above the pass's start |");
  out.push("|---|---|---|---|---|---|---|---|---|");
  out.push(`| series → surface | ${mb(ms.init)} | ${mb(ms.afterAddFile)} | ${mb(ms.afterSurface)} (after the surface) | ${mb(tS)} | ${f(ms.afterSurface / tS, 2)} | ${met(ms.afterSurface < tS)} | ${mb(ms.end)} | ${native?.peakMB ? f(native.peakMB.surface, 1) : "?"} |`);
  out.push(`| edit | ${mb(me.init)} | ${mb(me.afterGcode)} | ${mb(throughEdit)} (through the edit stage) | ${mb(tE)} | ${f(throughEdit / tE, 2)} | ${met(throughEdit < tE)} | ${mb(me.afterRun)} after the run (analysis with preview) | ${native?.peakMB ? f(native.peakMB.edit, 1) : "?"} (whole pass) |`);
  out.push("");
  out.push(`Edit run, wasm MB at each stage's first progress report: ${marks.map((m) => `${m.stage} ${mb(m.memory)}`).join(" → ")} → end ${mb(me.afterRun)}.`);
  out.push("");
  return out.join("\n");
}

/** Runs one command in a fresh bench worker and resolves with its `type` answer. */
async function workerStep(page, message, type) {
  return page.evaluate(async ({ message, type, timeout }) => {
    const w = new Worker("/tests/e2e/bench-worker.js", { type: "module" });
    try {
      return await new Promise((ok, fail) => {
        const timer = setTimeout(() => fail(new Error(`no ${type} result within ${timeout / 1000} s`)), timeout);
        w.onmessage = ({ data }) => {
          clearTimeout(timer);
          if (data.type === type) ok(data);
          else fail(new Error(data.message ?? JSON.stringify(data)));
        };
        w.onerror = (e) => { clearTimeout(timer); fail(new Error(e.message || "worker failed to start")); };
        w.postMessage(message);
      });
    } finally {
      w.terminate();
    }
  }, { message, type, timeout: TIMEOUT });
}

/** Whole designs stage by stage: worker beside native (`weft bench --design` table rows). */
function designsReport(browserRun, nativeText) {
  // Native rows: | design | stage | 1 thread s | N threads s | speed-up |
  const native = {};
  const nativeAll = {};
  for (const m of nativeText.matchAll(/^\| ([^|]+) \| ([^|*]+) \| ([0-9.]+) \| ([0-9.]+) \| [^|]+ \|$/gm)) {
    (native[m[1].trim()] ??= {})[m[2].trim()] = Number(m[3]) * 1000;
    (nativeAll[m[1].trim()] ??= {})[m[2].trim()] = Number(m[4]) * 1000;
  }
  for (const m of nativeText.matchAll(/^\| ([^|]+) \| \*\*total\*\* \| \*\*([0-9.]+)\*\* \| \*\*([0-9.]+)\*\*/gm)) {
    (native[m[1].trim()] ??= {}).total = Number(m[2]) * 1000;
    (nativeAll[m[1].trim()] ??= {}).total = Number(m[3]) * 1000;
  }
  const threads = nativeText.match(/\| ([0-9]+) threads s \|/)?.[1] ?? "N";
  const out = [];
  out.push(`## Whole designs, stage by stage (best of ${REPEATS} runs, no cache)`);
  out.push("");
  out.push(`Browser: Chromium ${browserRun.version}, module Web Worker, wasm (\`Session.run\`, a fresh session per run). Native: \`weft bench --design\`. Milliseconds; a stage runs from its first progress report to the next stage's.`);
  out.push("");
  out.push(`| design | stage | worker ms (1 thread) | native ms, 1 thread | worker / native | native ms, ${threads} threads | 1 ÷ ${threads} threads |`);
  out.push("|---|---|---|---|---|---|---|");
  const ratio = (a, b) => (a && b ? `${f(a / b, 2)}×` : "?");
  for (const row of browserRun.designs.rows) {
    const n = native[row.name] ?? {};
    const a = nativeAll[row.name] ?? {};
    for (const s of row.stages) out.push(`| ${row.name} | ${s.stage} | ${f(s.ms, 1)} | ${f(n[s.stage], 1)} | ${ratio(s.ms, n[s.stage])} | ${f(a[s.stage], 1)} | ${ratio(n[s.stage], a[s.stage])} |`);
    const best = Math.min(...row.runs);
    out.push(`| ${row.name} | **total** | **${f(best, 1)}** | **${f(n.total, 1)}** | ${ratio(best, n.total)} | **${f(a.total, 1)}** | ${ratio(n.total, a.total)} |`);
  }
  out.push("");
  out.push(`Worker runs (ms): ${browserRun.designs.rows.map((r) => `${r.name} ${r.runs.map((x) => f(x, 0)).join(", ")}`).join("; ")}; wasm linear memory after: ${f(browserRun.designs.memory / MiB, 0)} MiB.`);
  return out.join("\n");
}

/** The pairing benchmark: worker rows beside the native table of `weft bench --pairing`. */
function pairingReport(browserRun, nativeText) {
  const native = {};
  for (const m of nativeText.matchAll(/^\| ([\w/-]+) \| (\d+) \| (\d+) \| ([\d.]+) \| ([\d.]+) \| ([^|]+) \| ([\d.]+) \| ([\d.]+) \| ([^|]+) \|/gm)) {
    native[m[1]] = { heuristicMs: Number(m[4]), heuristicMm: Number(m[5]), exactMs: Number(m[7]), exactMm: Number(m[8]) };
  }
  const out = [];
  out.push(`## odd-node pairing: heuristic vs exact, one layer (\`paths::optimise\`, circuit order, one pass each)`);
  out.push("");
  out.push(`Browser: Chromium ${browserRun.version}, module Web Worker, wasm (\`BenchPairing.run\`). Native: \`weft bench --pairing\`. Exact = \`exact_pairing_seconds\` at its maximum (60 s); where the exact solve is estimated over it, the heuristic runs and the row says "within x %".`);
  out.push("");
  out.push("| case | edges | odd nodes | heuristic: worker ms | native ms | mm | status | exact: worker ms | native ms | mm | status | cost exact ÷ heuristic | time exact ÷ heuristic (worker) | worker ÷ native (exact) |");
  out.push("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
  const rows = browserRun.pairing.rows;
  for (let i = 0; i + 1 < rows.length; i += 2) {
    const [h, e] = [rows[i], rows[i + 1]];
    const n = native[h.name];
    const same = !n || (Math.abs(n.heuristicMm - h.stats.pairingMm) < 0.01 && Math.abs(n.exactMm - e.stats.pairingMm) < 0.01) ? "" : " (native differs!)";
    out.push(`| ${h.name}${same} | ${h.stats.edges} | ${h.stats.oddNodes} | ${f(h.ms, 1)} | ${f(n?.heuristicMs, 1)} | ${f(h.stats.pairingMm, 2)} | ${h.stats.status} | ${f(e.ms, 1)} | ${f(n?.exactMs, 1)} | ${f(e.stats.pairingMm, 2)} | ${e.stats.status} | ${f(e.stats.pairingMm / h.stats.pairingMm, 4)} | ${f(e.ms / h.ms, 1)}× | ${n ? `${f(e.ms / n.exactMs, 2)}×` : "?"} |`);
  }
  out.push("");
  out.push(`Wasm linear memory after all cases: ${f(browserRun.pairing.memory / MiB, 0)} MiB.`);
  if (nativeText) out.push("\n<details><summary>weft bench --pairing output</summary>\n\n" + nativeText.trim() + "\n\n</details>");
  return out.join("\n");
}

// ---------------------------------------------------------------------------------------
// Report
// ---------------------------------------------------------------------------------------
const loadAverage = () => readFileSync("/proc/loadavg", "utf8").split(" ").slice(0, 3).join(" ");
const loadBefore = loadAverage();
const browserRun = await runBrowser();
/** Prints a case's report: the worker's numbers, then the native run made right after (so
 * the ratios come from one run), the load average around both, and the native output. */
function reportAndExit(runNative, report, details) {
  const loadBrowser = loadAverage();
  const native = runNative();
  const loadNative = loadAverage();
  console.log(report(browserRun, native));
  console.log(`Load average (1, 5, 15 min): ${loadBefore} at the start, ${loadBrowser} after the worker runs, ${loadNative} after the native run.`);
  if (native && details) console.log(details(native));
  process.exit(0);
}
if (SCALING_ONLY) {
  reportAndExit(runNativeScaling, scalingReport, (native) => "\n<details><summary>weft bench --scaling output</summary>\n\n```text\n" + native.text.trim() + "\n```\n\n</details>");
}
if (DESIGNS.length) {
  reportAndExit(() => (WEFT_BIN ? execFileSync(WEFT_BIN, ["bench", "--design", ...DESIGNS.map((d) => resolve(ROOT, d))], { encoding: "utf8", maxBuffer: 1 << 24 }) : ""), designsReport);
}
if (GRADED_ONLY) {
  reportAndExit(runNativeGraded, gradedReport, (native) => "\n<details><summary>weft bench --graded output</summary>\n\n" + native.text.trim() + "\n\n</details>");
}
if (PAIRING_ONLY) {
  reportAndExit(() => (WEFT_BIN ? execFileSync(WEFT_BIN, ["bench", "--pairing"], { encoding: "utf8", maxBuffer: 1 << 24 }) : ""), pairingReport);
}
const nativeCache = runNativeCache();
if (CACHE_ONLY) {
  console.log(cacheReport(browserRun, nativeCache));
  console.log("\n<details><summary>weft bench --cache output</summary>\n\n" + (nativeCache?.text.trim() ?? "") + "\n\n</details>");
  process.exit(0);
}
const native = runNative();
const { result: r, version } = browserRun;
const latticeOut = [];
{
  const median = (a) => [...a].sort((x, y) => x - y)[Math.floor(a.length / 2)];
  latticeOut.push(`## lattice path optimisation: \`paths::optimise\` of one prepared layer (strokes generated beforehand, not timed)`);
  latticeOut.push("");
  latticeOut.push(`Browser: Chromium ${version}, module Web Worker, wasm (\`BenchLattice.run\`, ${REPEATS} passes). Native: \`weft bench --lattice\`. Milliseconds.`);
  latticeOut.push("");
  latticeOut.push("| workload | method | edges | paths | score | native best | native median | worker best | worker median | worker / native (best) | target (worker) | met |");
  latticeOut.push("|---|---|---|---|---|---|---|---|---|---|---|---|");
  for (const row of browserRun.lattice.rows) {
    const n = native?.lattice?.[row.which];
    const best = Math.min(...row.ms);
    const med = median(row.ms);
    const same = !n || (n.edges === row.edges && n.paths === row.paths) ? "" : " (native differs!)";
    latticeOut.push(`| ${row.which} | ${row.method} | ${row.edges} | ${row.paths}${same} | ${f(row.score, 4)} | ${f(n?.best, 1)} | ${f(n?.median, 1)} | ${f(best, 1)} | ${f(med, 1)} | ${n ? `${f(best / n.best, 2)}×` : "?"} | < ${row.targetMs} | ${med < row.targetMs ? "yes" : "**no**"} |`);
  }
  latticeOut.push("");
  latticeOut.push(`Worker passes (ms): ${browserRun.lattice.rows.map((row) => `${row.which} ${row.ms.map((x) => f(x, 1)).join(", ")} (prepare ${f(row.prepareMs, 0)})`).join("; ")}; wasm linear memory after: ${f(browserRun.lattice.memory / MiB, 0)} MiB.`);
  latticeOut.push("");
}
if (LATTICE_ONLY) {
  console.log(latticeOut.join("\n"));
  if (native) console.log("\n<details><summary>weft bench --lattice output</summary>\n\n" + native.text.trim() + "\n\n</details>");
  process.exit(0);
}
const stlMB = r.stlBytes / MB;
const ws = Object.fromEntries(r.stages.map((s) => [s.stage, s.ms / 1000]));
const out = [];
out.push(`## slice + G-code: ${TRIANGLES} triangles requested (${f(stlMB, 1)} MB binary STL), 0.2 mm layers, ${r.layers} layers, G-code ${f(r.gcodeBytes / MB, 1)} MB`);
out.push("");
out.push(`Browser: Chromium ${version}, module Web Worker, wasm (\`pkg/\`). Native: \`weft bench\`. Seconds.`);
out.push("");
out.push("| stage | native, no preview (CLI) | native, with preview | worker (Session.run, with preview) | worker / native with preview |");
out.push("|---|---|---|---|---|");
for (const stage of ["import", "slice", "gcode", "analyze"]) {
  const n = native?.stages[stage];
  const w = ws[stage];
  out.push(`| ${stage} | ${f(n?.plain)} | ${f(n?.preview)} | ${f(w)} | ${n && w != null ? `${f(w / n.preview, 2)}×` : "?"} |`);
}
const wt = r.runMs / 1000;
out.push(`| **total (run)** | **${f(native?.total?.plain)}** | **${f(native?.total?.preview)}** | **${f(wt)}** | **${native?.total ? `${f(wt / native.total.preview, 2)}×` : "?"}** |`);
out.push(`| Session.addFile (extra import the page does on load) | | | ${f(r.addFileMs / 1000)} | |`);
out.push("");
const m = r.memory;
out.push("Worker wasm linear memory (`memory.buffer.byteLength`; it only grows, so each value is the peak so far):");
out.push("");
out.push("| point | MiB | × STL size |");
out.push("|---|---|---|");
const row = (label, bytes) => out.push(`| ${label} | ${f(bytes / MiB, 0)} | ${f(bytes / r.stlBytes, 2)}× |`);
row("after init", m.init);
row("STL bytes handed to the worker", m.beforeJob);
row("after Session.addFile (import)", m.afterAddFile);
row("**after Session.run (peak of the job)**", m.afterRun);
row(`after the analyzer workload (${f(r.analyze.bytes / MB, 0)} MB of G-code copied into wasm memory)`, m.end);
out.push("");
out.push(`Renderer process (page + worker) peak RSS during the job: ${f(browserRun.rendererPeakMiB, 0)} MiB` +
  `${browserRun.peakReset ? ` (peak reset before the job; ${f(browserRun.rendererBeforeMiB, 0)} MiB resident then, including the ${f(stlMB, 0)} MB STL held by the page)` : " (process lifetime peak: includes the STL generation)"}; ` +
  `it includes the analyzer workload's ${f(r.analyze.bytes / MB, 0)} MB buffer and its copy in wasm memory.`);
out.push("");
const wMBs = r.analyze.bytes / MB / (r.analyze.ms / 1000);
out.push(`## analyze: ${f(r.analyze.bytes / MB, 1)} MB of G-code (the run's G-code repeated), no preview`);
out.push("");
out.push("| | MB/s |");
out.push("|---|---|");
out.push(`| native (\`weft bench\`, best of 3) | ${native?.analyzeMBs ?? "?"} |`);
out.push(`| native with preview | ${native?.analyzePreviewMBs ?? "?"} |`);
out.push(`| worker (\`benchAnalyze\`, one pass) | ${f(wMBs, 0)} |`);
out.push("");
console.log(out.join("\n"));
console.log(latticeOut.join("\n"));
if (CACHE) console.log(cacheReport(browserRun, nativeCache));
if (GRADED) console.log(gradedReport(browserRun, runNativeGraded()));
if (native) {
  console.log("\n<details><summary>weft bench output</summary>\n\n" + native.text.trim() + "\n\n</details>");
}

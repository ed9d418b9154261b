#!/usr/bin/env node
// Threads in the browser (issue 15): the page itself, served cross-origin isolated, runs each
// workload in a fresh page (so nothing is cached) at `?threads=1` (the plain module, as on a
// host without isolation) and at more threads (the threaded module's pool), and reads the run
// report's stage times (the worker's wall time per stage) and the time from the drop to the
// first drawn frame. Then the native CLI runs the same designs at 1 thread and at the same
// counts (`weft run --threads N`, its run report). Prints Markdown; not a test (timings depend
// on the machine); see BENCHMARKS.md, "Threads".
//
//   node tests/e2e/threads-bench.mjs
// Environment:
//   WEFT_BIN          native CLI (default ./target/release/weft)
//   BENCH_THREADS     thread counts (default 1,2,4)
//   BENCH_REPEATS     fresh-page runs per design and count, best counts (default 3)
//   BENCH_DESIGNS     example names (default ball-burst-disc-48mm,sphere-30mm,graded-phantom,hourglass-omega3)
//   BENCH_SPHERE=0    leave out the 1M-triangle sphere (the default design with its mesh)
//   BENCH_BIG=1       also the 4M-triangle sphere (a 200 MB STL dropped on the page)
//   BENCH_WARM        page states, comma-separated (default 0,1): 0 a fresh page runs the workload
//                     first (cold: V8 optimises the code on the way), 1 it runs WARMUP first
//   BENCH_PERF=1      also which threads had the machine's cores during each stage (Linux perf,
//                     `perf record -e cpu-clock -a`, as root or with perf_event_paranoid ≤ 0): the
//                     share the worker and its pool got, and what took the rest (the page's own
//                     threads, the GPU process's software renderer, other programs). The stages are
//                     placed by the worker's `weft:stage:*` performance marks.
import { execFileSync } from "node:child_process";
import { existsSync, mkdirSync, readdirSync, readFileSync, writeFileSync } from "node:fs";
import { join, resolve } from "node:path";
import { ROOT, serve } from "./server.mjs";
import { dropAndTimeFirstFrame, launchChromium, recordCores, stageMarks, waitReady } from "./page-helpers.mjs";
import { sphereStl } from "./threads-checks.mjs";

const WEFT_BIN = resolve(ROOT, process.env.WEFT_BIN ?? "target/release/weft");
const COUNTS = (process.env.BENCH_THREADS ?? "1,2,4").split(",").map(Number);
const REPEATS = Number(process.env.BENCH_REPEATS ?? 3);
const DESIGNS = (process.env.BENCH_DESIGNS ?? "ball-burst-disc-48mm,sphere-30mm,graded-phantom,hourglass-omega3").split(",").filter(Boolean);
const SPHERE = process.env.BENCH_SPHERE !== "0";
const OUT = join(ROOT, "tests/e2e/out");
mkdirSync(OUT, { recursive: true });
const sphere = join(OUT, "sphere-1m.stl");
if (SPHERE && !existsSync(sphere)) writeFileSync(sphere, sphereStl(1000));
const BIG = process.env.BENCH_BIG === "1";
const bigSphere = join(OUT, "sphere-4m.stl");
if (BIG && !existsSync(bigSphere)) writeFileSync(bigSphere, sphereStl(2000));
// A quarter-size sphere: what a warm page drops first before a big sphere, so that the import,
// the slicer and the analysis have run long enough for V8 to optimise them (a 12-triangle
// cube leaves them in the baseline tier, and a first big run then shares the cores with V8's
// optimising compiler).
const warmSphere = join(OUT, "sphere-250k.stl");
if ((SPHERE || BIG) && !existsSync(warmSphere)) writeFileSync(warmSphere, sphereStl(500));
const meshes = { "sphere-1m": sphere, "sphere-4m": bigSphere, "sphere-250k": warmSphere };
/** The design a warm page runs first: another of the workload's kind (graded has one example). */
const WARMUP = { "ball-burst-disc-48mm": "honeycomb-10mm", "hourglass-omega3": "barrel-omega1", "sphere-30mm": "cube-20mm", "sphere-1m": "sphere-250k", "sphere-4m": "sphere-250k" };
const WARM = (process.env.BENCH_WARM ?? "0,1").split(",").map((w) => w === "1");
const PERF = process.env.BENCH_PERF === "1";
/** perf's sampling rate per core, Hz. */
const PERF_HZ = 999;
const CORES = Number(execFileSync("nproc", { encoding: "utf8" }).trim());

/**
 * Runs `work()` while perf samples every core, then returns, for each stage of the computing
 * worker that began during the recording (the windows between its `weft:stage:*` marks), the
 * share of the cores each group of threads had: worker (the worker and its pool), page (the
 * page's other threads), renderer (the GPU process's software renderer and compositor),
 * other, idle.
 */
async function coresDuring(page, work) {
  // CLOCK_REALTIME: the clock of performance.timeOrigin + performance.now().
  const perf = await recordCores(join(OUT, "threads-bench.perf"), { hz: PERF_HZ, clock: "CLOCK_REALTIME" });
  const result = await work();
  const samples = await perf.stop();
  const marks = await stageMarks(page);
  const windows = [];
  for (let k = 0; k + 1 < marks.length; k++) {
    const { name, at } = marks[k];
    if (name !== null && !name.endsWith("(reused)")) windows.push([name, at, marks[k + 1].at]);
  }
  // The processes holding a worker: the page's renderers.
  const renderer = new Set(samples.filter((s) => s.comm === "DedicatedWorker").map((s) => s.id));
  const shares = new Map();
  for (const [name, lo, hi] of windows) {
    // Stages of earlier runs (the warm-up) began before the recording; too short a stage has
    // too few samples to count.
    if (!(lo >= (samples[0]?.ms ?? Infinity)) || hi - lo < 20) continue;
    const by = { worker: 0, page: 0, renderer: 0, idle: 0, other: 0 };
    for (const { comm, id, ms: at } of samples) {
      if (at < lo || at >= hi) continue;
      const group = comm === "DedicatedWorker" ? "worker" : comm === "swapper" ? "idle" : renderer.has(id) ? "page"
        : /^Thread<\d+>$|^VizCompositor|^CrGpuMain/.test(comm) ? "renderer" : "other";
      by[group] += 1;
    }
    const total = ((hi - lo) / 1000) * PERF_HZ * CORES;
    const share = Object.fromEntries(Object.entries(by).map(([k, v]) => [k, v / total]));
    // An idle core may take no samples at all (a tickless kernel): idle is what the rest leave.
    share.idle = Math.max(0, 1 - share.worker - share.page - share.renderer - share.other);
    shares.set(name, share);
  }
  return { result, shares };
}

// WEFT_PKG_DIR: serve another build of the modules as /pkg/ (as run.mjs does).
const server = await serve({ root: ROOT, ...(process.env.WEFT_PKG_DIR ? { pkgDir: resolve(process.env.WEFT_PKG_DIR) } : {}) });
const browser = await launchChromium();
const log = (s) => process.stderr.write(`[threads-bench] ${s}\n`);

/**
 * The high-water mark of resident memory of the largest renderer process (the page, its
 * worker and the pool's workers live in one; each fresh context gets its own), bytes.
 * measureUserAgentSpecificMemory() would be per frame but resolves only at the next full
 * garbage collection (60 s here).
 */
function rendererPeakBytes() {
  let peak = 0;
  for (const pid of readdirSync("/proc").filter((d) => /^\d+$/.test(d))) {
    try {
      if (!readFileSync(`/proc/${pid}/cmdline`, "utf8").includes("--type=renderer")) continue;
      const hwm = /VmHWM:\s+(\d+) kB/.exec(readFileSync(`/proc/${pid}/status`, "utf8"));
      if (hwm) peak = Math.max(peak, Number(hwm[1]) * 1024);
    } catch { /* gone */ }
  }
  return peak;
}

/** Picks example `name` from the Examples menu (once the menu is filled). */
async function pickExample(page, name) {
  await page.waitForFunction(() => document.querySelectorAll("#examples option[value]:not([value=''])").length > 0);
  await page.selectOption("#examples", `${name}.json`);
}

/**
 * One fresh page at `threads`: the workload, its report's stage times, the frame time and
 * memory. `warm`: the page first runs another design of the same kind ([`WARMUP`]), so the
 * engine has optimised the code the workload runs (a fresh page runs it first in V8's
 * baseline tier and optimises the hot functions on the way, on the same cores).
 */
async function once(name, threads, warm) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 }, serviceWorkers: "block" });
  await context.addInitScript(() => localStorage.setItem("weft.autoRun", "0"));
  const page = await context.newPage();
  try {
    await page.goto(`${server.url}/www/?threads=${threads}`);
    await waitReady(page);
    await page.waitForFunction(() => window.weft.threads.used != null);
    const used = await page.evaluate(() => window.weft.threads.used);
    if (used !== threads) throw new Error(`asked ${threads} threads, the worker uses ${used}`);
    if (warm) {
      const k = await page.evaluate(() => window.weft.resultCount);
      const first = WARMUP[name] ?? "cube-20mm";
      if (meshes[first]) await page.setInputFiles("#file", meshes[first]);
      else await pickExample(page, first);
      await page.waitForFunction((n) => window.weft.resultCount > n && !window.weft.busy, k, { timeout: 600000 });
    }
    if (!meshes[name]) await page.waitForFunction(() => document.querySelectorAll("#examples option[value]:not([value=''])").length > 0);
    const drop = () => dropAndTimeFirstFrame(page, meshes[name] ?? null, name);
    let r;
    if (PERF) {
      const { result, shares } = await coresDuring(page, drop);
      r = result;
      r.shares = shares;
    } else {
      r = await drop();
    }
    r.memory = rendererPeakBytes();
    return r;
  } finally {
    await context.close();
  }
}

/** Best of REPEATS per stage and for the whole; memory the largest seen; cores' shares of the best run of each stage. */
function best(runs) {
  const stages = new Map();
  const shares = new Map();
  for (const r of runs) {
    for (const s of r.stages) {
      if (s.ms < (stages.get(s.stage) ?? Infinity)) {
        stages.set(s.stage, s.ms);
        if (r.shares?.has(s.stage)) shares.set(s.stage, r.shares.get(s.stage));
      }
    }
    if (r.shares?.has("load") && (r.loadMs ?? Infinity) <= Math.min(...runs.map((q) => q.loadMs ?? Infinity))) shares.set("load", r.shares.get("load"));
  }
  // Medians too: on a shared machine one lucky run can make the best of a few look better (or
  // a ratio of bests worse) than the runs are.
  const median = (xs) => {
    const v = xs.filter((x) => Number.isFinite(x)).sort((a, b) => a - b);
    return v.length ? (v.length % 2 ? v[(v.length - 1) / 2] : (v[v.length / 2 - 1] + v[v.length / 2]) / 2) : NaN;
  };
  const medians = new Map([...stages.keys()].map((st) => [st, median(runs.map((r) => r.stages.find((s) => s.stage === st)?.ms))]));
  medians.set("**whole run**", median(runs.map((r) => r.ms)));
  medians.set("drop → first frame", median(runs.map((r) => r.frameMs || NaN)));
  return {
    shares, medians,
    ms: Math.min(...runs.map((r) => r.ms)), frameMs: Math.min(...runs.map((r) => r.frameMs)),
    loadMs: Math.min(...runs.map((r) => r.loadMs ?? 0)),
    memory: Math.max(...runs.map((r) => r.memory ?? 0)), stages,
  };
}

/** Native: `weft run --threads N` (the report's timings), best of REPEATS. */
function native(name, threads) {
  const runs = [];
  for (let i = 0; i < REPEATS; i++) {
    const report = join(OUT, `threads-bench-${name}.json`);
    const args = meshes[name]
      ? ["run", join(ROOT, "examples/cube-20mm.json"), "--input", meshes[name]]
      : ["run", join(ROOT, `examples/${name}.json`)];
    const t0 = performance.now();
    execFileSync(WEFT_BIN, [...args, "--out", join(OUT, `threads-bench-${name}.gcode`), "--report", report, "--threads", String(threads)],
      { cwd: ROOT, stdio: ["ignore", "ignore", "pipe"], timeout: 600000 });
    const ms = performance.now() - t0;
    const rep = JSON.parse(readFileSync(report, "utf8"));
    runs.push({ ms, frameMs: 0, stages: rep.timings.filter((t) => !t.cached).map((t) => ({ stage: t.stage, ms: t.ms })) });
  }
  return best(runs);
}

const names = [...(SPHERE ? ["sphere-1m"] : []), ...(BIG ? ["sphere-4m"] : []), ...DESIGNS];
const rows = [];
for (const name of names) {
  const cli = new Map();
  for (const warm of WARM) {
    const worker = new Map();
    // Alternate the counts run by run, so a change of load touches them alike.
    const runs = new Map(COUNTS.map((c) => [c, []]));
    for (let i = 0; i < REPEATS; i++) {
      for (const c of COUNTS) {
        log(`${name}: worker at ${c} thread(s), ${warm ? "warm" : "cold"} page, run ${i + 1}/${REPEATS}`);
        const r = await once(name, c, warm);
        runs.get(c).push(r);
        log(`  ${r.stages.map((t) => `${t.stage} ${t.ms.toFixed(0)} ms`).join(", ")}; drop → first frame ${r.frameMs.toFixed(0)} ms`);
      }
    }
    for (const c of COUNTS) worker.set(c, best(runs.get(c)));
    rows.push({ name: `${name} (${warm ? `warm: after ${WARMUP[name] ?? "cube-20mm"}` : "cold page"})`, worker, cli });
  }
  for (const c of COUNTS) {
    log(`${name}: native at ${c} thread(s)`);
    cli.set(c, native(name, c));
  }
}
await browser.close();
await server.close();

const f = (ms) => (ms >= 1000 ? `${(ms / 1000).toFixed(2)} s` : `${ms.toFixed(0)} ms`);
const x = (a, b) => (b > 0 ? `${(a / b).toFixed(2)}×` : "–");
const [one, ...more] = COUNTS;
const load = readFileSync("/proc/loadavg", "utf8").split(" ").slice(0, 3).join(" ");
console.log(`Browser worker (Chromium ${browser.version?.() ?? ""}) and native CLI, ${REPEATS} fresh runs each, best counts; load after: ${load}\n`);
console.log(`| workload | stage | ${COUNTS.map((c) => `worker ${c}T`).join(" | ")} | ${more.map((c) => `worker ${one}T ÷ ${c}T`).join(" | ")} | ${COUNTS.map((c) => `native ${c}T`).join(" | ")} | ${more.map((c) => `native ${one}T ÷ ${c}T`).join(" | ")} | worker ÷ native at ${more[0] ?? one}T |`);
console.log(`|${"---|".repeat(2 + COUNTS.length * 2 + more.length * 2 + 1)}`);
for (const { name, worker, cli } of rows) {
  const stages = [...worker.get(one).stages.keys()].filter((s) => worker.get(one).stages.get(s) >= 5);
  const line = (label, get) => {
    const w = COUNTS.map((c) => get(worker.get(c)));
    const n = COUNTS.map((c) => get(cli.get(c)));
    const top = more[0] ?? one;
    console.log(`| ${name} | ${label} | ${w.map(f).join(" | ")} | ${more.map((c) => x(w[0], get(worker.get(c)))).join(" | ")} | ${n.map(f).join(" | ")} | ${more.map((c) => x(n[0], get(cli.get(c)))).join(" | ")} | ${x(get(worker.get(top)), get(cli.get(top)))} |`);
  };
  if (worker.get(one).loadMs > 0) {
    console.log(`| ${name} | dropping the file: its read, the import and the summary (page marks, before the run) | ${COUNTS.map((c) => f(worker.get(c).loadMs)).join(" | ")} | ${more.map((c) => x(worker.get(one).loadMs, worker.get(c).loadMs)).join(" | ")} | ${COUNTS.map((c) => f(cli.get(c).stages.get("import") ?? NaN)).join(" | ")} | ${more.map((c) => x(cli.get(one).stages.get("import"), cli.get(c).stages.get("import"))).join(" | ")} | ${x(worker.get(more[0] ?? one).loadMs, cli.get(more[0] ?? one).stages.get("import"))} |`);
  }
  for (const s of stages) line(s, (b) => b.stages.get(s) ?? NaN);
  line("**whole run**", (b) => b.ms);
  console.log(`| ${name} | drop → first frame | ${COUNTS.map((c) => f(worker.get(c).frameMs)).join(" | ")} | ${more.map((c) => x(worker.get(one).frameMs, worker.get(c).frameMs)).join(" | ")} | ${COUNTS.map(() => "").join(" | ")} | ${more.map(() => "").join(" | ")} | |`);
  console.log(`| ${name} | renderer peak RSS (page + worker + pool) | ${COUNTS.map((c) => `${(worker.get(c).memory / 1048576).toFixed(0)} MiB`).join(" | ")} | ${more.map(() => "").join(" | ")} | ${COUNTS.map(() => "").join(" | ")} | ${more.map(() => "").join(" | ")} | |`);
}

if (REPEATS >= 3) {
  console.log(`\nMedians of the ${REPEATS} runs (the table above takes the best):\n`);
  console.log(`| workload | stage | ${COUNTS.map((c) => `worker ${c}T`).join(" | ")} | ${more.map((c) => `worker ${one}T ÷ ${c}T`).join(" | ")} | ${COUNTS.map((c) => `native ${c}T`).join(" | ")} | ${more.map((c) => `native ${one}T ÷ ${c}T`).join(" | ")} |`);
  console.log(`|${"---|".repeat(2 + COUNTS.length * 2 + more.length * 2)}`);
  for (const { name, worker, cli } of rows) {
    for (const st of worker.get(one).medians.keys()) {
      const w = COUNTS.map((c) => worker.get(c).medians.get(st));
      const n = COUNTS.map((c) => cli.get(c).medians.get(st) ?? NaN);
      if (!(w[0] >= 5)) continue;
      const cell = (v) => (Number.isFinite(v) ? f(v) : "");
      console.log(`| ${name} | ${st} | ${w.map(cell).join(" | ")} | ${w.slice(1).map((v) => x(w[0], v)).join(" | ")} | ${n.map(cell).join(" | ")} | ${n.slice(1).map((v) => (Number.isFinite(v) ? x(n[0], v) : "")).join(" | ")} |`);
    }
  }
}

if (PERF) {
  // Which threads had the cores during each stage, in the run that gave the stage's best time.
  const pct = (v) => (v == null ? "" : `${(100 * v).toFixed(0)} %`);
  console.log(`\nShare of the ${CORES} cores during each stage (perf, all threads of the machine; worker: the computing worker and its pool; page: the page's other threads; renderer: the GPU process's software renderer and compositor):\n`);
  console.log(`| workload | stage | ${COUNTS.map((c) => `${c}T: worker · page · renderer · other · idle`).join(" | ")} |`);
  console.log(`|${"---|".repeat(2 + COUNTS.length)}`);
  for (const { name, worker } of rows) {
    const names = new Set(COUNTS.flatMap((c) => [...worker.get(c).shares.keys()]));
    for (const s of names) {
      const cell = (c) => {
        const v = worker.get(c).shares.get(s);
        return v ? [v.worker, v.page, v.renderer, v.other, v.idle].map(pct).join(" · ") : "";
      };
      console.log(`| ${name} | ${s === "load" ? "dropping the file (the worker's load)" : s} | ${COUNTS.map(cell).join(" | ")} |`);
    }
  }
}

#!/usr/bin/env node
// Where a stage's time goes on each thread of the browser worker (issue 15): traces V8's
// sampling profiler in every thread of the page (the computing worker and the pool's
// workers) while a dropped mesh (after a quarter-size warm-up drop) is imported and run, then
// prints, for the window of one stage: each thread's busy time, the stage's phases by busy
// time, and what the first thread was doing while the second waited. Not a test.
//
//   node tests/e2e/worker-profile.mjs [THREADS] [STAGE]      (default 2 import)
//
// Function names need a module that keeps its name section: `wasm-opt -Oz` drops it, so
// point WEFT_PKG_DIR at a package made by wasm-bindgen alone from cargo's output, e.g.
//   wasm-bindgen --target web --out-dir /tmp/pkg-names --out-name weft target/wasm32-unknown-unknown/wasm/weft.wasm
//   wasm-bindgen --target web --out-dir /tmp/pkg-names/threads --out-name weft target/wasm-threads/wasm32-unknown-unknown/wasm/weft.wasm
// (unoptimised, so slower than the shipped module: compare thread counts, not absolutes).
// Samples are wall-clock: a thread the machine deschedules still counts as busy, so profile
// a quiet machine. BENCH_MESH / BENCH_WARM_MESH choose the files (default the spheres that
// threads-bench.mjs writes to tests/e2e/out/).
// PERF=1 also records which threads of the whole machine were on the cores during the stage
// (Linux `perf record -e cpu-clock -a`, as root or with perf_event_paranoid ≤ 0): the share of
// the cores the worker's threads got, and what else took the rest (the page's own threads,
// the GPU process's software renderer, other programs).

import { execFileSync } from "node:child_process";
import { readFileSync, rmSync } from "node:fs";
import { join, resolve } from "node:path";
import { ROOT, serve } from "./server.mjs";
import { dropAndTimeFirstFrame, launchChromium, recordCores, waitReady } from "./page-helpers.mjs";

const threads = Number(process.argv[2] ?? 2);
const stage = process.argv[3] ?? "import";
const mesh = process.env.BENCH_MESH ?? join(ROOT, "tests/e2e/out/sphere-1m.stl");
const warmMesh = process.env.BENCH_WARM_MESH ?? join(ROOT, "tests/e2e/out/sphere-250k.stl");
const tracePath = join(ROOT, "tests/e2e/out/worker-profile.json");
const perfPath = process.env.PERF === "1" ? join(ROOT, "tests/e2e/out/worker-profile.perf") : null;
/** perf's sampling rate per core, Hz: each sample stands for 1000 / PERF_HZ ms on a core. */
const PERF_HZ = 1999;

const server = await serve({ root: ROOT, ...(process.env.WEFT_PKG_DIR ? { pkgDir: resolve(process.env.WEFT_PKG_DIR) } : {}) });
const browser = await launchChromium();
let timed;
/** perf's samples of every core during the stage's drop (PERF=1). */
let onCoreSamples = null;
try {
  const page = await (await browser.newContext({ viewport: { width: 1280, height: 800 } })).newPage();
  await page.goto(`${server.url}/www/?threads=${threads}`);
  await waitReady(page);
  await dropAndTimeFirstFrame(page, warmMesh);
  await browser.startTracing(page, { path: tracePath, categories: ["disabled-by-default-v8.cpu_profiler"] });
  // CLOCK_MONOTONIC: the clock of the trace's timestamps (Chromium's TimeTicks on Linux).
  const perf = perfPath && (await recordCores(perfPath, { hz: PERF_HZ, clock: "CLOCK_MONOTONIC", id: "tid" }));
  timed = await dropAndTimeFirstFrame(page, mesh);
  if (perf) onCoreSamples = await perf.stop();
  await browser.stopTracing();
} finally {
  await browser.close();
  server.close();
}

/** Every sample of every thread: { thread, at (µs), ms (its length), stack (leaf first) }. */
function samplesOf(trace) {
  const profiles = new Map();
  for (const e of trace.traceEvents ?? trace) {
    if (e.name !== "Profile" && e.name !== "ProfileChunk") continue;
    const key = `${e.pid}:${e.id}`;
    if (!profiles.has(key)) profiles.set(key, { nodes: new Map(), samples: [], deltas: [], start: 0 });
    const p = profiles.get(key);
    if (e.name === "Profile") p.start = e.args.data.startTime ?? 0;
    const d = e.args.data;
    for (const n of d.cpuProfile?.nodes ?? []) p.nodes.set(n.id, n);
    p.samples.push(...(d.cpuProfile?.samples ?? []));
    p.deltas.push(...(d.timeDeltas ?? []));
  }
  const out = [];
  for (const [thread, p] of profiles) {
    for (const n of p.nodes.values()) for (const c of n.children ?? []) if (p.nodes.has(c)) p.nodes.get(c).parent = n.id;
    const name = (id) => (p.nodes.get(id)?.callFrame.functionName || "(anonymous)").replace(/\[[0-9a-f]+\]/g, "");
    let at = p.start;
    const times = p.samples.map((s, k) => ({ s, at: (at += p.deltas[k] ?? 0) }));
    for (let k = 0; k + 1 < times.length; k++) {
      const stack = [];
      for (let id = times[k].s; p.nodes.has(id); id = p.nodes.get(id).parent) stack.push(name(id));
      out.push({ thread, at: times[k].at, ms: (times[k + 1].at - times[k].at) / 1000, stack });
    }
  }
  return out;
}

// Waiting: asleep in a lock, a condition variable or a park, or V8's idle sample.
const waiting = (s) => /Condvar>::wait|Thread>::park|futex_wait|^\((idle|program)\)$/.test(s.stack[0] ?? "(idle)");
const phase = (s) => s.stack.slice(0, 12).join(" ").match(new RegExp(`weft::${stage}::([A-Za-z_]+(::[A-Za-z_]+)?)`))?.[1] ?? s.stack[0].slice(-60);
const add = (map, key, ms) => map.set(key, (map.get(key) ?? 0) + ms);
const top = (map, n) => [...map].sort((a, b) => b[1] - a[1]).slice(0, n);

const all = samplesOf(JSON.parse(readFileSync(tracePath, "utf8")));
rmSync(tracePath);
const inStage = all.filter((s) => s.stack.some((f) => f.includes(`weft::${stage}::`)));
if (!inStage.length) throw new Error(`no sample in weft::${stage}:: (does the module keep its names? see the notes at the top)`);
const [lo, hi] = [Math.min(...inStage.map((s) => s.at)), Math.max(...inStage.map((s) => s.at))];
const window = all.filter((s) => s.at >= lo && s.at <= hi && s.stack.length);
const busy = new Map();
const phases = new Map();
for (const s of window) {
  if (waiting(s)) continue;
  add(busy, s.thread, s.ms);
  add(phases, phase(s), s.ms);
}
const busiest = top(busy, 2).map(([t]) => t);
console.log(`${mesh}, ${threads} thread(s): the run's ${stage} took ${timed.stages.find((x) => x.stage === stage)?.ms?.toFixed(0) ?? "?"} ms`);
console.log(`window ${((hi - lo) / 1000).toFixed(0)} ms; busy per thread ${top(busy, 8).map(([, ms]) => `${ms.toFixed(0)} ms`).join(", ")}; in all ${[...busy.values()].reduce((a, b) => a + b, 0).toFixed(0)} ms`);
console.log(`${stage}'s phases by busy time (all threads):`);
for (const [k, ms] of top(phases, 16)) console.log(`  ${ms.toFixed(1).padStart(7)} ms  ${k}`);
if (busiest.length === 2) {
  // What the busiest thread did while the second one waited: sequential parts and the ends
  // of parallel rounds.
  const [a, b] = busiest;
  const aAt = window.filter((s) => s.thread === a);
  const meanwhile = new Map();
  for (const s of window.filter((x) => x.thread === b && waiting(x))) {
    const mid = s.at + (s.ms * 1000) / 2; // µs, as `at`
    const other = aAt.find((x) => x.at <= mid && mid < x.at + x.ms * 1000);
    add(meanwhile, !other ? "(no sample)" : waiting(other) ? "(waiting too)" : phase(other), s.ms);
  }
  console.log(`while the second thread waited (${[...meanwhile.values()].reduce((x, y) => x + y, 0).toFixed(0)} ms), the first was in:`);
  for (const [k, ms] of top(meanwhile, 12)) console.log(`  ${ms.toFixed(1).padStart(7)} ms  ${k}`);
}

if (onCoreSamples) {
  // On-core samples of every thread of the machine within the stage's window.
  const onCore = new Map();
  for (const { comm, id, ms } of onCoreSamples) {
    const at = ms * 1000; // µs, as the trace
    if (at < lo || at > hi) continue;
    const who = comm === "swapper" ? "(idle core)" : comm === "DedicatedWorker" ? `worker thread ${id}` : /^Thread<\d+>$/.test(comm) ? "GPU process: software renderer" : comm;
    add(onCore, who, 1000 / PERF_HZ);
  }
  const cores = ((hi - lo) / 1000) * Number(execFileSync("nproc", { encoding: "utf8" }).trim());
  const workers = [...onCore].filter(([k]) => k.startsWith("worker thread")).reduce((a, [, ms]) => a + ms, 0);
  console.log(`on the cores during the stage (perf, ${cores.toFixed(0)} core-ms in the window): the worker's threads ${workers.toFixed(0)} ms (${((100 * workers) / cores).toFixed(0)} %)`);
  for (const [k, ms] of top(onCore, 12)) console.log(`  ${ms.toFixed(1).padStart(7)} ms  ${(100 * ms / cores).toFixed(0).padStart(3)} %  ${k}`);
}

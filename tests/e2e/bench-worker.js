// Browser benchmark worker (module worker, started by tests/e2e/bench.mjs). Runs the same
// workloads as `weft bench` (src/bench.rs) inside a Web Worker and times them with
// performance.now().
//
// Messages (page → worker):
//   { cmd: "stl", triangles }        → { type: "stl", bytes (transferred), ms }
//       generates the benchmark mesh's binary STL (benchMeshStl; not part of the job).
//   { cmd: "run", stl, gcodeMb }     → { type: "result", ... } or { type: "error", message }
//       `stl` (ArrayBuffer, optional: generated here when absent). Times Session.addFile
//       (import) and Session.run(benchDesign()) per stage through the progress callback
//       (import / slice / gcode / analyze), then analyses ~gcodeMb MB of G-code (the run's
//       G-code repeated) with benchAnalyze. Reports wasm linear memory
//       (memory.buffer.byteLength, which only grows: its value at a point is the peak so far).
//   { cmd: "lattice", repeats }      → { type: "lattice", rows: [{ which, method, edges, paths,
//       score, targetMs, prepareMs, ms: [...] }] }: the lattice path-optimisation workloads
//       (src/bench.rs): BenchLattice(which) prepares the layer's strokes (not timed), then
//       run() (paths::optimise only) is timed `repeats` times with performance.now().
//   { cmd: "cache", stl, discJson } → { type: "cache", rows: [{ name, addFileMs, firstMs,
//       secondMs, stages: [{ stage, cached }], uncached: [...] }] }: the stage-cache workload
//       of `weft bench --cache` (src/bench.rs): per workload one Session, a full run, then a
//       re-run after material.bed_temp_c +10 (edited in the design JSON). `discJson` is the
//       ball-burst-disc-48mm example; `stl` (ArrayBuffer) the benchmark mesh (addFile first).
//   { cmd: "memory", stl }           → { type: "memory", stlBytes, addFileMs, runMs, layers,
//       memory: { init, afterAddFile, afterRun }, uaMemory }: peak wasm memory of a big input
//       (Session.addFile, then Session.run(benchDesign())); after each it posts
//       { type: "phase", phase } and waits for { cmd: "continue", measured }: the page's
//       performance.measureUserAgentSpecificMemory() (bytes, or why not), kept as uaMemory.
//   { cmd: "pairing" }              → { type: "pairing", rows: [{ name, exact, prepareMs, ms,
//       stats }] }: every case of `weft bench --pairing` (src/bench/pairing.rs), heuristic then
//       exact, one timed BenchPairing.run() each; `stats` is its JSON answer.
//   { cmd: "designs", designs: [{ name, json }], repeats } → { type: "designs", rows: [{ name,
//       runs: [ms…], stages: [{ stage, ms }] (best run) }] }: whole designs through
//       Session.run in a fresh Session each run (no cache), each stage timed from its first
//       progress report to the next stage's (`weft bench --design`, src/bench/designs.rs).
//   { cmd: "scaling-cases" }        → { type: "scaling-cases", names }: benchScalingCases().
//   { cmd: "scaling", name, scale, repeats } → { type: "scaling", name, scale, unit, size,
//       prepareMs, ms: [...], memory: { init, prepared, run } }: one case of `weft bench
//       --scaling` (src/bench/scaling.rs) at one scale: new BenchScaling(name, scale) prepares
//       the input (not timed), run() is timed `repeats` times (default 3, best counts) with
//       performance.now(). wasm memory never shrinks, so the page uses a fresh worker per
//       case×scale and reports run − init as the case's peak memory.
//   { cmd: "graded-inputs" }        → { type: "graded-inputs", ms, inputs: { files: [{ name,
//       bytes }], gcode: { name, bytes }, designs: { surface, edit }, volumeBytes } }: the
//       graded workload (new BenchGraded(), src/bench/graded.rs), its buffers transferred; the
//       page keeps it and hands a copy to each graded case's fresh worker.
//   { cmd: "graded-surface", inputs, repeats } → { type: "graded-surface", passes: [{
//       addFileMs, estimateMs, viewMs, addFileMs2, volumeMs, surfaceMs, triangles }], memory:
//       { init, afterAddFile, afterSurface, end } }: what the page does with a dropped series:
//       Session.addBlob("volume", path, blob) per file, Session.estimate(design) (runDesign
//       asks it first; it reads the volume and makes the surface), inspect(design, "surface",
//       0) (the surface view); then, in a new Session, the stages apart: inspect "axial" (the
//       volume stage), inspect "surface" (the surface stage). Memory: first pass, page path.
//   { cmd: "graded-edit", inputs, repeats } → { type: "graded-edit", passes: [{ addSeriesMs,
//       addGcodeMs, runMs, stages: [{ stage, ms }], edited }], marks: [{ stage, memory }],
//       memory: { init, afterSeries, afterGcode, afterRun, end } }: the series and the G-code
//       added as Blobs, as the page adds dropped files (addBlob reads every G-code line, in
//       pieces), then Session.run(edit design) timed per stage;
//       `marks` holds wasm memory at each stage's first progress report (first pass).
// Run the job in a fresh worker (the page does) so the STL generation does not count in the
// job's linear memory.
import init, { BenchGraded, BenchLattice, BenchPairing, BenchScaling, benchPairingCases, Session, benchAnalyze, benchDesign, benchMeshStl, benchScalingCases } from "../../pkg/weft.js";
import { plain } from "../../www/protocol.js"; // reports as objects (JSON text before wasm API v2)

const ready = init();

const MB = 1e6;

/** Marks `{ stage, t }` of one run (a stage's first progress report) → `[{ stage, ms }]`: a
 *  stage runs until the next stage's first report (the last one until `total`); a stage
 *  reported twice (estimated, then reused from the cache) is summed (src/bench/designs.rs
 *  `timed_run`). */
function stageTimes(marks, total) {
  const stages = [];
  marks.forEach((m, k) => {
    const ms = (k + 1 < marks.length ? marks[k + 1].t : total) - m.t;
    const s = stages.find((x) => x.stage === m.stage);
    if (s) s.ms += ms;
    else stages.push({ stage: m.stage, ms });
  });
  return stages;
}

let resume = null; // the memory step waits for the page's { cmd: "continue", measured }

self.onmessage = async ({ data }) => {
  if (data.cmd === "continue") {
    resume?.(data.measured);
    return;
  }
  try {
    const { memory } = await ready;
    const mem = () => memory.buffer.byteLength;
    if (data.cmd === "stl") {
      const t0 = performance.now();
      const bytes = benchMeshStl(data.triangles);
      const ms = performance.now() - t0;
      self.postMessage({ type: "stl", bytes: bytes.buffer, ms }, [bytes.buffer]);
      return;
    }
    if (data.cmd === "scaling-cases") {
      self.postMessage({ type: "scaling-cases", names: benchScalingCases() });
      return;
    }
    if (data.cmd === "scaling") {
      const init = mem();
      let t = performance.now();
      const b = new BenchScaling(data.name, data.scale);
      const prepareMs = performance.now() - t;
      const prepared = mem();
      const ms = [];
      for (let i = 0; i < (data.repeats ?? 3); i++) {
        t = performance.now();
        b.run();
        ms.push(performance.now() - t);
      }
      const run = mem();
      const size = b.size();
      const unit = b.unit();
      b.free();
      self.postMessage({ type: "scaling", name: data.name, scale: data.scale, unit, size, prepareMs, ms, memory: { init, prepared, run } });
      return;
    }
    if (data.cmd === "pairing") {
      const rows = [];
      for (const name of benchPairingCases()) {
        for (const exact of [false, true]) {
          let t = performance.now();
          const b = new BenchPairing(name, exact);
          const prepareMs = performance.now() - t;
          t = performance.now();
          const stats = JSON.parse(b.run());
          const ms = performance.now() - t;
          b.free();
          rows.push({ name, exact, prepareMs, ms, stats });
        }
      }
      self.postMessage({ type: "pairing", rows, memory: mem() });
      return;
    }
    if (data.cmd === "designs") {
      const rows = [];
      for (const d of data.designs) {
        let best = null;
        const runs = [];
        for (let i = 0; i < (data.repeats ?? 3); i++) {
          const session = new Session();
          const marks = [];
          const t0 = performance.now();
          session.run(d.json, (stage) => {
            if (marks.length === 0 || marks[marks.length - 1].stage !== stage) marks.push({ stage, t: performance.now() - t0 });
          });
          const total = performance.now() - t0;
          session.free();
          runs.push(total);
          const stages = stageTimes(marks, total);
          if (!best || total < best.total) best = { total, stages };
        }
        rows.push({ name: d.name, runs, stages: best.stages });
      }
      self.postMessage({ type: "designs", rows, memory: mem() });
      return;
    }
    if (data.cmd === "graded-inputs") {
      const t = performance.now();
      const b = new BenchGraded();
      const files = b.seriesNames().map((name, i) => ({ name, bytes: b.seriesFile(i).buffer }));
      const gcode = { name: b.gcodeName(), bytes: b.gcode().buffer };
      const inputs = { files, gcode, designs: { surface: b.surfaceDesign(), edit: b.editDesign() }, volumeBytes: b.volumeBytes() };
      b.free();
      const ms = performance.now() - t;
      self.postMessage({ type: "graded-inputs", ms, inputs }, [...files.map((f) => f.bytes), gcode.bytes]);
      return;
    }
    if (data.cmd === "graded-surface") {
      const { files, designs } = data.inputs;
      // As the page does for a dropped folder: one addBlob per file (the page hands the worker
      // each dropped File; its bytes stay in the blob store and are read when the volume is).
      const blobs = files.map((f) => ({ name: f.name, blob: new Blob([f.bytes]) }));
      const load = (session) => {
        const t = performance.now();
        for (const f of blobs) session.addBlob("volume", f.name, f.blob);
        return performance.now() - t;
      };
      const passes = [];
      let memory = null;
      for (let i = 0; i < (data.repeats ?? 3); i++) {
        // The page's path: after a drop it asks Session.estimate first (for a graded job that
        // reads the volume and makes the surface, kept for the run), then shows the views.
        const m = { init: mem() };
        let session = new Session();
        const addFileMs = load(session);
        m.afterAddFile = mem();
        let t = performance.now();
        session.estimate(designs.surface);
        const estimateMs = performance.now() - t;
        t = performance.now();
        const surface = session.inspect(designs.surface, "surface", 0);
        const viewMs = performance.now() - t;
        m.afterSurface = mem();
        session.free();
        // The two stages apart, in a new Session: a slice view needs only the volume stage.
        session = new Session();
        const addFileMs2 = load(session);
        t = performance.now();
        session.inspect(designs.surface, "axial", 0);
        const volumeMs = performance.now() - t;
        t = performance.now();
        session.inspect(designs.surface, "surface", 0);
        const surfaceMs = performance.now() - t;
        session.free();
        passes.push({ addFileMs, estimateMs, viewMs, addFileMs2, volumeMs, surfaceMs, triangles: surface.data.length / 9 });
        memory ??= m;
      }
      self.postMessage({ type: "graded-surface", passes, memory: { ...memory, end: mem() } });
      return;
    }
    if (data.cmd === "graded-edit") {
      const { files, gcode, designs } = data.inputs;
      // Blobs, as the page holds dropped files (made once, outside the timed passes).
      const blobs = files.map((f) => ({ name: f.name, blob: new Blob([f.bytes]) }));
      const gcodeBlob = new Blob([gcode.bytes]);
      const passes = [];
      let memory = null;
      let firstMarks = null;
      for (let i = 0; i < (data.repeats ?? 3); i++) {
        const m = { init: mem() };
        const session = new Session();
        let t = performance.now();
        for (const f of blobs) session.addBlob("volume", f.name, f.blob);
        const addSeriesMs = performance.now() - t;
        m.afterSeries = mem();
        t = performance.now();
        session.addBlob("gcode", gcode.name, gcodeBlob);
        const addGcodeMs = performance.now() - t;
        m.afterGcode = mem();
        const marks = [];
        const t0 = performance.now();
        const report = plain(session.run(designs.edit, (stage) => {
          if (marks.length === 0 || marks[marks.length - 1].stage !== stage) marks.push({ stage, t: performance.now() - t0, memory: mem() });
        }));
        const runMs = performance.now() - t0;
        m.afterRun = mem();
        session.free();
        const edited = report.stages.find((s) => s.stage === "edit")?.metrics.find((x) => x.key === "edited")?.value;
        passes.push({ addSeriesMs, addGcodeMs, runMs, stages: stageTimes(marks, runMs), edited });
        memory ??= m;
        firstMarks ??= marks.map(({ stage, memory }) => ({ stage, memory }));
      }
      self.postMessage({ type: "graded-edit", passes, marks: firstMarks, memory: { ...memory, end: mem() } });
      return;
    }
    if (data.cmd === "lattice") {
      const rows = [];
      for (const which of ["honeycomb-10mm", "disc-48mm", "euler-100k"]) {
        let t = performance.now();
        const b = new BenchLattice(which);
        const prepareMs = performance.now() - t;
        const ms = [];
        let stats = null;
        for (let i = 0; i < (data.repeats ?? 3); i++) {
          t = performance.now();
          const s = b.run();
          ms.push(performance.now() - t);
          if (stats !== null && s !== stats) throw new Error(`${which}: passes differ (${stats} vs ${s})`);
          stats = s;
        }
        rows.push({ which, method: b.method(), targetMs: b.targetMs(), prepareMs, ms, ...JSON.parse(stats) });
        b.free();
      }
      self.postMessage({ type: "lattice", rows, memory: mem() });
      return;
    }
    if (data.cmd === "cache") {
      const bump = (json) => {
        const d = JSON.parse(json);
        d.material.bed_temp_c += 10;
        return JSON.stringify(d);
      };
      const rows = [];
      const workloads = [{ name: "disc-48mm", json: data.discJson, stl: null }];
      if (data.stl) workloads.push({ name: "mesh", json: benchDesign(), stl: new Uint8Array(data.stl) });
      for (const w of workloads) {
        const session = new Session();
        let addFileMs = null;
        if (w.stl) {
          const t = performance.now();
          session.addFile("mesh", "bench.stl", w.stl);
          addFileMs = performance.now() - t;
          w.stl = null;
        }
        let t = performance.now();
        const a = plain(session.run(w.json, () => {}));
        const firstMs = performance.now() - t;
        const edited = bump(w.json);
        t = performance.now();
        const b = plain(session.run(edited, () => {}));
        const secondMs = performance.now() - t;
        session.free();
        const stages = b.stages.map((r) => ({ stage: r.stage, cached: r.cached }));
        const gi = stages.findIndex((r) => r.stage === "gcode");
        const uncached = stages.slice(0, gi < 0 ? stages.length : gi).filter((r) => !r.cached).map((r) => r.stage);
        rows.push({ name: w.name, addFileMs, firstMs, secondMs, stages, uncached, layers: [a.analysis.layers, b.analysis.layers] });
      }
      self.postMessage({ type: "cache", rows, memory: mem() });
      return;
    }
    if (data.cmd === "memory") {
      // measureUserAgentSpecificMemory is not exposed to dedicated workers: the page measures
      // (the whole agent cluster, this worker included) when told, and answers "continue".
      const uaMemory = (phase) => new Promise((ok) => {
        resume = (measured) => { resume = null; ok(measured ?? null); };
        self.postMessage({ type: "phase", phase });
      });
      const init = mem();
      let stl = new Uint8Array(data.stl);
      const stlBytes = stl.byteLength;
      const session = new Session();
      let t = performance.now();
      let stage = "addFile";
      try {
        session.addFile("mesh", "bench.stl", stl);
        stl = null;
        const addFileMs = performance.now() - t;
        const afterAddFile = mem();
        const uaAfterAddFile = await uaMemory("afterAddFile");
        stage = "run";
        t = performance.now();
        const ran = session.run(benchDesign(), () => {});
        const runMs = performance.now() - t;
        const report = plain(ran);
        const afterRun = mem();
        const uaAfterRun = await uaMemory("afterRun");
        session.free();
        self.postMessage({
          type: "memory", stlBytes, addFileMs, runMs, layers: report.analysis.layers,
          memory: { init, afterAddFile, afterRun }, uaMemory: { afterAddFile: uaAfterAddFile, afterRun: uaAfterRun },
        });
      } catch (err) {
        self.postMessage({ type: "error", message: `${stage}: ${String(err?.stack ?? err?.message ?? err)}`, memory: mem(), stlBytes });
      }
      return;
    }
    if (data.cmd !== "run") throw new Error(`unknown command ${data.cmd}`);
    const memInit = mem();
    let stl = data.stl ? new Uint8Array(data.stl) : null;
    let generated = false;
    if (!stl) {
      stl = benchMeshStl(data.triangles ?? 1_000_000);
      generated = true;
    }
    const stlBytes = stl.byteLength;
    const memBeforeJob = mem();

    // Import (Session.addFile reads the mesh once to report problems, and keeps the bytes).
    const session = new Session();
    let t = performance.now();
    session.addFile("mesh", "bench.stl", stl); // (slot, name, bytes): the slice job's mesh slot
    const addFileMs = performance.now() - t;
    stl = null; // the JS copy is no longer needed
    const memAfterAddFile = mem();

    // The run, stage by stage (the stage that reports progress first is timed from then on).
    const stages = [];
    let current = null;
    let stageStart = 0;
    const progress = (stage) => {
      if (stage !== current) {
        const now = performance.now();
        if (current !== null) stages.push({ stage: current, ms: now - stageStart });
        current = stage;
        stageStart = now;
      }
    };
    const design = benchDesign();
    t = performance.now();
    stageStart = t;
    const report = plain(session.run(design, progress));
    const end = performance.now();
    if (current !== null) stages.push({ stage: current, ms: end - stageStart });
    const runMs = end - t;
    const memAfterRun = mem();

    // Analyzer workload: the run's G-code repeated to ~gcodeMb MB.
    const gcode = session.gcode();
    const gcodeBytes = gcode.byteLength;
    session.free();
    const target = (data.gcodeMb ?? 100) * MB;
    const reps = Math.max(1, Math.ceil(target / gcodeBytes));
    const big = new Uint8Array(gcodeBytes * reps);
    for (let i = 0; i < reps; i++) big.set(gcode, i * gcodeBytes);
    t = performance.now();
    const analysis = plain(benchAnalyze(big));
    const analyzeMs = performance.now() - t;

    self.postMessage({
      type: "result",
      triangles: data.triangles ?? null,
      stlBytes,
      generatedInWorker: generated,
      addFileMs,
      stages,
      runMs,
      layers: report.analysis.layers,
      gcodeBytes,
      analyze: { bytes: big.byteLength, ms: analyzeMs, paths: analysis.extrusion_paths },
      memory: { init: memInit, beforeJob: memBeforeJob, afterAddFile: memAfterAddFile, afterRun: memAfterRun, end: mem() },
      userAgent: navigator.userAgent,
    });
  } catch (err) {
    self.postMessage({ type: "error", message: String(err?.stack ?? err?.message ?? err) });
  }
};

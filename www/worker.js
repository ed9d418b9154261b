// Module worker holding the wasm Session. Requests are queued until the module is
// initialised, then handled one at a time (every wasm call is synchronous). Cancel is done by
// the page terminating this worker (which ends the thread pool's workers with it); see main.js.
//
// Threads: the page asks for them in this script's URL (`worker.js?threads=N`, N > 1 only when
// the page is cross-origin isolated). Then the threaded module (pkg/threads/) builds rayon's
// pool of N threads, and the `ready` message hands the page the module and its shared memory:
// the page starts the N pool workers (pool-worker.js), so it can terminate them with this one.
// The core's parallel loops run on them and give the same bytes as on one thread. If the
// threaded module cannot start, the plain one runs on one thread and `ready` says why.
import { MSG, PREVIEW_BUFFERS, plain, transferList } from "./protocol.js";

/** Threads the page asked for (1: the plain module). */
const wanted = Math.max(1, Math.min(64, Number(new URL(self.location.href).searchParams.get("threads")) | 0 || 1));

/** @type {Session|null} */
let session = null;
/** @type {Array<Object>|null} requests waiting for init; null once ready */
let queue = [];
/** @type {WebAssembly.Memory|null} */
let memory = null;
/** key → id of the newest `inspect` request received with that key */
const newestInspect = new Map();

self.onmessage = ({ data }) => {
  if (data?.type === MSG.INSPECT) newestInspect.set(data.key ?? "", data.id);
  if (queue) queue.push(data);
  else if (data?.type === MSG.INSPECT) setTimeout(() => handle(data), 0); // let newer ones arrive first
  else handle(data);
};

/** @type {typeof import("../pkg/weft.js").Session} */
let Session;

/** The threaded module with its pool started, or the plain one: `{ exports, threads, note }`. */
async function start() {
  if (wanted > 1) {
    try {
      const mod = await import("../pkg/threads/weft.js");
      const exports = await mod.default();
      const [module, memory, cancelAt] = mod.threadPoolShare();
      Session = mod.Session;
      return { exports, threads: wanted, note: "", pool: { module, memory, cancelAt }, startPool: () => mod.startThreadPool(wanted) };
    } catch (err) {
      // A browser without wasm threads, or a host without pkg/threads/: one thread.
      const mod = await import("../pkg/weft.js");
      const exports = await mod.default();
      Session = mod.Session;
      return { exports, threads: 1, note: `the threaded module could not start (${messageOf(err)})` };
    }
  }
  const mod = await import("../pkg/weft.js");
  const exports = await mod.default();
  Session = mod.Session;
  return { exports, threads: 1, note: "" };
}

start()
  .then(({ exports, threads, note, pool, startPool }) => {
    memory = pool?.memory ?? exports?.memory ?? null;
    // The page starts the pool's workers on this message; startPool waits until they have
    // all joined (were one never to, the page sees it fail and replaces this worker).
    self.postMessage({ type: MSG.READY, threads, note, pool: pool ?? null });
    startPool?.();
    session = new Session();
    const waiting = queue;
    queue = null;
    for (const msg of waiting) handle(msg);
  })
  .catch((err) => {
    self.postMessage({
      type: MSG.ERROR, id: null, request: "init", fatal: true,
      message: `the WebAssembly module could not start: ${messageOf(err)}`,
    });
  });

function handle(msg) {
  try {
    switch (msg.type) {
      case MSG.LOAD: {
        markStage("load");
        // A Blob (a dropped file) stays where it is and is read in pieces; bytes are copied in.
        const info = plain(msg.blob
          ? session.addBlob(msg.slot, msg.name, msg.blob)
          : session.addFile(msg.slot, msg.name, new Uint8Array(msg.bytes)));
        markStage(null);
        self.postMessage({ type: MSG.LOADED, id: msg.id, slot: msg.slot, name: msg.name, info });
        break;
      }
      case MSG.UNLOAD:
        session.removeFile(msg.name);
        break;
      case MSG.DROP_RECORDINGS:
        session.dropRecordings();
        break;
      case MSG.RUN: {
        const t0 = performance.now();
        const report = plain(session.run(msg.design, progressReporter(msg.id), aheadReporter(msg.id)));
        markStage(null);
        postResult(msg.id, "run", report, t0);
        break;
      }
      case MSG.ESTIMATE:
        self.postMessage({ type: MSG.ESTIMATED, id: msg.id, plan: plain(session.estimate(msg.design)) });
        break;
      case MSG.ANALYZE: {
        const t0 = performance.now();
        markStage("analyze");
        self.postMessage({ type: MSG.PROGRESS, id: msg.id, stage: "analyze", fraction: 0 });
        // A Blob (a dropped file) is checked from its size, then read straight into wasm memory.
        const report = plain(msg.blob
          ? session.analyzeBlob(msg.name, msg.blob)
          : session.analyzeGcode(msg.name, new Uint8Array(msg.bytes)));
        markStage(null);
        postResult(msg.id, "analyze", report, t0);
        break;
      }
      case MSG.INSPECT: {
        const t0 = performance.now();
        if (newestInspect.get(msg.key ?? "") !== msg.id) {
          self.postMessage({
            type: MSG.INSPECTED, id: msg.id, view: msg.view, index: msg.index, shape: "", stride: 1, count: 0,
            data: new Float32Array(0), meta: {}, stale: true, ms: 0,
          });
          break;
        }
        const answer = plain(session.inspect(msg.design, msg.view, Math.max(0, msg.index | 0)));
        const { view, index, shape, stride, count, meta } = answer;
        const data = owned(answer.data, Float32Array);
        const overlay = answer.overlay ? owned(answer.overlay, Float32Array) : null;
        self.postMessage({
          type: MSG.INSPECTED, id: msg.id, view, index, shape, stride, count, data, overlay, meta, ms: performance.now() - t0,
        }, transferList(overlay ? [data, overlay] : [data]));
        break;
      }
      case MSG.CANCEL:
        // Nothing to do: a request that is running cannot see this message (the thread is
        // busy in wasm); the page terminates the worker instead.
        break;
      default:
        throw new Error(`unknown message type ${JSON.stringify(msg.type)}`);
    }
  } catch (err) {
    if (openStage) markStage(null);
    // A trap (panic → unreachable, stack overflow) or a failed memory.grow leaves the wasm
    // instance unusable: ask the page to replace this worker.
    const fatal = err instanceof WebAssembly.RuntimeError || err instanceof RangeError;
    self.postMessage({
      type: MSG.ERROR, id: msg.id ?? null, request: msg.type, name: msg.name,
      message: messageOf(err), fatal,
    });
  }
}

const MAX_MARKS = 1000;
/** Marks made since the timeline was last cleared, and whether a stage's work is under way. */
let marks = 0;
let openStage = false;

/**
 * Marks in this worker's performance timeline where each stage of a run, a file's load or a
 * G-code analysis begins, `weft:stage:<name>` (`<name> (reused)` for one made before), and
 * where the work ends or fails, `weft:stage-end` (`stage` null). DevTools shows them, and the
 * end-to-end checks and tests/e2e/threads-bench.mjs read them (page-helpers.mjs,
 * `stageMarks`). At most MAX_MARKS are kept.
 */
function markStage(stage) {
  if (marks >= MAX_MARKS) {
    performance.clearMarks();
    marks = 0;
  }
  marks += 1;
  openStage = stage != null;
  performance.mark(stage == null ? "weft:stage-end" : `weft:stage:${stage}`);
}

/** Progress callback for Session.run, posting at most ~100 messages per stage. */
function progressReporter(id) {
  let lastStage = "";
  let lastFraction = -1;
  return (stage, fraction) => {
    // A stage made before this run reports only its end.
    if (stage !== lastStage) markStage(fraction === 0 ? stage : `${stage} (reused)`);
    if (stage === lastStage && fraction < 1 && fraction - lastFraction < 0.01) return;
    lastStage = stage;
    lastFraction = fraction;
    self.postMessage({ type: MSG.PROGRESS, id, stage, fraction });
  };
}

/** Ahead callback for Session.run: posts the G-code sent ahead, its buffer transferred. */
function aheadReporter(id) {
  return (info, bytes) => {
    const gcode = owned(bytes, Uint8Array);
    self.postMessage({ type: MSG.AHEAD, id, ...plain(info), gcode }, transferList([gcode]));
  };
}

function postResult(id, request, report, t0) {
  const preview = {};
  for (const [key, [method, Type]] of Object.entries(PREVIEW_BUFFERS)) {
    preview[key] = owned(session[method](), Type);
  }
  const gcode = owned(session.gcode(), Uint8Array);
  const bgcode = owned(session.bgcode(), Uint8Array);
  self.postMessage(
    { type: MSG.RESULT, id, request, report, preview, gcode, bgcode, ms: performance.now() - t0 },
    transferList([...Object.values(preview), gcode, bgcode]),
  );
}

/**
 * A typed array that owns its whole buffer, so the buffer can be transferred. wasm-bindgen
 * already copies Vec<T> results out of wasm memory; a view into the wasm memory (or any
 * other shared buffer) is copied here so the memory is never detached.
 */
function owned(array, Type) {
  if (!array) return new Type(0);
  if (!(array instanceof Type)) array = Type.from(array);
  const whole = array.byteOffset === 0 && array.byteLength === array.buffer.byteLength;
  const shared = typeof SharedArrayBuffer !== "undefined" && array.buffer instanceof SharedArrayBuffer;
  const wasmMemory = memory !== null && array.buffer === memory.buffer;
  return whole && !shared && !wasmMemory ? array : array.slice();
}

function messageOf(err) {
  if (err instanceof Error) return err.message || String(err);
  return typeof err === "string" ? err : JSON.stringify(err);
}

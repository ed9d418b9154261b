// The worker client: starts worker.js (and its thread pool's pool-worker.js), sends it the
// typed requests of protocol.js and routes the answers, restarts it on a crash or Cancel with
// every loaded file sent again, and keeps the progress bar of the work going on. Its
// bookkeeping is state.client (the worker, pending requests, threads) and state.jobs (the
// work going on); `workers` and `jobs` here are the operations on them.
import { state } from "./state.js";
import { MSG } from "./protocol.js";
import { $, humanBytes } from "./util.js";
import { showError, showNotice } from "./messages.js";

const PROGRESS_DELAY_MS = 500;

// ---------------------------------------------------------------------------------------
// Worker management
// ---------------------------------------------------------------------------------------
export const workers = {
  start() {
    state.client.generation++;
    const ask = threadsToAsk(state.client.poolBroken);
    state.client.threads = { ...ask, used: null };
    showThreads();
    const url = new URL("./worker.js", import.meta.url);
    if (ask.asked > 1) url.searchParams.set("threads", String(ask.asked));
    const w = new Worker(url, { type: "module", name: `weft-${state.client.generation}` });
    state.client.worker = w;
    w.onmessage = ({ data }) => workers.onMessage(w, data);
    w.onerror = (e) => {
      e.preventDefault();
      if (w === state.client.worker) workers.crashed(e.message || "the worker script failed");
    };
    w.onmessageerror = () => {
      if (w === state.client.worker) workers.crashed("a message could not be read");
    };
    // Give the new worker every file the page holds, in its slot (Blob handles, not copies).
    for (const f of state.files.values()) {
      workers.request({ type: MSG.LOAD, slot: f.slot, name: f.name, blob: f.blob }).catch(() => {});
    }
  },

  /**
   * Starts the pool's threads: one pool worker each, joining the worker's module and shared
   * memory. Runs the worker has queued start as they join.
   */
  startPool(w, { module, memory }, threads) {
    for (let i = 0; i < threads; i++) {
      const p = new Worker(new URL("./pool-worker.js", import.meta.url), { type: "module", name: `weft-${state.client.generation}-thread-${i + 1}` });
      const failed = (message) => {
        if (w !== state.client.worker) return;
        state.client.poolBroken = `the thread pool's workers could not run (${message})`;
        workers.crashed(state.client.poolBroken);
      };
      p.onmessage = ({ data }) => { if (data?.type === "failed") failed(data.message); };
      p.onerror = (e) => { e.preventDefault(); failed(e.message || "a pool worker stopped"); };
      p.postMessage({ module, memory });
      state.client.pool.push(p);
    }
  },

  /**
   * Terminates the worker and every pool worker now. A worker busy in wasm dies only two
   * seconds after terminate() (Chromium), so the threaded module is first told through its
   * shared memory: its loops skip what has not started and the run throws (par::cancel_flag).
   */
  stop() {
    if (state.client.cancelWord) {
      try {
        Atomics.store(new Int32Array(state.client.cancelWord.memory.buffer), state.client.cancelWord.cancelAt >>> 2, 1);
      } catch { /* terminate() alone, then */ }
      state.client.cancelWord = null;
    }
    state.client.worker?.terminate();
    for (const p of state.client.pool) p.terminate();
    state.client.pool = [];
    state.client.worker = null;
  },

  /** Stops all work now (terminate) and starts a fresh worker with the files reloaded. */
  restart(reason) {
    workers.stop();
    const stopped = new Error(reason ?? "cancelled");
    stopped.cancelled = true;
    for (const p of state.client.pending.values()) p.reject(stopped);
    state.client.pending.clear();
    workers.start();
  },

  crashed(message) {
    const now = Date.now();
    state.client.recentCrashes = state.client.recentCrashes.filter((t) => now - t < 10000);
    state.client.recentCrashes.push(now);
    if (state.client.recentCrashes.length > 3) {
      workers.stop();
      const stopped = new Error(message);
      stopped.cancelled = true; // reported below
      for (const p of state.client.pending.values()) p.reject(stopped);
      state.client.pending.clear();
      showError(`The worker keeps stopping (${message}). Your design is kept; reload the page to try again.`);
      return;
    }
    workers.restart(message);
    showError(`The worker stopped (${message}); restarted — your design is kept.`);
  },

  /** Sends a request; resolves with the worker's answer. Transfers `bytes` if present. */
  request(msg, onProgress, onAhead) {
    if (!state.client.worker) workers.start();
    const id = state.client.nextId++;
    msg.id = id;
    return new Promise((resolve, reject) => {
      state.client.pending.set(id, { resolve, reject, type: msg.type, onProgress, onAhead });
      state.client.worker.postMessage(msg, msg.bytes ? [msg.bytes] : []);
    });
  },

  /** Sends a message that is not answered (unload, cancel). */
  post(msg) {
    if (!state.client.worker) return;
    msg.id = state.client.nextId++;
    state.client.worker.postMessage(msg);
  },

  onMessage(w, msg) {
    if (w !== state.client.worker) return; // a terminated worker's late message
    if (msg.type === MSG.READY) {
      state.client.threads = { ...state.client.threads, used: msg.threads ?? 1, note: msg.note || state.client.threads.note };
      if (msg.pool) {
        state.client.cancelWord = { memory: msg.pool.memory, cancelAt: msg.pool.cancelAt };
        workers.startPool(w, msg.pool, msg.threads);
      }
      showThreads();
      return;
    }
    if (msg.type === MSG.ERROR && (msg.fatal || msg.id === null)) {
      // The wasm instance is unusable (trap, out of memory, no module): restart, which
      // rejects the pending requests quietly, and say so once.
      workers.crashed(msg.message);
      return;
    }
    const p = state.client.pending.get(msg.id);
    if (msg.type === MSG.PROGRESS) {
      p?.onProgress?.(msg.stage, msg.fraction);
      return;
    }
    if (msg.type === MSG.AHEAD) {
      p?.onAhead?.(msg);
      return;
    }
    if (!p) {
      if (msg.type === MSG.ERROR) showError(msg.message); // e.g. a failed unload
      return;
    }
    state.client.pending.delete(msg.id);
    if (msg.type === MSG.ERROR) p.reject(new Error(msg.message));
    else p.resolve(msg);
  },
};

// --- jobs and the progress bar ----------------------------------------------------------
export const jobs = {
  begin(label) {
    const token = state.jobs.nextToken++;
    state.jobs.active.set(token, label);
    jobs.progress(label, null);
    if (!state.jobs.timer && $("progress").hidden) {
      state.jobs.timer = setTimeout(() => {
        state.jobs.timer = 0;
        if (state.jobs.active.size) $("progress").hidden = false;
      }, PROGRESS_DELAY_MS);
    }
    document.body.classList.add("busy");
    return token;
  },
  end(token) {
    state.jobs.active.delete(token);
    if (state.jobs.active.size) return;
    clearTimeout(state.jobs.timer);
    state.jobs.timer = 0;
    $("progress").hidden = true;
    jobs.ahead(null);
    document.body.classList.remove("busy");
  },
  endAll() {
    for (const t of [...state.jobs.active.keys()]) jobs.end(t);
  },
  /**
   * G-code a stage sent ahead (protocol AheadMessage) → a download link beside the bar while
   * the run goes on (null: remove it). The finished run's G-code replaces it.
   */
  ahead(msg, fileName) {
    const link = $("progress-ahead");
    if (link.href) URL.revokeObjectURL(link.href);
    link.removeAttribute("href");
    link.hidden = !msg;
    if (!msg) return;
    link.href = URL.createObjectURL(new Blob([msg.gcode], { type: "text/plain" }));
    link.download = fileName;
    link.textContent = `Start printing: ${msg.label} (${humanBytes(msg.gcode.byteLength)})`;
    link.title = "G-code fixed already: the final file's moves begin with these, while the rest is planned";
    $("progress").hidden = false;
  },
  /** stage progress → overall bar + "Slicing layers… 42%" label */
  progress(stage, fraction) {
    const bar = $("progress-bar");
    const i = state.jobs.stages.findIndex((s) => s.name === stage);
    const label = i >= 0 ? state.jobs.stages[i].label ?? stage : stage;
    if (fraction === null) {
      bar.removeAttribute("value"); // indeterminate
      $("progress-label").textContent = `${label}…`;
      return;
    }
    const overall = i < 0 ? fraction : (i + Math.min(1, Math.max(0, fraction))) / state.jobs.stages.length;
    bar.value = overall;
    $("progress-label").textContent = `${label}… ${Math.round(overall * 100)}%`;
    $("progress-label").dataset.stage = stage;
  },
};

export function cancel() {
  if (!state.jobs.active.size) return;
  workers.restart("cancelled");
  jobs.endAll();
  showNotice("Cancelled: the worker was stopped and restarted. Your design is kept.");
}

/**
 * Threads to ask the worker for. Shared memory needs a cross-origin isolated page (COOP/COEP
 * headers from the server, or from sw.js on a plain static host); without it the plain module
 * runs on one thread. `?threads=N` in the address asks for N (1: the plain module), else every
 * core the browser reports. The G-code is the same bytes whatever the count.
 */
function threadsToAsk(poolBroken = "") {
  if (poolBroken) return { asked: 1, cores: Math.max(1, navigator.hardwareConcurrency | 0 || 1), isolated: self.crossOriginIsolated === true, note: poolBroken };
  const cores = Math.max(1, navigator.hardwareConcurrency | 0 || 1);
  const isolated = self.crossOriginIsolated === true && typeof SharedArrayBuffer === "function";
  const param = new URLSearchParams(location.search).get("threads");
  const wanted = param !== null && /^\d+$/.test(param) ? Math.min(64, Math.max(1, Number(param))) : Math.min(cores, 16);
  if (!isolated) {
    const note = self.crossOriginIsolated === true ? "this browser has no SharedArrayBuffer"
      : window.parent !== window ? "weft is embedded in another page, and browsers share no memory inside a frame unless that page is cross-origin isolated too"
        : "the page is not cross-origin isolated (its host sends no COOP/COEP headers and no service worker added them)";
    return { asked: 1, cores, isolated: false, note };
  }
  return { asked: wanted, cores, isolated: true, note: wanted === 1 && param !== null ? "?threads=1 in the address" : "" };
}

/** Why the worker computes on one thread, as a sentence ("" when it uses more). */
export function threadsWhy() {
  const t = state.client.threads;
  if ((t.used ?? t.asked) > 1) return "";
  return t.note ? `One thread: ${t.note}.` : "One thread: this machine reports one core.";
}

/** The always-shown thread line: threads in use, and why only one. */
function showThreads() {
  const el = $("threads");
  if (!el) return;
  const t = state.client.threads;
  const n = t.used ?? t.asked;
  el.textContent = `${t.used === null ? "starting " : ""}${n} thread${n === 1 ? "" : "s"}${n === 1 && t.note ? " (no shared memory here)" : ""}`;
  el.title = n > 1
    ? `The worker computes on ${n} threads (web workers sharing its memory; ${t.cores} core${t.cores === 1 ? "" : "s"} reported). Same G-code at any thread count.`
    : `${threadsWhy()} Same G-code at any thread count, only slower.`;
  el.dataset.threads = String(n);
  el.classList.toggle("one", n === 1 && Boolean(t.note));
}

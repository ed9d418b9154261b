// Messages between the page (main.js) and the wasm worker (worker.js).
//
// Every request from the page carries an `id`; the worker answers each request with exactly
// one `loaded` / `estimated` / `result` / `inspected` / `error` message bearing the same id (plus any number
// of `progress` messages for `run` and `analyze`, and of `ahead` messages for `run`); `unload`, `drop-recordings` and `cancel` are not answered
// unless they fail. Bytes travel in ArrayBuffers listed in the transfer list of postMessage,
// so they move between threads instead of being copied.
//
// Nothing here knows a job kind, a stage or a feature: those come from designSchema() and
// the run report.

/** Message types. */
export const MSG = Object.freeze({
  // page → worker
  /** Parse a file into an input slot and keep it in the session. @see LoadRequest */
  LOAD: "load",
  /** Forget a loaded file. @see UnloadRequest */
  UNLOAD: "unload",
  /** Drop what the steps of "How it works" recorded (closed): `{type}`, not answered. */
  DROP_RECORDINGS: "drop-recordings",
  /** Run a design. @see RunRequest */
  RUN: "run",
  /** State a design's work before running it (answered by `estimated`). @see EstimateRequest */
  ESTIMATE: "estimate",
  /** Analyse a G-code file. @see AnalyzeRequest */
  ANALYZE: "analyze",
  /** One index of one of the job kind's views (answered by `inspected`). @see InspectRequest */
  INSPECT: "inspect",
  /** Advisory: the page stops work by terminating the worker; see main.js. */
  CANCEL: "cancel",
  // worker → page
  /**
   * The wasm module is initialised; queued requests are being handled. Carries `threads` (the
   * count the core computes on: the pool's size, or 1 for the plain module), `note` (why
   * fewer than asked, or "") and `pool`: null, or `{module, memory, cancelAt}`: the page
   * starts `threads` pool workers (pool-worker.js) with the module and the shared memory, and
   * on Cancel sets the 32-bit word at byte `cancelAt` of that memory before terminating.
   */
  READY: "ready",
  /** Answer to `load`. @see LoadedMessage */
  LOADED: "loaded",
  /** Stage progress of a `run` / `analyze`. @see ProgressMessage */
  PROGRESS: "progress",
  /** G-code a stage of a `run` sends ahead while the run goes on. @see AheadMessage */
  AHEAD: "ahead",
  /** Answer to `run` / `analyze`. @see ResultMessage */
  RESULT: "result",
  /** Answer to `estimate`. @see EstimatedMessage */
  ESTIMATED: "estimated",
  /** Answer to `inspect`. @see InspectedMessage */
  INSPECTED: "inspected",
  /** A request failed (or the module could not start). @see ErrorMessage */
  ERROR: "error",
});

/**
 * Preview buffers of a result: message key → [Session method, typed array constructor].
 * The worker copies nothing: each typed array returned by wasm-bindgen owns its buffer,
 * which is transferred.
 */
export const PREVIEW_BUFFERS = Object.freeze({
  positions: ["previewPositions", Float32Array],
  feature: ["previewFeature", Uint8Array],
  path: ["previewPath", Uint32Array],
  flow: ["previewFlow", Float32Array],
  ePerMm: ["previewEPerMm", Float32Array],
  speed: ["previewSpeed", Float32Array],
  width: ["previewWidth", Float32Array],
  layerStart: ["previewLayerStart", Uint32Array],
  travel: ["previewTravel", Float32Array],
  travelLayerStart: ["previewTravelLayerStart", Uint32Array],
  layerZ: ["previewLayerZ", Float32Array],
  bedSize: ["bedSize", Float64Array],
  axis: ["previewAxis", Float32Array],
  segmentMove: ["previewSegmentMove", Uint32Array],
  travelMove: ["previewTravelMove", Uint32Array],
});

/**
 * @typedef {Object} LoadRequest
 * @property {"load"} type
 * @property {number} id
 * @property {string} slot     input slot name of the job kind (schema.job_kinds[].slots[].name)
 * @property {string} name     file name, e.g. "part.stl"
 * @property {Blob} [blob]    the dropped file (a handle, not a copy: volumes and G-code are read
 *                            from it in pieces, meshes read in whole); or
 * @property {ArrayBuffer} [bytes]  transferred bytes (benchmarks, tests)
 */
/**
 * @typedef {Object} UnloadRequest
 * @property {"unload"} type
 * @property {number} id
 * @property {string} name
 */
/**
 * @typedef {Object} RunRequest
 * @property {"run"} type
 * @property {number} id
 * @property {string} design   design JSON
 */
/**
 * @typedef {Object} EstimateRequest
 * @property {"estimate"} type
 * @property {number} id
 * @property {string} design   design JSON
 */
/**
 * @typedef {Object} EstimatedMessage
 * @property {"estimated"} type
 * @property {number} id
 * @property {{stages: Object[], seconds: number, peak_bytes: number, segments: number,
 *   gcode_bytes: number, ask?: string, refused?: [string, {what: string, value: number,
 *   limit: number, unit: string, fix: string}]}} plan  every stage's estimate (budget::Plan)
 */
/**
 * @typedef {Object} AnalyzeRequest
 * @property {"analyze"} type
 * @property {number} id
 * @property {string} name
 * @property {Blob} [blob]        the dropped file, read in the worker in pieces (no copy here)
 * @property {ArrayBuffer} [bytes] G-code, transferred (when there is no Blob)
 */
/**
 * @typedef {Object} InspectRequest
 * @property {"inspect"} type
 * @property {number} id
 * @property {string} design   design JSON
 * @property {string} view     a view id of the design's job kind (schema.job_kinds[].views[].id)
 * @property {number} index    0-based index (layer, slice, …)
 * @property {string} [key]    requests with the same key supersede each other: when a newer
 *                             one is already waiting, the older is answered `stale` unrun
 */
/**
 * @typedef {Object} LoadedMessage
 * @property {"loaded"} type
 * @property {number} id
 * @property {string} slot
 * @property {string} name
 * @property {{slot: string, name: string, kind: string, summary: string, report: Object}} info
 */
/**
 * @typedef {Object} ProgressMessage
 * @property {"progress"} type
 * @property {number} id
 * @property {string} stage     a stage name of the job kind
 * @property {number} fraction  0..1 within the stage
 */
/**
 * @typedef {Object} AheadMessage
 * @property {"ahead"} type
 * @property {number} id
 * @property {string} stage     the stage sending it
 * @property {string} label     what it holds, in words ("the first 200 of 6120 beams")
 * @property {number} done      items it holds
 * @property {number} total     items of the whole run
 * @property {Uint8Array} gcode  transferred: a file a printer can start on; the result's G-code
 *                               moves begin with its moves (its header counts only them)
 */
/**
 * @typedef {Object} InspectedMessage
 * @property {"inspected"} type
 * @property {number} id
 * @property {string} view
 * @property {number} index     the index answered
 * @property {string} shape     "lines2d" | "lines3d" | "image" | "mesh"
 * @property {number} stride    floats per item
 * @property {number} count     valid indices are 0..count-1
 * @property {Float32Array} data  transferred; empty when stale
 * @property {Object} meta
 * @property {boolean} [stale]  skipped because a newer request with the same key was waiting
 * @property {number} ms
 */
/**
 * @typedef {Object} PreviewBuffers
 * @property {Float32Array} positions   extrusion segments, x0 y0 z0 x1 y1 z1 (mm)
 * @property {Uint8Array} feature       per segment feature code (schema.features)
 * @property {Uint32Array} path         per segment path index
 * @property {Float32Array} flow        per segment volumetric flow, mm³/s
 * @property {Float32Array} [ePerMm]    per segment filament per mm (ΔE / length), mm/mm
 * @property {Float32Array} [speed]     per segment feed rate, mm/s
 * @property {Float32Array} width       per segment width, mm
 * @property {Uint32Array} layerStart   first segment of each layer + final entry = segment count
 * @property {Float32Array} travel      travel segments, 6 floats each
 * @property {Uint32Array} travelLayerStart
 * @property {Float32Array} layerZ
 * @property {Float64Array} bedSize     [x, y, z] mm
 * @property {Float32Array} axis        3 floats per segment: tool axis at its end (empty: none)
 * @property {Uint32Array} segmentMove  per segment, index of its G-code move (increasing)
 * @property {Uint32Array} travelMove   per travel segment, index of its G-code move
 */
/**
 * @typedef {Object} ResultMessage
 * @property {"result"} type
 * @property {number} id
 * @property {"run"|"analyze"} request
 * @property {Object} report       the run report ({name, job, stages, gcode, analysis}) or {analysis}
 * @property {PreviewBuffers} preview  every buffer transferred
 * @property {Uint8Array} gcode    transferred
 * @property {Uint8Array} bgcode   transferred: the Prusa binary G-code when the printer asks for it, else empty
 * @property {number} ms           worker time spent
 */
/**
 * @typedef {Object} ErrorMessage
 * @property {"error"} type
 * @property {number|null} id   the failed request (null: module start-up)
 * @property {string} request   the failed request's type, or "init"
 * @property {string} message   the message from Rust (or JS)
 * @property {string} [name]    file name for load / analyze
 * @property {boolean} [fatal]  the wasm instance trapped or ran out of memory: restart the worker
 */

/**
 * Typed arrays to put in a transfer list: each distinct, non-empty buffer once.
 * @param {ArrayBufferView[]} views
 * @returns {ArrayBuffer[]}
 */
export function transferList(views) {
  const seen = new Set();
  for (const v of views) if (v && v.buffer && v.buffer.byteLength > 0) seen.add(v.buffer);
  return [...seen];
}

/**
 * A value from wasm as plain data: JSON text parsed, `Map`s (serde-wasm-bindgen's default for
 * maps) turned into objects. Typed arrays are kept as they are.
 */
export function plain(value) {
  if (typeof value === "string") {
    try {
      return JSON.parse(value);
    } catch {
      return value;
    }
  }
  return unmap(value);
}

function unmap(v) {
  if (v instanceof Map) {
    const o = {};
    for (const [k, x] of v) o[k] = unmap(x);
    return o;
  }
  if (Array.isArray(v)) return v.map(unmap);
  if (v && typeof v === "object" && !ArrayBuffer.isView(v) && !(v instanceof ArrayBuffer)) {
    const o = {};
    for (const k of Object.keys(v)) o[k] = unmap(v[k]);
    return o;
  }
  return v;
}

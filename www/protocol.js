// Messages between the page (main.js) and the wasm worker (worker.js).
//
// Every request from the page carries an `id`; the worker answers each request with exactly
// one `loaded` / `result` / `layer2d` / `error` message bearing the same id (plus any number of `progress`
// messages for `run` and `analyze`). Bytes travel in ArrayBuffers listed in the transfer list
// of postMessage, so they move between threads instead of being copied.

/** Message types. */
export const MSG = Object.freeze({
  // page → worker
  /** Parse a mesh file and keep it in the session. @see LoadRequest */
  LOAD: "load",
  /** Run a design (slice job). @see RunRequest */
  RUN: "run",
  /** Analyse a G-code file. @see AnalyzeRequest */
  ANALYZE: "analyze",
  /** Lattice strokes of one layer for the 2D preview (answered by `layer2d`). @see Layer2dRequest */
  LAYER2D: "layer2d",
  /** Advisory: the page stops work by terminating the worker; see main.js. @see CancelRequest */
  CANCEL: "cancel",
  // worker → page
  /** The wasm module is initialised; queued requests are being handled. */
  READY: "ready",
  /** Answer to `load`. @see LoadedMessage */
  LOADED: "loaded",
  /** Stage progress of a `run` / `analyze`. @see ProgressMessage */
  PROGRESS: "progress",
  /** Answer to `layer2d` (same type name). @see Layer2dMessage */
  LAYER2D_RESULT: "layer2d",
  /** Answer to `run` / `analyze`. @see ResultMessage */
  RESULT: "result",
  /** A request failed (or the module could not start). @see ErrorMessage */
  ERROR: "error",
});

/** Pipeline stage names reported by Session.run, in order. */
export const STAGES = Object.freeze(["import", "slice", "lattice", "paths", "nonplanar", "gcode", "analyze"]);

/** The stages each job kind goes through, in order (for the overall progress bar). */
export const JOB_STAGES = Object.freeze({
  slice: Object.freeze(["import", "slice", "gcode", "analyze"]),
  lattice: Object.freeze(["import", "slice", "lattice", "paths", "nonplanar", "gcode", "analyze"]),
});

/** Floats per segment of a `layer2d` answer: x0 y0 x1 y1 feature-code (mm). */
export const LAYER2D_STRIDE = 5;

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
  width: ["previewWidth", Float32Array],
  layerStart: ["previewLayerStart", Uint32Array],
  travel: ["previewTravel", Float32Array],
  travelLayerStart: ["previewTravelLayerStart", Uint32Array],
  layerZ: ["previewLayerZ", Float32Array],
  bedSize: ["bedSize", Float64Array],
});

/** Feature codes of previewFeature(), index = code (255 = unknown). */
export const FEATURES = Object.freeze([
  "External perimeter",
  "Perimeter",
  "Internal infill",
  "Solid infill",
  "Lattice",
  "Contour",
  "Handle",
  "Skirt/Brim",
]);
export const FEATURE_UNKNOWN = 255;

/**
 * @typedef {Object} LoadRequest
 * @property {"load"} type
 * @property {number} id
 * @property {string} name     file name, e.g. "part.stl"
 * @property {ArrayBuffer} bytes  transferred (the page keeps its own copy for restarts)
 * @property {boolean} [silent]  re-load after a worker restart: no UI feedback wanted
 */
/**
 * @typedef {Object} RunRequest
 * @property {"run"} type
 * @property {number} id
 * @property {string} design   design JSON
 */
/**
 * @typedef {Object} AnalyzeRequest
 * @property {"analyze"} type
 * @property {number} id
 * @property {string} name
 * @property {ArrayBuffer} bytes  G-code, transferred
 */
/**
 * @typedef {Object} Layer2dRequest
 * @property {"layer2d"} type
 * @property {number} id
 * @property {string} design   design JSON (a lattice job)
 * @property {number} layer    0-based layer (clamped to the last layer by the worker)
 * @property {string} [key]    requests with the same key supersede each other: when a newer
 *                             one is already waiting, the older is answered `stale` unrun
 */
/**
 * @typedef {Object} CancelRequest
 * @property {"cancel"} type
 * @property {number} id  the request to cancel
 */
/**
 * @typedef {Object} LoadedMessage
 * @property {"loaded"} type
 * @property {number} id
 * @property {string} name
 * @property {Object} report  import report {format, triangles, vertices, open_edges, ...}
 */
/**
 * @typedef {Object} ProgressMessage
 * @property {"progress"} type
 * @property {number} id
 * @property {string} stage     one of STAGES
 * @property {number} fraction  0..1 within the stage
 */
/**
 * @typedef {Object} Layer2dMessage
 * @property {"layer2d"} type
 * @property {number} id
 * @property {number} layer
 * @property {Float32Array} segments  LAYER2D_STRIDE floats per segment (transferred); empty when stale
 * @property {boolean} [stale]        skipped because a newer request with the same key was waiting
 * @property {number} ms
 */
/**
 * @typedef {Object} PreviewBuffers
 * @property {Float32Array} positions   extrusion segments, x0 y0 z0 x1 y1 z1 (mm)
 * @property {Uint8Array} feature       per segment feature code (FEATURES)
 * @property {Uint32Array} path         per segment path index
 * @property {Float32Array} flow        per segment volumetric flow, mm³/s
 * @property {Float32Array} width       per segment width, mm
 * @property {Uint32Array} layerStart   first segment of each layer + final entry = segment count
 * @property {Float32Array} travel      travel segments, 6 floats each
 * @property {Uint32Array} travelLayerStart
 * @property {Float32Array} layerZ
 * @property {Float64Array} bedSize     [x, y, z] mm
 */
/**
 * @typedef {Object} ResultMessage
 * @property {"result"} type
 * @property {number} id
 * @property {"run"|"analyze"} request
 * @property {Object} report       the run / analysis report (parsed JSON)
 * @property {PreviewBuffers} preview  every buffer transferred
 * @property {Uint8Array} gcode    transferred
 * @property {number} ms           worker time spent
 */
/**
 * @typedef {Object} ErrorMessage
 * @property {"error"} type
 * @property {number|null} id   the failed request (null: module start-up)
 * @property {string} request   "load" | "run" | "analyze" | "layer2d" | "init"
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

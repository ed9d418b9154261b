// The page's state, in one place: every value the page's modules change while it runs lives
// in `state` below (the design and its undo stacks, loaded files, the result and estimate
// shown, the schema, the registries of what the form, slots and views have built, the worker
// client's bookkeeping, sequence numbers and timers). The other modules keep no module-level
// variables of their own, only constants and, where said, a private cache.
//
// Nothing here does anything: the modules that own a part of the state (named beside it)
// change it.

export const state = {
  // --- set once at start-up (main.js) ---------------------------------------------------
  /** the wasm module, the page's own main-thread instance (schema, validation, share codec) */
  weft: null,
  /** designSchema(): fields, features, job kinds (slots, stages, views), shapes, patterns */
  schema: { version: 1, fields: [], features: [], job_kinds: [], builtin_shapes: [], patterns: [] },
  /** feature code → {label, color} (schema.features) */
  styles: new Map(),
  /** The default design (parsed once): its name, job kind and slot values. */
  defaults: null,
  /** the 3D preview (preview.js's Preview), null when it could not start */
  preview: null,
  /** Opened as the embedded weft (embed.html → index.html?embed, see embed.js). */
  embedded: new URLSearchParams(globalThis.location?.search ?? "").has("embed"),
  /** The embedded weft: the design paths its link names, the only fields the form shows; else null. */
  embedFields: null,

  // --- the design (design.js) -----------------------------------------------------------
  /** current design, normalized JSON (the source of truth) and its parse */
  json: "",
  design: null,
  undo: [],
  redo: [],
  /**
   * Names the page gave (the default design's, the examples', dropped files' stems): a design
   * with one of these follows a dropped part's name; a name the user typed or loaded stays.
   */
  autoNames: new Set(),

  // --- loaded files (slots.js) ----------------------------------------------------------
  /**
   * Loaded files: name → {slot, name, blob: Blob, info}. The dropped File itself (its bytes
   * stay in the browser's blob store, on disk for a dropped file): the worker gets the same
   * Blob (no copy) and reads volumes and G-code from it in pieces; share links read it.
   */
  files: new Map(),
  /**
   * Bumped whenever a loaded file is added, replaced or removed: with the design JSON it says
   * what a result or an estimate was made from (a file dropped again under the same name
   * changes no JSON).
   */
  filesVersion: 0,
  /** Nesting depth of dragenter/dragleave over the page while files are dragged over it. */
  dropDepth: 0,

  // --- results and estimates (results.js, actions.js) -----------------------------------
  /**
   * last result shown: {report, gcode: Uint8Array, fileName, ms, json, files}; `json` and
   * `files` (filesVersion) are what it was made from (json null for a G-code file read as it
   * is), so an edit marks it out of date.
   */
  result: null,
  /**
   * The result pinned for comparison (compare.js): {result, data (its preview buffers), origin,
   * json, design, name, at, stale, from: "pinned"|"link"}, or null.
   */
  pinned: null,
  /** Results shown since the page opened (a test hook). */
  resultCount: 0,
  /** the estimate of the current design: {json, files, plan} or {json, files, error} */
  estimate: null,
  /** The pending debounced estimate (setTimeout id) and the latest estimate request's number. */
  estimateTimer: 0,
  estimateSeq: 0,
  /** Number of the latest run or G-code read: an older run's answer is not shown. */
  latestRun: 0,
  /** chosen group (e.g. layer) per stage card (report.js) */
  groups: new Map(),
  /** When a worker crash was last reported (ms), so a result does not hide it at once. */
  crashShownAt: 0,

  // --- what the form, the slots and the views have built --------------------------------
  /** path → {f, inputs, error, wrap, doc, dirty?, picker?}: the form's fields (form.js) */
  fieldViews: new Map(),
  /** The form's shape (job kind, slots, field paths) it was last built for (form.js). */
  formKey: null,
  /** slot name → {slot, card, fields, source, extra, list, note, input} (slots.js) */
  slotCards: new Map(),
  /** view id → {view, card, canvas, range, number, info, legend, last, seq, timer, count, answers, items} (view-cards.js) */
  viewCards: new Map(),
  /** The job kind the view cards were built for (view-cards.js). */
  viewsKey: null,
  /** The "How it works" card: its steps, the one shown, open or closed, the last answer (steps.js). */
  steps: null,

  // --- the worker client (worker-client.js) ---------------------------------------------
  client: {
    /** @type {Worker|null} */
    worker: null,
    generation: 0,
    nextId: 1,
    /** id → {resolve, reject, type, onProgress} */
    pending: new Map(),
    recentCrashes: [],
    /** What the worker was asked for and uses (see threadsToAsk and the `ready` message). */
    threads: { asked: 1, used: null, cores: 1, isolated: false, note: "" },
    /** The current worker's pool workers (pool-worker.js), terminated with it. */
    pool: [],
    /** Why the pool's workers cannot start here ("" until they fail once): one thread from then on. */
    poolBroken: "",
    /** Where Cancel is said to the threaded module's loops: {memory, cancelAt} (null: plain module). */
    cancelWord: null,
  },
  /** Work going on, for the progress bar (worker-client.js's `jobs`). */
  jobs: {
    active: new Map(), // token → label
    /** stages of the running job ([{name, label}] from the job kind), for the overall bar */
    stages: [],
    timer: 0,
    nextToken: 1,
  },
};

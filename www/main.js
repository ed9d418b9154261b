// The page: design form, files, worker management, results. UI only: everything that can
// take time runs in worker.js; the cheap synchronous calls (schema, validation, share codec)
// use a wasm instance of our own.
import { MSG, STAGES, JOB_STAGES, LAYER2D_STRIDE } from "./protocol.js";
import { drawSegments2d, renderScorePlot, renderPathClasses, renderPathTable, FEATURE_COLORS_2D } from "./lattice.js";

const $ = (id) => document.getElementById(id);
const STORAGE_KEY = "weft.design";
const UNDO_LIMIT = 200;
const PROGRESS_DELAY_MS = 500;
const MESH_EXT = ["stl", "obj", "3mf"];
const GCODE_EXT = ["gcode", "gco", "g"];
const LAYER2D_DEBOUNCE_MS = 200;
/** Side of the square a pattern thumbnail shows, mm. */
const THUMB_MM = 6;
/** Parameters of the built-in shapes when the schema does not give defaults. */
const SHAPE_DEFAULTS = {
  cube: { shape: "cube", size: [20, 20, 20] },
  sphere: { shape: "sphere", radius: 10, segments: 64 },
  cylinder: { shape: "cylinder", radius: 10, height: 20, segments: 64 },
};

let weft; // the wasm module (main-thread instance)
let preview = null;
let schema = { fields: [], job_kinds: ["slice"], builtin_shapes: Object.keys(SHAPE_DEFAULTS) };

const state = {
  /** current design, normalized JSON (the source of truth) and its parse */
  json: "",
  design: null,
  undo: [],
  redo: [],
  /** loaded mesh files: name → ArrayBuffer (the page's copy; the worker gets copies) */
  files: new Map(),
  /** last result shown: {report, gcode: Uint8Array, fileName, ms} */
  result: null,
  /** import reports of loaded files: name → report */
  imports: {},
};

// ---------------------------------------------------------------------------------------
// Start-up
// ---------------------------------------------------------------------------------------
const ready = start();
ready.catch(() => {}); // reported in #error
window.weft = {
  ready,
  get design() { return state.json; },
  get result() { return state.result; },
  get resultCount() { return resultCount; },
  get files() { return [...state.files.keys()]; },
  get workerGeneration() { return workers.generation; },
  get busy() { return jobs.active.size > 0; },
  get preview() { return preview; },
  run: () => runDesign(),
  /** Completed 2D layer previews (and the segments drawn by the last one). */
  get layer2dCount() { return lattice2d.drawn; },
  get layer2dSegments() { return lattice2d.segments; },
  get thumbnails() { return [...thumbs.cache.keys()]; },
};

async function start() {
  try {
    weft = await import("../pkg/weft.js");
    await weft.default();
  } catch (err) {
    showError(`The WebAssembly module did not load (${messageOf(err)}).\n` +
      "Build it with scripts/build-www.sh and serve the repository root.");
    throw err;
  }
  try {
    schema = { ...schema, ...JSON.parse(weft.designSchema()) };
  } catch (err) {
    showError(`designSchema() failed: ${messageOf(err)}`);
  }
  wireUi();
  try {
    const { Preview } = await import("./preview.js");
    preview = new Preview($("preview"), {
      colorBy: $("color-by"), showTravel: $("show-travel"), showStarts: $("show-starts"), layerMin: $("layer-min"),
      layerMax: $("layer-max"), layerLabel: $("layer-label"), legend: $("legend"),
    });
  } catch (err) {
    showError(`The 3D preview could not start (${messageOf(err)}); slicing and downloads still work.`);
  }
  workers.start();
  loadInitialDesign();
  renderLatticeResult();
  fillExamples();
  if ("serviceWorker" in navigator && window.isSecureContext) {
    navigator.serviceWorker.register("sw.js").catch(() => {});
  }
  window.addEventListener("hashchange", () => {
    if (location.hash.startsWith("#d=")) openShare(location.hash);
  });
}

/** The design kept in this browser (or the default), then a share link's on top (undoable). */
function loadInitialDesign() {
  setDesign(storedDesign() ?? weft.defaultDesign(), { record: false });
  if (location.hash.startsWith("#d=")) openShare(location.hash);
}

function storedDesign() {
  let text = null;
  try {
    text = localStorage.getItem(STORAGE_KEY);
  } catch { /* storage disabled */ }
  if (!text) return null;
  try {
    return weft.validateDesign(text);
  } catch (err) {
    showNotice(`The design saved in this browser is no longer valid, so the default design is shown.\n${messageOf(err)}`);
    return null;
  }
}

/** Restores a design from a share fragment; runs it when everything it needs is at hand. */
function openShare(fragment) {
  let json;
  try {
    json = weft.decodeShare(fragment);
  } catch (err) {
    showError(`This share link cannot be opened: ${messageOf(err)}\nThe design you had is kept; ask for a new link.`);
    return;
  }
  setDesign(json);
  const file = usedInputFile();
  if (file && !file.embedded && !state.files.has(file.name)) {
    showNotice(`This design slices ${file.name}, which is not in the link: load ${file.name} ` +
      "(Open… or drop it on the page) and it will be sliced.");
    return;
  }
  runDesign();
}

// ---------------------------------------------------------------------------------------
// Design state, undo/redo, persistence
// ---------------------------------------------------------------------------------------
/**
 * Makes `json` (already validated) the current design.
 * @param {string} json
 * @param {{record?: boolean}} opts  record: push the previous design on the undo stack
 */
function setDesign(json, { record = true } = {}) {
  if (json === state.json) return;
  if (record && state.json) {
    state.undo.push(state.json);
    if (state.undo.length > UNDO_LIMIT) state.undo.shift();
    state.redo.length = 0;
  }
  state.json = json;
  state.design = JSON.parse(json);
  try {
    localStorage.setItem(STORAGE_KEY, json);
  } catch { /* quota or disabled: the design stays in memory */ }
  renderForm();
  updateButtons();
  scheduleLayer2d();
}

function undo() {
  if (!state.undo.length) return;
  forgetFieldEdits();
  state.redo.push(state.json);
  setDesign(state.undo.pop(), { record: false });
}

function redo() {
  if (!state.redo.length) return;
  forgetFieldEdits();
  state.undo.push(state.json);
  setDesign(state.redo.pop(), { record: false });
}

/** Applies a change to a copy of the design; returns the problem text or null. */
function changeDesign(mutate) {
  const next = structuredClone(state.design);
  mutate(next);
  try {
    setDesign(weft.validateDesign(JSON.stringify(next)));
    return null;
  } catch (err) {
    return messageOf(err);
  }
}

function inputFile() {
  return state.design?.job?.input?.file ?? null;
}

/** The loaded-file input the current design really reads (a lattice reads it only on a solid domain). */
function usedInputFile() {
  const job = state.design?.job;
  if (job?.kind === "lattice" && job.domain?.kind !== "solid") return null;
  return inputFile();
}

function isLattice() {
  return state.design?.job?.kind === "lattice";
}

/** Extension of the output: `.nc` for pneumatic (CNC-style) controllers, else `.gcode`. */
function gcodeExtension() {
  return state.design?.printer?.flavor === "pneumatic" ? "nc" : "gcode";
}

/**
 * Sets several fields through the Rust side (which resets a tagged object when its `kind`
 * changes) and makes the result the design in one undo step; returns the problem or null.
 * @param {Array<[string, string]>} assignments  [path, JSON value]
 */
function setFields(assignments) {
  let next = state.json;
  try {
    for (const [path, value] of assignments) next = weft.setField(next, path, value);
  } catch (err) {
    return messageOf(err).replace(/^--set:\s*/gm, "");
  }
  setDesign(next);
  return null;
}

function designName() {
  const name = String(state.design?.name ?? "").trim() || "weft";
  return name.replace(/[\\/:*?"<>|\u0000-\u001f]+/g, "_");
}

// ---------------------------------------------------------------------------------------
// Form (built from designSchema())
// ---------------------------------------------------------------------------------------
/** path → {inputs, error, field} */
const fieldViews = new Map();

/**
 * Schema fields shown for the current design: those of its job kind whose path exists in the
 * design (so only the current pattern's, domain's, surface's and built-in shape's parameters),
 * plus each `…kind` choice and optional Section whose parent object exists; a field with a `when`
 * condition only while that other field has the stated value.
 */
function visibleFields() {
  const design = state.design;
  const kind = design?.job?.kind;
  const usesInput = kind !== "lattice" || design?.job?.domain?.kind === "solid";
  const fields = schema.fields.filter((f) => {
    if (f.job && f.job !== kind) return false;
    if (f.when && String(getPath(design, f.when.path)) !== f.when.equals) return false;
    if (!f.path.startsWith("job.")) return true;
    if (f.path.startsWith("job.input.") && !usesInput) return false;
    const parent = f.path.slice(0, f.path.lastIndexOf("."));
    if (f.kind === "section" || (f.kind === "choice" && f.path.endsWith(".kind"))) {
      const p = getPath(design, parent);
      return p !== null && typeof p === "object" && !Array.isArray(p);
    }
    return getPath(design, f.path) !== undefined;
  });
  if (!fields.some((f) => f.path === "name")) {
    fields.unshift({ path: "name", section: "Design", label: "Name", kind: "text", unit: "", doc: "Used for the downloaded file name." });
  }
  if ((schema.job_kinds?.length ?? 0) > 1 && !fields.some((f) => f.path === "job.kind")) {
    fields.unshift({ path: "job.kind", section: "Design", label: "Job", kind: "choice", choices: schema.job_kinds, unit: "", doc: "What to make" });
  }
  return fields;
}

function renderForm() {
  const fields = visibleFields();
  const key = fields.map((f) => f.path).join(",");
  if (key !== formKey) buildForm(fields, key);
  for (const [path, view] of fieldViews) writeField(view, getPath(state.design, path));
  renderInput();
  renderPatternPicker();
  $("slice").textContent = isLattice() ? "Run" : "Slice";
  $("download").textContent = `Download ${gcodeExtension() === "nc" ? ".nc" : "G-code"}`;
  $("lattice-panel").hidden = !isLattice() && !state.result?.report?.paths;
}

/** Sections with a fixed place in the "Design" fieldset; the others get their own. */
const SECTION_HOSTS = { design: "input-fields", input: "input-params" };
let formKey = null;

function buildForm(fields, key) {
  formKey = key;
  fieldViews.clear();
  const host = $("schema-fields");
  host.replaceChildren();
  const sections = new Map();
  for (const id of Object.values(SECTION_HOSTS)) $(id).replaceChildren();
  for (const f of fields) {
    const name = (f.section || "other").toLowerCase();
    if (!sections.has(name)) {
      if (SECTION_HOSTS[name]) {
        sections.set(name, $(SECTION_HOSTS[name]));
      } else {
        const fs = document.createElement("fieldset");
        fs.className = "section";
        fs.id = `section-${name.replace(/[^a-z0-9]+/g, "-")}`;
        const legend = document.createElement("legend");
        legend.textContent = titleCase(f.section || "other");
        fs.append(legend);
        sections.set(name, fs);
        host.append(fs);
      }
    }
    sections.get(name).append(buildField(f));
  }
}

function buildField(f) {
  const id = `f-${f.path.replace(/[^a-zA-Z0-9_-]/g, "-")}`;
  const wrap = document.createElement("div");
  wrap.className = `field kind-${f.kind}`;
  const label = document.createElement("label");
  label.htmlFor = f.kind === "vec3" ? `${id}-0` : id;
  label.textContent = f.label || f.path;
  if (f.doc) label.title = f.doc;
  const control = document.createElement("span");
  control.className = "control";
  const error = document.createElement("span");
  error.className = "field-error";
  error.id = `${id}-error`;
  error.hidden = true;

  const inputs = [];
  const make = (tag, suffix = "") => {
    const el = document.createElement(tag);
    el.id = id + suffix;
    el.dataset.path = f.path;
    el.setAttribute("aria-describedby", error.id);
    if (f.doc) el.title = f.doc;
    inputs.push(el);
    control.append(el);
    return el;
  };
  const numeric = (el) => {
    el.type = "number";
    if (f.min !== undefined && f.min !== null) el.min = String(f.min);
    if (f.max !== undefined && f.max !== null) el.max = String(f.max);
    el.step = f.step !== undefined && f.step !== null ? String(f.step) : f.kind === "integer" ? "1" : "any";
    el.inputMode = f.kind === "integer" ? "numeric" : "decimal";
  };
  switch (f.kind) {
    case "bool":
    case "section": {
      const el = make("input");
      el.type = "checkbox";
      break;
    }
    case "choice": {
      const el = make("select");
      for (const c of f.choices ?? []) {
        const o = document.createElement("option");
        o.value = JSON.stringify(c);
        o.textContent = String(c);
        el.append(o);
      }
      break;
    }
    case "vec3":
      for (let i = 0; i < 3; i++) {
        const el = make("input", `-${i}`);
        numeric(el);
        el.setAttribute("aria-label", `${f.label || f.path} ${"xyz"[i]}`);
      }
      break;
    case "text": {
      // G-code templates and other multi-line values get a text area.
      const multiline = /gcode$/.test(f.path) || String(getPath(state.design, f.path) ?? "").includes("\n");
      const el = make(multiline ? "textarea" : "input");
      if (multiline) {
        el.rows = 3;
        el.spellcheck = false;
        wrap.classList.add("multiline");
      } else {
        el.type = "text";
      }
      break;
    }
    default:
      numeric(make("input"));
  }
  if (f.kind !== "bool" && f.kind !== "section" && f.kind !== "text") {
    const unit = document.createElement("span"); // empty too, so the inputs line up
    unit.className = "unit";
    unit.textContent = f.unit ?? "";
    control.append(unit);
  }
  const view = { f, inputs, error, wrap };
  for (const el of inputs) el.addEventListener("change", () => commitField(view));
  fieldViews.set(f.path, view);
  wrap.append(label, control, error);
  return wrap;
}

/** Undo/redo show the design as it is: drop invalid entries still showing in the form. */
function forgetFieldEdits() {
  for (const view of fieldViews.values()) view.dirty = false;
}

function writeField(view, value) {
  const { f, inputs } = view;
  if (view.error.hidden === false && view.dirty) return; // keep the user's invalid entry visible
  setFieldError(view, null);
  if (f.kind === "bool") inputs[0].checked = Boolean(value);
  else if (f.kind === "section") inputs[0].checked = value !== undefined && value !== null;
  else if (f.kind === "choice") inputs[0].value = JSON.stringify(value);
  else if (f.kind === "vec3") inputs.forEach((el, i) => { el.value = Array.isArray(value) ? String(value[i]) : ""; });
  else inputs[0].value = value === undefined || value === null ? "" : String(value);
}

function readField({ f, inputs }) {
  switch (f.kind) {
    case "bool": return String(inputs[0].checked);
    // An optional block: its default JSON when switched on; null (→ absent) when off.
    case "section": return inputs[0].checked ? (f.default ?? "{}") : "null";
    case "choice": return inputs[0].value;
    case "text": return JSON.stringify(inputs[0].value);
    case "vec3": return `[${inputs.map((el) => el.value.trim() || "null").join(",")}]`;
    default: return inputs[0].value.trim();
  }
}

function commitField(view) {
  let next;
  const value = readField(view);
  try {
    if (view.f.path === "job.domain.kind" && value === '"solid"' && isLattice() && !state.design.job.input) {
      // A solid domain needs a solid: the last loaded mesh, else a built-in cube.
      const name = [...state.files.keys()].pop();
      const input = name ? { file: { name } } : { builtin: shapeDefaults("cube") };
      next = weft.setField(weft.setField(state.json, "job.input", JSON.stringify(input)), view.f.path, value);
    } else {
      next = weft.setField(state.json, view.f.path, value);
    }
  } catch (err) {
    view.dirty = true;
    // setField reuses the CLI's `--set path=value` parser, whose messages start with "--set:".
    setFieldError(view, messageOf(err).replace(/^--set:\s*/gm, ""));
    return;
  }
  view.dirty = false;
  setFieldError(view, null);
  setDesign(next);
}

function setFieldError(view, message) {
  view.error.hidden = !message;
  view.error.textContent = message ?? "";
  view.wrap.classList.toggle("invalid", Boolean(message));
  for (const el of view.inputs) {
    if (message) el.setAttribute("aria-invalid", "true");
    else el.removeAttribute("aria-invalid");
  }
}

// --- the job input: built-in shape or loaded file ---------------------------------------
function shapeNames() {
  return (schema.builtin_shapes?.length ? schema.builtin_shapes : Object.keys(SHAPE_DEFAULTS))
    .map((s) => (typeof s === "string" ? s : s.shape));
}

function shapeDefaults(shape) {
  const fromSchema = (schema.builtin_shapes ?? []).find((s) => typeof s === "object" && s.shape === shape);
  return structuredClone(fromSchema ?? SHAPE_DEFAULTS[shape] ?? { shape });
}

function renderInput() {
  const input = state.design?.job?.input ?? {};
  const select = $("input-kind");
  const planar = isLattice() && state.design.job.domain?.kind !== "solid";
  select.closest(".field").hidden = planar;
  $("input-extra").hidden = planar;
  $("input-info").hidden = planar;
  const options = [];
  for (const shape of shapeNames()) options.push([`builtin:${shape}`, `Built-in ${shape}`]);
  const names = new Set(state.files.keys());
  if (input.file?.name) names.add(input.file.name);
  for (const name of names) {
    const missing = !state.files.has(name) && !(input.file?.name === name && input.file.embedded);
    options.push([`file:${name}`, `File: ${name}${missing ? " (not loaded)" : ""}`]);
  }
  options.push(["open", "Load a file…"]);
  select.replaceChildren(...options.map(([value, text]) => new Option(text, value)));
  select.value = input.builtin ? `builtin:${input.builtin.shape}` : input.file ? `file:${input.file.name}` : "";

  // Shape parameters come from the schema (job.input.builtin.*); any it lacks get a plain input.
  const extra = $("input-extra");
  extra.replaceChildren();
  const info = $("input-info");
  info.textContent = "";
  info.classList.remove("field-error");
  if (input.builtin) {
    for (const [key, value] of Object.entries(input.builtin)) {
      if (key === "shape" || fieldViews.has(`job.input.builtin.${key}`)) continue;
      extra.append(shapeParam(key, value));
    }
  } else if (input.file) {
    const f = input.file;
    const bytes = state.files.get(f.name)?.byteLength;
    info.textContent = bytes !== undefined ? `${f.name}: ${formatBytes(bytes)} loaded`
      : f.embedded ? `${f.name} is embedded in the shared link`
        : `${f.name} is not loaded: open or drop it to slice`;
  }
}

function shapeParam(key, value) {
  const wrap = document.createElement("div");
  wrap.className = "field";
  const id = `shape-${key}`;
  const label = document.createElement("label");
  label.htmlFor = Array.isArray(value) ? `${id}-0` : id;
  label.textContent = titleCase(key.replace(/_/g, " "));
  const control = document.createElement("span");
  control.className = "control";
  const error = $("input-info");
  const values = Array.isArray(value) ? value : [value];
  const inputs = values.map((v, i) => {
    const el = document.createElement("input");
    el.type = "number";
    el.id = Array.isArray(value) ? `${id}-${i}` : id;
    el.step = key === "segments" ? "1" : "any";
    el.min = key === "segments" ? "3" : "0";
    el.value = String(v);
    if (Array.isArray(value)) el.setAttribute("aria-label", `${key} ${"xyz"[i]}`);
    el.addEventListener("change", () => {
      const nums = inputs.map((x) => Number(x.value));
      const problem = changeDesign((d) => {
        d.job.input.builtin[key] = Array.isArray(value) ? nums : nums[0];
      });
      error.textContent = problem ?? "";
      error.classList.toggle("field-error", Boolean(problem));
    });
    control.append(el);
    return el;
  });
  const unit = document.createElement("span");
  unit.className = "unit";
  unit.textContent = key === "segments" ? "" : "mm";
  control.append(unit);
  wrap.append(label, control);
  return wrap;
}

function onInputKindChange() {
  const value = $("input-kind").value;
  if (value === "open") {
    renderInput();
    $("file").click();
    return;
  }
  const problem = changeDesign((d) => {
    if (value.startsWith("builtin:")) d.job.input = { builtin: shapeDefaults(value.slice(8)) };
    else d.job.input = { file: { name: value.slice(5) } };
  });
  if (problem) showError(problem);
}

// ---------------------------------------------------------------------------------------
// Lattice jobs: pattern picker, 2D layer preview, path-optimisation results
// ---------------------------------------------------------------------------------------
/** The 2D preview of one layer (#layer2d), fed by `layer2d` requests to the worker. */
const lattice2d = {
  timer: 0,
  seq: 0, // newest request sent; older answers are dropped
  drawn: 0, // answers drawn (for tests)
  segments: 0, // segments in the last drawing
  last: null, // {segments: Float32Array, layer}
};

function layerCount() {
  const job = state.design?.job;
  if (job?.kind !== "lattice") return 1;
  if (job.domain?.kind === "solid") return Math.max(1, state.result?.report?.lattice?.layers ?? 1);
  return Math.max(1, job.lattice?.layers ?? 1);
}

/** Asks the worker for the chosen layer's strokes after `delay` ms without further edits. */
function scheduleLayer2d(delay = LAYER2D_DEBOUNCE_MS) {
  clearTimeout(lattice2d.timer);
  if (!isLattice()) return;
  const input = $("layer2d-layer");
  const count = layerCount();
  input.max = String(count);
  const layer = Math.min(count, Math.max(1, Math.round(input.valueAsNumber) || 1));
  if (String(layer) !== input.value) input.value = String(layer);
  lattice2d.timer = setTimeout(() => requestLayer2d(layer - 1), delay);
}

async function requestLayer2d(layer) {
  const mine = ++lattice2d.seq;
  const info = $("layer2d-info");
  const file = usedInputFile();
  if (file && !file.embedded && !state.files.has(file.name)) {
    info.textContent = `load ${file.name} to see its layers`;
    return;
  }
  info.textContent = "…";
  let res;
  try {
    res = await workers.request({ type: MSG.LAYER2D, design: state.json, layer, key: "preview" });
  } catch (err) {
    if (mine === lattice2d.seq && !err.cancelled) {
      info.textContent = messageOf(err);
      info.classList.add("field-error");
    }
    return;
  }
  if (mine !== lattice2d.seq || res.stale) return; // a newer request is on its way
  info.classList.remove("field-error");
  lattice2d.last = { segments: res.segments, layer };
  lattice2d.drawn++;
  redrawLattice2d();
  const n = res.segments.length / LAYER2D_STRIDE;
  info.textContent = `of ${layerCount()} · ${n.toLocaleString("en-US")} segments · ${Math.round(res.ms)} ms`;
}

function redrawLattice2d() {
  if ($("lattice-panel").hidden) return;
  const { counts, segments } = drawSegments2d($("layer2d"), lattice2d.last?.segments ?? null, { stride: LAYER2D_STRIDE, scaleBar: true });
  lattice2d.segments = segments;
  const names = { 4: "lattice", 5: "contour", 6: "handle" };
  $("layer2d-legend").replaceChildren(...Object.keys(counts).map((code) => {
    const el = document.createElement("span");
    const sw = document.createElement("span");
    sw.className = "swatch";
    sw.style.background = FEATURE_COLORS_2D[code] ?? "#e0b84d";
    el.append(sw, ` ${names[code] ?? `feature ${code}`}`);
    return el;
  }));
}

/** Pattern thumbnails: name → {segments, stride}, drawn once per pattern and seed. */
const thumbs = { cache: new Map(), seed: null, pending: new Set() };

function thumbnailSeed() {
  return Number(state.design?.seed ?? 1);
}

/** Segments of a pattern's thumbnail: `patternThumbnail` when the module has it, else the worker. */
function loadThumbnail(kind) {
  const cached = thumbs.cache.get(kind);
  if ((cached && !(cached.failedAt < Date.now() - 10000)) || thumbs.pending.has(kind)) return;
  const seed = thumbnailSeed();
  if (typeof weft.patternThumbnail === "function") {
    const pattern = JSON.stringify({ kind });
    let segments = null;
    for (const s of [seed, BigInt(seed)]) { // u64 seeds cross as BigInt
      try {
        segments = weft.patternThumbnail(pattern, THUMB_MM, s);
        break;
      } catch { /* try the other seed type, then the worker */ }
    }
    if (segments) {
      thumbs.cache.set(kind, { segments, stride: 4 });
      return;
    }
  }
  // Fallback: the 2D preview of a default lattice design with this pattern.
  let design;
  try {
    design = weft.setField(weft.defaultDesign(), "job.kind", '"lattice"');
    for (const [path, value] of [
      ["seed", String(seed)],
      ["job.domain", JSON.stringify({ kind: "rectangle", width_mm: THUMB_MM, height_mm: THUMB_MM })],
      ["job.lattice.pattern", JSON.stringify({ kind })],
    ]) design = weft.setField(design, path, value);
  } catch {
    return;
  }
  thumbs.pending.add(kind);
  workers.request({ type: MSG.LAYER2D, design, layer: 0, key: `thumb:${kind}` })
    .then((res) => {
      if (!res.stale) thumbs.cache.set(kind, { segments: res.segments, stride: LAYER2D_STRIDE });
      drawThumbnail(kind);
    })
    // Drawn blank; tried again on a later form update.
    .catch(() => thumbs.cache.set(kind, { segments: new Float32Array(0), stride: LAYER2D_STRIDE, failedAt: Date.now() }))
    .finally(() => thumbs.pending.delete(kind));
}

function drawThumbnail(kind) {
  const canvas = document.querySelector(`#pattern-picker canvas[data-pattern="${kind}"]`);
  const t = thumbs.cache.get(kind);
  if (!canvas || !t) return;
  const half = THUMB_MM / 2;
  const frame = t.stride === 4 ? [-half, -half, half, half] : null;
  drawSegments2d(canvas, t.segments, { stride: t.stride, frame, lineWidth: 1, color: FEATURE_COLORS_2D[4] });
}

/** The atlas as a grid of thumbnails under the pattern choice; a click sets the pattern. */
function renderPatternPicker() {
  const view = fieldViews.get("job.lattice.pattern.kind");
  const patterns = schema.patterns ?? [];
  let picker = $("pattern-picker");
  if (!view || !patterns.length) {
    picker?.remove();
    return;
  }
  if (thumbs.seed !== thumbnailSeed()) {
    // Voronoi depends on the seed: redraw all with the design's.
    thumbs.cache.clear();
    thumbs.seed = thumbnailSeed();
  }
  if (!picker || picker.previousElementSibling !== view.wrap) {
    picker?.remove();
    picker = document.createElement("div");
    picker.id = "pattern-picker";
    picker.className = "pattern-picker";
    picker.setAttribute("role", "group");
    picker.setAttribute("aria-label", "Lattice patterns");
    for (const kind of patterns) {
      const b = document.createElement("button");
      b.type = "button";
      b.className = "pattern";
      b.dataset.pattern = kind;
      b.title = kind.replace(/_/g, " ");
      const c = document.createElement("canvas");
      c.dataset.pattern = kind;
      c.width = 64;
      c.height = 64;
      drawSegments2d(c, null); // background until the thumbnail arrives
      const label = document.createElement("span");
      label.textContent = kind.replace(/_/g, " ");
      b.append(c, label);
      b.addEventListener("click", () => {
        const problem = setFields([["job.lattice.pattern.kind", JSON.stringify(kind)]]);
        if (problem) showError(problem);
      });
      picker.append(b);
    }
    view.wrap.after(picker);
  }
  const current = state.design?.job?.lattice?.pattern?.kind;
  for (const b of picker.querySelectorAll("button")) b.setAttribute("aria-pressed", String(b.dataset.pattern === current));
  for (const kind of patterns) {
    loadThumbnail(kind);
    drawThumbnail(kind);
  }
}

/** Score plot, path classes and numbers of the chosen layer of the last result. */
function renderLatticeResult() {
  const report = state.result?.report;
  const layers = report?.paths?.layers ?? [];
  const panel = $("lattice-panel");
  panel.hidden = !isLattice() && !layers.length;
  const select = $("paths-layer");
  if (select.options.length !== layers.length) {
    const keep = select.value;
    select.replaceChildren(...layers.map((_, i) => new Option(`${i + 1} of ${layers.length}`, String(i))));
    if (keep && Number(keep) < layers.length) select.value = keep;
  }
  select.hidden = layers.length < 2;
  select.previousElementSibling.hidden = select.hidden;
  const i = Math.min(layers.length - 1, Math.max(0, Number(select.value) || 0));
  const layer = layers[i] ?? null;
  $("score-title").textContent = renderScorePlot($("score-plot"), layer, report?.paths?.method ?? null);
  renderPathClasses($("path-classes"), layer);
  renderPathTable($("path-table"), layer, { pores: report?.lattice?.pore_fraction_per_layer?.[i] });
  const np = report?.nonplanar;
  $("paths-title").textContent = layer
    ? `Paths${layers.length > 1 ? ` · layer ${i + 1}` : ""}${np ? ` · non-planar: ${np.missed_points ?? 0} missed, ${np.collisions ?? 0} collisions` : ""}`
    : "Paths";
  if (state.design?.job?.domain?.kind === "solid") scheduleLayer2d(0); // its layer count is known now
}

// ---------------------------------------------------------------------------------------
// Worker management
// ---------------------------------------------------------------------------------------
const workers = {
  /** @type {Worker|null} */
  worker: null,
  generation: 0,
  nextId: 1,
  /** id → {resolve, reject, type, onProgress} */
  pending: new Map(),
  recentCrashes: [],

  start() {
    this.generation++;
    const w = new Worker(new URL("./worker.js", import.meta.url), { type: "module", name: `weft-${this.generation}` });
    this.worker = w;
    w.onmessage = ({ data }) => this.onMessage(w, data);
    w.onerror = (e) => {
      e.preventDefault();
      if (w === this.worker) this.crashed(e.message || "the worker script failed");
    };
    w.onmessageerror = () => {
      if (w === this.worker) this.crashed("a message could not be read");
    };
    // Give the new worker every file the page holds (copies: the page keeps its own).
    for (const [name, bytes] of state.files) {
      this.request({ type: MSG.LOAD, name, bytes: bytes.slice(0), silent: true }).catch(() => {});
    }
  },

  /** Stops all work now (terminate) and starts a fresh worker with the files reloaded. */
  restart(reason) {
    this.worker?.terminate();
    this.worker = null;
    const stopped = new Error(reason ?? "cancelled");
    stopped.cancelled = true;
    for (const p of this.pending.values()) p.reject(stopped);
    this.pending.clear();
    this.start();
  },

  crashed(message) {
    const now = Date.now();
    this.recentCrashes = this.recentCrashes.filter((t) => now - t < 10000);
    this.recentCrashes.push(now);
    if (this.recentCrashes.length > 3) {
      this.worker?.terminate();
      this.worker = null;
      const stopped = new Error(message);
      stopped.cancelled = true; // reported below
      for (const p of this.pending.values()) p.reject(stopped);
      this.pending.clear();
      showError(`The worker keeps stopping (${message}). Your design is kept; reload the page to try again.`);
      return;
    }
    this.restart(message);
    showError(`The worker stopped (${message}); restarted — your design is kept.`);
  },

  /** Sends a request; resolves with the worker's answer. Transfers `bytes` if present. */
  request(msg, onProgress) {
    if (!this.worker) this.start();
    const id = this.nextId++;
    msg.id = id;
    return new Promise((resolve, reject) => {
      this.pending.set(id, { resolve, reject, type: msg.type, onProgress });
      this.worker.postMessage(msg, msg.bytes ? [msg.bytes] : []);
    });
  },

  onMessage(w, msg) {
    if (w !== this.worker) return; // a terminated worker's late message
    if (msg.type === MSG.READY) return;
    if (msg.type === MSG.ERROR && (msg.fatal || msg.id === null)) {
      // The wasm instance is unusable (trap, out of memory, no module): restart, which
      // rejects the pending requests quietly, and say so once.
      this.crashed(msg.message);
      return;
    }
    const p = this.pending.get(msg.id);
    if (msg.type === MSG.PROGRESS) {
      p?.onProgress?.(msg.stage, msg.fraction);
      return;
    }
    this.pending.delete(msg.id);
    if (msg.type === MSG.ERROR) p?.reject(new Error(msg.message));
    else p?.resolve(msg);
  },
};

// --- jobs and the progress bar ----------------------------------------------------------
const jobs = {
  active: new Map(), // token → label
  stages: null, // stage names of the running job (JOB_STAGES), for the overall bar
  timer: 0,
  nextToken: 1,
  begin(label) {
    const token = this.nextToken++;
    this.active.set(token, label);
    this.progress(label, null);
    if (!this.timer && $("progress").hidden) {
      this.timer = setTimeout(() => {
        this.timer = 0;
        if (this.active.size) $("progress").hidden = false;
      }, PROGRESS_DELAY_MS);
    }
    document.body.classList.add("busy");
    return token;
  },
  end(token) {
    this.active.delete(token);
    if (this.active.size) return;
    clearTimeout(this.timer);
    this.timer = 0;
    $("progress").hidden = true;
    document.body.classList.remove("busy");
  },
  endAll() {
    for (const t of [...this.active.keys()]) this.end(t);
  },
  /** stage progress → overall bar + "slice 42%" label */
  progress(stage, fraction) {
    const bar = $("progress-bar");
    if (fraction === null) {
      bar.removeAttribute("value"); // indeterminate
      $("progress-label").textContent = `${stage}…`;
      return;
    }
    const stages = this.stages ?? STAGES;
    const i = stages.indexOf(stage);
    const overall = i < 0 ? fraction : (i + Math.min(1, Math.max(0, fraction))) / stages.length;
    bar.value = overall;
    $("progress-label").textContent = `${stage}… ${Math.round(overall * 100)}%`;
  },
};

function cancel() {
  if (!jobs.active.size) return;
  workers.restart("cancelled");
  jobs.endAll();
  showNotice("Cancelled: the worker was stopped and restarted. Your design is kept.");
}

// ---------------------------------------------------------------------------------------
// Actions
// ---------------------------------------------------------------------------------------
let latestRun = 0;

async function runDesign() {
  const file = usedInputFile();
  if (file && !file.embedded && !state.files.has(file.name)) {
    showError(`The design slices ${file.name}, which is not loaded: open or drop ${file.name} first, or pick a built-in shape.`);
    return;
  }
  const token = jobs.begin("starting");
  const mine = ++latestRun;
  const name = designName();
  const ext = gcodeExtension();
  jobs.stages = JOB_STAGES[state.design?.job?.kind] ?? STAGES;
  try {
    const res = await workers.request({ type: MSG.RUN, design: state.json }, (s, f) => jobs.progress(s, f));
    if (mine === latestRun) showResult(res, `${name}.${ext}`);
  } catch (err) {
    if (!err.cancelled) showError(messageOf(err));
  } finally {
    jobs.end(token);
  }
}

/** Opens files from the picker or a drop: designs, meshes, G-code. */
async function openFiles(fileList) {
  for (const file of fileList) await openFile(file);
}

async function openFile(file) {
  const ext = file.name.toLowerCase().split(".").pop();
  hideError();
  if (ext === "json") {
    try {
      setDesign(weft.validateDesign(await file.text()));
      showNotice(`Design loaded from ${file.name}.`);
    } catch (err) {
      showError(`${file.name} is not a weft design:\n${messageOf(err)}`);
    }
    return;
  }
  if (GCODE_EXT.includes(ext)) {
    const token = jobs.begin(`reading ${file.name}`);
    latestRun++;
    try {
      const bytes = await file.arrayBuffer();
      const res = await workers.request({ type: MSG.ANALYZE, name: file.name, bytes }, (s, f) => jobs.progress(s, f));
      showResult(res, file.name);
    } catch (err) {
      if (!err.cancelled) showError(messageOf(err));
    } finally {
      jobs.end(token);
    }
    return;
  }
  if (!MESH_EXT.includes(ext)) {
    showError(`${file.name}: weft opens meshes (.stl, .obj, .3mf), G-code (.gcode) and designs (.json).`);
    return;
  }
  const token = jobs.begin(`reading ${file.name}`);
  let report;
  let bytes;
  try {
    bytes = await file.arrayBuffer();
    // Transfer a copy; keep ours for worker restarts and share links.
    const res = await workers.request({ type: MSG.LOAD, name: file.name, bytes: bytes.slice(0) });
    report = res.report;
  } catch (err) {
    if (!err.cancelled) showError(messageOf(err));
    return;
  } finally {
    jobs.end(token);
  }
  state.files.set(file.name, bytes);
  state.imports = { ...state.imports, [file.name]: report };
  // A lattice job fills the layers of the loaded solid (its domain becomes `solid`).
  const problem = isLattice()
    ? setFields([["job.input", JSON.stringify({ file: { name: file.name } })], ["job.domain.kind", '"solid"']])
    : changeDesign((d) => { d.job.input = { file: { name: file.name } }; });
  if (problem) {
    showError(problem);
    return;
  }
  renderInput();
  runDesign();
}

let resultCount = 0;
function showResult(res, fileName) {
  resultCount++;
  const { report, preview: buffers, gcode } = res;
  state.result = { report, gcode, fileName, ms: res.ms };
  $("download").disabled = !(gcode && gcode.byteLength);
  const origin = state.design?.printer?.origin;
  preview?.setResult(buffers, { origin: typeof origin === "string" ? origin : "corner" });
  renderStats(report, gcode, res.ms);
  renderLatticeResult();
  hideErrorUnlessCrash();
}

function renderStats(report, gcode, ms) {
  const a = report?.analysis ?? {};
  const g = report?.gcode ?? {};
  const num = (v, digits = 1) =>
    typeof v === "number" && Number.isFinite(v)
      ? v.toLocaleString("en-US", { maximumFractionDigits: digits, minimumFractionDigits: 0 }) : "–";
  const rows = [
    ["Layers", num(a.layers ?? g.layers, 0), ""],
    ["Extrusion paths", num(a.extrusion_paths, 0), ""],
    ["Extruded", num(a.extruded_mm ?? g.extruded_mm), "mm"],
    ["Filament", num(a.filament_mm ?? g.filament_mm), "mm"],
    ["Travel", num(a.travel_mm ?? g.travel_mm), "mm"],
    ["Retractions", num(a.retractions ?? g.retractions, 0), ""],
    ["Overlap", num(a.overlap_mm), "mm"],
    ["GIPPO score", num(a.gippo_score, 3), ""],
    ["Estimated time", formatDuration(a.estimated_time_s ?? g.estimated_time_s), "h:m:s"],
    ["G-code", gcode ? formatBytes(gcode.byteLength) : "–", ""],
  ];
  const imp = report?.import;
  if (imp && typeof imp === "object") {
    rows.push(["Mesh", num(imp.triangles, 0), "triangles"]);
    if (imp.open_edges) rows.push(["Open edges", num(imp.open_edges, 0), ""]);
  }
  if (typeof ms === "number") rows.push(["Worker time", num(ms / 1000, 2), "s"]);
  const dl = document.createElement("dl");
  for (const [k, v, unit] of rows) {
    const div = document.createElement("div");
    const dt = document.createElement("dt");
    dt.textContent = k;
    const dd = document.createElement("dd");
    dd.textContent = v;
    if (unit) {
      const u = document.createElement("span");
      u.className = "unit";
      u.textContent = ` ${unit}`;
      dd.append(u);
    }
    div.append(dt, dd);
    dl.append(div);
  }
  $("stats").replaceChildren(dl);
}

function download(data, name, type) {
  const url = URL.createObjectURL(new Blob([data], { type }));
  const a = document.createElement("a");
  a.href = url;
  a.download = name;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

async function share() {
  const file = inputFile();
  const bytes = file && state.files.has(file.name) ? new Uint8Array(state.files.get(file.name)) : undefined;
  let res;
  try {
    res = JSON.parse(weft.encodeShare(state.json, bytes ? file.name : undefined, bytes));
  } catch (err) {
    showError(`Could not make a share link: ${messageOf(err)}`);
    return;
  }
  history.replaceState(null, "", `${location.pathname}${location.search}${res.fragment}`);
  const url = location.href;
  let copied = false;
  try {
    await navigator.clipboard.writeText(url);
    copied = true;
  } catch { /* no clipboard permission: the address bar holds the link */ }
  const head = copied ? "Link copied to the clipboard" : "The link is in the address bar";
  const size = `${url.length.toLocaleString("en-US")} characters`;
  showNotice(`${head} (${size}${res.embedded ? `, ${file.name} included` : ""}).${res.note ? ` Note: ${res.note}.` : ""}`, url);
}

// ---------------------------------------------------------------------------------------
// UI wiring
// ---------------------------------------------------------------------------------------
function wireUi() {
  $("slice").addEventListener("click", () => runDesign());
  $("cancel").addEventListener("click", cancel);
  $("undo").addEventListener("click", undo);
  $("redo").addEventListener("click", redo);
  $("download").addEventListener("click", () => {
    const r = state.result;
    if (r?.gcode) download(r.gcode, r.fileName, "text/x-gcode");
  });
  $("download-design").addEventListener("click", () => download(`${state.json}\n`, `${designName()}.json`, "application/json"));
  $("share").addEventListener("click", share);
  $("file").addEventListener("change", async (e) => {
    const files = [...e.target.files];
    e.target.value = "";
    await openFiles(files);
  });
  $("input-kind").addEventListener("change", onInputKindChange);
  $("examples").addEventListener("change", openExample);
  $("layer2d-layer").addEventListener("change", () => scheduleLayer2d(0));
  $("paths-layer").addEventListener("change", renderLatticeResult);
  new ResizeObserver(() => redrawLattice2d()).observe($("layer2d"));
  $("error-close").addEventListener("click", hideError);
  $("notice-close").addEventListener("click", () => { $("notice").hidden = true; });
  $("design-form").addEventListener("submit", (e) => e.preventDefault());

  document.addEventListener("keydown", (e) => {
    const mod = e.ctrlKey || e.metaKey;
    if (!mod) {
      if (e.key === "Escape" && jobs.active.size) cancel();
      return;
    }
    const t = e.target;
    const textEditing = t instanceof HTMLTextAreaElement || (t instanceof HTMLInputElement && t.type === "text");
    const key = e.key.toLowerCase();
    if (key === "z" && !textEditing) {
      e.preventDefault();
      if (e.shiftKey) redo();
      else undo();
    } else if (key === "y" && !textEditing) {
      e.preventDefault();
      redo();
    } else if (key === "enter") {
      e.preventDefault();
      runDesign();
    }
  });

  // Drop anywhere on the page.
  let depth = 0;
  const hint = $("drop-hint");
  const hasFiles = (e) => [...(e.dataTransfer?.types ?? [])].includes("Files");
  window.addEventListener("dragenter", (e) => {
    if (!hasFiles(e)) return;
    e.preventDefault();
    depth++;
    hint.hidden = false;
  });
  window.addEventListener("dragover", (e) => {
    if (!hasFiles(e)) return;
    e.preventDefault();
    e.dataTransfer.dropEffect = "copy";
  });
  window.addEventListener("dragleave", () => {
    depth = Math.max(0, depth - 1);
    if (!depth) hint.hidden = true;
  });
  window.addEventListener("drop", (e) => {
    e.preventDefault();
    depth = 0;
    hint.hidden = true;
    const files = [...(e.dataTransfer?.files ?? [])];
    if (files.length) openFiles(files);
  });
}

function updateButtons() {
  $("undo").disabled = state.undo.length === 0;
  $("redo").disabled = state.redo.length === 0;
}

async function fillExamples() {
  const select = $("examples");
  try {
    const res = await fetch("examples/index.json");
    if (!res.ok) throw new Error(`HTTP ${res.status}`);
    const list = await res.json();
    for (const { name, file } of list) select.append(new Option(name, file));
    if (!list.length) select.disabled = true;
  } catch {
    select.disabled = true; // examples are optional (generated by scripts/build-www.sh)
  }
}

async function openExample() {
  const select = $("examples");
  const file = select.value;
  select.value = "";
  if (!file) return;
  try {
    const res = await fetch(`examples/${encodeURIComponent(file)}`);
    if (!res.ok) throw new Error(`HTTP ${res.status}`);
    setDesign(weft.validateDesign(await res.text()));
  } catch (err) {
    showError(`Example ${file} could not be opened: ${messageOf(err)}`);
    return;
  }
  const f = usedInputFile();
  if (!f || f.embedded || state.files.has(f.name)) runDesign();
  else showNotice(`This example slices ${f.name}: load ${f.name} to run it.`);
}

// ---------------------------------------------------------------------------------------
// Messages
// ---------------------------------------------------------------------------------------
let crashShownAt = 0;
function showError(message) {
  $("error-text").textContent = message;
  $("error").hidden = false;
  if (/^The worker (stopped|keeps)/.test(message)) crashShownAt = Date.now();
}
function hideError() {
  $("error").hidden = true;
}
function hideErrorUnlessCrash() {
  if (Date.now() - crashShownAt > 8000) hideError();
}
function showNotice(message, link) {
  const text = $("notice-text");
  text.textContent = message;
  if (link) {
    const input = document.createElement("input");
    input.id = "share-url";
    input.readOnly = true;
    input.value = link;
    input.setAttribute("aria-label", "Share link");
    input.addEventListener("focus", () => input.select());
    text.append(" ", input);
  }
  $("notice").hidden = false;
}

// ---------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------
function messageOf(err) {
  if (err instanceof Error) return err.message || String(err);
  return typeof err === "string" ? err : JSON.stringify(err);
}

function getPath(obj, path) {
  return path.split(".").reduce((o, k) => (o == null ? undefined : o[k]), obj);
}

function titleCase(s) {
  return s.charAt(0).toUpperCase() + s.slice(1);
}

function formatBytes(n) {
  if (n < 1024) return `${n} B`;
  if (n < 1024 * 1024) return `${(n / 1024).toFixed(1)} KiB`;
  return `${(n / 1024 / 1024).toFixed(1)} MiB`;
}

function formatDuration(s) {
  if (typeof s !== "number" || !Number.isFinite(s)) return "–";
  const t = Math.round(s);
  const h = Math.floor(t / 3600);
  const m = Math.floor((t % 3600) / 60);
  const sec = t % 60;
  return `${h}:${String(m).padStart(2, "0")}:${String(sec).padStart(2, "0")}`;
}

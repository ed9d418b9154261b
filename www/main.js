// The page: design form, input slots, worker management, results. UI only: everything that
// can take time runs in worker.js; the cheap synchronous calls (schema, validation, share
// codec) use a wasm instance of our own.
//
// Nothing here knows a job kind: the form, the job selector, the input slots, the progress
// stages, feature names and colours, the views and the pattern picker come from
// designSchema(); stage cards, metrics, plots and tables come from the run report.
import { MSG, plain } from "./protocol.js";
import { drawSegments2d, drawView, featureStyles } from "./views.js";
import { metricList, renderReport } from "./report.js";
import { formatNumber } from "./plot.js";

const $ = (id) => document.getElementById(id);
const STORAGE_KEY = "weft.design";
const UNDO_LIMIT = 200;
const PROGRESS_DELAY_MS = 500;
/** Extensions of G-code files analysed and previewed when no input slot takes them. */
const GCODE_EXT = ["gcode", "gco", "g", "nc"];
const INSPECT_DEBOUNCE_MS = 200;
/** Wait after an edit before estimating the next run, ms. */
const ESTIMATE_DEBOUNCE_MS = 250;
/** Jobs estimated under this re-run by themselves after an edit (when the user lets them), s. */
const AUTO_RUN_SECONDS = 0.5;
const AUTO_RUN_KEY = "weft.autoRun";
/** Side of the square a pattern thumbnail shows, mm. */
const THUMB_MM = 6;
/** Stroke colour of the pattern thumbnails. */
const THUMB_COLOR = "#29a3d6";

let weft; // the wasm module (main-thread instance)
/** The default design (parsed once): its name, job kind and slot values. */
let defaults = null;
let preview = null;
let schema = { version: 1, fields: [], features: [], job_kinds: [], builtin_shapes: [], patterns: [] };
/** feature code → {label, color} (schema.features) */
let styles = new Map();

const state = {
  /** current design, normalized JSON (the source of truth) and its parse */
  json: "",
  design: null,
  undo: [],
  redo: [],
  /**
   * Loaded files: name → {slot, name, blob: Blob, info}. The dropped File itself (its bytes
   * stay in the browser's blob store, on disk for a dropped file): the worker gets the same
   * Blob (no copy) and reads volumes and G-code from it in pieces; share links read it.
   */
  files: new Map(),
  /**
   * last result shown: {report, gcode: Uint8Array, fileName, ms, json, files}; `json` and
   * `files` (filesVersion) are what it was made from (json null for a G-code file read as it
   * is), so an edit marks it out of date.
   */
  result: null,
  /** the estimate of the current design: {json, files, plan} or {json, files, error} */
  estimate: null,
  /**
   * Bumped whenever a loaded file is added, replaced or removed: with the design JSON it says
   * what a result or an estimate was made from (a file dropped again under the same name
   * changes no JSON).
   */
  filesVersion: 0,
  /**
   * Names the page gave (the default design's, the examples', dropped files' stems): a design
   * with one of these follows a dropped part's name; a name the user typed or loaded stays.
   */
  autoNames: new Set(),
  /** chosen group (e.g. layer) per stage card */
  groups: new Map(),
};

// ---------------------------------------------------------------------------------------
// Start-up
// ---------------------------------------------------------------------------------------
const ready = start();
ready.catch(() => {}); // reported in #error
window.weft = {
  ready,
  get design() { return state.json; },
  get schema() { return schema; },
  get result() { return state.result; },
  get resultCount() { return resultCount; },
  get files() { return [...state.files.keys()]; },
  get workerGeneration() { return workers.generation; },
  /** Threads of the worker now: {asked, used, cores, isolated, note} (used null until it is ready). */
  get threads() { return { ...workers.threads }; },
  get busy() { return jobs.active.size > 0; },
  get preview() { return preview; },
  run: () => runDesign(),
  /** Input slots of the current job kind and the files each holds. */
  get slots() {
    return currentSlots().map((s) => ({ name: s.name, kind: s.kind, accept: s.accept ?? [], multiple: Boolean(s.multiple), files: filesOf(s).map((f) => f.name) }));
  },
  /** Stage cards shown: [{stage, label, cached, plots: [kind], tables}] */
  get reportCards() {
    return [...document.querySelectorAll("#report .stage-card")].map((c) => ({
      stage: c.dataset.stage, cached: c.dataset.cached === "true", group: c.dataset.group,
      plots: [...c.querySelectorAll("svg[data-plot-kind]")].map((s) => s.dataset.plotKind),
    }));
  },
  /** Views of the current job kind: [{id, shape, index, count, answers, items}] */
  get views() {
    return [...viewCards.values()].map((v) => ({ id: v.view.id, shape: v.last?.shape ?? v.view.shape, index: v.last?.index ?? null, count: v.count, answers: v.answers, items: v.items }));
  },
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
    schema = { ...schema, ...plain(weft.designSchema()) };
  } catch (err) {
    showError(`designSchema() failed: ${messageOf(err)}`);
  }
  styles = featureStyles(schema.features);
  defaults = JSON.parse(weft.defaultDesign());
  wireUi();
  try {
    const { Preview } = await import("./preview.js");
    preview = new Preview($("preview"), {
      colorBy: $("color-by"), showTravel: $("show-travel"), showStarts: $("show-starts"), layerMin: $("layer-min"),
      layerMax: $("layer-max"), layerLabel: $("layer-label"), legend: $("legend"),
      moveMax: $("move-max"), moveLabel: $("move-label"), showAxis: $("show-axis"), camera: $("camera-views"),
    }, { features: schema.features });
  } catch (err) {
    showError(`The 3D preview could not start (${messageOf(err)}); slicing and downloads still work.`);
  }
  workers.start();
  loadInitialDesign();
  fillExamples();
  if ("serviceWorker" in navigator && window.isSecureContext) {
    navigator.serviceWorker.register("sw.js").then(isolateThroughServiceWorker, () => {});
  }
  window.addEventListener("hashchange", () => {
    if (location.hash.startsWith("#d=")) openShare(location.hash);
  });
}

/**
 * A host that sends no cross-origin isolation headers (a plain static host) gets them from
 * sw.js, but only for pages it serves: the first visit is not isolated. Once the service
 * worker controls the page, reload once so the worker can use every core, unless a loaded file
 * would be lost (a run going on is let finish first). The design is kept in localStorage and
 * the address, so a reload keeps it; a result is made again by Run.
 */
function isolateThroughServiceWorker() {
  if (self.crossOriginIsolated) return;
  const KEY = "weft.isolationReload";
  const tryReload = () => {
    if (self.crossOriginIsolated || !navigator.serviceWorker.controller) return;
    if (sessionStorage.getItem(KEY)) return; // reloaded once already: the browser would not isolate
    if (state.files.size) return; // a dropped file would be lost
    if (jobs.active.size) {
      setTimeout(tryReload, 250); // a run going on (the first visit's default part): after it
      return;
    }
    sessionStorage.setItem(KEY, "1");
    location.reload();
  };
  if (navigator.serviceWorker.controller) tryReload();
  else navigator.serviceWorker.addEventListener("controllerchange", tryReload, { once: true });
}

/** The design kept in this browser (or the default), then a share link's on top (undoable). */
function loadInitialDesign() {
  state.autoNames.add(defaults.name);
  const stored = storedDesign();
  setDesign(stored ?? weft.defaultDesign(), { record: false });
  if (location.hash.startsWith("#d=")) {
    openShare(location.hash);
    return;
  }
  // A first visit shows a part at once (the default design is light) and what to do next.
  if (!stored) {
    showNotice("Welcome to weft. This is the default part, a 20 mm cube: drop your own STL, OBJ or 3MF on the page " +
      "to slice it, change its settings, or pick one of the examples (the Examples menu, or the gallery under the results).");
    runDesign({ auto: true });
  }
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

/** Restores a design from a share fragment; runs it when every file it names is at hand. */
function openShare(fragment) {
  let json;
  try {
    json = weft.decodeShare(fragment);
  } catch (err) {
    showError(`${messageOf(err).replace(/^this link/i, "This share link")}\nThe design you had is kept.`);
    return;
  }
  setDesign(json);
  if (askForMissing("This design")) return;
  // A link is untrusted and tiny: what it asks for is estimated before anything runs.
  runDesign({ fromLink: true });
}

/** Says which named files are missing (and where they go); true when some are. */
function askForMissing(what) {
  const missing = missingFiles();
  if (!missing.length) return false;
  const list = missing.map(({ slot, name }) => `${name} (${slot.label ?? slot.name})`).join(", ");
  showNotice(`${what} uses ${list}, not in the link or loaded here: load ${missing.length > 1 ? "them" : "it"} ` +
    "(drop on the page or on its input) and it will run.");
  return true;
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
  if (json === state.json) {
    refreshFreshness();
    return;
  }
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
  scheduleInspect();
  refreshFreshness();
  scheduleEstimate();
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

/** Extension of the output for the design's flavour (from the schema: `.gcode`, `.nc`, `.csv`). */
function gcodeExtension() {
  const flavor = state.design?.printer?.flavor;
  return schema.flavors?.find((f) => f.name === flavor)?.extension ?? "gcode";
}

function designName() {
  const name = String(state.design?.name ?? "").trim() || "weft";
  return name.replace(/[\\/:*?"<>|\u0000-\u001f]+/g, "_");
}

// --- the job kind, its slots and files --------------------------------------------------
function jobKind() {
  const name = state.design?.job?.kind;
  return schema.job_kinds.find((k) => k.name === name) ?? { name, label: name, stages: [], slots: [], views: [] };
}

function currentSlots() {
  return jobKind().slots ?? [];
}

/** Files the page holds for a slot. */
function filesOf(slot) {
  return [...state.files.values()].filter((f) => f.slot === slot.name);
}

/**
 * Files named by the design at a slot's path: `{file: {name, embedded?}}` or
 * `{files: [name | {name, embedded?}]}`.
 * @returns {Array<{name: string, embedded: boolean}>}
 */
function namedFiles(value) {
  if (!value || typeof value !== "object") return [];
  const one = (f) => (typeof f === "string" ? { name: f, embedded: false }
    : f && typeof f.name === "string" ? { name: f.name, embedded: f.embedded !== undefined && f.embedded !== null } : null);
  const list = value.file ? [value.file] : Array.isArray(value.files) ? value.files : [];
  return list.map(one).filter(Boolean);
}

/** Files the design names (current job kind's slots) that are neither embedded nor loaded. */
function missingFiles() {
  const out = [];
  for (const slot of currentSlots()) {
    for (const f of namedFiles(getPath(state.design, slot.path))) {
      if (!f.embedded && !state.files.has(f.name)) out.push({ slot, name: f.name });
    }
  }
  return out;
}

function extOf(name) {
  const i = name.lastIndexOf(".");
  return i < 0 ? "" : name.slice(i).toLowerCase();
}

function accepts(slot, name) {
  // A volume slot takes a whole folder: DICOM files often have no extension, and files that
  // are not part of the series are skipped (and listed) by the reader.
  if (slot.kind === "volume") return true;
  const ext = extOf(name);
  return (slot.accept ?? []).some((a) => a.toLowerCase() === ext);
}

// ---------------------------------------------------------------------------------------
// Form (built from designSchema())
// ---------------------------------------------------------------------------------------
/** path → {inputs, error, field} */
const fieldViews = new Map();

/**
 * Schema fields shown for the current design: those of its job kind whose path exists in the
 * design (so only the current pattern's, domain's, surface's and built-in shape's parameters),
 * plus each `…kind` choice and optional Section whose parent object exists; a field with a
 * `when` condition while the field at `when_path` has the stated value (even when absent).
 */
function visibleFields() {
  const design = state.design;
  const kind = design?.job?.kind;
  const fields = schema.fields.filter((f) => {
    if (f.job && f.job !== kind) return false;
    const whenPath = f.when_path ?? f.when?.path;
    if (whenPath && f.when && String(getPath(design, whenPath)) !== String(f.when.equals)) return false;
    if (f.path === "job.kind") return true;
    if (!f.path.startsWith("job.")) return true;
    const parent = f.path.slice(0, f.path.lastIndexOf("."));
    // A section, a `…kind` choice, or a field its `when` condition asks for (e.g. a polygon's
    // holes, left out of the design while there are none) shows while its parent exists.
    if (f.kind === "section" || (f.kind === "choice" && f.path.endsWith(".kind")) || (whenPath && f.when)) {
      const p = getPath(design, parent);
      return p !== null && typeof p === "object" && !Array.isArray(p);
    }
    return getPath(design, f.path) !== undefined;
  });
  if (!fields.some((f) => f.path === "name")) {
    fields.unshift({ path: "name", section: "Design", label: "Name", kind: "text", unit: "", doc: "Used for the downloaded file name." });
  }
  if (schema.job_kinds.length > 1 && !fields.some((f) => f.path === "job.kind")) {
    fields.splice(1, 0, { path: "job.kind", section: "Design", label: "Job", kind: "choice", unit: "", doc: "What to make" });
  }
  return fields;
}

let formKey = null;

function renderForm() {
  const fields = visibleFields();
  const slots = currentSlots();
  const key = `${jobKind().name}|${slots.map((s) => s.name).join(",")}|${fields.map((f) => f.path).join(",")}`;
  if (key !== formKey) buildForm(fields, slots, key);
  for (const [path, view] of fieldViews) writeField(view, getPath(state.design, path));
  renderSlots();
  renderPatternPickers();
  renderPresetPicker();
  $("download").textContent = `Download ${gcodeExtension() === "gcode" ? "G-code" : `.${gcodeExtension()}`}`;
  if (viewsKey !== jobKind().name) buildViews();
}

/**
 * The form: the design's name and job, its inputs, the job's own settings, then the machine
 * (printer, material, speeds: every field outside `job`) folded behind a printer-profile
 * picker, since a newcomer changes the job's settings first.
 */
function buildForm(fields, slots, key) {
  formKey = key;
  fieldViews.clear();
  const host = $("schema-fields");
  const machineOpen = $("machine")?.open ?? false;
  host.replaceChildren();
  $("design-fields").replaceChildren();
  buildSlots(slots);
  const machine = document.createElement("details");
  machine.id = "machine";
  machine.className = "machine";
  machine.open = machineOpen;
  const summary = document.createElement("summary");
  const title = document.createElement("span");
  title.className = "machine-title";
  title.textContent = "Printer, material and speeds";
  const current = document.createElement("span");
  current.id = "machine-summary";
  current.className = "machine-summary";
  summary.append(title, " ", current);
  machine.append(summary, buildPresetPicker());
  const sections = new Map([["design", $("design-fields")]]);
  for (const f of fields) {
    const slot = slots.find((s) => f.path.startsWith(`${s.path}.`));
    if (slot) {
      slotCards.get(slot.name)?.fields.append(buildField(f));
      continue;
    }
    const name = (f.section || "other").toLowerCase();
    if (!sections.has(name)) {
      const fs = document.createElement("fieldset");
      fs.className = "section";
      fs.id = `section-${name.replace(/[^a-z0-9]+/g, "-")}`;
      const legend = document.createElement("legend");
      legend.textContent = titleCase(f.section || "other");
      fs.append(legend);
      sections.set(name, fs);
      (isMachineField(f) ? machine : host).append(fs);
    }
    sections.get(name).append(buildField(f));
  }
  host.append(machine);
}

/**
 * A field of the machine (printer, material, speeds): outside the job and not one of the
 * design's own (the schema's "Design" section: name, description, seed).
 */
function isMachineField(f) {
  return !f.job && !f.path.startsWith("job.") && (f.section ?? "").toLowerCase() !== "design";
}

/** The printer-profile picker (schema.printer_presets): picking one sets the printer section. */
function buildPresetPicker() {
  const wrap = document.createElement("div");
  wrap.className = "field preset-picker";
  const label = document.createElement("label");
  label.htmlFor = "printer-preset";
  label.textContent = "Printer profile";
  const control = document.createElement("span");
  control.className = "control";
  const select = document.createElement("select");
  select.id = "printer-preset";
  select.title = "Pick your kind of printer; every value below stays editable";
  for (const p of schema.printer_presets ?? []) {
    const o = new Option(p.label, p.id);
    o.title = p.doc;
    select.append(o);
  }
  select.append(new Option("Custom (edited below)", "custom"));
  select.addEventListener("change", () => {
    const p = (schema.printer_presets ?? []).find((x) => x.id === select.value);
    if (!p) return;
    const problem = setFields([["printer", JSON.stringify(p.printer)]]);
    if (problem) showError(problem);
  });
  const doc = document.createElement("p");
  doc.className = "field-doc";
  doc.id = "printer-preset-doc";
  control.append(select);
  wrap.append(label, control, doc);
  return wrap;
}

/** The picker shows the profile the printer section equals (key order aside), else custom. */
function renderPresetPicker() {
  const select = $("printer-preset");
  if (!select) return;
  const current = canonical(state.design?.printer);
  const match = (schema.printer_presets ?? []).find((p) => canonical(p.printer) === current);
  select.value = match ? match.id : "custom";
  $("printer-preset-doc").textContent = match ? match.doc : "Your own values: pick a profile to start again from one.";
  const m = state.design?.material?.name;
  $("machine-summary").textContent = `${state.design?.printer?.name ?? ""}${m ? ` · ${m}` : ""}`;
}

/** JSON with sorted keys, to compare values regardless of key order. */
function canonical(v) {
  if (Array.isArray(v)) return `[${v.map(canonical).join(",")}]`;
  if (v && typeof v === "object") return `{${Object.keys(v).sort().map((k) => `${JSON.stringify(k)}:${canonical(v[k])}`).join(",")}}`;
  return JSON.stringify(v);
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
  const scale = f.percent ? 100 : 1; // shown in percent, stored as the design says
  const numeric = (el) => {
    el.type = "number";
    if (f.min !== undefined && f.min !== null) el.min = String(f.min * scale);
    if (f.max !== undefined && f.max !== null) el.max = String(f.max * scale);
    el.step = f.step !== undefined && f.step !== null ? String(f.step * scale) : f.kind === "integer" ? "1" : "any";
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
      // The job selector lists the schema's job kinds by label.
      const options = f.path === "job.kind"
        ? schema.job_kinds.map((k) => [k.name, k.label ?? k.name, k.doc])
        : (f.choices ?? []).map((c, i) => (typeof c === "object" && c !== null ? [c.value ?? c.name, c.label ?? c.name, c.doc] : [c, String(c), f.choice_docs?.[i]]));
      for (const [value, text, doc] of options) {
        const o = document.createElement("option");
        o.value = JSON.stringify(value);
        o.textContent = String(text).replace(/_/g, " ");
        if (doc) o.title = doc;
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
    case "points":
    case "rings": {
      // A list of 2-D points, one "a b" pair per line (rings: a blank line between rings).
      const el = make("textarea");
      el.rows = 6;
      el.spellcheck = false;
      wrap.classList.add("multiline");
      break;
    }
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
  if (f.kind !== "bool" && f.kind !== "section" && f.kind !== "text" && f.kind !== "points" && f.kind !== "rings") {
    const unit = document.createElement("span"); // empty too, so the inputs line up
    unit.className = "unit";
    unit.textContent = f.percent ? "%" : f.unit ?? "";
    control.append(unit);
  }
  // The job's own settings say what they do in a line under them (the machine's keep it in
  // their tooltip); a choice says what the picked value gives.
  let doc = null;
  if (!isMachineField(f) && (f.doc || f.choice_docs?.length) && f.kind !== "section") {
    doc = document.createElement("p");
    doc.className = "field-doc";
    doc.id = `${id}-doc`;
    doc.textContent = f.doc ?? "";
    for (const el of inputs) el.setAttribute("aria-describedby", `${error.id} ${doc.id}`);
  }
  const view = { f, inputs, error, wrap, doc };
  for (const el of inputs) el.addEventListener("change", () => commitField(view));
  fieldViews.set(f.path, view);
  wrap.append(label, control, error);
  if (doc) wrap.append(doc);
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
  else if (f.kind === "choice") {
    inputs[0].value = JSON.stringify(value);
    const i = (f.choices ?? []).findIndex((c) => (typeof c === "object" && c !== null ? c.value ?? c.name : c) === value);
    if (view.doc && f.choice_docs?.[i]) view.doc.textContent = `${f.choice_docs[i]}`;
  } else if (f.kind === "vec3") inputs.forEach((el, i) => { el.value = Array.isArray(value) ? String(value[i]) : ""; });
  else if (f.kind === "points") inputs[0].value = pointLines(value);
  else if (f.kind === "rings") inputs[0].value = Array.isArray(value) ? value.map(pointLines).join("\n\n") : "";
  else if (f.percent && typeof value === "number") inputs[0].value = String(Number((value * 100).toPrecision(12)));
  else inputs[0].value = value === undefined || value === null ? "" : String(value);
}

/** Points as lines "a b". */
function pointLines(value) {
  return Array.isArray(value) ? value.map((p) => (Array.isArray(p) ? p.join(" ") : String(p))).join("\n") : "";
}

/** Lines "a b" (commas or spaces) to points; a number that does not read is null. */
function readPoints(text) {
  return text.split("\n").map((l) => l.trim()).filter((l) => l !== "")
    .map((l) => l.split(/[\s,;]+/).map((t) => (Number.isFinite(Number(t)) ? Number(t) : null)));
}

function readField({ f, inputs }) {
  switch (f.kind) {
    case "bool": return String(inputs[0].checked);
    // An optional block: its default JSON when switched on; null (→ absent) when off.
    case "section": return inputs[0].checked ? (typeof f.default === "string" ? f.default : JSON.stringify(f.default ?? {})) : "null";
    case "choice": return inputs[0].value;
    case "text": return JSON.stringify(inputs[0].value);
    case "vec3": return `[${inputs.map((el) => el.value.trim() || "null").join(",")}]`;
    // Lines "a b" (commas or spaces); a number that does not read is null, which the design
    // names with its point.
    case "points": return JSON.stringify(readPoints(inputs[0].value));
    // Rings: blocks of such lines separated by blank lines.
    case "rings": return JSON.stringify(inputs[0].value.split(/\n[ \t]*\n/).map(readPoints).filter((r) => r.length > 0));
    default: {
      const text = inputs[0].value.trim();
      // A percentage back to the fraction the design stores (anything else is left for the
      // design's own check to name).
      return f.percent && text !== "" && Number.isFinite(Number(text)) ? String(Number((Number(text) / 100).toPrecision(12))) : text;
    }
  }
}

function commitField(view) {
  let next;
  try {
    next = weft.setField(state.json, view.f.path, readField(view));
  } catch (err) {
    view.dirty = true;
    // setField reuses the CLI's `--set path=value` parser, whose messages may start with
    // "--set:" and the field's path: under the field itself, neither helps.
    const path = view.f.path.replace(/[.*+?^${}()|[\]\\]/g, "\\$&");
    setFieldError(view, messageOf(err).replace(/^--set:\s*/gm, "").replace(new RegExp(`^${path}(\\.[\\w.]+)?:\\s*`, "gm"), ""));
    return;
  }
  view.dirty = false;
  setFieldError(view, null);
  setDesign(next);
}

function setFieldError(view, message) {
  const was = !view.error.hidden;
  view.error.hidden = !message;
  setMessage(view.error, message);
  view.wrap.classList.toggle("invalid", Boolean(message));
  for (const el of view.inputs) {
    if (message) el.setAttribute("aria-invalid", "true");
    else el.removeAttribute("aria-invalid");
  }
  if (was !== Boolean(message)) refreshFreshness();
}

/** Fields showing a value the design refused (their message is shown under them). */
function invalidFields() {
  return [...fieldViews.values()].filter((v) => !v.error.hidden);
}

// --- input slots: one drop zone per slot of the job kind ---------------------------------
/** slot name → {slot, card, fields, source, extra, list, note, input} */
const slotCards = new Map();

function buildSlots(slots) {
  const host = $("slots");
  slotCards.clear();
  host.replaceChildren();
  $("slots-section").hidden = slots.length === 0;
  for (const slot of slots) {
    const card = document.createElement("div");
    card.className = "slot";
    card.dataset.slot = slot.name;
    card.dataset.kind = slot.kind ?? "";
    if (slot.doc) card.title = slot.doc;
    const head = document.createElement("div");
    head.className = "slot-head";
    const label = document.createElement("span");
    label.className = "slot-label";
    label.textContent = slot.label ?? slot.name;
    const accept = document.createElement("span");
    accept.className = "slot-accept";
    accept.textContent = (slot.accept ?? []).join(" ") + (slot.multiple ? " · several files" : "");
    head.append(label, accept);
    if (slot.required) {
      const req = document.createElement("span");
      req.className = "slot-required";
      req.textContent = "required";
      head.append(req);
    }

    // A single mesh slot can also hold a built-in shape (schema.builtin_shapes).
    let source = null;
    if (slot.kind === "mesh" && !slot.multiple && schema.builtin_shapes.length) {
      const wrap = document.createElement("div");
      wrap.className = "field slot-source";
      const l = document.createElement("label");
      const id = `slot-${slot.name}-source`;
      l.htmlFor = id;
      l.textContent = "Part";
      const control = document.createElement("span");
      control.className = "control";
      source = document.createElement("select");
      source.id = id;
      source.addEventListener("change", () => onSourceChange(slot, source));
      control.append(source);
      wrap.append(l, control);
      source.wrap = wrap;
    }
    const fields = document.createElement("div");
    fields.className = "slot-fields";
    const extra = document.createElement("div");
    extra.className = "slot-extra";
    const list = document.createElement("ul");
    list.className = "slot-files";
    const input = document.createElement("input");
    input.type = "file";
    input.className = "visually-hidden";
    input.id = `slot-${slot.name}-file`;
    input.accept = (slot.accept ?? []).join(",");
    input.multiple = Boolean(slot.multiple);
    input.addEventListener("change", async () => {
      const files = [...input.files];
      input.value = "";
      if (files.length) await loadIntoSlot(slot, files);
    });
    const drop = document.createElement("label");
    drop.className = "slot-drop";
    drop.htmlFor = input.id;
    drop.tabIndex = 0;
    drop.addEventListener("keydown", (e) => {
      if (e.key === "Enter" || e.key === " ") {
        e.preventDefault();
        input.click();
      }
    });
    drop.append(`Drop ${slot.multiple ? "files" : "a file"} here or `);
    const browse = document.createElement("u");
    browse.textContent = "browse";
    drop.append(browse, input);
    const note = document.createElement("p");
    note.className = "slot-note hint";
    card.append(head);
    if (source) card.append(source.wrap);
    card.append(fields, extra, list, drop, note);

    card.addEventListener("dragover", (e) => {
      if (![...(e.dataTransfer?.types ?? [])].includes("Files")) return;
      e.preventDefault();
      card.classList.add("over");
    });
    card.addEventListener("dragleave", () => card.classList.remove("over"));
    card.addEventListener("drop", (e) => {
      e.preventDefault();
      e.stopPropagation();
      card.classList.remove("over");
      dropState.reset();
      droppedFiles(e.dataTransfer).then((files) => { if (files.length) loadIntoSlot(slot, files); });
    });
    if (slot.kind === "volume") {
      // A series is usually a folder: a second picker takes one.
      const folder = document.createElement("input");
      folder.type = "file";
      folder.className = "visually-hidden";
      folder.id = `slot-${slot.name}-folder`;
      folder.webkitdirectory = true;
      folder.addEventListener("change", async () => {
        const files = [...folder.files].map((f) => (f.webkitRelativePath ? new File([f], f.webkitRelativePath) : f));
        folder.value = "";
        if (files.length) await loadIntoSlot(slot, files);
      });
      const pick = document.createElement("label");
      pick.className = "slot-drop slot-folder";
      pick.htmlFor = folder.id;
      pick.tabIndex = 0;
      pick.append("or choose a ");
      const u = document.createElement("u");
      u.textContent = "folder";
      pick.append(u, folder);
      pick.addEventListener("keydown", (e) => {
        if (e.key === "Enter" || e.key === " ") {
          e.preventDefault();
          folder.click();
        }
      });
      drop.after(pick);
    }
    host.append(card);
    slotCards.set(slot.name, { slot, card, fields, source, extra, list, note, input });
  }
  // The toolbar's Open… takes designs, G-code and whatever a slot takes.
  const accept = new Set([".json", ...GCODE_EXT.map((e) => `.${e}`), ...slots.flatMap((s) => s.accept ?? [])]);
  $("file").accept = [...accept].join(",");
}

/** Updates every slot card from the design and the loaded files. */
function renderSlots() {
  for (const { slot, card, source, extra, list, note } of slotCards.values()) {
    const value = getPath(state.design, slot.path);
    const named = namedFiles(value);
    const held = filesOf(slot);
    const unused = value === undefined || value === null;
    card.classList.toggle("unused", unused);
    if (source) source.wrap.hidden = unused;

    if (source) {
      const options = schema.builtin_shapes.map((b, k) => [`builtin:${k}`, `Built-in ${b.label ?? b.kind ?? b.shape}`]);
      const names = new Set([...held.map((f) => f.name), ...named.map((f) => f.name)]);
      for (const name of names) options.push([`file:${name}`, `File: ${name}${state.files.has(name) || named.find((f) => f.name === name)?.embedded ? "" : " (not loaded)"}`]);
      options.push(["open", "Load a file…"]);
      source.replaceChildren(...options.map(([v, t]) => new Option(t, v)));
      const b = value?.builtin;
      const k = b ? schema.builtin_shapes.findIndex((s) => s.value?.builtin?.shape === b.shape || (s.kind ?? s.shape) === b.shape) : -1;
      source.value = k >= 0 ? `builtin:${k}` : named[0] ? `file:${named[0].name}` : "";
    }

    // Shape parameters the schema does not list get a plain input.
    extra.replaceChildren();
    if (value?.builtin && typeof value.builtin === "object") {
      for (const [key, v] of Object.entries(value.builtin)) {
        if (key === "shape" || fieldViews.has(`${slot.path}.builtin.${key}`)) continue;
        if (typeof v === "number" || (Array.isArray(v) && v.every((x) => typeof x === "number"))) extra.append(shapeParam(slot, key, v, note));
      }
    }

    const rows = [];
    const inDesign = new Set(named.map((f) => f.name));
    for (const f of held) {
      const li = document.createElement("li");
      li.dataset.file = f.name;
      li.classList.toggle("idle", !inDesign.has(f.name));
      const name = document.createElement("span");
      name.className = "file-name";
      name.textContent = f.name;
      const summary = document.createElement("span");
      summary.className = "file-summary";
      summary.textContent = f.info?.summary ?? formatBytes(f.blob.size);
      summary.title = summary.textContent;
      const remove = document.createElement("button");
      remove.type = "button";
      remove.className = "remove";
      remove.textContent = "×";
      remove.title = `Remove ${f.name}`;
      remove.setAttribute("aria-label", `Remove ${f.name}`);
      remove.addEventListener("click", () => removeFromSlot(slot, f.name));
      li.append(name, summary, remove);
      if (!inDesign.has(f.name)) {
        li.title = "Loaded but not used by the design: click to use it";
        name.addEventListener("click", () => useFiles(slot, [f.name]));
      }
      rows.push(li);
    }
    for (const f of named) {
      if (state.files.has(f.name)) continue;
      const li = document.createElement("li");
      li.dataset.file = f.name;
      li.className = f.embedded ? "embedded" : "missing";
      const name = document.createElement("span");
      name.className = "file-name";
      name.textContent = f.name;
      const summary = document.createElement("span");
      summary.className = "file-summary";
      summary.textContent = f.embedded ? "in the shared link" : "not loaded: drop it here";
      li.append(name, summary);
      rows.push(li);
    }
    list.replaceChildren(...rows);
    list.hidden = rows.length === 0;
    if (!note.classList.contains("field-error")) {
      // An empty slot says what it is for (the slot's one line from the schema).
      note.textContent = value === undefined || value === null ? slot.doc ?? "" : "";
    }
  }
}

function shapeParam(slot, key, value, note) {
  const wrap = document.createElement("div");
  wrap.className = "field";
  const id = `slot-${slot.name}-${key}`;
  const label = document.createElement("label");
  label.htmlFor = Array.isArray(value) ? `${id}-0` : id;
  label.textContent = titleCase(key.replace(/_/g, " "));
  const control = document.createElement("span");
  control.className = "control";
  const values = Array.isArray(value) ? value : [value];
  const inputs = values.map((v, i) => {
    const el = document.createElement("input");
    el.type = "number";
    el.id = Array.isArray(value) ? `${id}-${i}` : id;
    el.step = "any";
    el.value = String(v);
    if (Array.isArray(value)) el.setAttribute("aria-label", `${key} ${"xyz"[i]}`);
    el.addEventListener("change", () => {
      const nums = inputs.map((x) => Number(x.value));
      const problem = setFields([[`${slot.path}.builtin.${key}`, JSON.stringify(Array.isArray(value) ? nums : nums[0])]]);
      note.textContent = problem ?? "";
      note.classList.toggle("field-error", Boolean(problem));
    });
    control.append(el);
    return el;
  });
  wrap.append(label, control);
  return wrap;
}

function onSourceChange(slot, select) {
  const v = select.value;
  if (v === "open") {
    renderSlots();
    slotCards.get(slot.name)?.input.click();
    return;
  }
  const value = v.startsWith("builtin:") ? schema.builtin_shapes[Number(v.slice(8))]?.value : { file: { name: v.slice(5) } };
  const problem = value ? setFields([[slot.path, JSON.stringify(value)]]) : null;
  if (problem) showError(problem);
}

/**
 * Points the slot's design field at these files (added to a `multiple` slot's list), through
 * fillSlot, which also applies the job kind's rule for a filled slot (e.g. a lattice's domain
 * becomes the loaded solid); returns the problem or null.
 */
function useFiles(slot, names) {
  const had = namedFiles(getPath(state.design, slot.path)).map((f) => f.name);
  const all = slot.kind === "volume" ? names : slot.multiple ? [...new Set([...had, ...names])] : [names[names.length - 1]];
  try {
    let next = weft.fillSlot(state.json, slot.name, all);
    // The part names the design (downloads, G-code header), unless the user named it.
    const part = currentSlots().find((s) => s.kind === "mesh" && !s.multiple);
    const name = String(state.design?.name ?? "");
    if (part?.name === slot.name && (state.autoNames.has(name) || !name.trim())) {
      const stem = fileStem(all[all.length - 1]);
      if (stem) {
        state.autoNames.add(stem);
        next = weft.setField(next, "name", JSON.stringify(stem));
      }
    }
    setDesign(next);
    return null;
  } catch (err) {
    return messageOf(err);
  }
}

/** A file name without folders and extension, as a design name. */
function fileStem(name) {
  const base = String(name).split(/[\\/]/).pop() ?? "";
  const i = base.lastIndexOf(".");
  return (i > 0 ? base.slice(0, i) : base).replace(/[\u0000-\u001f\u007f]/g, "").trim().slice(0, 80);
}

/**
 * The files of a drop, folders walked (names are paths inside the dropped folder, e.g.
 * "knee/IM0001"), in name order; plain files when the browser cannot list folders.
 */
async function droppedFiles(dataTransfer) {
  const items = [...(dataTransfer?.items ?? [])].map((i) => i.webkitGetAsEntry?.()).filter(Boolean);
  if (!items.length || !items.some((e) => e.isDirectory)) return [...(dataTransfer?.files ?? [])];
  const out = [];
  const MAX_FILES = 20000; // a bound on what a drop may list (the reader has its own)
  async function walk(entry, prefix, depth) {
    if (out.length >= MAX_FILES || depth > 8) return;
    if (entry.isFile) {
      const file = await new Promise((resolve) => entry.file(resolve, () => resolve(null)));
      if (file) out.push(prefix ? new File([file], `${prefix}${file.name}`) : file);
      return;
    }
    const reader = entry.createReader();
    for (;;) {
      const batch = await new Promise((resolve) => reader.readEntries(resolve, () => resolve([])));
      if (!batch.length) break;
      for (const child of batch) await walk(child, `${prefix}${entry.name}/`, depth + 1);
    }
  }
  for (const entry of items) await walk(entry, "", 0);
  return out.sort((a, b) => (a.name < b.name ? -1 : a.name > b.name ? 1 : 0));
}

/** Reads files into a slot (worker first, so a bad file is refused at once), then uses them. */
async function loadIntoSlot(slot, fileList) {
  hideError();
  const files = slot.multiple ? fileList : fileList.slice(-1);
  const wrong = files.filter((f) => !accepts(slot, f.name));
  if (wrong.length) {
    showError(`${wrong.map((f) => f.name).join(", ")}: ${slot.label ?? slot.name} takes ${(slot.accept ?? []).join(", ")} files.`);
    return;
  }
  const loaded = [];
  for (const file of files) {
    const token = jobs.begin(`reading ${file.name}`);
    try {
      // The File goes to the worker as a Blob handle: its bytes are not copied here.
      performance.mark("weft:load");
      const res = await workers.request({ type: MSG.LOAD, slot: slot.name, name: file.name, blob: file });
      performance.mark("weft:loaded");
      state.files.set(file.name, { slot: slot.name, name: file.name, blob: file, info: res.info ?? {} });
      filesChanged();
      loaded.push(file.name);
    } catch (err) {
      if (!err.cancelled) showError(messageOf(err));
    } finally {
      jobs.end(token);
    }
  }
  if (!loaded.length) return;
  if (!slot.multiple || slot.kind === "volume") {
    // One file (one series) per slot: what was loaded replaces the others.
    for (const f of filesOf(slot)) if (!loaded.includes(f.name)) forgetFile(f.name);
  }
  const problem = useFiles(slot, loaded);
  renderSlots();
  if (problem) {
    showError(problem);
    return;
  }
  if (!missingFiles().length) runDesign();
}

function forgetFile(name) {
  if (!state.files.delete(name)) return;
  workers.post({ type: MSG.UNLOAD, name });
  filesChanged();
}

/** The loaded files changed: results and estimates made before are of other inputs. */
function filesChanged() {
  state.filesVersion++;
  refreshFreshness();
  scheduleEstimate();
}

/** Removes a file from its slot; the design falls back to the default value of the slot. */
function removeFromSlot(slot, name) {
  forgetFile(name);
  const value = getPath(state.design, slot.path);
  const named = namedFiles(value).map((f) => f.name);
  if (named.includes(name)) {
    let next;
    const rest = named.filter((n) => n !== name);
    if (slot.multiple && rest.length) {
      // The slot's own rule applies to what is left (a foam keeps one V*/H* row per region).
      try {
        setDesign(weft.fillSlot(state.json, slot.name, rest));
      } catch (err) {
        showNotice(`${name} was removed; the design still names it (${messageOf(err)}).`);
      }
      renderSlots();
      return;
    }
    if (slot.multiple) next = { files: rest };
    else {
      const fallback = getPath(defaults, slot.path);
      next = fallback && !namedFiles(fallback).length ? fallback : schema.builtin_shapes[0]?.value ?? null;
    }
    const problem = setFields([[slot.path, JSON.stringify(next)]]);
    if (problem) showNotice(`${name} was removed; the design still names it (${problem}).`);
  }
  renderSlots();
}

// ---------------------------------------------------------------------------------------
// Views (schema.job_kinds[].views): one card each, fed by `inspect` requests
// ---------------------------------------------------------------------------------------
/** view id → {view, card, canvas, range, number, info, legend, last, seq, timer, count, answers, items} */
const viewCards = new Map();
let viewsKey = null;

function buildViews() {
  viewsKey = jobKind().name;
  for (const v of viewCards.values()) { clearTimeout(v.timer); clearTimeout(v.playTimer); v.playing = false; }
  viewCards.clear();
  const host = $("views");
  host.replaceChildren();
  for (const view of jobKind().views ?? []) {
    const card = document.createElement("section");
    card.className = "card view-card";
    card.dataset.view = view.id;
    card.dataset.shape = view.shape;
    const head = document.createElement("div");
    head.className = "card-head";
    const h2 = document.createElement("h2");
    h2.textContent = view.label ?? view.id;
    if (view.doc) h2.title = view.doc;
    const id = `view-${view.id}-index`;
    const label = document.createElement("label");
    label.className = "inline";
    label.htmlFor = id;
    label.textContent = (view.index_label ?? "index").toLowerCase();
    const number = document.createElement("input");
    number.type = "number";
    number.id = id;
    number.min = "1";
    number.max = "1";
    number.step = "1";
    number.value = "1";
    number.inputMode = "numeric";
    const info = document.createElement("output");
    info.className = "hint";
    info.htmlFor = id;
    head.append(h2, label, number, info);
    const range = document.createElement("input");
    range.type = "range";
    range.className = "view-range";
    range.min = "1";
    range.max = "1";
    range.value = "1";
    range.setAttribute("aria-label", `${view.label ?? view.id}: ${view.index_label ?? "index"}`);
    const box = document.createElement("div");
    box.className = "canvas-box";
    const canvas = document.createElement("canvas");
    canvas.setAttribute("aria-label", `${view.label ?? view.id}${view.doc ? `: ${view.doc}` : ""}`);
    box.append(canvas);
    const legend = document.createElement("div");
    legend.className = "mini-legend";
    card.append(head, range, box, legend);
    host.append(card);
    // Drawing a points field on the view (meta.draw of the answer: which field, which data
    // axis goes in each slot of a pair): clicks add corners, Finish writes the field.
    const tools = document.createElement("div");
    tools.className = "view-tools";
    tools.hidden = true;
    const drawButton = document.createElement("button");
    drawButton.type = "button";
    drawButton.className = "view-draw";
    const finishButton = document.createElement("button");
    finishButton.type = "button";
    finishButton.className = "view-finish";
    finishButton.hidden = true;
    const cancelButton = document.createElement("button");
    cancelButton.type = "button";
    cancelButton.className = "view-cancel";
    cancelButton.textContent = "Cancel";
    cancelButton.hidden = true;
    // A mesh view whose answer says `meta.stl` can be downloaded as an STL.
    const stlButton = document.createElement("button");
    stlButton.type = "button";
    stlButton.className = "view-stl";
    stlButton.textContent = "Download STL";
    stlButton.hidden = true;
    // A view whose answer says `meta.play` steps through its indices by itself (a print
    // sequence): Play advances one index per answer, at most every PLAY_STEP_MS.
    const playButton = document.createElement("button");
    playButton.type = "button";
    playButton.className = "view-play";
    playButton.textContent = "▶ Play";
    playButton.hidden = true;
    tools.append(playButton, drawButton, finishButton, cancelButton, stlButton);
    card.append(tools);
    // An image's value window (black … white): starts at the answer's meta.window, kept
    // while the user steps through slices; drawn locally (no new request).
    const windowBox = document.createElement("div");
    windowBox.className = "view-window";
    windowBox.hidden = view.shape !== "image";
    const windowInputs = ["from", "to"].map((which) => {
      const wrap = document.createElement("label");
      wrap.className = "inline";
      const input = document.createElement("input");
      input.type = "number";
      input.step = "any";
      input.className = `view-window-${which}`;
      input.setAttribute("aria-label", `${view.label ?? view.id}: window ${which}`);
      wrap.append(which === "from" ? "window " : "to ", input);
      windowBox.append(wrap);
      return input;
    });
    const windowUnit = document.createElement("span");
    windowUnit.className = "hint";
    windowBox.append(windowUnit);
    card.append(windowBox);
    const v = { view, card, canvas, range, number, info, legend, tools, playButton, playing: false, playTimer: 0, drawButton, finishButton, cancelButton, stlButton, drawing: null, frame: null, last: null, seq: 0, timer: 0, count: 0, answers: 0, items: 0, windowInputs, windowUnit, window: null };
    for (const input of windowInputs) input.addEventListener("change", () => {
      const [a, b] = windowInputs.map((x) => x.valueAsNumber);
      v.window = Number.isFinite(a) && Number.isFinite(b) && b > a ? [a, b] : null;
      redrawView(v);
    });
    playButton.addEventListener("click", () => setPlaying(v, !v.playing));
    drawButton.addEventListener("click", () => { v.drawing = []; syncDrawTools(v); redrawView(v); });
    cancelButton.addEventListener("click", () => { v.drawing = null; syncDrawTools(v); redrawView(v); });
    finishButton.addEventListener("click", () => finishDrawing(v));
    stlButton.addEventListener("click", () => {
      if (!v.last?.data?.length) return;
      const name = fileStem(String(state.design?.name ?? "")) || "weft";
      const bytes = weft.meshStl(v.last.data, name);
      download(bytes, `${name}-${view.id}.stl`, "model/stl");
    });
    canvas.addEventListener("click", (e) => {
      if (!v.drawing || !v.frame?.toData) return;
      const r = canvas.getBoundingClientRect();
      v.drawing.push(v.frame.toData(e.clientX - r.left, e.clientY - r.top));
      syncDrawTools(v);
      redrawView(v);
    });
    number.addEventListener("change", () => { setPlaying(v, false); range.value = number.value; scheduleInspect(0, v); });
    range.addEventListener("input", () => { setPlaying(v, false); number.value = range.value; scheduleInspect(INSPECT_DEBOUNCE_MS / 2, v); });
    new ResizeObserver(() => redrawView(v)).observe(box);
    viewCards.set(view.id, v);
  }
  host.hidden = viewCards.size === 0;
}

/** Time between the steps of a playing view, ms (or longer: the next step waits for its answer). */
const PLAY_STEP_MS = 120;

/** Starts or stops a view's playback (from the start when it is at its last index). */
function setPlaying(v, on) {
  clearTimeout(v.playTimer);
  v.playing = on && v.count > 1;
  v.playButton.textContent = v.playing ? "❚❚ Pause" : "▶ Play";
  v.playButton.setAttribute("aria-pressed", String(v.playing));
  if (!v.playing) return;
  if ((v.number.valueAsNumber || 1) >= v.count) v.number.value = v.range.value = "1";
  v.playTimer = setTimeout(() => requestInspect(v), 0);
}

/** After an answer of a playing view: the next index, or stop at the last. */
function playNext(v) {
  if (!v.playing) return;
  const next = (v.number.valueAsNumber || 1) + 1;
  if (next > v.count) { setPlaying(v, false); return; }
  v.playTimer = setTimeout(() => {
    if (!v.playing) return;
    v.number.value = v.range.value = String(next);
    requestInspect(v);
  }, PLAY_STEP_MS);
}

/** Asks the worker for each view (or one) after `delay` ms without further edits. */
function scheduleInspect(delay = INSPECT_DEBOUNCE_MS, only = null) {
  for (const v of only ? [only] : viewCards.values()) {
    clearTimeout(v.timer);
    v.timer = setTimeout(() => requestInspect(v), delay);
  }
}

async function requestInspect(v) {
  const mine = ++v.seq;
  const missing = missingFiles();
  if (missing.length) {
    v.info.textContent = `load ${missing.map((m) => m.name).join(", ")} to see this`;
    return;
  }
  const index = Math.max(0, Math.round(v.number.valueAsNumber || 1) - 1);
  v.info.textContent = "…";
  v.info.classList.remove("field-error");
  let res;
  try {
    res = await workers.request({ type: MSG.INSPECT, design: state.json, view: v.view.id, index, key: `view:${v.view.id}` });
  } catch (err) {
    if (mine === v.seq && !err.cancelled) {
      setMessage(v.info, messageOf(err));
      v.info.classList.add("field-error");
    }
    return;
  }
  if (mine !== v.seq || res.stale) return; // a newer request is on its way
  v.last = res;
  v.answers++;
  v.count = res.count;
  const max = String(Math.max(1, res.count));
  for (const el of [v.number, v.range]) el.max = max;
  v.range.hidden = res.count < 2;
  if (res.index !== index && document.activeElement !== v.number) v.number.value = v.range.value = String(res.index + 1);
  syncDrawTools(v);
  redrawView(v);
  const what = res.shape === "image" ? `${res.meta?.width ?? 0} × ${res.meta?.height ?? 0} px`
    : `${v.items.toLocaleString("en-US")} ${res.shape === "mesh" ? "triangles" : "segments"}`;
  const caption = typeof res.meta?.caption === "string" ? `${res.meta.caption} · ` : "";
  v.info.textContent = `of ${Math.max(1, res.count)} · ${caption}${what} · ${Math.round(res.ms)} ms`;
  playNext(v);
}

/** Shows the view's draw tools for the answer's `meta.draw` (hidden without one). */
function syncDrawTools(v) {
  const spec = v.last?.meta?.draw;
  const stl = v.last?.shape === "mesh" && Boolean(v.last?.meta?.stl) && v.last.data?.length > 0;
  const play = Boolean(v.last?.meta?.play) && v.count > 1;
  if (!play && v.playing) setPlaying(v, false);
  v.playButton.hidden = !play;
  v.stlButton.hidden = !stl;
  v.drawButton.hidden = !spec;
  v.tools.hidden = !spec && !stl && !play;
  if (!spec) { v.drawing = null; v.finishButton.hidden = v.cancelButton.hidden = true; return; }
  const on = Array.isArray(v.drawing);
  v.drawButton.hidden = on;
  v.drawButton.textContent = spec.label ?? "Draw";
  v.finishButton.hidden = !on;
  v.cancelButton.hidden = !on;
  v.finishButton.disabled = !on || v.drawing.length < (spec.min_points ?? 3);
  v.finishButton.textContent = on ? `Finish (${v.drawing.length} point${v.drawing.length === 1 ? "" : "s"})` : "Finish";
  v.canvas.classList.toggle("drawing", on);
}

/** Writes the drawn corners into the field `meta.draw.path` (pairs ordered by `meta.draw.pair`). */
function finishDrawing(v) {
  const spec = v.last?.meta?.draw;
  if (!spec || !v.drawing) return;
  const round = (x) => Math.round(x * 1e4) / 1e4;
  const pairs = v.drawing.map(([x, y]) => (spec.pair ?? ["x", "y"]).map((k) => round(k === "x" ? x : y)));
  const problem = setFields([[spec.path, JSON.stringify(pairs)]]);
  if (problem) {
    v.info.textContent = problem;
    v.info.classList.add("field-error");
    return;
  }
  v.drawing = null;
  syncDrawTools(v);
}

function redrawView(v) {
  if (!v.card.isConnected) return;
  if (v.last?.shape === "image") {
    // The user's window, else the view's own (meta.window), shown in the inputs.
    const win = v.window ?? (Array.isArray(v.last.meta?.window) ? v.last.meta.window : null);
    if (win) v.windowInputs.forEach((el, i) => { if (document.activeElement !== el) el.value = String(win[i]); });
    v.windowUnit.textContent = v.last.meta?.unit ?? "";
    v.last.window = v.window;
  }
  const r = drawView(v.canvas, v.last, styles);
  v.frame = r.toData ? r : null;
  // The corners drawn so far, over the view.
  if (v.drawing?.length && v.frame) {
    const ctx = v.canvas.getContext("2d");
    ctx.save();
    ctx.scale(v.frame.dpr, v.frame.dpr);
    ctx.strokeStyle = ctx.fillStyle = "#f5d76e";
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    v.drawing.forEach(([x, y], i) => { const [px, py] = v.frame.toPx(x, y); if (i) ctx.lineTo(px, py); else ctx.moveTo(px, py); });
    ctx.stroke();
    for (const [x, y] of v.drawing) { const [px, py] = v.frame.toPx(x, y); ctx.fillRect(px - 3, py - 3, 6, 6); }
    ctx.restore();
  }
  v.items = r.items;
  // A view may name its own entries (meta.legend: feature code → words), e.g. "seed points"
  // drawn in the lattice colour; otherwise the feature's name.
  const named = v.last?.meta?.legend ?? {};
  // An image's overlay names its own lines and colours (meta.overlay_legend).
  const overlayLegend = new Map((v.last?.meta?.overlay_legend ?? []).map((e) => [String(e.code), e]));
  const entries = Object.keys(r.counts).map((code) => overlayLegend.has(code)
    ? [overlayLegend.get(code).color ?? "#e0b84d", String(overlayLegend.get(code).label ?? code)]
    : [styles.get(Number(code))?.color ?? "#e0b84d",
      typeof named[code] === "string" ? named[code] : styles.get(Number(code))?.label ?? `feature ${code}`]);
  if (r.range) entries.push([null, `${formatNumber(r.range[0], 4)} … ${formatNumber(r.range[1], 4)}${v.last?.meta?.unit ? ` ${v.last.meta.unit}` : ""}`]);
  v.legend.replaceChildren(...entries.map(([color, text]) => {
    const el = document.createElement("span");
    if (color) {
      const sw = document.createElement("span");
      sw.className = "swatch";
      sw.style.background = color;
      el.append(sw, " ");
    } else {
      const ramp = document.createElement("span");
      ramp.className = "ramp grey";
      el.append(ramp, " ");
    }
    el.append(text);
    return el;
  }));
}

// ---------------------------------------------------------------------------------------
// Pattern picker: any field with widget "pattern_picker", thumbnails of schema.patterns
// ---------------------------------------------------------------------------------------
/** Pattern thumbnails: kind → {segments}, computed once per pattern and seed. */
const thumbs = { cache: new Map(), seed: null };

function thumbnailSeed() {
  return Number(state.design?.seed ?? 1);
}

function thumbnail(p) {
  let t = thumbs.cache.get(p.kind);
  if (t) return t;
  const seed = thumbnailSeed();
  let segments = new Float32Array(0);
  for (const s of [seed, BigInt(seed)]) { // u64 seeds cross as BigInt
    try {
      segments = weft.patternThumbnail(JSON.stringify(p.value ?? { kind: p.kind }), THUMB_MM, s);
      break;
    } catch { /* try the other seed type; drawn blank otherwise */ }
  }
  thumbs.cache.set(p.kind, (t = { segments }));
  return t;
}

/** Draws every thumbnail of one picker (when it is made, and when the seed changes). */
function drawThumbnails(picker) {
  const half = THUMB_MM / 2;
  for (const c of picker.querySelectorAll("canvas[data-pattern]")) {
    const p = schema.patterns.find((q) => q.kind === c.dataset.pattern);
    drawSegments2d(c, thumbnail(p).segments, { stride: 4, frame: [-half, -half, half, half], lineWidth: 1, color: THUMB_COLOR });
  }
}

function patternOf(view) {
  const v = getPath(state.design, view.f.path);
  return view.f.kind === "choice" ? v : v?.kind;
}

/**
 * Thumbnail buttons after each field with widget "pattern_picker". A picker lives as long as
 * its field's row (buildForm replaces both); a form render only updates which one is pressed.
 */
function renderPatternPickers() {
  const patterns = schema.patterns ?? [];
  const views = [...fieldViews.values()].filter((v) => v.f.widget === "pattern_picker");
  if (!views.length || !patterns.length) return;
  const reseeded = thumbs.seed !== thumbnailSeed();
  if (reseeded) {
    // Voronoi depends on the seed: redraw all with the design's.
    thumbs.cache.clear();
    thumbs.seed = thumbnailSeed();
  }
  views.forEach((view, n) => {
    const made = !view.picker;
    if (made) {
      const picker = document.createElement("div");
      picker.id = n === 0 ? "pattern-picker" : `pattern-picker-${n}`;
      picker.className = "pattern-picker";
      picker.setAttribute("role", "group");
      picker.setAttribute("aria-label", view.f.label ?? "Patterns");
      for (const p of patterns) {
        const b = document.createElement("button");
        b.type = "button";
        b.className = "pattern";
        b.dataset.pattern = p.kind;
        b.title = p.label ?? p.kind;
        const c = document.createElement("canvas");
        c.dataset.pattern = p.kind;
        c.width = 64;
        c.height = 64;
        const label = document.createElement("span");
        label.textContent = p.label ?? p.kind.replace(/_/g, " ");
        b.append(c, label);
        b.addEventListener("click", () => {
          const value = view.f.kind === "choice" ? p.kind : (p.value ?? { kind: p.kind });
          const problem = setFields([[view.f.path, JSON.stringify(value)]]);
          if (problem) showError(problem);
        });
        picker.append(b);
      }
      view.wrap.after(picker);
      view.picker = picker;
    }
    if (made || reseeded) drawThumbnails(view.picker);
    const current = patternOf(view);
    for (const b of view.picker.querySelectorAll("button")) b.setAttribute("aria-pressed", String(b.dataset.pattern === current));
  });
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

  /** What the worker was asked for and uses (see threadsToAsk and the `ready` message). */
  threads: { asked: 1, used: null, cores: 1, isolated: false, note: "" },
  /** The current worker's pool workers (pool-worker.js), terminated with it. */
  pool: [],
  /** Why the pool's workers cannot start here ("" until they fail once): one thread from then on. */
  poolBroken: "",

  start() {
    this.generation++;
    const ask = threadsToAsk(this.poolBroken);
    this.threads = { ...ask, used: null };
    showThreads();
    const url = new URL("./worker.js", import.meta.url);
    if (ask.asked > 1) url.searchParams.set("threads", String(ask.asked));
    const w = new Worker(url, { type: "module", name: `weft-${this.generation}` });
    this.worker = w;
    w.onmessage = ({ data }) => this.onMessage(w, data);
    w.onerror = (e) => {
      e.preventDefault();
      if (w === this.worker) this.crashed(e.message || "the worker script failed");
    };
    w.onmessageerror = () => {
      if (w === this.worker) this.crashed("a message could not be read");
    };
    // Give the new worker every file the page holds, in its slot (Blob handles, not copies).
    for (const f of state.files.values()) {
      this.request({ type: MSG.LOAD, slot: f.slot, name: f.name, blob: f.blob }).catch(() => {});
    }
  },

  /**
   * Starts the pool's threads: one pool worker each, joining the worker's module and shared
   * memory. Runs the worker has queued start as they join.
   */
  startPool(w, { module, memory }, threads) {
    for (let i = 0; i < threads; i++) {
      const p = new Worker(new URL("./pool-worker.js", import.meta.url), { type: "module", name: `weft-${this.generation}-thread-${i + 1}` });
      const failed = (message) => {
        if (w !== this.worker) return;
        this.poolBroken = `the thread pool's workers could not run (${message})`;
        this.crashed(this.poolBroken);
      };
      p.onmessage = ({ data }) => { if (data?.type === "failed") failed(data.message); };
      p.onerror = (e) => { e.preventDefault(); failed(e.message || "a pool worker stopped"); };
      p.postMessage({ module, memory });
      this.pool.push(p);
    }
  },

  /** Where Cancel is said to the threaded module's loops: {memory, cancelAt} (null: plain module). */
  cancelWord: null,

  /**
   * Terminates the worker and every pool worker now. A worker busy in wasm dies only two
   * seconds after terminate() (Chromium), so the threaded module is first told through its
   * shared memory: its loops skip what has not started and the run throws (par::cancel_flag).
   */
  stop() {
    if (this.cancelWord) {
      try {
        Atomics.store(new Int32Array(this.cancelWord.memory.buffer), this.cancelWord.cancelAt >>> 2, 1);
      } catch { /* terminate() alone, then */ }
      this.cancelWord = null;
    }
    this.worker?.terminate();
    for (const p of this.pool) p.terminate();
    this.pool = [];
    this.worker = null;
  },

  /** Stops all work now (terminate) and starts a fresh worker with the files reloaded. */
  restart(reason) {
    this.stop();
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
      this.stop();
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
  request(msg, onProgress, onAhead) {
    if (!this.worker) this.start();
    const id = this.nextId++;
    msg.id = id;
    return new Promise((resolve, reject) => {
      this.pending.set(id, { resolve, reject, type: msg.type, onProgress, onAhead });
      this.worker.postMessage(msg, msg.bytes ? [msg.bytes] : []);
    });
  },

  /** Sends a message that is not answered (unload, cancel). */
  post(msg) {
    if (!this.worker) return;
    msg.id = this.nextId++;
    this.worker.postMessage(msg);
  },

  onMessage(w, msg) {
    if (w !== this.worker) return; // a terminated worker's late message
    if (msg.type === MSG.READY) {
      this.threads = { ...this.threads, used: msg.threads ?? 1, note: msg.note || this.threads.note };
      if (msg.pool) {
        this.cancelWord = { memory: msg.pool.memory, cancelAt: msg.pool.cancelAt };
        this.startPool(w, msg.pool, msg.threads);
      }
      showThreads();
      return;
    }
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
    if (msg.type === MSG.AHEAD) {
      p?.onAhead?.(msg);
      return;
    }
    if (!p) {
      if (msg.type === MSG.ERROR) showError(msg.message); // e.g. a failed unload
      return;
    }
    this.pending.delete(msg.id);
    if (msg.type === MSG.ERROR) p.reject(new Error(msg.message));
    else p.resolve(msg);
  },
};

// --- jobs and the progress bar ----------------------------------------------------------
const jobs = {
  active: new Map(), // token → label
  /** stages of the running job ([{name, label}] from the job kind), for the overall bar */
  stages: [],
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
    this.ahead(null);
    document.body.classList.remove("busy");
  },
  endAll() {
    for (const t of [...this.active.keys()]) this.end(t);
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
    const i = this.stages.findIndex((s) => s.name === stage);
    const label = i >= 0 ? this.stages[i].label ?? stage : stage;
    if (fraction === null) {
      bar.removeAttribute("value"); // indeterminate
      $("progress-label").textContent = `${label}…`;
      return;
    }
    const overall = i < 0 ? fraction : (i + Math.min(1, Math.max(0, fraction))) / this.stages.length;
    bar.value = overall;
    $("progress-label").textContent = `${label}… ${Math.round(overall * 100)}%`;
    $("progress-label").dataset.stage = stage;
  },
};

function cancel() {
  if (!jobs.active.size) return;
  workers.restart("cancelled");
  jobs.endAll();
  showNotice("Cancelled: the worker was stopped and restarted. Your design is kept.");
}

// ---------------------------------------------------------------------------------------
// Freshness: a result belongs to the design it was made from; the next run is estimated
// ---------------------------------------------------------------------------------------
/** Why the result shown does not match the form (null when it does, or when there is none). */
function staleReason() {
  const r = state.result;
  if (!r || r.json === null || r.json === undefined) return null;
  const invalid = invalidFields();
  if (invalid.length) {
    const v = invalid[0];
    return `“${v.f.label || v.f.path}” is not valid, so the design cannot run: the preview, numbers and download are of the previous run.`;
  }
  if (r.json !== state.json) return "Settings changed since this result: the preview, numbers and download are of the previous run.";
  if (r.files !== state.filesVersion) return "The input files changed since this result: the preview, numbers and download are of the previous run.";
  return null;
}

/** Whether `made` (a result or an estimate) was made from the current design and files. */
function isCurrent(made) {
  return Boolean(made) && made.json === state.json && made.files === state.filesVersion;
}

/** Dims the preview, numbers and cards of a result that no longer matches the design. */
function refreshFreshness() {
  const reason = staleReason();
  document.querySelector(".view")?.classList.toggle("stale-result", Boolean(reason));
  $("stale").hidden = !reason;
  $("stale-text").textContent = reason ?? "";
  $("stale-run").disabled = invalidFields().length > 0;
  const download = $("download");
  download.title = reason ? "Runs the changed design first, then saves its G-code" : "Save the G-code of the last result";
  download.dataset.stale = String(Boolean(reason));
}

let estimateTimer = 0;
let estimateSeq = 0;
/** Estimates the current design in the worker (debounced), shows it, then maybe re-runs. */
function scheduleEstimate() {
  clearTimeout(estimateTimer);
  estimateTimer = setTimeout(estimateNow, ESTIMATE_DEBOUNCE_MS);
}

async function estimateNow() {
  const json = state.json;
  const files = state.filesVersion;
  const seq = ++estimateSeq;
  const missing = missingFiles();
  if (missing.length) {
    state.estimate = { json, files, error: `load ${missing.map((m) => m.name).join(", ")} to estimate` };
    showEstimate();
    return;
  }
  try {
    const { plan } = await workers.request({ type: MSG.ESTIMATE, design: json });
    if (seq !== estimateSeq) return;
    state.estimate = { json, files, plan };
  } catch (err) {
    if (err.cancelled || seq !== estimateSeq) return;
    state.estimate = { json, files, error: messageOf(err) };
  }
  showEstimate();
  maybeAutoRun();
}

/** The estimate line: what the next run will make and take. */
function showEstimate() {
  const e = state.estimate;
  const el = $("estimate");
  el.classList.remove("over", "ask");
  if (!isCurrent(e)) {
    el.textContent = "Estimating…";
    return;
  }
  if (e.error) {
    el.textContent = `Next run: ${e.error}`;
    return;
  }
  const p = e.plan;
  el.textContent = `Next run: ${planSummary(p)}`;
  if (p.refusal) {
    el.classList.add("over");
    el.textContent += ` · too big: ${p.refusal}`;
  } else if (p.ask) {
    el.classList.add("ask");
    el.textContent += " · big: you will be asked first";
  }
}

/** A plan in a few words: layers, segments, G-code, time, memory. */
function planSummary(p) {
  const quantity = (key) => Math.max(0, ...(p.stages ?? []).flatMap((s) => (s.quantities ?? []).filter((q) => q.key === key).map((q) => q.value)));
  const count = (n) => (n >= 1e6 ? `${(n / 1e6).toFixed(n >= 1e7 ? 0 : 1)}M` : n >= 1e4 ? `${Math.round(n / 1e3)}k` : String(Math.round(n)));
  const parts = [];
  const layers = quantity("layers");
  if (layers) parts.push(`${count(layers)} layer${layers === 1 ? "" : "s"}`);
  if (p.segments) parts.push(`${count(p.segments)} segments`);
  if (p.gcode_bytes) parts.push(`${humanBytes(p.gcode_bytes)} of G-code`);
  // The time on the threads the worker uses (the plan counts each stage's parallel share).
  const s = p.wall_seconds ?? p.seconds;
  const on = p.threads > 1 ? ` on ${p.threads} threads` : "";
  parts.push(s < 1 ? `under 1 s${on}` : `about ${formatSeconds(s)}${on}`);
  if (p.peak_bytes) parts.push(`${humanBytes(p.peak_bytes)} of memory`);
  return parts.join(" · ");
}

function formatSeconds(s) {
  if (s < 90) return `${Math.round(s)} s`;
  if (s < 5400) return `${Math.round(s / 60)} min`;
  return `${(s / 3600).toFixed(1)} h`;
}

function autoRunWanted() {
  try {
    return localStorage.getItem(AUTO_RUN_KEY) !== "0";
  } catch {
    return true;
  }
}

/** Re-runs a light job after an edit (live preview), when the user lets it and nothing runs. */
function maybeAutoRun() {
  const e = state.estimate;
  if (!$("auto-run").checked || !e?.plan || !isCurrent(e)) return;
  if (!state.result || state.result.json === null || isCurrent(state.result)) return; // nothing shown from a design, or fresh
  const p = e.plan;
  if (p.refusal || p.ask || !((p.wall_seconds ?? p.seconds) < AUTO_RUN_SECONDS) || jobs.active.size) return;
  runDesign({ auto: true });
}

/** Download: the result when it matches the design, else the design is run first. */
function downloadResult() {
  const r = state.result;
  if (!r?.gcode) return;
  if (!staleReason()) {
    download(r.gcode, r.fileName, "text/x-gcode");
    return;
  }
  if (invalidFields().length) {
    runDesign(); // says which field to fix
    return;
  }
  runDesign({ then: () => download(state.result.gcode, state.result.fileName, "text/x-gcode") });
  showNotice("The settings changed since the last run: running the design first; the download starts when it is done.");
}

// ---------------------------------------------------------------------------------------
// Actions
// ---------------------------------------------------------------------------------------
let latestRun = 0;

/**
 * Runs the design after stating its work: a run over a budget is refused with the estimate's
 * message, a big one (over the soft thresholds of the plan) is asked about first.
 * @param {{confirmed?: boolean, fromLink?: boolean}} opts  confirmed: the user said "run
 *   anyway"; fromLink: opened from a share link (which never runs a big job by itself)
 */
async function runDesign({ confirmed = false, fromLink = false, auto = false, then = null } = {}) {
  const invalid = invalidFields();
  if (invalid.length) {
    // The form shows a value the design does not hold: running would use the last valid one.
    if (!auto) {
      const v = invalid[0];
      const label = v.f.label || v.f.path;
      const said = v.error.textContent.includes(label) ? v.error.textContent : `${label}: ${v.error.textContent}`;
      showError(`${said}\nFix ${invalid.length > 1 ? `this and ${invalid.length - 1} other field${invalid.length > 2 ? "s" : ""}` : "it"} (or undo) to run; nothing was run.`);
      v.inputs[0]?.focus();
    }
    return;
  }
  const missing = missingFiles();
  if (missing.length) {
    const { slot, name } = missing[0];
    showError(`The design uses ${name}, which is not loaded: load it into “${slot.label ?? slot.name}” ` +
      `(drop it on the page)${slot.kind === "mesh" && schema.builtin_shapes.length ? " or pick a built-in shape" : ""}.`);
    return;
  }
  if (!auto) $("notice").hidden = true; // an old notice (cancelled, opened…) is about the past
  const token = jobs.begin("starting");
  const mine = ++latestRun;
  const name = designName();
  const ext = gcodeExtension();
  const json = state.json;
  const files = state.filesVersion;
  jobs.stages = jobKind().stages ?? [];
  try {
    // The estimate made after the last edit is this design's plan; otherwise ask for it.
    const known = isCurrent(state.estimate) ? state.estimate.plan : null;
    performance.mark("weft:estimate");
    const plan = known ?? (await workers.request({ type: MSG.ESTIMATE, design: json })).plan;
    performance.mark("weft:estimated");
    if (!known) {
      state.estimate = { json, files, plan };
      showEstimate();
    }
    if (plan.refusal) {
      showError(`${plan.refusal}. Nothing was run; your design is kept.`);
      return;
    }
    if (plan.ask && !confirmed) {
      const opened = fromLink ? "This shared design was opened without running it: it is " : "This is ";
      showNotice(`${opened}${plan.ask}, peak memory ${humanBytes(plan.peak_bytes)}. Run it anyway?`, null,
        { label: "Run anyway", run: () => runDesign({ confirmed: true, then }) });
      return;
    }
    performance.mark("weft:run");
    const res = await workers.request({ type: MSG.RUN, design: json }, (s, f) => jobs.progress(s, f),
      (a) => mine === latestRun && jobs.ahead(a, `${name}.ahead.${ext}`));
    performance.mark("weft:result");
    if (mine === latestRun) {
      showResult(res, `${name}.${ext}`, json, files);
      then?.();
    }
  } catch (err) {
    if (!err.cancelled) showError(messageOf(err));
  } finally {
    jobs.end(token);
  }
}

/** Opens files from the picker or a drop: designs, slot files, G-code. */
async function openFiles(fileList) {
  // One part dropped on a job that is not the default one (a lattice) may mean "fill this
  // part" or "slice this part": ask, with the choices the schema's job kinds allow.
  if (fileList.length === 1 && askWhatFileIsFor(fileList[0])) return;
  // Files for the same slot travel together (a `multiple` slot takes them all at once).
  const bySlot = new Map();
  for (const file of fileList) {
    // A .json is a weft design unless it is an input of a slot (a wireframe): look inside.
    const design = extOf(file.name) === ".json" && await looksLikeDesign(file);
    const slot = design ? null : slotFor(file.name) ?? await switchForSlot(file);
    if (slot) {
      if (!bySlot.has(slot)) bySlot.set(slot, []);
      bySlot.get(slot).push(file);
    } else {
      await openFile(file);
    }
  }
  for (const [slot, files] of bySlot) await loadIntoSlot(slot, files);
}

/** Whether a dropped .json is a weft design (it has a `job`), not a job's input file. */
async function looksLikeDesign(file) {
  try {
    const value = JSON.parse(await file.text());
    return Boolean(value) && typeof value === "object" && !Array.isArray(value) && "job" in value;
  } catch {
    return true; // not JSON at all: opened as a design, whose error says so
  }
}

/**
 * A file no slot of this job takes but another job kind's slot does (a wireframe dropped on
 * a slicing job): switches to that kind (the first, in the menu's order) and returns its slot.
 */
async function switchForSlot(file) {
  const ext = extOf(file.name);
  if (GCODE_EXT.includes(ext.slice(1))) return null; // previewed as it is
  // Only a slot that names the extension (a volume slot takes any file of a folder).
  const named = (s) => s.kind !== "volume" && (s.accept ?? []).some((a) => a.toLowerCase() === ext);
  const other = schema.job_kinds.find((k) => k.name !== jobKind().name && (k.slots ?? []).some(named));
  if (!other) return null;
  const problem = setFields([["job.kind", JSON.stringify(other.name)]]);
  if (problem) {
    showError(problem);
    return null;
  }
  showNotice(`${file.name} is a ${other.label ?? other.name} input: switched the job to “${other.label ?? other.name}”.`);
  return slotFor(file.name);
}

/** The job kind of the default design (the plain slicer). */
function defaultJobKind() {
  return schema.job_kinds.find((k) => k.name === defaults?.job?.kind) ?? null;
}

/**
 * A file dropped on a job other than the default one, which the default job also takes (a
 * part dropped on a lattice design): asks what it is for instead of guessing; true if asked.
 */
function askWhatFileIsFor(file) {
  const kind = jobKind();
  const plainKind = defaultJobKind();
  if (!plainKind || kind.name === plainKind.name) return false;
  const here = currentSlots().filter((s) => accepts(s, file.name));
  const there = (plainKind.slots ?? []).filter((s) => accepts(s, file.name));
  if (!here.length || !there.length) return false;
  if (here.some((s) => namedFiles(getPath(state.design, s.path)).some((f) => f.name === file.name))) return false;
  const actions = here.map((s) => ({ label: s.label ?? s.name, title: s.doc, run: () => loadIntoSlot(s, [file]) }));
  actions.push({
    label: plainKind.label ?? plainKind.name,
    title: plainKind.doc,
    run: async () => {
      const problem = setFields([["job.kind", JSON.stringify(plainKind.name)]]);
      if (problem) {
        showError(problem);
        return;
      }
      const slot = currentSlots().find((s) => accepts(s, file.name));
      if (slot) await loadIntoSlot(slot, [file]);
    },
  });
  const uses = here.map((s) => `its “${s.label ?? s.name}”${s.doc ? ` (${s.doc.replace(/\.$/, "")})` : ""}`).join(" or ");
  showNotice(`What is ${file.name} for? This design is a “${kind.label ?? kind.name}” job: use the file as ${uses}, ` +
    `or switch to “${plainKind.label ?? plainKind.name}” and use it as the part.`, null, actions);
  return true;
}

/**
 * The slot a file goes to: the one whose design field names it, else the first slot of the
 * job kind that accepts its extension.
 */
function slotFor(name) {
  const slots = currentSlots();
  return slots.find((s) => accepts(s, name) && namedFiles(getPath(state.design, s.path)).some((f) => f.name === name))
    ?? slots.find((s) => accepts(s, name)) ?? null;
}

async function openFile(file) {
  const ext = extOf(file.name).slice(1);
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
    jobs.stages = [];
    try {
      // The file goes as a Blob: the worker checks its size and reads it in pieces.
      const res = await workers.request({ type: MSG.ANALYZE, name: file.name, blob: file }, (s, f) => jobs.progress(s, f));
      showResult(res, file.name);
    } catch (err) {
      if (!err.cancelled) showError(messageOf(err));
    } finally {
      jobs.end(token);
    }
    return;
  }
  const takes = currentSlots().map((s) => `${s.label ?? s.name} (${(s.accept ?? []).join(", ")})`);
  showError(`${file.name}: this job opens ${[...takes, "G-code (.gcode)", "designs (.json)"].join(", ")}.`);
}

let resultCount = 0;
function showResult(res, fileName, json = null, files = state.filesVersion) {
  resultCount++;
  const { report, preview: buffers, gcode } = res;
  state.result = { report, gcode, fileName, ms: res.ms, json, files };
  $("download").disabled = !(gcode && gcode.byteLength);
  const origin = state.design?.printer?.origin;
  preview?.setResult(buffers, { origin: typeof origin === "string" ? origin : "corner" });
  performance.mark("weft:preview-set");
  renderStats(report, gcode, res.ms);
  renderReport($("report"), report, state);
  performance.mark("weft:shown");
  if (res.request === "run") scheduleInspect(0); // views of a loaded solid know their count now
  hideErrorUnlessCrash();
  refreshFreshness();
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
    ["Overlap", num(a.overlap_mm), "mm", "Length printed over the same place twice (0 is ideal)."],
    ["GIPPO score", num(a.gippo_score, 3), "", "The paper's equation 1 on this G-code: higher means longer and fewer paths."],
    ["Estimated time", formatDuration(a.estimated_time_s ?? g.estimated_time_s), "h:m:s"],
    ["G-code", gcode ? formatBytes(gcode.byteLength) : "–", ""],
  ];
  if (typeof ms === "number") rows.push(["Worker time", num(ms / 1000, 2), "s"]);
  const reused = (report?.stages ?? []).filter((s) => s.cached).length;
  if (reused) rows.push(["Stages reused", `${reused} of ${report.stages.length}`, ""]);
  $("stats").replaceChildren(metricList(rows.map(([label, value, unit, hint]) => ({ label, value, unit, hint })), ""), timeLine(report, ms));
}

/** "Where the time went": each stage's wall time in the worker, slowest first, and the threads. */
function timeLine(report, ms) {
  const p = document.createElement("p");
  p.className = "time-line";
  const times = (report?.timings ?? []).filter((t) => !t.cached && t.ms >= 0.5).sort((a, b) => b.ms - a.ms);
  const label = (name) => jobs.stages.find((s) => s.name === name)?.label ?? name;
  const parts = times.map((t) => `${label(t.stage)} ${t.ms >= 1000 ? `${(t.ms / 1000).toFixed(2)} s` : `${Math.round(t.ms)} ms`}`);
  const threads = report?.threads ?? 1;
  // Stages made before the run (a dropped mesh's import, a view's stage) are counted with the
  // result they made, so the parts can add up to more than the run's own time.
  const total = times.reduce((a, t) => a + t.ms, 0);
  const earlier = typeof ms === "number" && total > 1.1 * ms + 50 ? ", some of it before the run (loading a file, a view)" : "";
  p.textContent = `Where the time went: ${parts.length ? parts.join(" · ") : "nothing measurable (reused)"}${earlier} — ${threads} thread${threads === 1 ? "" : "s"}`;
  p.title = threads === 1 ? `${threadsWhy()} The weft CLI uses every core (weft run --threads N) and gives the same G-code.` : "";
  return p;
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
      : "the page is not cross-origin isolated (its host sends no COOP/COEP headers and no service worker added them)";
    return { asked: 1, cores, isolated: false, note };
  }
  return { asked: wanted, cores, isolated: true, note: wanted === 1 && param !== null ? "?threads=1 in the address" : "" };
}

/** Why the worker computes on one thread, as a sentence ("" when it uses more). */
function threadsWhy() {
  const t = workers.threads;
  if ((t.used ?? t.asked) > 1) return "";
  return t.note ? `One thread: ${t.note}.` : "One thread: this machine reports one core.";
}

/** The always-shown thread line: threads in use, and why only one. */
function showThreads() {
  const el = $("threads");
  if (!el) return;
  const t = workers.threads;
  const n = t.used ?? t.asked;
  el.textContent = `${t.used === null ? "starting " : ""}${n} thread${n === 1 ? "" : "s"}${n === 1 && t.note ? " (no shared memory here)" : ""}`;
  el.title = n > 1
    ? `The worker computes on ${n} threads (web workers sharing its memory; ${t.cores} core${t.cores === 1 ? "" : "s"} reported). Same G-code at any thread count.`
    : `${threadsWhy()} Same G-code at any thread count, only slower.`;
  el.dataset.threads = String(n);
  el.classList.toggle("one", n === 1 && Boolean(t.note));
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
  // Every loaded file with its slot; Rust keeps the ones the design names, small ones inside.
  let files;
  try {
    files = await Promise.all([...state.files.values()].map(async (f) => ({ slot: f.slot, name: f.name, bytes: new Uint8Array(await f.blob.arrayBuffer()) })));
  } catch (err) {
    showError(`Could not read a loaded file for the link (${messageOf(err)}); load it again.`);
    return;
  }
  let res;
  try {
    res = plain(weft.encodeShare(state.json, files));
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
  const embedded = res.embedded ?? [];
  const missing = res.missing ?? [];
  const size = `${url.length.toLocaleString("en-US")} characters${embedded.length ? `, ${embedded.join(", ")} included` : ""}`;
  const left = missing.length ? ` Not in the link (too large): ${missing.join(", ")}; whoever opens it is asked to load ${missing.length > 1 ? "them" : "it"}.` : "";
  showNotice(`${head} (${size}).${left}${res.note ? ` Note: ${res.note}.` : ""}`, url);
}

// ---------------------------------------------------------------------------------------
// UI wiring
// ---------------------------------------------------------------------------------------
/** Drag-and-drop over the whole page. */
const dropState = {
  depth: 0,
  reset() {
    this.depth = 0;
    $("drop-hint").hidden = true;
  },
};

function wireUi() {
  $("slice").addEventListener("click", () => runDesign());
  $("cancel").addEventListener("click", cancel);
  $("undo").addEventListener("click", undo);
  $("redo").addEventListener("click", redo);
  $("download").addEventListener("click", downloadResult);
  $("stale-run").addEventListener("click", () => runDesign());
  $("auto-run").checked = autoRunWanted();
  $("auto-run").addEventListener("change", (e) => {
    try {
      localStorage.setItem(AUTO_RUN_KEY, e.target.checked ? "1" : "0");
    } catch { /* storage disabled: the choice lasts this visit */ }
    maybeAutoRun();
  });
  $("download-design").addEventListener("click", () => download(`${state.json}\n`, `${designName()}.json`, "application/json"));
  $("share").addEventListener("click", share);
  $("file").addEventListener("change", async (e) => {
    const files = [...e.target.files];
    e.target.value = "";
    await openFiles(files);
  });
  $("examples").addEventListener("change", openExample);
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
      // A number typed and not yet committed (no change event before the shortcut) counts.
      const view = t instanceof HTMLElement && t.dataset.path ? fieldViews.get(t.dataset.path) : null;
      if (view) commitField(view);
      runDesign();
    }
  });

  // Drop anywhere on the page: to the slot that takes the file (see openFiles).
  const hint = $("drop-hint");
  const hasFiles = (e) => [...(e.dataTransfer?.types ?? [])].includes("Files");
  window.addEventListener("dragenter", (e) => {
    if (!hasFiles(e)) return;
    e.preventDefault();
    dropState.depth++;
    const takes = currentSlots().map((s) => `${s.label ?? s.name} (${(s.accept ?? []).join(" ")})`);
    hint.textContent = `Drop ${[...takes, "G-code", "a design (.json)"].join(", ")}`;
    hint.hidden = false;
  });
  window.addEventListener("dragover", (e) => {
    if (!hasFiles(e)) return;
    e.preventDefault();
    e.dataTransfer.dropEffect = "copy";
  });
  window.addEventListener("dragleave", () => {
    dropState.depth = Math.max(0, dropState.depth - 1);
    if (!dropState.depth) hint.hidden = true;
  });
  window.addEventListener("drop", (e) => {
    e.preventDefault();
    dropState.reset();
    const files = [...(e.dataTransfer?.files ?? [])];
    if (files.length) openFiles(files);
  });
}

function updateButtons() {
  $("undo").disabled = state.undo.length === 0;
  $("redo").disabled = state.redo.length === 0;
}

/**
 * The examples (www/examples/index.json, made by scripts/build-www.sh), grouped by job kind
 * in the toolbar's menu and in the gallery: a thumbnail and one line each.
 */
async function fillExamples() {
  const select = $("examples");
  let list = [];
  try {
    const res = await fetch("examples/index.json");
    if (!res.ok) throw new Error(`HTTP ${res.status}`);
    list = await res.json();
  } catch {
    select.disabled = true; // examples are optional (generated by scripts/build-www.sh)
    return;
  }
  if (!list.length) select.disabled = true;
  const kinds = [...schema.job_kinds.map((k) => k.name), ...new Set(list.map((e) => e.kind))];
  const groups = [...new Set(kinds)].map((kind) => ({
    kind,
    label: schema.job_kinds.find((k) => k.name === kind)?.label ?? (kind || "Other"),
    doc: schema.job_kinds.find((k) => k.name === kind)?.doc ?? "",
    items: list.filter((e) => (e.kind ?? "") === kind),
  })).filter((g) => g.items.length);
  const gallery = $("gallery-groups");
  gallery.replaceChildren();
  for (const g of groups) {
    const og = document.createElement("optgroup");
    og.label = g.label;
    const section = document.createElement("section");
    section.className = "gallery-group";
    section.dataset.kind = g.kind;
    const h = document.createElement("h3");
    h.textContent = g.label;
    const doc = document.createElement("p");
    doc.className = "hint";
    doc.textContent = g.doc;
    const items = document.createElement("div");
    items.className = "gallery-items";
    for (const e of g.items) {
      state.autoNames.add(e.name);
      const o = new Option(e.name, e.file);
      if (e.description) o.title = e.description;
      og.append(o);
      const b = document.createElement("button");
      b.type = "button";
      b.className = "example";
      b.dataset.file = e.file;
      if (e.thumbnail) {
        const img = document.createElement("img");
        img.src = `examples/${encodeURIComponent(e.thumbnail)}`;
        img.alt = "";
        img.width = 72;
        img.height = 72;
        img.loading = "lazy";
        b.append(img);
      }
      const text = document.createElement("span");
      text.className = "example-text";
      const name = document.createElement("strong");
      name.textContent = e.name;
      const line = document.createElement("span");
      line.textContent = e.description ?? "";
      text.append(name, line);
      b.append(text);
      b.addEventListener("click", () => openExample(e.file));
      items.append(b);
    }
    select.append(og);
    section.append(h, doc, items);
    gallery.append(section);
  }
  $("gallery").hidden = !groups.length;
}

async function openExample(chosen) {
  const select = $("examples");
  const file = typeof chosen === "string" ? chosen : select.value;
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
  if (!askForMissing("This example")) runDesign();
}

// ---------------------------------------------------------------------------------------
// Messages
// ---------------------------------------------------------------------------------------
let crashShownAt = 0;
function showError(message) {
  setMessage($("error-text"), message);
  $("error").hidden = false;
  if (/^The worker (stopped|keeps)/.test(message)) crashShownAt = Date.now();
}
function hideError() {
  $("error").hidden = true;
}
function hideErrorUnlessCrash() {
  if (Date.now() - crashShownAt > 8000) hideError();
}
/**
 * Shows a notice (as text); with `link`, a read-only field holding it; with `action` (one or
 * a list of {label, title?, run}), buttons that close the notice and run their action.
 */
function showNotice(message, link, action) {
  const text = $("notice-text");
  setMessage(text, message);
  for (const a of Array.isArray(action) ? action : action ? [action] : []) {
    const button = document.createElement("button");
    button.type = "button";
    button.className = "notice-action";
    button.textContent = a.label;
    if (a.title) button.title = a.title;
    button.addEventListener("click", () => {
      $("notice").hidden = true;
      a.run();
    });
    text.append(" ", button);
  }
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
/** Bytes as a person reads them. */
function humanBytes(n) {
  const units = ["bytes", "KiB", "MiB", "GiB"];
  let i = 0;
  while (n >= 1024 && i < units.length - 1) {
    n /= 1024;
    i++;
  }
  return `${n >= 100 || i === 0 ? Math.round(n) : n.toFixed(1)} ${units[i]}`;
}

/**
 * Shows a message from the core as text. Its `quoted` parts (a command, a setting's path) are
 * shown as code, without the backticks: made as text nodes and <code> elements, never parsed
 * as HTML. An unpaired backtick stays as it is.
 */
function setMessage(el, message) {
  const parts = String(message ?? "").split("`");
  if (parts.length % 2 === 0) {
    const last = parts.pop();
    parts[parts.length - 1] += `\`${last}`;
  }
  el.replaceChildren(...parts.map((part, i) => {
    if (i % 2 === 0) return part;
    const code = document.createElement("code");
    code.textContent = part;
    return code;
  }));
}

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

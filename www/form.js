// The form, built from designSchema(): the fields shown for the current design (its job kind's,
// the machine's folded behind a printer-profile picker), reading and writing their values,
// their error messages, and the pattern picker's thumbnails. The fields' views live in
// state.fieldViews (path → view), shared with the slots and the keyboard shortcuts.
import { state } from "./state.js";
import { $, getPath, messageOf, setMessage, titleCase } from "./util.js";
import { showError } from "./messages.js";
import { currentSlots, gcodeExtension, jobKind, setDesign, setFields } from "./design.js";
import { buildSlots, renderSlots } from "./slots.js";
import { buildViews } from "./view-cards.js";
import { teachKind } from "./teach.js";
import { refreshFreshness } from "./results.js";
import { drawSegments2d } from "./views.js";

/** Side of the square a pattern thumbnail shows, mm. */
const THUMB_MM = 6;
/** Stroke colour of the pattern thumbnails. */
const THUMB_COLOR = "#29a3d6";

/**
 * Schema fields shown for the current design: those of its job kind whose path exists in the
 * design (so only the current pattern's, domain's, surface's and built-in shape's parameters),
 * plus each `…kind` choice and optional Section whose parent object exists; a field with a
 * `when` condition while the field at `when_path` has the stated value (even when absent).
 */
function visibleFields() {
  const design = state.design;
  const kind = design?.job?.kind;
  const fields = state.schema.fields.filter((f) => {
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
  if (state.schema.job_kinds.length > 1 && !fields.some((f) => f.path === "job.kind")) {
    fields.splice(1, 0, { path: "job.kind", section: "Design", label: "Job", kind: "choice", unit: "", doc: "What to make" });
  }
  // The embedded weft shows only the fields its link names (embed.js).
  return state.embedFields ? fields.filter((f) => state.embedFields.includes(f.path)) : fields;
}

export function renderForm() {
  const fields = visibleFields();
  const slots = currentSlots();
  const key = `${jobKind().name}|${slots.map((s) => s.name).join(",")}|${fields.map((f) => f.path).join(",")}`;
  if (key !== state.formKey) buildForm(fields, slots, key);
  for (const [path, view] of state.fieldViews) writeField(view, getPath(state.design, path));
  renderSlots();
  renderPatternPickers();
  renderPresetPicker();
  $("download").textContent = `Download ${gcodeExtension() === "gcode" ? "G-code" : `.${gcodeExtension()}`}`;
  if (state.viewsKey !== jobKind().name) {
    buildViews();
    teachKind(jobKind());
  }
}

/**
 * The form: the design's name and job, its inputs, the job's own settings, then the machine
 * (printer, material, speeds: every field outside `job`) folded behind a printer-profile
 * picker, since a newcomer changes the job's settings first.
 */
function buildForm(fields, slots, key) {
  state.formKey = key;
  state.fieldViews.clear();
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
      state.slotCards.get(slot.name)?.fields.append(buildField(f));
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
  // Embedded, the printer section shows only when the link names one of its fields.
  machine.hidden = Boolean(state.embedFields) && !machine.querySelector("fieldset");
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
  for (const p of state.schema.printer_presets ?? []) {
    const o = new Option(p.label, p.id);
    o.title = p.doc;
    select.append(o);
  }
  select.append(new Option("Custom (edited below)", "custom"));
  select.addEventListener("change", () => {
    const p = (state.schema.printer_presets ?? []).find((x) => x.id === select.value);
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
  const match = (state.schema.printer_presets ?? []).find((p) => canonical(p.printer) === current);
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
        ? state.schema.job_kinds.map((k) => [k.name, k.label ?? k.name, k.doc])
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
  state.fieldViews.set(f.path, view);
  wrap.append(label, control, error);
  if (doc) wrap.append(doc);
  return wrap;
}

/** Undo/redo show the design as it is: drop invalid entries still showing in the form. */
export function forgetFieldEdits() {
  for (const view of state.fieldViews.values()) view.dirty = false;
}

function writeField(view, value) {
  const { f, inputs } = view;
  if (view.error.hidden === false && view.dirty) return; // keep the user's invalid entry visible
  setFieldError(view, null);
  if (f.kind === "bool") inputs[0].checked = Boolean(value);
  else if (f.kind === "section") inputs[0].checked = value !== undefined && value !== null;
  else if (f.kind === "choice") {
    // A choice left out of the design (the cartesian `printer.machine`, written only when it
    // differs) has its default, which is the first choice.
    const first = f.choices?.[0];
    if (value === undefined && first !== undefined) value = typeof first === "object" && first !== null ? first.value ?? first.name : first;
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

export function commitField(view) {
  let next;
  try {
    next = state.weft.setField(state.json, view.f.path, readField(view));
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
export function invalidFields() {
  return [...state.fieldViews.values()].filter((v) => !v.error.hidden);
}

// ---------------------------------------------------------------------------------------
// Pattern picker: any field with widget "pattern_picker", thumbnails of schema.patterns
// ---------------------------------------------------------------------------------------
/**
 * Pattern thumbnails: kind → {segments}, computed once per pattern and seed. A private cache
 * of this module (nothing else reads or changes it; its kinds are a test hook).
 */
const thumbs = { cache: new Map(), seed: null };

/** Patterns whose thumbnail is drawn (window.weft.thumbnails). */
export function thumbnailKinds() {
  return [...thumbs.cache.keys()];
}

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
      segments = state.weft.patternThumbnail(JSON.stringify(p.value ?? { kind: p.kind }), THUMB_MM, s);
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
    const p = state.schema.patterns.find((q) => q.kind === c.dataset.pattern);
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
  const patterns = state.schema.patterns ?? [];
  const views = [...state.fieldViews.values()].filter((v) => v.f.widget === "pattern_picker");
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

// The design: the current design JSON (state.json, the source of truth), undo/redo, keeping it
// in localStorage, share links and the first design shown; and what the design's job kind
// says about its input slots and the files they name. Every change of the design goes
// through setDesign, which re-renders the form and marks results and estimates out of date.
import { state } from "./state.js";
import { $, extOf, getPath, messageOf } from "./util.js";
import { showError, showNotice } from "./messages.js";
import { forgetFieldEdits, renderForm } from "./form.js";
import { scheduleInspect } from "./view-cards.js";
import { refreshFreshness, scheduleEstimate } from "./results.js";
import { runDesign } from "./actions.js";

const STORAGE_KEY = "weft.design";
const UNDO_LIMIT = 200;
/** Extensions of G-code files analysed and previewed when no input slot takes them. */
export const GCODE_EXT = ["gcode", "gco", "g", "nc"];

/** The design kept in this browser (or the default), then a share link's on top (undoable). */
export function loadInitialDesign() {
  state.autoNames.add(state.defaults.name);
  const stored = storedDesign();
  setDesign(stored ?? state.weft.defaultDesign(), { record: false });
  if (location.hash.startsWith("#d=")) {
    openShare(location.hash);
    return;
  }
  // A first visit shows a part at once (the default design is light) and what to do next.
  if (!stored) {
    if (!state.embedded) showNotice("Welcome to weft. This is the default part, a 20 mm cube: drop your own STL, OBJ or 3MF on the page " +
      "to slice it, change its settings, or pick one of the examples (the Examples menu, or the gallery under the results).");
    runDesign({ auto: true });
  }
}

function storedDesign() {
  if (state.embedded) return null;
  let text = null;
  try {
    text = localStorage.getItem(STORAGE_KEY);
  } catch { /* storage disabled */ }
  if (!text) return null;
  try {
    return state.weft.validateDesign(text);
  } catch (err) {
    showNotice(`The design saved in this browser is no longer valid, so the default design is shown.\n${messageOf(err)}`);
    return null;
  }
}

/** Restores a design from a share fragment; runs it when every file it names is at hand. */
export function openShare(fragment) {
  let json;
  try {
    json = state.weft.decodeShare(fragment);
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
export function askForMissing(what) {
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
export function setDesign(json, { record = true } = {}) {
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
  // The embedded weft keeps its design to itself: a full page opened here keeps its own.
  if (!state.embedded) {
    try {
      localStorage.setItem(STORAGE_KEY, json);
    } catch { /* quota or disabled: the design stays in memory */ }
  }
  renderForm();
  updateButtons();
  scheduleInspect();
  refreshFreshness();
  scheduleEstimate();
}

export function undo() {
  if (!state.undo.length) return;
  forgetFieldEdits();
  state.redo.push(state.json);
  setDesign(state.undo.pop(), { record: false });
}

export function redo() {
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
export function setFields(assignments) {
  let next = state.json;
  // An edit dates the design (UTC): the G-code header's date, the same on every later run.
  if (!assignments.some(([path]) => path === "date")) assignments = [...assignments, ["date", utcNow()]];
  try {
    for (const [path, value] of assignments) next = state.weft.setField(next, path, value);
  } catch (err) {
    return messageOf(err).replace(/^--set:\s*/gm, "");
  }
  setDesign(next);
  return null;
}

/** Now as `YYYY-MM-DD HH:MM:SS` in UTC (the design's `date`). */
export function utcNow() {
  return new Date().toISOString().slice(0, 19).replace("T", " ");
}

/** Extension of the output for the design's flavour (from the schema: `.gcode`, `.nc`, `.csv`). */
export function gcodeExtension() {
  const flavor = state.design?.printer?.flavor;
  const ext = state.schema.flavors?.find((f) => f.name === flavor)?.extension ?? "gcode";
  // Prusa binary G-code: the run also gives the .bgcode bytes (`printer.binary_gcode`).
  return ext === "gcode" && state.design?.printer?.binary_gcode === true ? "bgcode" : ext;
}

export function designName() {
  const name = String(state.design?.name ?? "").trim() || "weft";
  return name.replace(/[\\/:*?"<>|\u0000-\u001f]+/g, "_");
}

// --- the job kind, its slots and files --------------------------------------------------
export function jobKind() {
  const name = state.design?.job?.kind;
  return state.schema.job_kinds.find((k) => k.name === name) ?? { name, label: name, stages: [], slots: [], views: [] };
}

export function currentSlots() {
  return jobKind().slots ?? [];
}

/** Files the page holds for a slot. */
export function filesOf(slot) {
  return [...state.files.values()].filter((f) => f.slot === slot.name);
}

/**
 * Files named by the design at a slot's path: `{file: {name, embedded?}}` or
 * `{files: [name | {name, embedded?}]}`.
 * @returns {Array<{name: string, embedded: boolean}>}
 */
export function namedFiles(value) {
  if (!value || typeof value !== "object") return [];
  const one = (f) => (typeof f === "string" ? { name: f, embedded: false }
    : f && typeof f.name === "string" ? { name: f.name, embedded: f.embedded !== undefined && f.embedded !== null } : null);
  const list = value.file ? [value.file] : Array.isArray(value.files) ? value.files : [];
  return list.map(one).filter(Boolean);
}

/** Files the design names (current job kind's slots) that are neither embedded nor loaded. */
export function missingFiles() {
  const out = [];
  for (const slot of currentSlots()) {
    for (const f of namedFiles(getPath(state.design, slot.path))) {
      if (!f.embedded && !state.files.has(f.name)) out.push({ slot, name: f.name });
    }
  }
  return out;
}

export function accepts(slot, name) {
  // A volume slot takes a whole folder: DICOM files often have no extension, and files that
  // are not part of the series are skipped (and listed) by the reader.
  if (slot.kind === "volume") return true;
  const ext = extOf(name);
  return (slot.accept ?? []).some((a) => a.toLowerCase() === ext);
}

function updateButtons() {
  $("undo").disabled = state.undo.length === 0;
  $("redo").disabled = state.redo.length === 0;
}

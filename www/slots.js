// The input slots of the job kind: one card each (drop zone, file list, built-in shape
// picker and its parameters), loading files into the worker and naming them in the design,
// removing them, and the page-wide drag state (endDrag). Cards live in state.slotCards.
import { state } from "./state.js";
import { MSG } from "./protocol.js";
import { $, fileStem, formatBytes, getPath, messageOf, titleCase } from "./util.js";
import { hideError, showError, showNotice } from "./messages.js";
import { accepts, currentSlots, filesOf, GCODE_EXT, missingFiles, namedFiles, setDesign, setFields } from "./design.js";
import { jobs, workers } from "./worker-client.js";
import { refreshFreshness, scheduleEstimate } from "./results.js";
import { runDesign } from "./actions.js";

export function buildSlots(slots) {
  const host = $("slots");
  state.slotCards.clear();
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
    if (slot.kind === "mesh" && !slot.multiple && state.schema.builtin_shapes.length) {
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
      endDrag();
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
    state.slotCards.set(slot.name, { slot, card, fields, source, extra, list, note, input });
  }
  // The toolbar's Open… takes designs, G-code and whatever a slot takes.
  const accept = new Set([".json", ...GCODE_EXT.map((e) => `.${e}`), ...slots.flatMap((s) => s.accept ?? [])]);
  $("file").accept = [...accept].join(",");
}

/** Updates every slot card from the design and the loaded files. */
export function renderSlots() {
  for (const { slot, card, source, extra, list, note } of state.slotCards.values()) {
    const value = getPath(state.design, slot.path);
    const named = namedFiles(value);
    const held = filesOf(slot);
    const unused = value === undefined || value === null;
    card.classList.toggle("unused", unused);
    if (source) source.wrap.hidden = unused;

    if (source) {
      const options = state.schema.builtin_shapes.map((b, k) => [`builtin:${k}`, `Built-in ${b.label ?? b.kind ?? b.shape}`]);
      const names = new Set([...held.map((f) => f.name), ...named.map((f) => f.name)]);
      for (const name of names) options.push([`file:${name}`, `File: ${name}${state.files.has(name) || named.find((f) => f.name === name)?.embedded ? "" : " (not loaded)"}`]);
      options.push(["open", "Load a file…"]);
      source.replaceChildren(...options.map(([v, t]) => new Option(t, v)));
      const b = value?.builtin;
      const k = b ? state.schema.builtin_shapes.findIndex((s) => s.value?.builtin?.shape === b.shape || (s.kind ?? s.shape) === b.shape) : -1;
      source.value = k >= 0 ? `builtin:${k}` : named[0] ? `file:${named[0].name}` : "";
    }

    // Shape parameters the schema does not list get a plain input.
    extra.replaceChildren();
    if (value?.builtin && typeof value.builtin === "object") {
      for (const [key, v] of Object.entries(value.builtin)) {
        if (key === "shape" || state.fieldViews.has(`${slot.path}.builtin.${key}`)) continue;
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
    state.slotCards.get(slot.name)?.input.click();
    return;
  }
  const value = v.startsWith("builtin:") ? state.schema.builtin_shapes[Number(v.slice(8))]?.value : { file: { name: v.slice(5) } };
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
    let next = state.weft.fillSlot(state.json, slot.name, all);
    // The part names the design (downloads, G-code header), unless the user named it.
    const part = currentSlots().find((s) => s.kind === "mesh" && !s.multiple);
    const name = String(state.design?.name ?? "");
    if (part?.name === slot.name && (state.autoNames.has(name) || !name.trim())) {
      const stem = fileStem(all[all.length - 1]);
      if (stem) {
        state.autoNames.add(stem);
        next = state.weft.setField(next, "name", JSON.stringify(stem));
      }
    }
    setDesign(next);
    return null;
  } catch (err) {
    return messageOf(err);
  }
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
export async function loadIntoSlot(slot, fileList) {
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
        setDesign(state.weft.fillSlot(state.json, slot.name, rest));
      } catch (err) {
        showNotice(`${name} was removed; the design still names it (${messageOf(err)}).`);
      }
      renderSlots();
      return;
    }
    if (slot.multiple) next = { files: rest };
    else {
      const fallback = getPath(state.defaults, slot.path);
      next = fallback && !namedFiles(fallback).length ? fallback : state.schema.builtin_shapes[0]?.value ?? null;
    }
    const problem = setFields([[slot.path, JSON.stringify(next)]]);
    if (problem) showNotice(`${name} was removed; the design still names it (${problem}).`);
  }
  renderSlots();
}

/** A drag of files over the page ended (dropped, here or on a slot): the drop hint goes. */
export function endDrag() {
  state.dropDepth = 0;
  $("drop-hint").hidden = true;
}

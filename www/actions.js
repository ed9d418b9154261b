// What the user's commands do: Run (estimated first, refused or asked about when big),
// Download, Share, opening files (designs, G-code, slot inputs, asking what a file is for)
// and examples. Undo and redo are in design.js.
import { state } from "./state.js";
import { defaultsFor, settingsDiff } from "./picture-caption.js";
import { MSG, plain } from "./protocol.js";
import { $, download, extOf, getPath, humanBytes, messageOf } from "./util.js";
import { hideError, showError, showNotice } from "./messages.js";
import { accepts, askForMissing, currentSlots, designName, GCODE_EXT, gcodeExtension, jobKind, missingFiles, namedFiles, setDesign, setFields } from "./design.js";
import { invalidFields } from "./form.js";
import { loadIntoSlot } from "./slots.js";
import { jobs, workers } from "./worker-client.js";
import { isCurrent, showEstimate, showResult, staleReason } from "./results.js";

/** Download: the result when it matches the design, else the design is run first. */
export function downloadResult() {
  const r = state.result;
  if (!r?.gcode) return;
  if (!staleReason()) {
    saveResult(r);
    return;
  }
  if (invalidFields().length) {
    runDesign(); // says which field to fix
    return;
  }
  runDesign({ then: () => saveResult(state.result) });
  showNotice("The settings changed since the last run: running the design first; the download starts when it is done.");
}
/** Saves a result: its binary G-code when the run made one (the file name says .bgcode), else its text. */
function saveResult(r) {
  if (r.bgcode?.byteLength) download(r.bgcode, r.fileName, "application/octet-stream");
  else download(r.gcode, r.fileName, "text/x-gcode");
}

/**
 * Runs the design after stating its work: a run over a budget is refused with the estimate's
 * message, a big one (over the soft thresholds of the plan) is asked about first.
 * @param {{confirmed?: boolean, fromLink?: boolean}} opts  confirmed: the user said "run
 *   anyway"; fromLink: opened from a share link (which never runs a big job by itself)
 */
export async function runDesign({ confirmed = false, fromLink = false, auto = false, then = null } = {}) {
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
      `(drop it on the page)${slot.kind === "mesh" && state.schema.builtin_shapes.length ? " or pick a built-in shape" : ""}.`);
    return;
  }
  if (!auto) $("notice").hidden = true; // an old notice (cancelled, opened…) is about the past
  const token = jobs.begin("starting");
  const mine = ++state.latestRun;
  const name = designName();
  const ext = gcodeExtension();
  const json = state.json;
  const files = state.filesVersion;
  state.jobs.stages = jobKind().stages ?? [];
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
      (a) => mine === state.latestRun && jobs.ahead(a, `${name}.ahead.${ext}`));
    performance.mark("weft:result");
    if (mine === state.latestRun) {
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
export async function openFiles(fileList) {
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
  const other = state.schema.job_kinds.find((k) => k.name !== jobKind().name && (k.slots ?? []).some(named));
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
  return state.schema.job_kinds.find((k) => k.name === state.defaults?.job?.kind) ?? null;
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
      setDesign(state.weft.validateDesign(await file.text()));
      showNotice(`Design loaded from ${file.name}.`);
    } catch (err) {
      showError(`${file.name} is not a weft design:\n${messageOf(err)}`);
    }
    return;
  }
  if (GCODE_EXT.includes(ext)) {
    const token = jobs.begin(`reading ${file.name}`);
    state.latestRun++;
    state.jobs.stages = [];
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

/** The design's share link ({fragment, embedded, missing, note}), or null after saying why not. */
async function shareLink() {
  // Every loaded file with its slot; Rust keeps the ones the design names, small ones inside.
  let files;
  try {
    files = await Promise.all([...state.files.values()].map(async (f) => ({ slot: f.slot, name: f.name, bytes: new Uint8Array(await f.blob.arrayBuffer()) })));
  } catch (err) {
    showError(`Could not read a loaded file for the link (${messageOf(err)}); load it again.`);
    return null;
  }
  try {
    return plain(state.weft.encodeShare(state.json, files));
  } catch (err) {
    showError(`Could not make a share link: ${messageOf(err)}`);
    return null;
  }
}

export async function share() {
  const res = await shareLink();
  if (!res) return;
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

/**
 * Copies an <iframe> that embeds this design (embed.html with the share link) for a course
 * page, naming the job's fields that differ from the kind's defaults (at most four) so they
 * show beside the preview; the notice says how to name others.
 */
export async function copyEmbed() {
  const res = await shareLink();
  if (!res) return;
  const fields = changedJobFields().slice(0, 4);
  const dir = `${location.origin}${location.pathname.replace(/[^/]*$/, "")}`;
  const src = `${dir}embed.html${res.fragment}${fields.length ? `&fields=${fields.join(",")}` : ""}`;
  const title = String(state.design?.name ?? "design").replace(/[<>&"]/g, "");
  const code = `<iframe src="${src}" width="900" height="640" style="border:0;max-width:100%" title="weft: ${title}" loading="lazy"></iframe>`;
  let copied = false;
  try {
    await navigator.clipboard.writeText(code);
    copied = true;
  } catch { /* no clipboard permission: the notice's field holds it */ }
  const left = (res.missing ?? []).length ? ` Not in it (too large): ${res.missing.join(", ")}.` : "";
  showNotice(`${copied ? "Embed code copied" : "Embed code below"} (${code.length.toLocaleString("en-US")} characters): ` +
    `the preview, "How it works" and ${fields.length ? fields.join(", ") : "no fields"}; list others after &fields= (comma-separated design paths). ` +
    `A course page can set fields, run and step through it with postMessage (README, "Embedding").${left}`, code);
}

/** Form fields under `job` whose values differ from the job kind's defaults, in the design's order. */
function changedJobFields() {
  return settingsDiff(defaultsFor(state.design), state.design).map((d) => d.path).filter((p) => p.startsWith("job.") && state.fieldViews.has(p));
}

export async function openExample(chosen) {
  const select = $("examples");
  const file = typeof chosen === "string" ? chosen : select.value;
  select.value = "";
  if (!file) return;
  try {
    const res = await fetch(`examples/${encodeURIComponent(file)}`);
    if (!res.ok) throw new Error(`HTTP ${res.status}`);
    setDesign(state.weft.validateDesign(await res.text()));
  } catch (err) {
    showError(`Example ${file} could not be opened: ${messageOf(err)}`);
    return;
  }
  if (!askForMissing("This example")) runDesign();
}

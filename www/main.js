// The page's entry (index.html's module script): starts the wasm module, the preview and the
// worker, wires the toolbar, keys and page-wide drops to the actions, lists the examples, and
// exposes window.weft, the hooks the browser tests read. The page's parts are modules by
// concern, each saying what it owns:
//   state.js          every value the page changes while it runs (one object)
//   design.js         the design, undo/redo, persistence, share links, its slots' files
//   form.js           the form built from designSchema(), the pattern picker
//   slots.js          the input slots: file cards, loading and removing files, drops
//   view-cards.js     the job kind's views, fed by `inspect` requests (inspect.js: one request)
//   worker-client.js  worker.js and its thread pool: requests (protocol.js), the progress bar
//   results.js        freshness, the estimate line, a result's numbers and stage cards
//   actions.js        Run, Download, Share, opening files and examples
//   send.js           Send: the G-code to a print host (send-hosts.js: what hosts answer)
//   steps.js          "How it works": the kind's method step by step (views at indices)
//   teach.js          a kind's teaching defaults: its first colouring, the backdrop after a run
//   embed.js          the embedded weft (embed.html): its postMessage API for course pages
//   pictures.js       Picture…: a view, plot or the preview as a captioned PNG/SVG for slides
//   compare.js        Pin for comparison: two results side by side, linked cameras, one table
//   messages.js       the error and notice bars
//   util.js           small shared helpers
// Nothing here knows a job kind: the form, the job selector, the input slots, the progress
// stages, feature names and colours, the views and the pattern picker come from
// designSchema(); stage cards, metrics, plots and tables come from the run report.
import { state } from "./state.js";
import { plain } from "./protocol.js";
import { $, download, messageOf } from "./util.js";
import { hideError, showError } from "./messages.js";
import { currentSlots, designName, filesOf, loadInitialDesign, openShare, redo, undo } from "./design.js";
import { commitField, thumbnailKinds } from "./form.js";
import { endDrag } from "./slots.js";
import { cancel, workers } from "./worker-client.js";
import { AUTO_RUN_KEY, autoRunWanted, maybeAutoRun } from "./results.js";
import { copyEmbed, downloadResult, openExample, openFiles, runDesign, share } from "./actions.js";
import { featureStyles } from "./views.js";
import { sendResult } from "./send.js";
import { goToStep, setOpen, stepsStatus } from "./steps.js";
import { startEmbed } from "./embed.js";
import { installPictures } from "./pictures.js";
import { comparisonShown, openCompareLink } from "./compare.js";

const ready = start();
ready.catch(() => {}); // reported in #error
window.weft = {
  ready,
  get design() { return state.json; },
  get schema() { return state.schema; },
  get result() { return state.result; },
  get resultCount() { return state.resultCount; },
  get files() { return [...state.files.keys()]; },
  get workerGeneration() { return state.client.generation; },
  /** Threads of the worker now: {asked, used, cores, isolated, note} (used null until it is ready). */
  get threads() { return { ...state.client.threads }; },
  get busy() { return state.jobs.active.size > 0; },
  get preview() { return state.preview; },
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
    return [...state.viewCards.values()].map((v) => ({ id: v.view.id, shape: v.last?.shape ?? v.view.shape, index: v.last?.index ?? null, count: v.count, answers: v.answers, items: v.items }));
  },
  get thumbnails() { return thumbnailKinds(); },
  /** The step-through: {open, count, index, title, view, frame, frames, answers, items, shape, caption}. */
  get steps() { return stepsStatus(); },
  step: (i) => goToStep(i),
  openSteps: (open = true) => setOpen(open),
  /** The comparison shown: {a, b} cameras (position, target) and the table's rows, or null. */
  get comparison() { return comparisonShown(); },
};

async function start() {
  try {
    state.weft = await import("../pkg/weft.js");
    await state.weft.default();
  } catch (err) {
    showError(`The WebAssembly module did not load (${messageOf(err)}).\n` +
      "Build it with scripts/build-www.sh and serve the repository root.");
    throw err;
  }
  try {
    state.schema = { ...state.schema, ...plain(state.weft.designSchema()) };
  } catch (err) {
    showError(`designSchema() failed: ${messageOf(err)}`);
  }
  state.styles = featureStyles(state.schema.features);
  state.defaults = JSON.parse(state.weft.defaultDesign());
  wireUi();
  try {
    const { Preview } = await import("./preview.js");
    state.preview = new Preview($("preview"), {
      colorBy: $("color-by"), showTravel: $("show-travel"), showStarts: $("show-starts"), layerMin: $("layer-min"),
      layerMax: $("layer-max"), layerLabel: $("layer-label"), legend: $("legend"),
      moveMax: $("move-max"), moveLabel: $("move-label"), showAxis: $("show-axis"), camera: $("camera-views"),
    }, { features: state.schema.features });
  } catch (err) {
    showError(`The 3D preview could not start (${messageOf(err)}); slicing and downloads still work.`);
  }
  installPictures();
  workers.start();
  openCompareLink(); // #d=B&vs=A: A runs first, #d=B is then opened as any share link
  loadInitialDesign();
  startEmbed();
  fillExamples();
  if ("serviceWorker" in navigator && window.isSecureContext) {
    navigator.serviceWorker.register("sw.js").then(isolateThroughServiceWorker, () => {});
  }
  window.addEventListener("hashchange", () => {
    openCompareLink();
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
  // A framed page is isolated only when its embedding page is too: a reload would not help.
  if (self.crossOriginIsolated || window.parent !== window) return;
  const KEY = "weft.isolationReload";
  const tryReload = () => {
    if (self.crossOriginIsolated || !navigator.serviceWorker.controller) return;
    if (sessionStorage.getItem(KEY)) return; // reloaded once already: the browser would not isolate
    if (state.files.size) return; // a dropped file would be lost
    if (state.jobs.active.size) {
      setTimeout(tryReload, 250); // a run going on (the first visit's default part): after it
      return;
    }
    sessionStorage.setItem(KEY, "1");
    location.reload();
  };
  if (navigator.serviceWorker.controller) tryReload();
  else navigator.serviceWorker.addEventListener("controllerchange", tryReload, { once: true });
}

function wireUi() {
  $("slice").addEventListener("click", () => runDesign());
  $("cancel").addEventListener("click", cancel);
  $("undo").addEventListener("click", undo);
  $("redo").addEventListener("click", redo);
  $("download").addEventListener("click", downloadResult);
  $("send").addEventListener("click", sendResult);
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
  $("copy-embed").addEventListener("click", copyEmbed);
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
      if (e.key === "Escape" && state.jobs.active.size) cancel();
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
      const view = t instanceof HTMLElement && t.dataset.path ? state.fieldViews.get(t.dataset.path) : null;
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
    state.dropDepth++;
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
    state.dropDepth = Math.max(0, state.dropDepth - 1);
    if (!state.dropDepth) hint.hidden = true;
  });
  window.addEventListener("drop", (e) => {
    e.preventDefault();
    endDrag();
    const files = [...(e.dataTransfer?.files ?? [])];
    if (files.length) openFiles(files);
  });
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
  const kinds = [...state.schema.job_kinds.map((k) => k.name), ...new Set(list.map((e) => e.kind))];
  const groups = [...new Set(kinds)].map((kind) => ({
    kind,
    label: state.schema.job_kinds.find((k) => k.name === kind)?.label ?? (kind || "Other"),
    doc: state.schema.job_kinds.find((k) => k.name === kind)?.doc ?? "",
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

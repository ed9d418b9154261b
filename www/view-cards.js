// The job kind's views (schema.job_kinds[].views): one card each, fed by `inspect` requests
// to the worker (an index picker, play, drawing a points field on the view, an image's value
// window, STL download), drawn by views.js. Cards live in state.viewCards.
import { state } from "./state.js";
import { $, button, download, fileStem } from "./util.js";
import { inspectView } from "./inspect.js";
import { jobKind, setFields } from "./design.js";
import { drawView, fillLegend } from "./views.js";
import { buildSteps, refreshSteps } from "./steps.js";

const INSPECT_DEBOUNCE_MS = 200;

// ---------------------------------------------------------------------------------------
// Views (schema.job_kinds[].views): one card each, fed by `inspect` requests
// ---------------------------------------------------------------------------------------
/** view id → {view, card, canvas, range, number, info, legend, last, seq, timer, count, answers, items} */

export function buildViews() {
  state.viewsKey = jobKind().name;
  for (const v of state.viewCards.values()) { clearTimeout(v.timer); clearTimeout(v.playTimer); v.playing = false; }
  state.viewCards.clear();
  const host = $("views");
  host.replaceChildren();
  // A view drawn only by a step of "How it works" (card: false) gets no card of its own.
  for (const view of (jobKind().views ?? []).filter((v) => v.card !== false)) {
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
    const drawButton = button("view-draw", "", false);
    const finishButton = button("view-finish");
    const cancelButton = button("view-cancel", "Cancel");
    // A mesh view whose answer says `meta.stl` can be downloaded as an STL.
    const stlButton = button("view-stl", "Download STL");
    // A view whose answer says `meta.play` steps through its indices by itself (a print
    // sequence): Play advances one index per answer, at most every PLAY_STEP_MS.
    const playButton = button("view-play", "▶ Play");
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
      const bytes = state.weft.meshStl(v.last.data, name);
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
    state.viewCards.set(view.id, v);
  }
  host.hidden = state.viewCards.size === 0;
  buildSteps();
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
export function scheduleInspect(delay = INSPECT_DEBOUNCE_MS, only = null) {
  if (!only) refreshSteps(delay);
  for (const v of only ? [only] : state.viewCards.values()) {
    clearTimeout(v.timer);
    v.timer = setTimeout(() => requestInspect(v), delay);
  }
}

async function requestInspect(v) {
  const index = Math.max(0, Math.round(v.number.valueAsNumber || 1) - 1);
  const res = await inspectView(v, v.info, { view: v.view.id, index, key: `view:${v.view.id}` });
  if (!res) return; // missing input, replaced by a newer request, or failed (said in the card)
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
  const r = drawView(v.canvas, v.last, state.styles);
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
  fillLegend(v.legend, v.last, r, state.styles);
}

// "How it works": the job kind's method as steps (schema.job_kinds[].steps), each one of the
// kind's views at an index with a sentence or two and where the paper says it. Back / Next /
// Play walk the steps; a step that iterates (`scrub`) gets a scrubber over its frames. Closed,
// the card asks the worker for nothing and keeps no answer, so the recorded frames cost
// nothing; opened, it asks for the shown step only. Drawn by views.js like the view cards.
import { state } from "./state.js";
import { MSG } from "./protocol.js";
import { $, button, el } from "./util.js";
import { inspectView } from "./inspect.js";
import { jobKind } from "./design.js";
import { workers } from "./worker-client.js";
import { drawView, fillLegend } from "./views.js";

/** Time between frames (and between steps) while playing, ms: the next waits for its answer too. */
const PLAY_MS = 160;
/** Time a step's sentence stays before Play moves on to the next step, ms. */
const PLAY_STEP_PAUSE_MS = 1400;
const INSPECT_DEBOUNCE_MS = 120;

/** The card's parts and what it shows: built once per job kind. */
function emptySteps() {
  return { kind: null, list: [], open: false, index: 0, frame: 0, frames: 1, last: null, seq: 0, timer: 0, playTimer: 0, playing: false, answers: 0, items: 0, el: null };
}

/** (Re)builds the card for the current job kind (called with the view cards). */
export function buildSteps() {
  const s = state.steps ?? (state.steps = emptySteps());
  stopPlaying(s);
  clearTimeout(s.timer);
  const kind = jobKind();
  const host = $("how");
  if (!host) return;
  s.kind = kind.name;
  s.list = kind.steps ?? [];
  s.index = Math.min(s.index, Math.max(0, s.list.length - 1));
  if (s.kind !== host.dataset.kind) s.index = 0;
  host.dataset.kind = kind.name;
  s.frame = 0;
  s.last = null;
  host.hidden = s.list.length === 0;
  host.replaceChildren();
  if (!s.list.length) return;
  const toggle = el("button", { type: "button", id: "how-toggle", attrs: { "aria-expanded": "false", "aria-controls": "how-body" } });
  const head = el("div", { className: "how-head" },
    el("h2", { textContent: "How it works" }),
    el("span", { className: "hint", textContent: `${kind.label ?? kind.name}: ${s.list.length} steps` }),
    toggle);
  const tabs = el("ol", { className: "how-tabs" }, ...s.list.map((step, i) => {
    const b = el("button", { type: "button", textContent: step.title });
    b.dataset.index = String(i);
    b.addEventListener("click", () => { stopPlaying(s); goToStep(i); });
    return el("li", {}, b);
  }));
  const title = el("h3", { className: "how-title" });
  const text = el("p", { className: "how-text" });
  const cite = el("p", { className: "how-cite hint" });
  const canvas = el("canvas");
  const box = el("div", { className: "canvas-box how-canvas" }, canvas);
  const range = el("input", { type: "range", min: "1", max: "1", value: "1", id: "how-frame" });
  const scrub = el("div", { className: "how-scrub" }, el("label", { htmlFor: range.id, textContent: "frame" }), range);
  const caption = el("output", { className: "how-caption hint" });
  caption.htmlFor = range.id;
  const legend = el("div", { className: "mini-legend" });
  const back = navButton("how-back", "◀ Back", () => { stopPlaying(s); goToStep(s.index - 1); });
  const play = navButton("how-play", "▶ Play", () => (s.playing ? stopPlaying(s) : startPlaying(s)));
  const next = navButton("how-next", "Next ▶", () => { stopPlaying(s); goToStep(s.index + 1); });
  const count = el("span", { className: "how-count hint" });
  const nav = el("div", { className: "how-nav" }, back, count, play, next);
  const body = el("div", { id: "how-body", className: "how-body" }, tabs, title, text, cite, box, scrub, caption, legend, nav);
  host.append(head, body);
  s.el = { host, toggle, body, tabs, title, text, cite, canvas, range, scrub, caption, legend, back, play, next, count };
  toggle.addEventListener("click", () => setOpen(!s.open));
  range.addEventListener("input", () => {
    stopPlaying(s);
    s.frame = Math.max(0, range.valueAsNumber - 1);
    schedule(INSPECT_DEBOUNCE_MS / 2);
  });
  new ResizeObserver(() => redraw(s)).observe(box);
  setOpen(s.open);
}

function navButton(className, text, onClick) {
  const b = button(className, text, false);
  b.addEventListener("click", onClick);
  return b;
}

/** Opens or closes the step-through; closed, the answer is dropped and nothing is asked. */
export function setOpen(open) {
  const s = state.steps;
  if (!s?.el) return;
  s.open = Boolean(open);
  s.el.body.hidden = !s.open;
  s.el.toggle.textContent = s.open ? "Close" : "Open the steps";
  s.el.toggle.setAttribute("aria-expanded", String(s.open));
  s.el.host.classList.toggle("open", s.open);
  if (!s.open) {
    stopPlaying(s);
    clearTimeout(s.timer);
    s.seq++; // an answer on its way is dropped
    s.last = null;
    workers.post({ type: MSG.DROP_RECORDINGS }); // the worker keeps no recorded frames
    return;
  }
  show(s);
  schedule(0);
}

/** Shows step `i` (clamped) from its first frame. */
export function goToStep(i) {
  const s = state.steps;
  if (!s?.list.length) return;
  s.index = Math.max(0, Math.min(s.list.length - 1, i | 0));
  s.frame = s.list[s.index].index ?? 0;
  s.frames = 1;
  s.last = null;
  if (!s.open) setOpen(true);
  else { show(s); schedule(0); }
}

/** Asks again for the shown step after a design change (when open). */
export function refreshSteps(delay = INSPECT_DEBOUNCE_MS) {
  const s = state.steps;
  if (s?.open) schedule(delay);
}

function show(s) {
  const step = s.list[s.index];
  const e = s.el;
  e.title.textContent = `${s.index + 1}. ${step.title}`;
  e.text.textContent = step.text;
  e.cite.textContent = step.cite ? `Paper: ${step.cite}` : "";
  e.count.textContent = `step ${s.index + 1} of ${s.list.length}`;
  e.back.disabled = s.index === 0;
  e.next.disabled = s.index === s.list.length - 1;
  e.scrub.hidden = !step.scrub;
  for (const b of e.tabs.querySelectorAll("button")) b.setAttribute("aria-current", b.dataset.index === String(s.index) ? "step" : "false");
  e.canvas.setAttribute("aria-label", `${step.title}: ${step.text}`);
}

function schedule(delay) {
  const s = state.steps;
  clearTimeout(s.timer);
  s.timer = setTimeout(() => request(s), delay);
}

async function request(s) {
  if (!s.open || !s.list.length) return;
  const step = s.list[s.index];
  const res = await inspectView(s, s.el.caption, { view: step.view, index: s.frame, key: "steps", what: "this step", onError: () => stopPlaying(s) });
  if (!res || !s.open) return;
  s.last = res;
  s.answers++;
  s.frames = Math.max(1, res.count);
  s.frame = res.index;
  const e = s.el;
  e.range.max = String(s.frames);
  if (document.activeElement !== e.range || !s.playing) e.range.value = String(s.frame + 1);
  redraw(s);
  const caption = typeof res.meta?.caption === "string" ? res.meta.caption : "";
  const frame = step.scrub ? `frame ${s.frame + 1} of ${s.frames}` : "";
  e.caption.textContent = [frame, caption].filter(Boolean).join(" · ");
  if (s.playing) playOn(s);
}

function redraw(s) {
  if (!s.el?.canvas.isConnected || !s.open) return;
  const r = drawView(s.el.canvas, s.last, state.styles);
  s.items = r.items ?? 0;
  fillLegend(s.el.legend, s.last, r, state.styles);
}

// Play: through a scrubbing step's frames, then on to the next step, to the last.
function startPlaying(s) {
  if (!s.open) setOpen(true);
  if (s.index === s.list.length - 1 && (!s.list[s.index].scrub || s.frame >= s.frames - 1)) goToStep(0);
  s.playing = true;
  s.el.play.textContent = "❚❚ Pause";
  s.el.play.setAttribute("aria-pressed", "true");
  playOn(s);
}

function stopPlaying(s) {
  clearTimeout(s.playTimer);
  s.playing = false;
  if (s.el) {
    s.el.play.textContent = "▶ Play";
    s.el.play.setAttribute("aria-pressed", "false");
  }
}

function playOn(s) {
  clearTimeout(s.playTimer);
  if (!s.playing) return;
  const step = s.list[s.index];
  if (step.scrub && s.frame < s.frames - 1) {
    s.playTimer = setTimeout(() => { s.frame += 1; request(s); }, PLAY_MS);
  } else if (s.index < s.list.length - 1) {
    s.playTimer = setTimeout(() => { if (s.playing) goToStep(s.index + 1); }, PLAY_STEP_PAUSE_MS);
  } else {
    stopPlaying(s);
  }
}

/**
 * The step shown, shaped like a view card (`{last, legend, view: {id, label}}`), for what
 * saves a view's picture; null while no step is shown.
 */
export function stepAsView() {
  const s = state.steps;
  const step = s?.list[s.index];
  if (!step) return null;
  const frame = s.frames > 1 ? ` (frame ${s.frame + 1} of ${s.frames})` : "";
  return { last: s.last, legend: s.el?.legend, view: { id: `step${s.index + 1}-${step.view}`, label: `How it works ${s.index + 1}: ${step.title}${frame}` } };
}

/** What the browser tests and an embedding page read: the step shown and what it drew. */
export function stepsStatus() {
  const s = state.steps;
  if (!s) return { open: false, count: 0 };
  const step = s.list[s.index];
  return {
    open: s.open, count: s.list.length, index: s.index, title: step?.title ?? null, view: step?.view ?? null,
    frame: s.frame, frames: s.frames, answers: s.answers, items: s.items, shape: s.last?.shape ?? null,
    caption: s.last?.meta?.caption ?? null, playing: s.playing,
  };
}

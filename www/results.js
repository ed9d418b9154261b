// Results and their freshness: a result belongs to the design and files it was made from
// (an edit dims it and offers Run again); the next run is estimated after every edit and a
// light job re-runs by itself; a result is shown as the preview, its numbers, the time line
// and the stage cards (report.js).
import { state } from "./state.js";
import { MSG } from "./protocol.js";
import { $, formatBytes, formatDuration, humanBytes, messageOf } from "./util.js";
import { hideErrorUnlessCrash, tellParent } from "./messages.js";
import { missingFiles } from "./design.js";
import { invalidFields } from "./form.js";
import { scheduleInspect } from "./view-cards.js";
import { showBackdrop } from "./teach.js";
import { threadsWhy, workers } from "./worker-client.js";
import { runDesign } from "./actions.js";
import { metricList, renderReport } from "./report.js";
import { compareFreshness, showComparison } from "./compare.js";

/** Wait after an edit before estimating the next run, ms. */
const ESTIMATE_DEBOUNCE_MS = 250;
/** Jobs estimated under this re-run by themselves after an edit (when the user lets them), s. */
const AUTO_RUN_SECONDS = 0.5;
export const AUTO_RUN_KEY = "weft.autoRun";

// ---------------------------------------------------------------------------------------
// Freshness: a result belongs to the design it was made from; the next run is estimated
// ---------------------------------------------------------------------------------------
/** Why the result shown does not match the form (null when it does, or when there is none). */
export function staleReason() {
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
export function isCurrent(made) {
  return Boolean(made) && made.json === state.json && made.files === state.filesVersion;
}

/** Dims the preview, numbers and cards of a result that no longer matches the design. */
export function refreshFreshness() {
  const reason = staleReason();
  document.querySelector(".view")?.classList.toggle("stale-result", Boolean(reason));
  $("stale").hidden = !reason;
  $("stale-text").textContent = reason ?? "";
  $("stale-run").disabled = invalidFields().length > 0;
  const download = $("download");
  download.title = reason ? "Runs the changed design first, then saves its G-code" : "Save the G-code of the last result";
  download.dataset.stale = String(Boolean(reason));
  compareFreshness();
}

/** Estimates the current design in the worker (debounced), shows it, then maybe re-runs. */
export function scheduleEstimate() {
  clearTimeout(state.estimateTimer);
  state.estimateTimer = setTimeout(estimateNow, ESTIMATE_DEBOUNCE_MS);
}

async function estimateNow() {
  const json = state.json;
  const files = state.filesVersion;
  const seq = ++state.estimateSeq;
  const missing = missingFiles();
  if (missing.length) {
    state.estimate = { json, files, error: `load ${missing.map((m) => m.name).join(", ")} to estimate` };
    showEstimate();
    return;
  }
  try {
    const { plan } = await workers.request({ type: MSG.ESTIMATE, design: json });
    if (seq !== state.estimateSeq) return;
    state.estimate = { json, files, plan };
  } catch (err) {
    if (err.cancelled || seq !== state.estimateSeq) return;
    state.estimate = { json, files, error: messageOf(err) };
  }
  showEstimate();
  maybeAutoRun();
}

/** The estimate line: what the next run will make and take. */
export function showEstimate() {
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

export function autoRunWanted() {
  try {
    return localStorage.getItem(AUTO_RUN_KEY) !== "0";
  } catch {
    return true;
  }
}

/** Re-runs a light job after an edit (live preview), when the user lets it and nothing runs. */
export function maybeAutoRun() {
  const e = state.estimate;
  if (!$("auto-run").checked || !e?.plan || !isCurrent(e)) return;
  if (!state.result || state.result.json === null || isCurrent(state.result)) return; // nothing shown from a design, or fresh
  const p = e.plan;
  if (p.refusal || p.ask || !((p.wall_seconds ?? p.seconds) < AUTO_RUN_SECONDS) || state.jobs.active.size) return;
  runDesign({ auto: true });
}

export function showResult(res, fileName, json = null, files = state.filesVersion) {
  state.resultCount++;
  const { report, preview: buffers, gcode } = res;
  // `bgcode`: the run's Prusa binary G-code (printer.binary_gcode), else absent.
  const bgcode = res.bgcode?.byteLength ? res.bgcode : undefined;
  state.result = { report, gcode, bgcode, fileName, ms: res.ms, json, files };
  $("download").disabled = !(gcode && gcode.byteLength);
  $("send").disabled = $("download").disabled;
  const origin = state.design?.printer?.origin;
  state.preview?.setResult(buffers, { origin: typeof origin === "string" ? origin : "corner" });
  performance.mark("weft:preview-set");
  renderStats(report, gcode, res.ms, bgcode);
  renderReport($("report"), report, state);
  performance.mark("weft:shown");
  if (res.request === "run") {
    scheduleInspect(0); // views of a loaded solid know their count now
    showBackdrop();
  } else {
    state.preview?.setBackdrop(null); // a dropped G-code: no kind's surface behind it
  }
  hideErrorUnlessCrash();
  refreshFreshness();
  showComparison();
  tellParent({ type: "weft:result", stats: statsOf(report), design: json ?? state.json });
}

/**
 * A run's statistics as numbers, keyed as `weft analyze --json` keys them (the embed's
 * weft:result, the comparison's table); `part` "gcode" reads the writer's totals instead.
 */
export function statsOf(report, part = "analysis") {
  const out = {};
  for (const [k, v] of Object.entries(report?.[part] ?? {})) if (typeof v === "number" && Number.isFinite(v)) out[k] = v;
  return out;
}

function renderStats(report, gcode, ms, bgcode) {
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
  // Prusa binary G-code is what Download saves when the printer asks for it.
  if (bgcode) rows.push(["Binary G-code", formatBytes(bgcode.byteLength), "", "The .bgcode Download saves and Send offers first (printer.binary_gcode)."]);
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
  const label = (name) => state.jobs.stages.find((s) => s.name === name)?.label ?? name;
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

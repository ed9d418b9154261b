// Comparing two results: "Pin for comparison" keeps the result shown (its preview buffers,
// report and design); the next result (a changed setting and Run, or another slicer's G-code
// dropped on the page) is shown beside it, A (pinned) and B (current), in two previews whose
// cameras move together, with one table of the statistics (keyed like `weft analyze --json`),
// B − A and the settings that differ. Never stale silently: each column says what it is of,
// and a note says when the form no longer matches B. A comparison is shared as one link,
// `#d=<B>&vs=<A>` (each a share fragment's payload); opening one runs A, then B, and shows both.
// The pinned result is state.pinned; the comparison's previews live in `panes` (built once).
import { state } from "./state.js";
import { MSG, plain } from "./protocol.js";
import { $, formatBytes, formatDuration, messageOf } from "./util.js";
import { showError, showNotice } from "./messages.js";
import { jobs, workers } from "./worker-client.js";
import { staleReason, statsOf } from "./results.js";
import { formatNumber } from "./plot.js";
import { settingsDiff } from "./picture-caption.js";

/** The table's rows: [key as in `weft analyze --json`, label, unit, digits]. */
const ROWS = [
  ["layers", "Layers", "", 0], ["extrusion_paths", "Extrusion paths", "", 0], ["extruded_mm", "Extruded", "mm", 1],
  ["filament_mm", "Filament", "mm", 1], ["travel_mm", "Travel", "mm", 1], ["retractions", "Retractions", "", 0],
  ["overlap_mm", "Overlap", "mm", 1], ["gippo_score", "GIPPO score", "", 3], ["estimated_time_s", "Estimated time", "h:m:s", 0],
  ["gcode_bytes", "G-code", "", 0],
];
/** Settings differences listed before "and N more". */
const DIFF_SHOWN = 8;

let panes = null; // {section, bar, a: {preview, label, ...}, b: {...}, table, note}; built once

/** The comparison shown, for tests: cameras of A and B and the table's values (null when hidden). */
export function comparisonShown() {
  if (!panes || panes.section.hidden) return null;
  const cam = (s) => s.preview && { position: s.preview.camera.position.toArray(), target: s.preview.controls.target.toArray(), segments: s.preview.segmentCount() };
  const rows = [...panes.table.tBodies[0].rows].map((tr) => ({
    key: tr.dataset.key, a: tr.querySelector(".a").dataset.value ?? null, b: tr.querySelector(".b").dataset.value ?? null,
  }));
  return { a: cam(panes.sides.a), b: cam(panes.sides.b), rows, notes: panes.note.textContent };
}

/** The table's statistics of a result (results.js's, keyed like `weft analyze --json`, plus gcode_bytes). */
function rowsOf(result) {
  const stats = { ...statsOf(result?.report, "gcode"), ...statsOf(result?.report), gcode_bytes: result?.gcode?.byteLength };
  return Object.fromEntries(ROWS.map(([key]) => [key, typeof stats[key] === "number" ? stats[key] : null]));
}

function build() {
  if (panes) return panes;
  const bar = document.createElement("div");
  bar.className = "compare-bar";
  bar.hidden = true;
  const pin = document.createElement("button");
  pin.type = "button";
  pin.className = "compare-pin";
  pin.textContent = "Pin for comparison";
  pin.title = "Keep this result to compare the next one with (a changed setting and Run, or another slicer's G-code dropped on the page)";
  const status = document.createElement("span");
  status.className = "compare-status hint";
  bar.append(pin, status);
  const section = document.createElement("section");
  section.className = "compare";
  section.setAttribute("aria-label", "Comparison");
  section.hidden = true;
  section.innerHTML = `<div class="card-head"><h2>Comparison</h2>
    <button type="button" class="compare-share" title="Put both designs in the address (#d=B&amp;vs=A) and copy the link">Share comparison</button>
    <button type="button" class="compare-unpin">Unpin</button></div>
    <ul class="compare-note" role="note"></ul>
    <div class="compare-panes"></div>
    <div class="table-wrap"><table class="report-table compare-table"><thead><tr><th scope="col">Statistic</th>
      <th scope="col" class="compare-a"></th><th scope="col" class="compare-b"></th><th scope="col">B − A</th></tr></thead><tbody></tbody></table></div>`;
  $("stats").before(bar, section);
  panes = { bar, pin, status, section, note: section.querySelector(".compare-note"), table: section.querySelector(".compare-table"), sides: {} };
  for (const side of ["a", "b"]) {
    const fig = document.createElement("figure");
    fig.className = `compare-pane compare-pane-${side}`;
    fig.innerHTML = `<figcaption></figcaption><div class="compare-canvas"><div class="compare-gl"><canvas tabindex="0"></canvas></div><div class="legend"></div></div>`;
    section.querySelector(".compare-panes").append(fig);
    panes.sides[side] = { fig, caption: fig.querySelector("figcaption"), canvas: fig.querySelector("canvas"), legend: fig.querySelector(".legend"), preview: null };
  }
  pin.addEventListener("click", pinCurrent);
  section.querySelector(".compare-unpin").addEventListener("click", unpin);
  section.querySelector(".compare-share").addEventListener("click", shareComparison);
  return panes;
}

/** A Preview for one side (its own hidden controls; colour mode follows the page's), made once. */
function previewOf(side) {
  const s = panes.sides[side];
  if (!state.preview) return Promise.resolve(null);
  s.making ??= makePreview(s, side);
  return s.making;
}

async function makePreview(s, side) {
  const { Preview } = await import("./preview.js");
  const input = (type) => Object.assign(document.createElement("input"), { type });
  const colorBy = $("color-by").cloneNode(true);
  colorBy.removeAttribute("id");
  colorBy.value = $("color-by").value;
  $("color-by").addEventListener("change", () => { colorBy.value = $("color-by").value; colorBy.dispatchEvent(new Event("change")); });
  s.preview = new Preview(s.canvas, {
    colorBy, showTravel: input("checkbox"), layerMin: input("range"), layerMax: input("range"),
    layerLabel: document.createElement("output"), legend: s.legend,
  }, { features: state.schema.features });
  s.canvas.setAttribute("aria-label", `3D preview of result ${side.toUpperCase()}: drag to orbit; the other preview follows`);
  return s.preview;
}

/** Moves `to`'s camera where `from`'s is (once; its own change event is not passed back). */
function follow(from, to) {
  if (panes.syncing) return;
  panes.syncing = true;
  try {
    to.camera.position.copy(from.camera.position);
    to.camera.up.copy(from.camera.up);
    to.controls.target.copy(from.controls.target);
    to.controls.update();
    to.requestRender();
  } finally {
    panes.syncing = false;
  }
}

function link(a, b) {
  if (panes.linked) return;
  panes.linked = true;
  a.controls.addEventListener("change", () => follow(a, b));
  b.controls.addEventListener("change", () => follow(b, a));
  a.controls.addEventListener("start", () => { b.autoFit = false; });
  b.controls.addEventListener("start", () => { a.autoFit = false; });
}

function pinCurrent() {
  const r = state.result;
  if (!r) return;
  state.pinned = {
    result: r, data: state.preview?.data ?? null, origin: state.design?.printer?.origin ?? "corner",
    json: r.json, design: r.json ? JSON.parse(r.json) : null, name: r.json ? JSON.parse(r.json).name : r.fileName,
    at: new Date(), stale: Boolean(staleReason()), from: "pinned",
  };
  showComparison();
}

function unpin() {
  state.pinned = null;
  for (const s of Object.values(panes?.sides ?? {})) s.preview?.setResult(null);
  showComparison();
}

/** Shows the pin bar and, with a pinned result and another one shown, the comparison. */
export async function showComparison() {
  const p = build();
  const pinned = state.pinned;
  const current = state.result;
  p.bar.hidden = !current && !pinned;
  p.pin.textContent = pinned ? "Pin this result instead" : "Pin for comparison";
  p.pin.hidden = !current || pinned?.result === current;
  const time = (d) => d.toLocaleTimeString("en-GB", { hour: "2-digit", minute: "2-digit" });
  p.status.textContent = !pinned ? "" : pinned.result === current
    ? `Pinned: ${pinned.name} (${time(pinned.at)}). Change a setting and Run, or drop another slicer's G-code, to compare.`
    : pinned.from === "link" ? `A is ${pinned.name}, from the comparison link.` : `A is ${pinned.name}, pinned at ${time(pinned.at)}.`;
  const on = Boolean(pinned && current && pinned.result !== current);
  p.section.hidden = !on;
  if (!on) return;
  let a = null;
  let b = null;
  try {
    a = await previewOf("a");
    b = await previewOf("b");
  } catch { /* no more WebGL contexts here: the table and notes still show */ }
  if (state.pinned !== pinned || state.result !== current) return; // a newer call shows the newer pair
  for (const s of Object.values(p.sides)) s.fig.querySelector(".compare-canvas").hidden = !(a && b);
  if (a && b) {
    link(a, b);
    if (p.sides.a.shown !== pinned.data) a.setResult(pinned.data, { origin: pinned.origin });
    if (p.sides.b.shown !== state.preview.data) b.setResult(state.preview.data, { origin: state.design?.printer?.origin ?? "corner" });
    p.sides.a.shown = pinned.data;
    p.sides.b.shown = state.preview.data;
    // One framing for both: the larger part's, so the smaller sits inside it.
    const [lead, other] = (a.sphere?.radius ?? 0) >= (b.sphere?.radius ?? 0) ? [a, b] : [b, a];
    lead.fit();
    follow(lead, other);
  }
  fillTable(pinned, current);
  compareFreshness();
}

function fillTable(pinned, current) {
  const A = rowsOf(pinned.result);
  const B = rowsOf(current);
  const show = (key, v, digits) => (v === null ? "–" : key === "estimated_time_s" ? formatDuration(v) : key === "gcode_bytes" ? formatBytes(v) : formatNumber(v, digits));
  const nameB = current.json ? JSON.parse(current.json).name : current.fileName;
  panes.table.tHead.querySelector(".compare-a").textContent = "A · pinned";
  panes.table.tHead.querySelector(".compare-a").title = pinned.name;
  panes.table.tHead.querySelector(".compare-b").textContent = "B · current";
  panes.table.tHead.querySelector(".compare-b").title = nameB;
  panes.table.tBodies[0].replaceChildren(...ROWS.filter(([k]) => A[k] !== null || B[k] !== null).map(([key, label, unit, digits]) => {
    const tr = document.createElement("tr");
    tr.dataset.key = key;
    const th = document.createElement("th");
    th.scope = "row";
    th.textContent = unit && unit !== "h:m:s" ? `${label} (${unit})` : label;
    const cell = (v, cls, text) => {
      const td = document.createElement("td");
      td.className = `num ${cls}`;
      if (v !== null) td.dataset.value = String(v);
      td.textContent = text;
      return td;
    };
    const d = A[key] !== null && B[key] !== null ? B[key] - A[key] : null;
    const pct = d !== null && A[key] ? ` (${d >= 0 ? "+" : ""}${formatNumber((100 * d) / Math.abs(A[key]), 1)} %)` : "";
    const dText = d === null ? "–" : d === 0 ? "same" : `${d > 0 ? "+" : "−"}${show(key, Math.abs(d), digits)}`;
    const diff = cell(d, "diff", dText);
    if (pct && d !== 0) diff.append(Object.assign(document.createElement("span"), { className: "pct", textContent: pct }));
    tr.append(th, cell(A[key], "a", show(key, A[key], digits)), cell(B[key], "b", show(key, B[key], digits)), diff);
    return tr;
  }));
  panes.sides.a.caption.textContent = `A · pinned: ${pinned.name}`;
  panes.sides.b.caption.textContent = `B · current: ${nameB}`;
}

/** The notes: what differs between A and B, and whether the form still matches B (after every edit). */
export function compareFreshness() {
  const pinned = state.pinned;
  const current = state.result;
  if (!panes || !pinned || !current || pinned.result === current) return;
  const notes = [];
  if (!current.json) notes.push(`B is ${current.fileName}, a G-code read as it is (no design to compare settings with).`);
  if (!pinned.json) notes.push(`A is ${pinned.name}, a G-code read as it is.`);
  if (pinned.json && current.json) {
    const diff = settingsDiff(pinned.design, JSON.parse(current.json));
    if (!diff.length) notes.push(pinned.json === current.json ? "A and B are of the same design." : "A and B differ only in their name or date.");
    else {
      const listed = diff.slice(0, DIFF_SHOWN).map((d) => `${d.path} ${d.from} → ${d.to}`).join(" · ");
      notes.push(`B differs from A in: ${listed}${diff.length > DIFF_SHOWN ? ` and ${diff.length - DIFF_SHOWN} more` : ""}.`);
    }
  }
  if (pinned.stale) notes.push("A was pinned while its settings had been changed: it is the run before those changes.");
  if (staleReason()) notes.push("The form changed since B was run: B is the last run, not the form; Run to update B.");
  panes.note.replaceChildren(...notes.map((t) => Object.assign(document.createElement("li"), { textContent: t })));
}

// ---------------------------------------------------------------------------------------
// The comparison's link: #d=<B>&vs=<A>
// ---------------------------------------------------------------------------------------
async function shareComparison() {
  const pinned = state.pinned;
  const current = state.result;
  if (!pinned?.json || !current?.json) {
    showError("A G-code read as it is cannot go in a link, only designs can: share the design on its own (Share).");
    return;
  }
  let files;
  let a;
  let b;
  try {
    files = await Promise.all([...state.files.values()].map(async (f) => ({ slot: f.slot, name: f.name, bytes: new Uint8Array(await f.blob.arrayBuffer()) })));
    b = plain(state.weft.encodeShare(current.json, files));
    a = plain(state.weft.encodeShare(pinned.json, files));
  } catch (err) {
    showError(`Could not make the comparison's link (${messageOf(err)}); load its files again and retry.`);
    return;
  }
  history.replaceState(null, "", `${location.pathname}${location.search}${b.fragment}&vs=${a.fragment.replace(/^#d=/, "")}`);
  let copied = false;
  try {
    await navigator.clipboard.writeText(location.href);
    copied = true;
  } catch { /* no clipboard permission: the address bar holds the link */ }
  const missing = [...new Set([...(a.missing ?? []), ...(b.missing ?? [])])];
  showNotice(`${copied ? "Comparison link copied to the clipboard" : "The comparison's link is in the address bar"} ` +
    `(${location.href.length.toLocaleString("en-US")} characters): it opens B with A pinned beside it.` +
    `${missing.length ? ` Not in the link (too large): ${missing.join(", ")}.` : ""}`, location.href);
}

/**
 * A comparison link in the address (#d=B&vs=A): leaves #d=B for the share link's usual path
 * (opened and run as the design) and runs A first, then pins it. True when there was one.
 */
export function openCompareLink() {
  const m = /^#d=([^&]*)&vs=(.+)$/.exec(location.hash);
  if (!m) return false;
  history.replaceState(null, "", `${location.pathname}${location.search}#d=${m[1]}`);
  runPinned(`#d=${m[2]}`);
  return true;
}

async function runPinned(fragment) {
  let json;
  try {
    json = state.weft.decodeShare(fragment);
  } catch (err) {
    showError(`The compared design in this link (after &vs=) is not readable: ${messageOf(err)}\nOpen the link again, or share the comparison anew.`);
    return;
  }
  const token = jobs.begin("running the compared design (A)");
  try {
    const { plan } = await workers.request({ type: MSG.ESTIMATE, design: json });
    if (plan.refusal || plan.ask) {
      showNotice(`The compared design (A) was not run: it is ${plan.refusal ?? plan.ask}. Open it on its own to run it.`);
      return;
    }
    const res = await workers.request({ type: MSG.RUN, design: json }, (s, f) => jobs.progress(s, f));
    const design = JSON.parse(json);
    const result = { report: res.report, gcode: res.gcode, fileName: design.name, ms: res.ms, json, files: state.filesVersion };
    state.pinned = { result, data: res.preview, origin: design.printer?.origin ?? "corner", json, design, name: design.name, at: new Date(), stale: false, from: "link" };
    showComparison();
  } catch (err) {
    if (!err.cancelled) showError(`The compared design (A) could not run: ${messageOf(err)}`);
  } finally {
    jobs.end(token);
  }
}

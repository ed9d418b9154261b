// Lattice-job views: 2D layer and pattern thumbnails (canvas), score per GIPPO iteration,
// path classes and the per-layer numbers (SVG / table). Pure drawing: main.js owns the state
// and the worker; these functions only turn data into pixels and elements.

const SVG_NS = "http://www.w3.org/2000/svg";
const BACKGROUND = "#1f232a";
/** Colours of the 2D views by feature code (the 3D preview's, see preview.js). */
export const FEATURE_COLORS_2D = Object.freeze({
  4: "#29a3d6", // Lattice
  5: "#1fb04c", // Contour
  6: "#b4b4b4", // Handle
});
const OTHER_COLOR = "#e0b84d";
/** Path classes of the GIPPO paper (Fig. 2): nodes ≥ 15, 5–14, < 5. */
const CLASSES = Object.freeze([
  ["long", "long_paths", "≥ 15 nodes", "#2563eb"],
  ["medium", "medium_paths", "5–14 nodes", "#f59e0b"],
  ["short", "short_paths", "< 5 nodes", "#dc2626"],
]);
const BEST = "#e5484d";
const WORST = "#1f9d55";

/**
 * Draws 2D segments (mm) on a canvas, fitted with a margin, Y up.
 * @param {HTMLCanvasElement} canvas
 * @param {Float32Array|null} segments  `stride` floats per segment: x0 y0 x1 y1 [feature]
 * @param {{stride?: number, frame?: number[]|null, lineWidth?: number, scaleBar?: boolean,
 *          background?: string, color?: string}} [opts]
 *        frame: [minX, minY, maxX, maxY] to fit instead of the segments' bounds
 * @returns {{segments: number, counts: Object<number, number>}}
 */
export function drawSegments2d(canvas, segments, opts = {}) {
  const { stride = 5, frame = null, lineWidth = 1.25, scaleBar = false, background = BACKGROUND, color = null } = opts;
  const dpr = Math.min(window.devicePixelRatio || 1, 2);
  const w = Math.max(1, Math.round((canvas.clientWidth || canvas.width) * dpr));
  const h = Math.max(1, Math.round((canvas.clientHeight || canvas.height) * dpr));
  if (canvas.width !== w) canvas.width = w;
  if (canvas.height !== h) canvas.height = h;
  const ctx = canvas.getContext("2d");
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.fillStyle = background;
  ctx.fillRect(0, 0, w, h);
  const n = segments ? Math.floor(segments.length / stride) : 0;
  const counts = {};
  if (n === 0) return { segments: 0, counts };

  let [minX, minY, maxX, maxY] = frame ?? [Infinity, Infinity, -Infinity, -Infinity];
  if (!frame) {
    for (let i = 0; i < n * stride; i += stride) {
      for (const [x, y] of [[segments[i], segments[i + 1]], [segments[i + 2], segments[i + 3]]]) {
        if (x < minX) minX = x;
        if (x > maxX) maxX = x;
        if (y < minY) minY = y;
        if (y > maxY) maxY = y;
      }
    }
  }
  const margin = 8 * dpr;
  const spanX = Math.max(maxX - minX, 1e-6);
  const spanY = Math.max(maxY - minY, 1e-6);
  const scale = Math.min((w - 2 * margin) / spanX, (h - 2 * margin) / spanY);
  const ox = (w - spanX * scale) / 2 - minX * scale;
  const oy = (h + spanY * scale) / 2 + minY * scale;

  // One path per colour: few state changes however many segments.
  const byColor = new Map();
  for (let s = 0; s < n; s++) {
    const i = s * stride;
    const code = stride > 4 ? segments[i + 4] : 4;
    counts[code] = (counts[code] ?? 0) + 1;
    const c = color ?? FEATURE_COLORS_2D[code] ?? OTHER_COLOR;
    let list = byColor.get(c);
    if (!list) byColor.set(c, (list = []));
    list.push(i);
  }
  ctx.lineCap = "round";
  ctx.lineWidth = lineWidth * dpr;
  for (const [c, list] of byColor) {
    ctx.strokeStyle = c;
    ctx.beginPath();
    for (const i of list) {
      ctx.moveTo(ox + segments[i] * scale, oy - segments[i + 1] * scale);
      ctx.lineTo(ox + segments[i + 2] * scale, oy - segments[i + 3] * scale);
    }
    ctx.stroke();
  }
  if (scaleBar) {
    // A round length of about a fifth of the width, bottom right.
    const target = (w * 0.2) / scale;
    const p = 10 ** Math.floor(Math.log10(target));
    const len = [5, 2, 1].map((k) => k * p).find((v) => v <= target) ?? p;
    const px = len * scale;
    const x1 = w - margin;
    const y = h - margin;
    ctx.strokeStyle = "#e6e9ee";
    ctx.lineWidth = 2 * dpr;
    ctx.beginPath();
    ctx.moveTo(x1 - px, y);
    ctx.lineTo(x1, y);
    ctx.stroke();
    ctx.fillStyle = "#e6e9ee";
    ctx.font = `${11 * dpr}px system-ui, sans-serif`;
    ctx.textAlign = "right";
    ctx.textBaseline = "bottom";
    ctx.fillText(`${len} mm`, x1, y - 3 * dpr);
  }
  return { segments: n, counts };
}

function svg(tag, attrs = {}, text) {
  const el = document.createElementNS(SVG_NS, tag);
  for (const [k, v] of Object.entries(attrs)) el.setAttribute(k, String(v));
  if (text !== undefined) el.textContent = text;
  return el;
}

function fmt(v, digits = 3) {
  if (typeof v !== "number" || !Number.isFinite(v)) return "–";
  return v.toLocaleString("en-US", { maximumFractionDigits: digits, minimumFractionDigits: 0 });
}

/** Round tick values covering [lo, hi] (about `count` of them). */
function ticks(lo, hi, count) {
  const span = hi - lo;
  if (!(span > 0)) return [lo];
  const raw = span / count;
  const p = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((k) => k * p).find((v) => v >= raw) ?? raw;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(Number(v.toPrecision(12)));
  return out;
}

/**
 * Score of every GIPPO iteration (equation 1), best red, worst green (the paper's Fig. 2 (i)).
 * For methods without iterations (euler, continuous) the paths produced are compared with
 * the proven lower bound instead.
 * @param {SVGSVGElement} host
 * @param {Object|null} layer  one entry of report.paths.layers
 * @param {string|null} method report.paths.method
 * @returns {string} the card title
 */
export function renderScorePlot(host, layer, method) {
  const W = 360;
  const H = 190;
  host.replaceChildren();
  host.setAttribute("viewBox", `0 0 ${W} ${H}`);
  host.removeAttribute("data-points");
  host.removeAttribute("data-kind");
  const scores = layer?.iteration_scores ?? [];
  if (!layer) {
    host.append(svg("text", { x: W / 2, y: H / 2, "text-anchor": "middle", class: "plot-empty" }, "run a lattice design to see its scores"));
    return "Score per iteration";
  }
  if (!scores.length) {
    renderBound(host, layer, method, W, H);
    return "Paths vs lower bound";
  }
  host.dataset.kind = "scores";
  host.dataset.points = String(scores.length);
  const m = { l: 46, r: 10, t: 22, b: 30 };
  let lo = Infinity;
  let hi = -Infinity;
  let best = 0;
  let worst = 0;
  scores.forEach((s, i) => {
    if (s > scores[best]) best = i;
    if (s < scores[worst]) worst = i;
    if (s < lo) lo = s;
    if (s > hi) hi = s;
  });
  const pad = hi > lo ? (hi - lo) * 0.08 : Math.max(Math.abs(hi) * 0.05, 1e-3);
  const y0 = lo - pad;
  const y1 = hi + pad;
  const n = scores.length;
  const px = (i) => m.l + (n > 1 ? (i / (n - 1)) * (W - m.l - m.r) : (W - m.l - m.r) / 2);
  const py = (v) => H - m.b - ((v - y0) / (y1 - y0)) * (H - m.t - m.b);

  const axes = svg("g", { class: "plot-axes" });
  axes.append(svg("line", { x1: m.l, y1: H - m.b, x2: W - m.r, y2: H - m.b }));
  axes.append(svg("line", { x1: m.l, y1: m.t, x2: m.l, y2: H - m.b }));
  const yt = ticks(y0, y1, 4);
  const digits = Math.max(0, Math.min(6, 1 - Math.floor(Math.log10(Math.max(1e-12, (yt[1] ?? yt[0]) - yt[0] || Math.abs(yt[0]) || 1)))));
  for (const v of yt) {
    axes.append(svg("line", { x1: m.l, y1: py(v), x2: W - m.r, y2: py(v), class: "grid" }));
    axes.append(svg("text", { x: m.l - 4, y: py(v) + 3, "text-anchor": "end" }, v.toFixed(digits)));
  }
  for (const i of [...new Set([0, Math.floor((n - 1) / 2), n - 1])]) {
    axes.append(svg("text", { x: px(i), y: H - m.b + 13, "text-anchor": "middle" }, String(i + 1)));
  }
  axes.append(svg("text", { x: (m.l + W - m.r) / 2, y: H - 4, "text-anchor": "middle", class: "axis-title" }, "iteration"));
  axes.append(svg("text", { x: 11, y: (m.t + H - m.b) / 2, "text-anchor": "middle", class: "axis-title",
    transform: `rotate(-90 11 ${(m.t + H - m.b) / 2})` }, "score (eq. 1)"));
  host.append(axes);

  // Every iteration as a dot: one path element ("M x y h0" per point, round caps).
  let d = "";
  for (let i = 0; i < n; i++) d += `M${px(i).toFixed(1)} ${py(scores[i]).toFixed(1)}h0`;
  host.append(svg("path", { d, class: "dots" }));
  const mark = (i, color, label) => {
    const c = svg("circle", { cx: px(i), cy: py(scores[i]), r: 4, fill: color, class: `mark-${label}` });
    c.append(svg("title", {}, `${label}: ${fmt(scores[i], 4)} (iteration ${i + 1})`));
    host.append(c);
  };
  mark(worst, WORST, "worst");
  mark(best, BEST, "best");
  const legend = svg("text", { x: m.l + 4, y: 13, class: "plot-legend" });
  legend.append(svg("tspan", { fill: BEST }, "● "), svg("tspan", {}, `best ${fmt(scores[best], 4)} (it. ${best + 1})   `),
    svg("tspan", { fill: WORST }, "● "), svg("tspan", {}, `worst ${fmt(scores[worst], 4)} (it. ${worst + 1})`));
  host.append(legend);
  return `Score · ${method ?? "gippo"}`;
}

function renderBound(host, layer, method, W, H) {
  host.dataset.kind = "bound";
  const bound = layer.lower_bound_paths ?? 0;
  const paths = layer.paths ?? 0;
  const max = Math.max(bound, paths, 1);
  const rows = [["lower bound", bound, "#8a93a3"], [`${method ?? "method"} paths`, paths, paths === bound ? WORST : "#2563eb"]];
  const x0 = 110;
  const wMax = W - x0 - 50;
  rows.forEach(([label, v, color], k) => {
    const y = 40 + k * 46;
    host.append(svg("text", { x: x0 - 8, y: y + 15, "text-anchor": "end", class: "bar-label" }, label));
    host.append(svg("rect", { x: x0, y, width: Math.max(1, (v / max) * wMax), height: 22, rx: 3, fill: color }));
    host.append(svg("text", { x: x0 + (v / max) * wMax + 6, y: y + 15, class: "bar-value" }, String(v)));
  });
  const verdict = paths === bound ? "minimal: as few paths as any method can print" : `${paths - bound} above the minimum`;
  host.append(svg("text", { x: W / 2, y: H - 16, "text-anchor": "middle", class: paths === bound ? "verdict minimal" : "verdict" }, verdict));
}

/**
 * Long / medium / short path counts as horizontal bars.
 * @param {SVGSVGElement} host
 * @param {Object|null} layer
 */
export function renderPathClasses(host, layer) {
  const W = 300;
  const H = 84;
  host.replaceChildren();
  host.setAttribute("viewBox", `0 0 ${W} ${H}`);
  host.removeAttribute("data-drawn");
  if (!layer) {
    host.append(svg("text", { x: W / 2, y: H / 2, "text-anchor": "middle", class: "plot-empty" }, "long, medium and short paths after a run"));
    return;
  }
  const total = CLASSES.reduce((s, [, key]) => s + (layer[key] ?? 0), 0);
  const max = Math.max(1, ...CLASSES.map(([, key]) => layer[key] ?? 0));
  const x0 = 58;
  const wMax = W - x0 - 62;
  CLASSES.forEach(([name, key, doc, color], k) => {
    const v = layer[key] ?? 0;
    const y = 6 + k * 26;
    const g = svg("g", { class: `bar bar-${name}` });
    g.append(svg("title", {}, `${name} paths (${doc}): ${v}`));
    g.append(svg("text", { x: x0 - 6, y: y + 13, "text-anchor": "end", class: "bar-label" }, name));
    g.append(svg("rect", { x: x0, y, width: wMax, height: 18, rx: 3, class: "bar-track" }));
    g.append(svg("rect", { x: x0, y, width: v ? Math.max(2, (v / max) * wMax) : 0, height: 18, rx: 3, fill: color }));
    const pct = total ? ` · ${Math.round((v / total) * 100)}%` : "";
    g.append(svg("text", { x: x0 + wMax + 6, y: y + 13, class: "bar-value" }, `${v}${pct}`));
    host.append(g);
  });
  host.dataset.drawn = String(total);
}

/**
 * The layer's numbers. Marks `paths` when it equals the lower bound ("minimal").
 * @param {HTMLTableElement} table
 * @param {Object|null} layer
 * @param {{pores?: number, strokes?: number}} [extra]
 */
export function renderPathTable(table, layer, extra = {}) {
  table.replaceChildren();
  table.removeAttribute("data-minimal");
  if (!layer) return;
  const minimal = layer.paths === layer.lower_bound_paths;
  table.dataset.minimal = String(minimal);
  const rows = [
    ["Nodes", fmt(layer.nodes, 0)],
    ["Edges", fmt(layer.edges, 0)],
    ["Components", fmt(layer.components, 0)],
    ["Odd nodes", fmt(layer.odd_nodes, 0)],
    ["Lower bound", fmt(layer.lower_bound_paths, 0)],
    ["Paths", fmt(layer.paths, 0), minimal ? "minimal" : `+${fmt(layer.paths - layer.lower_bound_paths, 0)}`],
    ["Score (eq. 1)", fmt(layer.score, 4)],
    ["LTS", fmt(layer.lts_percent, 1), "%"],
    ["OE", fmt(layer.oe_percent, 1), "%"],
    ["Travel", fmt(layer.travel_mm, 1), "mm"],
    ["Retractions", fmt(layer.retractions, 0)],
  ];
  if (layer.degenerate_dropped) rows.push(["Degenerate dropped", fmt(layer.degenerate_dropped, 0)]);
  if (typeof extra.pores === "number") rows.push(["Pores", fmt(extra.pores * 100, 1), "%"]);
  const body = document.createElement("tbody");
  for (const [k, v, note] of rows) {
    const tr = document.createElement("tr");
    const th = document.createElement("th");
    th.scope = "row";
    th.textContent = k;
    const td = document.createElement("td");
    td.textContent = v;
    if (note === "minimal") {
      tr.className = "minimal";
      const badge = document.createElement("span");
      badge.className = "badge";
      badge.textContent = "minimal";
      badge.title = "paths = lower bound: no method can print this layer in fewer paths";
      td.append(" ", badge);
    } else if (note) {
      const u = document.createElement("span");
      u.className = "unit";
      u.textContent = ` ${note}`;
      td.append(u);
    }
    tr.append(th, td);
    body.append(tr);
  }
  table.append(body);
}

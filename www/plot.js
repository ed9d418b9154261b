// Generic SVG plots of a run report: line, scatter, histogram and (horizontal) bars, with
// dashed horizontal reference lines. Knows nothing about a job kind: the report says what to
// draw (see the RunReport `plots` in protocol.js / ARCHITECTURE.md).
//
//   renderPlot(svgElement, plot, { group })  → { series, points, bars }
//
// plot = { key, title, kind, x: {label, unit}, y: {label, unit}, group?,
//          series: [{ name, kind?, group_index?, x, y, color? }] }
// A plot with a `group` shows only the series of the chosen group (and those without one).

const SVG_NS = "http://www.w3.org/2000/svg";
/** Series colours when the report gives none. */
export const PALETTE = Object.freeze(["#2563eb", "#e5484d", "#1f9d55", "#f59e0b", "#8b5cf6", "#0891b2", "#db2777", "#64748b"]);
/** Bar colours by category when a bars plot has one series (long, medium, short …). */
const CATEGORY_PALETTE = Object.freeze(["#2563eb", "#f59e0b", "#dc2626", "#1f9d55", "#8b5cf6", "#0891b2", "#db2777", "#64748b"]);
const W = 360;
const H = 200;

function el(tag, attrs = {}, text) {
  const e = document.createElementNS(SVG_NS, tag);
  for (const [k, v] of Object.entries(attrs)) if (v !== undefined && v !== null) e.setAttribute(k, String(v));
  if (text !== undefined) e.textContent = text;
  return e;
}

/** "label (unit)", or the label alone. */
export function axisTitle(axis) {
  if (!axis) return "";
  const label = axis.label ?? "";
  return axis.unit ? `${label}${label ? " " : ""}(${axis.unit})` : label;
}

/** A number for people: grouped thousands, at most `digits` decimals (more below 0.1, so a
 * small value keeps two significant digits instead of showing as 0). */
export function formatNumber(v, digits = 3) {
  if (typeof v !== "number") return v === undefined || v === null ? "–" : String(v);
  if (!Number.isFinite(v)) return "–";
  const a = Math.abs(v);
  if (a !== 0 && (a >= 1e9 || a < 1e-4)) return v.toExponential(2);
  const d = a >= 1000 ? 0 : a >= 100 ? Math.min(digits, 1) : a >= 10 ? Math.min(digits, 2) : a > 0 && a < 0.1 ? Math.max(digits, Math.ceil(-Math.log10(a)) + 1) : digits;
  return v.toLocaleString("en-US", { maximumFractionDigits: d, minimumFractionDigits: 0 });
}

/** Round tick values covering [lo, hi] (about `count` of them) and their step. */
export function ticks(lo, hi, count) {
  const span = hi - lo;
  // A span within rounding of the values (a constant that interpolation left 1 ulp off) has
  // no ticks between: one value, as for a flat line.
  if (!(span > 0) || !Number.isFinite(span) || span <= Math.max(Math.abs(lo), Math.abs(hi)) * 1e-9) return { values: [lo], step: 1 };
  const raw = span / count;
  const p = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((k) => k * p).find((v) => v >= raw) ?? raw;
  const values = [];
  for (let v = Math.ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-9; v += step) values.push(Number(v.toPrecision(12)));
  return { values, step };
}

function tickText(v, step) {
  const digits = Math.max(0, Math.min(6, -Math.floor(Math.log10(step) + 1e-9)));
  const a = Math.abs(v);
  if (a >= 1e6) return v.toExponential(1);
  if (a >= 10000 && step >= 1000) return `${(v / 1000).toLocaleString("en-US", { maximumFractionDigits: 1 })}k`;
  return v.toLocaleString("en-US", { maximumFractionDigits: digits, minimumFractionDigits: Math.min(digits, 6) });
}

/** The series of `plot` shown for `group` (null: all). */
export function visibleSeries(plot, group) {
  const all = plot?.series ?? [];
  if (!plot?.group || group === null || group === undefined) return all;
  return all.filter((s) => s.group_index === undefined || s.group_index === null || s.group_index === group);
}

/** Group indices used by a plot's series. */
export function plotGroups(plot) {
  if (!plot?.group) return [];
  return (plot.series ?? []).map((s) => s.group_index).filter((g) => Number.isInteger(g));
}

/**
 * Draws `plot` into `host` (an <svg>), replacing its content.
 * @param {SVGSVGElement} host
 * @param {Object} plot
 * @param {{group?: number|null}} [opts]
 * @returns {{series: number, points: number, bars: number}}
 */
export function renderPlot(host, plot, { group = null } = {}) {
  host.replaceChildren();
  host.classList.add("plot");
  host.dataset.plotKind = plot?.kind ?? "";
  host.dataset.plotKey = plot?.key ?? "";
  host.setAttribute("role", "img");
  host.setAttribute("aria-label", plot?.title ?? "plot");
  const series = visibleSeries(plot, group).map((s, i) => ({
    ...s,
    kind: s.kind ?? (plot.kind === "histogram" ? "histogram" : plot.kind),
    color: s.color ?? PALETTE[i % PALETTE.length],
    given: Boolean(s.color),
  }));
  const data = series.filter((s) => (s.y?.length ?? 0) > 0);
  let info;
  if (!data.length) info = renderEmpty(host, "no data");
  else if (plot.kind === "bars") info = renderBars(host, plot, data);
  else info = renderXY(host, plot, data);
  host.dataset.points = String(info.points);
  host.dataset.bars = String(info.bars);
  host.dataset.series = String(info.series);
  return info;
}

function renderEmpty(host, text) {
  host.setAttribute("viewBox", `0 0 ${W} 60`);
  host.append(el("text", { x: W / 2, y: 34, "text-anchor": "middle", class: "plot-empty" }, text));
  return { series: 0, points: 0, bars: 0 };
}

/** Line, scatter and histogram series (and hlines) on numeric axes. */
function renderXY(host, plot, series) {
  host.setAttribute("viewBox", `0 0 ${W} ${H}`);
  host.style.maxWidth = "620px";
  const lines = series.filter((s) => s.kind !== "hline");
  const hlines = series.filter((s) => s.kind === "hline");
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  for (const s of lines) {
    const xs = s.x ?? [];
    const n = s.kind === "histogram" ? s.y.length + 1 : s.y.length;
    for (let i = 0; i < n; i++) {
      const x = typeof xs[i] === "number" ? xs[i] : i + 1;
      if (x < x0) x0 = x;
      if (x > x1) x1 = x;
    }
    for (const v of s.y) {
      if (!Number.isFinite(v)) continue;
      if (v < y0) y0 = v;
      if (v > y1) y1 = v;
    }
    if (s.kind === "histogram") y0 = Math.min(y0, 0);
  }
  for (const s of hlines) {
    const v = s.y[0];
    if (Number.isFinite(v)) {
      y0 = Math.min(y0, v);
      y1 = Math.max(y1, v);
    }
  }
  if (!Number.isFinite(x0)) { x0 = 0; x1 = 1; }
  if (!Number.isFinite(y0)) { y0 = 0; y1 = 1; }
  if (x1 === x0) { x0 -= 0.5; x1 += 0.5; }
  // A flat line (or one flat within rounding) gets a band around it.
  const flat = !(y1 - y0 > Math.max(Math.abs(y0), Math.abs(y1)) * 1e-9);
  const pad = flat ? Math.max(Math.abs(y1) * 0.05, 1e-3) : (y1 - y0) * 0.08;
  const histogram = lines.some((s) => s.kind === "histogram");
  y0 = histogram && y0 >= 0 ? 0 : y0 - pad;
  y1 += pad;

  const yt = ticks(y0, y1, 4);
  const yLabels = yt.values.map((v) => tickText(v, yt.step));
  const m = { l: 20 + Math.max(...yLabels.map((t) => t.length)) * 5.6 + 4, r: 10, t: 22, b: 30 };
  const px = (x) => m.l + ((x - x0) / (x1 - x0)) * (W - m.l - m.r);
  const py = (v) => H - m.b - ((v - y0) / (y1 - y0)) * (H - m.t - m.b);

  const axes = el("g", { class: "plot-axes" });
  yt.values.forEach((v, k) => {
    axes.append(el("line", { x1: m.l, y1: py(v), x2: W - m.r, y2: py(v), class: "grid" }));
    axes.append(el("text", { x: m.l - 4, y: py(v) + 3, "text-anchor": "end" }, yLabels[k]));
  });
  const xt = ticks(x0, x1, 5);
  const integerX = lines.every((s) => (s.x ?? []).every((x) => typeof x !== "number" || Number.isInteger(x)));
  const xStep = integerX ? Math.max(1, xt.step) : xt.step;
  for (const v of xt.values) {
    if (integerX && !Number.isInteger(v)) continue;
    axes.append(el("line", { x1: px(v), y1: H - m.b, x2: px(v), y2: H - m.b + 3 }));
    axes.append(el("text", { x: px(v), y: H - m.b + 13, "text-anchor": "middle" }, tickText(v, xStep)));
  }
  axes.append(el("line", { x1: m.l, y1: H - m.b, x2: W - m.r, y2: H - m.b, class: "axis" }));
  axes.append(el("line", { x1: m.l, y1: m.t, x2: m.l, y2: H - m.b, class: "axis" }));
  const xTitle = axisTitle(plot.x);
  const yTitle = axisTitle(plot.y);
  if (xTitle) axes.append(el("text", { x: (m.l + W - m.r) / 2, y: H - 3, "text-anchor": "middle", class: "axis-title" }, xTitle));
  if (yTitle) {
    const cy = (m.t + H - m.b) / 2;
    axes.append(el("text", { x: 10, y: cy, "text-anchor": "middle", class: "axis-title", transform: `rotate(-90 10 ${cy})` }, yTitle));
  }
  host.append(axes);

  let points = 0;
  let bars = 0;
  const body = el("g", { class: "plot-body" });
  for (const s of lines) {
    const xs = s.x ?? [];
    const xAt = (i) => (typeof xs[i] === "number" ? xs[i] : i + 1);
    const n = s.y.length;
    const g = el("g", { class: `series series-${s.kind}`, "data-series": s.name ?? "", "data-points": n });
    g.append(el("title", {}, seriesSummary(s, plot)));
    if (s.kind === "histogram") {
      for (let i = 0; i < n; i++) {
        const a = px(xAt(i)), b = px(xAt(i + 1));
        const top = py(Math.max(0, s.y[i]));
        g.append(el("rect", { x: Math.min(a, b) + 0.5, y: top, width: Math.max(0.5, Math.abs(b - a) - 1), height: Math.max(0, py(Math.max(y0, 0)) - top), fill: s.color, class: "bar" }));
      }
      bars += n;
    } else if (s.kind === "scatter") {
      let d = "";
      for (let i = 0; i < n; i++) if (Number.isFinite(s.y[i])) d += `M${px(xAt(i)).toFixed(1)} ${py(s.y[i]).toFixed(1)}h0`;
      g.append(el("path", { d, class: "dots", stroke: s.color }));
    } else {
      let d = "";
      let pen = false;
      for (let i = 0; i < n; i++) {
        if (!Number.isFinite(s.y[i])) { pen = false; continue; }
        d += `${pen ? "L" : "M"}${px(xAt(i)).toFixed(1)} ${py(s.y[i]).toFixed(1)}`;
        pen = true;
      }
      g.append(el("path", { d, class: "line", stroke: s.color }));
      if (n === 1) g.append(el("circle", { cx: px(xAt(0)), cy: py(s.y[0]), r: 2.5, fill: s.color }));
    }
    points = Math.max(points, n);
    body.append(g);
  }
  for (const s of hlines) {
    const v = s.y[0];
    if (!Number.isFinite(v)) continue;
    const g = el("g", { class: "series series-hline", "data-series": s.name ?? "", "data-points": 1 });
    g.append(el("title", {}, `${s.name ?? "reference"}: ${formatNumber(v, 4)}${plot.y?.unit ? ` ${plot.y.unit}` : ""}`));
    g.append(el("line", { x1: m.l, y1: py(v), x2: W - m.r, y2: py(v), stroke: s.color, class: "hline" }));
    g.append(el("text", { x: W - m.r - 2, y: py(v) - 3, "text-anchor": "end", fill: s.color, class: "hline-label" },
      `${s.name ?? ""} ${formatNumber(v, 4)}`.trim()));
    body.append(g);
  }
  host.append(body);
  host.append(legend(series, m.l));
  addHover(host, plot, lines, { px, py, m, x0, x1 });
  return { series: series.length, points, bars };
}

function seriesSummary(s, plot) {
  const ys = s.y.filter(Number.isFinite);
  if (!ys.length) return s.name ?? "";
  const unit = plot.y?.unit ? ` ${plot.y.unit}` : "";
  const lo = Math.min(...ys);
  const hi = Math.max(...ys);
  return `${s.name ?? "series"}: ${ys.length} values, ${formatNumber(lo, 4)} – ${formatNumber(hi, 4)}${unit}, last ${formatNumber(ys[ys.length - 1], 4)}${unit}`;
}

function legend(series, x) {
  const g = el("g", { class: "plot-legend" });
  const named = series.filter((s) => s.name);
  if (named.length < 2 && !named.some((s) => s.kind === "hline")) return g;
  let cx = x;
  for (const s of named) {
    if (s.kind === "hline") g.append(el("line", { x1: cx, y1: 9, x2: cx + 12, y2: 9, stroke: s.color, class: "hline" }));
    else if (s.kind === "scatter") g.append(el("circle", { cx: cx + 5, cy: 9, r: 3, fill: s.color }));
    else g.append(el("rect", { x: cx, y: 5, width: 12, height: 8, rx: 2, fill: s.color }));
    const t = el("text", { x: cx + 16, y: 12.5 }, s.name);
    g.append(t);
    cx += 16 + s.name.length * 5.6 + 12;
    if (cx > W - 40) break;
  }
  return g;
}

/** A vertical guide and the values of every series at the pointer's x. */
function addHover(host, plot, series, { px, py, m, x0, x1 }) {
  const targets = series.filter((s) => s.kind !== "histogram" && s.y.length > 0);
  if (!targets.length) return;
  const guide = el("g", { class: "plot-hover", visibility: "hidden" });
  const line = el("line", { y1: m.t, y2: H - m.b });
  const box = el("rect", { rx: 3, height: 14 + 12 * targets.length });
  const text = el("text", {});
  guide.append(line, box, text);
  const area = el("rect", { x: m.l, y: m.t, width: W - m.l - m.r, height: H - m.t - m.b, class: "plot-area" });
  host.append(guide, area);
  const toData = (evt) => {
    const r = host.getBoundingClientRect();
    const vb = host.viewBox.baseVal;
    const sx = ((evt.clientX - r.left) / r.width) * vb.width;
    return x0 + ((sx - m.l) / (W - m.l - m.r)) * (x1 - x0);
  };
  area.addEventListener("pointermove", (evt) => {
    const x = toData(evt);
    const first = targets[0];
    const xs = first.x ?? [];
    let best = 0;
    let bestD = Infinity;
    for (let i = 0; i < first.y.length; i++) {
      const d = Math.abs((typeof xs[i] === "number" ? xs[i] : i + 1) - x);
      if (d < bestD) { bestD = d; best = i; }
    }
    const xv = typeof xs[best] === "number" ? xs[best] : best + 1;
    const gx = px(xv);
    line.setAttribute("x1", gx);
    line.setAttribute("x2", gx);
    text.replaceChildren();
    const lines = [`${plot.x?.label ?? "x"} ${formatNumber(xv, 4)}`];
    for (const s of targets) {
      const sx = s.x ?? [];
      let j = sx.length ? sx.indexOf(xv) : best;
      if (j < 0) j = Math.min(best, s.y.length - 1);
      lines.push(`${s.name ?? "y"}: ${formatNumber(s.y[j], 4)}`);
    }
    const left = gx > W / 2;
    const tx = left ? gx - 6 : gx + 6;
    lines.forEach((t, k) => text.append(el("tspan", { x: tx, y: m.t + 11 + 12 * k, "text-anchor": left ? "end" : "start" }, t)));
    const wBox = Math.max(...lines.map((t) => t.length)) * 5.4 + 8;
    box.setAttribute("x", left ? tx - wBox + 4 : tx - 4);
    box.setAttribute("y", m.t + 1);
    box.setAttribute("width", wBox);
    guide.setAttribute("visibility", "visible");
  });
  area.addEventListener("pointerleave", () => guide.setAttribute("visibility", "hidden"));
}

/** Horizontal bars: one row per category (and per series when there are several). */
function renderBars(host, plot, series) {
  const bars = series.filter((s) => s.kind !== "hline");
  const refs = series.filter((s) => s.kind === "hline");
  const cats = [];
  for (const s of bars) for (const c of s.x ?? s.y.map((_, i) => String(i + 1))) if (!cats.includes(String(c))) cats.push(String(c));
  const rows = [];
  for (const c of cats) {
    for (const s of bars) {
      const i = (s.x ?? []).map(String).indexOf(c);
      const v = i >= 0 ? s.y[i] : s.x ? undefined : s.y[cats.indexOf(c)];
      if (v !== undefined) rows.push({ cat: c, s, v, label: bars.length > 1 ? `${c} · ${s.name}` : c });
    }
  }
  const rowH = 24;
  const title = axisTitle(plot.y);
  const h = 8 + rows.length * rowH + (title ? 14 : 0);
  const w = 440;
  host.setAttribute("viewBox", `0 0 ${w} ${h}`);
  host.style.maxWidth = `${w}px`; // text at its size: bars do not grow with the card
  const max = Math.max(1e-12, ...rows.map((r) => Math.abs(r.v)), ...refs.map((s) => Math.abs(s.y[0] ?? 0)));
  const totals = new Map();
  for (const r of rows) totals.set(r.s, (totals.get(r.s) ?? 0) + (r.v > 0 ? r.v : 0));
  const x0 = 8 + Math.min(20, Math.max(3, ...rows.map((r) => r.label.length))) * 5.6;
  const wMax = w - x0 - 60;
  const unit = plot.y?.unit ? ` ${plot.y.unit}` : "";
  const body = el("g", { class: "plot-body" });
  rows.forEach((r, k) => {
    const y = 4 + k * rowH;
    const single = bars.length === 1 && !r.s.given;
    const color = single ? CATEGORY_PALETTE[cats.indexOf(r.cat) % CATEGORY_PALETTE.length] : r.s.color;
    const g = el("g", { class: "bar-row", "data-category": r.cat, "data-series": r.s.name ?? "" });
    const total = totals.get(r.s);
    const pct = total > 0 && r.v >= 0 ? ` (${Math.round((r.v / total) * 100)} % of ${formatNumber(total, 4)})` : "";
    g.append(el("title", {}, `${r.label}: ${formatNumber(r.v, 4)}${unit}${pct}`));
    g.append(el("text", { x: x0 - 6, y: y + 12.5, "text-anchor": "end", class: "bar-label" }, r.label));
    g.append(el("rect", { x: x0, y, width: wMax, height: 17, rx: 3, class: "bar-track" }));
    g.append(el("rect", { x: x0, y, width: r.v > 0 ? Math.max(2, (r.v / max) * wMax) : 0, height: 17, rx: 3, fill: color, class: "bar" }));
    g.append(el("text", { x: x0 + wMax + 6, y: y + 12.5, class: "bar-value" }, `${formatNumber(r.v, 3)}${unit}`));
    body.append(g);
  });
  for (const s of refs) {
    const x = x0 + ((s.y[0] ?? 0) / max) * wMax;
    const g = el("g", { class: "series series-hline", "data-series": s.name ?? "" });
    g.append(el("title", {}, `${s.name ?? "reference"}: ${formatNumber(s.y[0], 4)}${unit}`));
    g.append(el("line", { x1: x, y1: 2, x2: x, y2: 6 + rows.length * rowH - 4, stroke: s.color, class: "hline" }));
    body.append(g);
  }
  host.append(body);
  if (title) host.append(el("text", { x: x0 + wMax / 2, y: h - 3, "text-anchor": "middle", class: "axis-title" }, title));
  return { series: bars.length, points: rows.length, bars: rows.length };
}

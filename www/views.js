// Generic viewers for the answers of Session.inspect, chosen by their `shape`:
//   lines2d  stride 5: x0 y0 x1 y1 code         (mm, coloured by feature code)
//   lines3d  stride 7: x0 y0 z0 x1 y1 z1 code   (orthographic view from the front left)
//   image    width × height floats, row-major    (grey ramp from meta.min to meta.max)
//   mesh     stride 9: one triangle              (orthographic, flat shaded)
// Pure drawing on a <canvas>: main.js owns the state and the worker.

import { formatNumber } from "./plot.js";

export const BACKGROUND = "#1f232a";
export const OTHER_COLOR = "#e0b84d";
export const TEXT = "#e6e9ee";

/**
 * Feature styles from the schema: code → {label, color}.
 * @param {Array<{code: number, label?: string, name?: string, color?: string}>} features
 * @returns {Map<number, {label: string, color: string}>}
 */
export function featureStyles(features) {
  const m = new Map();
  for (const f of features ?? []) m.set(Number(f.code), { label: f.label ?? f.name ?? `feature ${f.code}`, color: f.color ?? OTHER_COLOR });
  return m;
}

/** Sizes the canvas' backing store to its CSS box; returns the 2D context and size. */
function setup(canvas, background = BACKGROUND) {
  // A picture (pictures.js) is drawn at its own size and scale: canvas.picture = {width, height, scale}.
  const pic = canvas.picture;
  const dpr = pic?.scale ?? Math.min(window.devicePixelRatio || 1, 2);
  const w = pic?.width ?? Math.max(1, Math.round((canvas.clientWidth || canvas.width) * dpr));
  const h = pic?.height ?? Math.max(1, Math.round((canvas.clientHeight || canvas.height) * dpr));
  if (canvas.width !== w) canvas.width = w;
  if (canvas.height !== h) canvas.height = h;
  const ctx = canvas.getContext("2d");
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.fillStyle = background;
  ctx.fillRect(0, 0, w, h);
  return { ctx, w, h, dpr };
}

/** A fit of [minX, minY, maxX, maxY] into the canvas with a margin, Y up. */
function fitFrame(w, h, margin, [minX, minY, maxX, maxY]) {
  const spanX = Math.max(maxX - minX, 1e-6);
  const spanY = Math.max(maxY - minY, 1e-6);
  const scale = Math.min((w - 2 * margin) / spanX, (h - 2 * margin) / spanY);
  const ox = (w - spanX * scale) / 2 - minX * scale;
  const oy = (h + spanY * scale) / 2 + minY * scale;
  return { scale, sx: (x) => ox + x * scale, sy: (y) => oy - y * scale, ix: (px) => (px - ox) / scale, iy: (py) => (oy - py) / scale };
}

function scaleBar(ctx, w, h, dpr, scale) {
  // A round length of about a fifth of the width, bottom right.
  const target = (w * 0.2) / scale;
  if (!(target > 0) || !Number.isFinite(target)) return;
  const p = 10 ** Math.floor(Math.log10(target));
  const len = [5, 2, 1].map((k) => k * p).find((v) => v <= target) ?? p;
  const px = len * scale;
  const margin = 8 * dpr;
  const x1 = w - margin;
  const y = h - margin;
  ctx.strokeStyle = TEXT;
  ctx.lineWidth = 2 * dpr;
  ctx.beginPath();
  ctx.moveTo(x1 - px, y);
  ctx.lineTo(x1, y);
  ctx.stroke();
  ctx.fillStyle = TEXT;
  ctx.font = `${11 * dpr}px system-ui, sans-serif`;
  ctx.textAlign = "right";
  ctx.textBaseline = "bottom";
  ctx.fillText(`${Number(len.toPrecision(3))} mm`, x1, y - 3 * dpr);
}

/** Strokes segments grouped by colour (one path per colour). */
function strokeByColor(ctx, n, colorOf, draw) {
  const byColor = new Map();
  for (let s = 0; s < n; s++) {
    const c = colorOf(s);
    let list = byColor.get(c);
    if (!list) byColor.set(c, (list = []));
    list.push(s);
  }
  for (const [c, list] of byColor) {
    ctx.strokeStyle = c;
    ctx.beginPath();
    for (const s of list) draw(s);
    ctx.stroke();
  }
}

/**
 * Draws 2D segments (mm) on a canvas, fitted with a margin, Y up.
 * @param {HTMLCanvasElement} canvas
 * @param {Float32Array|null} segments  `stride` floats per segment: x0 y0 x1 y1 [code]
 * @param {{stride?: number, frame?: number[]|null, lineWidth?: number, scaleBar?: boolean,
 *          background?: string, color?: string|null, styles?: Map<number, {color: string}>}} [opts]
 *        frame: [minX, minY, maxX, maxY] to fit instead of the segments' bounds
 * @returns {{items: number, counts: Object<number, number>, toData?: Function, toPx?: Function}}
 *          toData(x, y) / toPx(x, y): CSS pixels of the canvas ↔ data coordinates
 */
export function drawSegments2d(canvas, segments, opts = {}) {
  const { stride = 5, frame = null, lineWidth = 1.25, background = BACKGROUND, color = null, styles = new Map() } = opts;
  const { ctx, w, h, dpr } = setup(canvas, background);
  const n = segments ? Math.floor(segments.length / stride) : 0;
  const counts = {};
  if (n === 0) return { items: 0, counts };
  let box = frame;
  if (!box) {
    box = [Infinity, Infinity, -Infinity, -Infinity];
    for (let i = 0; i < n * stride; i += stride) {
      for (const k of [0, 2]) {
        const x = segments[i + k], y = segments[i + k + 1];
        if (x < box[0]) box[0] = x;
        if (x > box[2]) box[2] = x;
        if (y < box[1]) box[1] = y;
        if (y > box[3]) box[3] = y;
      }
    }
  }
  const { scale, sx, sy, ix, iy } = fitFrame(w, h, 8 * dpr, box);
  ctx.lineCap = "round";
  ctx.lineWidth = lineWidth * dpr;
  strokeByColor(ctx, n, (s) => {
    const code = stride > 4 ? segments[s * stride + 4] : -1;
    counts[code] = (counts[code] ?? 0) + 1;
    return color ?? styles.get(code)?.color ?? OTHER_COLOR;
  }, (s) => {
    const i = s * stride;
    ctx.moveTo(sx(segments[i]), sy(segments[i + 1]));
    ctx.lineTo(sx(segments[i + 2]), sy(segments[i + 3]));
  });
  if (opts.scaleBar) scaleBar(ctx, w, h, dpr, scale);
  if (opts.axes) axisLabels(ctx, w, h, dpr, box, opts.axes);
  // The fit both ways, in CSS pixels of the canvas: for overlays and clicks (drawing a field).
  const toData = (x, y) => [ix(x * dpr), iy(y * dpr)];
  const toPx = (x, y) => [sx(x) / dpr, sy(y) / dpr];
  return { items: n, counts, toData, toPx, dpr };
}

/** Names and ranges of a plot-like 2D view whose units are not mm (meta.x_label, y_label). */
function axisLabels(ctx, w, h, dpr, [minX, minY, maxX, maxY], { x, y }) {
  const fmt = (v) => String(Number(v.toPrecision(3)));
  ctx.fillStyle = TEXT;
  ctx.font = `${11 * dpr}px system-ui, sans-serif`;
  ctx.textBaseline = "bottom";
  ctx.textAlign = "left";
  ctx.fillText(`${x}: ${fmt(minX)} … ${fmt(maxX)}`, 8 * dpr, h - 4 * dpr);
  ctx.textBaseline = "top";
  ctx.fillText(`${y}: ${fmt(minY)} … ${fmt(maxY)}`, 8 * dpr, 4 * dpr);
}

/** Orthographic view from the front left, above (the 3D preview's default direction). */
const VIEW = (() => {
  const yaw = (-30 * Math.PI) / 180;
  const pitch = (35 * Math.PI) / 180;
  const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
  // screen x, screen y (up) and depth (towards the viewer) of a model point
  return {
    u: (x, y) => cy * x - sy * y,
    v: (x, y, z) => cp * z + sp * (sy * x + cy * y),
    d: (x, y, z) => -cp * (sy * x + cy * y) + sp * z,
  };
})();

/** 3D segments, stride 7 (x0 y0 z0 x1 y1 z1 code), drawn as an orthographic projection. */
export function drawLines3d(canvas, data, { stride = 7, styles = new Map(), lineWidth = 1 } = {}) {
  const { ctx, w, h, dpr } = setup(canvas);
  const n = data ? Math.floor(data.length / stride) : 0;
  const counts = {};
  if (!n) return { items: 0, counts };
  const u = new Float32Array(n * 2);
  const v = new Float32Array(n * 2);
  const box = [Infinity, Infinity, -Infinity, -Infinity];
  for (let s = 0; s < n; s++) {
    for (let e = 0; e < 2; e++) {
      const i = s * stride + e * 3;
      const a = VIEW.u(data[i], data[i + 1]);
      const b = VIEW.v(data[i], data[i + 1], data[i + 2]);
      u[s * 2 + e] = a;
      v[s * 2 + e] = b;
      if (a < box[0]) box[0] = a;
      if (a > box[2]) box[2] = a;
      if (b < box[1]) box[1] = b;
      if (b > box[3]) box[3] = b;
    }
  }
  const { scale, sx, sy } = fitFrame(w, h, 10 * dpr, box);
  ctx.lineWidth = lineWidth * dpr;
  ctx.lineCap = "round";
  strokeByColor(ctx, n, (s) => {
    const code = stride > 6 ? data[s * stride + 6] : -1;
    counts[code] = (counts[code] ?? 0) + 1;
    return styles.get(code)?.color ?? OTHER_COLOR;
  }, (s) => {
    ctx.moveTo(sx(u[s * 2]), sy(v[s * 2]));
    ctx.lineTo(sx(u[s * 2 + 1]), sy(v[s * 2 + 1]));
  });
  scaleBar(ctx, w, h, dpr, scale);
  return { items: n, counts };
}

/** Triangles, stride 9, flat shaded and painted back to front. */
export function drawMesh(canvas, data, { stride = 9, color = [150, 170, 200] } = {}) {
  const { ctx, w, h, dpr } = setup(canvas);
  const n = data ? Math.floor(data.length / stride) : 0;
  if (!n) return { items: 0, counts: {} };
  const P = new Float32Array(n * 6);
  const depth = new Float32Array(n);
  const shade = new Float32Array(n);
  const box = [Infinity, Infinity, -Infinity, -Infinity];
  const light = [-0.4, -0.6, 0.7];
  const ll = Math.hypot(...light);
  for (let t = 0; t < n; t++) {
    const i = t * stride;
    let dz = 0;
    for (let k = 0; k < 3; k++) {
      const x = data[i + k * 3], y = data[i + k * 3 + 1], z = data[i + k * 3 + 2];
      const a = VIEW.u(x, y);
      const b = VIEW.v(x, y, z);
      P[t * 6 + k * 2] = a;
      P[t * 6 + k * 2 + 1] = b;
      dz += VIEW.d(x, y, z);
      if (a < box[0]) box[0] = a;
      if (a > box[2]) box[2] = a;
      if (b < box[1]) box[1] = b;
      if (b > box[3]) box[3] = b;
    }
    depth[t] = dz;
    const ax = data[i + 3] - data[i], ay = data[i + 4] - data[i + 1], az = data[i + 5] - data[i + 2];
    const bx = data[i + 6] - data[i], by = data[i + 7] - data[i + 1], bz = data[i + 8] - data[i + 2];
    const nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
    const nl = Math.hypot(nx, ny, nz) || 1;
    shade[t] = Math.abs((nx * light[0] + ny * light[1] + nz * light[2]) / (nl * ll));
  }
  const order = Array.from({ length: n }, (_, t) => t).sort((a, b) => depth[a] - depth[b]);
  const { scale, sx, sy } = fitFrame(w, h, 10 * dpr, box);
  for (const t of order) {
    const k = 0.35 + 0.65 * shade[t];
    ctx.fillStyle = `rgb(${Math.round(color[0] * k)},${Math.round(color[1] * k)},${Math.round(color[2] * k)})`;
    ctx.beginPath();
    ctx.moveTo(sx(P[t * 6]), sy(P[t * 6 + 1]));
    ctx.lineTo(sx(P[t * 6 + 2]), sy(P[t * 6 + 3]));
    ctx.lineTo(sx(P[t * 6 + 4]), sy(P[t * 6 + 5]));
    ctx.closePath();
    ctx.fill();
  }
  scaleBar(ctx, w, h, dpr, scale);
  return { items: n, counts: {} };
}

/**
 * A scalar image as a grey ramp, drawn at its true aspect. meta: {width, height, min, max,
 * pixel_mm: number | [x, y] (anisotropic voxels are stretched to their size in mm),
 * window?: [lo, hi] (values mapped to black … white; outside clamped), overlay_legend?:
 * [{code, label, color}]}. `overlay` (stride 5: x0 y0 x1 y1 code, mm from the centre of
 * pixel (0, 0), y down the rows) is drawn on top in the legend's colours.
 * Returns the frame (toData/toPx in the image's mm) for clicks.
 */
export function drawImage(canvas, data, meta = {}, overlay = null, window = null) {
  const { ctx, w, h, dpr } = setup(canvas);
  const iw = meta.width | 0;
  const ih = meta.height | 0;
  if (!data || iw <= 0 || ih <= 0 || data.length < iw * ih) return { items: 0, counts: {} };
  let [lo, hi] = Array.isArray(window) ? window : Array.isArray(meta.window) ? meta.window : [meta.min, meta.max];
  if (!Number.isFinite(lo) || !Number.isFinite(hi)) {
    lo = Infinity;
    hi = -Infinity;
    for (let i = 0; i < iw * ih; i++) {
      if (data[i] < lo) lo = data[i];
      if (data[i] > hi) hi = data[i];
    }
  }
  const k = hi > lo ? 255 / (hi - lo) : 0;
  const img = new ImageData(iw, ih);
  for (let i = 0; i < iw * ih; i++) {
    const g = Math.max(0, Math.min(255, Math.round((data[i] - lo) * k)));
    img.data[i * 4] = img.data[i * 4 + 1] = img.data[i * 4 + 2] = g;
    img.data[i * 4 + 3] = 255;
  }
  const off = document.createElement("canvas");
  off.width = iw;
  off.height = ih;
  off.getContext("2d").putImageData(img, 0, 0);
  const [px, py] = Array.isArray(meta.pixel_mm) ? meta.pixel_mm : [meta.pixel_mm, meta.pixel_mm];
  const mmX = px > 0 ? px : 1;
  const mmY = py > 0 ? py : mmX;
  const margin = 8 * dpr;
  // Screen pixels per mm, the image spanning iw·mmX × ih·mmY mm.
  const scale = Math.min((w - 2 * margin) / (iw * mmX), (h - 2 * margin) / (ih * mmY));
  const x0 = (w - iw * mmX * scale) / 2;
  const y0 = (h - ih * mmY * scale) / 2;
  ctx.imageSmoothingEnabled = false;
  ctx.drawImage(off, x0, y0, iw * mmX * scale, ih * mmY * scale);
  // Overlay coordinates are from the centre of pixel (0, 0).
  const toPx = (x, y) => [(x0 + (x + mmX / 2) * scale) / dpr, (y0 + (y + mmY / 2) * scale) / dpr];
  const toData = (cx, cy) => [(cx * dpr - x0) / scale - mmX / 2, (cy * dpr - y0) / scale - mmY / 2];
  const counts = {};
  if (overlay?.length >= 5) {
    const colors = new Map((meta.overlay_legend ?? []).map((e) => [Number(e.code), e.color ?? OTHER_COLOR]));
    ctx.lineWidth = 1.5 * dpr;
    strokeByColor(ctx, Math.floor(overlay.length / 5), (i) => colors.get(overlay[i * 5 + 4]) ?? OTHER_COLOR, (i) => {
      const o = i * 5;
      ctx.moveTo(x0 + (overlay[o] + mmX / 2) * scale, y0 + (overlay[o + 1] + mmY / 2) * scale);
      ctx.lineTo(x0 + (overlay[o + 2] + mmX / 2) * scale, y0 + (overlay[o + 3] + mmY / 2) * scale);
    });
    for (let i = 4; i < overlay.length; i += 5) counts[overlay[i]] = (counts[overlay[i]] ?? 0) + 1;
  }
  if (px > 0) scaleBar(ctx, w, h, dpr, scale);
  return { items: iw * ih, counts, range: [lo, hi], toPx, toData, dpr };
}

/**
 * Draws an inspect answer by its shape.
 * @param {HTMLCanvasElement} canvas
 * @param {{shape: string, stride: number, data: Float32Array, meta: Object}|null} answer
 * @param {Map<number, {label: string, color: string}>} styles
 * @returns {{items: number, counts: Object<number, number>, range?: number[]}}
 */
export function drawView(canvas, answer, styles) {
  if (!answer) return drawSegments2d(canvas, null);
  switch (answer.shape) {
    case "lines2d": {
      // A view in other units than mm names its axes instead of a scale bar.
      const m = answer.meta ?? {};
      const axes = m.x_label && m.y_label ? { x: m.x_label, y: m.y_label } : null;
      return drawSegments2d(canvas, answer.data, { stride: answer.stride || 5, styles, scaleBar: m.scale_bar !== false && !axes, axes });
    }
    case "lines3d": return drawLines3d(canvas, answer.data, { stride: answer.stride || 7, styles });
    case "mesh": return drawMesh(canvas, answer.data, { stride: answer.stride || 9 });
    case "image": return drawImage(canvas, answer.data, answer.meta ?? {}, answer.overlay ?? null, answer.window ?? null);
    default: {
      const r = drawSegments2d(canvas, null);
      const ctx = canvas.getContext("2d");
      ctx.fillStyle = TEXT;
      ctx.font = "12px system-ui, sans-serif";
      ctx.fillText(`no viewer for shape "${answer.shape}"`, 10, 20);
      return r;
    }
  }
}

/**
 * Fills a view's legend under its canvas from an answer and what drawView drew (`r`): a view
 * may name its own entries (meta.legend: feature code → words, e.g. "seed points" drawn in the
 * lattice colour), an image's overlay names its lines (meta.overlay_legend), otherwise the
 * feature's name; binned values (meta.bins) come lowest first; an image adds its value range.
 */
export function fillLegend(el, answer, r, styles) {
  const named = answer?.meta?.legend ?? {};
  const overlayLegend = new Map((answer?.meta?.overlay_legend ?? []).map((e) => [String(e.code), e]));
  // A view that bins a value into codes (meta.bins: [{code, …}] lowest first) lists them in order.
  const order = new Map((Array.isArray(answer?.meta?.bins) ? answer.meta.bins : []).map((b, i) => [String(b?.code), i]));
  const codes = Object.keys(r.counts ?? {}).sort((a, b) => (order.get(a) ?? order.size) - (order.get(b) ?? order.size));
  const entries = codes.map((code) => overlayLegend.has(code)
    ? [overlayLegend.get(code).color ?? OTHER_COLOR, String(overlayLegend.get(code).label ?? code)]
    : [styles.get(Number(code))?.color ?? OTHER_COLOR,
      typeof named[code] === "string" ? named[code] : styles.get(Number(code))?.label ?? `feature ${code}`]);
  if (r.range) entries.push([null, `${formatNumber(r.range[0], 4)} … ${formatNumber(r.range[1], 4)}${answer?.meta?.unit ? ` ${answer.meta.unit}` : ""}`]);
  el.replaceChildren(...entries.map(([color, text]) => {
    const item = document.createElement("span");
    const mark = document.createElement("span");
    if (color) {
      mark.className = "swatch";
      mark.style.background = color;
    } else {
      mark.className = "ramp grey";
    }
    item.append(mark, " ", text);
    return item;
  }));
}

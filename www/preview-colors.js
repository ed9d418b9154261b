// The preview's colours: by feature (the schema's names and colours), by path (a golden-ratio
// palette) or on a ramp (flow, ΔE/mm, speed) over the whole print's range, one byte per
// channel per segment, and the legend under the canvas saying what they mean. The functions
// take the Preview `p` (preview.js), whose methods of the same names call them.
import * as THREE from "./vendor/three.module.js";
import { STILL_TUBE_LIMIT, TUBE_LIMIT, textureArray } from "./preview-gl.js";

export const UNKNOWN_COLOR = [190, 190, 190];

/** Colour modes drawn on the colour ramp: preview buffer, legend label and unit. */
const RAMP_MODES = {
  flow: { key: "flow", label: "flow", unit: "mm³/s", title: "volumetric flow, mm³/s" },
  e_per_mm: { key: "ePerMm", label: "ΔE/mm", unit: "mm/mm", title: "filament fed per mm of travel (ΔE ÷ length), mm/mm" },
  speed: { key: "speed", label: "speed", unit: "mm/s", title: "feed rate, mm/s (for a VTP foam: V* × the thread's speed)" },
  width: { key: "width", label: "bead width", unit: "mm", title: "bead (line) width, mm (for a graded scaffold: its density)" },
};

/** 256-entry "turbo"-like ramp (blue → green → yellow → red), sRGB bytes. */
const RAMP = buildRamp();

/** @returns {Uint8Array} RGBA per segment (A unused), as long as a colour texture */
export function computeColors(p, mode, segments) {
  const d = p.data;
  const out = textureArray(Uint8Array, segments);
  const put = (i, r, g, b) => {
    out[i * 4] = r;
    out[i * 4 + 1] = g;
    out[i * 4 + 2] = b;
  };
  if (mode === "feature" && d.feature.length >= segments) {
    for (let i = 0; i < segments; i++) {
      const c = p.featureRgb[d.feature[i]] ?? UNKNOWN_COLOR;
      put(i, c[0], c[1], c[2]);
    }
  } else if (RAMP_MODES[mode] && d[RAMP_MODES[mode].key]?.length >= segments) {
    const values = d[RAMP_MODES[mode].key];
    const [lo, hi] = p.getRange(mode);
    const scale = hi > lo ? 255 / (hi - lo) : 0;
    for (let i = 0; i < segments; i++) {
      const k = Math.max(0, Math.min(255, Math.round((values[i] - lo) * scale))) * 3;
      put(i, RAMP[k], RAMP[k + 1], RAMP[k + 2]);
    }
  } else if (mode === "path" && d.path.length >= segments) {
    const palette = PATH_PALETTE;
    const n = palette.length / 3;
    for (let i = 0; i < segments; i++) {
      // Consecutive paths are a golden-ratio hue step (≈ 137.5°) apart.
      const k = (d.path[i] % n) * 3;
      put(i, palette[k], palette[k + 1], palette[k + 2]);
    }
  } else {
    out.fill(200);
  }
  return out;
}

/** [lo, hi] of a ramp mode's values over the whole print. */
export function getRange(p, mode) {
  if (mode === "flow") return p.getFlowRange();
  if (p.ranges.has(mode)) return p.ranges.get(mode);
  const values = p.data[RAMP_MODES[mode].key] ?? [];
  let lo = Infinity;
  let hi = -Infinity;
  for (let i = 0; i < values.length; i++) {
    const f = values[i];
    if (f < lo) lo = f;
    if (f > hi) hi = f;
  }
  if (!(lo <= hi)) lo = hi = 0;
  p.ranges.set(mode, [lo, hi]);
  return [lo, hi];
}

export function getFlowRange(p) {
  if (p.flowRange) return p.flowRange;
  const flow = p.data.flow;
  let lo = Infinity;
  let hi = -Infinity;
  for (let i = 0; i < flow.length; i++) {
    const f = flow[i];
    if (f < lo) lo = f;
    if (f > hi) hi = f;
  }
  if (!(lo <= hi)) lo = hi = 0;
  p.flowRange = [lo, hi];
  return p.flowRange;
}

export function getFeatureCounts(p) {
  if (p.featureCounts) return p.featureCounts;
  const counts = new Uint32Array(256);
  const f = p.data.feature;
  for (let i = 0; i < f.length; i++) counts[f[i]]++;
  p.featureCounts = counts;
  return counts;
}

export function updateLegend(p, mode, segments) {
  const legend = p.ui.legend;
  legend.replaceChildren();
  if (segments === 0) {
    legend.append(item(null, "no toolpath yet: slice a design or drop a file"));
    return;
  }
  if (mode === "feature") {
    const counts = p.getFeatureCounts();
    for (const code of p.featureOrder) {
      if (counts[code] > 0) legend.append(item(p.featureRgb[code], p.featureLabel[code]));
    }
    let unknown = 0;
    for (let code = 0; code < 256; code++) if (!p.featureRgb[code]) unknown += counts[code];
    if (unknown > 0) legend.append(item(UNKNOWN_COLOR, "unknown"));
  } else if (RAMP_MODES[mode]) {
    const { label, unit, title } = RAMP_MODES[mode];
    const [lo, hi] = p.getRange(mode);
    const bar = document.createElement("span");
    bar.className = "ramp";
    const stops = [];
    for (let k = 0; k <= 8; k++) {
      const j = Math.round((k / 8) * 255) * 3;
      stops.push(`rgb(${RAMP[j]},${RAMP[j + 1]},${RAMP[j + 2]})`);
    }
    bar.style.background = `linear-gradient(to right, ${stops.join(",")})`;
    const text = (v) => `${v.toFixed(v < 1 ? 3 : v < 10 ? 2 : 1)}`;
    const low = document.createElement("span");
    low.textContent = text(lo);
    const high = document.createElement("span");
    high.textContent = `${text(hi)} ${unit}`;
    const wrap = document.createElement("span");
    wrap.className = "legend-item flow-legend";
    wrap.title = title;
    wrap.append(`${label} `, low, bar, high);
    legend.append(wrap);
  } else {
    const paths = p.data.path.length ? p.data.path[p.data.path.length - 1] + 1 : 0;
    legend.append(item(null, `one colour per extrusion path (${paths.toLocaleString()} paths)`));
  }
  if (p.starts.visible) legend.append(item([255, 255, 255], "path start", true));
  const asLines = p.restStyle() === "lines" && segments > 0;
  const count = item(null, `${segments.toLocaleString()} segments${asLines ? " · lines" : ""}`);
  if (asLines) {
    count.title = p.style === "auto"
      ? `Drawn as lines: over ${STILL_TUBE_LIMIT.toLocaleString()} segments, tubes are too slow without a fast GPU`
      : "Drawn as lines";
  } else if (p.style === "auto" && segments > TUBE_LIMIT) {
    count.title = `Drawn as lines while the view moves (over ${TUBE_LIMIT.toLocaleString()} segments)`;
  }
  legend.append(count);
}

function item(rgb, text, round = false) {
  const el = document.createElement("span");
  el.className = "legend-item";
  if (rgb) {
    const sw = document.createElement("span");
    sw.className = round ? "swatch round" : "swatch";
    sw.style.background = `rgb(${rgb[0]},${rgb[1]},${rgb[2]})`;
    el.append(sw);
  }
  el.append(text);
  return el;
}

function buildRamp() {
  // Piecewise-linear through a few "turbo" colour-map stops.
  const stops = [
    [0.0, 48, 18, 59], [0.15, 70, 107, 227], [0.3, 41, 187, 236], [0.45, 49, 241, 153],
    [0.6, 163, 253, 61], [0.75, 237, 208, 58], [0.88, 251, 128, 34], [1.0, 180, 20, 10],
  ];
  const out = new Uint8Array(256 * 3);
  for (let i = 0; i < 256; i++) {
    const t = i / 255;
    let s = 0;
    while (s < stops.length - 2 && t > stops[s + 1][0]) s++;
    const [t0, r0, g0, b0] = stops[s];
    const [t1, r1, g1, b1] = stops[s + 1];
    const u = (t - t0) / (t1 - t0);
    out[i * 3] = Math.round(r0 + (r1 - r0) * u);
    out[i * 3 + 1] = Math.round(g0 + (g1 - g0) * u);
    out[i * 3 + 2] = Math.round(b0 + (b1 - b0) * u);
  }
  return out;
}

/**
 * 256 colours for colouring by path, entry i at hue i × golden ratio: consecutive paths are
 * ≈ 137.5° apart on the colour wheel, and lightness cycles over three levels.
 */
const PATH_PALETTE = (() => {
  const n = 256;
  const out = new Uint8Array(n * 3);
  const c = new THREE.Color();
  for (let i = 0; i < n; i++) {
    c.setHSL((i * 0.618034) % 1, 0.8, [0.55, 0.68, 0.45][i % 3]);
    out[i * 3] = Math.round(c.r * 255);
    out[i * 3 + 1] = Math.round(c.g * 255);
    out[i * 3 + 2] = Math.round(c.b * 255);
  }
  return out;
})();

/** "#rrggbb" → [r, g, b], or null. */
export function hexRgb(hex) {
  const m = /^#?([0-9a-f]{6})$/i.exec(String(hex ?? "").trim());
  if (!m) return null;
  const v = parseInt(m[1], 16);
  return [(v >> 16) & 255, (v >> 8) & 255, v & 255];
}

// A JavaScript stand-in for pkg/weft.js with the wasm API v2 contract (designSchema object,
// Session.addFile(slot, …) / addBlob, run → RunReport with stage plots, inspect, previewAxis,
// previewSegmentMove …). Lets the page be tested without the Rust build:
//
//   WEFT_PKG_DIR=tests/e2e/mock-pkg node tests/e2e/ui-mock.mjs
//
// The numbers are invented; only the shapes of the values follow the contract.
// Served as /pkg/weft.js by tests/e2e/server.mjs, so ../www/ is the page's directory.
import { PREVIEW_BUFFERS } from "../www/protocol.js";

export default async function init() {
  return {};
}

const FEATURES = [
  ["external_perimeter", "External perimeter", "#ff7d38"], ["perimeter", "Perimeter", "#ffe64d"],
  ["internal_infill", "Internal infill", "#b03029"], ["solid_infill", "Solid infill", "#9654cc"],
  ["lattice", "Lattice", "#29a3d6"], ["contour", "Contour", "#1fb04c"], ["handle", "Handle", "#a0a0a0"],
];
const PATTERNS = ["honeycomb", "voronoi", "penrose", "snub_square", "arrowhead", "reentrant", "rectilinear", "square_grid", "triangle_grid"];
const SLOTS = {
  slice: [{ name: "mesh", label: "Part", kind: "mesh", accept: [".stl", ".obj", ".3mf"], multiple: false, required: false, path: "job.input", doc: "The solid to slice" }],
  lattice: [
    { name: "mesh", label: "Solid domain", kind: "mesh", accept: [".stl", ".obj", ".3mf"], multiple: false, required: false, path: "job.input", doc: "Layers of this solid" },
    { name: "surface", label: "Surface", kind: "mesh", accept: [".stl", ".obj"], multiple: false, required: false, path: "job.surface_input", doc: "Non-planar surface" },
  ],
};
const STAGES = {
  slice: [["import", "Reading the mesh"], ["slice", "Slicing layers"], ["gcode", "Writing G-code"], ["analyze", "Measuring the G-code"]],
  lattice: [["lattice", "Generating the lattice"], ["paths", "Optimising print paths"], ["gcode", "Writing G-code"], ["analyze", "Measuring the G-code"]],
};

export function designSchema() {
  const f = (path, section, label, kind, extra = {}) => ({ path, section, label, unit: "", kind, doc: "", ...extra });
  return {
    version: 1,
    fields: [
      f("name", "Design", "Name", "text"),
      f("job.kind", "Design", "Job", "choice", { choices: ["slice", "lattice"] }),
      f("seed", "Design", "Random seed", "integer", { min: 0, max: 1e9, step: 1 }),
      f("printer.flavor", "Printer", "G-code flavour", "choice", { choices: ["marlin", "pneumatic"] }),
      f("printer.pneumatic.pressure_kpa", "Printer", "Pressure", "number", { unit: "kPa", when: { path: "flavor", equals: "pneumatic" }, when_path: "printer.flavor" }),
      f("material.nozzle_temp_c", "Material", "Nozzle temperature", "number", { unit: "°C", min: 0, max: 500, step: 1 }),
      f("job.input.builtin.size", "Input", "Size", "vec3", { unit: "mm", min: 1, max: 500, step: 1 }),
      f("job.slice.layer_height_mm", "Slicing", "Layer height", "number", { unit: "mm", min: 0.01, max: 2, step: 0.01, job: "slice" }),
      f("job.slice.perimeters", "Slicing", "Perimeters", "integer", { min: 0, max: 50, step: 1, job: "slice" }),
      f("job.lattice.pattern.kind", "Lattice", "Pattern", "choice", { choices: PATTERNS, widget: "pattern_picker", job: "lattice" }),
      f("job.lattice.layers", "Lattice", "Layers", "integer", { min: 1, max: 1000, step: 1, job: "lattice" }),
      f("job.paths.method", "Paths", "Optimiser", "choice", { choices: ["gippo_max", "gippo_min", "euler", "continuous"], job: "lattice" }),
      f("job.paths.iterations", "Paths", "Iterations", "integer", { min: 1, max: 10000, step: 1, job: "lattice" }),
    ],
    features: FEATURES.map(([key, name, color], code) => ({ code, key, name, label: name, color })),
    job_kinds: Object.keys(STAGES).map((name) => ({
      name, label: name === "slice" ? "Slice a mesh" : "Lattice (GIPPO)", doc: "",
      stages: STAGES[name].map(([n, label]) => ({ name: n, label })),
      slots: SLOTS[name],
      views: name === "lattice" ? [{ id: "layer2d", stage: "lattice", label: "Layer (2D)", shape: "lines2d", index_label: "Layer", doc: "" }] : [],
    })),
    builtin_shapes: [
      { kind: "cube", label: "cube", value: { builtin: { shape: "cube", size: [20, 20, 20] } } },
      { kind: "sphere", label: "sphere", value: { builtin: { shape: "sphere", radius: 10, segments: 64 } } },
    ],
    patterns: PATTERNS.map((kind) => ({ kind, label: kind.replace(/_/g, " "), value: { kind, cell_mm: 1 } })),
  };
}

function defaults(kind) {
  const base = { version: 1, name: "cube-20mm", seed: 1, printer: { flavor: "marlin" }, material: { nozzle_temp_c: 210 } };
  if (kind === "lattice") {
    return { ...base, name: "lattice", job: { kind, domain: { kind: "rectangle", width_mm: 10, height_mm: 10 },
      lattice: { pattern: { kind: "honeycomb", cell_mm: 1 }, layers: 3 }, paths: { method: "gippo_max", iterations: 50 } } };
  }
  return { ...base, job: { kind: "slice", input: { builtin: { shape: "cube", size: [20, 20, 20] } }, slice: { layer_height_mm: 0.2, perimeters: 2 } } };
}

export function defaultDesign() {
  return JSON.stringify(defaults("slice"), null, 2);
}

export function validateDesign(json) {
  const d = JSON.parse(json);
  if (d.version !== 1) throw new Error("design: version must be 1");
  return JSON.stringify(d, null, 2);
}

export function setField(json, path, valueJson) {
  const d = JSON.parse(json);
  let v;
  try { v = JSON.parse(valueJson); } catch { v = valueJson; }
  if (path === "job.kind") {
    if (v !== d.job.kind) d.job = defaults(v).job;
    return JSON.stringify(d, null, 2);
  }
  if (path.endsWith("nozzle_temp_c") && (v < 0 || v > 500)) throw new Error(`${path}: must be 0 … 500`);
  const keys = path.split(".");
  let o = d;
  for (const k of keys.slice(0, -1)) o = o[k] ??= {};
  if (v === null) delete o[keys.at(-1)];
  else o[keys.at(-1)] = v;
  return JSON.stringify(d, null, 2);
}

/** Points a slot's design field at the files (the real one also applies the kind's rule). */
export function fillSlot(json, slot, names) {
  const d = JSON.parse(json);
  const s = SLOTS[d.job.kind]?.find((x) => x.name === slot);
  if (!s) throw new Error(`job ${d.job.kind} has no input slot ${slot}`);
  return setField(json, s.path, JSON.stringify(s.multiple ? { files: names } : { file: { name: names.at(-1) } }));
}

export function encodeShare(json, files) {
  const d = JSON.parse(json);
  const embedded = [];
  const missing = [];
  for (const f of files ?? []) {
    if (!json.includes(`"${f.name}"`)) continue;
    (f.bytes.length < 2000 ? embedded : missing).push(f.name);
  }
  return { fragment: `#d=${btoa(JSON.stringify(d))}`, embedded, missing, note: "" };
}

export function decodeShare(fragment) {
  const s = fragment.replace(/^.*#d=/, "");
  try {
    return JSON.stringify(JSON.parse(atob(s)), null, 2);
  } catch {
    throw new Error("this link is damaged: it was cut short or changed while copying; ask for the link again");
  }
}

export function patternThumbnail(patternJson, size, seed) {
  const { kind } = JSON.parse(patternJson);
  const k = PATTERNS.indexOf(kind) + 2;
  const out = [];
  for (let i = 0; i <= k; i++) {
    const t = -size / 2 + (i * size) / k;
    out.push(t, -size / 2, t + (kind.length % 3) - 1, size / 2, -size / 2, t, size / 2, t);
  }
  return new Float32Array(out);
}

export class Session {
  constructor() {
    this.files = new Map();
    this.last = null;
    this.out = null;
  }

  addFile(slot, name, bytes) {
    if (/corrupt/.test(name)) throw new Error(`${name}: line 4: a vertex needs 3 numbers`);
    this.files.set(name, bytes);
    return { slot, name, kind: "mesh", summary: `${Math.floor(bytes.length / 50)} triangles, 20 × 20 × 20 mm`, report: { triangles: 12 } };
  }

  /** As the real Session: a dropped File (Blob); the mock reads it whole. */
  addBlob(slot, name, blob) {
    return this.addFile(slot, name, new Uint8Array(new FileReaderSync().readAsArrayBuffer(blob)));
  }

  removeFile(name) {
    this.files.delete(name);
  }

  /** A plan like budget::Plan: designs named `big-*` ask first, `huge-*` are refused. */
  estimate(designJson) {
    const d = JSON.parse(designJson);
    const big = /^big/.test(d.name), huge = /^huge/.test(d.name);
    const plan = { stages: [], seconds: big ? 40 : 0.1, peak_bytes: 1e6, segments: 1e4, gcode_bytes: 3e5 };
    if (big) plan.ask = "a big job: about 40 s";
    if (huge) {
      plan.refused = ["lattice", { what: "struts on one layer", value: 1.85e7, limit: 2e6, unit: "", fix: "use cells ≥ 0.6 mm" }];
      plan.refusal = "lattice: struts on one layer would be about 18.5M, limit 2M: use cells ≥ 0.6 mm";
    }
    return plan;
  }

  run(designJson, onProgress) {
    const d = JSON.parse(designJson);
    const kind = d.job.kind;
    const key = JSON.stringify({ ...d, material: null });
    const cached = this.last === key;
    this.last = key;
    for (const [s] of STAGES[kind]) {
      onProgress(s, 0);
      const t = performance.now();
      while (performance.now() - t < (d.name === "long-sphere" ? 2000 : 5)) { /* work */ }
      onProgress(s, 1);
    }
    const layers = kind === "lattice" ? d.job.lattice.layers : 10;
    this.out = preview(layers, kind === "lattice");
    const iterations = d.job.paths?.iterations ?? 0;
    const stages = STAGES[kind].map(([stage, label]) => ({
      stage, label, cached: cached && stage !== "gcode" && stage !== "analyze",
      metrics: [{ key: "layers", label: "Layers", value: layers, unit: "", hint: "layers made" }], plots: [], tables: [], data: {},
    }));
    if (kind === "lattice") {
      const paths = stages.find((s) => s.stage === "paths");
      const series = [];
      const bars = [];
      const rows = [];
      for (let l = 0; l < layers; l++) {
        const y = Array.from({ length: iterations }, (_, i) => 0.5 + 0.3 * Math.sin(i * 1.7 + l) * Math.cos(i * 0.37));
        let best = -Infinity;
        series.push({ name: "score", group_index: l, x: y.map((_, i) => i + 1), y });
        series.push({ name: "best so far", group_index: l, x: y.map((_, i) => i + 1), y: y.map((v) => (best = Math.max(best, v))) });
        series.push({ name: "lower bound", kind: "hline", group_index: l, x: [], y: [0.3] });
        bars.push({ name: "paths", group_index: l, x: ["long", "medium", "short"], y: [4 + l, 7, 2] });
        rows.push({ group_index: l, cells: [l + 1, 13 + l, 12, 0.81] });
      }
      paths.plots.push({ key: "score", title: "GIPPO score per iteration", kind: "line", group: "Layer", x: { label: "iteration", unit: "" }, y: { label: "score", unit: "eq. 1" }, series });
      paths.plots.push({ key: "classes", title: "Path classes", kind: "bars", group: "Layer", x: { label: "class", unit: "" }, y: { label: "paths", unit: "" }, series: bars });
      paths.tables.push({ key: "per_layer", title: "Paths per layer", group: "Layer", columns: [{ label: "Layer" }, { label: "Paths" }, { label: "Lower bound" }, { label: "Score", unit: "" }], rows });
    }
    const temp = d.material.nozzle_temp_c;
    this.gcodeText = `; weft mock\nM104 S${temp}\nM109 S${temp}\n${"G1 X1 Y1 E0.1\n".repeat(layers * 8)}`;
    return {
      name: d.name, job: kind, stages,
      gcode: { layers, extruded_mm: 100, filament_mm: 5, travel_mm: 20, retractions: 4, estimated_time_s: 600 },
      analysis: { layers, extrusion_paths: layers * 2, extruded_mm: 100, travel_mm: 20, retractions: 4, overlap_mm: 0, gippo_score: 0.8, estimated_time_s: 600, filament_mm: 5, per_layer: [] },
    };
  }

  inspect(designJson, view, index) {
    const d = JSON.parse(designJson);
    const count = d.job.lattice?.layers ?? 1;
    const i = Math.min(index, count - 1);
    const out = [];
    for (let k = 0; k <= 10; k++) out.push(k, 0, k, 10, 4, 0, k, 10, k + (i % 2), 4);
    out.push(0, 0, 10, 0, 5, 10, 0, 10, 10, 5);
    return { view, shape: "lines2d", index: i, count, stride: 5, data: new Float32Array(out), meta: {} };
  }

  analyzeGcode(name, bytes) {
    this.out = preview(3, false);
    this.gcodeText = new TextDecoder().decode(bytes);
    return { analysis: { layers: 3, extrusion_paths: 3, extruded_mm: 10, travel_mm: 1, retractions: 0, overlap_mm: 0, gippo_score: 0.5, estimated_time_s: 60, filament_mm: 1, per_layer: [] } };
  }

  gcode() { return new TextEncoder().encode(this.gcodeText ?? ""); }
}

// The preview getters (previewPositions, …, bedSize) of protocol.js's table: the buffer of
// the last result under the same key, empty before one.
for (const [key, [method, Type]] of Object.entries(PREVIEW_BUFFERS)) {
  Session.prototype[method] = function () { return this.out?.[key] ?? new Type(0); };
}

/** A stack of squares (4 segments per layer, one path each) and a travel between layers. */
function preview(layers, withAxis) {
  const pos = [], feature = [], path = [], flow = [], width = [], layerStart = [], travel = [], travelLayerStart = [], layerZ = [], axis = [], seg = [], tmove = [];
  let move = 0;
  for (let l = 0; l < layers; l++) {
    const z = 0.2 * (l + 1);
    layerStart.push(pos.length / 6);
    travelLayerStart.push(travel.length / 6);
    layerZ.push(z);
    travel.push(100, 100, z, 100, 100, z);
    tmove.push(move++);
    const c = [[100, 100], [120, 100], [120, 120], [100, 120], [100, 100]];
    for (let k = 0; k < 4; k++) {
      pos.push(c[k][0], c[k][1], z, c[k + 1][0], c[k + 1][1], z);
      feature.push(l % 2 ? 0 : 4);
      path.push(l);
      flow.push(1 + k);
      width.push(0.4);
      axis.push(0, 0, 1);
      seg.push(move++);
    }
  }
  layerStart.push(pos.length / 6);
  travelLayerStart.push(travel.length / 6);
  return {
    bedSize: new Float64Array([220, 220, 250]),
    positions: new Float32Array(pos), feature: new Uint8Array(feature), path: new Uint32Array(path), flow: new Float32Array(flow),
    width: new Float32Array(width), layerStart: new Uint32Array(layerStart), travel: new Float32Array(travel),
    travelLayerStart: new Uint32Array(travelLayerStart), layerZ: new Float32Array(layerZ),
    axis: withAxis ? new Float32Array(axis) : new Float32Array(0), segmentMove: new Uint32Array(seg), travelMove: new Uint32Array(tmove),
  };
}

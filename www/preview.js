// 3D toolpath preview: three.js LineSegments over the preview buffers of a result.
//
// Built for millions of segments: the transferred Float32Array is the position attribute
// as is; colours are Uint8 normalized attributes computed once per colour mode and cached;
// the layer range and the print-order limit are one drawRange (a few array lookups per
// change); nothing is allocated per frame and a frame is drawn only when something changed
// (no animation loop). Feature names and colours come from the schema (setFeatures).
import * as THREE from "./vendor/three.module.js";
import { OrbitControls } from "./vendor/OrbitControls.js";

// Colours are given in sRGB and drawn as they are: no colour management.
THREE.ColorManagement.enabled = false;

const BACKGROUND = 0x1f232a;
const DEFAULT_BED = [200, 200, 200];
const UNKNOWN_COLOR = [190, 190, 190];
const TRAVEL_COLOR = 0x5aa0ff;
const START_COLOR = 0xffffff;
const AXIS_COLOR = 0xf2f2f2;
/** Size of a path-start marker, CSS pixels. */
const START_SIZE_PX = 7;

/** 256-entry "turbo"-like ramp (blue → green → yellow → red), sRGB bytes. */
const RAMP = buildRamp();

export class Preview {
  /**
   * @param {HTMLCanvasElement} canvas
   * @param {{colorBy: HTMLSelectElement, showTravel: HTMLInputElement,
   *          showStarts?: HTMLInputElement, layerMin: HTMLInputElement, layerMax: HTMLInputElement,
   *          layerLabel: HTMLElement, legend: HTMLElement, moveMax?: HTMLInputElement,
   *          moveLabel?: HTMLElement, showAxis?: HTMLInputElement}} ui
   * @param {{features?: Array<{code: number, label?: string, name?: string, color: string}>}} [options]
   */
  constructor(canvas, ui, options = {}) {
    this.canvas = canvas;
    this.ui = ui;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    this.renderer.setClearColor(BACKGROUND, 1);

    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.1, 10000);
    this.camera.up.set(0, 0, 1);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.enableDamping = false; // damping needs a continuous loop
    this.controls.screenSpacePanning = true;
    this.controls.listenToKeyEvents(canvas); // arrow keys pan when the canvas has focus
    this.controls.addEventListener("change", () => this.requestRender());

    this.plate = new THREE.Group();
    this.scene.add(this.plate);

    this.extrusion = new THREE.LineSegments(
      new THREE.BufferGeometry(),
      new THREE.LineBasicMaterial({ vertexColors: true }),
    );
    this.extrusion.frustumCulled = false;
    this.travel = new THREE.LineSegments(
      new THREE.BufferGeometry(),
      new THREE.LineBasicMaterial({ color: TRAVEL_COLOR, transparent: true, opacity: 0.35 }),
    );
    this.travel.frustumCulled = false;
    this.travel.visible = ui.showTravel.checked;
    // Path starts: a round marker at the first vertex of every extrusion path.
    this.starts = new THREE.Points(
      new THREE.BufferGeometry(),
      new THREE.PointsMaterial({
        color: START_COLOR, size: START_SIZE_PX * this.renderer.getPixelRatio(), sizeAttenuation: false,
        map: dotTexture(), alphaTest: 0.5, transparent: true, depthTest: false,
      }),
    );
    this.starts.frustumCulled = false;
    this.starts.renderOrder = 2;
    this.starts.visible = Boolean(ui.showStarts?.checked);
    // Tool axis: a short line along the axis at the end of every extrusion segment.
    this.axis = new THREE.LineSegments(
      new THREE.BufferGeometry(),
      new THREE.LineBasicMaterial({ color: AXIS_COLOR, transparent: true, opacity: 0.55 }),
    );
    this.axis.frustumCulled = false;
    this.axis.visible = Boolean(ui.showAxis?.checked);
    this.scene.add(this.extrusion, this.travel, this.starts, this.axis);
    /** segment index of every path-start marker (increasing) */
    this.startSegment = new Uint32Array(0);
    /** layers shown, and the last G-code move shown (Infinity: all) */
    this.range = { lo: 0, hi: -1, move: Infinity };
    /** segments drawn now (for tests and the legend) */
    this.drawn = { extrusion: 0, travel: 0 };
    /** feature code → sRGB bytes and label (setFeatures) */
    this.featureRgb = new Array(256).fill(null);
    this.featureLabel = new Array(256).fill(null);
    this.featureOrder = [];

    /** @type {import("./protocol.js").PreviewBuffers|null} */
    this.data = null;
    /** @type {Map<string, THREE.BufferAttribute>} colour attribute per mode, built on demand */
    this.colorCache = new Map();
    this.setFeatures(options.features ?? []);
    this.layers = 0;
    this.bedKey = "";
    this.frameRequested = false;
    this.drawFrame = () => {
      this.frameRequested = false;
      this.renderer.render(this.scene, this.camera);
    };

    ui.colorBy.addEventListener("change", () => this.applyColors());
    ui.showStarts?.addEventListener("change", () => {
      this.starts.visible = ui.showStarts.checked;
      this.updateLegend(ui.colorBy.value, this.data ? this.data.positions.length / 6 : 0);
      this.requestRender();
    });
    ui.showAxis?.addEventListener("change", () => {
      this.axis.visible = ui.showAxis.checked;
      this.requestRender();
    });
    ui.moveMax?.addEventListener("input", () => {
      const v = ui.moveMax.valueAsNumber;
      this.setMoveLimit(v >= Number(ui.moveMax.max) ? Infinity : v);
    });
    ui.showTravel.addEventListener("change", () => {
      this.travel.visible = ui.showTravel.checked;
      this.requestRender();
    });
    const onRange = (moved) => () => {
      let lo = ui.layerMin.valueAsNumber;
      let hi = ui.layerMax.valueAsNumber;
      if (lo > hi) {
        if (moved === "min") ui.layerMax.value = String((hi = lo));
        else ui.layerMin.value = String((lo = hi));
      }
      this.setLayerRange(lo, hi);
    };
    ui.layerMin.addEventListener("input", onRange("min"));
    ui.layerMax.addEventListener("input", onRange("max"));

    new ResizeObserver(() => this.resize()).observe(canvas.parentElement);
    this.setBed(DEFAULT_BED, "corner");
    this.fit();
    this.setResult(null);
  }

  /** Draws one frame at the next animation frame (coalesced). */
  requestRender() {
    if (this.frameRequested) return;
    this.frameRequested = true;
    requestAnimationFrame(this.drawFrame);
  }

  resize() {
    const { clientWidth: w, clientHeight: h } = this.canvas.parentElement;
    if (w === 0 || h === 0) return;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  /**
   * Shows a result's preview buffers (kept by reference, never copied).
   * @param {import("./protocol.js").PreviewBuffers|null} data
   * @param {{origin?: string}} [options]  printer origin: "corner" (default) or "center"
   */
  setResult(data, options = {}) {
    const geometry = this.extrusion.geometry;
    const travelGeometry = this.travel.geometry;
    geometry.dispose();
    travelGeometry.dispose();
    this.starts.geometry.dispose();
    this.axis.geometry.dispose();
    this.colorCache.clear(); // their GPU buffers go with the disposed geometry / GC
    this.data = data;
    this.featureCounts = null;
    this.flowRange = null;

    const segments = data ? data.positions.length / 6 : 0;
    const empty = new Float32Array(0);
    this.extrusion.geometry = new THREE.BufferGeometry();
    this.extrusion.geometry.setAttribute("position", new THREE.BufferAttribute(data?.positions ?? empty, 3));
    this.travel.geometry = new THREE.BufferGeometry();
    this.travel.geometry.setAttribute("position", new THREE.BufferAttribute(data?.travel ?? empty, 3));

    const layerStart = data?.layerStart ?? new Uint32Array(0);
    this.layers = Math.max(0, layerStart.length - 1);
    if (segments > 0 && this.layers === 0) {
      // No layer table: treat everything as one layer.
      data.layerStart = Uint32Array.of(0, segments);
      this.layers = 1;
    }
    const { layerMin, layerMax } = this.ui;
    for (const input of [layerMin, layerMax]) {
      input.min = "0";
      input.max = String(Math.max(0, this.layers - 1));
      input.disabled = this.layers === 0;
      input.style.visibility = this.layers > 1 ? "" : "hidden";
    }
    layerMin.value = "0";
    layerMax.value = String(Math.max(0, this.layers - 1));
    const bounds = segments > 0 ? boundsOf(data.positions) : null;
    this.buildStarts();
    this.buildAxis(segments, bounds);
    this.setupMoves(segments);

    const bed = data?.bedSize && data.bedSize.length >= 2 && data.bedSize[0] > 0 ? data.bedSize : DEFAULT_BED;
    this.setBed(bed, options.origin ?? "corner");
    this.applyColors(false);
    this.setLayerRange(0, this.layers - 1);
    this.fit(bounds);
    this.requestRender();
  }

  /** Shows layers lo..hi (0-based, inclusive): O(log n). */
  setLayerRange(lo, hi) {
    this.range.lo = lo;
    this.range.hi = hi;
    this.applyRange();
  }

  /** Shows only what the G-code does up to move `move` (Infinity: everything). */
  setMoveLimit(move) {
    this.range.move = move;
    const ui = this.ui;
    if (ui.moveMax && move === Infinity) ui.moveMax.value = ui.moveMax.max;
    else if (ui.moveMax) ui.moveMax.value = String(move);
    this.applyRange();
  }

  /** Draw ranges of extrusion, travel, starts and axis from the layer range and move limit. */
  applyRange() {
    const d = this.data;
    const label = this.ui.layerLabel;
    const { lo, hi, move } = this.range;
    if (!d || this.layers === 0) {
      for (const o of [this.extrusion, this.travel, this.starts, this.axis]) o.geometry.setDrawRange(0, 0);
      this.drawn = { extrusion: 0, travel: 0 };
      label.textContent = "no layers";
      this.updateMoveLabel();
      this.requestRender();
      return;
    }
    const segments = d.positions.length / 6;
    const start = d.layerStart[lo];
    let end = d.layerStart[hi + 1];
    const limited = move !== Infinity;
    if (limited && this.bySegment) end = Math.max(start, Math.min(end, move + 1));
    else if (limited) end = Math.max(start, Math.min(end, upperBound(d.segmentMove, move)));
    this.extrusion.geometry.setDrawRange(start * 2, (end - start) * 2);
    if (this.axisSegments) this.axis.geometry.setDrawRange(start * 2, (end - start) * 2);
    const s0 = lowerBound(this.startSegment, start);
    const s1 = lowerBound(this.startSegment, end);
    this.starts.geometry.setDrawRange(s0, s1 - s0);
    const ts = d.travelLayerStart;
    const travels = d.travel.length / 6;
    let t0 = 0;
    let t1 = travels;
    if (ts && ts.length > hi + 1) {
      t0 = ts[lo];
      t1 = ts[hi + 1];
    }
    if (limited && !this.bySegment && d.travelMove?.length === travels) {
      t1 = Math.max(t0, Math.min(t1, upperBound(d.travelMove, move)));
    } else if (limited && this.bySegment && ts && ts.length > hi + 1) {
      // No move indices: the travels of the layers up to the one being printed.
      const layer = Math.max(0, upperBound(d.layerStart, move) - 1);
      t1 = Math.max(t0, Math.min(t1, ts[Math.min(layer + 1, ts.length - 1)]));
    }
    this.travel.geometry.setDrawRange(t0 * 2, (t1 - t0) * 2);
    this.drawn = { extrusion: end - start, travel: t1 - t0 };
    const z = d.layerZ;
    const zText = z && z.length > hi ? ` · z ${z[lo].toFixed(2)}–${z[hi].toFixed(2)} mm` : "";
    label.textContent = `layers ${lo + 1}–${hi + 1} of ${this.layers}${zText}`;
    this.updateMoveLabel();
    this.requestRender();
  }

  /**
   * The print-order slider: 0 … last G-code move of the result. Without move indices
   * (segmentMove empty) it steps through the extrusion segments, which are in print order.
   */
  setupMoves(segments) {
    const d = this.data;
    const ui = this.ui;
    const travels = d ? d.travel.length / 6 : 0;
    this.bySegment = !(d?.segmentMove?.length === segments && segments > 0);
    if (this.bySegment) {
      this.lastMove = segments - 1;
    } else {
      const tm = d.travelMove?.length === travels && travels > 0 ? d.travelMove[travels - 1] : -1;
      this.lastMove = Math.max(d.segmentMove[segments - 1], tm);
    }
    this.range.move = Infinity;
    if (!ui.moveMax) return;
    const wrap = ui.moveMax.closest("[data-moves]") ?? ui.moveMax;
    wrap.hidden = this.lastMove < 1;
    ui.moveMax.min = "0";
    ui.moveMax.max = String(Math.max(0, this.lastMove));
    ui.moveMax.value = ui.moveMax.max;
    ui.moveMax.disabled = this.lastMove < 1;
  }

  updateMoveLabel() {
    const out = this.ui.moveLabel;
    if (!out) return;
    const { move } = this.range;
    const total = Math.max(0, this.lastMove ?? -1) + 1;
    const what = this.bySegment ? "segment" : "move";
    out.textContent = !total ? "" : move === Infinity ? `all ${total.toLocaleString("en-US")} ${what}s`
      : `${what} ${(move + 1).toLocaleString("en-US")} of ${total.toLocaleString("en-US")}`;
  }

  /**
   * Tool-axis lines (2 vertices per segment) when the result has an axis per segment.
   * @param {THREE.Box3|null} bounds  of the extrusion segments (setResult computes it once)
   */
  buildAxis(segments, bounds) {
    const d = this.data;
    const axis = d?.axis;
    this.axis.geometry = new THREE.BufferGeometry();
    this.axisSegments = 0;
    const has = Boolean(axis && segments > 0 && axis.length >= segments * 3);
    const toggle = this.ui.showAxis;
    if (toggle) (toggle.closest("label") ?? toggle).hidden = !has;
    if (!has) {
      this.axis.geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(0), 3));
      return;
    }
    const len = Math.max(0.3, Math.min(5, bounds.getSize(new THREE.Vector3()).length() * 0.02));
    const p = d.positions;
    const out = new Float32Array(segments * 6);
    for (let i = 0; i < segments; i++) {
      const ax = axis[i * 3], ay = axis[i * 3 + 1], az = axis[i * 3 + 2];
      const n = Math.hypot(ax, ay, az) || 1;
      const x = p[i * 6 + 3], y = p[i * 6 + 4], z = p[i * 6 + 5];
      out[i * 6] = x;
      out[i * 6 + 1] = y;
      out[i * 6 + 2] = z;
      out[i * 6 + 3] = x + (ax / n) * len;
      out[i * 6 + 4] = y + (ay / n) * len;
      out[i * 6 + 5] = z + (az / n) * len;
    }
    this.axis.geometry.setAttribute("position", new THREE.BufferAttribute(out, 3));
    this.axisSegments = segments;
  }

  /**
   * Feature names and colours (schema.features: {code, label, color "#rrggbb"}).
   * @param {Array<{code: number, label?: string, name?: string, color?: string}>} features
   */
  setFeatures(features) {
    this.featureRgb.fill(null);
    this.featureLabel.fill(null);
    this.featureOrder = [];
    for (const f of features ?? []) {
      const code = Number(f.code);
      if (!(code >= 0 && code < 256)) continue;
      this.featureRgb[code] = hexRgb(f.color) ?? UNKNOWN_COLOR;
      this.featureLabel[code] = f.label ?? f.name ?? `feature ${code}`;
      this.featureOrder.push(code);
    }
    this.colorCache.delete("feature");
    if (this.data) this.applyColors();
  }

  /**
   * Path-start markers: the first vertex of every segment whose path index differs from the
   * previous segment's, with the first marker of each layer (for the layer range).
   */
  buildStarts() {
    const d = this.data;
    const segments = d ? d.positions.length / 6 : 0;
    const path = d?.path;
    this.starts.geometry = new THREE.BufferGeometry();
    if (!segments || !path || path.length < segments) {
      this.startSegment = new Uint32Array(0);
      this.starts.geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(0), 3));
      return;
    }
    let count = 0;
    for (let i = 0; i < segments; i++) if (i === 0 || path[i] !== path[i - 1]) count++;
    const pos = new Float32Array(count * 3);
    const startSegment = new Uint32Array(count);
    let k = 0;
    for (let i = 0; i < segments; i++) {
      if (i === 0 || path[i] !== path[i - 1]) {
        pos[k * 3] = d.positions[i * 6];
        pos[k * 3 + 1] = d.positions[i * 6 + 1];
        pos[k * 3 + 2] = d.positions[i * 6 + 2];
        startSegment[k++] = i;
      }
    }
    this.startSegment = startSegment;
    this.starts.geometry.setAttribute("position", new THREE.BufferAttribute(pos, 3));
  }

  /** Sets (or reuses) the colour attribute for the selected mode and updates the legend. */
  applyColors(render = true) {
    const mode = this.ui.colorBy.value;
    const d = this.data;
    const segments = d ? d.positions.length / 6 : 0;
    if (segments > 0) {
      let attr = this.colorCache.get(mode);
      if (!attr) {
        attr = new THREE.BufferAttribute(this.computeColors(mode, segments), 3, true);
        this.colorCache.set(mode, attr);
      }
      this.extrusion.geometry.setAttribute("color", attr);
    }
    this.updateLegend(mode, segments);
    if (render) this.requestRender();
  }

  /** @returns {Uint8Array} 2 vertices × RGB per segment */
  computeColors(mode, segments) {
    const d = this.data;
    const out = new Uint8Array(segments * 6);
    const put = (i, r, g, b) => {
      const o = i * 6;
      out[o] = out[o + 3] = r;
      out[o + 1] = out[o + 4] = g;
      out[o + 2] = out[o + 5] = b;
    };
    if (mode === "feature" && d.feature.length >= segments) {
      for (let i = 0; i < segments; i++) {
        const c = this.featureRgb[d.feature[i]] ?? UNKNOWN_COLOR;
        put(i, c[0], c[1], c[2]);
      }
    } else if (mode === "flow" && d.flow.length >= segments) {
      const [lo, hi] = this.getFlowRange();
      const scale = hi > lo ? 255 / (hi - lo) : 0;
      for (let i = 0; i < segments; i++) {
        const k = Math.max(0, Math.min(255, Math.round((d.flow[i] - lo) * scale))) * 3;
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

  getFlowRange() {
    if (this.flowRange) return this.flowRange;
    const flow = this.data.flow;
    let lo = Infinity;
    let hi = -Infinity;
    for (let i = 0; i < flow.length; i++) {
      const f = flow[i];
      if (f < lo) lo = f;
      if (f > hi) hi = f;
    }
    if (!(lo <= hi)) lo = hi = 0;
    this.flowRange = [lo, hi];
    return this.flowRange;
  }

  getFeatureCounts() {
    if (this.featureCounts) return this.featureCounts;
    const counts = new Uint32Array(256);
    const f = this.data.feature;
    for (let i = 0; i < f.length; i++) counts[f[i]]++;
    this.featureCounts = counts;
    return counts;
  }

  updateLegend(mode, segments) {
    const legend = this.ui.legend;
    legend.replaceChildren();
    if (segments === 0) {
      legend.append(item(null, "no toolpath yet: slice a design or drop a file"));
      return;
    }
    if (mode === "feature") {
      const counts = this.getFeatureCounts();
      for (const code of this.featureOrder) {
        if (counts[code] > 0) legend.append(item(this.featureRgb[code], this.featureLabel[code]));
      }
      let unknown = 0;
      for (let code = 0; code < 256; code++) if (!this.featureRgb[code]) unknown += counts[code];
      if (unknown > 0) legend.append(item(UNKNOWN_COLOR, "unknown"));
    } else if (mode === "flow") {
      const [lo, hi] = this.getFlowRange();
      const bar = document.createElement("span");
      bar.className = "ramp";
      const stops = [];
      for (let k = 0; k <= 8; k++) {
        const j = Math.round((k / 8) * 255) * 3;
        stops.push(`rgb(${RAMP[j]},${RAMP[j + 1]},${RAMP[j + 2]})`);
      }
      bar.style.background = `linear-gradient(to right, ${stops.join(",")})`;
      const text = (v) => `${v.toFixed(v < 10 ? 2 : 1)}`;
      const low = document.createElement("span");
      low.textContent = text(lo);
      const high = document.createElement("span");
      high.textContent = `${text(hi)} mm³/s`;
      const wrap = document.createElement("span");
      wrap.className = "legend-item flow-legend";
      wrap.title = "volumetric flow, mm³/s";
      wrap.append("flow ", low, bar, high);
      legend.append(wrap);
    } else {
      const paths = this.data.path.length ? this.data.path[this.data.path.length - 1] + 1 : 0;
      legend.append(item(null, `one colour per extrusion path (${paths.toLocaleString()} paths)`));
    }
    if (this.starts.visible) legend.append(item([255, 255, 255], "path start", true));
    legend.append(item(null, `${segments.toLocaleString()} segments`));
  }

  /** Draws the build plate: outline, 10 mm grid, origin axes. */
  setBed(bed, origin) {
    const [bx, by] = bed;
    const key = `${bx}x${by}:${origin}`;
    if (key === this.bedKey) return;
    this.bedKey = key;
    for (const child of this.plate.children) child.geometry.dispose();
    this.plate.clear();
    const x0 = origin === "center" ? -bx / 2 : 0;
    const y0 = origin === "center" ? -by / 2 : 0;
    this.bedBox = new THREE.Box3(new THREE.Vector3(x0, y0, 0), new THREE.Vector3(x0 + bx, y0 + by, Math.min(bx, by) * 0.25));

    const grid = [];
    for (let x = Math.ceil(x0 / 10) * 10; x <= x0 + bx; x += 10) grid.push(x, y0, 0, x, y0 + by, 0);
    for (let y = Math.ceil(y0 / 10) * 10; y <= y0 + by; y += 10) grid.push(x0, y, 0, x0 + bx, y, 0);
    this.plate.add(lines(grid, 0x3a414d));
    this.plate.add(lines([x0, y0, 0, x0 + bx, y0, 0, x0 + bx, y0, 0, x0 + bx, y0 + by, 0,
      x0 + bx, y0 + by, 0, x0, y0 + by, 0, x0, y0 + by, 0, x0, y0, 0], 0x8a93a3));
    // Origin: X red, Y green, Z blue, drawn over the plate lines.
    const a = Math.max(5, Math.min(bx, by) * 0.08);
    for (const [flat, color] of [[[0, 0, 0, a, 0, 0], 0xff5a5f], [[0, 0, 0, 0, a, 0], 0x4cc76a], [[0, 0, 0, 0, 0, a], 0x5b8cff]]) {
      const axis = lines(flat, color);
      axis.material.depthTest = false;
      axis.renderOrder = 1;
      this.plate.add(axis);
    }
    const plane = new THREE.Mesh(
      new THREE.PlaneGeometry(bx, by),
      new THREE.MeshBasicMaterial({ color: 0x262b33, side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 }),
    );
    plane.position.set(x0 + bx / 2, y0 + by / 2, -0.01);
    this.plate.add(plane);
  }

  /** Points the camera at a box (default: the plate) from the front left, above. */
  fit(box = null) {
    const b = box ?? this.bedBox;
    const center = b.getCenter(new THREE.Vector3());
    const radius = Math.max(1, b.getSize(new THREE.Vector3()).length() / 2);
    const fov = (this.camera.fov * Math.PI) / 180;
    const dist = (radius / Math.sin(fov / 2)) * (box ? 1.45 : 1.0);
    const dir = new THREE.Vector3(-0.55, -1, 0.75).normalize();
    this.camera.position.copy(center).addScaledVector(dir, dist);
    this.camera.near = Math.max(0.01, dist / 1000);
    this.camera.far = dist * 20 + 2000;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(center);
    this.controls.update();
    this.requestRender();
  }
}

function lines(flat, color) {
  const g = new THREE.BufferGeometry();
  g.setAttribute("position", new THREE.Float32BufferAttribute(flat, 3));
  return new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color }));
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

/** Bounding box of x0 y0 z0 x1 y1 z1 segments. */
function boundsOf(p) {
  let minX = Infinity, minY = Infinity, minZ = Infinity;
  let maxX = -Infinity, maxY = -Infinity, maxZ = -Infinity;
  for (let i = 0; i < p.length; i += 3) {
    const x = p[i], y = p[i + 1], z = p[i + 2];
    if (x < minX) minX = x;
    if (x > maxX) maxX = x;
    if (y < minY) minY = y;
    if (y > maxY) maxY = y;
    if (z < minZ) minZ = z;
    if (z > maxZ) maxZ = z;
  }
  return new THREE.Box3(new THREE.Vector3(minX, minY, minZ), new THREE.Vector3(maxX, maxY, maxZ));
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

/** A round white dot (alpha) for the path-start markers. */
function dotTexture() {
  const size = 32;
  const c = document.createElement("canvas");
  c.width = c.height = size;
  const ctx = c.getContext("2d");
  ctx.fillStyle = "#000";
  ctx.beginPath();
  ctx.arc(size / 2, size / 2, size / 2 - 1, 0, Math.PI * 2);
  ctx.fill();
  ctx.fillStyle = "#fff";
  ctx.beginPath();
  ctx.arc(size / 2, size / 2, size / 2 - 6, 0, Math.PI * 2);
  ctx.fill();
  const t = new THREE.CanvasTexture(c);
  t.colorSpace = THREE.NoColorSpace;
  return t;
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
function hexRgb(hex) {
  const m = /^#?([0-9a-f]{6})$/i.exec(String(hex ?? "").trim());
  if (!m) return null;
  const v = parseInt(m[1], 16);
  return [(v >> 16) & 255, (v >> 8) & 255, v & 255];
}

/** First index whose value is >= x (sorted array). */
function lowerBound(a, x) {
  let lo = 0;
  let hi = a.length;
  while (lo < hi) {
    const mid = (lo + hi) >>> 1;
    if (a[mid] < x) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

/** First index whose value is > x (sorted array). */
function upperBound(a, x) {
  let lo = 0;
  let hi = a.length;
  while (lo < hi) {
    const mid = (lo + hi) >>> 1;
    if (a[mid] <= x) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

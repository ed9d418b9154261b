// 3D toolpath preview: every extrusion segment is drawn as a shaded tube (a camera-facing quad
// shaded as a round tube with round ends, lit by a light fixed to the camera and darker with
// depth) or as a line lit by its direction and darker with depth: lines while the camera moves
// over TUBE_LIMIT segments, and always over STILL_TUBE_LIMIT.
//
// Built for millions of segments: the segments' ends and widths are one float texture, their
// colours one byte texture per colour mode (computed once per mode and cached), and the shaders
// pull a segment's data by vertex index, so a draw needs no vertex buffers; the layer range and
// the print-order limit are a draw range (a few array lookups per change);
// nothing is allocated per frame and a frame is drawn only when something changed (no
// animation loop). The camera is fitted to the part on every new result and on request
// (Fit, top, front, iso views); its near and far planes follow the part's bounding sphere on
// every frame, and the zoom is limited to the part's scale, so zoom never clips the part.
// Feature names and colours come from the schema (setFeatures).
// The parts: preview-gl.js (shaders, data textures), preview-colors.js (colour modes, legend),
// preview-camera.js (plate, framing, clipping).
import * as THREE from "./vendor/three.module.js";
import { OrbitControls } from "./vendor/OrbitControls.js";
import * as Colors from "./preview-colors.js";
import * as Camera from "./preview-camera.js";
import { DEFAULT_WIDTH, LINE_FRAGMENT, LINE_VERTEX, STILL_TUBE_LIMIT, TUBE_FRAGMENT, TUBE_LIMIT, TUBE_VERTEX, dotTexture, segmentGeometry, segmentTexture, textureArray } from "./preview-gl.js";
import { UNKNOWN_COLOR, hexRgb } from "./preview-colors.js";
import { VIEWS, boundsOf, farthestFrom } from "./preview-camera.js";

export { STILL_TUBE_LIMIT, TUBE_LIMIT };

// Colours are given in sRGB and drawn as they are: no colour management.
THREE.ColorManagement.enabled = false;

const BACKGROUND = 0x1f232a;
const DEFAULT_BED = [200, 200, 200];
const TRAVEL_COLOR = 0x5aa0ff;
const START_COLOR = 0xffffff;
const AXIS_COLOR = 0xf2f2f2;
/** The backdrop's lines (a platform under its path): a muted blue-grey. */
const BACKDROP_COLOR = 0x8a9bb0;
/** Size of a path-start marker, CSS pixels. */
const START_SIZE_PX = 7;

/** Tubes come back this long after the camera stops (ms). */
const REST_MS = 250;
/** Vertical field of view, degrees. */
const FOV = 30;
/** Keys on the focused canvas (shown in the buttons' titles and aria-keyshortcuts). */
const CAMERA_KEYS = { f: "fit", Home: "fit", 1: "top", 2: "front", 3: "iso" };

export class Preview {
  /**
   * @param {HTMLCanvasElement} canvas
   * @param {{colorBy: HTMLSelectElement, showTravel: HTMLInputElement,
   *          showStarts?: HTMLInputElement, layerMin: HTMLInputElement, layerMax: HTMLInputElement,
   *          layerLabel: HTMLElement, legend: HTMLElement, moveMax?: HTMLInputElement,
   *          moveLabel?: HTMLElement, showAxis?: HTMLInputElement, camera?: HTMLElement}} ui
   *   `camera`: an element holding buttons with data-camera="fit|top|front|iso"
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
    this.camera = new THREE.PerspectiveCamera(FOV, 1, 0.1, 10000);
    this.camera.up.set(0, 0, 1);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.enableDamping = false; // damping needs a continuous loop
    this.controls.screenSpacePanning = true;
    this.controls.listenToKeyEvents(canvas); // arrow keys pan when the canvas has focus
    this.controls.addEventListener("change", () => this.requestRender());
    // A user's orbit, pan or zoom ends the automatic framing (a resize refits until then), and
    // draws lines while it lasts when the tubes are too many to move smoothly.
    this.controls.addEventListener("start", () => {
      this.autoFit = false;
      this.setMoving(true);
    });
    this.controls.addEventListener("end", () => this.setMoving(false));
    this.moving = false;
    this.restTimer = 0;
    /** unit vector from the target to the camera: the view kept by Fit and new results */
    this.viewDir = VIEWS.iso.clone();
    this.autoFit = true;

    this.plate = new THREE.Group();
    this.scene.add(this.plate);

    // Extrusion: a tube (4 vertices, 6 indices) or a line (2 vertices) per segment (see TUBE_LIMIT).
    this.uniforms = {
      uEnds: { value: null },
      uColors: { value: null },
      uPixel: { value: 0.001 }, // world size of one drawing-buffer pixel at distance 1
      uDepth: { value: new THREE.Vector2(0, 1) }, // the part's depth range in view: near, length
    };
    this.tubes = new THREE.Mesh(segmentGeometry(), new THREE.ShaderMaterial({
      uniforms: this.uniforms, vertexShader: TUBE_VERTEX, fragmentShader: TUBE_FRAGMENT, side: THREE.DoubleSide,
    }));
    this.lines = new THREE.LineSegments(segmentGeometry(), new THREE.ShaderMaterial({
      uniforms: this.uniforms, vertexShader: LINE_VERTEX, fragmentShader: LINE_FRAGMENT,
    }));
    for (const o of [this.tubes, this.lines]) o.frustumCulled = false;
    /** segment textures of the result (ends and widths) */
    this.textures = [];
    this.lines.visible = false;
    /** "auto" (see TUBE_LIMIT), "tubes" or "lines"; `drawStyle` is the one in use now */
    this.style = "auto";
    this.drawStyle = "tubes";
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
    // A backdrop: a kind's surface drawn faintly behind its toolpath (the platform an
    // axisymmetric path is printed on), set by steps.js from the kind's `teach.backdrop` view.
    this.backdrop = new THREE.LineSegments(
      new THREE.BufferGeometry(),
      new THREE.LineBasicMaterial({ color: BACKDROP_COLOR, transparent: true, opacity: 0.4 }),
    );
    this.backdrop.frustumCulled = false;
    this.scene.add(this.tubes, this.lines, this.travel, this.starts, this.axis, this.backdrop);
    /** segment index of every path-start marker (increasing) */
    this.startSegment = new Uint32Array(0);
    /** layers shown, and the last G-code move shown (Infinity: all) */
    this.range = { lo: 0, hi: -1, move: Infinity };
    /** segments drawn now (for tests and the legend), and the first one */
    this.drawn = { extrusion: 0, travel: 0 };
    this.first = 0;
    /** feature code → sRGB bytes and label (setFeatures) */
    this.featureRgb = new Array(256).fill(null);
    this.featureLabel = new Array(256).fill(null);
    this.featureOrder = [];

    /** @type {import("./protocol.js").PreviewBuffers|null} */
    this.data = null;
    /** part bounds and bounding sphere (null: no result; the plate is framed) */
    this.bounds = null;
    this.sphere = null;
    /** @type {Map<string, THREE.DataTexture>} colours per mode (a texel a segment), built on demand */
    this.colorCache = new Map();
    this.setFeatures(options.features ?? []);
    this.layers = 0;
    this.bedKey = "";
    this.frameRequested = false;
    /** The last frame drawn: when (performance.now(), ms) and how many segments it showed. */
    this.lastFrame = { at: 0, segments: 0 };
    this.drawFrame = () => {
      this.frameRequested = false;
      this.updateClipping();
      this.renderer.render(this.scene, this.camera);
      this.lastFrame = { at: performance.now(), segments: this.segmentCount() };
    };

    ui.colorBy.addEventListener("change", () => this.applyColors());
    ui.showStarts?.addEventListener("change", () => {
      this.starts.visible = ui.showStarts.checked;
      this.updateLegend(ui.colorBy.value, this.segmentCount());
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
    // Camera buttons (data-camera="fit|top|front|iso") and their keys on the canvas.
    ui.camera?.addEventListener("click", (e) => {
      const which = e.target.closest?.("[data-camera]")?.dataset.camera;
      if (which) this.view(which);
    });
    canvas.addEventListener("keydown", (e) => {
      if (e.ctrlKey || e.metaKey || e.altKey) return;
      const which = CAMERA_KEYS[e.key.length === 1 ? e.key.toLowerCase() : e.key];
      if (!which) return;
      e.preventDefault();
      this.view(which);
    });

    new ResizeObserver(() => this.resize()).observe(canvas.parentElement);
    this.setBed(DEFAULT_BED, "corner");
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
    if (this.autoFit) this.fit();
    this.requestRender();
  }

  segmentCount() {
    return this.data ? this.data.positions.length / 6 : 0;
  }

  /**
   * Shows a result's preview buffers (kept by reference, never copied).
   * @param {import("./protocol.js").PreviewBuffers|null} data
   * @param {{origin?: string}} [options]  printer origin: "corner" (default) or "center"
   */
  setResult(data, options = {}) {
    this.travel.geometry.dispose();
    this.starts.geometry.dispose();
    this.axis.geometry.dispose();
    for (const t of this.textures) t.dispose();
    for (const t of this.colorCache.values()) t.dispose();
    this.textures = [];
    this.colorCache.clear();
    this.uniforms.uEnds.value = this.uniforms.uColors.value = null;
    this.data = data;
    this.featureCounts = null;
    this.flowRange = null;
    this.ranges = new Map();
    this.first = 0;
    this.drawn = { extrusion: 0, travel: 0 };

    const segments = data ? data.positions.length / 6 : 0;
    const empty = new Float32Array(0);
    this.travel.geometry = new THREE.BufferGeometry();
    this.travel.geometry.setAttribute("position", new THREE.BufferAttribute(data?.travel ?? empty, 3));
    if (segments > 0) {
      // Ends and width, two RGBA float texels a segment (the copy is dropped once uploaded).
      const p = data.positions;
      const w = data.width?.length >= segments ? data.width : null;
      const ends = textureArray(Float32Array, 2 * segments);
      for (let i = 0; i < segments; i++) {
        const o = i * 8, k = i * 6;
        ends[o] = p[k];
        ends[o + 1] = p[k + 1];
        ends[o + 2] = p[k + 2];
        ends[o + 3] = w && w[i] > 0 ? w[i] : DEFAULT_WIDTH;
        ends[o + 4] = p[k + 3];
        ends[o + 5] = p[k + 4];
        ends[o + 6] = p[k + 5];
      }
      const texture = segmentTexture(ends, 2 * segments, THREE.FloatType);
      texture.onUpdate = () => { texture.image.data = null; };
      this.textures.push(texture);
      this.uniforms.uEnds.value = texture;
    }

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
    this.bounds = bounds;
    this.sphere = bounds ? bounds.getBoundingSphere(new THREE.Sphere()) : null;
    this.shadeRadius = bounds ? farthestFrom(this.sphere.center, data.positions) : 0;
    this.buildStarts();
    this.buildAxis(segments, bounds);
    this.setupMoves(segments);
    this.chooseStyle();

    const bed = data?.bedSize && data.bedSize.length >= 2 && data.bedSize[0] > 0 ? data.bedSize : DEFAULT_BED;
    this.setBed(bed, options.origin ?? "corner");
    this.applyColors(false);
    this.setLayerRange(0, this.layers - 1);
    this.fit();
    this.requestRender();
  }

  /**
   * Draws `lines` (a lines3d view's data: x0 y0 z0 x1 y1 z1 code per segment, mm, in the
   * toolpath's frame) faintly behind the toolpath; null or empty removes it. Returns the
   * segments drawn.
   */
  setBackdrop(lines) {
    this.backdrop.geometry.dispose();
    const n = lines ? Math.floor(lines.length / 7) : 0;
    const pos = new Float32Array(6 * n);
    for (let i = 0; i < n; i++) for (let k = 0; k < 6; k++) pos[6 * i + k] = lines[7 * i + k];
    this.backdrop.geometry = new THREE.BufferGeometry();
    this.backdrop.geometry.setAttribute("position", new THREE.BufferAttribute(pos, 3));
    this.backdropSegments = n;
    this.requestRender();
    return n;
  }

  /**
   * How the extrusion is drawn: "tubes", "lines", or "auto" (see TUBE_LIMIT).
   * @param {"auto"|"tubes"|"lines"} style
   */
  setStyle(style) {
    this.style = style;
    this.chooseStyle();
    this.updateLegend(this.ui.colorBy.value, this.segmentCount());
    this.requestRender();
  }

  /** The style at rest: tubes up to STILL_TUBE_LIMIT segments in "auto". */
  restStyle() {
    return this.style !== "auto" ? this.style : this.segmentCount() > STILL_TUBE_LIMIT ? "lines" : "tubes";
  }

  /** The camera starts or stops moving: lines while it moves over TUBE_LIMIT segments. */
  setMoving(on) {
    clearTimeout(this.restTimer);
    if (on) {
      if (this.moving) return;
      this.moving = true;
      this.chooseStyle();
    } else {
      this.restTimer = setTimeout(() => {
        this.moving = false;
        if (this.chooseStyle()) this.requestRender();
      }, REST_MS);
    }
  }

  /** @returns {boolean} whether the style changed */
  chooseStyle() {
    const before = this.drawStyle;
    const moving = this.moving && this.style === "auto" && this.segmentCount() > TUBE_LIMIT;
    this.drawStyle = moving ? "lines" : this.restStyle();
    this.tubes.visible = this.drawStyle === "tubes";
    this.lines.visible = this.drawStyle === "lines";
    if (this.drawStyle === "tubes" && this.drawn.extrusion > 0) this.ensureQuads(this.first + this.drawn.extrusion);
    return before !== this.drawStyle;
  }

  /**
   * The tubes' index buffer (6 indices a segment, 2 triangles of its 4 vertices), grown to
   * `segments` in powers of two and kept across results.
   */
  ensureQuads(segments) {
    const index = this.tubes.geometry.index;
    if (index && index.count >= segments * 6) return;
    let n = 1024;
    while (n < segments) n *= 2;
    const quads = new Uint32Array(n * 6);
    for (let i = 0, v = 0; i < quads.length; i += 6, v += 4) {
      quads[i] = v;
      quads[i + 1] = v + 1;
      quads[i + 2] = v + 2;
      quads[i + 3] = v + 2;
      quads[i + 4] = v + 1;
      quads[i + 5] = v + 3;
    }
    const range = this.tubes.geometry.drawRange;
    this.tubes.geometry.dispose();
    this.tubes.geometry = segmentGeometry();
    this.tubes.geometry.setIndex(new THREE.BufferAttribute(quads, 1));
    this.tubes.geometry.setDrawRange(range.start, range.count);
  }

  /** Draws segments first … first + count - 1 (both drawings: tubes 6 indices a segment, lines 2 vertices). */
  setSegmentRange(first, count) {
    this.first = first;
    if (!this.uniforms.uEnds.value || !this.uniforms.uColors.value) count = 0;
    if (count > 0 && this.drawStyle === "tubes") this.ensureQuads(first + count);
    this.tubes.geometry.setDrawRange(first * 6, count * 6);
    this.lines.geometry.setDrawRange(first * 2, count * 2);
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
      for (const o of [this.travel, this.starts, this.axis]) o.geometry.setDrawRange(0, 0);
      this.setSegmentRange(0, 0);
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
    this.setSegmentRange(start, end - start);
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
      let colors = this.colorCache.get(mode);
      if (!colors) {
        colors = segmentTexture(this.computeColors(mode, segments), segments, THREE.UnsignedByteType);
        this.colorCache.set(mode, colors);
      }
      this.uniforms.uColors.value = colors;
      this.setSegmentRange(this.first, this.drawn.extrusion);
    }
    this.updateLegend(mode, segments);
    if (render) this.requestRender();
  }

  // --- colours and legend (preview-colors.js) ---
  /** RGBA per segment for a colour mode (A unused), as long as a colour texture. */
  computeColors(mode, segments) {
    return Colors.computeColors(this, mode, segments);
  }

  /** [lo, hi] of a ramp mode's values over the whole print (cached). */
  getRange(mode) {
    return Colors.getRange(this, mode);
  }

  /** [lo, hi] of the flow over the whole print (cached). */
  getFlowRange() {
    return Colors.getFlowRange(this);
  }

  /** Segments per feature code (cached). */
  getFeatureCounts() {
    return Colors.getFeatureCounts(this);
  }

  /** The legend under the canvas for a colour mode. */
  updateLegend(mode, segments) {
    return Colors.updateLegend(this, mode, segments);
  }

  // --- plate and camera (preview-camera.js) ---
  /** Draws the build plate: outline, 10 mm grid, origin axes. */
  setBed(bed, origin) {
    return Camera.setBed(this, bed, origin);
  }

  /** Frames the part from the camera's current direction. */
  fit() {
    return Camera.fit(this);
  }

  /** Fractions of the canvas height the page's controls cover: {top, bottom}. */
  overlayBands() {
    return Camera.overlayBands(this);
  }

  /** A camera view: "fit", "top", "front" or "iso". */
  view(which) {
    return Camera.view(this, which);
  }

  /** Near and far planes, depth shading range and pixel size; before every frame. */
  updateClipping() {
    return Camera.updateClipping(this);
  }
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

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
/** Colour modes drawn on the colour ramp: preview buffer, legend label and unit. */
const RAMP_MODES = {
  flow: { key: "flow", label: "flow", unit: "mm³/s", title: "volumetric flow, mm³/s" },
  e_per_mm: { key: "ePerMm", label: "ΔE/mm", unit: "mm/mm", title: "filament fed per mm of travel (ΔE ÷ length), mm/mm" },
  speed: { key: "speed", label: "speed", unit: "mm/s", title: "feed rate, mm/s (for a VTP foam: V* × the thread's speed)" },
};

const RAMP = buildRamp();

/**
 * Over this many extrusion segments the preview draws lines (lit by their direction, darker
 * with depth) while the camera moves, and tubes again once it rests (REST_MS): the count where
 * orbiting tubes drops under 10 frames a second in headless Chromium with SwiftShader
 * (tests/e2e/preview-bench.mjs; ARCHITECTURE.md, "The 3D preview"). `setStyle` overrides it.
 */
export const TUBE_LIMIT = 10000;
/** Over this many segments, lines at rest too: one frame of tubes takes over a second there. */
export const STILL_TUBE_LIMIT = 150000;
/** Tubes come back this long after the camera stops (ms). */
const REST_MS = 250;
/** Vertical field of view, degrees. */
const FOV = 30;
/** Fit: the part's projection spans this fraction of the canvas in its limiting direction. */
const FILL = 0.86;
/** Tube width (mm) when the result has no width per segment. */
const DEFAULT_WIDTH = 0.45;
/** Directions from the target to the camera of the camera buttons (z up). */
const VIEWS = {
  iso: new THREE.Vector3(-0.55, -1, 0.75).normalize(),
  top: new THREE.Vector3(0, -1e-3, 1).normalize(), // a hair to the front: +y is up on screen
  front: new THREE.Vector3(0, -1, 0),
};
/** Keys on the focused canvas (shown in the buttons' titles and aria-keyshortcuts). */
const CAMERA_KEYS = { f: "fit", Home: "fit", 1: "top", 2: "front", 3: "iso" };

// One light fixed to the camera (upper left, in front), a weak fill from the lower right and a
// small highlight; colours are sRGB bytes, shaded as they are (no colour management).
const LIGHTS = /* glsl */ `
const vec3 KEY = vec3(-0.4082, 0.5443, 0.7328);
const vec3 FILL_LIGHT = vec3(0.6727, -0.3363, 0.6590);
const vec3 HALF_KEY = vec3(-0.2193, 0.2924, 0.9308);
`;
/** Width of the segment data textures (texels); a segment's texels are found from its index. */
const TEX_WIDTH = 4096;
const TEX_SHIFT = 12;
// Segment data is pulled from textures by gl_VertexID (no instancing: SwiftShader, the software
// WebGL of headless browsers and GPU-less machines, pays about 30 µs per instance).
const SEGMENT_DATA = /* glsl */ `
uniform highp sampler2D uEnds;   // 2 texels per segment: x y z width, x y z 0 (mm)
uniform lowp sampler2D uColors;  // 1 texel per segment: sRGB of the colour mode
uniform float uPixel;
uniform vec2 uDepth;
ivec2 texel(int i) { return ivec2(i & ${TEX_WIDTH - 1}, i >> ${TEX_SHIFT}); }
`;

/**
 * A tube: a camera-facing quad round each segment, half a width wider than it on every side,
 * shaded as a round tube with round ends (an impostor: 4 vertices and 2 triangles a segment,
 * the round ends cut out in the fragment shader), so consecutive segments join without gaps.
 */
const TUBE_VERTEX = /* glsl */ `${SEGMENT_DATA}
varying vec3 vColor;
varying vec2 vAt;              // across (-1 … 1) and along (-1 … len + 1), in radii
flat varying float vLen;       // the segment's length on screen, in radii
flat varying vec3 vSide;       // view-space frame of the tube: across, along, towards the eye
flat varying vec3 vAlong;
flat varying vec3 vFacing;
flat varying float vRadius;
varying vec3 vView;            // the point on the quad, view space
varying float vFar;
void main() {
  int seg = gl_VertexID >> 2;
  int q = gl_VertexID & 3; // the quad's corners: start or end (q >> 1), one side or the other (q & 1)
  vec4 a = texelFetch(uEnds, texel(2 * seg), 0);
  vec4 b = texelFetch(uEnds, texel(2 * seg + 1), 0);
  vec3 p0 = (modelViewMatrix * vec4(a.xyz, 1.0)).xyz;
  vec3 p1 = (modelViewMatrix * vec4(b.xyz, 1.0)).xyz;
  vec3 mid = 0.5 * (p0 + p1);
  vec3 eye = isOrthographic ? vec3(0.0, 0.0, 1.0) : normalize(-mid);
  vec3 d = p1 - p0;
  // The segment's direction on screen (any, when it points at the eye).
  vec3 ds = d - eye * dot(d, eye);
  vec3 along = dot(ds, ds) > 1e-12 ? normalize(ds) : normalize(cross(eye, vec3(0.0, 1.0, 0.0)) + vec3(1e-6, 0.0, 0.0));
  vec3 side = normalize(cross(along, eye));
  // Never thinner than about a pixel, however far away.
  float r = max(0.5 * a.w, 0.6 * uPixel * (isOrthographic ? 1.0 : max(-mid.z, 1e-6)));
  float len = dot(d, along) / r;
  float s = (q & 1) == 0 ? -1.0 : 1.0;
  vec3 p = (q < 2 ? p0 - along * r : p1 + along * r) + side * (s * r);
  gl_Position = projectionMatrix * vec4(p, 1.0);
  vView = p;
  vRadius = r;
  vAt = vec2(s, q < 2 ? -1.0 : len + 1.0);
  vLen = len;
  vec3 axis = dot(d, d) > 1e-12 ? normalize(d) : along;
  vSide = side;
  vAlong = along;
  vFacing = normalize(cross(side, axis));
  if (dot(vFacing, eye) < 0.0) vFacing = -vFacing;
  vColor = texelFetch(uColors, texel(seg), 0).rgb;
  vFar = clamp((-mid.z - uDepth.x) / uDepth.y, 0.0, 1.0);
}
`;
const TUBE_FRAGMENT = /* glsl */ `${LIGHTS}
uniform mat4 projectionMatrix;
varying vec3 vColor;
varying vec2 vAt;
flat varying float vLen;
flat varying vec3 vSide;
flat varying vec3 vAlong;
flat varying vec3 vFacing;
flat varying float vRadius;
varying vec3 vView;
varying float vFar;
void main() {
  float end = vAt.y - clamp(vAt.y, 0.0, vLen); // beyond an end, in radii
  float q = vAt.x * vAt.x + end * end;
  if (q > 1.0) discard;
  float h = sqrt(1.0 - q);
  vec3 n = normalize(vSide * vAt.x + vAlong * end + vFacing * h);
  // The depth of the tube's surface, not of the quad: tubes that meet or cross intersect as
  // tubes do (the round end of one segment hides inside the next).
  vec4 clip = projectionMatrix * vec4(vView + vFacing * (h * vRadius), 1.0);
  gl_FragDepth = 0.5 + 0.5 * clip.z / clip.w;
  float key = max(dot(n, KEY), 0.0);
  float fill = max(dot(n, FILL_LIGHT), 0.0);
  float spec = pow(max(dot(n, HALF_KEY), 0.0), 24.0);
  vec3 c = vColor * (0.12 + 0.8 * key + 0.18 * fill) + 0.25 * spec;
  gl_FragColor = vec4(c * (1.12 - 0.8 * sqrt(vFar)), 1.0);
}
`;
/** A line per segment: lit by its direction (bright across the light, dim along it) and darker with depth. */
const LINE_VERTEX = /* glsl */ `${SEGMENT_DATA}${LIGHTS}
varying vec3 vColor;
void main() {
  int seg = gl_VertexID >> 1;
  vec3 a = texelFetch(uEnds, texel(2 * seg), 0).xyz;
  vec3 b = texelFetch(uEnds, texel(2 * seg + 1), 0).xyz;
  vec4 mv = modelViewMatrix * vec4((gl_VertexID & 1) == 0 ? a : b, 1.0);
  gl_Position = projectionMatrix * mv;
  vec3 t = mat3(modelViewMatrix) * (b - a);
  float lt = dot(t, t) > 0.0 ? dot(normalize(t), KEY) : 0.0;
  float lit = sqrt(max(1.0 - lt * lt, 0.0));
  float far = clamp((-mv.z - uDepth.x) / uDepth.y, 0.0, 1.0);
  vColor = texelFetch(uColors, texel(seg), 0).rgb * (0.4 + 0.6 * lit) * (1.15 - 0.85 * sqrt(far));
}
`;
const LINE_FRAGMENT = /* glsl */ `
varying vec3 vColor;
void main() {
  gl_FragColor = vec4(vColor, 1.0);
}
`;

/** A geometry without attributes: the shaders pull segments by vertex index; drawRange picks them. */
function segmentGeometry() {
  const g = new THREE.BufferGeometry();
  g.setDrawRange(0, 0);
  g.boundingSphere = new THREE.Sphere(new THREE.Vector3(), 1e9); // never culled or sorted by it
  return g;
}

/** A data texture of `texels` texels (TEX_WIDTH wide), `channels` RGBA values each. */
function segmentTexture(data, texels, type) {
  const t = new THREE.DataTexture(data, TEX_WIDTH, Math.max(1, Math.ceil(texels / TEX_WIDTH)), THREE.RGBAFormat, type);
  t.minFilter = t.magFilter = THREE.NearestFilter;
  t.generateMipmaps = false;
  t.colorSpace = THREE.NoColorSpace;
  t.needsUpdate = true;
  return t;
}

/** Room for `texels` texels, RGBA, in a TEX_WIDTH-wide texture. */
function textureArray(Type, texels) {
  return new Type(Math.max(1, Math.ceil(texels / TEX_WIDTH)) * TEX_WIDTH * 4);
}

/** Distance from `c` to the farthest of (about 300k of) the points x y z … */
function farthestFrom(c, p) {
  const step = 3 * Math.max(1, Math.ceil(p.length / 3 / 300000));
  let r2 = 0;
  for (let i = 0; i < p.length; i += step) {
    const dx = p[i] - c.x, dy = p[i + 1] - c.y, dz = p[i + 2] - c.z;
    const d2 = dx * dx + dy * dy + dz * dz;
    if (d2 > r2) r2 = d2;
  }
  return Math.sqrt(r2);
}

/** The 8 corners of a box, x y z each. */
function boxCorners(b) {
  const out = [];
  for (let i = 0; i < 8; i++) {
    out.push(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z);
  }
  return new Float32Array(out);
}

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
    this.scene.add(this.tubes, this.lines, this.travel, this.starts, this.axis);
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

  /** @returns {Uint8Array} RGBA per segment (A unused), as long as a colour texture */
  computeColors(mode, segments) {
    const d = this.data;
    const out = textureArray(Uint8Array, segments);
    const put = (i, r, g, b) => {
      out[i * 4] = r;
      out[i * 4 + 1] = g;
      out[i * 4 + 2] = b;
    };
    if (mode === "feature" && d.feature.length >= segments) {
      for (let i = 0; i < segments; i++) {
        const c = this.featureRgb[d.feature[i]] ?? UNKNOWN_COLOR;
        put(i, c[0], c[1], c[2]);
      }
    } else if (RAMP_MODES[mode] && d[RAMP_MODES[mode].key]?.length >= segments) {
      const values = d[RAMP_MODES[mode].key];
      const [lo, hi] = this.getRange(mode);
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
  getRange(mode) {
    if (mode === "flow") return this.getFlowRange();
    if (this.ranges.has(mode)) return this.ranges.get(mode);
    const values = this.data[RAMP_MODES[mode].key] ?? [];
    let lo = Infinity;
    let hi = -Infinity;
    for (let i = 0; i < values.length; i++) {
      const f = values[i];
      if (f < lo) lo = f;
      if (f > hi) hi = f;
    }
    if (!(lo <= hi)) lo = hi = 0;
    this.ranges.set(mode, [lo, hi]);
    return [lo, hi];
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
    } else if (RAMP_MODES[mode]) {
      const { label, unit, title } = RAMP_MODES[mode];
      const [lo, hi] = this.getRange(mode);
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
      const paths = this.data.path.length ? this.data.path[this.data.path.length - 1] + 1 : 0;
      legend.append(item(null, `one colour per extrusion path (${paths.toLocaleString()} paths)`));
    }
    if (this.starts.visible) legend.append(item([255, 255, 255], "path start", true));
    const asLines = this.restStyle() === "lines" && segments > 0;
    const count = item(null, `${segments.toLocaleString()} segments${asLines ? " · lines" : ""}`);
    if (asLines) {
      count.title = this.style === "auto"
        ? `Drawn as lines: over ${STILL_TUBE_LIMIT.toLocaleString()} segments, tubes are too slow without a fast GPU`
        : "Drawn as lines";
    } else if (this.style === "auto" && segments > TUBE_LIMIT) {
      count.title = `Drawn as lines while the view moves (over ${TUBE_LIMIT.toLocaleString()} segments)`;
    }
    legend.append(count);
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
    this.bedSphere = this.bedBox.getBoundingSphere(new THREE.Sphere());

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

  /**
   * Frames the part (the plate when there is none) from the camera's current direction: the
   * camera looks at the centre of the part's projection, at the distance where the part's
   * points span FILL of the canvas in its limiting direction.
   */
  fit() {
    const cam = this.camera;
    const back = cam.position.clone().sub(this.controls.target);
    if (back.lengthSq() < 1e-12) back.copy(VIEWS.iso);
    back.normalize();
    const right = new THREE.Vector3(0, 0, 1).cross(back);
    if (right.lengthSq() < 1e-12) right.set(1, 0, 0);
    right.normalize();
    const up = back.clone().cross(right);
    // The controls drawn over the canvas (top row(s), legend and camera buttons at the bottom)
    // cover bands of it: frame the part in the band between them.
    const { top, bottom } = this.overlayBands();
    const free = Math.max(0.3, 1 - top - bottom);
    const tanHalf = Math.tan((cam.fov * Math.PI) / 360);
    const tanY = tanHalf * FILL * free;
    const tanX = tanHalf * FILL * cam.aspect;
    const points = this.data && this.bounds ? this.data.positions : boxCorners(this.bedBox);
    // At most ~300k points: enough to frame, fast at 2M segments.
    const step = 3 * Math.max(1, Math.ceil(points.length / 3 / 300000));
    const box = this.bounds ?? this.bedBox;
    const center = box.getCenter(new THREE.Vector3());
    let dist = 0;
    for (let pass = 0; pass < 2; pass++) {
      // Distance that fits every point: |x| ≤ tanX · depth, |y| ≤ tanY · depth, depth = dist - z.
      dist = 0;
      const cx = center.x, cy = center.y, cz = center.z;
      for (let i = 0; i < points.length; i += step) {
        const px = points[i] - cx, py = points[i + 1] - cy, pz = points[i + 2] - cz;
        const x = px * right.x + py * right.y + pz * right.z;
        const y = px * up.x + py * up.y + pz * up.z;
        const z = px * back.x + py * back.y + pz * back.z;
        const need = Math.max(Math.abs(x) / tanX, Math.abs(y) / tanY) + z;
        if (need > dist) dist = need;
      }
      if (pass === 1) break;
      // Centre the projection: shift the target by the middle of the projected extent.
      let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
      for (let i = 0; i < points.length; i += step) {
        const px = points[i] - cx, py = points[i + 1] - cy, pz = points[i + 2] - cz;
        const depth = dist - (px * back.x + py * back.y + pz * back.z);
        const x = (px * right.x + py * right.y + pz * right.z) / depth;
        const y = (px * up.x + py * up.y + pz * up.z) / depth;
        if (x < x0) x0 = x;
        if (x > x1) x1 = x;
        if (y < y0) y0 = y;
        if (y > y1) y1 = y;
      }
      center.addScaledVector(right, ((x0 + x1) / 2) * dist).addScaledVector(up, ((y0 + y1) / 2) * dist);
    }
    // Centre of the free band, in the canvas's [-1, 1] vertical: move the target so the part
    // sits there (a positive offset moves the picture up).
    const shift = bottom - top;
    center.addScaledVector(up, -shift * tanHalf * dist);
    const radius = (this.sphere ?? this.bedSphere).radius;
    dist = Math.max(dist, radius * 0.05, 1);
    this.controls.minDistance = Math.max(0.05, radius * 0.02);
    this.controls.maxDistance = Math.max(dist, radius / Math.sin((cam.fov * Math.PI) / 360)) * 6;
    cam.position.copy(center).addScaledVector(back, dist);
    this.controls.target.copy(center);
    this.controls.update();
    this.autoFit = true;
    this.requestRender();
  }

  /**
   * Fractions of the canvas height covered by the controls drawn over it: from the top (the
   * view controls) and from the bottom (legend, camera buttons). Zero when they are not laid
   * out (hidden page, tests without the controls).
   */
  overlayBands() {
    const c = this.canvas.getBoundingClientRect();
    if (!(c.height > 0)) return { top: 0, bottom: 0 };
    const topEl = this.ui.colorBy?.closest(".view-controls");
    const bottomEls = [this.ui.legend, this.ui.camera].filter(Boolean);
    let top = 0;
    let bottom = 0;
    const t = topEl?.getBoundingClientRect();
    if (t && t.height > 0) top = Math.max(0, t.bottom - c.top);
    for (const el of bottomEls) {
      const r = el.getBoundingClientRect();
      if (r.height > 0 && r.top > c.top + c.height / 2) bottom = Math.max(bottom, c.bottom - r.top);
    }
    // Each band at most a third of the canvas: a tall overlay still leaves the part room.
    return { top: Math.min(top / c.height, 1 / 3), bottom: Math.min(bottom / c.height, 1 / 3) };
  }

  /**
   * A camera view: "fit" frames the part from where the camera looks now; "top", "front" and
   * "iso" look from that side, then frame the part.
   * @param {"fit"|"top"|"front"|"iso"} which
   */
  view(which) {
    const dir = VIEWS[which];
    if (dir) this.camera.position.copy(this.controls.target).add(dir);
    this.fit();
  }

  /**
   * Near and far planes from the part's bounding sphere and the camera's distance to it (the
   * plate is kept inside the far plane), the depth range of the line shading and the size of a
   * pixel for the tubes' minimum width. Called before every frame, so after every camera change.
   */
  updateClipping() {
    const cam = this.camera;
    const part = this.sphere ?? this.bedSphere;
    cam.updateMatrixWorld();
    const d = cam.position.distanceTo(part.center);
    const r = part.radius * 1.02 + 2 * DEFAULT_WIDTH;
    const near = Math.max(d * 0.002, Math.min(d - r, d * 0.05), 1e-4);
    const far = Math.max(d + r, cam.position.distanceTo(this.bedSphere.center) + this.bedSphere.radius) * 1.01;
    if (near !== cam.near || far !== cam.far) {
      cam.near = near;
      cam.far = far;
      cam.updateProjectionMatrix();
    }
    // Depth shading over the part's own depth in this view: the tighter of its box's corners
    // and the sphere round its centre through its farthest point (a ball's depth is its
    // diameter, a flat part seen from the top has almost none).
    const m = cam.matrixWorldInverse.elements;
    const depthOf = (x, y, z) => -(m[2] * x + m[6] * y + m[10] * z + m[14]);
    const c = part.center;
    const shade = this.sphere ? this.shadeRadius : part.radius;
    let front = depthOf(c.x, c.y, c.z) - shade;
    let back = front + 2 * shade;
    const b = this.bounds ?? this.bedBox;
    let lo = Infinity, hi = -Infinity;
    for (let i = 0; i < 8; i++) {
      const z = depthOf(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z);
      lo = Math.min(lo, z);
      hi = Math.max(hi, z);
    }
    front = Math.max(front, lo);
    back = Math.min(back, hi);
    this.uniforms.uDepth.value.set(front, Math.max(back - front, 0.1 * shade, 1e-3));
    const height = this.renderer.getDrawingBufferSize(this.tmp2 ??= new THREE.Vector2()).y || 1;
    this.uniforms.uPixel.value = (2 * Math.tan((cam.fov * Math.PI) / 360)) / height;
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

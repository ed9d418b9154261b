// The preview's drawing on the GPU: the shaders that draw every extrusion segment as a shaded
// tube or a lit line, pulling the segment's ends, width and colour from data textures by
// vertex index (see preview.js's header), the textures and geometry they read, the path-start
// dot, and the segment counts over which lines are drawn instead of tubes.
import * as THREE from "./vendor/three.module.js";

/**
 * Over this many extrusion segments the preview draws lines (lit by their direction, darker
 * with depth) while the camera moves, and tubes again once it rests (REST_MS): the count where
 * orbiting tubes drops under 10 frames a second in headless Chromium with SwiftShader
 * (tests/e2e/preview-bench.mjs; ARCHITECTURE.md, "The 3D preview"). `setStyle` overrides it.
 */
export const TUBE_LIMIT = 10000;
/** Over this many segments, lines at rest too: one frame of tubes takes over a second there. */
export const STILL_TUBE_LIMIT = 150000;

/** Tube width (mm) when the result has no width per segment. */
export const DEFAULT_WIDTH = 0.45;

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
export const TUBE_VERTEX = /* glsl */ `${SEGMENT_DATA}
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
export const TUBE_FRAGMENT = /* glsl */ `${LIGHTS}
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
export const LINE_VERTEX = /* glsl */ `${SEGMENT_DATA}${LIGHTS}
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
export const LINE_FRAGMENT = /* glsl */ `
varying vec3 vColor;
void main() {
  gl_FragColor = vec4(vColor, 1.0);
}
`;

/** A geometry without attributes: the shaders pull segments by vertex index; drawRange picks them. */
export function segmentGeometry() {
  const g = new THREE.BufferGeometry();
  g.setDrawRange(0, 0);
  g.boundingSphere = new THREE.Sphere(new THREE.Vector3(), 1e9); // never culled or sorted by it
  return g;
}

/** A data texture of `texels` texels (TEX_WIDTH wide), `channels` RGBA values each. */
export function segmentTexture(data, texels, type) {
  const t = new THREE.DataTexture(data, TEX_WIDTH, Math.max(1, Math.ceil(texels / TEX_WIDTH)), THREE.RGBAFormat, type);
  t.minFilter = t.magFilter = THREE.NearestFilter;
  t.generateMipmaps = false;
  t.colorSpace = THREE.NoColorSpace;
  t.needsUpdate = true;
  return t;
}

/** Room for `texels` texels, RGBA, in a TEX_WIDTH-wide texture. */
export function textureArray(Type, texels) {
  return new Type(Math.max(1, Math.ceil(texels / TEX_WIDTH)) * TEX_WIDTH * 4);
}

/** A round white dot (alpha) for the path-start markers. */
export function dotTexture() {
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

// The preview's plate and camera: the build plate drawn for the printer's bed, framing the
// part from the current view direction (Fit, Top, Front, Iso), the bands of the canvas the
// page's controls cover, and the near and far planes and depth shading range kept around the
// part on every frame. The functions take the Preview `p` (preview.js), whose methods of the
// same names call them.
import * as THREE from "./vendor/three.module.js";
import { DEFAULT_WIDTH } from "./preview-gl.js";

/** Fit: the part's projection spans this fraction of the canvas in its limiting direction. */
const FILL = 0.86;
/** Directions from the target to the camera of the camera buttons (z up). */
export const VIEWS = {
  iso: new THREE.Vector3(-0.55, -1, 0.75).normalize(),
  top: new THREE.Vector3(0, -1e-3, 1).normalize(), // a hair to the front: +y is up on screen
  front: new THREE.Vector3(0, -1, 0),
};

/** Distance from `c` to the farthest of (about 300k of) the points x y z … */
export function farthestFrom(c, p) {
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

/** Draws the build plate: outline, 10 mm grid, origin axes. */
export function setBed(p, bed, origin) {
  const [bx, by] = bed;
  const key = `${bx}x${by}:${origin}`;
  if (key === p.bedKey) return;
  p.bedKey = key;
  for (const child of p.plate.children) child.geometry.dispose();
  p.plate.clear();
  const x0 = origin === "center" ? -bx / 2 : 0;
  const y0 = origin === "center" ? -by / 2 : 0;
  p.bedBox = new THREE.Box3(new THREE.Vector3(x0, y0, 0), new THREE.Vector3(x0 + bx, y0 + by, Math.min(bx, by) * 0.25));
  p.bedSphere = p.bedBox.getBoundingSphere(new THREE.Sphere());

  const grid = [];
  for (let x = Math.ceil(x0 / 10) * 10; x <= x0 + bx; x += 10) grid.push(x, y0, 0, x, y0 + by, 0);
  for (let y = Math.ceil(y0 / 10) * 10; y <= y0 + by; y += 10) grid.push(x0, y, 0, x0 + bx, y, 0);
  p.plate.add(lines(grid, 0x3a414d));
  p.plate.add(lines([x0, y0, 0, x0 + bx, y0, 0, x0 + bx, y0, 0, x0 + bx, y0 + by, 0,
    x0 + bx, y0 + by, 0, x0, y0 + by, 0, x0, y0 + by, 0, x0, y0, 0], 0x8a93a3));
  // Origin: X red, Y green, Z blue, drawn over the plate lines.
  const a = Math.max(5, Math.min(bx, by) * 0.08);
  for (const [flat, color] of [[[0, 0, 0, a, 0, 0], 0xff5a5f], [[0, 0, 0, 0, a, 0], 0x4cc76a], [[0, 0, 0, 0, 0, a], 0x5b8cff]]) {
    const axis = lines(flat, color);
    axis.material.depthTest = false;
    axis.renderOrder = 1;
    p.plate.add(axis);
  }
  const plane = new THREE.Mesh(
    new THREE.PlaneGeometry(bx, by),
    new THREE.MeshBasicMaterial({ color: 0x262b33, side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 }),
  );
  plane.position.set(x0 + bx / 2, y0 + by / 2, -0.01);
  p.plate.add(plane);
}

/**
 * Frames the part (the plate when there is none) from the camera's current direction: the
 * camera looks at the centre of the part's projection, at the distance where the part's
 * points span FILL of the canvas in its limiting direction.
 */
export function fit(p) {
  const cam = p.camera;
  const back = cam.position.clone().sub(p.controls.target);
  if (back.lengthSq() < 1e-12) back.copy(VIEWS.iso);
  back.normalize();
  const right = new THREE.Vector3(0, 0, 1).cross(back);
  if (right.lengthSq() < 1e-12) right.set(1, 0, 0);
  right.normalize();
  const up = back.clone().cross(right);
  // The controls drawn over the canvas (top row(s), legend and camera buttons at the bottom)
  // cover bands of it: frame the part in the band between them.
  const { top, bottom } = p.overlayBands();
  const free = Math.max(0.3, 1 - top - bottom);
  const tanHalf = Math.tan((cam.fov * Math.PI) / 360);
  const tanY = tanHalf * FILL * free;
  const tanX = tanHalf * FILL * cam.aspect;
  const points = p.data && p.bounds ? p.data.positions : boxCorners(p.bedBox);
  // At most ~300k points: enough to frame, fast at 2M segments.
  const step = 3 * Math.max(1, Math.ceil(points.length / 3 / 300000));
  const box = p.bounds ?? p.bedBox;
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
  const radius = (p.sphere ?? p.bedSphere).radius;
  dist = Math.max(dist, radius * 0.05, 1);
  p.controls.minDistance = Math.max(0.05, radius * 0.02);
  p.controls.maxDistance = Math.max(dist, radius / Math.sin((cam.fov * Math.PI) / 360)) * 6;
  cam.position.copy(center).addScaledVector(back, dist);
  p.controls.target.copy(center);
  p.controls.update();
  p.autoFit = true;
  p.requestRender();
}

/**
 * Fractions of the canvas height covered by the controls drawn over it: from the top (the
 * view controls) and from the bottom (legend, camera buttons). Zero when they are not laid
 * out (hidden page, tests without the controls).
 */
export function overlayBands(p) {
  const c = p.canvas.getBoundingClientRect();
  if (!(c.height > 0)) return { top: 0, bottom: 0 };
  const topEl = p.ui.colorBy?.closest(".view-controls");
  const bottomEls = [p.ui.legend, p.ui.camera].filter(Boolean);
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
export function view(p, which) {
  const dir = VIEWS[which];
  if (dir) p.camera.position.copy(p.controls.target).add(dir);
  p.fit();
}

/**
 * Near and far planes from the part's bounding sphere and the camera's distance to it (the
 * plate is kept inside the far plane), the depth range of the line shading and the size of a
 * pixel for the tubes' minimum width. Called before every frame, so after every camera change.
 */
export function updateClipping(p) {
  const cam = p.camera;
  const part = p.sphere ?? p.bedSphere;
  cam.updateMatrixWorld();
  const d = cam.position.distanceTo(part.center);
  const r = part.radius * 1.02 + 2 * DEFAULT_WIDTH;
  const near = Math.max(d * 0.002, Math.min(d - r, d * 0.05), 1e-4);
  const far = Math.max(d + r, cam.position.distanceTo(p.bedSphere.center) + p.bedSphere.radius) * 1.01;
  if (near !== cam.near || far !== cam.far) {
    cam.near = near;
    cam.far = far;
    cam.updateProjectionMatrix();
  }
  // Depth shading over the part's own depth in p view: the tighter of its box's corners
  // and the sphere round its centre through its farthest point (a ball's depth is its
  // diameter, a flat part seen from the top has almost none).
  const m = cam.matrixWorldInverse.elements;
  const depthOf = (x, y, z) => -(m[2] * x + m[6] * y + m[10] * z + m[14]);
  const c = part.center;
  const shade = p.sphere ? p.shadeRadius : part.radius;
  let front = depthOf(c.x, c.y, c.z) - shade;
  let back = front + 2 * shade;
  const b = p.bounds ?? p.bedBox;
  let lo = Infinity, hi = -Infinity;
  for (let i = 0; i < 8; i++) {
    const z = depthOf(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z);
    lo = Math.min(lo, z);
    hi = Math.max(hi, z);
  }
  front = Math.max(front, lo);
  back = Math.min(back, hi);
  p.uniforms.uDepth.value.set(front, Math.max(back - front, 0.1 * shade, 1e-3));
  const height = p.renderer.getDrawingBufferSize(p.tmp2 ??= new THREE.Vector2()).y || 1;
  p.uniforms.uPixel.value = (2 * Math.tan((cam.fov * Math.PI) / 360)) / height;
}

function lines(flat, color) {
  const g = new THREE.BufferGeometry();
  g.setAttribute("position", new THREE.Float32BufferAttribute(flat, 3));
  return new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color }));
}

/** Bounding box of x0 y0 z0 x1 y1 z1 segments. */
export function boundsOf(p) {
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

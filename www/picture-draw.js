// The drawing parts of a picture (pictures.js): the caption band under it (laid out once,
// drawn on a canvas or written as SVG text), a lines2d view as SVG vector paths (the same fit,
// colours and scale bar as views.js draws on a canvas), and text chunks put into a PNG.
// No state of its own.
import { OTHER_COLOR, TEXT } from "./views.js";

const FONT = "system-ui, -apple-system, 'Segoe UI', Roboto, sans-serif";

export function escapeXml(s) {
  return String(s).replace(/[<>&"']/g, (c) => ({ "<": "&lt;", ">": "&gt;", "&": "&amp;", '"': "&quot;", "'": "&apos;" })[c]);
}

/**
 * Lays out the caption band of a W × H picture: the title, the caption lines wrapped to the
 * width, and the legend's swatches; at most 40 % of the height (the rest is cut with "…").
 * @returns {{height: number, items: Array<Object>}} items at y from the band's top
 */
export function layoutBand(ctx, W, H, cap, legend) {
  const fs = Math.max(12, Math.min(44, Math.round(Math.min(W / 70, H / 40))));
  const pad = Math.round(fs * 0.8);
  const lineH = Math.round(fs * 1.35);
  const maxH = Math.floor(H * 0.4);
  const items = [];
  let y = pad;
  const fits = () => y + lineH + pad <= maxH;
  const text = (t, bold, muted) => {
    const font = `${bold ? "600 " : ""}${bold ? Math.round(fs * 1.1) : fs}px ${FONT}`;
    ctx.font = font;
    for (const line of wrap(ctx, t, W - 2 * pad)) {
      if (!fits()) {
        if (items.length) items[items.length - 1].text = `${items[items.length - 1].text.replace(/…$/, "")}…`;
        return false;
      }
      items.push({ kind: "text", text: line, x: pad, y: y + fs, font, size: bold ? Math.round(fs * 1.1) : fs, bold, muted });
      y += lineH;
    }
    return true;
  };
  if (cap.title && text(cap.title, true, false)) for (const l of cap.lines) if (!text(l, false, true)) break;
  if (legend.length && fits()) {
    const ls = Math.round(fs * 0.9);
    const font = `${ls}px ${FONT}`;
    ctx.font = font;
    let x = pad;
    for (const e of legend) {
      const sw = e.color ? Math.round(ls * 0.8) + Math.round(ls * 0.4) : 0;
      const width = sw + ctx.measureText(e.text).width;
      if (x > pad && x + width > W - pad) {
        y += lineH;
        x = pad;
        if (!fits()) break;
      }
      if (e.color) items.push({ kind: "swatch", x, y: y + Math.round(ls * 0.25), size: Math.round(ls * 0.8), color: e.color });
      items.push({ kind: "text", text: e.text, x: x + sw, y: y + ls, font, size: ls, muted: false });
      x += width + ls * 1.5;
    }
    y += lineH;
  }
  return { height: items.length ? y + pad - Math.round(lineH - fs) : 0, items, fs };
}

/** Words of `text` in lines no wider than `width` (a word wider than that stays whole). */
function wrap(ctx, text, width) {
  const lines = [];
  let line = "";
  for (const word of text.split(" ")) {
    const next = line ? `${line} ${word}` : word;
    if (line && ctx.measureText(next).width > width) {
      lines.push(line);
      line = word;
    } else line = next;
  }
  if (line) lines.push(line);
  return lines;
}

const colors = (dark) => ({ band: dark ? "#171a20" : "#f4f5f7", text: dark ? TEXT : "#1c2026", muted: dark ? "#aab2bf" : "#5f6873", rule: dark ? "#3a414d" : "#d9dde3" });

/** Draws the band laid out by layoutBand at y0 (the picture's height above it). */
export function drawBand(ctx, band, y0, W, dark) {
  if (!band.height) return;
  const c = colors(dark);
  ctx.fillStyle = c.band;
  ctx.fillRect(0, y0, W, band.height);
  ctx.fillStyle = c.rule;
  ctx.fillRect(0, y0, W, Math.max(1, Math.round(band.fs / 12)));
  ctx.textBaseline = "alphabetic";
  ctx.textAlign = "left";
  for (const it of band.items) {
    if (it.kind === "swatch") {
      ctx.fillStyle = it.color;
      ctx.fillRect(it.x, y0 + it.y, it.size, it.size);
    } else {
      ctx.font = it.font;
      ctx.fillStyle = it.muted ? c.muted : c.text;
      ctx.fillText(it.text, it.x, y0 + it.y);
    }
  }
}

/** The band as SVG elements (text as <text>, swatches as <rect>). */
export function bandSvg(band, y0, W, dark) {
  if (!band.height) return "";
  const c = colors(dark);
  const parts = [`<g class="caption"><rect x="0" y="${y0}" width="${W}" height="${band.height}" fill="${c.band}"/>`,
    `<rect x="0" y="${y0}" width="${W}" height="${Math.max(1, Math.round(band.fs / 12))}" fill="${c.rule}"/>`];
  for (const it of band.items) {
    if (it.kind === "swatch") parts.push(`<rect x="${it.x}" y="${y0 + it.y}" width="${it.size}" height="${it.size}" fill="${escapeXml(it.color)}"/>`);
    else parts.push(`<text x="${it.x}" y="${y0 + it.y}" font-family="${escapeXml(FONT)}" font-size="${it.size}"${it.bold ? ' font-weight="600"' : ""} fill="${it.muted ? c.muted : c.text}">${escapeXml(it.text)}</text>`);
  }
  parts.push("</g>");
  return parts.join("");
}

/**
 * A lines2d answer (stride 5: x0 y0 x1 y1 code, mm) as SVG: one <path> per colour, fitted into
 * w × h with views.js's margin, Y up, with its scale bar (or axis names for other units).
 */
export function segmentsSvg(answer, styles, w, h, scale) {
  const s = answer.data;
  const stride = answer.stride || 5;
  const n = Math.floor((s?.length ?? 0) / stride);
  if (!n) return "";
  const box = [Infinity, Infinity, -Infinity, -Infinity];
  for (let i = 0; i < n * stride; i += stride) {
    for (const k of [0, 2]) {
      box[0] = Math.min(box[0], s[i + k]);
      box[2] = Math.max(box[2], s[i + k]);
      box[1] = Math.min(box[1], s[i + k + 1]);
      box[3] = Math.max(box[3], s[i + k + 1]);
    }
  }
  const margin = 8 * scale;
  const spanX = Math.max(box[2] - box[0], 1e-6);
  const spanY = Math.max(box[3] - box[1], 1e-6);
  const k = Math.min((w - 2 * margin) / spanX, (h - 2 * margin) / spanY);
  const ox = (w - spanX * k) / 2 - box[0] * k;
  const oy = (h + spanY * k) / 2 + box[1] * k;
  const f = (v) => (Math.round(v * 100) / 100).toString();
  const byColor = new Map();
  for (let i = 0; i < n * stride; i += stride) {
    const code = stride > 4 ? s[i + 4] : -1;
    const color = styles.get(code)?.color ?? OTHER_COLOR;
    if (!byColor.has(color)) byColor.set(color, []);
    byColor.get(color).push(`M${f(ox + s[i] * k)} ${f(oy - s[i + 1] * k)}L${f(ox + s[i + 2] * k)} ${f(oy - s[i + 3] * k)}`);
  }
  const parts = [`<g class="lines" fill="none" stroke-width="${f(1.25 * scale)}" stroke-linecap="round">`];
  for (const [color, d] of byColor) parts.push(`<path stroke="${escapeXml(color)}" d="${d.join("")}"/>`);
  parts.push("</g>");
  const m = answer.meta ?? {};
  const font = `font-family="${escapeXml(FONT)}" font-size="${f(11 * scale)}" fill="${TEXT}"`;
  if (m.x_label && m.y_label) {
    const v = (x) => String(Number(x.toPrecision(3)));
    parts.push(`<text x="${f(8 * scale)}" y="${f(h - 4 * scale)}" ${font}>${escapeXml(`${m.x_label}: ${v(box[0])} … ${v(box[2])}`)}</text>`);
    parts.push(`<text x="${f(8 * scale)}" y="${f(4 * scale + 11 * scale)}" ${font}>${escapeXml(`${m.y_label}: ${v(box[1])} … ${v(box[3])}`)}</text>`);
  } else if (m.scale_bar !== false) {
    const target = (w * 0.2) / k;
    const p = 10 ** Math.floor(Math.log10(target));
    const len = [5, 2, 1].map((q) => q * p).find((q) => q <= target) ?? p;
    const x1 = w - 8 * scale;
    const y = h - 8 * scale;
    parts.push(`<g class="scale-bar"><line x1="${f(x1 - len * k)}" y1="${f(y)}" x2="${f(x1)}" y2="${f(y)}" stroke="${TEXT}" stroke-width="${f(2 * scale)}"/>`);
    parts.push(`<text x="${f(x1)}" y="${f(y - 3 * scale)}" text-anchor="end" ${font}>${Number(len.toPrecision(3))} mm</text></g>`);
  }
  return parts.join("");
}

// --- PNG text chunks ---------------------------------------------------------------------
const CRC_TABLE = (() => {
  const t = new Uint32Array(256);
  for (let n = 0; n < 256; n++) {
    let c = n;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    t[n] = c >>> 0;
  }
  return t;
})();

function crc32(bytes) {
  let c = 0xffffffff;
  for (const b of bytes) c = CRC_TABLE[(c ^ b) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

/** The PNG `blob` with an iTXt chunk (UTF-8 text) per entry, after its header chunk. */
export async function withPngText(blob, entries) {
  const png = new Uint8Array(await blob.arrayBuffer());
  const enc = new TextEncoder();
  const chunks = Object.entries(entries).filter(([, v]) => v).map(([key, value]) => {
    const data = new Uint8Array([...enc.encode(key), 0, 0, 0, 0, 0, ...enc.encode(value)]);
    const out = new Uint8Array(12 + data.length);
    const view = new DataView(out.buffer);
    view.setUint32(0, data.length);
    out.set(enc.encode("iTXt"), 4);
    out.set(data, 8);
    view.setUint32(8 + data.length, crc32(out.subarray(4, 8 + data.length)));
    return out;
  });
  const at = 8 + 25; // signature, then IHDR (13 bytes of data in a 25-byte chunk)
  return new Blob([png.subarray(0, at), ...chunks, png.subarray(at)], { type: "image/png" });
}

// Pictures for slides: every view card, every report plot and the 3D preview saves as PNG or
// SVG at a chosen size, captioned with the design's name and the settings that differ from
// its job kind's defaults (picture-caption.js). A "Picture…" button is added to each view
// card, plot and the preview's camera row (by watching #views and #report, so no card knows
// about it); it opens one dialog: size (presets for slides), format, caption.
//   PNG  the view redrawn at the size into an offscreen canvas (views.js drawers, the preview
//        rendered at the size), the caption band under it, with the caption as PNG text.
//   SVG  a plot as its own SVG; a lines2d view as vector paths (segmentsSvg); a 3D, image or
//        mesh view and the preview as the PNG embedded in an <image> with the caption as text.
// File names: <design-name>-<view-id>-<w>x<h>.png|svg. The last size and format chosen are
// kept in localStorage; the dialog is built once, on first use (`dialogParts`).
import { state } from "./state.js";
import { $, download, messageOf } from "./util.js";
import { BACKGROUND, drawView } from "./views.js";
import { captionOf } from "./picture-caption.js";
import { stepAsView } from "./steps.js";
import { layoutBand, bandSvg, drawBand, escapeXml, segmentsSvg, withPngText } from "./picture-draw.js";

const PRESETS = [
  ["1600×1000 (default)", 1600, 1000],
  ["Slide 16:9, 1920×1080", 1920, 1080],
  ["Slide 16:9 HD, 1280×720", 1280, 720],
  ["Slide 4:3, 1600×1200", 1600, 1200],
  ["Square, 1080×1080", 1080, 1080],
  ["4K, 3840×2160", 3840, 2160],
];
const MIN_PX = 200;
const MAX_PX = 4096;
const STORE_KEY = "weft.picture";
const PLOT_BACKGROUND = "#ffffff";

/** Adds the Picture… buttons now and whenever the views, plots or preview are drawn anew. */
export function installPictures() {
  const decorate = () => {
    for (const head of document.querySelectorAll("#views .view-card > .card-head")) {
      if (head.querySelector(".picture-button")) continue;
      const card = head.closest(".view-card");
      head.append(pictureButton("Save this view as a picture (PNG or SVG) at a chosen size, captioned", () => ({ type: "view", card })));
    }
    const nav = document.querySelector("#how .how-nav");
    if (nav && !nav.querySelector(".picture-button")) {
      nav.append(pictureButton("Save this step's view as a picture (PNG or SVG) at a chosen size, captioned", () => ({ type: "step" })));
    }
    for (const fig of document.querySelectorAll("#report figure.plot-figure")) {
      if (fig.querySelector(":scope > .picture-button")) continue;
      fig.append(pictureButton("Save this plot as a picture (PNG or SVG) at a chosen size, captioned", () => ({ type: "plot", fig })));
    }
  };
  for (const id of ["views", "report", "how"]) new MutationObserver(decorate).observe($(id), { childList: true, subtree: true });
  decorate();
  $("camera-views")?.append(pictureButton("Save the preview as a picture (PNG, or SVG embedding the PNG) at a chosen size, captioned", () => ({ type: "preview" })));
}

function pictureButton(title, target) {
  const b = document.createElement("button");
  b.type = "button";
  b.className = "picture-button";
  b.textContent = "Picture…";
  b.title = title;
  b.setAttribute("aria-haspopup", "dialog");
  b.addEventListener("click", () => openDialog(target()));
  return b;
}

// ---------------------------------------------------------------------------------------
// What a picture is of: {id, label, design, background, legend, vector?, raster?, svgNote}
// ---------------------------------------------------------------------------------------
/** The picture source of a target ({type: "view"|"plot"|"preview", …}); throws a plain sentence. */
export function sourceOf(target) {
  const resultDesign = () => {
    const r = state.result;
    if (!r) return null;
    return r.json ? JSON.parse(r.json) : { name: r.fileName, gcodeFile: r.fileName };
  };
  if (target.type === "view" || target.type === "step") {
    const v = target.type === "step" ? stepAsView() : state.viewCards.get(target.card.dataset.view);
    if (!v?.last || !v.last.data?.length) throw new Error("This view has nothing drawn yet: wait until it shows, then save its picture.");
    const answer = v.last;
    return {
      id: v.view.id, label: v.view.label ?? v.view.id, design: state.design, background: BACKGROUND, dark: true,
      legend: legendOf(v.legend),
      raster: (w, h, scale) => {
        const canvas = document.createElement("canvas");
        canvas.picture = { width: w, height: h, scale };
        drawView(canvas, answer, state.styles);
        return canvas;
      },
      vector: answer.shape === "lines2d" ? (w, h, scale) => segmentsSvg(answer, state.styles, w, h, scale) : null,
    };
  }
  if (target.type === "plot") {
    const svg = target.fig.querySelector("svg.plot");
    if (!svg) throw new Error("This plot is not drawn: run the design again, then save its picture.");
    const title = target.fig.querySelector("figcaption")?.textContent ?? svg.getAttribute("aria-label") ?? "plot";
    return {
      id: svg.dataset.plotKey || slug(title), label: title, design: resultDesign(), background: PLOT_BACKGROUND, dark: false,
      legend: [], vector: (w, h) => plotSvg(svg, w, h),
    };
  }
  const p = state.preview;
  if (!p) throw new Error("The 3D preview did not start in this browser, so it has no picture; the views and plots still save.");
  if (!p.segmentCount()) throw new Error("The preview shows no toolpath yet: run the design (or drop a G-code), then save its picture.");
  return {
    id: "preview", label: "3D toolpath preview", design: resultDesign(), background: BACKGROUND, dark: true,
    legend: legendOf($("legend")), raster: (w, h) => renderPreview(p, w, h),
  };
}

/** Swatches and words of a legend element (the preview's or a view card's). */
function legendOf(el) {
  if (!el) return [];
  return [...el.children].map((item) => {
    const sw = item.querySelector(".swatch, .ramp");
    const color = sw?.classList.contains("ramp") ? null : sw?.style.background || null;
    return { color, text: item.textContent.trim().replace(/\s+/g, " ") };
  }).filter((e) => e.text);
}

/** Renders the preview at w × h (device pixels): the camera as on screen, refitted when the user has not moved it. */
function renderPreview(p, w, h) {
  const saved = {
    pos: p.camera.position.clone(), target: p.controls.target.clone(), fov: p.camera.fov, aspect: p.camera.aspect,
    autoFit: p.autoFit, min: p.controls.minDistance, max: p.controls.maxDistance, ratio: p.renderer.getPixelRatio(),
  };
  const out = document.createElement("canvas");
  out.width = w;
  out.height = h;
  try {
    p.renderer.setPixelRatio(1);
    p.renderer.setSize(w, h, false);
    p.camera.aspect = w / h;
    if (saved.autoFit) {
      p.overlayBands = () => ({ top: 0, bottom: 0 }); // nothing covers a picture
      p.fit();
    } else if (w / h < saved.aspect) {
      // Narrower than the screen: widen the field so what the screen shows across still fits.
      const t = Math.tan((saved.fov * Math.PI) / 360) * (saved.aspect / (w / h));
      p.camera.fov = (Math.atan(t) * 360) / Math.PI;
    }
    p.camera.updateProjectionMatrix();
    p.drawFrame();
    out.getContext("2d").drawImage(p.renderer.domElement, 0, 0, w, h);
  } finally {
    delete p.overlayBands;
    p.camera.position.copy(saved.pos);
    p.controls.target.copy(saved.target);
    p.camera.fov = saved.fov;
    p.camera.aspect = saved.aspect;
    p.camera.updateProjectionMatrix();
    p.controls.minDistance = saved.min;
    p.controls.maxDistance = saved.max;
    p.controls.update();
    p.autoFit = saved.autoFit;
    p.renderer.setPixelRatio(saved.ratio);
    p.resize();
    p.requestRender();
  }
  return out;
}

/** The plot's SVG content at w × h: a copy with the page's styles written on each element. */
function plotSvg(svg, w, h) {
  const copy = svg.cloneNode(true);
  copy.querySelectorAll(".plot-hover").forEach((e) => e.remove());
  const props = ["fill", "stroke", "stroke-width", "stroke-dasharray", "stroke-linecap", "stroke-linejoin", "opacity",
    "font-size", "font-family", "font-weight", "paint-order", "text-anchor", "dominant-baseline"];
  const live = [...svg.querySelectorAll("*")].filter((e) => !e.closest(".plot-hover"));
  const copies = [...copy.querySelectorAll("*")];
  live.forEach((el, i) => {
    const cs = getComputedStyle(el);
    copies[i]?.setAttribute("style", props.map((k) => `${k}:${cs.getPropertyValue(k)}`).join(";"));
  });
  const root = getComputedStyle(svg);
  const inner = [...copy.childNodes].map((n) => new XMLSerializer().serializeToString(n)).join("");
  const m = Math.round(Math.min(w, h) * 0.03); // the plot's legend and labels reach its edges
  return `<svg x="${m}" y="${m}" width="${w - 2 * m}" height="${h - 2 * m}" viewBox="${svg.getAttribute("viewBox") ?? "0 0 360 200"}" ` +
    `style="font-family:${escapeXml(root.fontFamily)};font-size:${root.fontSize}">${inner.replace(/ xmlns="http:\/\/www\.w3\.org\/2000\/svg"/g, "")}</svg>`;
}

// ---------------------------------------------------------------------------------------
// Making the files
// ---------------------------------------------------------------------------------------
/**
 * The picture of `source` as a file: {blob, name, caption}.
 * @param {{format: "png"|"svg", width: number, height: number, caption?: boolean}} opts
 */
export async function makePicture(source, { format, width: W, height: H, caption = true }) {
  const cap = caption ? captionOf(source.design, source.label) : { title: "", lines: [] };
  const measure = document.createElement("canvas").getContext("2d");
  const band = layoutBand(measure, W, H, cap, caption ? source.legend : []);
  const h = H - band.height;
  const scale = Math.max(1, Math.min(4, Math.min(W / 800, h / 500)));
  const name = `${fileSafe(source.design?.name ?? "weft")}-${fileSafe(source.id)}-${W}x${H}.${format}`;
  const text = [cap.title, ...cap.lines].filter(Boolean).join("\n");
  if (format === "svg") {
    let body = source.vector?.(W, h, scale);
    if (!body) {
      const png = source.raster(W, h, scale).toDataURL("image/png");
      body = `<image x="0" y="0" width="${W}" height="${h}" href="${png}"/>`;
    }
    const svg = svgDocument(W, H, source.background, body, bandSvg(band, h, W, source.dark), text);
    return { blob: new Blob([svg], { type: "image/svg+xml" }), name, caption: text };
  }
  const out = document.createElement("canvas");
  out.width = W;
  out.height = H;
  const ctx = out.getContext("2d");
  ctx.fillStyle = source.background;
  ctx.fillRect(0, 0, W, H);
  const area = source.raster ? source.raster(W, h, scale) : await svgToCanvas(svgDocument(W, h, source.background, source.vector(W, h, scale), "", ""), W, h);
  ctx.drawImage(area, 0, 0);
  drawBand(ctx, band, h, W, source.dark);
  const blob = await new Promise((resolve) => out.toBlob(resolve, "image/png"));
  if (!blob) throw new Error(`This browser could not make a ${W} × ${H} PNG: try a smaller size.`);
  return { blob: await withPngText(blob, { Title: cap.title || source.label, Description: text, Software: "weft" }), name, caption: text };
}

function svgDocument(W, H, background, body, band, text) {
  return `<?xml version="1.0" encoding="UTF-8"?>\n<svg xmlns="http://www.w3.org/2000/svg" width="${W}" height="${H}" viewBox="0 0 ${W} ${H}">` +
    (text ? `<title>${escapeXml(text)}</title>` : "") +
    `<rect width="${W}" height="${H}" fill="${background}"/>${body}${band}</svg>\n`;
}

/** Rasterises an SVG document into a w × h canvas. */
async function svgToCanvas(svg, w, h) {
  const url = URL.createObjectURL(new Blob([svg], { type: "image/svg+xml" }));
  try {
    const img = new Image();
    img.src = url;
    await img.decode();
    const c = document.createElement("canvas");
    c.width = w;
    c.height = h;
    c.getContext("2d").drawImage(img, 0, 0, w, h);
    return c;
  } finally {
    URL.revokeObjectURL(url);
  }
}

/** A name as the G-code download names it (design.js's designName): characters no file system takes become "_". */
const fileSafe = (s) => String(s).trim().replace(/[\\/:*?"<>|\u0000-\u001f]+/g, "_").slice(0, 80) || "weft";
const slug = (s) => String(s).toLowerCase().replace(/[^a-z0-9]+/g, "-").replace(/^-|-$/g, "").slice(0, 40) || "plot";

// ---------------------------------------------------------------------------------------
// The dialog
// ---------------------------------------------------------------------------------------
let dialogParts = null; // built once, on first use

function dialog() {
  if (dialogParts) return dialogParts;
  const d = document.createElement("dialog");
  d.id = "picture-dialog";
  d.className = "picture-dialog";
  d.setAttribute("aria-labelledby", "picture-title");
  d.innerHTML = `<form method="dialog" novalidate>
    <h2 id="picture-title">Save picture</h2>
    <p class="picture-what"></p>
    <label class="picture-field">Size
      <select class="picture-preset">${PRESETS.map(([l, w, h]) => `<option value="${w}x${h}">${l}</option>`).join("")}<option value="custom">Custom</option></select>
    </label>
    <div class="picture-size">
      <label>Width <input class="picture-width" type="number" min="${MIN_PX}" max="${MAX_PX}" step="1" inputmode="numeric"></label>
      <span aria-hidden="true">×</span>
      <label>Height <input class="picture-height" type="number" min="${MIN_PX}" max="${MAX_PX}" step="1" inputmode="numeric"></label>
      <span class="hint">px</span>
    </div>
    <fieldset class="picture-format"><legend>Format</legend>
      <label><input type="radio" name="picture-format" value="png" checked> PNG</label>
      <label><input type="radio" name="picture-format" value="svg"> SVG</label>
      <span class="picture-svg-note hint"></span>
    </fieldset>
    <label class="picture-check"><input class="picture-caption-on" type="checkbox" checked> Caption: the design's name and its settings that differ from the defaults</label>
    <p class="picture-caption" aria-live="polite"></p>
    <p class="picture-error" role="alert" hidden></p>
    <div class="picture-buttons">
      <button type="button" class="picture-close">Close</button>
      <button type="submit" class="primary picture-save">Save</button>
    </div>
  </form>`;
  document.body.append(d);
  const q = (sel) => d.querySelector(sel);
  dialogParts = {
    d, what: q(".picture-what"), preset: q(".picture-preset"), width: q(".picture-width"), height: q(".picture-height"),
    svgNote: q(".picture-svg-note"), captionOn: q(".picture-caption-on"), caption: q(".picture-caption"), error: q(".picture-error"),
    save: q(".picture-save"), source: null,
  };
  const p = dialogParts;
  p.preset.addEventListener("change", () => {
    if (p.preset.value === "custom") return;
    const [w, h] = p.preset.value.split("x");
    p.width.value = w;
    p.height.value = h;
  });
  for (const input of [p.width, p.height]) input.addEventListener("input", () => {
    const key = `${p.width.value}x${p.height.value}`;
    p.preset.value = [...p.preset.options].some((o) => o.value === key) ? key : "custom";
  });
  p.captionOn.addEventListener("change", () => showCaption());
  q(".picture-close").addEventListener("click", () => d.close());
  q("form").addEventListener("submit", (e) => { e.preventDefault(); savePicture(); });
  return p;
}

function remembered() {
  try {
    const v = JSON.parse(localStorage.getItem(STORE_KEY) ?? "null");
    if (v && Number.isInteger(v.width) && Number.isInteger(v.height)) return v;
  } catch { /* storage disabled or garbled */ }
  return { width: 1600, height: 1000, format: "png" };
}

function openDialog(target) {
  const p = dialog();
  let source;
  try {
    source = sourceOf(target);
  } catch (err) {
    p.source = null;
    p.what.textContent = "";
    p.caption.textContent = "";
    showDialogError(messageOf(err));
    p.save.disabled = true;
    p.d.showModal();
    return;
  }
  p.source = source;
  p.save.disabled = false;
  p.error.hidden = true;
  const last = remembered();
  p.width.value = String(last.width);
  p.height.value = String(last.height);
  p.width.dispatchEvent(new Event("input"));
  p.d.querySelector(`input[value="${last.format === "svg" ? "svg" : "png"}"]`).checked = true;
  p.what.textContent = `${source.label} · ${source.design?.name ?? "weft"}`;
  p.svgNote.textContent = source.vector ? (target.type === "plot" ? "SVG: the plot as vectors" : "SVG: the lines as vectors")
    : "SVG: the picture embedded as PNG, the caption as text";
  p.d.querySelector('input[value="svg"]').parentElement.title = p.svgNote.textContent;
  showCaption();
  p.d.showModal();
}

function showCaption() {
  const p = dialogParts;
  if (!p.source) return;
  const cap = captionOf(p.source.design, p.source.label);
  p.caption.textContent = p.captionOn.checked ? [cap.title, ...cap.lines].join("\n") : "No caption.";
}

function showDialogError(text) {
  dialogParts.error.textContent = text;
  dialogParts.error.hidden = false;
}

async function savePicture() {
  const p = dialogParts;
  if (!p.source) return;
  const width = p.width.valueAsNumber;
  const height = p.height.valueAsNumber;
  const ok = (v) => Number.isInteger(v) && v >= MIN_PX && v <= MAX_PX;
  if (!ok(width) || !ok(height)) {
    showDialogError(`Width and height must be whole numbers from ${MIN_PX} to ${MAX_PX} px: fix them to save.`);
    return;
  }
  const format = p.d.querySelector('input[name="picture-format"]:checked')?.value === "svg" ? "svg" : "png";
  p.error.hidden = true;
  p.save.disabled = true;
  try {
    const pic = await makePicture(p.source, { format, width, height, caption: p.captionOn.checked });
    download(pic.blob, pic.name, pic.blob.type);
    try {
      localStorage.setItem(STORE_KEY, JSON.stringify({ width, height, format }));
    } catch { /* storage disabled: the choice lasts this visit */ }
    p.d.close();
  } catch (err) {
    showDialogError(/[.:]$|\.\s/.test(messageOf(err)) ? messageOf(err) : `The picture could not be made (${messageOf(err)}): try a smaller size.`);
  } finally {
    p.save.disabled = false;
  }
}

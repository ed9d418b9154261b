// Browser checks of pictures for slides and of comparing two results (issue 45, items 3 and
// 4): a view's PNG decodes at the asked size (its IHDR read here, createImageBitmap in the
// page) with drawn pixels and the caption (band pixels and the PNG's Description text); the
// SVG of a plot and of a lines2d view parse with the asked size, the caption text and their
// line paths; Pin, a changed setting and Run show two previews and one table whose numbers
// are each run's; the comparison's link opened in a fresh page shows the same table. The
// dialog and the comparison are photographed at 1280×800 and 390×844.
//
//   import { picturesChecks } from "./pictures-checks.mjs";
//   await picturesChecks({ newPage, base, check, outDir, first: 70, timeoutMs, weftBin });
import { readFileSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { fileURLToPath } from "node:url";
import { runExample, setFieldUntil, waitResult } from "./page-helpers.mjs";

const ROOT = fileURLToPath(new URL("../..", import.meta.url));

const LATTICE = "honeycomb-10mm.json";

/** Width, height and text chunks (tEXt / iTXt keyword → text) of a PNG file's bytes. */
export function pngInfo(bytes) {
  const sig = [137, 80, 78, 71, 13, 10, 26, 10];
  if (!sig.every((b, i) => bytes[i] === b)) throw new Error("not a PNG (bad signature)");
  if (bytes.toString("latin1", 12, 16) !== "IHDR") throw new Error("the PNG's first chunk is not IHDR");
  const info = { width: bytes.readUInt32BE(16), height: bytes.readUInt32BE(20), text: {} };
  for (let at = 8; at + 8 <= bytes.length;) {
    const len = bytes.readUInt32BE(at);
    const type = bytes.toString("latin1", at + 4, at + 8);
    const data = bytes.subarray(at + 8, at + 8 + len);
    if (type === "tEXt" || type === "iTXt") {
      const z = data.indexOf(0);
      const key = data.toString("latin1", 0, z);
      if (type === "tEXt") info.text[key] = data.toString("latin1", z + 1);
      else {
        // keyword \0 flag method language \0 translated \0 text
        let p = z + 3;
        p = data.indexOf(0, p) + 1;
        p = data.indexOf(0, p) + 1;
        info.text[key] = data.toString("utf8", p);
      }
    }
    if (type === "IEND") break;
    at += 12 + len;
  }
  return info;
}

/** Opens the Picture… dialog of `button` (a selector), sets size and format, saves; returns the download. */
export async function savePicture(page, button, { width, height, format }, shot = null) {
  await page.locator(button).first().scrollIntoViewIfNeeded();
  await page.locator(button).first().click();
  await page.waitForSelector("#picture-dialog[open]", { timeout: 5000 });
  await page.fill("#picture-dialog .picture-width", String(width));
  await page.fill("#picture-dialog .picture-height", String(height));
  await page.check(`#picture-dialog input[value="${format}"]`);
  if (shot) await page.screenshot({ path: shot });
  const caption = await page.$eval("#picture-dialog .picture-caption", (e) => e.textContent);
  const [dl] = await Promise.all([page.waitForEvent("download", { timeout: 30000 }), page.click("#picture-dialog .picture-save")]);
  const path = join(await dl.path());
  const error = await page.$eval("#picture-dialog .picture-error", (e) => (e.hidden ? "" : e.textContent));
  if (error) throw new Error(`the dialog says: ${error}`);
  return { name: dl.suggestedFilename(), bytes: readFileSync(path), caption };
}

/** In the page: decodes PNG bytes (base64) with createImageBitmap; size, drawn pixels above the band, caption-band text pixels. */
function decodeInPage(page, b64, bandFrom) {
  return page.evaluate(async ({ b64, bandFrom }) => {
    const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
    const bmp = await createImageBitmap(new Blob([bytes], { type: "image/png" }));
    const c = document.createElement("canvas");
    c.width = bmp.width;
    c.height = bmp.height;
    const ctx = c.getContext("2d");
    ctx.drawImage(bmp, 0, 0);
    const d = ctx.getImageData(0, 0, c.width, c.height).data;
    const bg = [d[0], d[1], d[2]];
    let drawn = 0;
    let band = 0;
    const split = Math.floor(c.height * bandFrom);
    for (let y = 0; y < c.height; y++) {
      for (let x = 0; x < c.width; x += 2) {
        const i = (y * c.width + x) * 4;
        const diff = Math.abs(d[i] - bg[0]) + Math.abs(d[i + 1] - bg[1]) + Math.abs(d[i + 2] - bg[2]);
        if (y < split && diff > 60) drawn++;
        if (y >= split && d[i] > 150 && d[i + 1] > 150 && d[i + 2] > 150) band++; // light caption text on the dark band
      }
    }
    return { width: bmp.width, height: bmp.height, drawn, band };
  }, { b64, bandFrom });
}

/** Parses an SVG in the page: size, caption text, path/line elements. */
function parseSvgInPage(page, text) {
  return page.evaluate((text) => {
    const doc = new DOMParser().parseFromString(text, "image/svg+xml");
    const bad = doc.querySelector("parsererror");
    const svg = doc.documentElement;
    return {
      error: bad ? bad.textContent.slice(0, 200) : "",
      width: Number(svg.getAttribute("width")), height: Number(svg.getAttribute("height")),
      captionText: [...doc.querySelectorAll(".caption text")].map((t) => t.textContent).join("\n"),
      lines: doc.querySelectorAll("path, line, polyline").length,
      images: doc.querySelectorAll("image").length,
    };
  }, text);
}

export async function picturesChecks({ newPage, base, check, outDir, first, timeoutMs }) {
  let n = first;

  await check(n++, "pictures: a lattice view and the preview save as PNG at the asked size, drawn and captioned (name, changed settings); the view's lines2d SVG is vector lines with the caption", async () => {
    const { context, page, errors } = await newPage();
    try {
      await page.setViewportSize({ width: 1280, height: 800 });
      await runExample(page, base, LATTICE, timeoutMs);
      const design = JSON.parse(await page.evaluate(() => window.weft.design));
      await page.waitForFunction(() => window.weft.views.some((v) => v.shape === "lines2d" && v.items > 0), null, { timeout: 30000 });
      const viewId = await page.evaluate(() => window.weft.views.find((v) => v.shape === "lines2d" && v.items > 0).id);
      const btn = `#views .view-card[data-view="${viewId}"] .picture-button`;
      const png = await savePicture(page, btn, { width: 1200, height: 900, format: "png" }, join(outDir, "pictures-dialog-1280.png"));
      writeFileSync(join(outDir, png.name), png.bytes);
      const want = `${design.name}-${viewId}-1200x900.png`;
      if (png.name !== want) throw new Error(`file name ${png.name}, expected ${want}`);
      const info = pngInfo(png.bytes);
      if (info.width !== 1200 || info.height !== 900) throw new Error(`IHDR says ${info.width}×${info.height}`);
      if (!info.text.Description?.includes(design.name)) throw new Error(`the PNG's Description is "${info.text.Description}"`);
      if (!/changed from the defaults: .+ = /.test(info.text.Description)) throw new Error(`no changed settings in the caption: "${info.text.Description}"`);
      const seen = await decodeInPage(page, png.bytes.toString("base64"), 0.6);
      if (seen.width !== 1200 || seen.height !== 900) throw new Error(`createImageBitmap: ${seen.width}×${seen.height}`);
      if (seen.drawn < 2000) throw new Error(`only ${seen.drawn} drawn pixels above the caption`);
      if (seen.band < 200) throw new Error(`only ${seen.band} caption-text pixels in the band`);

      const svg = await savePicture(page, btn, { width: 1920, height: 1080, format: "svg" });
      writeFileSync(join(outDir, svg.name), svg.bytes);
      const parsed = await parseSvgInPage(page, svg.bytes.toString("utf8"));
      if (parsed.error) throw new Error(`the view's SVG does not parse: ${parsed.error}`);
      if (parsed.width !== 1920 || parsed.height !== 1080) throw new Error(`SVG size ${parsed.width}×${parsed.height}`);
      if (!parsed.captionText.includes(design.name)) throw new Error(`SVG caption: "${parsed.captionText.slice(0, 120)}"`);
      if (parsed.lines < 2 || parsed.images) throw new Error(`SVG has ${parsed.lines} line paths and ${parsed.images} images`);

      const pv = await savePicture(page, "#camera-views .picture-button", { width: 1600, height: 1000, format: "png" });
      writeFileSync(join(outDir, pv.name), pv.bytes);
      const pInfo = pngInfo(pv.bytes);
      const pSeen = await decodeInPage(page, pv.bytes.toString("base64"), 0.7);
      if (pInfo.width !== 1600 || pInfo.height !== 1000 || pSeen.drawn < 2000) throw new Error(`preview PNG ${pInfo.width}×${pInfo.height}, ${pSeen.drawn} drawn pixels`);
      const plotBtn = "#report figure.plot-figure .picture-button";
      if (!(await page.locator(plotBtn).count())) throw new Error("no plot has a Picture… button");
      const plot = await savePicture(page, plotBtn, { width: 1600, height: 1000, format: "svg" });
      writeFileSync(join(outDir, plot.name), plot.bytes);
      const ps = await parseSvgInPage(page, plot.bytes.toString("utf8"));
      if (ps.error) throw new Error(`the plot's SVG does not parse: ${ps.error}`);
      if (ps.width !== 1600 || ps.height !== 1000 || !ps.captionText.includes(design.name) || ps.lines < 1) {
        throw new Error(`plot SVG ${ps.width}×${ps.height}, ${ps.lines} lines, caption "${ps.captionText.slice(0, 80)}"`);
      }
      const plotPng = await savePicture(page, plotBtn, { width: 1280, height: 720, format: "png" });
      writeFileSync(join(outDir, plotPng.name), plotPng.bytes);
      const pp = pngInfo(plotPng.bytes);
      if (pp.width !== 1280 || pp.height !== 720) throw new Error(`plot PNG ${pp.width}×${pp.height}`);
      const pvSvg = await savePicture(page, "#camera-views .picture-button", { width: 1920, height: 1080, format: "svg" });
      writeFileSync(join(outDir, pvSvg.name), pvSvg.bytes);
      const pvs = await parseSvgInPage(page, pvSvg.bytes.toString("utf8"));
      if (pvs.error || pvs.width !== 1920 || pvs.height !== 1080 || pvs.images !== 1 || !pvs.captionText.includes(design.name)) {
        throw new Error(`preview SVG: ${pvs.error || `${pvs.width}×${pvs.height}, ${pvs.images} images, caption "${pvs.captionText.slice(0, 60)}"`}`);
      }
      for (const viewport of [{ width: 1280, height: 800 }, { width: 390, height: 844 }]) {
        await page.setViewportSize(viewport);
        await page.locator(`#views .view-card[data-view="${viewId}"]`).scrollIntoViewIfNeeded();
        await page.waitForTimeout(300);
        await page.screenshot({ path: join(outDir, `pictures-view-card-${viewport.width}.png`) });
      }
      await page.setViewportSize({ width: 1280, height: 800 });
      await page.waitForTimeout(300);
      const canvas = await page.$eval("#preview", (c) => [c.width, c.height, c.clientWidth]);
      if (canvas[0] === 1600) throw new Error("the preview canvas kept the picture's size");
      if (errors.length) throw new Error(`page errors: ${errors.join("; ")}`);
      return `${png.name}: ${seen.drawn} drawn px, caption "${info.text.Description.slice(0, 70)}…"; SVG ${parsed.lines} paths; plot ${plot.name} ${ps.lines} lines; preview ${pv.name}`;
    } finally {
      await context.close();
    }
  });

  await check(n++, "compare: Pin, a changed setting and Run show two previews with linked cameras and one table whose numbers are each run's; the comparison's link opened in a fresh page shows the same table (desktop and phone)", async () => {
    const said = [];
    let link = null;
    let table = null;
    for (const viewport of [{ width: 1280, height: 800 }, { width: 390, height: 844 }]) {
      const { context, page, errors } = await newPage();
      try {
        await page.setViewportSize(viewport);
        await page.goto(`${base}/www/`);
        await page.waitForFunction(() => window.weft?.resultCount > 0 && !window.weft.busy, null, { timeout: timeoutMs });
        const statsA = await page.evaluate(() => window.weft.result.report.analysis);
        await page.click(".compare-pin");
        const pinnedSays = await page.$eval(".compare-status", (e) => e.textContent);
        if (!/Pinned/.test(pinnedSays)) throw new Error(`after Pin the bar says "${pinnedSays}"`);
        await setFieldUntil(page, "#f-job-slice-infill_density", "45", (d) => Math.abs(d.job.slice.infill_density - 0.45) < 1e-9, "infill density");
        const before = await page.evaluate(() => window.weft.resultCount);
        await page.click("#slice");
        await waitResult(page, before, "running the changed design", timeoutMs);
        const statsB = await page.evaluate(() => window.weft.result.report.analysis);
        await page.waitForFunction(() => window.weft.comparison?.a?.segments > 0 && window.weft.comparison?.b?.segments > 0, null, { timeout: 10000 });
        const shown = await page.evaluate(() => window.weft.comparison);
        for (const row of shown.rows) {
          if (row.key === "gcode_bytes") continue;
          for (const [side, stats] of [["a", statsA], ["b", statsB]]) {
            if (typeof stats[row.key] !== "number") continue;
            if (Number(row[side]) !== stats[row.key]) throw new Error(`${row.key} ${side.toUpperCase()}: table ${row[side]}, run ${stats[row.key]}`);
          }
        }
        if (shown.rows.length < 6) throw new Error(`the table has ${shown.rows.length} rows`);
        if (!/infill_density 20 % → 45 %|infill_density .* → 45 %/.test(shown.notes)) throw new Error(`the notes say "${shown.notes}"`);
        // Linked cameras: orbit A, B follows.
        const box = await page.locator(".compare-pane-a canvas").boundingBox();
        await page.locator(".compare-pane-a canvas").scrollIntoViewIfNeeded();
        const b2 = await page.locator(".compare-pane-a canvas").boundingBox();
        await page.mouse.move(b2.x + b2.width / 2, b2.y + b2.height / 2);
        await page.mouse.down();
        await page.mouse.move(b2.x + b2.width / 2 + 60, b2.y + b2.height / 2 + 20, { steps: 5 });
        await page.mouse.up();
        const moved = await page.evaluate(() => window.weft.comparison);
        const same = moved.a.position.every((v, i) => Math.abs(v - moved.b.position[i]) < 1e-6);
        const changed = moved.a.position.some((v, i) => Math.abs(v - shown.a.position[i]) > 1e-3);
        if (!changed || !same) throw new Error(`orbiting A: A moved ${changed}, B at the same place ${same} (box ${JSON.stringify(box)})`);
        // The stale note: edit the form, the comparison says B is not the form.
        await page.locator(".compare").scrollIntoViewIfNeeded();
        await page.waitForTimeout(300);
        await page.screenshot({ path: join(outDir, `compare-${viewport.width}.png`) });
        await page.locator(".compare").screenshot({ path: join(outDir, `compare-card-${viewport.width}.png`) });
        // An edit after B's run: the comparison says B is not the form.
        await setFieldUntil(page, "#f-job-slice-infill_density", "30", (d) => Math.abs(d.job.slice.infill_density - 0.3) < 1e-9, "infill density");
        const staleNote = await page.evaluate(() => window.weft.comparison.notes);
        if (!/B is the last run, not the form/.test(staleNote)) throw new Error(`after an edit the notes say "${staleNote}"`);
        await page.click(".compare-share");
        link = await page.evaluate(() => location.href);
        if (!/#d=[^&]+&vs=/.test(link)) throw new Error(`the comparison's link is ${link.slice(0, 120)}`);
        table = shown.rows;
        if (viewport.width > 500) {
          // Another slicer's G-code dropped on the page is B, against the same pinned A.
          const before2 = await page.evaluate(() => window.weft.resultCount);
          await page.setInputFiles("#file", join(ROOT, "tests/fixtures/prusaslicer-style.gcode"));
          await waitResult(page, before2, "reading prusaslicer-style.gcode", timeoutMs);
          const stats = await page.evaluate(() => window.weft.result.report.analysis);
          const vs = await page.evaluate(() => window.weft.comparison);
          if (!/G-code read as it is/.test(vs.notes)) throw new Error(`with a dropped G-code the notes say "${vs.notes}"`);
          const layers = vs.rows.find((r) => r.key === "layers");
          if (Number(layers.b) !== stats.layers || Number(layers.a) !== statsA.layers) throw new Error(`layers row with the G-code: ${JSON.stringify(layers)}`);
          said.push(`a dropped G-code is B (${stats.layers} layers)`);
        }
        if (viewport.width < 500) {
          await page.locator("#views .picture-button, #camera-views .picture-button").first().scrollIntoViewIfNeeded();
          await page.locator("#camera-views .picture-button").click();
          await page.waitForSelector("#picture-dialog[open]");
          await page.screenshot({ path: join(outDir, "pictures-dialog-390.png") });
          await page.click("#picture-dialog .picture-close");
        }
        if (errors.length) throw new Error(`page errors: ${errors.join("; ")}`);
        said.push(`${viewport.width}px: ${shown.rows.length} rows, cameras linked`);
      } finally {
        await context.close();
      }
    }
    const { context, page, errors } = await newPage();
    try {
      await page.goto(link);
      await page.waitForFunction(() => window.weft?.comparison?.rows?.length > 0 && !window.weft.busy, null, { timeout: timeoutMs });
      const opened = await page.evaluate(() => window.weft.comparison);
      for (const row of table) {
        const o = opened.rows.find((r) => r.key === row.key);
        if (!o || o.a !== row.a || o.b !== row.b) throw new Error(`${row.key}: link shows ${JSON.stringify(o)}, the page had ${JSON.stringify(row)}`);
      }
      if (!(opened.a.segments > 0 && opened.b.segments > 0)) throw new Error("the link's previews are empty");
      await page.locator(".compare").scrollIntoViewIfNeeded();
      await page.screenshot({ path: join(outDir, "compare-link-1400.png") });
      if (errors.length) throw new Error(`page errors: ${errors.join("; ")}`);
      said.push(`the link (${link.length} chars) shows the same ${opened.rows.length} rows`);
    } finally {
      await context.close();
    }
    return said.join("; ");
  });

  return n;
}

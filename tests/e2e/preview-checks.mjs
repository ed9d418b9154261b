// Browser checks of the 3D preview's framing (issue 8): fit-to-part, top view, zoom without
// clipping, Fit after orbiting. Called by run.mjs with its check(); `partBox` measures the
// part's pixels and is shared with preview-shots.mjs.

/**
 * Box of the part's pixels on the preview canvas: the plate is hidden for one frame and every
 * pixel away from the background colour counts. `fill` = how much of the canvas the box
 * spans in its limiting direction, max(w / width, h / height) (1: edge to edge).
 * @returns {Promise<{width: number, height: number, x0: number, y0: number, w: number, h: number, count: number, fill: number}>}
 */
export async function partBox(page) {
  return page.evaluate(async () => {
    const frame = () => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
    const preview = window.weft.preview;
    const plate = preview.plate;
    plate.visible = false;
    preview.requestRender();
    await frame();
    const src = document.getElementById("preview");
    const c = document.createElement("canvas");
    c.width = src.width;
    c.height = src.height;
    const ctx = c.getContext("2d");
    ctx.drawImage(src, 0, 0);
    plate.visible = true;
    preview.requestRender();
    const d = ctx.getImageData(0, 0, c.width, c.height).data;
    const bg = [0x1f, 0x23, 0x2a];
    let x0 = Infinity, y0 = Infinity, x1 = -1, y1 = -1, count = 0;
    for (let y = 0; y < c.height; y++) {
      for (let x = 0; x < c.width; x++) {
        const i = (y * c.width + x) * 4;
        if (Math.abs(d[i] - bg[0]) + Math.abs(d[i + 1] - bg[1]) + Math.abs(d[i + 2] - bg[2]) <= 30) continue;
        count++;
        if (x < x0) x0 = x;
        if (x > x1) x1 = x;
        if (y < y0) y0 = y;
        if (y > y1) y1 = y;
      }
    }
    const w = count ? x1 - x0 + 1 : 0;
    const h = count ? y1 - y0 + 1 : 0;
    return { width: c.width, height: c.height, x0, y0, w, h, count, fill: Math.max(w / c.width, h / c.height) };
  });
}

/** Minimum framing after Fit: the part spans this much of the canvas in its limiting direction. */
export const MIN_FILL = 0.7;

/**
 * @param {{baseUrl: string, check: (n: number, title: string, fn: () => Promise<string|void>) => Promise<void>,
 *          newPage: () => Promise<{context: any, page: any, errors: string[]}>, first: number, timeoutMs?: number}} opts
 * @returns {Promise<number>} the next check number
 */
export async function previewChecks({ baseUrl, check, newPage, first, timeoutMs = 120000 }) {
  let n = first;
  const { context, page, errors } = await newPage();
  const fill = (b) => `${b.w}×${b.h} px of ${b.width}×${b.height} (${Math.round(b.fill * 100)} %)`;
  const wheel = async (steps, dy) => {
    for (let i = 0; i < steps; i++) await page.mouse.wheel(0, dy);
  };
  let middle = null;
  try {
    await check(n++, `preview: a new result (a flat square plate) is framed: the part spans ≥ ${MIN_FILL * 100} % of the canvas in its limiting direction`, async () => {
      await page.goto(`${baseUrl}/www/`);
      await page.waitForFunction(() => window.weft && window.weft.design && window.weft.preview, null, { timeout: 30000 });
      // A flat square plate, 20 × 20 × 1 mm, in the middle of the bed.
      const design = await page.evaluate(() => {
        const d = JSON.parse(window.weft.design);
        d.name = "flat-square";
        d.job.input = { builtin: { shape: "cube", size: [20, 20, 1] } };
        return JSON.stringify(d);
      });
      await page.setInputFiles("#file", { name: "flat-square.json", mimeType: "application/json", buffer: Buffer.from(design) });
      await page.waitForFunction(() => JSON.parse(window.weft.design).name === "flat-square", null, { timeout: 10000 });
      const before = await page.evaluate(() => window.weft.resultCount);
      await page.click("#slice");
      await page.waitForFunction((k) => window.weft.resultCount > k && !window.weft.busy, before, { timeout: timeoutMs });
      const r = await page.$eval("#preview", (c) => c.getBoundingClientRect().toJSON());
      middle = { x: r.x + r.width / 2, y: r.y + r.height / 2 };
      // The stats and report settle (a resize refits): until the canvas keeps its size over
      // 5 frames in a row (counted in frames, not milliseconds: a loaded machine draws later).
      await page.evaluate(async () => {
        const frame = () => new Promise((r) => requestAnimationFrame(() => r()));
        const box = document.getElementById("preview").parentElement;
        let size = "", same = 0;
        for (let i = 0; i < 600 && same < 5; i++) {
          await frame();
          const now = `${box.clientWidth}×${box.clientHeight}`;
          same = now === size ? same + 1 : 0;
          size = now;
        }
      });
      const b = await partBox(page);
      if (!(b.fill >= MIN_FILL)) throw new Error(`the part spans ${fill(b)}`);
      return fill(b);
    });

    await check(n++, "preview: top view (key 1 on the canvas, and the Top button) of a flat square part draws a square box", async () => {
      await page.focus("#preview");
      await page.keyboard.press("1");
      const byKey = await partBox(page);
      await page.click('#camera-views [data-camera="iso"]', { timeout: 5000 });
      await page.click('#camera-views [data-camera="top"]', { timeout: 5000 });
      const b = await partBox(page);
      const ratio = b.w / b.h;
      if (!(ratio > 0.9 && ratio < 1.11)) throw new Error(`the top view's part box is ${b.w}×${b.h} px`);
      if (Math.abs(byKey.w - b.w) > 2 || Math.abs(byKey.h - b.h) > 2) throw new Error(`key 1 gave ${byKey.w}×${byKey.h} px, the Top button ${b.w}×${b.h}`);
      if (!(b.fill >= MIN_FILL)) throw new Error(`the top view is not framed: ${fill(b)}`);
      return `${b.w}×${b.h} px, ${Math.round(b.fill * 100)} %`;
    });

    await check(n++, "preview: 40 wheel steps in, then 120 out: the part never disappears (near and far planes follow it)", async () => {
      await page.click('#camera-views [data-camera="iso"]', { timeout: 5000 });
      await page.mouse.move(middle.x, middle.y);
      const counts = [];
      for (const [steps, dy] of [[40, -100], [120, 100]]) {
        for (let done = 0; done < steps; done += 10) {
          await wheel(10, dy);
          counts.push((await partBox(page)).count);
        }
      }
      if (counts.some((c) => !(c > 0))) throw new Error(`part pixels every 10 steps: ${counts.join(", ")}`);
      return `part pixels ${Math.min(...counts)}–${Math.max(...counts)}`;
    });

    await check(n++, "preview: after orbiting and zooming out, Fit frames the part again", async () => {
      await page.mouse.move(middle.x, middle.y);
      await page.mouse.down();
      await page.mouse.move(middle.x + 160, middle.y + 40, { steps: 8 });
      await page.mouse.up();
      await wheel(8, 100);
      const moved = await partBox(page);
      if (moved.fill >= MIN_FILL) throw new Error(`the part still spans ${fill(moved)} after zooming out: nothing to restore`);
      await page.click('#camera-views [data-camera="fit"]', { timeout: 5000 });
      const b = await partBox(page);
      if (!(b.fill >= MIN_FILL)) throw new Error(`after Fit the part spans ${fill(b)}`);
      return `${Math.round(moved.fill * 100)} % → ${Math.round(b.fill * 100)} %`;
    });

    await check(n++, "preview: colour modes, layer range, travel and path starts change the drawing; lines draw the same segments", async () => {
      await page.click('#camera-views [data-camera="iso"]', { timeout: 5000 });
      const state = await page.evaluate(async () => {
        const frame = () => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
        const p = window.weft.preview;
        const ui = (id) => document.getElementById(id);
        const hash = async () => {
          await frame();
          const src = ui("preview");
          const c = document.createElement("canvas");
          c.width = src.width;
          c.height = src.height;
          const ctx = c.getContext("2d");
          ctx.drawImage(src, 0, 0);
          const d = ctx.getImageData(0, 0, c.width, c.height).data;
          let h = 0;
          let lit = 0;
          for (let i = 0; i < d.length; i += 4) {
            h = (h * 31 + d[i] * 7 + d[i + 1] * 3 + d[i + 2]) >>> 0;
            if (Math.max(d[i], d[i + 1], d[i + 2]) - Math.min(d[i], d[i + 1], d[i + 2]) > 60) lit++;
          }
          return { h, lit };
        };
        const set = (id, prop, value, event) => { ui(id)[prop] = value; ui(id).dispatchEvent(new Event(event)); };
        const out = { style: p.drawStyle };
        out.base = await hash();
        set("color-by", "value", "path", "change");
        out.path = await hash();
        set("color-by", "value", "flow", "change");
        out.flow = await hash();
        set("color-by", "value", "feature", "change");
        const layers = Number(ui("layer-max").max) + 1;
        set("layer-max", "value", "0", "input");
        out.oneLayer = { drawn: p.drawn.extrusion, ...(await hash()) };
        set("layer-max", "value", String(layers - 1), "input");
        set("show-travel", "checked", true, "change");
        out.travel = await hash();
        set("show-travel", "checked", false, "change");
        set("show-starts", "checked", true, "change");
        out.starts = await hash();
        set("show-starts", "checked", false, "change");
        out.all = p.drawn.extrusion;
        p.setStyle("lines");
        out.lines = { style: p.drawStyle, drawn: p.drawn.extrusion, ...(await hash()) };
        p.setStyle("auto");
        out.back = await hash();
        out.layers = layers;
        return out;
      });
      const problems = [];
      if (state.style !== "tubes") problems.push(`drawn as ${state.style}, expected tubes`);
      for (const k of ["path", "flow", "travel", "starts"]) if (state[k].h === state.base.h) problems.push(`${k} did not change the picture`);
      if (!(state.oneLayer.drawn < state.all && state.oneLayer.drawn > 0)) problems.push(`one layer draws ${state.oneLayer.drawn} of ${state.all} segments`);
      if (!(state.oneLayer.lit < state.base.lit)) problems.push(`one layer of ${state.layers} lights ${state.oneLayer.lit} pixels, all ${state.base.lit}`);
      if (state.lines.style !== "lines" || state.lines.drawn !== state.all || !(state.lines.lit > 0)) problems.push(`lines: ${JSON.stringify(state.lines)}`);
      if (state.back.h !== state.base.h) problems.push("back to tubes draws a different picture");
      if (problems.length) throw new Error(problems.join("; "));
      return `${state.all} segments in ${state.layers} layers; one layer ${state.oneLayer.drawn}; lines light ${state.lines.lit} pixels, tubes ${state.base.lit}`;
    });
    if (errors.length) console.log(`note: console errors in the preview page:\n  ${errors.join("\n  ")}`);
  } finally {
    await context.close();
  }
  return n;
}

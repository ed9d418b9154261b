// Browser checks of the lattice job (GIPPO print paths): example from the menu, the paths
// stage card's score plot and path classes drawn by the generic plot code from the run
// report, 3D preview, the layer2d view through inspect, euler's minimal paths, continuous's
// certificate named (the open postman's deadhead), share link vs
// the native CLI, pattern thumbnails. Called by run.mjs with its browser, server and check() so the summary line
// counts these too:
//
//   import { latticeChecks } from "./lattice-checks.mjs";
//   await latticeChecks({ browser, baseUrl: base, weftBin: WEFT_BIN, check, newPage, outDir: OUT, first: 8 });
//
// `newPage` (optional) makes a fresh context + page ({context, page, errors}); without it a
// plain context is used. Checks are numbered from `first`.
import { readFileSync, writeFileSync, existsSync, mkdirSync } from "node:fs";
import { createHash } from "node:crypto";
import { execFileSync } from "node:child_process";
import { join } from "node:path";
import { tmpdir } from "node:os";
import { collectErrors, colouredPixels, downloadGcode, waitReady, waitResult } from "./page-helpers.mjs";

const EXAMPLE = "honeycomb-10mm.json";
const BACKGROUND = [0x1f, 0x23, 0x2a]; // the 2D views' background (views.js)
const sha256 = (buf) => createHash("sha256").update(buf).digest("hex");

/**
 * @param {{browser: import("playwright-core").Browser, baseUrl: string, weftBin?: string,
 *          check: (n: number, title: string, fn: () => Promise<string|void>) => Promise<void>,
 *          newPage?: () => Promise<{context: any, page: any, errors: string[]}>,
 *          outDir?: string, first?: number, timeoutMs?: number}} opts
 */
export async function latticeChecks({ browser, baseUrl, weftBin = process.env.WEFT_BIN, check, newPage, outDir, first = 1, timeoutMs }) {
  const out = outDir ?? join(tmpdir(), "weft-e2e-lattice");
  mkdirSync(out, { recursive: true });
  const jobTimeout = timeoutMs ?? Number(process.env.E2E_TIMEOUT_S ?? 120) * 1000;
  const open = newPage ?? (async () => {
    const context = await browser.newContext({ viewport: { width: 1400, height: 900 }, acceptDownloads: true });
    const page = await context.newPage();
    return { context, page, errors: collectErrors(page) };
  });
  let n = first;
  const main = await open();
  const { page } = main;
  let shared = null; // {url, designPath, gcode}

  try {
    await check(n++, "lattice: honeycomb-10mm from the Examples menu runs; the paths card draws the report's score plot and path classes with the generic plot code; 3D preview; layer2d view via inspect", async () => {
      await page.goto(`${baseUrl}/www/`);
      await waitReady(page);
      const before = await page.evaluate(() => window.weft.resultCount);
      // The menu is filled by an asynchronous fetch of examples/index.json after start-up.
      await page.waitForSelector(`#examples option[value="${EXAMPLE}"]`, { state: "attached", timeout: 10000 }).catch(() => {});
      const offered = await page.$$eval("#examples option", (os) => os.map((o) => o.value));
      if (!offered.includes(EXAMPLE)) throw new Error(`the Examples menu does not offer ${EXAMPLE} (has ${offered.join(", ")})`);
      await page.selectOption("#examples", EXAMPLE);
      await waitResult(page, before, `running ${EXAMPLE}`, jobTimeout);
      const report = await page.evaluate(() => window.weft.result?.report ?? null);
      const paths = report?.stages?.find((s) => s.stage === "paths");
      if (!paths) throw new Error(`the run report has no paths stage (stages: ${(report?.stages ?? []).map((s) => s.stage).join(", ")})`);
      const scores = paths.plots.find((p) => p.kind === "line");
      const iterations = scores?.series.find((s) => s.name === "score" && (s.group_index ?? 0) === 0)?.y.length ?? 0;
      if (iterations !== 500) throw new Error(`the report's score series has ${iterations} iterations, expected 500`);
      const shown = await page.evaluate(() => {
        const card = document.querySelector('#report .stage-card[data-stage="paths"]');
        if (!card) return null;
        const line = card.querySelector('svg[data-plot-kind="line"]');
        const classes = [...card.querySelectorAll('svg[data-plot-kind="bars"]')].find((s) => s.querySelectorAll("rect.bar").length === 3);
        return {
          group: card.dataset.group,
          points: Number(line?.querySelector('.series[data-series="score"]')?.dataset.points ?? 0),
          path: line?.querySelector('.series[data-series="score"] path')?.getAttribute("d")?.split(/[ML]/).filter(Boolean).length ?? 0,
          hlines: line?.querySelectorAll(".series-hline line").length ?? 0,
          axes: [...(line?.querySelectorAll(".axis-title") ?? [])].map((t) => t.textContent),
          bars: classes ? [...classes.querySelectorAll("rect.bar")].map((r) => Number(r.getAttribute("width"))) : [],
          labels: classes ? [...classes.querySelectorAll(".bar-label")].map((t) => t.textContent) : [],
          table: card.querySelector("table")?.textContent ?? "",
        };
      });
      if (!shown) throw new Error("no stage card for the paths stage in #report");
      if (shown.points !== iterations || shown.path !== iterations) {
        throw new Error(`the line plot shows ${shown.points} points (path with ${shown.path} vertices); the report has ${iterations}`);
      }
      if (shown.hlines < 1) throw new Error("the score plot has no dashed reference line (hline series)");
      if (shown.axes.length < 2) throw new Error(`axis titles: ${JSON.stringify(shown.axes)}`);
      const layer0 = paths.plots.find((p) => p.kind === "bars" && p.series.some((s) => s.x.length === 3))
        ?.series.find((s) => (s.group_index ?? 0) === 0);
      if (shown.bars.length !== 3 || !shown.bars.some((w) => w > 0)) throw new Error(`path-class bars not drawn: ${JSON.stringify(shown)}`);
      if (layer0 && shown.labels.join("|") !== layer0.x.join("|")) throw new Error(`bar labels ${shown.labels} vs report ${layer0.x}`);
      // A resize may clear the canvas until the next frame: read again for up to 20 s (a
      // loaded machine draws later; a drawn preview ends the loop at once).
      let px = await colouredPixels(page);
      for (const t0 = Date.now(); px < 300 && Date.now() - t0 < 20000;) {
        await page.waitForTimeout(200);
        px = await colouredPixels(page);
      }
      if (px < 300) throw new Error(`only ${px} toolpath-coloured pixels in the 3D preview`);
      await page.waitForFunction(() => window.weft.views.find((v) => v.id === "layer2d")?.answers > 0, null, { timeout: jobTimeout }).catch(() => {});
      const view = await page.evaluate(() => window.weft.views.find((v) => v.id === "layer2d") ?? null);
      if (!view) throw new Error(`no layer2d view card (views: ${JSON.stringify(await page.evaluate(() => window.weft.views))})`);
      if (!(view.answers > 0) || !(view.items > 0) || view.shape !== "lines2d") throw new Error(`the layer2d view drew nothing: ${JSON.stringify(view)}`);
      await page.screenshot({ path: join(out, "lattice.png") });
      return `${iterations} iterations plotted, bars ${shown.labels.join("/")}, ${px} coloured pixels, layer2d ${view.items} segments of ${view.count} layer(s)`;
    });

    await check(n++, "lattice: the layer2d view's index control asks inspect for another layer", async () => {
      await waitReady(page);
      const v0 = await page.evaluate(() => window.weft.views.find((v) => v.id === "layer2d"));
      if (!(v0?.count > 1)) return `only ${v0?.count} layer: nothing to step through`;
      const input = '.view-card[data-view="layer2d"] input[type=number]';
      await page.fill(input, "2");
      await page.dispatchEvent(input, "change");
      await page.waitForFunction((k) => {
        const v = window.weft.views.find((x) => x.id === "layer2d");
        return v.answers > k && v.index === 1;
      }, v0.answers, { timeout: jobTimeout });
      const v1 = await page.evaluate(() => window.weft.views.find((v) => v.id === "layer2d"));
      if (!(v1.items > 0)) throw new Error(`layer 2 drew nothing: ${JSON.stringify(v1)}`);
      return `layer 2 of ${v1.count}: ${v1.items} segments`;
    });

    await check(n++, "lattice: optimiser euler → the paths card shows paths = proven minimum", async () => {
      await waitReady(page);
      if (!(await page.$("#f-job-paths-method"))) throw new Error("no optimiser field (#f-job-paths-method) in the form");
      const before = await page.evaluate(() => window.weft.resultCount);
      await page.selectOption("#f-job-paths-method", JSON.stringify("euler"));
      const method = await page.evaluate(() => JSON.parse(window.weft.design).job.paths.method);
      if (method !== "euler") throw new Error(`the design's method is ${method}`);
      await page.click("#slice");
      await waitResult(page, before, "running with euler", jobTimeout);
      const metrics = await page.evaluate(() => {
        const card = document.querySelector('#report .stage-card[data-stage="paths"]');
        const value = (key) => card?.querySelector(`.metrics [data-key="${key}"] dd`)?.firstChild?.textContent ?? null;
        // The per-layer table as drawn: the "Pairing quality" column's cells.
        const table = card?.querySelector('table.report-table[data-key="layers"]');
        let quality = [];
        if (table?.classList.contains("transposed")) {
          const row = [...table.querySelectorAll("tr")].find((r) => /Pairing quality/.test(r.querySelector("th")?.textContent ?? ""));
          quality = row ? [row.querySelector("td")?.textContent.trim() ?? ""] : [];
        } else if (table) {
          const col = [...table.querySelectorAll("thead th")].findIndex((h) => /Pairing quality/.test(h.textContent));
          quality = col >= 0 ? [...table.querySelectorAll("tbody tr")].map((r) => r.children[col]?.textContent.trim() ?? "") : [];
        }
        return { paths: value("paths"), bound: value("lower_bound"), line: Boolean(card?.querySelector('svg[data-plot-kind="line"]')), quality };
      });
      if (metrics.paths === null || metrics.bound === null) throw new Error(`the paths card lacks the paths / lower_bound metrics: ${JSON.stringify(metrics)}`);
      if (metrics.paths !== metrics.bound) throw new Error(`euler made ${metrics.paths} paths, lower bound ${metrics.bound}`);
      const layers = await page.evaluate(() => window.weft.result?.report?.stages?.find((s) => s.stage === "paths")?.tables?.find((t) => t.key === "layers")?.rows?.length ?? 0);
      if (!metrics.quality.length || metrics.quality.length !== layers) throw new Error(`the per-layer table shows ${metrics.quality.length} pairing-quality cells for ${layers} layers`);
      const bad = metrics.quality.filter((q) => !/^(optimal|within \d+(\.\d)? %)$/.test(q));
      if (bad.length) throw new Error(`pairing quality cells that say neither "optimal" nor "within x %": ${bad.slice(0, 5).join(" | ")}`);
      return `${metrics.paths} paths = bound${metrics.line ? "" : " (no iteration plot for euler)"}; pairing per layer: ${[...new Set(metrics.quality)].join(", ")}`;
    });

    await check(n++, "lattice: optimiser continuous → the paths card names what is optimal (deadhead of open walks) and shows travel through the air apart", async () => {
      await waitReady(page);
      const before = await page.evaluate(() => window.weft.resultCount);
      await page.selectOption("#f-job-paths-method", JSON.stringify("continuous"));
      await page.click("#slice");
      await waitResult(page, before, "running with continuous", jobTimeout);
      const card = await page.evaluate(() => {
        const el = document.querySelector('#report .stage-card[data-stage="paths"]');
        const item = (key) => {
          const dd = el?.querySelector(`.metrics [data-key="${key}"]`);
          return dd ? { label: dd.querySelector("dt")?.textContent ?? "", value: dd.querySelector("dd")?.firstChild?.textContent ?? "", hint: dd.getAttribute("title") ?? dd.querySelector("[title]")?.getAttribute("title") ?? "" } : null;
        };
        return { gap: item("pairing_gap"), pairing: item("pairing"), air: item("free_travel"), ratio: item("travel_per_pairing"), text: el?.textContent ?? "" };
      });
      if (!card.gap || !card.pairing || !card.air || !card.ratio) throw new Error(`the paths card lacks pairing_gap / pairing / free_travel / travel_per_pairing: ${JSON.stringify(card).slice(0, 400)}`);
      if (!/Deadhead: optimal/.test(card.gap.label)) throw new Error(`the certificate reads "${card.gap.label}", not "Deadhead: optimal"`);
      if (!/Deadhead along struts/.test(card.pairing.label)) throw new Error(`the pairing metric reads "${card.pairing.label}"`);
      if (!/open Chinese postman/.test(card.text + card.gap.hint + card.pairing.hint)) throw new Error("nothing on the card names the open Chinese postman");
      if (Number(card.ratio.value) !== 1) throw new Error(`travel ÷ pairing ${card.ratio.value} on one piece, not 1`);
      await page.evaluate(() => document.querySelector('#report .stage-card[data-stage="paths"]')?.scrollIntoView());
      for (const [w, h, name] of [[1280, 800, "lattice-continuous-desktop.png"], [390, 844, "lattice-continuous-phone.png"]]) {
        await page.setViewportSize({ width: w, height: h });
        await page.waitForTimeout(300);
        await page.evaluate(() => document.querySelector('#report .stage-card[data-stage="paths"]')?.scrollIntoView());
        await page.screenshot({ path: join(out, name) });
      }
      await page.setViewportSize({ width: 1400, height: 900 });
      return `${card.gap.label} ${card.gap.value} %; ${card.pairing.label} ${card.pairing.value} mm; travel through the air ${card.air.value} mm`;
    });

    await check(n++, "lattice: share link in a fresh browser gives the same G-code (SHA-256) as `weft run design.json`", async () => {
      await waitReady(page);
      await page.click("#share");
      await page.waitForFunction(() => location.hash.startsWith("#d="), null, { timeout: 10000 });
      const url = page.url();
      const design = await page.evaluate(() => window.weft.design);
      if (JSON.parse(design).job.kind !== "lattice") throw new Error("the shared design is not a lattice job");
      const designPath = join(out, "lattice-design.json");
      writeFileSync(designPath, design);
      const other = await open();
      let web;
      try {
        await other.page.goto(url);
        await waitReady(other.page);
        await waitResult(other.page, 0, "auto-run of the shared lattice design", jobTimeout);
        const same = await other.page.evaluate(() => window.weft.design);
        if (same !== design) throw new Error("the shared page shows a different design");
        web = await downloadGcode(other.page, join(out, "lattice-shared.gcode"));
        if (!web.name.endsWith(".gcode")) throw new Error(`download named ${web.name} (marlin flavour: .gcode)`);
      } finally {
        await other.context.close();
      }
      if (!web.bytes.length) throw new Error("the shared page's G-code is empty");
      if (!weftBin || !existsSync(weftBin)) throw new Error(`native CLI ${weftBin} not found (set WEFT_BIN)`);
      const cliPath = join(out, "lattice-cli.gcode");
      try {
        execFileSync(weftBin, ["run", designPath, "--out", cliPath], { encoding: "utf8", stdio: ["ignore", "pipe", "pipe"], timeout: 300000 });
      } catch (err) {
        throw new Error(`weft run failed: ${(err.stderr || err.message || "").toString().trim()}`);
      }
      const cli = readFileSync(cliPath);
      if (sha256(cli) !== sha256(web.bytes)) {
        throw new Error(`CLI G-code differs from the shared page's (${cli.length} vs ${web.bytes.length} bytes): compare ${cliPath} with ${web.path}`);
      }
      return `sha256 ${sha256(cli).slice(0, 12)}…, ${url.length}-character URL`;
    });

    await check(n++, `lattice: the pattern picker shows a drawn thumbnail of every pattern in the schema`, async () => {
      await waitReady(page);
      await page.waitForSelector("#pattern-picker canvas", { timeout: 10000 });
      await page.waitForFunction(() => window.weft.thumbnails.length >= document.querySelectorAll("#pattern-picker canvas").length,
        null, { timeout: jobTimeout }).catch(() => {});
      const counts = await page.$$eval("#pattern-picker canvas", (canvases, bg) => canvases.map((c) => {
        const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
        let n = 0;
        for (let i = 0; i < d.length; i += 4) {
          if (Math.abs(d[i] - bg[0]) + Math.abs(d[i + 1] - bg[1]) + Math.abs(d[i + 2] - bg[2]) > 60) n++;
        }
        return [c.dataset.pattern, n];
      }), BACKGROUND);
      // Every pattern of the schema (11 since the wavy ones of issue 9), and at least those 11.
      const expected = await page.evaluate(() => window.weft.schema.patterns.length);
      if (expected < 11 || counts.length !== expected) throw new Error(`${counts.length} thumbnails, expected ${expected} (schema) and at least 11`);
      const blank = counts.filter(([, k]) => k < 20).map(([name]) => name);
      if (blank.length) throw new Error(`blank thumbnails: ${blank.join(", ")}`);
      // A click picks the pattern.
      await page.click('#pattern-picker button[data-pattern="square_grid"]');
      const kind = await page.evaluate(() => JSON.parse(window.weft.design).job.lattice.pattern.kind);
      if (kind !== "square_grid") throw new Error(`clicking square_grid set the pattern to ${kind}`);
      return counts.map(([name, k]) => `${name} ${k}`).join(", ");
    });
    if (main.errors.length) console.log(`note: console errors in the lattice page:\n  ${main.errors.join("\n  ")}`);
  } finally {
    await main.context.close();
  }
  return n;
}


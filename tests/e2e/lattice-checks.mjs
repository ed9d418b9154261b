// Browser checks of the lattice job (GIPPO print paths): example from the menu, score plot,
// path classes, 3D preview, euler's minimal paths, share link vs the native CLI, pattern
// thumbnails. Called by run.mjs with its browser, server and check() so the summary line
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
import { colouredPixels, downloadGcode, waitReady, waitResult } from "./page-helpers.mjs";

const EXAMPLE = "honeycomb-10mm.json";
const BACKGROUND = [0x1f, 0x23, 0x2a]; // the 2D views' background (lattice.js)
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
    const errors = [];
    page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });
    page.on("pageerror", (e) => errors.push(`uncaught: ${e.message}`));
    return { context, page, errors };
  });
  let n = first;
  const main = await open();
  const { page } = main;
  let shared = null; // {url, designPath, gcode}

  try {
    await check(n++, "lattice: honeycomb-10mm from the Examples menu runs; 500-point score plot, path classes, 3D preview", async () => {
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
      const layer = report?.paths?.layers?.[0];
      if (!layer) throw new Error(`the run report has no paths.layers (lattice: ${JSON.stringify(report?.lattice ?? null)}): the lattice/paths stages returned nothing`);
      const plot = await page.$eval("#score-plot", (el) => ({
        kind: el.dataset.kind, points: Number(el.dataset.points ?? 0),
        best: el.querySelectorAll("circle.mark-best").length, worst: el.querySelectorAll("circle.mark-worst").length,
      }));
      if (plot.points !== 500) {
        throw new Error(`score plot has ${plot.points} points (kind ${plot.kind}); expected 500 (report: ${layer.iteration_scores?.length} iteration scores)`);
      }
      if (plot.best !== 1 || plot.worst !== 1) throw new Error(`best/worst marks: ${plot.best}/${plot.worst}`);
      const bars = await page.$eval("#path-classes", (el) => ({
        drawn: el.dataset.drawn, widths: [...el.querySelectorAll("rect:not(.bar-track)")].map((r) => Number(r.getAttribute("width"))),
      }));
      const classes = layer.long_paths + layer.medium_paths + layer.short_paths;
      if (bars.widths.length !== 3 || Number(bars.drawn) !== classes || !bars.widths.some((w) => w > 0)) {
        throw new Error(`path-class bars not drawn: ${JSON.stringify(bars)} for ${classes} paths`);
      }
      const table = await page.$eval("#path-table", (t) => t.textContent);
      if (!table.includes(String(layer.lower_bound_paths))) throw new Error(`the table does not show the lower bound: ${table}`);
      let px = 0;
      for (let tries = 0; tries < 10 && px < 300; tries++) { // a resize may clear the canvas until the next frame
        if (tries) await page.waitForTimeout(200);
        px = await colouredPixels(page);
      }
      if (px < 300) throw new Error(`only ${px} toolpath-coloured pixels in the 3D preview`);
      const l2d = await page.evaluate(() => window.weft.layer2dSegments);
      if (!(l2d > 0)) throw new Error("the 2D layer preview drew no segments");
      await page.screenshot({ path: join(out, "lattice.png") });
      return `${layer.paths} paths (bound ${layer.lower_bound_paths}), best score ${layer.score.toFixed(3)}, ${px} coloured pixels, 2D ${l2d} segments`;
    });

    await check(n++, "lattice: optimiser euler → the page shows paths = lower bound (minimal)", async () => {
      await waitReady(page);
      if (!(await page.$("#f-job-paths-method"))) throw new Error("no optimiser field (#f-job-paths-method) in the form");
      const before = await page.evaluate(() => window.weft.resultCount);
      await page.selectOption("#f-job-paths-method", JSON.stringify("euler"));
      const method = await page.evaluate(() => JSON.parse(window.weft.design).job.paths.method);
      if (method !== "euler") throw new Error(`the design's method is ${method}`);
      await page.click("#slice");
      await waitResult(page, before, "running with euler", jobTimeout);
      const layer = await page.evaluate(() => window.weft.result?.report?.paths?.layers?.[0] ?? null);
      if (!layer) throw new Error("no paths report");
      const shown = await page.evaluate(() => ({
        minimal: document.getElementById("path-table").dataset.minimal,
        badge: document.querySelector("#path-table .badge")?.textContent ?? "",
        kind: document.getElementById("score-plot").dataset.kind,
        verdict: document.querySelector("#score-plot .verdict")?.textContent ?? "",
      }));
      if (layer.paths !== layer.lower_bound_paths) throw new Error(`euler made ${layer.paths} paths, lower bound ${layer.lower_bound_paths}`);
      if (shown.minimal !== "true" || !/minimal/i.test(shown.badge)) throw new Error(`the table does not say minimal: ${JSON.stringify(shown)}`);
      if (shown.kind !== "bound" || !/minimal/i.test(shown.verdict)) throw new Error(`the plot does not compare with the bound: ${JSON.stringify(shown)}`);
      return `${layer.paths} paths = bound`;
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

    await check(n++, "lattice: the pattern picker shows 9 drawn thumbnails", async () => {
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
      if (counts.length !== 9) throw new Error(`${counts.length} thumbnails, expected 9`);
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


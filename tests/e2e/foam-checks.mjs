// Browser checks of the foam job (VTP foams graded between regions): the dogbone example from
// the Examples menu runs in the worker as one uninterrupted thread; its grade card plots the
// weighting functions and V*, H*, ΔE/mm along the probe line; the shared-boundary and layer
// views draw; the preview colours by ΔE per mm; the G-code equals the CLI's. Then two region
// STLs dropped on the Regions slot give one V*/H* row each, run, and an overlapping pair is
// refused naming both files. Then the stiffness map (beyond the paper): regions set by a
// modulus show modulus rows, the grade card plots the predicted modulus, a modulus outside
// the calibration is named under its field. Called by run.mjs:
//
//   import { foamChecks } from "./foam-checks.mjs";
//   await foamChecks({ baseUrl: base, weftBin: WEFT_BIN, check, newPage, outDir: OUT, first: n });
import { readFileSync, writeFileSync } from "node:fs";
import { execFileSync } from "node:child_process";
import { join } from "node:path";
import { boxStl, colouredPixels, downloadGcode, runExample, setFieldUntil, waitReady, waitResult } from "./page-helpers.mjs";

const EXAMPLE = "foam-dogbone-linear.json";

/**
 * @param {{baseUrl: string, weftBin?: string, check: Function, newPage: Function, outDir: string,
 *          first: number, timeoutMs?: number}} opts
 * @returns {Promise<number>} the next check number
 */
export async function foamChecks({ baseUrl, weftBin = process.env.WEFT_BIN, check, newPage, outDir, first, timeoutMs }) {
  const jobTimeout = timeoutMs ?? Number(process.env.E2E_TIMEOUT_S ?? 120) * 1000;
  let n = first;
  const { context, page } = await newPage();
  try {
    await check(n++, "foam: foam-dogbone-linear from the Examples menu is one thread (1 path, 0 retractions); the grade card plots w(x) and V*, H*, ΔE/mm along x; boundary and layer views draw; ΔE-per-mm colours; G-code equals the CLI's", async () => {
      const report = await runExample(page, baseUrl, EXAMPLE, jobTimeout);
      const a = report?.analysis;
      if (a?.extrusion_paths !== 1 || a?.retractions !== 0) throw new Error(`analysis: ${a?.extrusion_paths} paths, ${a?.retractions} retractions`);
      for (const s of ["regions", "slice", "raster", "grade"]) if (!report.stages.find((x) => x.stage === s)) throw new Error(`no ${s} stage (${report.stages.map((x) => x.stage)})`);
      const drawn = await page.evaluate(() => {
        const card = document.querySelector('#report .stage-card[data-stage="grade"]');
        const plots = [...(card?.querySelectorAll("[data-plot-key]") ?? [])].map((p) => p.dataset.plotKey);
        const series = [...(card?.querySelectorAll(".series[data-series]") ?? [])].map((e) => e.dataset.series);
        return { plots, series };
      });
      for (const k of ["weighting", "probe_v", "probe_h", "probe_e"]) if (!drawn.plots.includes(k)) throw new Error(`grade card plots ${drawn.plots}`);
      if (!drawn.series.some((s) => /linear \(used\)/.test(s))) throw new Error(`weighting series: ${drawn.series}`);
      // V* along x: 0.15 left of the transition, 0.4 right of it, 0.275 at the boundary.
      const probe = report.stages.find((x) => x.stage === "grade").plots.find((p) => p.key === "probe_v").series[0];
      const at = (x) => probe.y[probe.x.reduce((b, v, i) => (Math.abs(v - x) < Math.abs(probe.x[b] - x) ? i : b), 0)];
      if (Math.abs(at(-40) - 0.15) > 1e-9 || Math.abs(at(40) - 0.4) > 1e-9 || Math.abs(at(0) - 0.275) > 0.01) throw new Error(`V* along x: ${at(-40)}, ${at(0)}, ${at(40)}`);
      for (const id of ["boundaries", "layer"]) {
        await page.waitForFunction((v) => window.weft.views.find((x) => x.id === v)?.answers > 0, id, { timeout: jobTimeout }).catch(() => {});
        const view = await page.evaluate((v) => window.weft.views.find((x) => x.id === v) ?? null, id);
        if (!(view?.items > 0)) throw new Error(`the ${id} view drew nothing: ${JSON.stringify(view)}`);
      }
      await page.selectOption("#color-by", "e_per_mm");
      const legend = await page.evaluate(() => document.querySelector(".flow-legend")?.textContent ?? "");
      if (!/ΔE\/mm/.test(legend)) throw new Error(`legend reads "${legend}"`);
      const pixels = await colouredPixels(page);
      if (pixels < 500) throw new Error(`only ${pixels} coloured pixels in ΔE-per-mm mode`);
      const gcodePath = join(outDir, "foam-dogbone-linear.gcode");
      const text = (await downloadGcode(page, gcodePath)).bytes.toString("utf8");
      let native = "";
      if (weftBin) {
        const cli = join(outDir, "foam-dogbone-linear.cli.gcode");
        execFileSync(weftBin, ["run", join(process.cwd(), "examples", EXAMPLE), "--out", cli, "-q"]);
        native = readFileSync(cli, "utf8");
        if (native !== text) throw new Error("the page's G-code differs from the CLI's");
      }
      for (const [w, h, name] of [[1280, 800, "foam-desktop.png"], [390, 844, "foam-phone.png"]]) {
        await page.setViewportSize({ width: w, height: h });
        await page.waitForTimeout(300);
        await page.screenshot({ path: join(outDir, name), fullPage: w < 500 });
      }
      await page.setViewportSize({ width: 1400, height: 900 });
      const g = report.stages.find((x) => x.stage === "grade").data;
      return `${g.pieces} pieces, ${g.queries} exact evaluations, ${pixels} px coloured by ΔE/mm${native ? ", same bytes as the CLI" : ""}`;
    });

    await check(n++, "foam: two region STLs dropped on the Regions slot get a V*/H* row each and run; an overlapping pair is refused naming both files", async () => {
      const left = join(outDir, "left-block.stl");
      const right = join(outDir, "right-block.stl");
      const over = join(outDir, "over-block.stl");
      writeFileSync(left, boxStl([0, 0, 0], [30, 20, 6]));
      writeFileSync(right, boxStl([30, 0, 0], [60, 20, 6]));
      writeFileSync(over, boxStl([20, 0, 0], [50, 20, 6]));
      await waitReady(page);
      const input = '.slot[data-slot="regions"] input[type=file]';
      await page.waitForSelector(input, { state: "attached", timeout: 10000 });
      await page.setInputFiles(input, [left, right]);
      await page.waitForFunction(() => JSON.parse(window.weft.design).job.meshes?.files?.length === 2, null, { timeout: jobTimeout });
      const job = await page.evaluate(() => JSON.parse(window.weft.design).job);
      if (job.model !== undefined || job.regions.length !== 2) throw new Error(`job after loading: ${JSON.stringify(job).slice(0, 200)}`);
      for (const f of ["#f-job-regions-0-v_star", "#f-job-regions-1-h_star"]) await page.waitForSelector(f, { state: "attached", timeout: 5000 });
      await setFieldUntil(page, "#f-job-regions-1-v_star", "0.35", (d) => d.job.regions[1].v_star === 0.35, "region 2's V*");
      const before = await page.evaluate(() => window.weft.resultCount);
      await page.click("#slice");
      await waitResult(page, before, "running two dropped regions", jobTimeout);
      const r = await page.evaluate(() => window.weft.result.report);
      const g = r.stages.find((x) => x.stage === "grade");
      const vmax = g.metrics.find((m) => m.key === "v_star_max").value;
      if (Math.abs(vmax - 0.35) > 1e-9 || r.analysis.extrusion_paths !== 1) throw new Error(`V* max ${vmax}, ${r.analysis.extrusion_paths} paths`);
      // Replace the right block by one reaching into the left: refused, both files named.
      await page.setInputFiles(input, [over]);
      await page.waitForFunction(() => JSON.parse(window.weft.design).job.meshes?.files?.length === 3, null, { timeout: jobTimeout }).catch(() => {});
      const names = await page.evaluate(() => JSON.parse(window.weft.design).job.meshes?.files ?? []);
      if (names.length !== 3) throw new Error(`meshes after the third file: ${names}`);
      // Drop the right block so left and over remain.
      await page.evaluate(() => {
        const row = [...document.querySelectorAll('.slot[data-slot="regions"] li[data-file]')].find((li) => li.dataset.file === "right-block.stl");
        row?.querySelector("button")?.click();
      });
      await page.waitForFunction(() => JSON.parse(window.weft.design).job.meshes?.files?.length === 2, null, { timeout: jobTimeout });
      const count = await page.evaluate(() => window.weft.resultCount);
      await page.click("#slice");
      const message = await page.waitForFunction(() => {
        const err = document.getElementById("error");
        return !err.hidden && !window.weft.busy ? document.getElementById("error-text").textContent : false;
      }, null, { timeout: jobTimeout }).then((h) => h.jsonValue());
      if (!/overlap/.test(message) || !/left-block\.stl/.test(message) || !/over-block\.stl/.test(message)) throw new Error(`refusal reads "${message}"`);
      if ((await page.evaluate(() => window.weft.resultCount)) !== count) throw new Error("a result was shown for overlapping regions");
      return `V* max ${vmax}; refused: "${message.slice(0, 120)}"`;
    });

    await check(n++, "foam: the stiffness map foam-stiffness-sectors: regions set by a modulus show modulus rows, not V*; the grade card plots the predicted modulus 20 → 2 kPa along x and each region's V*; a modulus outside the calibration is named under its field; G-code equals the CLI's", async () => {
      const file = "foam-stiffness-sectors.json";
      const report = await runExample(page, baseUrl, file, jobTimeout);
      const g = report.stages.find((x) => x.stage === "grade");
      const vs = g.metrics.filter((m) => m.key === "region_v_star").map((m) => m.value);
      if (vs.length !== 3 || Math.abs(vs[0] - 0.16011) > 1e-4 || Math.abs(vs[2] - 0.34521) > 1e-4) throw new Error(`region V*: ${vs}`);
      const modulus = g.plots.find((p) => p.key === "probe_modulus")?.series[0];
      if (!modulus || Math.abs(Math.max(...modulus.y) - 20) > 1e-6 || Math.abs(Math.min(...modulus.y) - 2) > 1e-6) throw new Error(`predicted modulus: ${modulus ? [Math.min(...modulus.y), Math.max(...modulus.y)] : "none"}`);
      const rows = await page.evaluate(() => ({
        modulus: Boolean(document.querySelector("#f-job-regions-1-modulus_kpa")),
        vstar: Boolean(document.querySelector("#f-job-regions-1-v_star")),
        plotted: [...document.querySelectorAll('#report .stage-card[data-stage="grade"] [data-plot-key]')].map((p) => p.dataset.plotKey),
      }));
      if (!rows.modulus || rows.vstar) throw new Error(`form rows: modulus ${rows.modulus}, V* ${rows.vstar}`);
      if (!rows.plotted.includes("probe_modulus")) throw new Error(`grade card plots ${rows.plotted}`);
      if (weftBin) {
        const text = (await downloadGcode(page, join(outDir, "foam-stiffness-sectors.gcode"))).bytes.toString("utf8");
        const cli = join(outDir, "foam-stiffness-sectors.cli.gcode");
        execFileSync(weftBin, ["run", join(process.cwd(), "examples", file), "--out", cli, "-q"]);
        if (readFileSync(cli, "utf8") !== text) throw new Error("the page's G-code differs from the CLI's");
      }
      for (const [w, h, name] of [[1280, 800, "foam-stiffness-desktop.png"], [390, 844, "foam-stiffness-phone.png"]]) {
        await page.setViewportSize({ width: w, height: h });
        await page.evaluate(() => document.querySelector('#report .stage-card[data-stage="grade"] [data-plot-key="probe_modulus"]')?.scrollIntoView());
        await page.waitForTimeout(300);
        await page.screenshot({ path: join(outDir, name) });
      }
      await page.setViewportSize({ width: 1400, height: 900 });
      // 40 kPa is stiffer than the paper's sweep gives: named under the field, with the range.
      await page.evaluate(() => document.querySelector("#f-job-regions-1-modulus_kpa")?.closest("details")?.setAttribute("open", ""));
      await page.fill("#f-job-regions-1-modulus_kpa", "40");
      await page.dispatchEvent("#f-job-regions-1-modulus_kpa", "change");
      const said = await page.waitForFunction(() => {
        const e = document.getElementById("f-job-regions-1-modulus_kpa-error");
        return e && !e.hidden && e.textContent ? e.textContent : false;
      }, null, { timeout: 10000 }).then((h) => h.jsonValue());
      if (!/outside the calibration/.test(said) || !/22\.68 kPa/.test(said)) throw new Error(`the field says "${said}"`);
      // Back to V* for region 2: its V* row shows and the modulus row goes.
      await page.fill("#f-job-regions-1-modulus_kpa", "8");
      await page.dispatchEvent("#f-job-regions-1-modulus_kpa", "change");
      await page.evaluate(() => document.querySelector("#f-job-regions-1-set_by")?.closest("details")?.setAttribute("open", ""));
      await page.selectOption("#f-job-regions-1-set_by", JSON.stringify("v_star"));
      await page.waitForSelector("#f-job-regions-1-v_star", { state: "attached", timeout: 5000 });
      if (await page.$("#f-job-regions-1-modulus_kpa")) throw new Error("the modulus row stayed after choosing V*");
      return `region V* ${vs.map((v) => v.toFixed(4)).join(", ")}; modulus 2–20 kPa along x; refused: "${said.slice(0, 100)}"`;
    });
  } finally {
    await context.close();
  }
  return n;
}

// Browser checks of the axisymmetric job (uniform infill on a curved platform): the
// hourglass example from the Examples menu runs in the worker; the platform card plots κ,
// the metric and the Christoffel symbols; the points card plots energy, sorted kernel density
// and the neighbour-distance histogram for seed and result; the embedded-map and 3D platform
// views draw through inspect; the downloaded G-code carries rotary words and matches the
// native CLI byte for byte; the custom platform's control points are edited as lines and a
// kinked polygon is refused naming the field; the tool-axis smoothing lowers the axes'
// accelerations in the axes card. Called by run.mjs:
//
//   import { axisymChecks } from "./axisym-checks.mjs";
//   await axisymChecks({ baseUrl: base, weftBin: WEFT_BIN, check, newPage, outDir: OUT, first: n });
import { readFileSync, writeFileSync } from "node:fs";
import { execFileSync } from "node:child_process";
import { join } from "node:path";
import { downloadGcode, runExample, waitReady, waitResult } from "./page-helpers.mjs";

const EXAMPLE = "hourglass-omega3.json";

/**
 * @param {{baseUrl: string, weftBin?: string, check: Function, newPage: Function, outDir: string,
 *          first: number, timeoutMs?: number}} opts
 * @returns {Promise<number>} the next check number
 */
export async function axisymChecks({ baseUrl, weftBin = process.env.WEFT_BIN, check, newPage, outDir, first, timeoutMs }) {
  const jobTimeout = timeoutMs ?? Number(process.env.E2E_TIMEOUT_S ?? 120) * 1000;
  let n = first;
  const { context, page } = await newPage();
  try {
    await check(n++, "axisymmetric: hourglass-omega3 from the Examples menu runs; platform and points cards plot their curves; map and 3D views draw; G-code has B/C words and equals the CLI's", async () => {
      const report = await runExample(page, baseUrl, EXAMPLE, jobTimeout);
      const stage = (name) => report?.stages?.find((s) => s.stage === name);
      for (const s of ["platform", "points", "path"]) if (!stage(s)) throw new Error(`no ${s} stage in the report (${(report?.stages ?? []).map((x) => x.stage)})`);
      const drawn = await page.evaluate(() => {
        const card = (s) => document.querySelector(`#report .stage-card[data-stage="${s}"]`);
        const plots = (s) => [...(card(s)?.querySelectorAll("svg[data-plot-kind]") ?? [])].map((p) => p.dataset.plotKind);
        const series = (s) => [...(card(s)?.querySelectorAll(".series[data-series]") ?? [])].map((e) => e.dataset.series);
        const metric = (s, key) => card(s)?.querySelector(`.metrics [data-key="${key}"] dd`)?.textContent ?? null;
        return { platform: plots("platform"), points: plots("points"), pointSeries: series("points"), n: metric("points", "points"), reduction: metric("points", "std_reduction"), visited: metric("path", "visited"), crossings: metric("path", "crossings") };
      });
      if (drawn.platform.filter((k) => k === "line").length < 3) throw new Error(`platform card plots: ${drawn.platform}`);
      if (!drawn.points.includes("histogram") || drawn.points.filter((k) => k === "line").length < 2) throw new Error(`points card plots: ${drawn.points}`);
      for (const name of ["seed", "repulsion"]) if (!drawn.pointSeries.includes(name)) throw new Error(`points card series: ${drawn.pointSeries}`);
      const points = stage("points").data;
      const path = stage("path").data;
      if (path.visited !== points.points || path.crossings_left !== 0) throw new Error(`path visits ${path.visited} of ${points.points} points with ${path.crossings_left} crossings`);
      if (!(points.std_mm < points.seed_std_mm)) throw new Error(`repulsion did not even the spacing: ${points.seed_std_mm} → ${points.std_mm}`);
      for (const id of ["map", "platform3d"]) {
        await page.waitForFunction((v) => window.weft.views.find((x) => x.id === v)?.answers > 0, id, { timeout: jobTimeout }).catch(() => {});
        const view = await page.evaluate((v) => window.weft.views.find((x) => x.id === v) ?? null, id);
        if (!(view?.items > 0)) throw new Error(`the ${id} view drew nothing: ${JSON.stringify(view)}`);
      }
      // Step the map view to the path (index 3).
      const input = '.view-card[data-view="map"] input[type=number]';
      const k = await page.evaluate(() => window.weft.views.find((x) => x.id === "map").answers);
      await page.fill(input, "3");
      await page.dispatchEvent(input, "change");
      await page.waitForFunction((a) => { const v = window.weft.views.find((x) => x.id === "map"); return v.answers > a && v.index === 2; }, k, { timeout: jobTimeout });
      // The view names its own legend entries (not the feature names "Contour" / "Infill").
      const legend = await page.evaluate(() => document.querySelector('.view-card[data-view="map"] .mini-legend')?.textContent ?? "");
      if (!/outline of Ω/.test(legend) || !/path \(geodesics\)/.test(legend) || /Contour|Lattice/.test(legend)) throw new Error(`map legend reads "${legend}"`);
      const gcodePath = join(outDir, "hourglass-omega3.gcode");
      const text = (await downloadGcode(page, gcodePath)).bytes.toString("utf8");
      const rotary = text.split("\n").filter((l) => /^G1 .*\bB-?\d/.test(l) && /\bC-?\d/.test(l)).length;
      if (rotary < 100) throw new Error(`only ${rotary} G1 lines with B and C words`);
      let native = "";
      if (weftBin) {
        const cli = join(outDir, "hourglass-omega3.cli.gcode");
        execFileSync(weftBin, ["run", join(process.cwd(), "examples", EXAMPLE), "--out", cli, "-q"]);
        native = readFileSync(cli, "utf8");
        if (native !== text) throw new Error("the page's G-code differs from the CLI's");
      }
      for (const [w, h, name] of [[1280, 800, "axisym-desktop.png"], [390, 844, "axisym-phone.png"]]) {
        await page.setViewportSize({ width: w, height: h });
        await page.waitForTimeout(300);
        await page.screenshot({ path: join(outDir, name), fullPage: w < 500 });
      }
      await page.setViewportSize({ width: 1400, height: 900 });
      return `N ${points.points}, spread −${(100 * points.std_reduction).toFixed(1)} %, path ${path.length_mm.toFixed(0)} mm, ${rotary} rotary moves${native ? ", same bytes as the CLI" : ""}`;
    });

    await check(n++, "axisymmetric: smoothing the tool axis (most tilt 10°) in the form lowers every axis's acceleration in the axes card's table, as drawn", async () => {
      await waitReady(page);
      const field = "#f-job-tool_axis-max_tilt_deg";
      await page.waitForSelector(field, { state: "attached", timeout: 5000 });
      const before = await page.evaluate(() => window.weft.resultCount);
      await page.evaluate((sel) => { const el = document.querySelector(sel); el.closest("details")?.setAttribute("open", ""); }, field);
      await page.fill(field, "10");
      await page.dispatchEvent(field, "change");
      const tilt = await page.evaluate(() => JSON.parse(window.weft.design).job.tool_axis?.max_tilt_deg);
      if (tilt !== 10) throw new Error(`the design's tilt is ${tilt}`);
      await page.click("#slice");
      await waitResult(page, before, "running with a smoothed tool axis", jobTimeout);
      const rows = await page.evaluate(() => {
        const table = document.querySelector('#report .stage-card[data-stage="axes"] table.report-table[data-key="dynamics"]');
        return [...(table?.querySelectorAll("tbody tr") ?? [])].map((r) => [...r.children].map((c) => c.textContent.trim()));
      });
      if (rows.length !== 3) throw new Error(`the dynamics table has ${rows.length} rows (want tool axis, B, C): ${JSON.stringify(rows)}`);
      const num = (t) => Number(t.replace(/[\s,\u202f]/g, ""));
      const cuts = rows.map((r) => [r[0], num(r[2]), num(r[4])]);
      const worse = cuts.filter(([, raw, smooth]) => !(smooth < raw));
      if (worse.length) throw new Error(`smoothing did not lower: ${JSON.stringify(worse)}`);
      return cuts.map(([a, raw, smooth]) => `${a} ${raw} → ${smooth} °/s²`).join(", ");
    });

    await check(n++, "axisymmetric: barrel-graded draws commanded against measured density; Ω drawn by clicks on the map fills the polygon field; then 2 layers and a polygon with a hole from the form: the per-layer table, the domain's hole and the map's 6 pictures", async () => {
      // Its own page: the next check edits the hourglass loaded above.
      const own = await newPage();
      const page = own.page;
      try {
        await page.goto(`${baseUrl}/www/`);
        await waitReady(page);
        await page.waitForSelector('#examples option[value="barrel-graded.json"]', { state: "attached", timeout: 10000 }).catch(() => {});
        let before = await page.evaluate(() => window.weft.resultCount);
        await page.selectOption("#examples", "barrel-graded.json");
        await waitResult(page, before, "running barrel-graded", jobTimeout);
        const graded = await page.evaluate(() => {
          const card = document.querySelector('#report .stage-card[data-stage="points"]');
          const plot = card?.querySelector('[data-plot-key="graded_density"]');
          const series = [...(plot?.querySelectorAll(".series[data-series]") ?? [])].map((e) => e.dataset.series);
          const value = (key) => card?.querySelector(`.metrics [data-key="${key}"] dd`)?.firstChild?.textContent ?? null;
          return { series, reduction: value("rel_std_reduction") };
        });
        if (graded.series.length < 3) throw new Error(`the graded-density plot draws ${graded.series.length} series: ${graded.series}`);
        if (!(Number(graded.reduction) > 30)) throw new Error(`spread against the target reduced by ${graded.reduction} %`);
        // Two layers on a polygon with a square hole, typed into the form.
        await page.selectOption("#f-job-domain-kind", JSON.stringify("polygon"));
        await page.waitForSelector("#f-job-domain-polygon", { state: "visible", timeout: 5000 });
        // Draw Ω on the map: the view offers it for a polygon domain; four clicks, Finish.
        const mapCard = '.view-card[data-view="map"]';
        await page.waitForFunction((c) => document.querySelector(`${c} .view-tools`)?.hidden === false, mapCard, { timeout: jobTimeout });
        await page.click(`${mapCard} .view-draw`);
        const box = await (await page.$(`${mapCard} canvas`)).boundingBox();
        for (const [fx, fy] of [[0.35, 0.4], [0.65, 0.4], [0.65, 0.6], [0.35, 0.6]]) await page.mouse.click(box.x + fx * box.width, box.y + fy * box.height);
        const finish = await page.textContent(`${mapCard} .view-finish`);
        if (!/4 points/.test(finish)) throw new Error(`the Finish button reads "${finish}"`);
        await page.click(`${mapCard} .view-finish`);
        const drawn = await page.evaluate(() => JSON.parse(window.weft.design).job.domain.polygon);
        // (u, θ) pairs: x on the map is θ (rightwards), y is u (upwards).
        const ok = drawn?.length === 4 && drawn[0][1] < drawn[1][1] && drawn[2][0] < drawn[1][0] && Math.abs(drawn[0][0] - drawn[1][0]) < 1e-3 && drawn.every(([u, t]) => Number.isFinite(u) && Number.isFinite(t));
        if (!ok) throw new Error(`the drawn outline is ${JSON.stringify(drawn)}`);
        const typed = await page.inputValue("#f-job-domain-polygon");
        if (typed.split("\n").filter((l) => l.trim()).length !== 4) throw new Error(`the polygon field shows "${typed}" after drawing`);
        await page.fill("#f-job-domain-polygon", "0.8 0\n1.2 0\n1.2 1\n0.8 1");
        await page.dispatchEvent("#f-job-domain-polygon", "change");
        await page.fill("#f-job-domain-holes", "0.95 0.4\n1.05 0.4\n1.05 0.6\n0.95 0.6");
        await page.dispatchEvent("#f-job-domain-holes", "change");
        await page.fill("#f-job-layers", "2");
        await page.dispatchEvent("#f-job-layers", "change");
        const job = await page.evaluate(() => JSON.parse(window.weft.design).job);
        if (job.layers !== 2 || job.domain.holes?.length !== 1 || job.domain.holes[0].length !== 4) throw new Error(`the design did not take the form: ${JSON.stringify({ layers: job.layers, holes: job.domain.holes })}`);
        before = await page.evaluate(() => window.weft.resultCount);
        await page.click("#slice");
        await waitResult(page, before, "running 2 layers with a hole", jobTimeout);
        const shown = await page.evaluate(() => {
          const table = document.querySelector('#report .stage-card[data-stage="path"] table.report-table[data-key="layers"]');
          const rows = [...(table?.querySelectorAll("tbody tr") ?? [])].map((r) => [...r.children].map((c) => c.textContent.trim()));
          const holes = document.querySelector('#report .stage-card[data-stage="domain"] .metrics [data-key="holes"] dd')?.firstChild?.textContent ?? null;
          return { rows, holes };
        });
        if (shown.rows.length !== 2 || shown.holes !== "1") throw new Error(`per-layer rows ${shown.rows.length}, holes kept ${shown.holes}`);
        await page.waitForFunction(() => (window.weft.views.find((x) => x.id === "map")?.count ?? 0) === 6, null, { timeout: jobTimeout });
        const input = '.view-card[data-view="map"] input[type=number]';
        const k = await page.evaluate(() => window.weft.views.find((x) => x.id === "map").answers);
        await page.fill(input, "5");
        await page.dispatchEvent(input, "change");
        await page.waitForFunction((a) => { const v = window.weft.views.find((x) => x.id === "map"); return v.answers > a && v.index === 4; }, k, { timeout: jobTimeout });
        const info = await page.evaluate(() => document.querySelector('.view-card[data-view="map"] output.hint')?.textContent ?? "");
        if (!/layer 2 of 2/.test(info)) throw new Error(`the map's caption reads "${info}"`);
        await page.screenshot({ path: join(outDir, "axisym-layers-hole.png"), fullPage: true });
        return `drawn ${JSON.stringify(drawn)}; graded: ${graded.series.length} series, spread −${graded.reduction} %; layers: ${shown.rows.map((r) => `${r[0]}: ${r[3]} points`).join(", ")}; map "${info.slice(0, 60)}"`;
      } finally {
        await own.context.close();
      }
    });

    await check(n++, "axisymmetric: a custom platform's control points are edited as lines; a kinked polygon is refused naming the field and the previous result stays", async () => {
      await waitReady(page);
      await page.selectOption("#f-job-platform-preset", JSON.stringify("custom"));
      const area = "#f-job-platform-control_points";
      await page.waitForSelector(area, { state: "visible", timeout: 5000 });
      const lines = (await page.inputValue(area)).split("\n").filter((l) => l.trim() !== "");
      if (lines.length !== 25) throw new Error(`the hourglass polygon shows ${lines.length} lines, expected 25`);
      const kinked = [...lines];
      kinked[7] = "60 80"; // the second segment's first inner point: breaks C¹ at the knot
      await page.fill(area, kinked.join("\n"));
      await page.dispatchEvent(area, "change");
      await page.waitForFunction(() => document.querySelector("#f-job-platform-control_points-error:not([hidden])") || /jumps/.test(document.querySelector("#error")?.textContent ?? ""), null, { timeout: 10000 });
      const message = await page.evaluate(() => (document.querySelector("#f-job-platform-control_points-error:not([hidden])") ?? document.querySelector("#error"))?.textContent ?? "");
      if (!/jump|knot/.test(message)) throw new Error(`the refusal does not say what is wrong: ${message}`);
      writeFileSync(join(outDir, "axisym-refusal.txt"), message);
      await page.screenshot({ path: join(outDir, "axisym-custom.png") });
      return message.slice(0, 120);
    });
  } finally {
    await context.close();
  }
  return n;
}

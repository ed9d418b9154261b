// Browser checks of the graded job (CT-driven graded scaffolds): the graded-phantom example
// (a DICOM series embedded as a .zip) runs in the worker; the volume, surface, density and
// grade cards report; the slice views draw the CT with iso-contours and the ROI, with a
// value window; the surface view offers its STL; the G-code equals the CLI's; a dropped
// .zip fills the volume slot and a truncated DICOM file is refused by name while the design
// keeps its other inputs. Called by run.mjs:
//
//   import { gradedChecks } from "./graded-checks.mjs";
//   await gradedChecks({ baseUrl: base, weftBin: WEFT_BIN, check, newPage, outDir: OUT, first: n });
import { readFileSync } from "node:fs";
import { execFileSync } from "node:child_process";
import { inflateRawSync } from "node:zlib";
import { join } from "node:path";
import { downloadGcode, waitReady, waitResult } from "./page-helpers.mjs";

const EXAMPLE = "graded-phantom.json";

/**
 * @param {{baseUrl: string, weftBin?: string, check: Function, newPage: Function, outDir: string,
 *          first: number, timeoutMs?: number}} opts
 * @returns {Promise<number>} the next check number
 */
export async function gradedChecks({ baseUrl, weftBin = process.env.WEFT_BIN, check, newPage, outDir, first, timeoutMs }) {
  const jobTimeout = timeoutMs ?? Number(process.env.E2E_TIMEOUT_S ?? 120) * 1000;
  let n = first;
  const { context, page } = await newPage();
  try {
    await check(n++, "graded: graded-phantom from the Examples menu runs; volume, surface, density and grade cards report; slice views draw HU with contours and the ROI; the surface view offers an STL; G-code equals the CLI's", async () => {
      await page.goto(`${baseUrl}/www/`);
      await waitReady(page);
      await page.waitForSelector(`#examples option[value="${EXAMPLE}"]`, { state: "attached", timeout: 10000 }).catch(() => {});
      const before = await page.evaluate(() => window.weft.resultCount);
      await page.selectOption("#examples", EXAMPLE);
      await waitResult(page, before, `running ${EXAMPLE}`, jobTimeout);
      const report = await page.evaluate(() => window.weft.result?.report ?? null);
      const stage = (name) => report?.stages?.find((s) => s.stage === name);
      for (const s of ["volume", "surface", "density", "slice", "grade", "compare"]) if (!stage(s)) throw new Error(`no ${s} stage in the report (${(report?.stages ?? []).map((x) => x.stage)})`);
      if (stage("surface").data.closed !== true) throw new Error(`surface not closed: ${JSON.stringify(stage("surface").data)}`);
      const drawn = await page.evaluate(() => {
        const card = (s) => document.querySelector(`#report .stage-card[data-stage="${s}"]`);
        const plots = (s) => [...(card(s)?.querySelectorAll("svg[data-plot-kind]") ?? [])].map((p) => p.dataset.plotKind);
        const metric = (s, key) => card(s)?.querySelector(`.metrics [data-key="${key}"] dd`)?.textContent ?? null;
        return { density: plots("density"), grade: plots("grade"), compare: plots("compare"), editError: metric("compare", "edit_error"), rhoMin: metric("density", "rho_min"), cell: metric("density", "cell"), saved: metric("grade", "saved") };
      });
      if (!drawn.density.includes("histogram") || drawn.density.filter((k) => k === "line").length < 2) throw new Error(`density card plots: ${drawn.density}`);
      if (!drawn.grade.includes("line")) throw new Error(`grade card plots: ${drawn.grade}`);
      if (!drawn.compare.includes("line") || !drawn.editError) throw new Error(`compare card: ${JSON.stringify(drawn)}`);
      if (!drawn.rhoMin || !drawn.cell) throw new Error(`density metrics: ${JSON.stringify(drawn)}`);
      for (const id of ["axial", "coronal", "sagittal", "density", "surface"]) {
        await page.waitForFunction((v) => window.weft.views.find((x) => x.id === v)?.answers > 0, id, { timeout: jobTimeout }).catch(() => {});
        const view = await page.evaluate((v) => window.weft.views.find((x) => x.id === v) ?? null, id);
        if (!(view?.items > 0)) throw new Error(`the ${id} view drew nothing: ${JSON.stringify(view)}`);
      }
      // The axial view at slice 16 (z = 30 mm, inside the ROI): its legend names the contour
      // levels and the ROI; its window inputs hold the bone window.
      const answers = await page.evaluate(() => window.weft.views.find((x) => x.id === "axial").answers);
      await page.fill('.view-card[data-view="axial"] input[type=number]', "16");
      await page.dispatchEvent('.view-card[data-view="axial"] input[type=number]', "change");
      await page.waitForFunction((a) => { const v = window.weft.views.find((x) => x.id === "axial"); return v.answers > a && v.index === 15; }, answers, { timeout: jobTimeout });
      const axial = await page.evaluate(() => {
        const card = document.querySelector('.view-card[data-view="axial"]');
        return {
          legend: card?.querySelector(".mini-legend")?.textContent ?? "",
          window: [...(card?.querySelectorAll(".view-window input") ?? [])].map((i) => Number(i.value)),
          windowHidden: card?.querySelector(".view-window")?.hidden,
        };
      });
      if (!/350 HU/.test(axial.legend) || !/region of interest/.test(axial.legend)) throw new Error(`axial legend reads "${axial.legend}"`);
      if (axial.windowHidden || axial.window.length !== 2 || !(axial.window[1] > axial.window[0])) throw new Error(`axial window: ${JSON.stringify(axial)}`);
      const stl = await page.evaluate(() => document.querySelector('.view-card[data-view="surface"] .view-stl')?.hidden === false);
      if (!stl) throw new Error("the surface view offers no STL download");
      const [download] = await Promise.all([page.waitForEvent("download"), page.click('.view-card[data-view="surface"] .view-stl')]);
      const stlPath = join(outDir, "graded-surface.stl");
      await download.saveAs(stlPath);
      const stlBytes = readFileSync(stlPath);
      const triangles = stlBytes.readUInt32LE(80);
      if (stlBytes.length !== 84 + 50 * triangles || triangles < 100) throw new Error(`STL of ${stlBytes.length} bytes, ${triangles} triangles`);
      const text = (await downloadGcode(page, join(outDir, "graded-phantom.gcode"))).bytes.toString("utf8");
      if (weftBin) {
        const cli = join(outDir, "graded-phantom.cli.gcode");
        execFileSync(weftBin, ["run", join(process.cwd(), "examples", EXAMPLE), "--out", cli, "-q"]);
        if (readFileSync(cli, "utf8") !== text) throw new Error("the page's G-code differs from the CLI's");
      }
      for (const [w, h, name] of [[1280, 800, "graded-desktop.png"], [390, 844, "graded-phone.png"]]) {
        await page.setViewportSize({ width: w, height: h });
        await page.waitForTimeout(300);
        await page.screenshot({ path: join(outDir, name), fullPage: w < 500 });
      }
      await page.setViewportSize({ width: 1400, height: 900 });
      const g = stage("grade").data;
      return `${g.segments} graded segments, ρ_min ${drawn.rhoMin}, material saved ${drawn.saved}; STL ${triangles} triangles${weftBin ? "; same bytes as the CLI" : ""}`;
    });

    await check(n++, "graded: a .zip series dropped on the volume slot is used; a truncated DICOM file is refused naming it and the design keeps its settings", async () => {
      await waitReady(page);
      // The example's own series, unpacked from its share-link form (base64url of raw deflate).
      const design = JSON.parse(readFileSync(join(process.cwd(), "examples", EXAMPLE), "utf8"));
      const packed = design.job.volume.file.embedded;
      const zip = inflateRawSync(Buffer.from(packed.replace(/-/g, "+").replace(/_/g, "/"), "base64"));
      const input = '.slot[data-slot="volume"] input[type=file]';
      let before = await page.evaluate(() => window.weft.resultCount);
      await page.setInputFiles(input, { name: "dropped-series.zip", mimeType: "application/zip", buffer: zip });
      await page.waitForFunction(() => JSON.parse(window.weft.design).job.volume?.file?.name === "dropped-series.zip", null, { timeout: 10000 });
      await waitResult(page, before, "running the dropped .zip", jobTimeout);
      const iso = await page.evaluate(() => JSON.parse(window.weft.design).job.surface.iso);
      // A broken file: the DICOM preamble and a header cut short.
      const broken = Buffer.concat([Buffer.alloc(128), Buffer.from("DICM"), Buffer.from([2, 0, 0, 0, 0x55, 0x4c, 4, 0])]);
      await page.setInputFiles(input, { name: "IM0007.dcm", mimeType: "application/dicom", buffer: broken });
      await page.waitForFunction(() => !document.getElementById("error").hidden || JSON.parse(window.weft.design).job.volume?.file?.name === "IM0007.dcm", null, { timeout: jobTimeout });
      if (!(await page.evaluate(() => window.weft.busy === false))) await page.waitForFunction(() => window.weft.busy === false, null, { timeout: jobTimeout });
      await page.waitForFunction(() => !document.getElementById("error").hidden, null, { timeout: jobTimeout });
      const message = await page.textContent("#error-text");
      if (!/IM0007\.dcm/.test(message)) throw new Error(`the error does not name the file: ${message}`);
      const after = await page.evaluate(() => JSON.parse(window.weft.design).job);
      if (after.surface.iso !== iso || after.kind !== "graded") throw new Error(`the design lost its settings: ${JSON.stringify(after).slice(0, 200)}`);
      return `zip run; refused: ${message.slice(0, 120)}`;
    });
  } finally {
    await context.close();
  }
  return n;
}

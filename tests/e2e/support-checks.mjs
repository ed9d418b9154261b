// Browser check of supports (issue 44): a T-shaped part (a stem and a bar, 15 mm overhangs)
// dropped on the page, "Supports" switched on in the form: the run prints support and its
// interface (their own features and colours in the legend), the support settings show in the
// form with units, and the page's G-code is the CLI's for the same design and file. The form
// is photographed at 1280×800 and 390×844.
//
//   import { supportChecks } from "./support-checks.mjs";
//   await supportChecks({ newPage, weftBin, check, outDir: OUT, base, first: n, timeoutMs });
import { execFileSync } from "node:child_process";
import { readFileSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { boxStl, downloadGcode, waitReady, waitResult } from "./page-helpers.mjs";

/** A binary STL of several boxes (overlapping shells; the slicer unions them). */
function boxesStl(boxes) {
  const parts = boxes.map(([a, b]) => boxStl(a, b, "weft e2e T"));
  const count = parts.reduce((n, p) => n + p.readUInt32LE(80), 0);
  const head = Buffer.alloc(84);
  head.write("weft e2e T-bracket", 0);
  head.writeUInt32LE(count, 80);
  return Buffer.concat([head, ...parts.map((p) => p.subarray(84))]);
}

export async function supportChecks({ newPage, weftBin, check, outDir, base, first, timeoutMs }) {
  await check(first, "supports: a T-shaped part dropped, Supports switched on in the form: support and its interface print in their own colours, the support rows show with units, and the G-code is the CLI's (desktop and phone)", async () => {
    const stl = boxesStl([
      [[15, 0, 0], [25, 10, 20]],
      [[0, 0, 20], [40, 10, 25]],
    ]);
    const stlPath = join(outDir, "t-bracket.stl");
    writeFileSync(stlPath, stl);
    const said = [];
    for (const viewport of [{ width: 1280, height: 800 }, { width: 390, height: 844 }]) {
      const { context, page } = await newPage();
      try {
        await page.setViewportSize(viewport);
        await page.goto(`${base}/www/`);
        await waitReady(page);
        let before = await page.evaluate(() => window.weft.resultCount);
        await page.setInputFiles("#file", { name: "t-bracket.stl", mimeType: "model/stl", buffer: stl });
        await waitResult(page, before, "slicing t-bracket.stl", timeoutMs);
        const box = "#f-job-slice-support-enabled";
        await page.waitForSelector(box, { state: "attached", timeout: 10000 });
        await page.evaluate((sel) => document.querySelector(sel)?.closest("details")?.setAttribute("open", ""), box);
        await page.check(box);
        await page.dispatchEvent(box, "change");
        await page.waitForFunction(() => JSON.parse(window.weft.design).job.slice.support?.enabled === true, null, { timeout: 10000 });
        const rows = await page.evaluate(() => ({
          style: Boolean(document.querySelector("#f-job-slice-support-style")),
          gap: document.querySelector("#f-job-slice-support-z_gap_mm")?.closest(".field, label, div")?.textContent ?? "",
        }));
        if (!rows.style || !/mm/.test(rows.gap)) throw new Error(`support rows after switching on: style ${rows.style}, gap row "${rows.gap.slice(0, 80)}"`);
        before = await page.evaluate(() => window.weft.resultCount);
        await page.click("#slice");
        await waitResult(page, before, "slicing with supports", timeoutMs);
        await page.selectOption("#color-by", "feature");
        await page.waitForTimeout(300);
        const legend = await page.$eval("#legend", (e) => e.textContent);
        if (!/Support material interface/.test(legend) || !/Support material/.test(legend.replace("Support material interface", ""))) {
          throw new Error(`the legend lists ${legend}`);
        }
        await page.evaluate((sel) => document.querySelector(sel)?.scrollIntoView({ block: "center" }), box);
        await page.screenshot({ path: join(outDir, `supports-form-${viewport.width}.png`) });
        const web = await downloadGcode(page, join(outDir, `t-bracket-${viewport.width}.gcode`));
        const text = web.bytes.toString("utf8");
        const support = (text.match(/;TYPE:Support material\n/g) ?? []).length;
        const iface = (text.match(/;TYPE:Support material interface\n/g) ?? []).length;
        if (support === 0 || iface === 0) throw new Error(`G-code: ${support} support and ${iface} interface blocks`);
        if (weftBin) {
          const designPath = join(outDir, "t-bracket.json");
          writeFileSync(designPath, await page.evaluate(() => window.weft.design));
          const cliOut = join(outDir, "t-bracket-cli.gcode");
          execFileSync(weftBin, ["run", designPath, "--input", stlPath, "--out", cliOut, "-q"], { stdio: ["ignore", "pipe", "pipe"] });
          if (!web.bytes.equals(readFileSync(cliOut))) throw new Error("the page's G-code differs from the CLI's");
        }
        said.push(`${viewport.width}px: ${support} support and ${iface} interface blocks${weftBin ? ", same bytes as the CLI" : ""}`);
      } finally {
        await context.close();
      }
    }
    return said.join("; ");
  });
  return first + 1;
}

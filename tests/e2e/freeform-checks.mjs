// Browser checks of the freeform job (wireframe sequencing, issue 13): the lattice tower from
// the Examples menu is planned in the worker; its cards report the constraints, the plan's
// largest ε, the deadheads and both costs with the paper's Fig. 8 plots; the print-sequence
// view draws printed, current and waiting beams and Play steps through it; the G-code equals
// the CLI's. Then a real wireframe JSON dropped on a slicing job switches the job to freeform,
// fills the Wireframe slot (summary: beams, joints, grounded) and runs; the same design with
// the default 13° cone on the conmech truss is refused naming the two beams, and the design
// keeps its settings. The exact search's card on a small dome: the proven optimum below the
// heuristic planner's, printed. A tilting 5-axis nozzle on the truss; a tower planned in
// bands. Called by run.mjs:
//
//   import { freeformChecks } from "./freeform-checks.mjs";
//   await freeformChecks({ baseUrl: base, weftBin: WEFT_BIN, check, newPage, outDir: OUT, first: n });
import { readFileSync } from "node:fs";
import { execFileSync } from "node:child_process";
import { join } from "node:path";
import { confirmBigJobs, downloadGcode, runExample, waitReady, waitResult } from "./page-helpers.mjs";

const EXAMPLE = "freeform-tower.json";

/** Screenshots `selector`, centred, at desktop and phone sizes: `<base>-desktop.png`, `<base>-phone.png`. */
async function shots(page, selector, base) {
  for (const [w, h, name] of [[1280, 800, "desktop"], [390, 844, "phone"]]) {
    await page.setViewportSize({ width: w, height: h });
    await page.waitForTimeout(300);
    await page.evaluate((sel) => document.querySelector(sel)?.scrollIntoView({ block: "center" }), selector);
    await page.screenshot({ path: `${base}-${name}.png` });
  }
  await page.setViewportSize({ width: 1400, height: 900 });
}

/**
 * @param {{baseUrl: string, weftBin?: string, check: Function, newPage: Function, outDir: string,
 *          first: number, timeoutMs?: number}} opts
 * @returns {Promise<number>} the next check number
 */
export async function freeformChecks({ baseUrl, weftBin = process.env.WEFT_BIN, check, newPage, outDir, first, timeoutMs }) {
  const jobTimeout = timeoutMs ?? Number(process.env.E2E_TIMEOUT_S ?? 120) * 1000;
  let n = first;
  const { context, page } = await newPage();
  try {
    await check(n++, "freeform: freeform-tower from the Examples menu is planned in the worker; the cards give precedences, the largest ε, deadheads and both costs with Fig. 8 plots; the sequence view draws and Play steps through it; G-code equals the CLI's", async () => {
      const report = await runExample(page, baseUrl, EXAMPLE, jobTimeout);
      for (const s of ["import", "constraints", "plan", "order", "costs"]) if (!report.stages.find((x) => x.stage === s)) throw new Error(`no ${s} stage (${report.stages.map((x) => x.stage)})`);
      const metric = (stage, key) => report.stages.find((x) => x.stage === stage)?.metrics.find((m) => m.key === key)?.value;
      const beams = metric("import", "beams");
      if (beams !== 116 || report.analysis.extrusion_paths !== 116) throw new Error(`${beams} beams, ${report.analysis.extrusion_paths} extrusion paths`);
      const eps = metric("plan", "max_eps");
      if (!(eps > 0) || Math.abs(metric("costs", "max_exact") - eps) > 1e-9 * eps) throw new Error(`largest ε ${eps} µm planned, ${metric("costs", "max_exact")} measured`);
      if (metric("costs", "above") !== 0) throw new Error(`heuristic above exact on ${metric("costs", "above")} steps`);
      const cards = await page.evaluate(() => {
        const card = document.querySelector('#report .stage-card[data-stage="costs"]');
        return {
          plots: [...(card?.querySelectorAll("[data-plot-key]") ?? [])].map((p) => p.dataset.plotKey),
          units: [...document.querySelectorAll('#report .stage-card[data-stage="plan"] dl.metrics > div')].map((m) => m.textContent).join(" | "),
        };
      });
      for (const k of ["eps_sequence", "compliance_sorted", "heuristic_vs_exact", "eps_histogram"]) if (!cards.plots.includes(k)) throw new Error(`costs card plots ${cards.plots}`);
      if (!/µm/.test(cards.units)) throw new Error(`plan card reads "${cards.units.slice(0, 200)}"`);
      // The sequence view: one index per beam, the current beam drawn, Play moves on.
      await page.waitForFunction(() => window.weft.views.find((x) => x.id === "sequence")?.answers > 0, null, { timeout: jobTimeout });
      const view = await page.evaluate(() => window.weft.views.find((x) => x.id === "sequence"));
      if (view.count !== 116 || !(view.items >= 116)) throw new Error(`sequence view: ${JSON.stringify(view)}`);
      const play = '.view-card[data-view="sequence"] .view-play';
      await page.waitForSelector(play, { state: "visible", timeout: 5000 });
      const start = await page.evaluate(() => window.weft.views.find((x) => x.id === "sequence").index);
      await page.click(play);
      await page.waitForFunction((s) => window.weft.views.find((x) => x.id === "sequence").index >= s + 3, start, { timeout: 20000 });
      await page.click(play); // pause
      await page.waitForTimeout(300);
      const legend = await page.evaluate(() => document.querySelector('.view-card[data-view="sequence"] .mini-legend')?.textContent ?? "");
      for (const w of ["printed", "printing now", "still to print"]) if (!legend.includes(w)) throw new Error(`legend reads "${legend}"`);
      const caption = await page.evaluate(() => document.querySelector('.view-card[data-view="sequence"] output')?.textContent ?? "");
      if (!/beam \d+ from joint \d+ to joint \d+, ε/.test(caption)) throw new Error(`caption reads "${caption}"`);
      let native = "";
      if (weftBin) {
        const text = (await downloadGcode(page, join(outDir, "freeform-tower.gcode"))).bytes.toString("utf8");
        const cli = join(outDir, "freeform-tower.cli.gcode");
        execFileSync(weftBin, ["run", join(process.cwd(), "examples", EXAMPLE), "--out", cli, "-q"]);
        native = readFileSync(cli, "utf8");
        if (native !== text) throw new Error("the page's G-code differs from the CLI's");
      }
      await page.evaluate(() => document.querySelector('.view-card[data-view="sequence"]')?.scrollIntoView({ block: "center" }));
      for (const [w, h, name] of [[1280, 800, "freeform-desktop.png"], [390, 844, "freeform-phone.png"]]) {
        await page.setViewportSize({ width: w, height: h });
        await page.waitForTimeout(300);
        await page.screenshot({ path: join(outDir, name), fullPage: w < 500 });
      }
      await page.setViewportSize({ width: 1400, height: 900 });
      return `116 beams, largest ε ${eps.toFixed(3)} µm, played ${start + 1} → beyond ${start + 3}${native ? ", same bytes as the CLI" : ""}`;
    });

    await check(n++, "freeform: a wireframe JSON dropped on a slicing job switches to freeform and fills the Wireframe slot; it runs; the conmech truss through the default cone is refused naming two beams and the design stays", async () => {
      await page.goto(`${baseUrl}/www/`);
      await waitReady(page);
      const four = join(process.cwd(), "tests/fixtures/wireframes/four-frame.json");
      // The page-wide file input takes any file (as a drop does).
      await page.setInputFiles("#file", [four]);
      await page.waitForFunction(() => JSON.parse(window.weft.design).job.kind === "freeform" && JSON.parse(window.weft.design).job.input?.file?.name === "four-frame.json", null, { timeout: jobTimeout });
      const summary = await page.waitForFunction(() => document.querySelector('.slot[data-slot="frame"] .file-summary')?.textContent || false, null, { timeout: jobTimeout }).then((h) => h.jsonValue());
      if (!/4 beams, 5 joints, .* mm \(2 joints grounded, as the file marks them\)/.test(summary)) throw new Error(`slot reads "${summary}"`);
      const before = await page.evaluate(() => window.weft.resultCount);
      await page.click("#slice");
      await waitResult(page, before, "running four-frame.json", jobTimeout);
      const r = await page.evaluate(() => window.weft.result.report);
      if (r.analysis.extrusion_paths !== 4) throw new Error(`${r.analysis.extrusion_paths} paths`);
      // The truss example, then the default cone.
      const ran = await runExample(page, baseUrl, "freeform-cantilever-truss.json", jobTimeout);
      if (ran.analysis.extrusion_paths !== 2197) throw new Error(`the truss printed ${ran.analysis.extrusion_paths} paths`);
      const count = await page.evaluate(() => window.weft.resultCount);
      await page.evaluate(() => document.querySelector("#f-job-nozzle-half_angle_deg")?.closest("details")?.setAttribute("open", ""));
      await page.fill("#f-job-nozzle-half_angle_deg", "13");
      await page.dispatchEvent("#f-job-nozzle-half_angle_deg", "change");
      await page.click("#slice");
      const message = await page.waitForFunction(() => {
        const err = document.getElementById("error");
        return !err.hidden && !window.weft.busy ? document.getElementById("error-text").textContent : false;
      }, null, { timeout: jobTimeout }).then((h) => h.jsonValue());
      if (!/cannot be printed in this orientation/.test(message) || !/element 827/.test(message) || !/element 1149/.test(message)) throw new Error(`refusal reads "${message}"`);
      if ((await page.evaluate(() => window.weft.resultCount)) !== count) throw new Error("a result was shown for an unconstructable design");
      const kept = await page.evaluate(() => JSON.parse(window.weft.design).job.nozzle.half_angle_deg);
      if (kept !== 13) throw new Error(`the design lost its setting: ${kept}`);
      for (const [w, h, name] of [[1280, 800, "freeform-refused-desktop.png"], [390, 844, "freeform-refused-phone.png"]]) {
        await page.setViewportSize({ width: w, height: h });
        await page.waitForTimeout(200);
        await page.screenshot({ path: join(outDir, name) });
      }
      await page.setViewportSize({ width: 1400, height: 900 });
      return `slot: ${summary}; refused: "${message.slice(0, 110)}"`;
    });

    await check(n++, "freeform: freeform-dome-exact from the Examples menu: the exact search's card proves the least largest ε below the heuristic planner's, plots both sequences, and its sequence is printed (same bytes as the CLI)", async () => {
      const report = await runExample(page, baseUrl, "freeform-dome-exact.json", jobTimeout);
      const stage = report.stages.find((x) => x.stage === "optimum");
      if (!stage || !/better sequence \(printed\)/.test(stage.label)) throw new Error(`optimum stage: ${stage?.label}`);
      const metric = (st, key) => report.stages.find((x) => x.stage === st)?.metrics.find((m) => m.key === key)?.value;
      const best = metric("optimum", "best");
      const planner = metric("optimum", "planner");
      if (!(best > 0 && planner > best)) throw new Error(`optimum ${best} µm, planner ${planner} µm`);
      if (Math.abs(metric("costs", "max_exact") - best) > 1e-9 * best) throw new Error(`printed ${metric("costs", "max_exact")} µm, optimum ${best} µm`);
      const card = await page.evaluate(() => {
        const c = document.querySelector('#report .stage-card[data-stage="optimum"]');
        return { title: c?.querySelector("h3, summary, header")?.textContent ?? c?.textContent?.slice(0, 80) ?? "", plots: [...(c?.querySelectorAll("[data-plot-key]") ?? [])].map((p) => p.dataset.plotKey), text: c?.textContent ?? "" };
      });
      if (!card.plots.includes("optimum_sequence")) throw new Error(`optimum card plots ${card.plots}`);
      if (!/proven/.test(card.text) || !/%/.test(card.text)) throw new Error(`optimum card reads "${card.text.slice(0, 200)}"`);
      if (weftBin) {
        const text = (await downloadGcode(page, join(outDir, "freeform-dome-exact.gcode"))).bytes.toString("utf8");
        const cli = join(outDir, "freeform-dome-exact.cli.gcode");
        execFileSync(weftBin, ["run", join(process.cwd(), "examples", "freeform-dome-exact.json"), "--out", cli, "-q"]);
        if (readFileSync(cli, "utf8") !== text) throw new Error("the page's G-code differs from the CLI's");
      }
      await shots(page, '#report .stage-card[data-stage="optimum"]', join(outDir, "freeform-exact"));
      return `optimum ${best.toFixed(1)} µm proven, heuristic planner ${planner.toFixed(1)} µm (gap ${metric("optimum", "gap").toFixed(1)} %)`;
    });

    await check(n++, "freeform: a tilting 5-axis nozzle prints the truss a 3-axis printer refuses (the constraints card counts the tilted beams), and a tower planned in bands shows the cost of the joins per band", async () => {
      const tilt = await runExample(page, baseUrl, "freeform-cantilever-truss-tilt.json", jobTimeout, { confirm: true });
      const metric = (r, st, key) => r.stages.find((x) => x.stage === st)?.metrics.find((m) => m.key === key)?.value;
      const tilted = metric(tilt, "constraints", "tilted");
      if (!(tilted > 1000) || tilt.analysis.extrusion_paths !== 2197) throw new Error(`${tilted} beams tilted, ${tilt.analysis.extrusion_paths} paths`);
      if (!(metric(tilt, "constraints", "pairs") * 4 < metric(tilt, "constraints", "vertical_pairs"))) throw new Error("tilting did not cut the precedences");
      const card = await page.evaluate(() => document.querySelector('#report .stage-card[data-stage="constraints"]')?.textContent ?? "");
      if (!/Beams tilted/.test(card) || !/Precedences if vertical/.test(card)) throw new Error(`constraints card reads "${card.slice(0, 200)}"`);
      await page.evaluate(() => document.querySelector('#report .stage-card[data-stage="constraints"]')?.scrollIntoView({ block: "center" }));
      await page.screenshot({ path: join(outDir, "freeform-tilt-desktop.png") });
      const banded = await runExample(page, baseUrl, "freeform-tower-bands.json", jobTimeout);
      const bands = metric(banded, "plan", "bands");
      const joinCost = metric(banded, "costs", "band_join");
      if (!(bands >= 3) || !(joinCost >= 0)) throw new Error(`${bands} bands, joins ${joinCost} µm`);
      const plots = await page.evaluate(() => [...document.querySelectorAll('#report .stage-card[data-stage="costs"] [data-plot-key]')].map((p) => p.dataset.plotKey));
      if (!plots.includes("bands")) throw new Error(`costs card plots ${plots}`);
      await shots(page, '#report .stage-card[data-stage="costs"] [data-plot-key="bands"]', join(outDir, "freeform-bands"));
      return `truss: ${tilted} of 2197 beams tilted; tower: ${bands} bands, joins cost up to ${joinCost.toFixed(3)} µm`;
    });

    await check(n++, "freeform: a big plan sends its first beams ahead while it goes on: the progress bar offers their G-code, and the final G-code's moves begin with theirs (desktop and phone)", async () => {
      // Every `ahead` message the worker posts, as the page receives it.
      await page.addInitScript(() => {
        const Base = window.Worker;
        window.Worker = class extends Base {
          constructor(...args) {
            super(...args);
            this.addEventListener("message", ({ data }) => {
              if (data?.type === "ahead") (window.__ahead ??= []).push({ label: data.label, done: data.done, total: data.total, text: new TextDecoder().decode(data.gcode) });
            });
          }
        };
      });
      const moves = (text) => {
        const from = text.indexOf(";LAYER_CHANGE");
        const to = text.lastIndexOf("; weft: ");
        return text.slice(from, to > from ? to : text.length);
      };
      const seen = [];
      for (const [file, w, h, name] of [["freeform-cantilever-truss.json", 1280, 800, "desktop"], ["freeform-cantilever-truss-tilt.json", 390, 844, "phone"]]) {
        await page.setViewportSize({ width: w, height: h });
        await page.goto(`${baseUrl}/www/`);
        await waitReady(page);
        await confirmBigJobs(page); // the tilted truss is asked about on one thread
        const before = await page.evaluate(() => window.weft.resultCount);
        await page.selectOption("#examples", file);
        // The link shows while the rest is planned, ordered and measured (or the run ends
        // before the test sees it: then only the messages received are checked).
        const link = await page.waitForFunction((k) => {
          const a = document.getElementById("progress-ahead");
          if (!a.hidden) return { text: a.textContent, download: a.download, href: a.href };
          return window.weft.resultCount > k && !window.weft.busy ? "ended" : false;
        }, before, { timeout: jobTimeout, polling: 20 }).then((h) => h.jsonValue()).then((v) => (v === "ended" ? null : v)).catch(() => null);
        if (link) await page.screenshot({ path: join(outDir, `freeform-ahead-${name}.png`) });
        await waitResult(page, before, `running ${file}`, jobTimeout);
        const design = file.replace(".json", "");
        await page.waitForFunction((d) => !window.weft.busy && window.weft.result?.report?.name === d, design, { timeout: jobTimeout });
        const got = await page.evaluate(() => window.__ahead ?? []);
        if (got.length !== 1) throw new Error(`${file}: ${got.length} files sent ahead`);
        const a = got[0];
        const report = await page.evaluate(() => window.weft.result.report);
        const paths = report.analysis.extrusion_paths;
        if (!(a.done >= 200 && a.done < paths && a.total === paths)) throw new Error(`${file}: ${a.done} of ${a.total} sent, ${paths} printed`);
        const sent = report.stages.find((x) => x.stage === "plan")?.metrics.find((m) => m.key === "sent")?.value;
        if (sent !== a.done) throw new Error(`${file}: the plan card says ${sent} sent`);
        const final = (await downloadGcode(page, join(outDir, file.replace(".json", ".gcode")))).bytes.toString("utf8");
        const head = moves(a.text);
        if (head.length < 1000 || !moves(final).startsWith(head)) throw new Error(`${file}: the final G-code does not begin with the moves sent ahead`);
        // One pass per beam.
        const beamsSent = (a.text.match(/^;LAYER:\d+$/gm) ?? []).length;
        if (beamsSent !== a.done) throw new Error(`${file}: ${beamsSent} beams in the file sent ahead, ${a.done} stated`);
        if (link && !/Start printing: the first \d+ of \d+ beams/.test(link.text)) throw new Error(`link reads "${link.text}"`);
        // Where the time went, and on how many threads (the worker's pool: the page is isolated).
        const timeLine = await page.evaluate(() => document.querySelector("#stats .time-line")?.textContent ?? "");
        const used = await page.evaluate(() => window.weft.threads.used);
        const said = `${used} thread${used === 1 ? "" : "s"}`;
        if (!timeLine.startsWith("Where the time went: ") || !/\d (ms|s)\b/.test(timeLine) || !timeLine.endsWith(` — ${said}`) || report.threads !== used) throw new Error(`time line reads "${timeLine}" (${report.threads} threads, the worker has ${used})`);
        if (name === "desktop") {
          await page.evaluate(() => document.querySelector("#stats .time-line")?.scrollIntoView({ block: "center" }));
          await page.screenshot({ path: join(outDir, "time-line-desktop.png") });
        }
        seen.push(`${file}: ${a.done} of ${a.total} beams, ${(a.text.length / 1024).toFixed(0)} KiB${link ? ", link shown" : ""}`);
      }
      await page.evaluate(() => document.querySelector("#stats .time-line")?.scrollIntoView({ block: "center" }));
      await page.screenshot({ path: join(outDir, "time-line-phone.png") });
      await page.setViewportSize({ width: 1400, height: 900 });
      return seen.join("; ");
    });
  } finally {
    await context.close();
  }
  return n;
}

// Browser checks of what a newcomer meets (issue "the page a newcomer understands"): a first
// visit shows a part and says what to do; a result is tied to the design it came from (an
// edit dims it and Download never gives the old file); an invalid field blocks Run with its
// message; light jobs re-run by themselves; the next run's estimate is shown; a part dropped
// on a lattice design asks what it is for and names the design; printer profiles; examples
// grouped with thumbnails; a phone-sized page without clipped labels. Called by run.mjs:
//
//   await newcomerChecks({ base, check, newPage, outDir: OUT, first: 18, cube });
import { join } from "node:path";
import { downloadGcode, waitReady, waitResult } from "./page-helpers.mjs";

const TIMEOUT = Number(process.env.E2E_TIMEOUT_S ?? 120) * 1000;

/**
 * @param {{base: string, check: Function, newPage: Function, outDir: string, first: number,
 *          cube: {name: string, bytes: Buffer}}} opts
 */
export async function newcomerChecks({ base, check, newPage, outDir, first, cube }) {
  let n = first;

  /** A fresh page at `path` (first visit: nothing stored). */
  async function fresh(path = "/www/", viewport) {
    const made = await newPage();
    if (viewport) await made.page.setViewportSize(viewport);
    await made.page.goto(`${base}${path}`);
    await waitReady(made.page);
    return made;
  }
  const count = (p) => p.evaluate(() => window.weft.resultCount);
  const design = (p) => p.evaluate(() => JSON.parse(window.weft.design));
  const stale = (p) => p.evaluate(() => ({
    dimmed: document.querySelector(".view").classList.contains("stale-result"),
    banner: !document.getElementById("stale").hidden,
    text: document.getElementById("stale-text").textContent,
  }));

  await check(n++, "first visit: the default part is shown at once, with one line on what to do", async () => {
    const { page, context, errors } = await fresh();
    try {
      if ((await count(page)) < 1) throw new Error("a first visit shows no result (the default part was not run)");
      const notice = await page.$eval("#notice", (e) => (e.hidden ? "" : e.textContent));
      if (!/drop/i.test(notice) || !/example/i.test(notice)) throw new Error(`the first-visit line does not say what to do: "${notice}"`);
      const est = await page.textContent("#estimate");
      if (!/segments/.test(est) || !/G-code/.test(est)) throw new Error(`no estimate of the next run shown: "${est}"`);
      // The time is stated for the threads the worker uses (the plan counts each stage's
      // parallel share over them).
      const used = await page.evaluate(() => window.weft.threads?.used);
      if (used > 1 && !est.includes(`on ${used} threads`)) throw new Error(`the estimate does not say it is for ${used} threads: "${est}"`);
      if (used === 1 && /threads/.test(est)) throw new Error(`one thread, but the estimate names threads: "${est}"`);
      if (errors.length) throw new Error(`console errors: ${errors.join("\n")}`);
      return `estimate line: "${est}"`;
    } finally {
      await context.close();
    }
  });

  await check(n++, "an edit marks the result out of date (dimmed, banner); Download runs the changed design first, never the old file; undo makes it current again", async () => {
    const { page, context } = await fresh();
    try {
      const before = await count(page);
      const old = await downloadGcode(page, join(outDir, "fresh-old.gcode"));
      if (!/layer_height|;\s*layer/i.test(old.bytes.toString("utf8").slice(0, 100000))) throw new Error("the first download is not G-code");
      const field = "#f-job-slice-layer_height_mm";
      const h = Number(await page.inputValue(field));
      await page.fill(field, String(h === 0.2 ? 0.25 : 0.2));
      await page.dispatchEvent(field, "change");
      const s = await stale(page);
      if (!s.dimmed || !s.banner) throw new Error(`after a layer-height change the result is not marked out of date: ${JSON.stringify(s)}`);
      // Download now runs the new design, then saves its G-code.
      const [dl] = await Promise.all([page.waitForEvent("download", { timeout: TIMEOUT }), page.click("#download")]);
      const path = join(outDir, "fresh-new.gcode");
      await dl.saveAs(path);
      const { readFileSync } = await import("node:fs");
      const fresh = readFileSync(path);
      if (fresh.equals(old.bytes)) throw new Error("Download gave the old G-code after the layer height changed");
      if ((await count(page)) <= before) throw new Error("Download did not run the changed design");
      const after = await stale(page);
      if (after.dimmed || after.banner) throw new Error(`after the run the result is still marked out of date: ${JSON.stringify(after)}`);
      // Undo back to the design of an earlier result: not the shown one → out of date again.
      await page.click("#undo");
      const u = await stale(page);
      if (!u.dimmed) throw new Error("after undo the result of the redone design is not marked out of date");
      return `${old.bytes.length} → ${fresh.length} bytes; banner: "${s.text}"`;
    } finally {
      await context.close();
    }
  });

  await check(n++, "an invalid field blocks Run with its message (the old value is not used silently)", async () => {
    const { page, context } = await fresh();
    try {
      const field = "#f-job-slice-perimeters";
      await page.fill(field, "2.5");
      await page.dispatchEvent(field, "change");
      const fieldError = await page.$eval("#f-job-slice-perimeters-error", (e) => (e.hidden ? "" : e.textContent));
      if (!fieldError) throw new Error("2.5 perimeters shows no message under the field");
      const before = await count(page);
      await page.click("#slice");
      // Run answers at once, on the page: the error shows and no job starts (a job would make
      // the page busy before its answer, whatever the machine's load).
      const err = await page.waitForFunction(() => { const e = document.getElementById("error"); return !e.hidden && e.textContent; }, null, { timeout: TIMEOUT })
        .then((h) => h.jsonValue()).catch(() => "");
      if (!/perimeters/i.test(err)) throw new Error(`the error does not name the field: "${err}"`);
      if ((await count(page)) !== before || await page.evaluate(() => window.weft.busy)) throw new Error("Run ran with an invalid field");
      const s = await stale(page);
      if (!s.dimmed) throw new Error("the result is not marked out of date while a field is invalid");
      await page.fill(field, "3");
      await page.dispatchEvent(field, "change");
      await page.click("#slice");
      await waitResult(page, before, "run after fixing the field", TIMEOUT);
      return `field: "${fieldError.trim()}"; Run: "${err.trim().split("\n")[0]}"`;
    } finally {
      await context.close();
    }
  });

  await check(n++, "with live re-run on, a light job re-runs by itself after an edit", async () => {
    const { page, context } = await fresh();
    try {
      await page.check("#auto-run");
      const before = await count(page);
      const field = "#f-job-slice-perimeters";
      await page.fill(field, "1");
      await page.dispatchEvent(field, "change");
      await waitResult(page, before, "live re-run after the edit", TIMEOUT);
      const d = await design(page);
      const s = await stale(page);
      if (s.dimmed) throw new Error("after the live re-run the result is still out of date");
      if (d.job.slice.perimeters !== 1) throw new Error("the design did not take the edit");
      return "re-ran after the perimeter change";
    } finally {
      await page.evaluate(() => localStorage.setItem("weft.autoRun", "0"));
      await context.close();
    }
  });

  await check(n++, "a part dropped on a lattice design asks what it is for; 'slice it' switches the job; the design takes the part's name", async () => {
    const { page, context } = await fresh();
    try {
      let before = await count(page);
      await page.selectOption("#examples", "honeycomb-10mm.json");
      await waitResult(page, before, "honeycomb example", TIMEOUT);
      before = await count(page);
      await page.setInputFiles("#file", { name: "bunny.stl", mimeType: "model/stl", buffer: cube.bytes });
      // The question comes once the file is read (later on a loaded machine: no short bound).
      const notice = await page.waitForSelector("#notice:not([hidden]) .notice-action", { timeout: TIMEOUT }).catch(() => null);
      if (!notice) throw new Error("dropping a part on the lattice design did not ask what it is for");
      const labels = await page.$$eval("#notice .notice-action", (bs) => bs.map((b) => b.textContent));
      await page.waitForTimeout(300);
      if ((await count(page)) !== before || await page.evaluate(() => window.weft.busy)) throw new Error("the drop ran something before the user chose");
      if ((await design(page)).job.kind !== "lattice") throw new Error("the drop changed the job before the user chose");
      const slice = labels.find((l) => /slice/i.test(l));
      if (!slice) throw new Error(`no choice to slice the part: ${labels.join(" | ")}`);
      await page.click(`#notice .notice-action:text-is("${slice}")`);
      await waitResult(page, before, "slicing the dropped part", TIMEOUT);
      const d = await design(page);
      if (d.job.kind !== "slice") throw new Error(`job is ${d.job.kind} after choosing to slice`);
      if (d.name !== "bunny") throw new Error(`the design is named "${d.name}", not after the part (bunny)`);
      const header = (await downloadGcode(page, join(outDir, "bunny.gcode")));
      if (header.name !== "bunny.gcode") throw new Error(`download named ${header.name}`);
      if (!/^; design: bunny$/m.test(header.bytes.toString("utf8").split(";LAYER_CHANGE")[0])) throw new Error("the G-code header does not name the part");
      // A name the user typed stays.
      await page.fill("#f-name", "my-part");
      await page.dispatchEvent("#f-name", "change");
      await page.setInputFiles("#file", { name: "other.stl", mimeType: "model/stl", buffer: cube.bytes });
      await page.waitForFunction(() => window.weft.files.includes("other.stl"), null, { timeout: 10000 });
      const kept = (await design(page)).name;
      if (kept !== "my-part") throw new Error(`a typed name was replaced by "${kept}"`);
      return `choices: ${labels.join(" | ")}`;
    } finally {
      await context.close();
    }
  });

  await check(n++, "a big job shows its estimate and asks before it starts", async () => {
    const { page, context } = await fresh();
    try {
      await page.fill("#f-job-slice-layer_height_mm", "0.02");
      await page.dispatchEvent("#f-job-slice-layer_height_mm", "change");
      await page.fill("#f-job-slice-first_layer_height_mm", "0.02");
      await page.dispatchEvent("#f-job-slice-first_layer_height_mm", "change");
      await page.fill("#f-job-slice-infill_density", "100"); // percent in the form
      await page.dispatchEvent("#f-job-slice-infill_density", "change");
      if ((await design(page)).job.slice.infill_density !== 1) throw new Error("100 % infill is not stored as 1");
      // A bigger built-in cube, through its size fields in the part's slot.
      for (const [i, v] of [200, 200, 60].entries()) {
        const id = `#f-job-input-builtin-size-${i}`;
        if (!(await page.$(id))) throw new Error(`no ${id}`);
        await page.fill(id, String(v));
        await page.dispatchEvent(id, "change");
      }
      await page.waitForFunction(() => /big|too big/.test(document.getElementById("estimate").textContent), null, { timeout: TIMEOUT });
      const est = await page.textContent("#estimate");
      const before = await count(page);
      await page.click("#slice");
      // The page asks, or refuses, once the worker has planned the run: whichever comes first.
      const answer = await page.waitForFunction(() => (document.querySelector("#notice:not([hidden]) .notice-action") ? "asked" : "") ||
        (document.getElementById("error").hidden ? false : "refused"), null, { timeout: TIMEOUT }).then((h) => h.jsonValue()).catch(() => null);
      const ask = answer === "asked";
      const err = await page.$eval("#error", (e) => (e.hidden ? "" : e.textContent));
      if (!ask && !/limit/.test(err)) throw new Error(`a big job neither asked nor was refused (estimate "${est}")`);
      await page.waitForTimeout(300);
      if ((await count(page)) !== before || await page.evaluate(() => window.weft.busy)) throw new Error("the big job ran without asking");
      return `estimate: "${est}"`;
    } finally {
      await context.close();
    }
  });

  await check(n++, "printer profiles: picking one sets the printer section (G-code follows); an edit shows 'custom'", async () => {
    const { page, context } = await fresh();
    try {
      const open = await page.$eval("#machine", (d) => d.open);
      if (open) throw new Error("the printer section is not folded under the job's settings");
      await page.click("#machine > summary");
      const ids = await page.$$eval("#printer-preset option", (os) => os.map((o) => o.value));
      for (const want of ["prusa-mk4", "ender-3", "generic-220", "bioprinter-pneumatic", "custom"]) {
        if (!ids.includes(want)) throw new Error(`no ${want} profile: ${ids.join(", ")}`);
      }
      await page.selectOption("#printer-preset", "ender-3");
      const d = await design(page);
      if (d.printer.retraction.length_mm !== 5) throw new Error(`Ender-3 profile gave retraction ${d.printer.retraction.length_mm} mm`);
      const before = await count(page);
      await page.click("#slice");
      await waitResult(page, before, "run with the Ender-3 profile", TIMEOUT);
      const g = (await downloadGcode(page, join(outDir, "ender.gcode"))).bytes.toString("utf8");
      if (!/^; printer: Ender-3/m.test(g)) throw new Error("the G-code header does not name the Ender-3 profile");
      await page.fill("#f-printer-travel_speed_mm_s", "123");
      await page.dispatchEvent("#f-printer-travel_speed_mm_s", "change");
      const v = await page.inputValue("#printer-preset");
      if (v !== "custom") throw new Error(`after editing the travel speed the picker shows ${v}`);
      return `${ids.length - 1} profiles`;
    } finally {
      await context.close();
    }
  });

  await check(n++, "examples are grouped by job kind, each with a thumbnail and one line; clicking one opens and runs it", async () => {
    const { page, context } = await fresh();
    try {
      const groups = await page.$$eval("#gallery .gallery-group", (gs) => gs.map((g) => ({
        kind: g.dataset.kind,
        items: [...g.querySelectorAll(".example")].map((b) => ({
          file: b.dataset.file, text: b.querySelector(".example-text span")?.textContent ?? "",
          img: b.querySelector("img")?.naturalWidth ?? 0,
        })),
      })));
      if (groups.length < 2) throw new Error(`examples in ${groups.length} group(s)`);
      const items = groups.flatMap((g) => g.items);
      // Thumbnails load lazily: bring each into view as a reader scrolling the gallery would.
      for (const img of await page.$$("#gallery img")) await img.scrollIntoViewIfNeeded();
      await page.waitForFunction(() => [...document.querySelectorAll("#gallery img")].every((i) => i.complete), null, { timeout: 10000 });
      const noThumb = await page.$$eval("#gallery .example", (bs) => bs.filter((b) => !(b.querySelector("img")?.naturalWidth > 0)).map((b) => b.dataset.file));
      if (noThumb.length) throw new Error(`examples without a thumbnail: ${noThumb.join(", ")}`);
      const noLine = items.filter((i) => i.text.length < 20).map((i) => i.file);
      if (noLine.length) throw new Error(`examples without a one-line description: ${noLine.join(", ")}`);
      const optgroups = await page.$$eval("#examples optgroup", (os) => os.map((o) => o.label));
      if (optgroups.length !== groups.length) throw new Error(`menu groups ${optgroups.join(", ")}`);
      const before = await count(page);
      await page.click('#gallery .example[data-file="voronoi-10mm.json"]');
      await waitResult(page, before, "example from the gallery", TIMEOUT);
      if ((await design(page)).name !== "voronoi-10mm") throw new Error("the gallery did not open voronoi-10mm");
      return groups.map((g) => `${g.kind}: ${g.items.length}`).join(", ");
    } finally {
      await context.close();
    }
  });

  await check(n++, "phone (390 × 844): the preview comes first, no label or legend is clipped, the progress bar does not move the page", async () => {
    const { page, context } = await fresh("/www/", { width: 390, height: 844 });
    try {
      const order = await page.evaluate(() => {
        const v = document.querySelector(".canvas-wrap").getBoundingClientRect().top;
        const s = document.querySelector(".sidebar").getBoundingClientRect().top;
        return { v, s };
      });
      if (!(order.v < order.s)) throw new Error(`the settings come before the preview on a phone (${JSON.stringify(order)})`);
      const clipped = await page.evaluate(() => {
        const out = [];
        for (const el of document.querySelectorAll("label, legend, .card-head, .card-head *, dt, .layer-range output, figcaption, .estimate, .stale span")) {
          if (!el.offsetParent || el.closest("[hidden]") || el.closest("details:not([open])")) continue;
          const st = getComputedStyle(el);
          if (el.scrollWidth > el.clientWidth + 1 && st.overflow !== "visible" && st.textOverflow !== "clip") {
            if (!el.title) out.push(`${el.tagName.toLowerCase()}.${el.className}: "${el.textContent.trim().slice(0, 40)}"`);
          }
          const r = el.getBoundingClientRect();
          if (r.right > window.innerWidth + 1) out.push(`off-screen ${el.tagName.toLowerCase()}: "${el.textContent.trim().slice(0, 40)}"`);
        }
        return out;
      });
      if (clipped.length) throw new Error(`clipped: ${clipped.slice(0, 6).join("; ")}`);
      const y0 = await page.evaluate(() => document.querySelector(".layout").getBoundingClientRect().top);
      await page.evaluate(() => { document.getElementById("progress").hidden = false; });
      const y1 = await page.evaluate(() => document.querySelector(".layout").getBoundingClientRect().top);
      await page.evaluate(() => { document.getElementById("progress").hidden = true; });
      if (Math.abs(y1 - y0) > 0.5) throw new Error(`showing the progress bar moved the page by ${y1 - y0} px`);
      await page.screenshot({ path: join(outDir, "phone-first-visit.png"), fullPage: true });
      return "no clipped labels";
    } finally {
      await context.close();
    }
  });
  return n;
}

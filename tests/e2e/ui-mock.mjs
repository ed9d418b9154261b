#!/usr/bin/env node
// Page checks against the JavaScript stand-in of the wasm API (tests/e2e/mock-pkg/weft.js):
// the schema-driven form, slots, stage cards, generic plots, views, print-order slider and
// tool axis, without building the Rust side. Needs www/vendor (SKIP_WASM=1 scripts/build-www.sh).
//
//   node tests/e2e/ui-mock.mjs          (SHOTS=dir: also save screenshots there)
import { mkdirSync } from "node:fs";
import { join } from "node:path";
import { ROOT, serve } from "./server.mjs";
import { collectErrors, launchChromium, waitReady, waitResult } from "./page-helpers.mjs";

const server = await serve({ pkgDir: join(ROOT, "tests/e2e/mock-pkg") });
const browser = await launchChromium();
const shots = process.env.SHOTS;
if (shots) mkdirSync(shots, { recursive: true });
let failed = 0;
async function check(title, fn) {
  try {
    const d = await fn();
    console.log(`PASS ${title}${d ? ` (${d})` : ""}`);
  } catch (err) {
    failed++;
    console.log(`FAIL ${title}: ${err.message}`);
  }
}
const context = await browser.newContext({ viewport: { width: 1280, height: 800 }, acceptDownloads: true });
const page = await context.newPage();
const errors = collectErrors(page);
const T = 20000;

await check("page starts; slots of the slice kind match the schema", async () => {
  await page.goto(`${server.url}/www/`);
  await waitReady(page);
  const { slots, schemaSlots } = await page.evaluate(() => ({
    slots: [...document.querySelectorAll("#slots .slot")].map((s) => s.dataset.slot),
    schemaSlots: window.weft.schema.job_kinds.find((k) => k.name === "slice").slots.map((s) => s.name),
  }));
  if (JSON.stringify(slots) !== JSON.stringify(schemaSlots)) throw new Error(`${slots} vs ${schemaSlots}`);
  if (errors.length) throw new Error(errors.join("\n"));
  return slots.join(",");
});

await check("slice run: stage cards, stats, preview segments", async () => {
  await page.click("#slice");
  await waitResult(page, 0, "slice", T);
  const cards = await page.evaluate(() => window.weft.reportCards);
  if (cards.length !== 4) throw new Error(JSON.stringify(cards));
  const drawn = await page.evaluate(() => window.weft.preview.drawn.extrusion);
  if (drawn !== 40) throw new Error(`drawn ${drawn}`);
  return cards.map((c) => c.stage).join(",");
});

await check("print-order slider hides later moves", async () => {
  const r = await page.evaluate(() => {
    const el = document.getElementById("move-max");
    const all = window.weft.preview.drawn.extrusion;
    el.value = String(Math.floor(Number(el.max) / 2));
    el.dispatchEvent(new Event("input"));
    const half = window.weft.preview.drawn.extrusion;
    el.value = el.max;
    el.dispatchEvent(new Event("input"));
    return { all, half, back: window.weft.preview.drawn.extrusion, hidden: el.closest("[data-moves]").hidden };
  });
  if (r.hidden || !(r.half < r.all) || r.back !== r.all) throw new Error(JSON.stringify(r));
  return JSON.stringify(r);
});

await check("temperature change → stages before gcode reused", async () => {
  const before = await page.evaluate(() => window.weft.resultCount);
  await page.evaluate(() => { document.getElementById("machine").open = true; });
  await page.fill("#f-material-nozzle_temp_c", "215");
  await page.dispatchEvent("#f-material-nozzle_temp_c", "change");
  await page.click("#slice");
  await waitResult(page, before, "re-run", T);
  const cards = await page.evaluate(() => window.weft.reportCards);
  const bad = cards.filter((c) => ["import", "slice"].includes(c.stage) && !c.cached);
  if (bad.length) throw new Error(JSON.stringify(cards));
  const badge = await page.$$eval(".stage-card .badge.reused", (b) => b.length);
  return `${badge} reused badges`;
});

await check("drop an STL → goes to the mesh slot, summary shown, remove works", async () => {
  const before = await page.evaluate(() => window.weft.resultCount);
  await page.setInputFiles("#file", { name: "part.stl", mimeType: "model/stl", buffer: Buffer.alloc(684) });
  await waitResult(page, before, "slice part.stl", T);
  const slots = await page.evaluate(() => window.weft.slots);
  if (slots[0].files[0] !== "part.stl") throw new Error(JSON.stringify(slots));
  const input = await page.evaluate(() => JSON.parse(window.weft.design).job.input);
  if (input.file?.name !== "part.stl") throw new Error(JSON.stringify(input));
  const summary = await page.textContent('.slot[data-slot="mesh"] .file-summary');
  await page.click('.slot[data-slot="mesh"] button.remove');
  const after = await page.evaluate(() => ({ files: window.weft.files, input: JSON.parse(window.weft.design).job.input }));
  if (after.files.length || !after.input.builtin) throw new Error(JSON.stringify(after));
  return summary;
});

await check("lattice job: slots, pattern picker, view answers, plots drawn generically", async () => {
  const before = await page.evaluate(() => window.weft.resultCount);
  await page.selectOption("#f-job-kind", JSON.stringify("lattice"));
  const slots = await page.$$eval("#slots .slot", (s) => s.map((x) => x.dataset.slot));
  if (slots.join() !== "mesh,surface") throw new Error(`slots ${slots}`);
  await page.waitForFunction(() => window.weft.views[0]?.answers > 0, null, { timeout: T });
  const views = await page.evaluate(() => window.weft.views);
  if (!(views[0].items > 0) || views[0].count !== 3) throw new Error(JSON.stringify(views));
  const thumbs = await page.$$eval("#pattern-picker canvas", (c) => c.length);
  if (thumbs !== 9) throw new Error(`${thumbs} thumbnails`);
  await page.click("#slice");
  await waitResult(page, before, "lattice", T);
  const plot = await page.evaluate(() => {
    const card = document.querySelector('.stage-card[data-stage="paths"]');
    const line = card.querySelector('svg[data-plot-kind="line"]');
    const bars = card.querySelector('svg[data-plot-kind="bars"]');
    return {
      points: Number(line?.querySelector('[data-series="score"]')?.dataset.points ?? 0),
      hline: line?.querySelectorAll(".series-hline").length ?? 0,
      bars: bars?.querySelectorAll("rect.bar").length ?? 0,
      groups: card.querySelectorAll(".group-select option").length,
    };
  });
  if (plot.points !== 50 || plot.bars !== 3 || plot.hline !== 1 || plot.groups !== 3) throw new Error(JSON.stringify(plot));
  await page.selectOption('.stage-card[data-stage="paths"] .group-select', "2");
  const group = await page.$eval('.stage-card[data-stage="paths"]', (c) => c.dataset.group);
  if (group !== "2") throw new Error(`group ${group}`);
  const axis = await page.$eval("#show-axis", (el) => el.closest("label").hidden);
  if (axis) throw new Error("tool axis toggle hidden with an axis");
  return JSON.stringify(plot);
});

await check("view index control asks for another layer", async () => {
  const n = await page.evaluate(() => window.weft.views[0].answers);
  await page.fill(".view-card input[type=number]", "2");
  await page.dispatchEvent(".view-card input[type=number]", "change");
  await page.waitForFunction((k) => window.weft.views[0].answers > k && window.weft.views[0].index === 1, n, { timeout: T });
});

if (shots) {
  await page.screenshot({ path: join(shots, "mock-desktop.png"), fullPage: false });
  await page.setViewportSize({ width: 390, height: 844 });
  await page.waitForTimeout(300);
  await page.screenshot({ path: join(shots, "mock-phone.png"), fullPage: true });
}
if (errors.length) console.log(`console errors:\n  ${errors.join("\n  ")}`);
await browser.close();
await server.close();
console.log(failed ? `${failed} failed` : "all passed");
process.exit(failed ? 1 : 0);

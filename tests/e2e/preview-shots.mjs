#!/usr/bin/env node
// Screenshots of the 3D preview at a few viewports, with the framing measured: runs examples
// from the Examples menu in headless Chromium and saves tests/e2e/out/preview-<example>-<w>x<h>.png.
// Prints, per shot, the canvas size and the box of the part's pixels (the plate hidden).
//
//   node tests/e2e/preview-shots.mjs [example …]     (default: sphere-30mm honeycomb-10mm)
// Environment: PREVIEW_VIEWPORTS="1280x800,390x844" (default), CHROMIUM.
import { mkdirSync } from "node:fs";
import { join } from "node:path";
import { ROOT, serve } from "./server.mjs";
import { launchChromium, waitReady, waitResult } from "./page-helpers.mjs";
import { partBox } from "./preview-checks.mjs";

const OUT = join(ROOT, "tests/e2e/out");
mkdirSync(OUT, { recursive: true });
const examples = process.argv.slice(2).length ? process.argv.slice(2) : ["sphere-30mm", "honeycomb-10mm"];
const viewports = (process.env.PREVIEW_VIEWPORTS ?? "1280x800,390x844").split(",").map((s) => s.split("x").map(Number));

const server = await serve();
const browser = await launchChromium();
try {
  for (const [width, height] of viewports) {
    const context = await browser.newContext({ viewport: { width, height } });
    const page = await context.newPage();
    page.on("pageerror", (e) => console.log(`page error: ${e.message}`));
    await page.goto(`${server.url}/www/`);
    await waitReady(page);
    for (const name of examples) {
      await page.waitForSelector(`#examples option[value="${name}.json"]`, { state: "attached", timeout: 10000 });
      const before = await page.evaluate(() => window.weft.resultCount);
      await page.selectOption("#examples", `${name}.json`);
      await waitResult(page, before, name, 180000);
      await page.waitForTimeout(800); // report cards, view cards and a resize settle
      const box = await partBox(page);
      const path = join(OUT, `preview-${name}-${width}x${height}.png`);
      await page.locator(".canvas-wrap").scrollIntoViewIfNeeded();
      await page.screenshot({ path });
      await page.locator("#preview").screenshot({ path: path.replace(/\.png$/, "-canvas.png") });
      if (await page.locator("#views").isVisible()) {
        await page.locator("#views .card").first().screenshot({ path: path.replace(/\.png$/, "-view-card.png") });
      }
      console.log(`${name} @ ${width}x${height}: canvas ${box.width}×${box.height}, part ${box.w}×${box.h} px ` +
        `(${Math.round(box.fill * 100)} % of the canvas in its limiting direction) → ${path}`);
    }
    await context.close();
  }
} finally {
  await browser.close();
  await server.close();
}

// Scratch: screenshots of the axisymmetric cards and views (not part of the suite).
import { serve } from "./server.mjs";
import { launchChromium, waitReady, waitResult } from "./page-helpers.mjs";
const { url, close } = await serve();
const browser = await launchChromium();
for (const [w, h, tag] of [[1400, 900, "desktop"], [390, 844, "phone"]]) {
  const page = await browser.newPage({ viewport: { width: w, height: h } });
  await page.goto(`${url}/www/`);
  await waitReady(page);
  for (const ex of ["hourglass-omega3.json", "barrel-omega2.json"]) {
    const before = await page.evaluate(() => window.weft.resultCount);
    await page.selectOption("#examples", ex);
    await waitResult(page, before, ex, 120000);
    await page.waitForTimeout(1500);
    for (const sel of ['.stage-card[data-stage="platform"]', '.stage-card[data-stage="points"]', '.stage-card[data-stage="path"]', '.view-card[data-view="map"]', '.view-card[data-view="platform3d"]']) {
      const el = await page.$(sel);
      if (el) await el.screenshot({ path: `/tmp/shots/${tag}-${ex.replace(".json", "")}-${sel.match(/"(\w+)"/)[1]}.png` });
    }
  }
  await page.close();
}
await browser.close();
close?.();
process.exit(0);

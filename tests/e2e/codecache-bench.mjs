#!/usr/bin/env node
// A first visit against a return visit (issue 15): V8 starts a page's WebAssembly in its
// baseline tier and optimises hot functions as they run (on a background thread, sharing the
// cores with the pool), then keeps the optimised code with the cached module, so a reload or
// a later visit starts optimised. This drops the 1M-triangle sphere (tests/e2e/out/, made by
// threads-bench.mjs) on: a fresh browser profile (a first visit), the same profile after a
// reload and a later reload (a return visit: a new page, worker and pool), and a page that
// ran a quarter-size sphere first (warm). Prints the stage times of the run report and the
// drop → first frame time, as Markdown. Not a test (timings depend on the machine).
//
//   node tests/e2e/codecache-bench.mjs
// Environment: BENCH_THREADS (default 1,2), BENCH_ROUNDS fresh profiles per count (default 2),
//   BENCH_SW=block to keep the service worker out (default: allowed, as a visitor has it).
import { existsSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { ROOT, serve } from "./server.mjs";
import { dropAndTimeFirstFrame, launchChromium, waitReady } from "./page-helpers.mjs";
import { sphereStl } from "./threads-checks.mjs";

const OUT = join(ROOT, "tests/e2e/out");
const big = join(OUT, "sphere-1m.stl");
const small = join(OUT, "sphere-250k.stl");
if (!existsSync(big)) writeFileSync(big, sphereStl(1000));
if (!existsSync(small)) writeFileSync(small, sphereStl(500));
const COUNTS = (process.env.BENCH_THREADS ?? "1,2").split(",").map(Number);
const ROUNDS = Number(process.env.BENCH_ROUNDS ?? 2);
const server = await serve({ root: ROOT });
const browser = await launchChromium();

/** Drops `file` and waits for its first frame: the run's stage times and the frame time, ms. */
async function drop(page, file) {
  const r = await dropAndTimeFirstFrame(page, file);
  return { frame: r.frameMs, ...Object.fromEntries(r.stages.map((s) => [s.stage, s.ms])) };
}

const rows = [];
for (const threads of COUNTS) {
  for (let round = 1; round <= ROUNDS; round++) {
    const context = await browser.newContext({ viewport: { width: 1280, height: 800 }, serviceWorkers: process.env.BENCH_SW ?? "allow" });
    await context.addInitScript(() => localStorage.setItem("weft.autoRun", "0"));
    const page = await context.newPage();
    const open = async () => {
      await page.goto(`${server.url}/www/?threads=${threads}`);
      await waitReady(page);
      await page.waitForFunction(() => window.weft.threads.used != null);
    };
    await open();
    rows.push({ threads, round, visit: "first visit (fresh profile)", ...(await drop(page, big)) });
    await open();
    rows.push({ threads, round, visit: "reloaded", ...(await drop(page, big)) });
    await open();
    rows.push({ threads, round, visit: "reloaded again", ...(await drop(page, big)) });
    await open();
    await drop(page, small);
    rows.push({ threads, round, visit: "after a 250k sphere on the same page", ...(await drop(page, big)) });
    await context.close();
  }
}
await browser.close();
await server.close();

const ms = (v) => (v == null ? "–" : v >= 1000 ? `${(v / 1000).toFixed(2)} s` : `${Math.round(v)} ms`);
console.log("| threads | profile | page | import | slice | gcode | analyze | drop → first frame |");
console.log("|---|---|---|---|---|---|---|---|");
for (const r of rows) console.log(`| ${r.threads} | ${r.round} | ${r.visit} | ${ms(r.import)} | ${ms(r.slice)} | ${ms(r.gcode)} | ${ms(r.analyze)} | ${ms(r.frame)} |`);

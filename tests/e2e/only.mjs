#!/usr/bin/env node
// Runs one check module of the browser test on its own, while working on it:
//   node tests/e2e/only.mjs support-checks.mjs [first-number]
// The module's exported `…Checks` function gets the options run.mjs gives every module
// (browser, newPage, base/baseUrl, check, outDir, weftBin, first, timeoutMs). Environment as
// run.mjs (WEFT_PKG_DIR serves another wasm build, WEFT_BIN the CLI for cross-checks).
import { existsSync, mkdirSync } from "node:fs";
import { join, resolve } from "node:path";
import { ROOT, serve } from "./server.mjs";
import { checker, collectErrors, launchChromium } from "./page-helpers.mjs";

const [file, firstArg] = process.argv.slice(2);
if (!file) {
  console.error("usage: node tests/e2e/only.mjs MODULE.mjs [first-number]");
  process.exit(2);
}
const mod = await import(`./${file}`);
const fn = Object.entries(mod).find(([name, f]) => name.endsWith("Checks") && typeof f === "function")?.[1];
if (!fn) {
  console.error(`${file} exports no …Checks function`);
  process.exit(2);
}
const OUT = join(ROOT, "tests/e2e/out");
mkdirSync(OUT, { recursive: true });
const pkgDir = process.env.WEFT_PKG_DIR ? resolve(process.env.WEFT_PKG_DIR) : join(ROOT, "pkg");
const weftBin = resolve(ROOT, process.env.WEFT_BIN ?? "target/release/weft");
const { results, check } = checker();
const server = await serve({ root: ROOT, pkgDir });
const browser = await launchChromium();
const newPage = async () => {
  const context = await browser.newContext({ viewport: { width: 1400, height: 900 }, acceptDownloads: true });
  await context.addInitScript(() => {
    if (localStorage.getItem("weft.autoRun") === null) localStorage.setItem("weft.autoRun", "0");
  });
  const page = await context.newPage();
  return { context, page, errors: collectErrors(page) };
};
try {
  await fn({
    browser, newPage, base: server.url, baseUrl: server.url, check, outDir: OUT,
    weftBin: existsSync(weftBin) ? weftBin : null, first: Number(firstArg ?? 1),
    timeoutMs: Number(process.env.E2E_TIMEOUT_S ?? 120) * 1000,
  });
} finally {
  await browser.close();
  await server.close?.();
}
const failed = results.filter((r) => !r).length;
console.log(`${results.length - failed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);

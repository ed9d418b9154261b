// Page helpers shared by the end-to-end checks (run.mjs, lattice-checks.mjs, ui-mock.mjs).
import { readFileSync } from "node:fs";
import { chromium } from "playwright-core";

/**
 * The system Chromium (CHROMIUM, default /usr/bin/chromium), headless unless E2E_HEADED=1,
 * with a software WebGL.
 */
export function launchChromium() {
  const headed = Boolean(process.env.E2E_HEADED);
  return chromium.launch({
    executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
    headless: !headed,
    args: [
      "--headless", "--no-sandbox", "--disable-background-networking", "--disable-component-update",
      "--disable-sync", "--disable-gpu-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
    ].filter((a) => !(headed && a === "--headless")),
  });
}

/** Console errors and uncaught exceptions of `page`, collected from now on. */
export function collectErrors(page) {
  const errors = [];
  page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });
  page.on("pageerror", (e) => errors.push(`uncaught: ${e.message}`));
  return errors;
}

/**
 * Waits until the page has initialised, holds a design, and has finished what it does by
 * itself on opening (a first visit runs the default part).
 */
export async function waitReady(page) {
  await page.waitForFunction(() => window.weft && window.weft.design && !window.weft.busy, null, { timeout: 60000 });
}

/** Waits for the page to show one more result than `before`; fails on a visible error. */
export async function waitResult(page, before, what, timeout) {
  const handle = await page.waitForFunction(
    (n) => {
      if (window.weft.resultCount > n) return "ok";
      const err = document.getElementById("error");
      if (!err.hidden && !window.weft.busy) return `error: ${document.getElementById("error-text").textContent.trim()}`;
      return false;
    },
    before,
    { timeout, polling: 100 },
  ).catch(() => null);
  const state = handle ? await handle.jsonValue() : `no result within ${timeout / 1000} s`;
  if (state !== "ok") throw new Error(`${what}: ${state}`);
}

/** Pixels of the preview canvas that are toolpath-coloured (saturated), read after a frame. */
export async function colouredPixels(page) {
  return page.evaluate(async () => {
    await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
    const src = document.getElementById("preview");
    const c = document.createElement("canvas");
    c.width = src.width;
    c.height = src.height;
    const ctx = c.getContext("2d");
    ctx.drawImage(src, 0, 0);
    const d = ctx.getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) {
      const max = Math.max(d[i], d[i + 1], d[i + 2]);
      const min = Math.min(d[i], d[i + 1], d[i + 2]);
      if (max - min > 60 && max > 90) n++;
    }
    return n;
  });
}

/** Clicks "Download G-code" and saves the file to `path`. */
export async function downloadGcode(page, path) {
  if (await page.isDisabled("#download")) throw new Error("Download G-code is disabled: there is no result to download");
  const [dl] = await Promise.all([page.waitForEvent("download", { timeout: 30000 }), page.click("#download")]);
  await dl.saveAs(path);
  return { path, name: dl.suggestedFilename(), bytes: readFileSync(path) };
}

// Browser checks of teaching (issue 45): "How it works" for every job kind (each step draws
// pixels on its canvas, not just a title; every step photographed at 1280×800 and 390×844)
// and the embedded weft on a course page of another origin, driven by postMessage: it says it
// is ready, takes a field, runs and posts the statistics (the CLI's `weft analyze --json` of
// the CLI's G-code for the same design), steps, and answers a bad message in a plain sentence.
//
//   import { stepsChecks } from "./steps-checks.mjs";
//   await stepsChecks({ browser, newPage, weftBin, check, outDir: OUT, base, first: n, timeoutMs });
import { execFileSync } from "node:child_process";
import { writeFileSync } from "node:fs";
import { join } from "node:path";
import { ROOT, serve } from "./server.mjs";
import { runExample } from "./page-helpers.mjs";
import { pngInfo, savePicture } from "./pictures-checks.mjs";

/** The example each kind's step-through is checked on. */
const EXAMPLES = [
  ["lattice", "honeycomb-10mm.json"],
  ["axisymmetric", "hourglass-omega3.json"],
  ["graded", "graded-phantom.json"],
  ["foam", "foam-dogbone-linear.json"],
  ["freeform", "freeform-bridge.json"],
];

/** Pixels of the step canvas that differ from its background (the views' #1f232a). */
function drawnPixels(page) {
  return page.evaluate(() => {
    const c = document.querySelector("#how canvas");
    if (!c || !c.width || !c.height) return 0;
    const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) if (Math.abs(d[i] - 0x1f) + Math.abs(d[i + 1] - 0x23) + Math.abs(d[i + 2] - 0x2a) > 24) n++;
    return n;
  });
}

/** Waits until the step-through shows step `index` with an answer for it. */
async function waitStep(page, index, answersBefore, what) {
  await page.waitForFunction(([i, a]) => {
    const s = window.weft.steps;
    return s.open && s.index === i && s.answers > a && s.shape !== null;
  }, [index, answersBefore], { timeout: 60000 }).catch(async () => {
    const s = await page.evaluate(() => ({ ...window.weft.steps, caption: document.querySelector("#how .how-caption")?.textContent }));
    throw new Error(`${what}: step ${index + 1} never drew (${JSON.stringify(s)})`);
  });
}

export async function stepsChecks({ browser, newPage, weftBin, check, outDir, base, first, timeoutMs }) {
  await check(first, "how it works: every kind's steps each draw on their canvas (pixels, not just a title), scrubbing steps walk their frames; photographed at 1280×800 and 390×844", async () => {
    const said = [];
    for (const viewport of [{ width: 1280, height: 800 }, { width: 390, height: 844 }]) {
      const { context, page } = await newPage();
      try {
        await page.setViewportSize(viewport);
        for (const [kind, file] of EXAMPLES) {
          await runExample(page, base, file, timeoutMs, { confirm: true });
          // Each kind opens on the colouring that shows its method, an axisymmetric path on its platform.
          const teach = await page.evaluate(() => {
            const kind = JSON.parse(window.weft.design).job.kind;
            const t = window.weft.schema.job_kinds.find((k) => k.name === kind)?.teach ?? {};
            return { want: t.color_by, got: document.getElementById("color-by").value, backdrop: t.backdrop ?? null, drawn: window.weft.preview?.backdropSegments ?? 0 };
          });
          if (teach.want !== teach.got) throw new Error(`${kind} opens coloured by ${teach.got}, not ${teach.want}`);
          if (teach.backdrop) {
            await page.waitForFunction(() => (window.weft.preview?.backdropSegments ?? 0) > 0, null, { timeout: 30000 })
              .catch(() => { throw new Error(`${kind}: the backdrop ${teach.backdrop} is not drawn in the preview`); });
          }
          const count = await page.evaluate(() => window.weft.steps.count);
          if (count < 3) throw new Error(`${kind}: ${count} steps`);
          const drawn = [];
          for (let i = 0; i < count; i++) {
            const a = await page.evaluate(() => window.weft.steps.answers);
            await page.evaluate((k) => window.weft.step(k), i);
            await waitStep(page, i, a, kind);
            const s = await page.evaluate(() => window.weft.steps);
            const px = await drawnPixels(page);
            if (px < 200) throw new Error(`${kind} step ${i + 1} (${s.title}): ${px} drawn pixels`);
            const text = await page.$eval("#how .how-text", (e) => e.textContent);
            const cite = await page.$eval("#how .how-cite", (e) => e.textContent);
            if (text.length < 40 || !/\S/.test(cite)) throw new Error(`${kind} step ${i + 1}: text "${text}", cite "${cite}"`);
            if (s.frames > 1) {
              // The last frame draws too (a scrubbing step walks its frames).
              const b = await page.evaluate(() => window.weft.steps.answers);
              await page.$eval("#how-frame", (el) => { el.value = el.max; el.dispatchEvent(new Event("input")); });
              await page.waitForFunction(([n, f]) => window.weft.steps.answers > n && window.weft.steps.frame === f - 1, [b, s.frames], { timeout: 60000 });
              if ((await drawnPixels(page)) < 200) throw new Error(`${kind} step ${i + 1}: its last frame draws nothing`);
            }
            await page.$eval("#how", (el) => el.scrollIntoView({ block: "start" }));
            await page.screenshot({ path: join(outDir, `steps-${kind}-${i + 1}-${viewport.width}.png`) });
            drawn.push(`${s.title}${s.frames > 1 ? ` (${s.frames} frames)` : ""}`);
          }
          if (viewport.width === 1280) said.push(`${kind}: ${drawn.join(" → ")}`);
          if (kind === "lattice" && viewport.width === 1280) {
            // A step saves as a picture like any view: the PNG decodes at the asked size.
            await page.evaluate(() => window.weft.step(3));
            await page.waitForFunction(() => window.weft.steps.index === 3 && window.weft.steps.items > 0, null, { timeout: 60000 });
            const pic = await savePicture(page, "#how .picture-button", { width: 1200, height: 700, format: "png" });
            const info = pngInfo(pic.bytes);
            if (info.width !== 1200 || info.height !== 700 || !/How it works 4/.test(pic.caption)) {
              throw new Error(`the step's picture: ${info.width} × ${info.height}, caption "${pic.caption}"`);
            }
            said.push(`step 4's PNG ${info.width} × ${info.height} (${pic.name})`);
          }
        }
      } finally {
        await context.close();
      }
    }
    return said.join("; ");
  });

  await check(first + 1, "embed: a course page on another origin embeds weft, sets a field by postMessage, gets the run's statistics (the CLI's numbers for the same design), steps through, and gets plain sentences for bad messages", async () => {
    // The course page: another origin (a second, plain server), the weft page in an iframe.
    const host = await serve({ root: ROOT, isolated: false });
    const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
    try {
      const design = join(ROOT, "examples/honeycomb-10mm.json");
      const fragment = execFileSync(weftBin, ["share", design], { encoding: "utf8" }).trim();
      const weftOrigin = base;
      const hostPage = join(outDir, "embed-host.html");
      writeFileSync(hostPage, `<!doctype html><html><head><meta charset="utf-8"><title>course page</title></head><body>
<h1>A course page</h1><iframe id="w" width="1000" height="700" style="border:1px solid #999"></iframe>
<script src="embed-host.js"></script></body></html>`);
      writeFileSync(join(outDir, "embed-host.js"), `window.got = [];
window.addEventListener("message", (e) => { if (e.origin === ${JSON.stringify(weftOrigin)}) window.got.push(e.data); });
document.getElementById("w").src = ${JSON.stringify(`${weftOrigin}/www/embed.html${fragment}&fields=job.paths.method,job.lattice.pattern.hexagon_radius_mm`)};
window.send = (m) => document.getElementById("w").contentWindow.postMessage(m, "*");`);
      const page = await context.newPage();
      const hostUrl = host.url.replace("127.0.0.1", "localhost");
      await page.goto(`${hostUrl}/tests/e2e/out/embed-host.html`);
      const got = (type, after = 0) => page.waitForFunction(([t, n]) => window.got.slice(n).find((m) => m?.type === t), [type, after], { timeout: timeoutMs })
        .then((h) => h.jsonValue());
      const ready = await got("weft:ready");
      if (!(ready.steps?.length >= 3)) throw new Error(`weft:ready names ${JSON.stringify(ready.steps)}`);
      const first = await got("weft:result"); // the link runs its design
      if (!(first.stats?.layers > 0)) throw new Error(`first result: ${JSON.stringify(first.stats)}`);
      const frame = page.frames().find((f) => f.url().includes("index.html?embed"));
      if (!frame) throw new Error(`no embedded weft among ${page.frames().map((f) => f.url()).join(", ")}`);
      const shown = await frame.evaluate(() => ({
        fields: [...document.querySelectorAll("#schema-fields [data-path]")].filter((el) => !el.closest("[hidden]") && el.offsetParent).map((el) => el.dataset.path),
        isolated: self.crossOriginIsolated, threads: document.getElementById("threads")?.textContent ?? "",
        open: document.getElementById("embed-open")?.href ?? "",
      }));
      if (!shown.fields.includes("job.paths.method") || shown.fields.some((p) => !p.startsWith("job.paths.method") && !p.startsWith("job.lattice.pattern.hexagon_radius_mm"))) {
        throw new Error(`the embed shows fields ${shown.fields.join(", ")}`);
      }
      if (!shown.open.includes("index.html#d=")) throw new Error(`"Open in weft" goes to ${shown.open}`);
      if (!shown.isolated && !/1 thread|one thread/i.test(shown.threads)) throw new Error(`not isolated, but the page says "${shown.threads}"`);
      // Set a field, run: the statistics are the CLI's for the design the embed ran.
      let n = await page.evaluate(() => window.got.length);
      await page.evaluate(() => window.send({ type: "weft:set", path: "job.paths.method", value: "euler" }));
      await frame.waitForFunction(() => JSON.parse(window.weft.design).job.paths.method === "euler", null, { timeout: 10000 });
      await page.evaluate(() => window.send({ type: "weft:run" }));
      const result = await got("weft:result", n);
      const ran = join(outDir, "embed-ran.json");
      writeFileSync(ran, result.design);
      const out = join(outDir, "embed-ran.gcode");
      execFileSync(weftBin, ["run", ran, "--out", out, "-q"], { stdio: ["ignore", "pipe", "pipe"] });
      const cli = JSON.parse(execFileSync(weftBin, ["analyze", out, "--json"], { encoding: "utf8" }));
      const keys = Object.keys(cli).filter((k) => typeof cli[k] === "number");
      const off = keys.filter((k) => result.stats[k] !== cli[k]);
      if (keys.length < 5 || off.length) throw new Error(`stats differ from the CLI's on ${off.map((k) => `${k}: ${result.stats[k]} vs ${cli[k]}`).join(", ")}`);
      // Step.
      await page.evaluate(() => window.send({ type: "weft:step", index: 2 }));
      await frame.waitForFunction(() => window.weft.steps.index === 2 && window.weft.steps.shape !== null && window.weft.steps.items > 0, null, { timeout: 60000 });
      const step = await frame.evaluate(() => window.weft.steps);
      // Bad messages: one plain sentence each, no stack trace.
      n = await page.evaluate(() => window.got.length);
      await page.evaluate(() => window.send({ type: "weft:set", path: "job.paths.nope", value: 3 }));
      const bad = await got("weft:error", n);
      n = await page.evaluate(() => window.got.length);
      await page.evaluate(() => window.send({ type: "weft:step", index: 99 }));
      const badStep = await got("weft:error", n);
      for (const m of [bad.message, badStep.message]) {
        if (!m || /\n\s+at |Error:|wasm-function|\.js:\d+/.test(m)) throw new Error(`error message "${m}"`);
      }
      await page.screenshot({ path: join(outDir, "embed-1280.png") });
      await page.setViewportSize({ width: 390, height: 844 });
      await page.$eval("#w", (el) => { el.width = "370"; el.height = "760"; });
      await page.waitForTimeout(500);
      await page.screenshot({ path: join(outDir, "embed-390.png") });
      return `ready with ${ready.steps.length} steps; ${keys.length} statistics = the CLI's (${result.stats.layers} layers, ${result.stats.extruded_mm} mm); step 3 "${step.title}" drew ${step.items} items; ${shown.isolated ? "isolated" : `not isolated: "${shown.threads}"`}; errors: "${bad.message.slice(0, 80)}" | "${badStep.message}"`;
    } finally {
      await context.close();
      await host.close();
    }
  });
  return first + 2;
}

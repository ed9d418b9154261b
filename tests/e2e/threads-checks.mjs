// Browser checks of the worker's threads (issue 15): the page served cross-origin isolated runs
// the threaded module on a pool of web workers, a plain static host runs the plain module on
// one thread (and says why), or gets isolated by the service worker after one reload; every
// way gives the same G-code bytes (the examples' golden hashes, a generated 1M-triangle sphere
// against the native CLI); Cancel during the parallel slicing stops every thread and the next
// run gives the same bytes. Called by run.mjs:
//
//   import { threadsChecks } from "./threads-checks.mjs";
//   await threadsChecks({ browser, baseUrl: base, weftBin: WEFT_BIN, check, outDir: OUT, first: n });
import { existsSync, readdirSync, readFileSync, writeFileSync } from "node:fs";
import { createHash } from "node:crypto";
import { execFileSync } from "node:child_process";
import { join } from "node:path";
import { ROOT, serve } from "./server.mjs";
import { collectErrors, confirmBigJobs, waitReady, watchAfterCancel } from "./page-helpers.mjs";

const sha256 = (buf) => createHash("sha256").update(buf).digest("hex");

/**
 * A closed UV sphere (radius 40 mm, resting on z = 0) as a binary STL: `segments` around,
 * `segments / 2` rings, 2·segments·(rings − 1) triangles (998 000 for 1000).
 */
export function sphereStl(segments) {
  const rings = Math.floor(segments / 2);
  const R = 40;
  const vertex = (r, s) => {
    const th = (Math.PI * r) / rings, ph = (2 * Math.PI * (s % segments)) / segments;
    return [R * Math.sin(th) * Math.cos(ph), R * Math.sin(th) * Math.sin(ph), R + R * Math.cos(th)];
  };
  const count = 2 * segments * (rings - 1);
  const buf = Buffer.alloc(84 + 50 * count);
  buf.write("weft e2e sphere", 0, "ascii");
  buf.writeUInt32LE(count, 80);
  let o = 84;
  const put = (a, b, c) => {
    o += 12; // normal 0 0 0: readers recompute it from the winding
    for (const p of [a, b, c]) for (const v of p) { buf.writeFloatLE(v, o); o += 4; }
    o += 2;
  };
  for (let r = 0; r < rings; r++) {
    for (let s = 0; s < segments; s++) {
      const a = vertex(r, s), b = vertex(r, s + 1), c = vertex(r + 1, s), d = vertex(r + 1, s + 1);
      if (r > 0) put(a, c, b);
      if (r < rings - 1) put(b, c, d);
    }
  }
  return buf;
}

/**
 * CPU time (user + system, in clock ticks of 1/100 s) of every thread of Chromium's renderer
 * processes named for a dedicated worker, by "pid/tid" (Linux /proc). A terminated worker's
 * thread disappears; a new worker's thread has a new id.
 */
function workerThreadTicks() {
  const out = new Map();
  for (const pid of readdirSync("/proc").filter((d) => /^\d+$/.test(d))) {
    let tids;
    try {
      if (!readFileSync(`/proc/${pid}/cmdline`, "utf8").includes("--type=renderer")) continue;
      tids = readdirSync(`/proc/${pid}/task`);
    } catch { continue; }
    for (const tid of tids) {
      try {
        const stat = readFileSync(`/proc/${pid}/task/${tid}/stat`, "utf8");
        if (!/DedicatedWorker/.test(stat.slice(stat.indexOf("(") + 1, stat.lastIndexOf(")")))) continue;
        const f = stat.slice(stat.lastIndexOf(")") + 2).split(" ");
        out.set(`${pid}/${tid}`, Number(f[11]) + Number(f[12]));
      } catch { /* the thread ended */ }
    }
  }
  return out;
}

/** The SHA-256 of the page's last result's G-code. */
const resultHash = (page) => page.evaluate(async () => {
  const d = await crypto.subtle.digest("SHA-256", window.weft.result.gcode);
  return [...new Uint8Array(d)].map((b) => b.toString(16).padStart(2, "0")).join("");
});

/**
 * Waits until `ready(arg)` holds in the page (its value, or null after `timeout` ms), the page
 * answering "Run anyway" whenever it asks first (a big job is asked about once its file is
 * read, which takes longer under load).
 */
async function untilRunning(page, ready, arg, timeout) {
  await confirmBigJobs(page);
  return page.waitForFunction(ready, arg, { timeout, polling: 10 }).then((h) => h.jsonValue()).catch(() => null);
}

/** Waits for the worker to be ready and returns window.weft.threads. */
async function threadsOf(page) {
  await page.waitForFunction(() => window.weft?.threads?.used != null, null, { timeout: 60000 });
  return page.evaluate(() => window.weft.threads);
}

/**
 * @param {{browser: import("playwright-core").Browser, baseUrl: string, weftBin: string,
 *          check: Function, outDir: string, first: number, timeoutMs?: number}} opts
 * @returns {Promise<number>} the next check number
 */
export async function threadsChecks({ browser, baseUrl, weftBin, check, outDir, first, timeoutMs = 120000 }) {
  let n = first;
  const plainHost = await serve({ root: ROOT, isolated: false });
  const golden = new Map(readFileSync(join(ROOT, "tests/golden/gcode.sha256"), "utf8").trim().split("\n")
    .map((l) => l.split(/\s+/)).map(([h, name]) => [name.replace(/\.gcode$/, ""), h]));
  const sphere = join(outDir, "sphere-1m.stl");
  if (!existsSync(sphere)) writeFileSync(sphere, sphereStl(1000));
  let sphereHash = null;
  let cliHash = null;

  /** A fresh context at `url` (service workers blocked unless `serviceWorkers` is "allow"). */
  async function open(url, { serviceWorkers = "block", viewport = { width: 1280, height: 800 } } = {}) {
    const context = await browser.newContext({ viewport, acceptDownloads: true, serviceWorkers });
    await context.addInitScript(() => {
      if (localStorage.getItem("weft.autoRun") === null) localStorage.setItem("weft.autoRun", "0");
    });
    const page = await context.newPage();
    const errors = collectErrors(page);
    await page.goto(url);
    await waitReady(page);
    return { context, page, errors };
  }

  /** Drops the sphere on the mesh slot of the default design and waits for its result and its
   *  first drawn frame; returns the times (ms from the drop). */
  async function dropSphere(page) {
    const before = await page.evaluate(() => {
      window.__dropAt = null;
      document.getElementById("file").addEventListener("change", () => { window.__dropAt = performance.now(); }, { capture: true, once: true });
      return window.weft.resultCount;
    });
    await page.setInputFiles("#file", sphere);
    const done = await untilRunning(page, (k) => {
      if (window.weft.resultCount > k && !window.weft.busy) {
        const f = window.weft.preview?.lastFrame;
        if (f && f.segments > 0 && f.at > window.__dropAt) return { frame: f.at - window.__dropAt, segments: f.segments };
      }
      const err = document.getElementById("error");
      if (!err.hidden && !window.weft.busy) return { error: document.getElementById("error-text").textContent.trim() };
      return false;
    }, before, timeoutMs) ?? { error: "timed out" };
    if (done.error) throw new Error(`the 1M-triangle sphere: ${done.error}`);
    const result = await page.evaluate(() => ({ ms: window.weft.result.ms, threads: window.weft.result.report.threads }));
    return { ...done, ...result, hash: await resultHash(page) };
  }

  /** The CLI's G-code of the page's design (the default one, named after the dropped sphere). */
  async function cliSphereHash(page) {
    if (cliHash) return cliHash;
    const design = join(outDir, "sphere-1m-design.json");
    writeFileSync(design, await page.evaluate(() => window.weft.design));
    const out = join(outDir, "sphere-1m-cli.gcode");
    execFileSync(weftBin, ["run", design, "--input", sphere, "--out", out, "--threads", "2"],
      { cwd: ROOT, stdio: ["ignore", "pipe", "pipe"], timeout: 300000 });
    cliHash = sha256(readFileSync(out));
    return cliHash;
  }

  await check(n++, "threads: served cross-origin isolated (as scripts/serve.py), `?threads=4` runs the threaded module on 4 workers and says so; a dropped 1M-triangle sphere gives the CLI's G-code bytes; drop → first shaded frame timed", async () => {
    const { context, page, errors } = await open(`${baseUrl}/www/?threads=4`);
    try {
      const t = await threadsOf(page);
      if (!t.isolated || t.used !== 4) throw new Error(`threads ${JSON.stringify(t)}; expected 4 in an isolated page`);
      const line = (await page.textContent("#threads")).trim();
      if (line !== "4 threads") throw new Error(`the thread line reads "${line}"`);
      const r = await dropSphere(page);
      if (r.threads !== 4) throw new Error(`the run report says ${r.threads} threads`);
      const timeLine = (await page.textContent("#stats .time-line")).trim();
      if (!/— 4 threads$/.test(timeLine)) throw new Error(`time line "${timeLine}"`);
      if (r.hash !== await cliSphereHash(page)) throw new Error(`G-code ${r.hash.slice(0, 12)}… ≠ the CLI's ${cliHash.slice(0, 12)}…`);
      sphereHash = r.hash;
      if (errors.length) throw new Error(`console errors:\n${errors.join("\n")}`);
      return `drop → first frame ${(r.frame / 1000).toFixed(2)} s (worker ${(r.ms / 1000).toFixed(2)} s, ${r.segments} segments)`;
    } finally {
      await context.close();
    }
  });

  await check(n++, "threads: a plain static host (no COOP/COEP) without a service worker runs the plain module on one thread and says why; every example and the 1M sphere give the same bytes as threaded", async () => {
    const { context, page, errors } = await open(`${plainHost.url}/www/`);
    try {
      const t = await threadsOf(page);
      if (t.isolated || t.used !== 1) throw new Error(`threads ${JSON.stringify(t)}; expected 1, not isolated`);
      const line = (await page.textContent("#threads")).trim();
      const title = await page.getAttribute("#threads", "title");
      if (line !== "1 thread (no shared memory here)" || !/not cross-origin isolated/.test(title)) throw new Error(`the thread line reads "${line}" (${title})`);
      await page.waitForFunction(() => document.querySelectorAll("#examples option[value]:not([value=''])").length > 0);
      const files = await page.$$eval("#examples option", (os) => os.map((o) => o.value).filter(Boolean));
      const wrong = [];
      // On one thread the tilted truss is estimated over 5 s: the page asks first.
      await confirmBigJobs(page);
      for (const file of files) {
        const name = file.replace(/\.json$/, "");
        const before = await page.evaluate(() => window.weft.resultCount);
        await page.selectOption("#examples", file);
        await page.waitForFunction((k) => window.weft.resultCount > k && !window.weft.busy, before, { timeout: timeoutMs });
        const [hash, threads] = [await resultHash(page), await page.evaluate(() => window.weft.result.report.threads)];
        if (threads !== 1) wrong.push(`${name}: ${threads} threads`);
        if (hash !== golden.get(name)) wrong.push(`${name}: ${hash.slice(0, 12)}… ≠ ${golden.get(name)?.slice(0, 12)}…`);
      }
      if (wrong.length) throw new Error(wrong.join("; "));
      // The default design again, then the sphere on it.
      await page.evaluate(() => localStorage.removeItem("weft.design"));
      await page.reload();
      await waitReady(page);
      const r = await dropSphere(page);
      if (r.threads !== 1) throw new Error(`the sphere ran on ${r.threads} threads`);
      if (r.hash !== await cliSphereHash(page)) throw new Error(`sphere G-code ${r.hash.slice(0, 12)}… ≠ the CLI's ${cliHash.slice(0, 12)}…`);
      if (errors.length) throw new Error(`console errors:\n${errors.join("\n")}`);
      return `${files.length} examples at their golden hashes; sphere drop → first frame ${(r.frame / 1000).toFixed(2)} s on 1 thread (worker ${(r.ms / 1000).toFixed(2)} s)`;
    } finally {
      await context.close();
    }
  });

  await check(n++, "threads: on a plain static host the service worker adds the isolation headers; the page reloads itself once and runs on every core", async () => {
    const { context, page, errors } = await open(`${plainHost.url}/www/`, { serviceWorkers: "allow" });
    try {
      // The page reloads itself: poll across the navigation.
      const t0 = Date.now();
      let isolated = false;
      while (!isolated && Date.now() - t0 < 30000) {
        isolated = await page.evaluate(() => self.crossOriginIsolated && window.weft?.threads?.used != null).catch(() => false);
        if (!isolated) await new Promise((r) => setTimeout(r, 100));
      }
      if (!isolated) throw new Error("the page did not become cross-origin isolated");
      await waitReady(page);
      const t = await threadsOf(page);
      const cores = await page.evaluate(() => navigator.hardwareConcurrency);
      if (t.used !== Math.min(cores, 16) || t.used < 2 && cores >= 2) throw new Error(`threads ${JSON.stringify(t)} on ${cores} cores`);
      const reloads = await page.evaluate(() => sessionStorage.getItem("weft.isolationReload"));
      if (reloads !== "1") throw new Error("no reload was recorded");
      if (errors.length) throw new Error(`console errors:\n${errors.join("\n")}`);
      return `${t.used} threads after one reload`;
    } finally {
      await context.close();
    }
  });

  // The promise of Cancel on the threaded module: the page tells the pool's loops through
  // shared memory, so every thread of the run stops by itself at once, instead of computing
  // on until Chromium ends a busy worker, 2 s after terminate(). It is measured in CPU time,
  // not in wall-clock windows: a thread that goes on computing burns CPU until it is ended,
  // however busy the machine is, while a thread that stopped takes none, however late the
  // machine lets it see the word. On 2 cores, with the page's shared-memory store removed,
  // the threads took 1.1–1.3 s of CPU after Cancel, and still 1.0–1.1 s with both cores kept
  // busy by `stress-ng --cpu 2`; with it, 0–10 ms at any of those loads. Cancel is dated by
  // events (the page's worker generation changes, each worker's close, each thread's end in
  // /proc), the bounds on those only keep a broken run from hanging.
  const CANCEL_CPU_BUDGET_MS = 300;
  await check(n++, `threads: Cancel while 4 threads slice the 1M sphere: every thread of the run stops by itself (at most ${CANCEL_CPU_BUDGET_MS} ms of CPU among them after Cancel, at any load; computing until Chromium ends them takes over 1 s), every worker and its thread ends, nothing of the run shows after; the next run gives the same bytes as a fresh one`, async () => {
    // The DedicatedWorker threads already there (other pages' workers): this page's are the new ones.
    const others = workerThreadTicks();
    const { context, page, errors } = await open(`${baseUrl}/www/?threads=4`);
    try {
      await threadsOf(page);
      const before = await page.evaluate(() => window.weft.resultCount);
      const gen = await page.evaluate(() => window.weft.workerGeneration);
      await page.setInputFiles("#file", sphere);
      // Cancel while the slicing stage (parallel) runs.
      const slicing = await untilRunning(page, () => /slic/i.test(document.getElementById("progress-label")?.textContent ?? "") && !document.getElementById("progress").hidden, null, timeoutMs);
      if (!slicing) throw new Error("the slicing stage was never shown in progress");
      const old = page.workers();
      if (old.length !== 5) throw new Error(`${old.length} workers before Cancel; expected the worker and 4 pool workers`);
      const closed = Promise.all(old.map((w) => new Promise((r) => w.once("close", r))));
      const threads = [...workerThreadTicks().keys()].filter((id) => !others.has(id));
      if (threads.length < old.length) throw new Error(`only ${threads.length} new DedicatedWorker threads found in /proc for ${old.length} workers`);
      // From the moment Cancel has been handled (a listener after the page's own), anything
      // the page shows of a run (progress bar, its label, stats, report) is recorded.
      await watchAfterCancel(page);
      await page.click("#cancel");
      await page.waitForFunction((g) => window.weft.workerGeneration > g, gen, { timeout: 10000 });
      // Cancel has been handled: each thread's CPU time from now until its thread ends.
      const t0 = Date.now();
      const ticks = (id) => {
        try {
          const stat = readFileSync(`/proc/${id.replace("/", "/task/")}/stat`, "utf8");
          const f = stat.slice(stat.lastIndexOf(")") + 2).split(" ");
          return Number(f[11]) + Number(f[12]);
        } catch { return null; } // the thread ended
      };
      const first = new Map(threads.map((id) => [id, ticks(id)]));
      const last = new Map(first);
      let left = threads.filter((id) => first.get(id) !== null);
      const aliveAtCancel = left.length;
      // Chromium ends a terminated worker's thread 2 s after terminate() at the latest; the
      // bound only keeps a broken run from hanging (under load the 2 s stretch).
      while (left.length && Date.now() - t0 < 60000) {
        await new Promise((r) => setTimeout(r, 20));
        left = left.filter((id) => {
          const t = ticks(id);
          if (t === null) return false;
          last.set(id, t);
          return true;
        });
      }
      if (left.length) throw new Error(`${left.length} of the cancelled run's ${threads.length} worker threads still there 60 s after Cancel`);
      const threadsGoneMs = Date.now() - t0;
      const usedMs = 10 * threads.reduce((sum, id) => sum + ((last.get(id) ?? 0) - (first.get(id) ?? 0)), 0);
      if (!await Promise.race([closed.then(() => true), new Promise((r) => setTimeout(() => r(false), 60000))])) {
        throw new Error(`not every one of the ${old.length} workers closed within 60 s of Cancel`);
      }
      const shown = await page.evaluate(() => { window.__stopWatch?.(); return { after: window.__afterCancel, count: window.weft.resultCount, busy: window.weft.busy }; });
      if (shown.after === null) throw new Error("the Cancel click never reached the page");
      if (shown.after.length) throw new Error(`after Cancel the page still showed the cancelled run: ${[...new Set(shown.after)].join(", ")}`);
      if (shown.count !== before) throw new Error("the cancelled run delivered a result");
      if (shown.busy) throw new Error("still busy after Cancel");
      if (usedMs > CANCEL_CPU_BUDGET_MS) throw new Error(`the cancelled run's threads used ${usedMs} ms of CPU after Cancel (budget ${CANCEL_CPU_BUDGET_MS} ms): they did not stop by themselves`);
      // The next run, on the new worker and its new pool.
      await threadsOf(page);
      await page.click("#slice");
      if (!await untilRunning(page, (k) => window.weft.resultCount > k && !window.weft.busy, before, timeoutMs)) throw new Error("the run after Cancel gave no result");
      const hash = await resultHash(page);
      if (hash !== (sphereHash ?? await cliSphereHash(page))) throw new Error(`after Cancel the G-code is ${hash.slice(0, 12)}…, a fresh run's ${(sphereHash ?? cliHash).slice(0, 12)}…`);
      const real = errors.filter((e) => !/cancel/i.test(e));
      if (real.length) throw new Error(`console errors:\n${real.join("\n")}`);
      return `${old.length} workers, ${threads.length} threads (${aliveAtCancel} there when Cancel was handled): ${usedMs} ms of CPU after Cancel, all ended ${(threadsGoneMs / 1000).toFixed(1)} s after it; nothing shown after`;
    } finally {
      await context.close();
    }
  });

  await plainHost.close();
  return n;
}

// Browser checks of Send (www/send.js) against real print hosts: a Moonraker and an OctoPrint
// running on 127.0.0.1 (tests/hosts/hosts.py starts them from PyPI and prints their addresses
// and keys as JSON). A plain cube from the Examples menu is sent to Moonraker and found there
// with the download's exact bytes; sent to OctoPrint with "start" and seen printing on its
// virtual printer; a wrong key, a page origin the host does not allow (CORS), a closed port and
// an upload stopped half way each give their one sentence; saved hosts stay in localStorage
// only; the dialog is photographed at 1280×800 and 390×844 and must fit the screen.
//
//   import { sendChecks, hostsFromEnv } from "./send-checks.mjs";
//   await sendChecks({ browser, baseUrl: base, hosts: hostsFromEnv(), check, outDir: OUT, first: n });
//
// or by itself (starts the page server and Chromium, prints "N passed, M failed"):
//
//   WEFT_HOSTS="$(python3 tests/hosts/hosts.py …)" node tests/e2e/send-checks.mjs
//
// WEFT_HOSTS is the harness's JSON, or a path to a file holding it:
//   {"moonraker": {"url": "http://127.0.0.1:P", "key": "…"?},
//    "octoprint": {"url": "http://127.0.0.1:Q", "key": "…"}}
// (flat names are read too: moonraker_url, moonraker_key, octoprint_url, octoprint_key or
// octoprint_api_key). What the hosts must allow: Moonraker's [authorization] cors_domains
// lists http://127.0.0.1:* but not http://localhost:* (the CORS check opens the page from
// http://localhost:PORT), and the key, when given, is Moonraker's API key; OctoPrint has
// api.allowCrossOrigin on, a virtual printer connected, and the key is an admin's API key.
// Without WEFT_HOSTS the checks are counted as failed, naming what is missing.
import { createHash } from "node:crypto";
import { existsSync, readFileSync } from "node:fs";
import { join, resolve } from "node:path";
import { pathToFileURL } from "node:url";
import { ROOT, serve } from "./server.mjs";
import { checker, collectErrors, downloadGcode, launchChromium, runExample, waitResult } from "./page-helpers.mjs";

const EXAMPLE = "cube-20mm.json";
const sha256 = (buf) => createHash("sha256").update(buf).digest("hex");

/** The harness's hosts from WEFT_HOSTS (JSON text or a file), or null. */
export function hostsFromEnv(env = process.env) {
  const raw = env.WEFT_HOSTS?.trim();
  if (!raw) return null;
  const text = raw.startsWith("{") ? raw : readFileSync(raw, "utf8");
  const j = JSON.parse(text);
  const pick = (...xs) => xs.find((x) => typeof x === "string" && x) ?? "";
  // tests/hosts/hosts.py prints the addresses as strings ({"moonraker": "http://…", "octoprint_key": …}).
  const m = typeof j.moonraker === "string" ? { url: j.moonraker } : j.moonraker ?? {};
  const o = typeof j.octoprint === "string" ? { url: j.octoprint } : j.octoprint ?? {};
  const hosts = {
    moonraker: { url: pick(m.url, j.moonraker_url).replace(/\/+$/, ""), key: pick(m.key, m.api_key, j.moonraker_key) },
    octoprint: { url: pick(o.url, j.octoprint_url).replace(/\/+$/, ""), key: pick(o.key, o.api_key, o.apikey, j.octoprint_key, j.octoprint_api_key) },
  };
  return hosts;
}

/** GET/POST/DELETE on a host from Node (the test's own view of the host), JSON or text. */
async function host(url, path, { key = "", method = "GET", body = null } = {}) {
  const headers = key ? { "X-Api-Key": key } : {};
  if (body) headers["Content-Type"] = "application/json";
  const res = await fetch(`${url}${path}`, { method, headers, body: body ? JSON.stringify(body) : undefined });
  const buf = Buffer.from(await res.arrayBuffer());
  let json = null;
  try {
    json = JSON.parse(buf.toString("utf8"));
  } catch { /* a file's bytes */ }
  return { status: res.status, json, buf };
}

/**
 * @param {{browser: import("playwright-core").Browser, baseUrl: string, hosts: object|null,
 *          check: Function, outDir: string, first: number, timeoutMs?: number,
 *          root?: string}} opts  root: what the page server serves (run.mjs's ROOT)
 * @returns {Promise<number>} the next check number
 */
export async function sendChecks({ browser, baseUrl, hosts, check, outDir, first, timeoutMs, root = ROOT, weftBin = null }) {
  const jobTimeout = timeoutMs ?? Number(process.env.E2E_TIMEOUT_S ?? 120) * 1000;
  let n = first;
  const mr = hosts?.moonraker ?? {};
  const op = hosts?.octoprint ?? {};
  const need = () => {
    if (!mr.url || !op.url || !op.key) {
      throw new Error("no print hosts: set WEFT_HOSTS to tests/hosts/hosts.py's JSON (Moonraker url, OctoPrint url and key)");
    }
  };
  const port = new URL(baseUrl).port;
  // Pages of this file's own: the page at 127.0.0.1 or localhost, the hosts on 127.0.0.1;
  // nothing else may be asked for. Every console line is kept: none may hold a key.
  const consoleLines = [];
  const offOrigin = [];
  const open = async ({ viewport = { width: 1280, height: 800 }, serviceWorkers = "allow" } = {}) => {
    const context = await browser.newContext({ viewport, acceptDownloads: true, serviceWorkers });
    await context.addInitScript(() => {
      if (localStorage.getItem("weft.autoRun") === null) localStorage.setItem("weft.autoRun", "0");
    });
    await context.route(/^(?!http:\/\/(127\.0\.0\.1|localhost):\d+\/|blob:|data:)/, (route) => {
      offOrigin.push(route.request().url());
      return route.abort();
    });
    const page = await context.newPage();
    page.on("console", (m) => consoleLines.push(m.text()));
    return { context, page, errors: collectErrors(page) };
  };
  /** Opens the dialog, fills it and presses Send; resolves when it is done (uploaded or failed). */
  const sendVia = async (page, { kind, url, key = "", start = false, remember = true, wait = true, format = null }) => {
    if (!(await page.isVisible("#send-dialog"))) await page.click("#send");
    await page.waitForSelector("#send-dialog[open]", { timeout: 10000 });
    if (format) await page.selectOption("#send-format", format);
    await page.check(`input[name=send-kind][value=${kind}]`);
    await page.fill("#send-url", url);
    await page.fill("#send-key", key);
    await page.setChecked("#send-start", start);
    await page.setChecked("#send-remember", remember);
    await page.click("#send-go");
    if (!wait) return null;
    await page.waitForFunction(() => ["uploaded", "failed"].includes(document.getElementById("send-dialog").dataset.phase), null, { timeout: jobTimeout });
    return page.evaluate(() => ({
      phase: document.getElementById("send-dialog").dataset.phase,
      status: document.getElementById("send-status").textContent,
      error: document.getElementById("send-error").hidden ? "" : document.getElementById("send-error").textContent,
      job: document.getElementById("send-dialog").dataset.job ?? "",
    }));
  };
  const closeDialog = (page) => page.evaluate(() => document.getElementById("send-dialog").close());

  const main = await open();
  const { page } = main;
  let download = null;
  try {
    await check(n++, "send: a plain cube sent to Moonraker arrives with the download's exact bytes; the dialog says Uploaded and the host’s printer state", async () => {
      need();
      await runExample(page, baseUrl, EXAMPLE, jobTimeout);
      download = await downloadGcode(page, join(outDir, "send-cube.gcode"));
      const name = download.name;
      await host(mr.url, `/server/files/gcodes/${encodeURIComponent(name)}`, { key: mr.key, method: "DELETE" });
      const r = await sendVia(page, { kind: "moonraker", url: mr.url, key: mr.key });
      if (r.phase !== "uploaded" || !r.status.startsWith(`Uploaded ${name} to `)) throw new Error(`the dialog says: ${JSON.stringify(r)}`);
      await page.waitForFunction(() => document.getElementById("send-dialog").dataset.job, null, { timeout: 10000 });
      const job = await page.evaluate(() => ({ job: document.getElementById("send-dialog").dataset.job, status: document.getElementById("send-status").textContent }));
      const list = await host(mr.url, "/server/files/list?root=gcodes", { key: mr.key });
      const entry = (list.json?.result ?? []).find((f) => f.path === name);
      if (!entry) throw new Error(`${name} is not in Moonraker's file list: ${JSON.stringify(list.json).slice(0, 300)}`);
      if (entry.size !== download.bytes.length) throw new Error(`Moonraker holds ${entry.size} bytes, the download ${download.bytes.length}`);
      const back = await host(mr.url, `/server/files/gcodes/${encodeURIComponent(name)}`, { key: mr.key });
      if (sha256(back.buf) !== sha256(download.bytes)) throw new Error("the file on Moonraker is not the download's bytes");
      for (const [w, h, file] of [[1280, 800, "send-desktop.png"], [390, 844, "send-phone.png"]]) {
        await page.setViewportSize({ width: w, height: h });
        await page.waitForTimeout(200);
        const box = await page.locator("#send-dialog").boundingBox();
        if (!box || box.x < 0 || box.y < 0 || box.x + box.width > w + 0.5 || box.y + box.height > h + 0.5) throw new Error(`the dialog does not fit ${w}×${h}: ${JSON.stringify(box)}`);
        const scrolls = await page.evaluate(() => { const d = document.getElementById("send-dialog"); return d.scrollWidth > d.clientWidth + 1; });
        if (scrolls) throw new Error(`the dialog scrolls sideways at ${w}×${h}`);
        await page.screenshot({ path: join(outDir, file) });
      }
      await page.setViewportSize({ width: 1280, height: 800 });
      await closeDialog(page);
      return `${name}, ${download.bytes.length} bytes, same sha256 on the host; "${job.status.slice(0, 120)}"`;
    });

    await check(n++, "send: to OctoPrint with “start”: the virtual printer prints it; the dialog shows the job (state, %, file) read from /api/job", async () => {
      need();
      if (!download) throw new Error("no download from the Moonraker check");
      await closeDialog(page);
      const r = await sendVia(page, { kind: "octoprint", url: op.url, key: op.key, start: true });
      if (r.phase !== "uploaded" || !/printing started/.test(r.status)) throw new Error(`the dialog says: ${JSON.stringify(r)}`);
      await page.waitForFunction(() => /^Printing/.test(document.getElementById("send-dialog").dataset.job ?? ""), null, { timeout: 20000 });
      const shown = await page.evaluate(() => document.getElementById("send-status").textContent);
      const job = await host(op.url, "/api/job", { key: op.key });
      if (job.json?.job?.file?.name !== download.name || !/^Printing/.test(job.json?.state ?? "")) throw new Error(`OctoPrint's job: ${JSON.stringify(job.json).slice(0, 300)}`);
      const stored = await host(op.url, `/api/files/local/${encodeURIComponent(download.name)}`, { key: op.key });
      if (stored.json?.size !== download.bytes.length) throw new Error(`OctoPrint holds ${stored.json?.size} bytes, the download ${download.bytes.length}`);
      // The same file again while it prints: OctoPrint refuses to replace it (409).
      const again = await sendVia(page, { kind: "octoprint", url: op.url, key: op.key, start: true });
      const busy = `${new URL(op.url).host} did not take ${download.name}: it is busy (Trying to overwrite file that is currently being printed); wait for the print to end, or send it under another name.`;
      if (again.error !== busy) throw new Error(`sent again while printing: ${JSON.stringify(again)}`);
      await closeDialog(page);
      await host(op.url, "/api/job", { key: op.key, method: "POST", body: { command: "cancel" } });
      return `"${shown.slice(0, 160)}" | "${again.error}"`;
    });

    await check(n++, "send: a wrong key, a closed port and an https page with an http printer each give their one sentence; a Moonraker printer not ready is said when asked to start", async () => {
      need();
      await closeDialog(page);
      const said = [];
      let r = await sendVia(page, { kind: "octoprint", url: op.url, key: "not-the-key", remember: false });
      if (!/refused the API key \(403 .*\): make one in OctoPrint under Settings → Application Keys/.test(r.error)) throw new Error(`OctoPrint, wrong key: ${JSON.stringify(r)}`);
      said.push(r.error);
      r = await sendVia(page, { kind: "moonraker", url: mr.url, key: "not-the-key", remember: false });
      if (!/refused the API key \(401 Unauthorized\): .*trusted_clients/.test(r.error)) throw new Error(`Moonraker, wrong key: ${JSON.stringify(r)}`);
      said.push(r.error);
      r = await sendVia(page, { kind: "moonraker", url: mr.url, key: mr.key, start: true, remember: false });
      await page.waitForFunction(() => !document.getElementById("send-error").hidden, null, { timeout: 10000 });
      r.error = await page.textContent("#send-error");
      if (!/^Uploaded .* but the printer did not start: it is not connected \(Klippy .*\)/.test(r.error)) throw new Error(`Moonraker, start without Klippy: ${JSON.stringify(r)}`);
      said.push(r.error);
      const closed = await freePort();
      r = await sendVia(page, { kind: "moonraker", url: `http://127.0.0.1:${closed}`, remember: false });
      // This page is cross-origin isolated (require-corp): it cannot probe, so both fixes are named.
      if (!r.error.startsWith(`Cannot reach 127.0.0.1:${closed}`)) throw new Error(`closed port: ${JSON.stringify(r)}`);
      said.push(r.error);
      // An https page may not ask an http printer on the network (mixed content); localhost it may.
      const mixed = await page.evaluate(async () => {
        const m = await import("./send-hosts.js");
        return [m.blockedBeforeTrying(m.parseHostUrl("http://192.168.1.20:7125"), "https://weft.example/"), m.blockedBeforeTrying(m.parseHostUrl("localhost:7125"), "https://weft.example/")];
      });
      if (!/^This page is served over https, so the browser blocks an http printer \(mixed content\)/.test(mixed[0] ?? "") || mixed[1] !== null) throw new Error(`mixed content: ${JSON.stringify(mixed)}`);
      said.push(mixed[0]);
      await closeDialog(page);
      return said.map((s) => `"${s}"`).join(" | ");
    });

    await check(n++, "send: Stop during a slow upload to OctoPrint with “start” aborts it at N %: the dialog says nothing was started, and OctoPrint neither prints nor holds the whole file", async () => {
      need();
      if (!download) throw new Error("no download from the Moonraker check");
      await closeDialog(page);
      // OctoPrint idle first (check 2's print is cancelled).
      for (let i = 0; i < 40 && /^(Printing|Cancelling|Pausing)/.test((await host(op.url, "/api/job", { key: op.key })).json?.state ?? ""); i++) await new Promise((r) => setTimeout(r, 250));
      // 24 MiB of G-code in place of the result (the same send path; more than the loopback's
      // socket buffers hold, so the stop comes before the host has it all), on a slow link.
      const size = 24 * 1024 * 1024;
      await page.evaluate((n) => {
        const r = window.weft.result;
        r.realGcode = r.gcode;
        const line = new TextEncoder().encode("G1 X10 Y10 E0.1 ; weft send stop check\n");
        const big = new Uint8Array(n);
        for (let i = 0; i < n; i += line.length) big.set(line.subarray(0, Math.min(line.length, n - i)), i);
        r.gcode = big;
      }, size);
      const cdp = await page.context().newCDPSession(page);
      await cdp.send("Network.enable");
      await cdp.send("Network.emulateNetworkConditions", { offline: false, latency: 20, downloadThroughput: -1, uploadThroughput: 1024 * 1024 });
      try {
        await sendVia(page, { kind: "octoprint", url: op.url, key: op.key, start: true, wait: false });
        await page.waitForFunction(() => document.getElementById("send-bar").value > 0.05, null, { timeout: 60000 });
        await page.click("#send-cancel");
        await page.waitForFunction(() => document.getElementById("send-dialog").dataset.phase === "failed", null, { timeout: 20000 });
      } finally {
        await cdp.send("Network.emulateNetworkConditions", { offline: false, latency: 0, downloadThroughput: -1, uploadThroughput: -1 });
        await cdp.detach();
        await page.evaluate(() => {
          const r = window.weft.result;
          r.gcode = r.realGcode;
          delete r.realGcode;
        });
      }
      const error = await page.textContent("#send-error");
      await closeDialog(page);
      if (!/^The upload stopped at \d+ %: nothing was started on the printer\.$/.test(error)) throw new Error(`the dialog says: ${error}`);
      await new Promise((r) => setTimeout(r, 1000));
      const job = await host(op.url, "/api/job", { key: op.key });
      if (/^Printing/.test(job.json?.state ?? "")) throw new Error(`OctoPrint prints after the stop: ${JSON.stringify(job.json).slice(0, 200)}`);
      const stored = await host(op.url, `/api/files/local/${encodeURIComponent(download.name)}`, { key: op.key });
      if (stored.json?.size === size) throw new Error("OctoPrint holds the whole stopped file");
      return `"${error}"; OctoPrint ${job.json?.state}, ${download.name} ${stored.status === 200 ? `${stored.json?.size} bytes (the earlier one)` : "absent"}`;
    });

    await check(n++, "send: saved hosts are in localStorage only (not the design, the address, a share link or any console line); Forget removes one; a changed design runs before the dialog opens", async () => {
      need();
      await closeDialog(page);
      const saved = await page.evaluate(() => JSON.parse(localStorage.getItem("weft.hosts") ?? "[]"));
      const kinds = saved.map((h) => h.kind).sort().join(",");
      if (kinds !== "moonraker,octoprint") throw new Error(`saved hosts: ${kinds || "none"}`);
      if (saved.find((h) => h.kind === "octoprint").key !== op.key) throw new Error("the OctoPrint key was not saved with its host");
      await page.click("#share");
      await page.waitForFunction(() => location.hash.startsWith("#d="), null, { timeout: 10000 });
      const where = await page.evaluate(() => ({ design: window.weft.design, url: location.href }));
      for (const [what, text] of [["the design", where.design], ["the address (share link)", where.url], ["the console", consoleLines.join("\n")]]) {
        for (const k of [op.key, mr.key].filter(Boolean)) if (text.includes(k)) throw new Error(`a key is in ${what}`);
        if (text.includes(op.url) && what !== "the console") throw new Error(`the host's address is in ${what}`);
      }
      // A changed setting: Send runs the design first (as Download does), then opens.
      const before = await page.evaluate(() => window.weft.resultCount);
      await page.evaluate(() => {
        const input = [...document.querySelectorAll("#schema-fields input[type=number]")].find((i) => /perimeters$/.test(i.dataset.path));
        input.value = String(Number(input.value) + 1);
        input.dispatchEvent(new Event("change", { bubbles: true }));
      });
      await page.click("#send");
      await waitResult(page, before, "the run Send starts for a changed design", jobTimeout);
      await page.waitForSelector("#send-dialog[open]", { timeout: 10000 });
      const options = await page.$$eval("#send-saved option", (os) => os.map((o) => o.textContent));
      if (options.some((o) => [op.key, mr.key].filter(Boolean).some((k) => o.includes(k)))) throw new Error("the saved hosts' menu shows a key");
      await page.selectOption("#send-saved", { label: `OctoPrint · ${op.url}` });
      if ((await page.inputValue("#send-key")) !== op.key || (await page.inputValue("#send-url")) !== op.url) throw new Error("picking a saved host did not fill its address and key");
      await page.click("#send-forget");
      const left = await page.evaluate(() => JSON.parse(localStorage.getItem("weft.hosts") ?? "[]").map((h) => h.kind));
      if (left.includes("octoprint")) throw new Error(`Forget left: ${left}`);
      await closeDialog(page);
      return `saved ${kinds}; after Forget: ${left.join(",")}; ${options.length - 1} in the menu before`;
    });

    await check(n++, "send: a page origin Moonraker does not allow (http://localhost) gets the CORS sentence naming that origin and cors_domains (isolated page: with the reach fix too; plain page: the CORS fix alone); a closed port on a plain page is “Cannot reach”", async () => {
      need();
      const said = [];
      const local = `http://localhost:${port}`;
      const isolated = await open();
      try {
        await runExample(isolated.page, local, EXAMPLE, jobTimeout);
        const r = await sendVia(isolated.page, { kind: "moonraker", url: mr.url, key: mr.key, remember: false });
        const h = new URL(mr.url).host;
        const want = `Cannot reach ${h}, or it refuses requests from this page (${local}): check the address and that the printer is on the same network, and add ${local} to Moonraker's [authorization] cors_domains.`;
        if (r.error !== want) throw new Error(`isolated page: ${JSON.stringify(r)}\nwanted: ${want}`);
        said.push(r.error);
      } finally {
        await isolated.context.close();
      }
      // A plain static host (no isolation headers): the page can probe and tells them apart.
      const plain = await serve({ root, isolated: false, pkgDir: process.env.WEFT_PKG_DIR ? resolve(process.env.WEFT_PKG_DIR) : join(root, "pkg") });
      const plainLocal = plain.url.replace("127.0.0.1", "localhost");
      // Without its service worker (sw.js would add the isolation headers and reload once).
      const p = await open({ serviceWorkers: "block" });
      try {
        await runExample(p.page, plainLocal, EXAMPLE, jobTimeout);
        if (await p.page.evaluate(() => self.crossOriginIsolated)) throw new Error("the plain page is isolated");
        const h = new URL(mr.url).host;
        let r = await sendVia(p.page, { kind: "moonraker", url: mr.url, key: mr.key, remember: false });
        const want = `${h} refuses requests from this page (${plainLocal}): add ${plainLocal} to Moonraker's [authorization] cors_domains.`;
        if (r.error !== want) throw new Error(`plain page: ${JSON.stringify(r)}\nwanted: ${want}`);
        said.push(r.error);
        const closed = await freePort();
        r = await sendVia(p.page, { kind: "octoprint", url: `http://127.0.0.1:${closed}`, key: "x", remember: false });
        const wantClosed = `Cannot reach 127.0.0.1:${closed}: check the address and that the printer is on the same network.`;
        if (r.error !== wantClosed) throw new Error(`closed port, plain page: ${JSON.stringify(r)}`);
        said.push(r.error);
      } finally {
        await p.context.close();
        await plain.close();
      }
      if (offOrigin.length) throw new Error(`requests left 127.0.0.1/localhost: ${offOrigin.join(", ")}`);
      return said.map((s) => `"${s}"`).join(" | ");
    });

    await check(n++, "send: the Prusa MK4 profile: Download saves cube-20mm.bgcode with the CLI's bytes for the page's design; Send offers binary G-code first, Moonraker holds it byte for byte, OctoPrint refuses it in one sentence and takes the text format", async () => {
      need();
      const p = await open();
      try {
        await runExample(p.page, baseUrl, EXAMPLE, jobTimeout);
        await p.page.click("#machine > summary");
        const before = await p.page.evaluate(() => window.weft.resultCount);
        await p.page.selectOption("#printer-preset", "prusa-mk4");
        await p.page.click("#slice");
        await waitResult(p.page, before, "run with the Prusa MK4 profile", jobTimeout);
        const dl = await downloadGcode(p.page, join(outDir, "send-mk4.bgcode"));
        if (dl.name !== "cube-20mm.bgcode") throw new Error(`Download saved ${dl.name}`);
        const stats = await p.page.textContent("#stats");
        if (!/Binary G-code\s*[\d.]+ KiB/.test(stats)) throw new Error(`the numbers do not give the .bgcode's size: ${stats.slice(0, 300)}`);
        // The page's design (the profile picked, dated by the edit), run by the CLI.
        const d = JSON.parse(await p.page.evaluate(() => window.weft.design));
        if (d.printer.model !== "MK4" || d.printer.binary_gcode !== true) throw new Error(`the MK4 profile set ${JSON.stringify(d.printer).slice(0, 200)}`);
        let cliText = null;
        if (weftBin) {
          const { execFileSync } = await import("node:child_process");
          const { writeFileSync } = await import("node:fs");
          const designPath = join(outDir, "send-mk4.json");
          writeFileSync(designPath, JSON.stringify(d));
          for (const [file, what] of [["cli-mk4.bgcode", "binary"], ["cli-mk4.gcode", "text"]]) {
            execFileSync(weftBin, ["run", designPath, "-q", "-o", join(outDir, file)]);
            if (what === "binary" && sha256(readFileSync(join(outDir, file))) !== sha256(dl.bytes)) throw new Error("the page's .bgcode differs from weft run DESIGN -o x.bgcode");
          }
          cliText = readFileSync(join(outDir, "cli-mk4.gcode"));
        }
        await p.page.click("#send");
        await p.page.waitForSelector("#send-dialog[open]", { timeout: 10000 });
        const offered = await p.page.evaluate(() => ({ hidden: document.getElementById("send-format-row").hidden, value: document.getElementById("send-format").value, file: document.getElementById("send-file").textContent }));
        if (offered.hidden || offered.value !== "bgcode" || !offered.file.startsWith("cube-20mm.bgcode")) throw new Error(`the dialog offers ${JSON.stringify(offered)}`);
        for (const [w, h, file] of [[1280, 800, "send-mk4-desktop.png"], [390, 844, "send-mk4-phone.png"]]) {
          await p.page.setViewportSize({ width: w, height: h });
          await p.page.waitForTimeout(200);
          await p.page.screenshot({ path: join(outDir, file) });
        }
        await p.page.setViewportSize({ width: 1280, height: 800 });
        await host(mr.url, "/server/files/gcodes/cube-20mm.bgcode", { key: mr.key, method: "DELETE" });
        let r = await sendVia(p.page, { kind: "moonraker", url: mr.url, key: mr.key, remember: false });
        if (r.phase !== "uploaded" || !r.status.startsWith("Uploaded cube-20mm.bgcode to ")) throw new Error(`Moonraker, .bgcode: ${JSON.stringify(r)}`);
        const back = await host(mr.url, "/server/files/gcodes/cube-20mm.bgcode", { key: mr.key });
        if (sha256(back.buf) !== sha256(dl.bytes)) throw new Error("the .bgcode on Moonraker is not the download's bytes");
        r = await sendVia(p.page, { kind: "octoprint", url: op.url, key: op.key, remember: false });
        const refused = `${new URL(op.url).host} does not take cube-20mm.bgcode (415 Could not upload file, invalid type): send the plain G-code instead (Format: G-code).`;
        if (r.error !== refused) throw new Error(`OctoPrint, .bgcode: ${JSON.stringify(r)}`);
        r = await sendVia(p.page, { kind: "octoprint", url: op.url, key: op.key, remember: false, format: "gcode" });
        if (r.phase !== "uploaded" || !r.status.startsWith("Uploaded cube-20mm.gcode to ")) throw new Error(`OctoPrint, text: ${JSON.stringify(r)}`);
        const stored = await host(op.url, "/downloads/files/local/cube-20mm.gcode", { key: op.key });
        if (cliText && sha256(stored.buf) !== sha256(cliText)) throw new Error("the text OctoPrint holds differs from weft run DESIGN -o x.gcode");
        if (!/^; printer_model = MK4$/m.test(stored.buf.toString("utf8"))) throw new Error("the text G-code does not name the MK4");
        if (!/^; thumbnail_QOI begin 480x240 \d+$/m.test(stored.buf.toString("utf8"))) throw new Error("the text G-code has no QOI thumbnail for the MK4's screen");
        return `${dl.bytes.length} B .bgcode (the CLI's bytes: ${cliText ? "yes" : "no CLI"}) on Moonraker; OctoPrint: "${refused}", then the text (${stored.buf.length} B)`;
      } finally {
        await p.context.close();
      }
    });
  } finally {
    await main.context.close();
  }
  return n;
}

/** A loopback port nothing listens on (bound, then freed). */
async function freePort() {
  const { createServer } = await import("node:net");
  const s = createServer();
  await new Promise((r) => s.listen(0, "127.0.0.1", r));
  const { port } = s.address();
  await new Promise((r) => s.close(r));
  return port;
}

// Run by itself: `node tests/e2e/send-checks.mjs` (WEFT_HOSTS as above; WEFT_BIN: the CLI whose bytes the page's must equal).
if (import.meta.url === pathToFileURL(process.argv[1] ?? "").href) {
  const outDir = join(ROOT, "tests/e2e/out");
  const pkgDir = process.env.WEFT_PKG_DIR ? resolve(process.env.WEFT_PKG_DIR) : join(ROOT, "pkg");
  if (!existsSync(join(pkgDir, "weft.js"))) {
    console.log(`FAIL 1. send: no wasm package in ${pkgDir}: build it with scripts/build-www.sh`);
    console.log("0 passed, 1 failed");
    process.exit(1);
  }
  const server = await serve({ root: ROOT, pkgDir });
  const browser = await launchChromium();
  const { results, check } = checker();
  let hosts = null;
  try {
    hosts = hostsFromEnv();
  } catch (err) {
    console.log(`WEFT_HOSTS is not the harness's JSON: ${err.message}`);
  }
  try {
    const weftBin = process.env.WEFT_BIN ? resolve(process.env.WEFT_BIN) : null;
    await sendChecks({ browser, baseUrl: server.url, hosts, check, outDir, first: 1, weftBin: weftBin && existsSync(weftBin) ? weftBin : null });
  } finally {
    await browser.close();
    await server.close();
  }
  const failed = results.filter((r) => !r).length;
  console.log(`${results.length - failed} passed, ${failed} failed`);
  process.exit(failed ? 1 : 0);
}

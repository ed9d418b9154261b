// Send: the result's G-code to a print host (Moonraker/Klipper or OctoPrint) from the page.
// The Send button opens a dialog (host kind, address, API key, start after upload, format);
// Send checks the host with one small request (address, CORS and key problems are said before
// any upload), uploads the same bytes the download would save with a progress bar (XHR
// upload progress; Cancel aborts), then shows the host's job state, read every 2 s for up to
// a minute while the dialog is open. Every failure is one sentence with its fix
// (send-hosts.js). Saved hosts live in localStorage only: never in the design, a share link,
// the address or a log line; the key is sent only as the X-Api-Key header to that host.
import { state } from "./state.js";
import { $, formatBytes } from "./util.js";
import { showNotice } from "./messages.js";
import { invalidFields } from "./form.js";
import { staleReason } from "./results.js";
import { runDesign } from "./actions.js";
import {
  KINDS, blockedBeforeTrying, corsRefused, forgetHost, interrupted, jobLine, jobState, loadHosts, notStarted, parseHostUrl,
  refusal, rememberHost, timedOut, unreachable, unreachableOrCors, uploadOutcome,
} from "./send-hosts.js";

/** Job state reads: every this many ms, for at most JOB_WATCH_MS after the upload. */
const JOB_POLL_MS = 2000;
const JOB_WATCH_MS = 60000;
/** The first small request's time limit, ms. */
const HELLO_MS = 8000;
/** The upload's time limit: a minute, and a second for every 50 KB (a slow board on Wi-Fi). */
const uploadLimitMs = (bytes) => 60000 + bytes / 50;

/**
 * The dialog's own bookkeeping while it is open (this module's private state, like the
 * caches other modules keep): the upload under way, the job watch's turn, where it stands.
 */
const session = { wired: false, xhr: null, check: null, turn: 0, percent: 0, bodyDone: false, busy: false };

/** Send: the result when it matches the design, else the design is run first (as Download). */
export function sendResult() {
  const r = state.result;
  if (!r?.gcode) return;
  if (!staleReason()) {
    openSendDialog();
    return;
  }
  if (invalidFields().length) {
    runDesign(); // says which field to fix
    return;
  }
  runDesign({ then: openSendDialog });
  showNotice("The settings changed since the last run: running the design first; the send dialog opens when it is done.");
}

/**
 * The bytes a format sends, named as the download would name them. `state.result.bgcode` (the
 * hook for the core's Prusa binary G-code: a Uint8Array or ArrayBuffer, absent when the run
 * made none) is what Download saves when present, under `fileName` (then .bgcode); the text
 * G-code goes as .gcode. Without bgcode only the text is offered, under `fileName` as it is.
 */
function payload(format) {
  const r = state.result;
  const stem = r.fileName.replace(/\.[^.]*$/, "");
  if (!r.bgcode?.byteLength) return { name: r.fileName, bytes: r.gcode };
  if (format === "gcode") return { name: /\.bgcode$/i.test(r.fileName) ? `${stem}.gcode` : r.fileName, bytes: r.gcode };
  return { name: /\.bgcode$/i.test(r.fileName) ? r.fileName : `${stem}.bgcode`, bytes: r.bgcode };
}

/** Opens the dialog for the current result, with the last host used filled in. */
export function openSendDialog() {
  const dialog = $("send-dialog");
  if (!state.result?.gcode || dialog.open) return;
  wireOnce();
  // The format the download saves is the one offered first.
  const hasBgcode = Boolean(state.result.bgcode?.byteLength);
  $("send-format-row").hidden = !hasBgcode;
  $("send-format").value = hasBgcode ? "bgcode" : "gcode";
  fillSaved();
  const last = loadHosts()[0];
  if (last && !$("send-url").value) useHost(last);
  else {
    // No host used yet: the printer profile's host kind (`printer.host`) is offered first.
    const kind = state.design?.printer?.host;
    const radio = document.querySelector(`input[name=send-kind][value="${kind}"]`);
    if (radio && !$("send-url").value) radio.checked = true;
    syncKind();
  }
  showFile();
  resetProgress();
  say("", "");
  setBusy(false);
  dialog.showModal();
  ($("send-url").value ? $("send-go") : $("send-url")).focus();
}

/** The dialog's listeners, added on first use. */
function wireOnce() {
  if (session.wired) return;
  session.wired = true;
  const dialog = $("send-dialog");
  $("send-form").addEventListener("submit", (e) => {
    e.preventDefault();
    if (!session.busy) sendNow();
  });
  // While sending, the button (and Escape) stops the check or the upload; otherwise it closes
  // the dialog.
  const stop = () => {
    if (session.xhr) session.xhr.abort();
    else session.check?.abort();
  };
  $("send-cancel").addEventListener("click", () => {
    if (session.busy) stop();
    else dialog.close();
  });
  dialog.addEventListener("cancel", (e) => {
    if (session.busy) {
      e.preventDefault();
      stop();
    }
  });
  dialog.addEventListener("close", () => {
    session.turn++; // the job watch stops
    session.xhr?.abort();
    session.check?.abort();
  });
  for (const r of document.querySelectorAll("input[name=send-kind]")) r.addEventListener("change", syncKind);
  $("send-format").addEventListener("change", showFile);
  $("send-saved").addEventListener("change", () => {
    const h = loadHosts()[Number($("send-saved").value)];
    if (h) useHost(h);
    $("send-forget").disabled = !h;
  });
  $("send-forget").addEventListener("click", () => {
    const h = loadHosts()[Number($("send-saved").value)];
    if (!h) return;
    forgetHost(h);
    fillSaved();
    if (parseHostUrl($("send-url").value).base === h.url) $("send-key").value = "";
    say(`Forgot ${KINDS[h.kind].short} at ${h.url} (and its key) on this browser.`, "");
  });
}

function kind() {
  return document.querySelector("input[name=send-kind]:checked")?.value ?? "moonraker";
}

function syncKind() {
  const k = KINDS[kind()];
  $("send-key-note").textContent = k.keyNeeded ? "needed: OctoPrint → Settings → Application Keys" : "optional: only when this computer is not a trusted client";
  $("send-url").placeholder = `http://192.168.1.20:${k.port}`;
}

function useHost(h) {
  const radio = document.querySelector(`input[name=send-kind][value="${h.kind}"]`);
  if (radio) radio.checked = true;
  $("send-url").value = h.url;
  $("send-key").value = h.key ?? "";
  syncKind();
}

/** The saved hosts' menu (kind and address; never the key). */
function fillSaved() {
  const select = $("send-saved");
  const hosts = loadHosts();
  select.replaceChildren(new Option(hosts.length ? "Saved printers…" : "No saved printers", ""));
  hosts.forEach((h, i) => select.append(new Option(`${KINDS[h.kind].short} · ${h.url}`, String(i))));
  select.disabled = !hosts.length;
  $("send-forget").disabled = true;
}

function showFile() {
  const { name, bytes } = payload($("send-format").value);
  $("send-file").textContent = `${name} · ${formatBytes(bytes.byteLength)}`;
}

function resetProgress() {
  // The job line belongs to the last upload: a new send starts without it.
  $("send-dialog").dataset.job = "";
  $("send-progress").hidden = true;
  $("send-bar").value = 0;
  $("send-progress-text").textContent = "";
}

/** The bar at `loaded` of the request's `total` bytes, said in bytes of the file (`size`). */
function showProgress(loaded, total, size) {
  const f = total ? Math.min(1, loaded / total) : 0;
  session.percent = 100 * f;
  $("send-progress").hidden = false;
  $("send-bar").value = f;
  $("send-progress-text").textContent = `${Math.floor(session.percent)} % · ${formatBytes(Math.round(f * size))} of ${formatBytes(size)}`;
}

/** The dialog's status line and error line (either may be ""). */
function say(status, error, phase = error ? "failed" : "") {
  $("send-dialog").dataset.phase = phase;
  $("send-status").textContent = status;
  $("send-error").textContent = error;
  $("send-error").hidden = !error;
}

function setBusy(busy) {
  session.busy = busy;
  $("send-go").disabled = busy;
  $("send-cancel").textContent = busy ? "Stop" : "Close";
  for (const id of ["send-url", "send-key", "send-start", "send-format", "send-saved", "send-remember"]) $(id).disabled = busy || (id === "send-saved" && !loadHosts().length);
  for (const r of document.querySelectorAll("input[name=send-kind]")) r.disabled = busy;
}

/** A small GET to the host: `{status, json}`; `{status: 0, error}` when no answer may be read. */
async function getJson(base, path, key, stop = null) {
  try {
    const timeout = AbortSignal.timeout(HELLO_MS);
    const res = await fetch(`${base}${path}`, {
      headers: key ? { "X-Api-Key": key } : {}, cache: "no-store", credentials: "omit", signal: stop ? AbortSignal.any([timeout, stop]) : timeout,
    });
    const text = await res.text();
    let json = null;
    try {
      json = JSON.parse(text);
    } catch { /* not JSON: the status says enough */ }
    return { status: res.status, text, json };
  } catch (err) {
    return { status: 0, error: stop?.aborted ? "abort" : err?.name === "TimeoutError" ? "timeout" : "network" };
  }
}

/**
 * Why a request got no answer the page may read: nothing answers at the address, or the host
 * answers but not to this page's origin (CORS). A `no-cors` request tells them apart; a page
 * whose embedder policy is require-corp (cross-origin isolated for the worker's threads) may not
 * make one, so there the sentence names both fixes.
 */
async function whyNoAnswer(k, parsed) {
  const origin = location.origin;
  if (!(await mayProbe())) return unreachableOrCors(k, parsed.host, origin);
  try {
    await fetch(`${parsed.base}/`, { mode: "no-cors", cache: "no-store", credentials: "omit", signal: AbortSignal.timeout(5000) });
    return corsRefused(k, parsed.host, origin);
  } catch {
    return unreachable(parsed.host);
  }
}

/** Whether a no-cors request to another origin can succeed here (not isolated, or COEP credentialless). */
async function mayProbe() {
  if (!self.crossOriginIsolated) return true;
  try {
    const res = await fetch(location.href, { method: "HEAD", cache: "no-store" });
    return /credentialless/i.test(res.headers.get("cross-origin-embedder-policy") ?? "");
  } catch {
    return false;
  }
}

/** The job state now, or null when it cannot be read. */
async function readJob(k, base, key) {
  if (k === "moonraker") {
    const info = await getJson(base, "/server/info", key);
    if (info.status !== 200) return null;
    if (info.json?.result?.klippy_state !== "ready") {
      const printer = info.json?.result?.klippy_connected ? await getJson(base, "/printer/info", key) : null;
      return jobState(k, info.json, null, printer?.status === 200 ? printer.json : null);
    }
    const q = await getJson(base, "/printer/objects/query?print_stats&virtual_sdcard", key);
    return jobState(k, info.json, q.status === 200 ? q.json : null);
  }
  const job = await getJson(base, "/api/job", key);
  return job.status === 200 ? jobState(k, job.json) : null;
}

/**
 * After a stopped upload that asked for a print: the sentence when the host is printing `name`
 * all the same (it had the whole file before the stop), else null.
 */
async function printingNow(k, parsed, key, name) {
  await new Promise((r) => setTimeout(r, 1500));
  const job = await readJob(k, parsed.base, key);
  if (!job?.connected || job.file !== name || !/^print/i.test(job.state)) return null;
  return `The upload was stopped, but ${parsed.host} had the whole of ${name} already and is printing it: stop the print on the printer if you did not mean it.`;
}

/** Uploads `bytes` as `name`: resolves `{status, text}` or `{status: 0, error}` (network, abort, timeout). */
function upload(k, base, key, start, name, bytes) {
  return new Promise((resolve) => {
    const form = new FormData();
    if (k === "octoprint") {
      form.append("select", "true");
      form.append("print", start ? "true" : "false");
    } else if (start) {
      form.append("print", "true");
    }
    form.append("file", new Blob([bytes], { type: "application/octet-stream" }), name);
    const xhr = new XMLHttpRequest();
    session.xhr = xhr;
    session.percent = 0;
    session.bodyDone = false;
    xhr.open("POST", `${base}${KINDS[k].upload}`);
    if (key) xhr.setRequestHeader("X-Api-Key", key);
    xhr.timeout = uploadLimitMs(bytes.byteLength);
    xhr.upload.onprogress = (e) => { if (e.lengthComputable) showProgress(e.loaded, e.total, bytes.byteLength); };
    xhr.upload.onload = () => { session.bodyDone = true; };
    const done = (r) => {
      session.xhr = null;
      resolve(r);
    };
    xhr.onload = () => done({ status: xhr.status, text: xhr.responseText });
    xhr.onerror = () => done({ status: 0, error: "network" });
    xhr.onabort = () => done({ status: 0, error: "abort" });
    xhr.ontimeout = () => done({ status: 0, error: "timeout" });
    xhr.send(form);
  });
}

/** Send: check the host, upload with progress, then watch the job. */
async function sendNow() {
  const k = kind();
  const parsed = parseHostUrl($("send-url").value);
  const key = $("send-key").value.trim();
  const start = $("send-start").checked;
  const { name, bytes } = payload($("send-format").value);
  const turn = ++session.turn; // closing the dialog moves it on: what is under way then stops
  resetProgress();
  if (parsed.error) {
    say("", parsed.error);
    $("send-url").focus();
    return;
  }
  // A key is visible ASCII; anything else cannot go in a header (the browser would throw).
  if (key && !/^[\x21-\x7e]+$/.test(key)) {
    say("", "The API key has a character a key never has (a space, a line break or a non-ASCII letter): paste the key alone, as the host shows it.");
    $("send-key").focus();
    return;
  }
  const blocked = blockedBeforeTrying(parsed, location.href);
  if (blocked) {
    say("", blocked);
    return;
  }
  setBusy(true);
  try {
    say(`Checking ${parsed.host}…`, "", "checking");
    session.check = new AbortController();
    const hello = await getJson(parsed.base, KINDS[k].hello, key, session.check.signal);
    session.check = null;
    if (turn !== session.turn) return;
    if (hello.error === "abort") {
      say("", "Stopped before anything was sent.");
      return;
    }
    if (hello.status === 0) {
      say("", hello.error === "timeout" ? unreachable(parsed.host) : await whyNoAnswer(k, parsed));
      return;
    }
    if (hello.status < 200 || hello.status > 299) {
      say("", refusal(k, { host: parsed.host, status: hello.status, text: hello.text, hadKey: Boolean(key), name, upload: false }));
      return;
    }
    if ($("send-remember").checked) rememberHost({ kind: k, url: parsed.base, key });
    fillSaved();
    $("send-saved").disabled = true; // until the upload is over (setBusy)
    say(`Uploading ${name} to ${parsed.host}…`, "", "uploading");
    showProgress(0, 1, bytes.byteLength);
    const t0 = performance.now();
    const res = await upload(k, parsed.base, key, start, name, bytes);
    const seconds = (performance.now() - t0) / 1000;
    if (turn !== session.turn) return;
    if (res.status === 0) {
      if (res.error === "abort" && session.bodyDone) {
        const printing = start ? await printingNow(k, parsed, key, name) : null;
        if (turn !== session.turn) return;
        say("", printing ?? `The upload was stopped after the whole file had gone: ${parsed.host} may still store it; look at its file list before sending again.`);
      } else if (res.error === "timeout") {
        say("", timedOut(parsed.host));
      } else if (res.error === "network" && session.percent === 0) {
        say("", await whyNoAnswer(k, parsed));
      } else {
        // Bytes already on their way may still make a whole file on the host: when a print
        // was asked for, look before saying that nothing was started.
        const stoppedAt = session.percent;
        const printing = start ? await printingNow(k, parsed, key, name) : null;
        if (turn !== session.turn) return;
        say("", printing ?? interrupted(stoppedAt));
      }
      return;
    }
    if (res.status < 200 || res.status > 299) {
      say("", refusal(k, { host: parsed.host, status: res.status, text: res.text, hadKey: Boolean(key), name, upload: true }));
      return;
    }
    const outcome = uploadOutcome(k, res.text, name);
    const line = `Uploaded ${outcome.name} to ${parsed.host} (${formatBytes(bytes.byteLength)} in ${seconds.toFixed(1)} s)${outcome.started ? "; printing started" : ""}.`;
    say(line, "", "uploaded");
    setBusy(false);
    watchJob(k, parsed, key, line, start && !outcome.started ? outcome : null);
  } finally {
    if (session.busy) setBusy(false);
  }
}

/**
 * Shows the host's job under `line`, read every 2 s for up to a minute or until the dialog
 * closes or sends again; stops once the printer is not connected. `notStartedOutcome`: the
 * file was not started although asked (said with the host's state as the reason).
 */
async function watchJob(k, parsed, key, line, notStartedOutcome) {
  const turn = session.turn;
  const until = Date.now() + JOB_WATCH_MS;
  const dialog = $("send-dialog");
  for (let first = true; ; first = false) {
    if (!first) await new Promise((r) => setTimeout(r, JOB_POLL_MS));
    if (turn !== session.turn || !dialog.open) return;
    const job = await readJob(k, parsed.base, key);
    if (turn !== session.turn || !dialog.open) return;
    const words = job ? (job.connected ? `Printer: ${jobLine(job)}.` : `${jobLine(job).replace(/^p/, "P")}.`) : "The host did not say its job state.";
    $("send-status").textContent = `${line} ${words}`;
    dialog.dataset.job = job ? jobLine(job) : "";
    if (first && notStartedOutcome) say($("send-status").textContent, notStarted(k, parsed.host, notStartedOutcome.name, notStartedOutcome, job), "uploaded");
    if (!job || !job.connected || Date.now() > until) return;
  }
}

// What the page knows of print hosts, without the page: each kind's endpoints and form
// fields, the printer address checked and split, what an answer means (the file stored, a
// print started, the job's state), every failure as one sentence that says what to do, and
// the saved hosts (kept only in localStorage, never in the design, a link or a log). send.js
// does the requests and the dialog; the CLI's src/send.rs says the same things natively.
//
//   Moonraker (Klipper): POST {url}/server/files/upload, multipart `file` (+ print=true);
//                        GET /server/info (is Klippy there?),
//                        GET /printer/objects/query?print_stats&virtual_sdcard (the job).
//   OctoPrint:           POST {url}/api/files/local, multipart `file`, select=true,
//                        print=true|false; GET /api/version, GET /api/job.
// The key goes in the X-Api-Key header (OctoPrint needs one; Moonraker only when the browser's
// machine is not in its [authorization] trusted_clients).

/** Where saved hosts are kept (this browser's localStorage only). */
export const HOSTS_KEY = "weft.hosts";
/** Saved hosts kept at most (the most recently used first). */
const MAX_SAVED = 8;

export const KINDS = {
  moonraker: {
    label: "Moonraker (Klipper)",
    short: "Moonraker",
    port: 7125,
    hello: "/server/info",
    upload: "/server/files/upload",
    keyNeeded: false,
    keyHelp: "give Moonraker's API key (Mainsail or Fluidd: Settings → API key) or add this computer to Moonraker's [authorization] trusted_clients",
    corsFix: (origin) => `add ${origin} to Moonraker's [authorization] cors_domains`,
  },
  octoprint: {
    label: "OctoPrint",
    short: "OctoPrint",
    port: 5000,
    hello: "/api/version",
    upload: "/api/files/local",
    keyNeeded: true,
    keyHelp: "make one in OctoPrint under Settings → Application Keys (or your user's settings → API key) and paste it here",
    corsFix: () => "enable OctoPrint's Settings → API → Allow Cross Origin Resource Sharing (CORS) and restart OctoPrint",
  },
};

/**
 * A printer address checked and split: `{ base, host }` (base without a trailing slash, host
 * as HOST:PORT for messages), or `{ error }`. A bare HOST:PORT is taken as http; no user or
 * password in it (the key has its own field).
 */
export function parseHostUrl(text) {
  const raw = String(text ?? "").trim();
  const bad = { error: `“${raw}” is not a printer address: give it as http://HOST:PORT (e.g. http://192.168.1.20:7125 for Moonraker, http://192.168.1.20:5000 for OctoPrint).` };
  if (!raw) return { error: "Give the printer's address, as http://HOST:PORT (e.g. http://192.168.1.20:7125)." };
  const withScheme = /^[a-z][a-z0-9+.-]*:\/\//i.test(raw) ? raw : `http://${raw}`;
  let u;
  try {
    u = new URL(withScheme);
  } catch {
    return bad;
  }
  if (!/^https?:$/.test(u.protocol) || !u.hostname || u.username || u.password || u.search || u.hash) return bad;
  const path = u.pathname.replace(/\/+$/, "");
  return { base: `${u.protocol}//${u.host}${path}`, host: u.host, https: u.protocol === "https:", hostname: u.hostname };
}

/** Whether a host name is this machine (http to it is allowed from an https page). */
export function isLoopback(hostname) {
  const h = String(hostname).replace(/^\[|\]$/g, "").toLowerCase();
  return h === "localhost" || h.endsWith(".localhost") || /^127\./.test(h) || h === "::1";
}

/**
 * The sentence for a request the page may not make, before trying (null when it may): an
 * http printer from an https page is blocked by the browser (mixed content).
 */
export function blockedBeforeTrying(parsed, pageUrl) {
  const page = new URL(pageUrl);
  if (page.protocol === "https:" && !parsed.https && !isLoopback(parsed.hostname)) {
    return "This page is served over https, so the browser blocks an http printer (mixed content): open weft from http://localhost (scripts/serve.sh) or download the file.";
  }
  return null;
}

/** Sentences of a request that got no answer the page may read. */
export const unreachable = (host) => `Cannot reach ${host}: check the address and that the printer is on the same network.`;
export const corsRefused = (kind, host, origin) => `${host} refuses requests from this page (${origin}): ${KINDS[kind].corsFix(origin)}.`;
/** When the page cannot tell the two apart (a cross-origin isolated page cannot probe). */
export const unreachableOrCors = (kind, host, origin) =>
  `Cannot reach ${host}, or it refuses requests from this page (${origin}): check the address and that the printer is on the same network, and ${KINDS[kind].corsFix(origin)}.`;
export const interrupted = (percent) => `The upload stopped at ${Math.floor(percent)} %: nothing was started on the printer.`;
export const timedOut = (host) => `${host} stopped answering: check that the printer is on, then send again; nothing was started.`;

/** The host's own words in an error answer (Moonraker's error.message, OctoPrint's error), short. */
export function hostWords(text, status = 0) {
  let words = "";
  try {
    const v = JSON.parse(text);
    const e = v?.error;
    words = typeof e === "string" ? e : typeof e?.message === "string" ? e.message : typeof v?.message === "string" ? v.message : "";
  } catch {
    const title = /<title>([^<]*)<\/title>/i.exec(text ?? "");
    words = title ? title[1] : String(text ?? "").split("\n").find((l) => l.trim()) ?? "";
  }
  words = words.trim().replace(new RegExp(`^${status}\\s+`), "");
  // The first sentence is enough ("You don't have the permission … server." is two).
  const dot = words.indexOf(". ");
  words = (dot >= 0 ? words.slice(0, dot) : words.replace(/\.$/, "")).slice(0, 160);
  const reasons = { 400: "Bad Request", 401: "Unauthorized", 403: "Forbidden", 404: "Not Found", 409: "Conflict", 415: "Unsupported Media Type" };
  return words || reasons[status] || "";
}

/**
 * The sentence for an answer that is not a success: of the first small request (`upload`
 * false) or of the upload. `hadKey`: a key was sent.
 */
export function refusal(kind, { host, status, text, hadKey, name, upload }) {
  const k = KINDS[kind];
  const words = hostWords(text, status);
  const lower = words.toLowerCase();
  const busy = /in use|being printed|upload not permitted/.test(lower);
  if ((status === 403 || status === 409) && busy) {
    return `${host} did not take ${name}: it is busy (${words}); wait for the print to end, or send it under another name.`;
  }
  // OctoPrint answers 400 "CSRF validation failed" to an upload that brought no valid key.
  if (status === 401 || status === 403 || (status === 400 && lower.includes("csrf"))) {
    return hadKey
      ? `${host} refused the API key (${status} ${words}): ${k.keyHelp}.`
      : `${host} needs an API key (${status} ${words}): ${k.keyHelp}.`;
  }
  if (status === 409) return `${host} did not take ${name}: it is busy (${words}); wait for the print to end, or send it under another name.`;
  if (status === 415) return `${host} does not take ${name} (${status} ${words}): send the plain G-code instead (Format: G-code).`;
  if (status === 404 || status === 405) {
    return `${host} does not answer as ${k.short} (${upload ? k.upload : k.hello}: ${status} ${words}): check the port and the host kind (Moonraker listens on 7125, OctoPrint on 80 or 5000).`;
  }
  return `${host} answered ${status}${words ? ` (${words})` : ""}: nothing was started; the host's log says more.`;
}

/** What an upload's answer says: `{ name, started, queued, known }` (known: it speaks of printing). */
export function uploadOutcome(kind, text, fallbackName) {
  let v = {};
  try {
    v = JSON.parse(text) ?? {};
  } catch { /* an empty or odd body: the file's own name */ }
  if (kind === "moonraker") {
    const item = v.item ?? v.result?.item;
    return { name: item?.path ?? fallbackName, started: v.print_started === true, queued: v.print_queued === true, known: "print_started" in v };
  }
  return { name: v.files?.local?.path ?? fallbackName, started: v.effectivePrint === true, queued: false, known: "effectivePrint" in v };
}

/** The sentence for a file uploaded but not started although asked. */
export function notStarted(kind, host, name, outcome, job) {
  const head = `Uploaded ${name} to ${host}, but the printer did not start`;
  if (kind === "moonraker" && !outcome.known) return `${head}: Moonraker starts only plain G-code files (.gcode); send the G-code (Format: G-code) to print it.`;
  let why;
  if (outcome.queued) why = "busy (Moonraker queued the file: it starts when the printer is free)";
  else if (job && !job.connected) why = `not connected (${job.state})`;
  // Refused while a job was ending: the printer is idle by the time it is asked.
  else if (job && /^(Operational|standby|complete|cancelled)$/.test(job.state)) why = `busy when asked (it is ${job.state} now)`;
  else if (job) why = `busy (${job.state})`;
  else why = "busy or not connected (the host did not say which)";
  return `${head}: it is ${why}; start it from the host's page once the printer is ready.`;
}

/**
 * The job state from the host's answers: `{ connected, state, percent, file }`.
 * Moonraker: `info` is /server/info's JSON, `query` the objects query's (null when Klippy is
 * away), `printer` /printer/info's (its state_message says why a printer is not ready);
 * OctoPrint: `info` is /api/job's JSON.
 */
export function jobState(kind, info, query = null, printer = null) {
  if (kind === "moonraker") {
    const klippy = info?.result?.klippy_state ?? "unknown";
    if (klippy !== "ready" || !query) {
      const why = String(printer?.result?.state_message ?? "").split("\n").map((l) => l.trim()).find(Boolean)?.replace(/\.$/, "");
      const state = `Klippy ${klippy === "ready" ? "not connected" : klippy}${why ? `: ${why}` : ""}`;
      return { connected: false, state, percent: null, file: null };
    }
    const s = query?.result?.status ?? {};
    const file = s.print_stats?.filename || null;
    const p = s.virtual_sdcard?.progress;
    return { connected: true, state: s.print_stats?.state ?? "unknown", percent: file && typeof p === "number" ? p * 100 : null, file };
  }
  const state = info?.state ?? "unknown";
  const c = info?.progress?.completion;
  return {
    connected: !/^(Offline|Closed)/.test(state) && state !== "unknown",
    state,
    percent: typeof c === "number" ? c : null,
    file: info?.job?.file?.name ?? null,
  };
}

/** A job state in words: "Printing · 12 % · cube.gcode", or "printer not connected (Klippy disconnected)". */
export function jobLine(job) {
  if (!job.connected) return `printer not connected (${job.state})`;
  return [job.state, job.percent === null ? null : `${Math.floor(job.percent)} %`, job.file].filter((x) => x !== null && x !== "").join(" · ");
}

/** Whether a job state is over (no more polling needed): idle, done, or not connected. */
export function jobSettled(job) {
  return !job.connected || !/^(printing|paused|starting|Printing|Paused|Starting|Pausing|Resuming|Cancelling|Finishing|Sending file to SD)/.test(job.state);
}

// ---------------------------------------------------------------------------------------
// Saved hosts: [{kind, url, key}] in localStorage only
// ---------------------------------------------------------------------------------------
/** The saved hosts (the most recently used first); [] when storage is off or unreadable. */
export function loadHosts(storage = globalThis.localStorage) {
  try {
    const list = JSON.parse(storage?.getItem(HOSTS_KEY) ?? "[]");
    return Array.isArray(list) ? list.filter((h) => h && KINDS[h.kind] && typeof h.url === "string").map((h) => ({ kind: h.kind, url: h.url, key: typeof h.key === "string" ? h.key : "" })) : [];
  } catch {
    return [];
  }
}

/** Saves `host` first (replacing the same kind and address); false when storage is off. */
export function rememberHost(host, storage = globalThis.localStorage) {
  const rest = loadHosts(storage).filter((h) => !(h.kind === host.kind && h.url === host.url));
  return writeHosts([{ kind: host.kind, url: host.url, key: host.key ?? "" }, ...rest].slice(0, MAX_SAVED), storage);
}

/** Forgets the saved host of this kind and address (its key with it). */
export function forgetHost(host, storage = globalThis.localStorage) {
  return writeHosts(loadHosts(storage).filter((h) => !(h.kind === host.kind && h.url === host.url)), storage);
}

function writeHosts(list, storage) {
  try {
    if (list.length) storage.setItem(HOSTS_KEY, JSON.stringify(list));
    else storage.removeItem(HOSTS_KEY);
    return true;
  } catch {
    return false; // storage disabled: the host lasts this visit
  }
}

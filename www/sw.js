// Service worker: keeps the app shell, the wasm packages and three.js so the page works
// offline once it has been opened. Network first (a rebuilt page is seen at once), the cache
// when the network fails. Only same-origin GETs are handled (Send's requests to a print host
// go past it, straight to the host).
//
// It also makes the page cross-origin isolated where the host cannot send the headers (a
// plain static host, or offline from the cache): every response it serves carries COOP
// same-origin and COEP require-corp, so the worker may share memory with its thread pool
// (main.js reloads once when this worker first takes control). Everything the page loads is
// same-origin, so require-corp blocks nothing.
const CACHE = "weft-v6";
const SHELL = [
  "./", "index.html", "style.css", "main.js", "worker.js", "pool-worker.js", "protocol.js",
  // main.js's modules (see its header)
  "state.js", "util.js", "messages.js", "design.js", "form.js", "slots.js", "view-cards.js",
  "worker-client.js", "results.js", "actions.js", "send.js", "send-hosts.js",
  "preview.js", "preview-gl.js", "preview-colors.js", "preview-camera.js",
  "plot.js", "report.js", "views.js", "steps.js", "embed.js", "embed.html", "embed-open.js",
  "pictures.js", "picture-caption.js", "picture-draw.js", "compare.js",
  "vendor/three.module.js", "vendor/three.core.js", "vendor/OrbitControls.js",
  "examples/index.json", "../pkg/weft.js", "../pkg/weft_bg.wasm",
  "../pkg/threads/weft.js", "../pkg/threads/weft_bg.wasm",
];

/** `res` with the cross-origin isolation headers (an opaque or error response as it is). */
function isolated(res) {
  if (!res || res.type === "opaque" || res.status === 0) return res;
  const headers = new Headers(res.headers);
  headers.set("Cross-Origin-Opener-Policy", "same-origin");
  headers.set("Cross-Origin-Embedder-Policy", "require-corp");
  headers.set("Cross-Origin-Resource-Policy", "same-origin");
  return new Response(res.body, { status: res.status, statusText: res.statusText, headers });
}

self.addEventListener("install", (event) => {
  event.waitUntil((async () => {
    const cache = await caches.open(CACHE);
    // One missing file (e.g. no examples built) must not stop the others being cached.
    await Promise.all(SHELL.map((url) => cache.add(url).catch(() => {})));
    await self.skipWaiting();
  })());
});

self.addEventListener("activate", (event) => {
  event.waitUntil((async () => {
    for (const key of await caches.keys()) if (key !== CACHE) await caches.delete(key);
    await self.clients.claim();
  })());
});

self.addEventListener("fetch", (event) => {
  const req = event.request;
  if (req.method !== "GET" || new URL(req.url).origin !== self.location.origin) return;
  event.respondWith((async () => {
    const cache = await caches.open(CACHE);
    try {
      const res = await fetch(req);
      if (res.ok && res.type === "basic") cache.put(req, res.clone()).catch(() => {});
      return isolated(res);
    } catch (err) {
      const hit = await cache.match(req, { ignoreSearch: true });
      if (hit) return isolated(hit);
      throw err;
    }
  })());
});

// Service worker: keeps the app shell, the wasm package and three.js so the page works
// offline once it has been opened. Network first (a rebuilt page is seen at once), the cache
// when the network fails. Only same-origin GETs are handled; nothing leaves the origin.
const CACHE = "weft-v2";
const SHELL = [
  "./", "index.html", "style.css", "main.js", "worker.js", "protocol.js", "preview.js",
  "plot.js", "report.js", "views.js",
  "vendor/three.module.js", "vendor/three.core.js", "vendor/OrbitControls.js",
  "examples/index.json", "../pkg/weft.js", "../pkg/weft_bg.wasm",
];

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
      return res;
    } catch (err) {
      const hit = await cache.match(req, { ignoreSearch: true });
      if (hit) return hit;
      throw err;
    }
  })());
});

// Static file server for the browser tests and benchmarks: serves the repository root on
// 127.0.0.1 (localhost only) at a free port, with the MIME types the page needs (module
// scripts, application/wasm for streaming compilation) and no caching.
//
//   import { serve } from "./server.mjs";
//   const { url, close } = await serve();            // url = "http://127.0.0.1:<port>"
//   const { url, close } = await serve({ pkgDir });  // serve another directory as /pkg/
import { createServer } from "node:http";
import { createReadStream, statSync } from "node:fs";
import { dirname, extname, join, resolve, sep } from "node:path";
import { fileURLToPath } from "node:url";

/** The repository root (two levels above this file). */
export const ROOT = resolve(dirname(fileURLToPath(import.meta.url)), "../..");

/** Content types by file extension. */
export const MIME = {
  ".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
  ".mjs": "text/javascript; charset=utf-8", ".css": "text/css; charset=utf-8",
  ".json": "application/json; charset=utf-8", ".wasm": "application/wasm",
  ".png": "image/png", ".svg": "image/svg+xml", ".txt": "text/plain; charset=utf-8",
  ".stl": "model/stl", ".obj": "text/plain; charset=utf-8", ".3mf": "application/octet-stream",
  ".gcode": "text/plain; charset=utf-8", ".ts": "text/plain; charset=utf-8",
};

/** The headers that make a page cross-origin isolated (as scripts/serve.py sends them). */
export const ISOLATION = {
  "cross-origin-opener-policy": "same-origin",
  "cross-origin-embedder-policy": "require-corp",
  "cross-origin-resource-policy": "same-origin",
};

/**
 * Starts the server. Options: `root` (default the repository root), `pkgDir` (served as
 * `/pkg/`, default `<root>/pkg`), `isolated` (default true: the ISOLATION headers, as
 * scripts/serve.py; false: a plain static host). Resolves to `{ url, close, server }`;
 * `close()` returns a promise that settles when the server has stopped.
 */
export function serve({ root = ROOT, pkgDir = join(root, "pkg"), isolated = true } = {}) {
  const server = createServer((req, res) => {
    let path = decodeURIComponent(new URL(req.url, "http://localhost").pathname);
    let base = root;
    if (path.startsWith("/pkg/")) {
      base = pkgDir;
      path = path.slice(4);
    }
    let file = resolve(join(base, path));
    if (file !== base && !file.startsWith(base + sep)) {
      res.writeHead(403).end("forbidden");
      return;
    }
    try {
      if (statSync(file).isDirectory()) file = join(file, "index.html");
      const size = statSync(file).size;
      res.writeHead(200, {
        "content-type": MIME[extname(file)] ?? "application/octet-stream",
        "content-length": size,
        "cache-control": "no-store",
        ...(isolated ? ISOLATION : {}),
      });
      createReadStream(file).pipe(res);
    } catch {
      res.writeHead(404, { "content-type": "text/plain" }).end("not found");
    }
  });
  return new Promise((ok, fail) => {
    server.once("error", fail);
    server.listen(0, "127.0.0.1", () => {
      const url = `http://127.0.0.1:${server.address().port}`;
      const close = () => new Promise((done) => server.close(() => done()));
      ok({ url, close, server });
    });
  });
}

#!/usr/bin/env python3
"""Serves the weft page, and only the page, on 127.0.0.1 (python3 standard library only).

    /                  www/index.html
    /<file>            www/<file>   (main.js, worker.js, sw.js, style.css, vendor/…, examples/…)
    /pkg/<file>        pkg/<file>   (weft.js, weft_bg.wasm: the page loads ../pkg/weft.js,
                                     which from / is /pkg/weft.js)
    anything else      404          (the repository, .git, Cargo.toml, src/ are never served)

Paths are decoded once; a segment that is empty, `.`, `..`, hidden (`.git`) or holds a
backslash or NUL is refused before the file system is asked, and the file found must lie
inside www/ or pkg/. Files are sent with their MIME type (application/wasm, text/javascript
for module scripts), `Cache-Control: no-cache` (a rebuilt page is seen at once) and the
cross-origin isolation headers (COOP same-origin, COEP require-corp) that let the worker run
the threaded module.

Usage: scripts/serve.py [--port PORT] [--root DIR]
PORT defaults to $PORT or 8080 (0: any free port); DIR is the repository (default: this
script's parent folder). The first line printed is "serving http://127.0.0.1:PORT/".
"""

import argparse
import os
import posixpath
import sys
import urllib.parse
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

MIME = {
    ".html": "text/html; charset=utf-8",
    ".js": "text/javascript; charset=utf-8",
    ".mjs": "text/javascript; charset=utf-8",
    ".css": "text/css; charset=utf-8",
    ".json": "application/json; charset=utf-8",
    ".wasm": "application/wasm",
    ".png": "image/png",
    ".svg": "image/svg+xml",
    ".ico": "image/x-icon",
    ".txt": "text/plain; charset=utf-8",
}


def resolve(root, url_path):
    """The file the URL path names, or None (served as 404)."""
    path = urllib.parse.unquote(url_path.split("?", 1)[0].split("#", 1)[0], errors="strict")
    if not path.startswith("/"):
        return None
    if path == "/":
        path = "/index.html"
    parts = path[1:].split("/")
    if parts[0] == "pkg":
        base, parts = os.path.join(root, "pkg"), parts[1:]
    else:
        base = os.path.join(root, "www")
    if not parts or any(p in ("", ".", "..") or p.startswith(".") or "\\" in p or "\0" in p for p in parts):
        return None
    base = os.path.realpath(base)
    file = os.path.realpath(os.path.join(base, *parts))
    if os.path.commonpath([base, file]) != base or not os.path.isfile(file):
        return None
    return file


class Handler(BaseHTTPRequestHandler):
    root = "."
    server_version = "weft"
    sys_version = ""

    def send_file(self, body):
        try:
            file = resolve(self.root, self.path)
        except (UnicodeDecodeError, ValueError):
            file = None
        if file is None:
            data = b"not found\n"
            self.send_response(404)
            self.send_header("Content-Type", "text/plain; charset=utf-8")
            self.send_header("Content-Length", str(len(data)))
            self.end_headers()
            if body:
                self.wfile.write(data)
            return
        with open(file, "rb") as f:
            data = f.read()
        self.send_response(200)
        self.send_header("Content-Type", MIME.get(posixpath.splitext(file)[1].lower(), "application/octet-stream"))
        self.send_header("Content-Length", str(len(data)))
        self.send_header("Cache-Control", "no-cache")
        self.send_header("X-Content-Type-Options", "nosniff")
        # Cross-origin isolation: the page's worker may then share memory with its thread pool
        # (pkg/threads/). Everything is same-origin, so require-corp blocks nothing.
        self.send_header("Cross-Origin-Opener-Policy", "same-origin")
        self.send_header("Cross-Origin-Embedder-Policy", "require-corp")
        self.send_header("Cross-Origin-Resource-Policy", "same-origin")
        self.end_headers()
        if body:
            self.wfile.write(data)

    def do_GET(self):
        self.send_file(True)

    def do_HEAD(self):
        self.send_file(False)

    def log_message(self, fmt, *args):
        if os.environ.get("WEFT_SERVE_LOG"):
            sys.stderr.write("%s %s\n" % (self.address_string(), fmt % args))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description="Serve the weft page on 127.0.0.1.")
    ap.add_argument("--port", type=int, default=int(os.environ.get("PORT", "8080")))
    ap.add_argument("--root", default=os.path.dirname(here))
    args = ap.parse_args()
    Handler.root = os.path.abspath(args.root)
    server = ThreadingHTTPServer(("127.0.0.1", args.port), Handler)
    print("serving http://127.0.0.1:%d/" % server.server_address[1], flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()


if __name__ == "__main__":
    main()

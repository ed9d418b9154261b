#!/usr/bin/env python3
"""scripts/serve.py serves the page and nothing else (run by scripts/test.sh; needs no build).

Starts the server on a free port over a scratch copy of the layout it serves (www/, pkg/) next
to files it must never serve (.git/HEAD, Cargo.toml, src/lib.rs, a file beside the root), then
asks for each over raw HTTP (no client-side path clean-up) and checks status and MIME type.
"""

import http.client
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SERVE = os.path.join(HERE, "..", "..", "scripts", "serve.py")


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)


def main():
    with tempfile.TemporaryDirectory() as outer:
        root = os.path.join(outer, "repo")
        write(os.path.join(root, "www", "index.html"), "<!doctype html><title>weft</title>")
        write(os.path.join(root, "www", "main.js"), "import('../pkg/weft.js');")
        write(os.path.join(root, "www", "sw.js"), "// sw")
        write(os.path.join(root, "www", "examples", "index.json"), "[]")
        write(os.path.join(root, "www", ".hidden"), "secret")
        write(os.path.join(root, "pkg", "weft.js"), "export default 1;")
        write(os.path.join(root, "pkg", "weft_bg.wasm"), "\0asm")
        write(os.path.join(root, ".git", "HEAD"), "ref: refs/heads/main")
        write(os.path.join(root, "Cargo.toml"), "[package]")
        write(os.path.join(root, "src", "lib.rs"), "//! secret")
        write(os.path.join(outer, "outside.txt"), "secret")

        proc = subprocess.Popen([sys.executable, SERVE, "--port", "0", "--root", root], stdout=subprocess.PIPE, text=True)
        try:
            line = proc.stdout.readline().strip()
            assert line.startswith("serving http://127.0.0.1:"), line
            port = int(line.rsplit(":", 1)[1].strip("/"))

            def get(path, method="GET"):
                c = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
                c.putrequest(method, path, skip_host=False, skip_accept_encoding=True)
                c.endheaders()
                r = c.getresponse()
                body = r.read()
                c.close()
                return r.status, r.getheader("Content-Type", ""), body, r

            failures = []

            def expect(path, status, mime=None, method="GET"):
                got, ctype, body, _ = get(path, method)
                if got != status or (mime and not ctype.startswith(mime)) or (status == 404 and b"secret" in body):
                    failures.append(f"{method} {path}: {got} {ctype!r}, expected {status} {mime or ''}")

            expect("/", 200, "text/html")
            expect("/index.html", 200, "text/html")
            expect("/main.js", 200, "text/javascript")
            expect("/sw.js", 200, "text/javascript")
            expect("/examples/index.json", 200, "application/json")
            expect("/pkg/weft.js", 200, "text/javascript")
            expect("/pkg/weft_bg.wasm", 200, "application/wasm")
            expect("/pkg/weft.js", 200, "text/javascript", method="HEAD")
            expect("/main.js?v=2", 200, "text/javascript")
            for path in [
                "/.git/HEAD", "/Cargo.toml", "/src/lib.rs", "/www/index.html", "/pkg/", "/pkg", "/examples/",
                "/.hidden", "/%2ehidden",
                "/../", "/../Cargo.toml", "/../outside.txt", "/../../outside.txt", "/pkg/../Cargo.toml",
                "/pkg/../../Cargo.toml", "/pkg/../.git/HEAD", "/%2e%2e/Cargo.toml", "/%2E%2E/%2E%2E/outside.txt",
                "/pkg/%2e%2e/Cargo.toml", "/pkg/%2e%2e/src/lib.rs", "/..%2fCargo.toml", "/pkg/..%2f..%2fCargo.toml",
                "/%2e%2e%2f.git%2fHEAD", "/..%5cCargo.toml", "/pkg/..\\Cargo.toml", "/%00", "/index.html%00.js",
                "//etc/passwd", "/%2fetc%2fpasswd", "/%252e%252e/Cargo.toml", "/%ff", "/nonexistent.js",
            ]:
                expect(path, 404)
            # Cross-origin isolation, so the worker may run the threaded module.
            for path in ["/", "/main.js", "/pkg/weft_bg.wasm"]:
                _, _, _, r = get(path)
                for name, value in [("Cross-Origin-Opener-Policy", "same-origin"),
                                    ("Cross-Origin-Embedder-Policy", "require-corp")]:
                    if r.getheader(name) != value:
                        failures.append(f"GET {path}: {name} is {r.getheader(name)!r}, expected {value!r}")
            if failures:
                print("serve.py check failed:\n  " + "\n  ".join(failures))
                sys.exit(1)
            print("serve.py: the page at /, /pkg/ served, cross-origin isolated; the repository, dot files and .. tricks are 404")
        finally:
            proc.terminate()
            proc.wait(timeout=10)


if __name__ == "__main__":
    main()

#!/usr/bin/env bash
# Builds the wasm core and the page, then serves the page at http://127.0.0.1:${PORT:-8080}/
# (only www/ and pkg/: the rest of the repository is never served; see scripts/serve.py).
# Installs whatever is missing (idempotent): see scripts/build-www.sh. It builds in the same
# wasm target directory (target/www) and pkg/ as scripts/test.sh, and redoes nothing that is
# up to date: serving after testing starts at once.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build-www.sh
PORT="${PORT:-8080}"
echo "weft: Ctrl+C stops the server"
exec python3 scripts/serve.py --port "$PORT"

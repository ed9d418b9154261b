#!/usr/bin/env bash
# Builds the wasm core and the page, then serves the app on http://localhost:${PORT:-8080}/www/
# Installs whatever is missing (idempotent): see scripts/build-www.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build-www.sh
PORT="${PORT:-8080}"
echo "weft: serving on http://localhost:$PORT/www/  (Ctrl+C stops)"
exec python3 -m http.server "$PORT" --bind 127.0.0.1

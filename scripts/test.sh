#!/usr/bin/env bash
# Runs every test: Rust unit + integration tests (with the parser fuzz smoke tests),
# the wasm build, and the browser end-to-end test in headless Chromium.
# Installs whatever is missing (idempotent).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR=never

if [ ! -x /usr/bin/chromium ]; then
  echo "== installing Debian's chromium for the browser test"
  sudo_cmd=""; [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo -n"
  $sudo_cmd apt-get install -y chromium >/dev/null 2>&1 \
    || { $sudo_cmd apt-get update >/dev/null && $sudo_cmd apt-get install -y chromium >/dev/null; }
fi

echo "== serve.py: the page at /, nothing else of the repository"
python3 tests/serve/check.py

# The wasm modules and the page build in the background, in a target directory of their own
# (cargo locks a target directory while it builds), beside the Rust tests: those leave about a
# quarter of two cores idle (one-thread timing sections, short test binaries), which the
# builds' long one-core links fill. Its log is printed when it is waited for.
www_log=$(mktemp)
echo "== wasm + page: building in the background (log below, after the Rust tests)"
# Its own process group (setsid), so a failing test run stops the whole build, cargo included.
CARGO_TARGET_DIR="$PWD/target/www" setsid bash scripts/build-www.sh > "$www_log" 2>&1 &
www_pid=$!
trap 'kill -- -"$www_pid" 2>/dev/null || true; rm -f "$www_log"' EXIT
# Tests and the CLI they drive build without link-time optimisation: each of ~50 test binaries
# links the whole library, and thin LTO redoes that optimisation for every one of them. Output
# is the same bytes either way (the golden hashes and the wasm comparisons check it).
export CARGO_PROFILE_RELEASE_LTO=false
echo "== Rust tests"
cargo test --release 2>&1 | tee /tmp/weft-cargo-test.log
echo "== CLI (release, as the tests built it)"
cargo build --release --bin weft
echo "== wasm + page (built in the background)"
www_ok=0
wait "$www_pid" || www_ok=$?
cat "$www_log"
[ "$www_ok" = 0 ] || { echo "scripts/build-www.sh failed (exit $www_ok)"; exit 1; }
echo "== browser end-to-end (headless Chromium)"
WEFT_BIN="$PWD/target/release/weft" node tests/e2e/run.mjs

#!/usr/bin/env bash
# Runs every test: lint (rustfmt, clippy), Rust unit + integration tests (with the parser fuzz
# smoke tests), the wasm build, and the browser end-to-end test in headless Chromium.
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

echo "== lint: cargo fmt --check (rustfmt.toml)"
for component in rustfmt clippy; do
  rustup component list --installed 2>/dev/null | grep -q "^$component" || rustup component add "$component"
done
cargo fmt --check || { echo "cargo fmt would change the lines above: run cargo fmt"; exit 1; }

echo "== serve.py: the page at /, nothing else of the repository"
python3 tests/serve/check.py

# The wasm modules and the page build in the background, in the wasm's own target directory
# (build-www.sh's <target>/www, the one scripts/serve.sh builds in too: serving after testing
# rebuilds nothing; cargo locks a target directory while it builds), beside the Rust tests:
# those leave about a quarter of two cores idle (one-thread timing sections, short test
# binaries), which the builds' long one-core links fill. Its log is printed when it is waited for.
www_log=$(mktemp)
echo "== wasm + page: building in the background (log below, after the Rust tests)"
# Its own process group (setsid), so a failing test run stops the whole build, cargo included.
setsid bash scripts/build-www.sh > "$www_log" 2>&1 &
www_pid=$!
trap 'kill -- -"$www_pid" 2>/dev/null || true; rm -f "$www_log"' EXIT
# Tests and the CLI they drive build without link-time optimisation (the one test binary,
# tests/it, links the whole library, and thin LTO would redo that optimisation for it). Output
# is the same bytes either way (the golden hashes and the wasm comparisons check it).
export CARGO_PROFILE_RELEASE_LTO=false
echo "== Rust tests (the library's unit tests, the one integration-test binary tests/it, doc tests)"
cargo test --release 2>&1 | tee /tmp/weft-cargo-test.log
echo "== CLI (release, as the tests built it)"
cargo build --release --bin weft
echo "== lint: cargo clippy --all-targets -- -D warnings"
cargo clippy --all-targets -- -D warnings
echo "== wasm + page (built in the background)"
www_ok=0
wait "$www_pid" || www_ok=$?
cat "$www_log"
[ "$www_ok" = 0 ] || { echo "scripts/build-www.sh failed (exit $www_ok)"; exit 1; }
echo "== browser end-to-end (headless Chromium)"
WEFT_BIN="$PWD/target/release/weft" node tests/e2e/run.mjs

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
# Tests and the CLI they drive build without link-time optimisation: each of ~50 test binaries
# links the whole library, and thin LTO redoes that optimisation for every one of them. Output
# is the same bytes either way (the golden hashes and the wasm comparisons check it).
export CARGO_PROFILE_RELEASE_LTO=false
echo "== Rust tests"
cargo test --release 2>&1 | tee /tmp/weft-cargo-test.log
echo "== CLI (release, as the tests built it)"
cargo build --release --bin weft
echo "== wasm + page"
bash scripts/build-www.sh
echo "== browser end-to-end (headless Chromium)"
WEFT_BIN="$PWD/target/release/weft" node tests/e2e/run.mjs

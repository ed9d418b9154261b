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
# rebuilds nothing; cargo locks a target directory while it builds), beside the native build.
# Its log is printed when it is waited for. Each background job has its own process group
# (setsid), so a failure stops the whole job, cargo included.
www_log=$(mktemp)
rust_log=$(mktemp)
e2e_log=$(mktemp)
echo "== wasm + page: building in the background (log below)"
setsid bash scripts/build-www.sh > "$www_log" 2>&1 &
www_pid=$!
rust_pid=""
trap 'kill -- -"$www_pid" 2>/dev/null || true; [ -n "$rust_pid" ] && kill -- -"$rust_pid" 2>/dev/null; rm -f "$www_log" "$rust_log" "$e2e_log"' EXIT
# Tests and the CLI they drive build without link-time optimisation (the one test binary,
# tests/it, links the whole library, and thin LTO would redo that optimisation for it). Output
# is the same bytes either way (the golden hashes and the wasm comparisons check it).
export CARGO_PROFILE_RELEASE_LTO=false
# The library's own unit tests compile the library a second time, with its tests in it. That
# copy is built without optimisation (weft's code only; its dependencies stay optimised): it
# compiles in a fifth of the CPU time (about 25 s against 125 s) and its tests take about 60 s
# of CPU instead of 12, run beside the browser checks instead of in the build everything waits
# for. Same tests, same assertions.
unit_opt=(--config 'profile.release.package.weft.opt-level=0')
echo "== Rust: building tests/it and the CLI (release)"
cargo test --release --no-run --test it
cargo build --release --bin weft
# The Rust tests (about 200 s of CPU), the unit tests (60 s) and clippy (80 s) run in the
# background at a lower priority (nice): the wasm modules and then the browser checks, which
# everything waits for, keep the cores first. Their log is printed after the browser checks.
echo "== Rust tests (tests/it, then the library's unit tests and doc tests) and clippy: running in the background (log below, after the browser checks)"
setsid nice -n 15 bash -c 'set -o pipefail
  cargo test --release --test it || exit 1
  cargo test --release --lib "$@" || exit 1
  cargo test --release --bins || exit 1
  cargo test --release --doc || exit 1
  echo "== lint: cargo clippy --all-targets -- -D warnings"
  cargo clippy --all-targets -- -D warnings' unit-tests "${unit_opt[@]}" > "$rust_log" 2>&1 &
rust_pid=$!
# Real print hosts for Send (tests/hosts/): Moonraker and OctoPrint from PyPI in a venv under
# target/, started on 127.0.0.1 for the browser checks and the CLI's (check_weft.py); they stop
# when this script ends (the trap, and their watchdog watches this shell and a deadline).
echo "== print hosts: Moonraker and OctoPrint from PyPI (target/hosts-venv)"
bash tests/hosts/setup.sh target/hosts-venv
hosts_dir="$PWD/target/hosts-run"
hosts_json="$hosts_dir.json"
rm -rf "$hosts_dir"
trap 'target/hosts-venv/bin/python tests/hosts/hosts.py stop --dir "$hosts_dir" >/dev/null 2>&1 || true; kill -- -"$www_pid" 2>/dev/null || true; [ -n "$rust_pid" ] && kill -- -"$rust_pid" 2>/dev/null; rm -f "$www_log" "$rust_log" "$e2e_log"' EXIT
target/hosts-venv/bin/python tests/hosts/hosts.py start --dir "$hosts_dir" --cors-origin 'http://127.0.0.1:*' --cors-exact \
  --parent-pid $$ --max-minutes 30 > "$hosts_json"
echo "== weft's G-code on the print hosts (weft send, Moonraker's metadata, OctoPrint's virtual printer, .bgcode by libbgcode)"
target/hosts-venv/bin/python tests/hosts/check_weft.py --weft "$PWD/target/release/weft" --hosts "$hosts_json" --out target/hosts-out
echo "== wasm + page (built in the background)"
www_ok=0
wait "$www_pid" || www_ok=$?
cat "$www_log"
[ "$www_ok" = 0 ] || { echo "scripts/build-www.sh failed (exit $www_ok)"; exit 1; }
echo "== browser end-to-end (headless Chromium)"
e2e_ok=0
WEFT_HOSTS="$hosts_json" WEFT_BIN="$PWD/target/release/weft" node tests/e2e/run.mjs 2>&1 | tee "$e2e_log" || e2e_ok=$?
echo "== Rust tests and clippy (ran in the background)"
rust_ok=0
wait "$rust_pid" || rust_ok=$?
rust_pid=""
cat "$rust_log"
cp "$rust_log" /tmp/weft-cargo-test.log 2>/dev/null || true
echo "== summary"
grep '^test result' "$rust_log" || true
[ "$rust_ok" = 0 ] && echo "Rust tests and clippy: passed" || echo "Rust tests or clippy: FAILED (exit $rust_ok; the log above)"
echo "browser: $(tail -n 1 "$e2e_log")"
[ "$rust_ok" = 0 ] && [ "$e2e_ok" = 0 ]

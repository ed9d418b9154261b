#!/usr/bin/env bash
# Benchmarks of BENCHMARKS.md: builds the native CLI and the wasm page, then runs the browser
# worker benchmark and `weft bench` side by side (tests/e2e/bench.mjs), printing Markdown on
# stdout (progress on stderr). Not part of scripts/test.sh: timings depend on the machine.
# Usage: scripts/bench.sh                 (CARGO_TARGET_DIR is honoured; default ./target;
#                                          the wasm builds in its www/, as scripts/build-www.sh)
#        BENCH_TRIANGLES=200000 BENCH_GCODE_MB=20 scripts/bench.sh   (a quick run)
#        BENCH_LATTICE_ONLY=1 scripts/bench.sh   (only the lattice path-optimisation benchmarks)
#        BENCH_SCALING_ONLY=1 scripts/bench.sh   (only the growth benchmark: every `weft bench
#            --scaling` case at 1×, 4×, 16× in a fresh worker each, then natively; one table)
#        BENCH_PAIRING_ONLY=1 scripts/bench.sh   (only exact vs heuristic odd-node pairing:
#            `weft bench --pairing` cases in the worker, then natively; one table)
#        BENCH_GRADED_ONLY=1 scripts/bench.sh    (only the graded job, issue 11: a 182 × 197 ×
#            107 DICOM series loaded + its surface, a 50 MB G-code edited; worker, then
#            `weft bench --graded`; BENCH_GRADED=0 leaves it out of the full run)
# The wasm is built with the cargo feature `bench` (the benchmark exports the worker calls:
# benchMeshStl, benchDesign, benchAnalyze, BenchLattice, benchPairingCases, BenchPairing, benchScalingCases, BenchScaling, BenchGraded) into its own directory, default
# <target dir>/pkg-bench (WEFT_PKG_DIR overrides), which tests/e2e/bench.mjs serves as /pkg/;
# the production ./pkg (scripts/build-www.sh without features) is left as it is.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
target_dir=${CARGO_TARGET_DIR:-$root/target}
say() { printf '[bench] %s\n' "$*" >&2; }

say "cargo build --release --bin weft"
cargo build --release --bin weft >&2
export WEFT_PKG_DIR="${WEFT_PKG_DIR:-$target_dir/pkg-bench}"
say "WEFT_WASM_FEATURES=bench WEFT_PKG_DIR=$WEFT_PKG_DIR scripts/build-www.sh"
WEFT_WASM_FEATURES=bench bash scripts/build-www.sh >&2

say "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'), $(nproc) cores, $(free -g | awk '/^Mem:/{print $2}') GiB RAM; load: $(cut -d' ' -f1-3 /proc/loadavg)"
# The mode variables (BENCH_SCALING_ONLY, BENCH_LATTICE_ONLY, BENCH_CACHE_ONLY, BENCH_REPEATS…)
# reach tests/e2e/bench.mjs through the environment.
[ "${BENCH_SCALING_ONLY:-}" = 1 ] && say "BENCH_SCALING_ONLY=1: growth benchmark only (worker, then weft bench --scaling)"
WEFT_BIN="${WEFT_BIN:-$target_dir/release/weft}" node tests/e2e/bench.mjs

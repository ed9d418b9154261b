#!/usr/bin/env bash
# Builds everything the static page needs, idempotently, installing what is missing:
#   pkg/weft.js + pkg/weft_bg.wasm   (cargo --profile wasm → wasm-bindgen --target web →
#                                     wasm-opt -Oz from the npm package binaryen)
#   pkg/threads/                     (the same with threads: the worker's module when the page
#                                     is cross-origin isolated)
#   www/vendor/                      (three.js module build + OrbitControls, from node_modules)
#   www/examples/                    (examples/*.json + index.json)
# Usage: scripts/build-www.sh            (cargo builds the wasm in <target>/www, <target> being
#                                          $CARGO_TARGET_DIR or ./target: one directory that
#                                          scripts/serve.sh, scripts/test.sh and scripts/bench.sh
#                                          share, apart from the native build's so both can build
#                                          at once; cargo locks a target directory)
#        SKIP_WASM=1 scripts/build-www.sh  (only vendor + examples)
# A module's wasm-bindgen + wasm-opt -Oz (the slow part once cargo has nothing to do) run only
# when their input changed: each output directory keeps a stamp (.build-stamp: the sha256 of
# cargo's weft.wasm, the wasm-bindgen and binaryen versions, the wasm-opt flags, the sha256 of
# the outputs); when it matches, the module is said to be up to date and left as it is.
# Environment (the production build, used by the tests and the served app, sets neither):
#   WEFT_WASM_FEATURES  cargo features of the wasm build, e.g. "bench" (scripts/bench.sh)
#   WEFT_PKG_DIR        output directory of the wasm build instead of ./pkg (the variable
#                       tests/e2e/run.mjs and bench.mjs read to serve it as /pkg/)
#   WEFT_WASM_THREADS   0: no threaded module (pkg/threads/ removed)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
target_dir=${CARGO_TARGET_DIR:-$root/target}/www
bindgen_version=0.2.130
features=${WEFT_WASM_FEATURES:-}
pkg_dir=${WEFT_PKG_DIR:-pkg}
wasm_opt=$root/node_modules/.bin/wasm-opt
say() { printf '[build-www] %s\n' "$*"; }

# --- JS dependencies (three.js, playwright-core, binaryen's wasm-opt) ----------------------
# Every devDependency of package.json must be in node_modules at its pinned version (a
# dependency given as a range only needs to be there); otherwise `npm ci` installs them all.
js_deps_ok() {
  node --input-type=commonjs -e '
    const fs = require("fs");
    const deps = JSON.parse(fs.readFileSync("package.json", "utf8")).devDependencies ?? {};
    for (const [name, spec] of Object.entries(deps)) {
      let have;
      try { have = JSON.parse(fs.readFileSync(`node_modules/${name}/package.json`, "utf8")).version; }
      catch { process.exit(1); }
      if (/^\d+\.\d+\.\d+$/.test(spec) && have !== spec) process.exit(1);
    }' && [ -x "$wasm_opt" ]
}
if ! js_deps_ok; then
  say "installing JS dependencies (npm)"
  if [ -f package-lock.json ]; then npm ci --no-audit --no-fund; else npm install --no-audit --no-fund; fi
fi

# --- wasm --------------------------------------------------------------------------------
gz_bytes() { gzip -9 -c "$1" | wc -c | tr -d ' '; }
raw_bytes() { wc -c < "$1" | tr -d ' '; }
if [ -z "${SKIP_WASM:-}" ]; then
  if ! rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown; then
    say "adding rust target wasm32-unknown-unknown"
    rustup target add wasm32-unknown-unknown
  fi
  export PATH="$HOME/.cargo/bin:$PATH"
  if [ "$(wasm-bindgen --version 2>/dev/null | awk '{print $2}')" != "$bindgen_version" ]; then
    say "installing wasm-bindgen-cli $bindgen_version"
    cargo install wasm-bindgen-cli --version "$bindgen_version"
  fi

  binaryen_version=$(node -p 'require("./node_modules/binaryen/package.json").version')
  # Features rustc enables by default for wasm32-unknown-unknown (bulk memory, saturating
  # float→int, sign extension, mutable globals, multi-value, reference types): wasm-opt must
  # accept every one the module uses. Debian's binaryen is too old for the table.fill that
  # wasm-bindgen emits for reference types, hence the npm build (runs under node), pinned in
  # package.json.
  wasm_opt_flags=(-Oz --enable-bulk-memory --enable-nontrapping-float-to-int --enable-sign-ext
    --enable-mutable-globals --enable-multivalue --enable-reference-types)

  # build_pkg OUT_DIR CARGO_TARGET_DIR FEATURES WASM_OPT_FLAGS… : cargo → wasm-bindgen → wasm-opt.
  build_pkg() {
    local out=$1 tdir=$2 feats=$3
    shift 3
    local feature_args=()
    [ -n "$feats" ] && feature_args=(--features "$feats")
    say "cargo build --lib --profile wasm --target wasm32-unknown-unknown --no-default-features${feats:+ --features $feats}${BUILD_STD:+ $BUILD_STD}"
    # shellcheck disable=SC2086
    CARGO_TARGET_DIR=$tdir cargo build --lib --profile wasm --target wasm32-unknown-unknown \
      --no-default-features "${feature_args[@]}" ${BUILD_STD:-}
    local input=$tdir/wasm32-unknown-unknown/wasm/weft.wasm
    local wasm=$out/weft_bg.wasm stamp=$out/.build-stamp
    # pkg_stamp: what the outputs were made from and what they are. When the stamp holds the
    # same, cargo's module has not changed since this directory was made: nothing to redo.
    pkg_stamp() {
      printf 'input %s\nwasm-bindgen %s --target web --out-name weft\nbinaryen %s\nwasm-opt %s\n' \
        "$(sha256sum < "$input" | cut -d' ' -f1)" "$(wasm-bindgen --version | awk '{print $2}')" \
        "$binaryen_version" "${wasm_opt_flags[*]}${*:+ $*}"
      local f
      for f in weft.js weft_bg.wasm; do
        [ -f "$out/$f" ] || { echo "missing $f"; continue; }
        printf 'output %s %s\n' "$f" "$(sha256sum < "$out/$f" | cut -d' ' -f1)"
      done
    }
    if [ -f "$stamp" ] && [ "$(pkg_stamp "$@")" = "$(cat "$stamp")" ]; then
      say "$out/ up to date (${input#"$root"/} unchanged since it was made: no wasm-bindgen, no wasm-opt)"
      return 0
    fi
    rm -f "$stamp"
    mkdir -p "$out"
    wasm-bindgen --target web --out-dir "$out" --out-name weft "$input"
    local before after
    before="$(raw_bytes "$wasm") B (gzip -9: $(gz_bytes "$wasm") B)"
    # A failure here is an error: the module would ship unoptimised.
    if ! "$wasm_opt" "${wasm_opt_flags[@]}" "$@" -o "$wasm.opt" "$wasm"; then
      rm -f "$wasm.opt"
      say "wasm-opt ($("$wasm_opt" --version 2>/dev/null)) failed on $wasm"
      exit 1
    fi
    mv "$wasm.opt" "$wasm"
    after="$(raw_bytes "$wasm") B (gzip -9: $(gz_bytes "$wasm") B)"
    pkg_stamp "$@" > "$stamp"
    say "$wasm${feats:+ [features: $feats]}: $before before wasm-opt -Oz, $after after" \
      "(binaryen $binaryen_version)"
  }


  # The threaded module (pkg/threads/): rayon's pool on web workers sharing one memory. std
  # must be rebuilt with atomics (-Z build-std, which needs rust-src); RUSTC_BOOTSTRAP lets
  # the machine's stable toolchain take that flag, so both modules are built from the same
  # std source as the CLI and give the same bytes (a nightly's std could sort ties or round
  # differently). Memory may grow to the wasm32 limit of 4 GiB (the plain build's too).
  # WEFT_WASM_THREADS=0 skips it (the page then runs on one thread everywhere).
  if [ "${WEFT_WASM_THREADS:-1}" != 0 ]; then
    if ! rustup component list --installed 2>/dev/null | grep -q '^rust-src'; then
      say "adding rust component rust-src (std's source, for the threaded module)"
      rustup component add rust-src
    fi
    # rustc no longer links shared memory for +atomics by itself: the memory is imported and
    # shared, and the thread-local storage symbols wasm-bindgen's thread start needs exported.
    threads_rustflags="-C target-feature=+atomics,+bulk-memory,+mutable-globals"
    for arg in --shared-memory --import-memory --max-memory=4294967296 --export=__wasm_init_tls \
      --export=__tls_size --export=__tls_align --export=__tls_base; do
      threads_rustflags+=" -C link-arg=$arg"
    done
    # Built beside the plain module (own target dir): each build ends in a long one-core link
    # (fat LTO, one codegen unit) and wasm-opt, so the two overlap on two cores.
    threads_log=$(mktemp)
    (
      RUSTC_BOOTSTRAP=1 CARGO_PROFILE_WASM_PANIC=abort \
        RUSTFLAGS="$threads_rustflags" \
        BUILD_STD="-Z build-std=panic_abort,std" \
        build_pkg "$pkg_dir/threads" "$target_dir/wasm-threads" "wasm-threads${features:+,$features}" --enable-threads
    ) > "$threads_log" 2>&1 &
    threads_pid=$!
  else
    rm -rf "$pkg_dir/threads"
  fi

  # The plain module: one thread, for pages that are not cross-origin isolated (and the page's
  # own main-thread instance).
  BUILD_STD="" build_pkg "$pkg_dir" "$target_dir" "$features"

  if [ -n "${threads_pid:-}" ]; then
    threads_ok=0
    wait "$threads_pid" || threads_ok=$?
    cat "$threads_log"
    rm -f "$threads_log"
    [ "$threads_ok" = 0 ] || { say "the threaded module failed to build"; exit 1; }
  fi
fi

# --- three.js ----------------------------------------------------------------------------
mkdir -p www/vendor
three=node_modules/three
cp "$three/build/three.module.js" "$three/build/three.core.js" www/vendor/
# OrbitControls imports the bare specifier 'three'; point it at the copied module so the
# page needs no import map.
sed "s#from 'three';#from './three.module.js';#" \
  "$three/examples/jsm/controls/OrbitControls.js" > www/vendor/OrbitControls.js
cp "$three/LICENSE" www/vendor/three-LICENSE.txt

# --- example designs ---------------------------------------------------------------------
# index.json lists each example with its job kind and one-line description (from the design)
# and a thumbnail: the example run by the wasm just built (thumbnailSvg), drawn as a small SVG.
# Running every example takes about 20 s (one of them 10 s), so it is redone only when an
# example, the wasm package or this step changed (www/examples/.build-stamp: their sha256).
examples_js=$(cat <<'JS'
import { readdirSync, readFileSync, copyFileSync, writeFileSync, existsSync } from "node:fs";
import { resolve } from "node:path";
import { pathToFileURL } from "node:url";
const pkg = resolve(process.env.WEFT_PKG);
let weft = null;
if (existsSync(`${pkg}/weft.js`) && existsSync(`${pkg}/weft_bg.wasm`)) {
  weft = await import(pathToFileURL(`${pkg}/weft.js`).href);
  weft.initSync({ module: readFileSync(`${pkg}/weft_bg.wasm`) });
}
const files = readdirSync("examples").filter((f) => f.endsWith(".json")).sort();
const index = files.map((file) => {
  const entry = { name: file.replace(/\.json$/, ""), file, kind: "", description: "" };
  let text = "";
  try {
    text = readFileSync(`examples/${file}`, "utf8");
    const d = JSON.parse(text);
    if (d && typeof d.name === "string" && d.name) entry.name = d.name;
    if (typeof d?.description === "string") entry.description = d.description;
    if (typeof d?.job?.kind === "string") entry.kind = d.job.kind;
  } catch { /* not valid JSON: still listed; the page reports the parse error */ }
  copyFileSync(`examples/${file}`, `www/examples/${file}`);
  if (weft) {
    try {
      const thumb = file.replace(/\.json$/, ".svg");
      writeFileSync(`www/examples/${thumb}`, weft.thumbnailSvg(text, 96));
      entry.thumbnail = thumb;
    } catch (err) {
      console.log(`[build-www] no thumbnail for ${file}: ${err.message ?? err}`);
    }
  }
  return entry;
});
writeFileSync("www/examples/index.json", JSON.stringify(index, null, 2) + "\n");
console.log(`[build-www] www/examples: ${index.length} design(s), ${index.filter((e) => e.thumbnail).length} thumbnail(s)`);
JS
)
examples_stamp=$(
  printf '%s\n' "$examples_js" | sha256sum
  for f in "$pkg_dir/weft.js" "$pkg_dir/weft_bg.wasm" examples/*.json; do
    if [ -f "$f" ]; then printf '%s %s\n' "$(sha256sum < "$f" | cut -d' ' -f1)" "$f"; else echo "missing $f"; fi
  done
)
if [ -f www/examples/index.json ] && [ "$examples_stamp" = "$(cat www/examples/.build-stamp 2>/dev/null)" ]; then
  say "www/examples/ up to date (no example and no wasm changed since it was made)"
else
  rm -rf www/examples
  mkdir -p www/examples
  WEFT_PKG="$pkg_dir" node --input-type=module -e "$examples_js"
  printf '%s\n' "$examples_stamp" > www/examples/.build-stamp
fi
say "done"

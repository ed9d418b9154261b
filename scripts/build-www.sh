#!/usr/bin/env bash
# Builds everything the static page needs, idempotently, installing what is missing:
#   pkg/weft.js + pkg/weft_bg.wasm   (cargo --profile wasm → wasm-bindgen --target web → wasm-opt -Oz)
#   www/vendor/                      (three.js module build + OrbitControls, from node_modules)
#   www/examples/                    (examples/*.json + index.json)
# Usage: scripts/build-www.sh            (CARGO_TARGET_DIR is honoured; default ./target)
#        SKIP_WASM=1 scripts/build-www.sh  (only vendor + examples)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
target_dir=${CARGO_TARGET_DIR:-$root/target}
bindgen_version=0.2.130
say() { printf '[build-www] %s\n' "$*"; }

# --- JS dependencies (three.js, playwright-core) -------------------------------------------
if [ ! -d node_modules/three ] || [ ! -d node_modules/playwright-core ]; then
  if [ -f package-lock.json ]; then npm ci --no-audit --no-fund; else npm install --no-audit --no-fund; fi
fi

# --- wasm --------------------------------------------------------------------------------
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
  if ! command -v wasm-opt >/dev/null 2>&1; then
    say "wasm-opt missing; trying apt-get install binaryen"
    sudo_cmd=""; [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1 && sudo_cmd="sudo -n"
    { $sudo_cmd apt-get install -y binaryen >/dev/null 2>&1 \
      || { $sudo_cmd apt-get update >/dev/null 2>&1 && $sudo_cmd apt-get install -y binaryen >/dev/null 2>&1; }; } \
      || say "could not install binaryen; continuing without wasm-opt (bigger wasm)"
  fi

  say "cargo build --lib --profile wasm --target wasm32-unknown-unknown"
  cargo build --lib --profile wasm --target wasm32-unknown-unknown
  mkdir -p pkg
  wasm-bindgen --target web --out-dir pkg --out-name weft \
    "$target_dir/wasm32-unknown-unknown/wasm/weft.wasm"
  if command -v wasm-opt >/dev/null 2>&1; then
    # Features rustc enables by default for wasm32-unknown-unknown (bulk memory, saturating
    # float→int, sign extension, mutable globals, multi-value, reference types): wasm-opt must
    # accept every one the module uses. An old wasm-opt (Debian bookworm's binaryen 108 cannot
    # read the table.fill that wasm-bindgen emits for reference types) fails to parse the
    # module: the unoptimised module is kept then, it works the same, only larger.
    if wasm-opt -Oz --enable-bulk-memory --enable-nontrapping-float-to-int --enable-sign-ext \
      --enable-mutable-globals --enable-multivalue --enable-reference-types \
      -o pkg/weft_bg.wasm.opt pkg/weft_bg.wasm 2>pkg/wasm-opt.log; then
      mv pkg/weft_bg.wasm.opt pkg/weft_bg.wasm
      rm -f pkg/wasm-opt.log
    else
      rm -f pkg/weft_bg.wasm.opt
      say "wasm-opt $(wasm-opt --version 2>/dev/null | awk '{print $3}') could not optimise the module" \
        "($(head -c 200 pkg/wasm-opt.log | tr '\n' ' ')); keeping it unoptimised"
      rm -f pkg/wasm-opt.log
    fi
  fi
  say "pkg/weft_bg.wasm: $(du -k pkg/weft_bg.wasm | cut -f1) KiB"
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
rm -rf www/examples
mkdir -p www/examples
node --input-type=module - <<'JS'
import { readdirSync, readFileSync, copyFileSync, writeFileSync } from "node:fs";
const files = readdirSync("examples").filter((f) => f.endsWith(".json")).sort();
const index = files.map((file) => {
  let name = file.replace(/\.json$/, "");
  try {
    const d = JSON.parse(readFileSync(`examples/${file}`, "utf8"));
    if (d && typeof d.name === "string" && d.name) name = d.name;
  } catch { /* not valid JSON: still listed; the page reports the parse error */ }
  copyFileSync(`examples/${file}`, `www/examples/${file}`);
  return { name, file };
});
writeFileSync("www/examples/index.json", JSON.stringify(index, null, 2) + "\n");
console.log(`[build-www] www/examples: ${index.length} design(s)`);
JS
say "done"

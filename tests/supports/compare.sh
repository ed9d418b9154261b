#!/bin/bash
# Supports against PrusaSlicer 2.5 (Debian's prusa-slicer) on parts that need them, same settings
# (prusaslicer.ini gives PrusaSlicer weft's defaults); prints per part and slicer: unanchored and
# bridged mm by an independent checker (CHECKER, default ../shared/tools/support_check.py, run
# with --zgap 0.2: both slicers leave 0.2 mm of air above their supports), support filament (mm
# of filament fed on Support* moves), and print time by `weft analyze`.
# Usage: tests/supports/compare.sh [OUT_DIR]   (needs prusa-slicer, python3 with numpy and scipy)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=${1:-target/supports}
weft=${WEFT_BIN:-$root/target/release/weft}
checker=${CHECKER:-$root/../shared/tools/support_check.py}
py=${PYTHON:-python3}
mkdir -p "$out"
python3 "$here/parts.py" "$out"
cp /usr/share/PrusaSlicer/shapes/M3x10_screw.stl "$out/screw.stl"
for p in t-bracket ledge-90 bridge-20 sphere-on-stem screw; do
  prusa-slicer --load "$here/prusaslicer.ini" --support-material --center 110,110 --export-gcode -o "$out/$p.prusa.gcode" "$out/$p.stl" >/dev/null 2>&1
  for style in grid tree; do
    "$weft" run "$root/examples/cube-20mm.json" --input "$out/$p.stl" --set job.slice.support.enabled=true \
      --set job.slice.support.style=$style --out "$out/$p.weft-$style.gcode" -q 2>/dev/null
  done
  for f in "$out/$p.prusa.gcode" "$out/$p.weft-grid.gcode" "$out/$p.weft-tree.gcode"; do
    t=$("$weft" analyze "$f" --json | python3 -c "import json,sys; print(round(json.load(sys.stdin)['estimated_time_s']))")
    s=$(python3 - "$f" <<'PY'
import sys
e = 0.0; rel = False; t = ''; sup = 0.0
for line in open(sys.argv[1], errors='replace'):
    if line.startswith(';TYPE:'):
        t = line[6:].strip(); continue
    w = line.split(';')[0].split()
    if not w: continue
    if w[0] == 'M83': rel = True
    elif w[0] == 'M82': rel = False
    elif w[0] == 'G92':
        e = next((float(x[1:]) for x in w[1:] if x[0] == 'E'), e)
    elif w[0] in ('G0', 'G1', 'G2', 'G3'):
        xy = any(x[0] in 'XY' for x in w[1:])
        for x in w[1:]:
            if x[0] == 'E':
                v = float(x[1:]); d = v if rel else v - e; e = e + v if rel else v
                if d > 0 and xy and t.startswith('Support'): sup += d
print(round(sup, 1))
PY
)
    "$py" "$checker" "$f" --json --zgap 0.2 | python3 -c "
import json,sys; d=json.load(sys.stdin)
print('| %s | %.1f mm (%.2f %%) | %.0f | %s | %s |' % ('$(basename "$f" .gcode)', d['unanchored_mm'], d['unanchored_pct'], d['bridged_mm'], '$s', '$t'))"
  done
done

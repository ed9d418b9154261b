#!/usr/bin/env bash
# A lattice, weft against PrusaSlicer (BENCHMARKS.md, "Against other slicers"): the same
# struts printed by weft and by PrusaSlicer, both G-codes read back by `weft analyze`.
#
# Designs: examples/honeycomb-10mm.json, voronoi-10mm.json, ball-burst-disc-48mm.json as
# shipped. PrusaSlicer gets the lattice from `weft export-stl` (a nozzle-wide, one-layer prism
# per strut, round-capped only at ends shared with another strut) and prints it with one
# perimeter and nothing else (its defaults: Arachne perimeters, thin walls).
# weft runs each design as shipped (gippo_max, longest_first), with paths.method=euler, with
# euler and paths.order=min_travel, and with continuous and min_travel.
#
# Columns: the `weft analyze --json` report, plus
#   moves    = extruding moves in the G-code (G1 with motion and E increasing; counted by
#              scripts/gcode_paths.py, the analyser does not report it): the paper's EdgesTotReal;
#   struts   = the design's struts (printed by `weft export-stl`): EdgesTotNominal;
#   normalised GIPPO = score ÷ (moves ÷ struts), the paper's correction for a slicer that
#              splits a strut into several moves (weft prints a strut as one move; a
#              continuous walk's travelled-over struts are travels, not extrusion).
#
# Usage: scripts/compare-prusa-lattice.sh     (prints a Markdown table; files in $OUT)
# Environment: WEFT_BIN (default target/release/weft), PRUSA (default prusa-slicer),
#              OUT (default target/prusa-lattice),
#              DESIGNS (default "honeycomb-10mm voronoi-10mm ball-burst-disc-48mm").
set -euo pipefail
cd "$(dirname "$0")/.."
weft=${WEFT_BIN:-target/release/weft}
prusa=${PRUSA:-prusa-slicer}
out=${OUT:-target/prusa-lattice}
designs=${DESIGNS:-honeycomb-10mm voronoi-10mm ball-burst-disc-48mm}
mkdir -p "$out"
say() { printf '[compare] %s\n' "$*" >&2; }
[ -x "$weft" ] || { echo "$weft not found: cargo build --release" >&2; exit 1; }
command -v "$prusa" >/dev/null || { echo "$prusa not found: apt-get install prusa-slicer" >&2; exit 1; }
prusa_name=$("$prusa" --help 2>/dev/null | grep -m1 -o "PrusaSlicer-[0-9.]*" | tr - " ")

rows=()
for d in $designs; do
  design=examples/$d.json
  stl="$out/$d.stl"
  say "export-stl: $d"
  # "<file>: 158 struts, 1896 triangles, 131.816 mm of struts"
  struts=$("$weft" export-stl "$design" --out "$stl" 2>&1 | sed -n 's/.*: \([0-9]*\) struts, .*, \([0-9.]*\) mm of struts.*/\1 \2/p')
  [ -n "$struts" ] || { echo "could not read the strut count of $d" >&2; exit 1; }
  for variant in "gippo_max longest_first" "euler longest_first" "euler min_travel" "continuous min_travel"; do
    read -r method order <<<"$variant"
    g="$out/$d-$method-$order.gcode"
    say "weft: $d, $method, $order"
    "$weft" run "$design" --set "job.paths.method=$method" --set "job.paths.order=$order" --out "$g" --quiet
    "$weft" analyze "$g" --json > "$g.json"
    label="weft $method"
    [ "$method $order" = "gippo_max longest_first" ] && label="weft gippo_max (as shipped)"
    [ "$order" = min_travel ] && label="$label, min_travel"
    rows+=("$d|$struts|$label|$g")
  done
  g="$out/$d-prusa.gcode"
  say "PrusaSlicer: $d"
  "$prusa" --export-gcode --layer-height 0.148 --first-layer-height 0.148 \
    --nozzle-diameter 0.2 --filament-diameter 1.75 --perimeters 1 --fill-density 0 \
    --top-solid-layers 0 --bottom-solid-layers 0 --skirts 0 --brim-width 0 \
    -o "$g" "$stl" >&2
  "$weft" analyze "$g" --json > "$g.json"
  rows+=("$d|$struts|$prusa_name|$g")
done

python3 - "${rows[@]}" <<'EOF'
import json, os, sys
sys.path.insert(0, "scripts")
import gcode_paths
print("| design | G-code | paths | travel mm | retractions | extruded mm | vs nominal | overlap mm "
      "| extruding moves (real) | struts (nominal) | GIPPO score | normalised GIPPO | filament mm | est. time s |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
last = None
n = lambda x, p=0: f"{x:,.{p}f}".replace(",", " ")
for row in sys.argv[1:]:
    d, struts, label, g = row.split("|")
    nominal, nominal_mm = int(struts.split()[0]), float(struts.split()[1])
    a = json.load(open(g + ".json"))
    a = a.get("report", a)
    layers, moves = gcode_paths.read(g)
    assert sum(len(l) for l in layers) == a["extrusion_paths"], (g, "path count differs from weft analyze")
    head = f"{d} ({a['layers']} layer{'s' if a['layers'] > 1 else ''}, {n(nominal)} struts, {n(nominal_mm, 2)} mm)" if d != last else ""
    last = d
    score = a["gippo_score"]
    print(f"| {head} | {label} | {n(a['extrusion_paths'])} | {n(a['travel_mm'], 1)} | {n(a['retractions'])} "
          f"| {n(a['extruded_mm'], 2)} | {100 * a['extruded_mm'] / nominal_mm:.1f} % | {a['overlap_mm']:.3f} "
          f"| {n(moves)} | {n(nominal)} | {score:.4f} | {score / (moves / nominal):.4f} "
          f"| {a['filament_mm']:.2f} | {n(a['estimated_time_s'])} |")
EOF

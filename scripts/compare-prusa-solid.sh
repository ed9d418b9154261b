#!/usr/bin/env bash
# A lattice filling a solid, weft against PrusaSlicer (BENCHMARKS.md, "Lattice filling a
# solid"): travel and extrusion of the same part, both G-codes read back by `weft analyze`.
#
# Parts (binary STL written here, the same file given to both slicers; the geometry of weft's
# built-in `uv_sphere`, radius 15 mm, standing on the plate):
#   honeycomb: 30 mm sphere, 96 facets around (9 024 triangles, as examples/sphere-30mm.json),
#              filled with examples/honeycomb-10mm.json's lattice (honeycomb R 0.92 mm);
#   voronoi:   30 mm sphere, 84 facets around (6 888 triangles), filled with
#              examples/voronoi-10mm.json's lattice (Voronoi 0.6 /mm²).
# Both designs as shipped (0.2 mm nozzle, 0.148 mm layers, contour off), the mesh in the
# `mesh` slot (the domain becomes the solid's layers), with every paths method (gippo_max,
# euler, continuous) and order (longest_first, min_travel).
# PrusaSlicer (Debian's prusa-slicer): honeycomb infill at the lattice's solid fraction
# (honeycomb 1.155 w/R = 25 %, Voronoi 2 w √ρ = 31 %), 0.2 mm infill lines, no perimeters and no
# solid layers, so it prints only the infill of each layer, as the lattice does; and again at
# the density whose extruded length matches weft's (PrusaSlicer's honeycomb at 25 % extrudes
# ~1.5× the lattice's length: 16.5 % and 20.8 % give the same length as weft).
#
# Usage: scripts/compare-prusa-solid.sh        (prints a Markdown table; files in $OUT)
# Environment: WEFT_BIN (default target/release/weft), PRUSA (default prusa-slicer),
#              OUT (default target/prusa-solid), PARTS (default "honeycomb voronoi").
set -euo pipefail
cd "$(dirname "$0")/.."
weft=${WEFT_BIN:-target/release/weft}
prusa=${PRUSA:-prusa-slicer}
out=${OUT:-target/prusa-solid}
parts=${PARTS:-honeycomb voronoi}
mkdir -p "$out"
say() { printf '[compare] %s\n' "$*" >&2; }
[ -x "$weft" ] || { echo "$weft not found: cargo build --release" >&2; exit 1; }
command -v "$prusa" >/dev/null || { echo "$prusa not found: apt-get install prusa-slicer" >&2; exit 1; }

# weft's uv_sphere(r, seg) (src/geom/shapes.rs) as a binary STL.
sphere_stl() {
  python3 - "$1" "$2" "$3" <<'EOF'
import math, struct, sys
r, seg, path = float(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
rings = max(seg // 2, 4)
v = [(0.0, 0.0, 0.0)]
for i in range(1, rings):
    phi = math.pi * i / rings
    sp, cp = math.sin(phi), math.cos(phi)
    for j in range(seg):
        th = 2 * math.pi * j / seg
        v.append((r * sp * math.cos(th), r * sp * math.sin(th), r - r * cp))
north = len(v)
v.append((0.0, 0.0, 2 * r))
ring = lambda i, j: 1 + (i - 1) * seg + (j % seg)
t = []
for j in range(seg):
    t.append((0, ring(1, j + 1), ring(1, j)))
    t.append((north, ring(rings - 1, j), ring(rings - 1, j + 1)))
for i in range(1, rings - 1):
    for j in range(seg):
        a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)
        t += [(a, b, c), (a, c, d)]
with open(path, "wb") as f:
    f.write(b"weft uv_sphere".ljust(80, b" ") + struct.pack("<I", len(t)))
    for tri in t:
        f.write(struct.pack("<3f", 0, 0, 0))
        for k in tri:
            f.write(struct.pack("<3f", *v[k]))
        f.write(b"\0\0")
EOF
}

# name | design | facets | PrusaSlicer fill densities (nominal solid fraction, same length as weft)
spec() {
  case $1 in
    honeycomb) echo "examples/honeycomb-10mm.json 96 25% 16.5%" ;;
    voronoi) echo "examples/voronoi-10mm.json 84 31% 20.8%" ;;
    *) echo "unknown part $1" >&2; exit 1 ;;
  esac
}

rows=()
for part in $parts; do
  read -r design facets densities < <(spec "$part")
  stl="$out/sphere-30mm-$facets.stl"
  sphere_stl 15 "$facets" "$stl"
  for method in gippo_max euler continuous; do
    for order in longest_first min_travel; do
      g="$out/$part-$method-$order.gcode"
      say "weft: $part, $method, $order"
      t0=$(date +%s.%N)
      "$weft" run "$design" --input "mesh=$stl" --set "job.paths.method=$method" --set "job.paths.order=$order" --out "$g" --quiet
      t1=$(date +%s.%N)
      "$weft" analyze "$g" --json > "$g.json"
      rows+=("$part|weft $method, $order|$g.json|$(echo "$t1 - $t0" | bc)")
    done
  done
  for density in $densities; do
    g="$out/$part-prusa-${density%\%}.gcode"
    say "PrusaSlicer: $part, honeycomb infill $density"
    t0=$(date +%s.%N)
    "$prusa" --export-gcode --layer-height 0.148 --first-layer-height 0.148 \
      --nozzle-diameter 0.2 --filament-diameter 1.75 \
      --perimeters 0 --top-solid-layers 0 --bottom-solid-layers 0 --solid-infill-below-area 0 \
      --fill-pattern honeycomb --fill-density "$density" --extrusion-width 0.2 --first-layer-extrusion-width 0.2 \
      --skirts 0 --brim-width 0 -o "$g" "$stl" >&2
    t1=$(date +%s.%N)
    "$weft" analyze "$g" --json > "$g.json"
    rows+=("$part|$("$prusa" --help 2>/dev/null | grep -m1 -o "PrusaSlicer-[0-9.]*" | tr - " "), honeycomb infill $density|$g.json|$(echo "$t1 - $t0" | bc)")
  done
done

python3 - "${rows[@]}" <<'EOF'
import json, sys
print("| part | G-code | layers | paths | travel mm | extrusion mm | travel ÷ extrusion | retractions | est. print time s | slicing wall s |")
print("|---|---|---|---|---|---|---|---|---|---|")
for row in sys.argv[1:]:
    part, label, path, wall = row.split("|")
    a = json.load(open(path))
    a = a.get("report", a)
    tr, ex = a["travel_mm"], a["extruded_mm"]
    n = lambda x: f"{x:,.0f}".replace(",", " ")
    print(f"| {part} | {label} | {a['layers']} | {n(a['extrusion_paths'])} | {n(tr)} | {n(ex)} | {tr / ex:.2f} | {n(a['retractions'])} | {n(a['estimated_time_s'])} | {float(wall):.1f} |")
EOF

#!/usr/bin/env python3
"""Extrusion paths of a G-code file, for scripts/compare-prusa-lattice.sh and
scripts/lattice_path_ends.py.

Reads the Marlin-style subset that weft and PrusaSlicer write (G0/G1, G90/G91, M82/M83, G92,
G10/G11, `;LAYER_CHANGE`/`;LAYER:` comments) with the definitions of `weft analyze`
(src/analyze/mod.rs): an *extruding move* is a G0/G1 with XY(Z) motion and a positive E delta;
an *extrusion path* is a maximal run of extruding moves, broken by a travel, a retraction or a
layer change. Arcs (G2/G3) are refused: neither slicer writes them with the settings used here.

Usage:
  gcode_paths.py FILE.gcode           print {"extruding_moves": N, "paths": P, "layers": L}
  gcode_paths.py FILE.gcode --paths   also print every path's points (per layer)

As a module: `read(path)` returns a list of layers, each a list of paths, each a list of
(x, y) points (the first is where the path starts), and the number of extruding moves.
"""
import json
import sys


def read(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        comments = any(l.startswith(";LAYER_CHANGE") or l.startswith(";LAYER:") for l in f)
    absolute_xyz, absolute_e = True, True
    x = y = z = e = 0.0
    layers, layer, cur = [], [], None
    moves = 0
    layer_mark = False  # a layer comment was seen since the last extruding move
    retracted = False
    zs = []

    def end_path():
        nonlocal cur
        if cur is not None and len(cur) > 1:
            layer.append(cur)
        cur = None

    for raw in open(path, encoding="utf-8", errors="replace"):
        line = raw.strip()
        if line.startswith(";LAYER_CHANGE") or line.startswith(";LAYER:"):
            layer_mark = True
            continue
        code = line.split(";", 1)[0].strip()
        if not code:
            continue
        words = code.split()
        cmd = words[0].upper()
        params = {}
        for w in words[1:]:
            try:
                params[w[0].upper()] = float(w[1:])
            except ValueError:
                pass
        if cmd == "G90":
            absolute_xyz = absolute_e = True
        elif cmd == "G91":
            absolute_xyz = absolute_e = False
        elif cmd == "M82":
            absolute_e = True
        elif cmd == "M83":
            absolute_e = False
        elif cmd == "G92":
            if "E" in params:
                e = params["E"]
            for k in "XYZ":
                if k in params:
                    if k == "X": x = params[k]
                    if k == "Y": y = params[k]
                    if k == "Z": z = params[k]
        elif cmd == "G10":
            if "P" not in params and "L" not in params:
                end_path()
                retracted = True
        elif cmd == "G11":
            retracted = False
        elif cmd in ("G2", "G3"):
            raise SystemExit(f"{path}: arcs are not read by this script")
        elif cmd in ("G0", "G1"):
            nx = (params["X"] if absolute_xyz else x + params["X"]) if "X" in params else x
            ny = (params["Y"] if absolute_xyz else y + params["Y"]) if "Y" in params else y
            nz = (params["Z"] if absolute_xyz else z + params["Z"]) if "Z" in params else z
            de = 0.0
            if "E" in params:
                de = params["E"] - e if absolute_e else params["E"]
                e = params["E"] if absolute_e else e + params["E"]
            motion = (nx, ny, nz) != (x, y, z)
            if de < 0:
                end_path()
                retracted = True
            elif de > 0 and not motion:
                retracted = False
            if motion and de > 0:
                retracted = False
                if comments:
                    new_layer = layer_mark or not zs
                else:
                    new_layer = (not zs) or abs(nz - zs[-1]) > 1e-9
                if new_layer:
                    end_path()
                    if layer or zs:
                        layers.append(layer)
                    layer = []
                    zs.append(nz)
                    layer_mark = False
                if cur is None:
                    cur = [(x, y)]
                cur.append((nx, ny))
                moves += 1
            elif motion:
                end_path()
            x, y, z = nx, ny, nz
    end_path()
    if layer:
        layers.append(layer)
    return layers, moves


if __name__ == "__main__":
    layers, moves = read(sys.argv[1])
    out = {
        "extruding_moves": moves,
        "paths": sum(len(l) for l in layers),
        "layers": len(layers),
    }
    if "--paths" in sys.argv[2:]:
        out["per_layer"] = layers
    print(json.dumps(out))

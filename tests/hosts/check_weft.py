#!/usr/bin/env python3
"""weft's G-code on real print hosts: what Moonraker and OctoPrint read from it, sent by `weft send`.

usage: check_weft.py --weft BIN --hosts HOSTS.json --out DIR

HOSTS.json is the line `hosts.py start` printed (the hosts are running). With the CLI:
1. `weft run examples/cube-20mm.json` → cube-20mm.gcode (and .bgcode, checked by tests/bgcode/check_bgcode.py
   with libbgcode's reader from PyPI).
2. `weft send … --to moonraker`: Moonraker's /server/files/metadata must name the slicer weft with its version
   and hold weft's estimated time, filament length and weight, layer height, first-layer temperatures and the
   thumbnails; each thumbnail, fetched from Moonraker and decoded by Pillow, is the printer's size and drawn in
   the preview's feature colours.
3. `weft send … --to octoprint --key KEY --start`: the virtual printer prints it to completion; OctoPrint's own
   analysis finds weft's filament length and the part's size. A wrong key fails with a plain sentence and exit 1.
Exits 1 on the first failure, with what differed.
"""

import argparse
import io
import json
import os
import re
import subprocess
import sys
import time
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def check(cond, what):
    if not cond:
        print(f"check_weft: FAIL: {what}")
        sys.exit(1)


def get(url, headers=None):
    req = urllib.request.Request(url, headers=headers or {})
    with urllib.request.urlopen(req, timeout=15) as r:
        return r.read()


def weft(binary, *args, env=None):
    p = subprocess.run([binary, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=300, env=env)
    return p.returncode, p.stdout, p.stderr


def footer(text, key):
    m = re.findall(r"^; " + re.escape(key) + r" = (.*)$", text, re.M)
    check(m, f"no '; {key} =' in weft's G-code")
    return m[-1]


def feature_colours():
    """The preview's feature colours (src/geom/toolpath.rs, Feature::color)."""
    src = open(os.path.join(ROOT, "src/geom/toolpath.rs"), encoding="utf-8").read()
    body = src[src.index("pub fn color(self)"):]
    body = body[: body.index("\n    }\n")]
    return [tuple(int(h[i:i + 2], 16) for i in (0, 2, 4)) for h in re.findall(r'"#([0-9a-f]{6})"', body)]


def check_thumbnail(png_bytes, size, colours):
    from PIL import Image

    im = Image.open(io.BytesIO(png_bytes)).convert("RGBA")
    check(im.size == size, f"thumbnail is {im.size}, want {size}")
    raw = im.tobytes()
    opaque = [tuple(raw[i:i + 3]) for i in range(0, len(raw), 4) if raw[i + 3] == 255]
    check(len(opaque) > size[0] * size[1] // 20, f"thumbnail {size} has only {len(opaque)} opaque pixels")
    counts = {}
    for p in opaque:
        counts[p] = counts.get(p, 0) + 1
    top = max(counts, key=counts.get)
    # The top layer is drawn in the colour itself, lower layers darker: every opaque pixel is
    # a feature colour scaled by a shade in [0.45, 1].
    check(top in colours, f"thumbnail {size}: the most common colour {top} is no feature colour {colours}")
    for p, n in counts.items():
        ok = any(all(abs(p[i] - round(c[i] * s / 100)) <= 1 for i in range(3)) for c in colours for s in range(45, 101))
        check(ok, f"thumbnail {size}: colour {p} ({n} px) is no shade of a feature colour")
    return top


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--weft", required=True)
    ap.add_argument("--hosts", required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    t0 = time.monotonic()
    hosts = json.loads(open(args.hosts, encoding="utf-8").read())
    os.makedirs(args.out, exist_ok=True)
    gcode_path = os.path.join(args.out, "cube-20mm.gcode")
    design = os.path.join(ROOT, "examples/cube-20mm.json")
    rc, _, err = weft(args.weft, "run", design, "-q", "-o", gcode_path)
    check(rc == 0, f"weft run: {err}")
    text = open(gcode_path, encoding="utf-8").read()
    rc, out, err = weft(args.weft, "analyze", gcode_path, "--json")
    check(rc == 0, f"weft analyze: {err}")
    analysis = json.loads(out)

    # Binary G-code, read back by libbgcode.
    bg_path = os.path.join(args.out, "cube-20mm.bgcode")
    rc, _, err = weft(args.weft, "run", design, "-q", "-o", bg_path)
    check(rc == 0, f"weft run -o .bgcode: {err}")
    p = subprocess.run([sys.executable, os.path.join(ROOT, "tests/bgcode/check_bgcode.py"), bg_path, gcode_path],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120)
    check(p.returncode == 0, f"check_bgcode: {p.stdout.strip()}")
    print(p.stdout.strip())

    # Moonraker.
    mr = hosts["moonraker"]
    rc, out, err = weft(args.weft, "send", gcode_path, "--to", "moonraker", "--url", mr)
    check(rc == 0, f"weft send --to moonraker: exit {rc}: {err}")
    meta = json.loads(get(f"{mr}/server/files/metadata?filename=cube-20mm.gcode"))["result"]
    check(meta.get("slicer") == "weft", f"Moonraker names the slicer {meta.get('slicer')!r}, want 'weft'")
    version = text.splitlines()[0].split()[4]
    check(meta.get("slicer_version") == version, f"slicer_version {meta.get('slicer_version')!r}, want {version!r}")
    t = round(analysis["estimated_time_s"])
    check(abs(meta.get("estimated_time", -1) - t) <= 1, f"estimated_time {meta.get('estimated_time')} s, weft says {t} s")
    check(abs(meta.get("filament_total", -1) - analysis["filament_mm"]) < 0.01,
          f"filament_total {meta.get('filament_total')} mm, weft says {analysis['filament_mm']}")
    grams = float(footer(text, "total filament used [g]"))
    check(abs(meta.get("filament_weight_total", -1) - grams) < 1e-9, f"filament_weight_total {meta.get('filament_weight_total')}, want {grams}")
    check(meta.get("layer_height") == 0.2 and meta.get("first_layer_height") == 0.2, f"layer heights {meta.get('layer_height')} {meta.get('first_layer_height')}")
    check(meta.get("first_layer_extr_temp") == 215 and meta.get("first_layer_bed_temp") == 60,
          f"first-layer temperatures {meta.get('first_layer_extr_temp')} / {meta.get('first_layer_bed_temp')}")
    check(meta.get("layer_count") == analysis["layers"], f"layer_count {meta.get('layer_count')}, weft says {analysis['layers']}")
    check(abs(meta.get("object_height", -1) - 20.0) < 1e-6, f"object_height {meta.get('object_height')}, want 20")
    thumbs = sorted((t["width"], t["height"], t["relative_path"]) for t in meta.get("thumbnails", []))
    check([(w, h) for w, h, _ in thumbs] == [(32, 32), (300, 300)], f"thumbnails {thumbs}")
    colours = feature_colours()
    for w, h, rel in thumbs:
        check_thumbnail(get(f"{mr}/server/files/gcodes/{rel}"), (w, h), colours)
    print(f"Moonraker: slicer weft {version}, {meta['estimated_time']} s, {meta['filament_total']} mm, "
          f"{meta['filament_weight_total']} g, layer {meta['layer_height']} mm, {len(thumbs)} thumbnails in preview colours")

    # OctoPrint: a wrong key, then the print on the virtual printer.
    op, key = hosts["octoprint"], hosts["octoprint_key"]
    rc, _, err = weft(args.weft, "send", gcode_path, "--to", "octoprint", "--url", op, "--key", "wrong-key")
    check(rc != 0 and "key" in err.lower(), f"a wrong key: exit {rc}, {err!r}")
    check("wrong-key" not in err, "the key was printed")
    env = dict(os.environ, WEFT_HOST_KEY=key)
    rc, out, err = weft(args.weft, "send", gcode_path, "--to", "octoprint", "--url", op, "--start", env=env)
    check(rc == 0, f"weft send --to octoprint --start: exit {rc}: {err}")
    deadline = time.monotonic() + 120
    state = {}
    while time.monotonic() < deadline:
        state = json.loads(get(f"{op}/api/job", {"X-Api-Key": key}))
        done = (state.get("progress") or {}).get("completion")
        if state.get("state") == "Operational" and done is not None and done >= 100:
            break
        time.sleep(0.5)
    check(state.get("state") == "Operational" and state["progress"]["completion"] >= 100,
          f"the virtual printer did not finish in 120 s: {json.dumps(state)[:300]}")
    check(state["job"]["file"]["name"] == "cube-20mm.gcode", f"printed {state['job']['file']['name']}")
    info = {}
    while time.monotonic() < deadline:
        info = json.loads(get(f"{op}/api/files/local/cube-20mm.gcode", {"X-Api-Key": key}))
        if info.get("gcodeAnalysis", {}).get("filament"):
            break
        time.sleep(0.5)
    ga = info.get("gcodeAnalysis") or {}
    length = ga.get("filament", {}).get("tool0", {}).get("length", -1)
    check(abs(length - analysis["filament_mm"]) < 0.01 * analysis["filament_mm"], f"OctoPrint's filament {length} mm, weft says {analysis['filament_mm']}")
    # The 20 mm cube and its skirt loop 3 mm out: centre lines 2 × (10 + 3 + 0.2) = 26.4 mm apart.
    dims = ga.get("dimensions", {})
    check(abs(dims.get("width", 0) - 26.4) < 0.5 and abs(dims.get("depth", 0) - 26.4) < 0.5 and abs(dims.get("height", 0) - 20) < 0.5,
          f"OctoPrint's dimensions {dims}, want 26.4 × 26.4 × 20 (the cube and its skirt)")
    print(f"OctoPrint: printed to 100 % on the virtual printer; its analysis: {length:.1f} mm filament, "
          f"{dims.get('width', 0):.1f} × {dims.get('depth', 0):.1f} × {dims.get('height', 0):.1f} mm")
    print(f"check_weft: OK ({time.monotonic() - t0:.1f} s)")


if __name__ == "__main__":
    main()

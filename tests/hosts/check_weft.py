#!/usr/bin/env python3
"""weft's G-code on real print hosts: what Moonraker and OctoPrint read from it, sent by `weft send`.

usage: check_weft.py --weft BIN --hosts HOSTS.json --out DIR

HOSTS.json is the line `hosts.py start` printed (the hosts are running). With the CLI:
1. `weft run examples/cube-20mm.json` → cube-20mm.gcode (and .bgcode, checked by tests/bgcode/check_bgcode.py
   with libbgcode's reader from PyPI); with `--printer prusa-mk4`, its QOI thumbnails decoded by Pillow and its
   .bgcode (QOI thumbnail blocks) read back by libbgcode.
2. `weft send … --to moonraker` (and `weft run … --send moonraker`, the same bytes): Moonraker's /server/files/metadata must name the slicer weft with its version
   and hold weft's estimated time, filament length and weight, layer height, first-layer temperatures and the
   thumbnails; each thumbnail, fetched from Moonraker and decoded by Pillow, is the printer's size and drawn in
   the preview's feature colours.
3. `weft send … --to octoprint --key KEY --start`: the virtual printer prints it to completion; OctoPrint's own
   analysis finds weft's filament length and the part's size. A wrong key fails with a plain sentence and exit 1.
   While a longer print runs, sending the same file again is refused as busy (OctoPrint keeps the file being
   printed), and another file is stored but not started, each in one sentence with exit 1; then it is cancelled.
4. Object labels of two cubes apart, read by Moonraker's own upload processing (its metadata.py with
   --check-objects, which runs preprocess_cancellation): Klipper's labels (the klipper-220 profile) arrive on
   Moonraker byte for byte and the processing leaves them as they are; M486 labels (the default) are turned by it
   into Klipper's, two objects whose centres are weft's, which weft's analyzer reads back with the same extrusion.
   (Moonraker's metadata has no object list: Klipper builds it from EXCLUDE_OBJECT_DEFINE when printing.)
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


def check_thumbnail(image_bytes, size, colours):
    """A PNG or QOI thumbnail, decoded by Pillow: its size, and every pixel a shade of a feature colour."""
    from PIL import Image

    im = Image.open(io.BytesIO(image_bytes)).convert("RGBA")
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


def two_cubes_stl(path):
    """Two 10 mm cubes 20 mm apart, as a binary STL (outward normals)."""
    import struct

    faces = [(0, 1, 3), (0, 3, 2), (4, 7, 5), (4, 6, 7), (0, 4, 5), (0, 5, 1),
             (2, 7, 6), (2, 3, 7), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
    tris = []
    for x0 in (0.0, 30.0):
        v = [(x0 + 10 * dx, 10.0 * dy, 10.0 * dz) for dx in (0, 1) for dy in (0, 1) for dz in (0, 1)]
        tris += [[v[i] for i in f] for f in faces]
    with open(path, "wb") as f:
        f.write(b"two cubes".ljust(80, b" ") + struct.pack("<I", len(tris)))
        for t in tris:
            f.write(struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *p) for p in t) + b"\0\0")


def defined_objects(text):
    """EXCLUDE_OBJECT_DEFINE lines: name → (x, y) centre."""
    return {m.group(1): (float(m.group(2)), float(m.group(3)))
            for m in re.finditer(r"^EXCLUDE_OBJECT_DEFINE NAME=(\S+) CENTER=([-\d.]+),([-\d.]+)", text, re.M)}


def moonraker_processing(path, work):
    """Runs Moonraker's upload processing (metadata.py --check-objects, as Moonraker runs it with
    enable_object_processing) on a copy of `path`; the copy's text after it."""
    import shutil

    python = os.path.join(sys.prefix, "moonraker-env", "bin", "python")
    os.makedirs(work, exist_ok=True)
    name = os.path.basename(path)
    shutil.copyfile(path, os.path.join(work, name))
    p = subprocess.run([python, "-m", "moonraker.components.file_manager.metadata", "-f", name, "-p", work, "-o"],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=120)
    check(p.returncode == 0, f"Moonraker's metadata.py on {name}: exit {p.returncode}: {p.stdout[-400:]!r}")
    return open(os.path.join(work, name), encoding="utf-8").read()


def check_objects(binary, out, mr):
    stl = os.path.join(out, "two-cubes.stl")
    two_cubes_stl(stl)
    design = os.path.join(ROOT, "examples/cube-20mm.json")
    files = {}
    for variant, printer in (("klipper", "klipper-220"), ("m486", "generic-220")):
        path = os.path.join(out, f"two-cubes-{variant}.gcode")
        rc, _, err = weft(binary, "run", design, "--input", f"mesh={stl}", "--printer", printer, "--set", "name=two-cubes", "-q", "-o", path)
        check(rc == 0, f"weft run two cubes ({printer}): {err}")
        rc, js, err = weft(binary, "analyze", path, "--json")
        check(rc == 0, f"weft analyze {path}: {err}")
        files[variant] = (path, open(path, encoding="utf-8").read(), json.loads(js)["objects"])
    k_path, k_text, k_objects = files["klipper"]
    weft_centres = defined_objects(k_text)
    check(sorted(weft_centres) == ["two-cubes_1", "two-cubes_2"] == sorted(o["name"] for o in k_objects),
          f"weft's objects: defined {sorted(weft_centres)}, analyzed {[o['name'] for o in k_objects]}")
    # Klipper's labels: byte for byte on Moonraker, and its processing sees they are there.
    rc, _, err = weft(binary, "send", k_path, "--to", "moonraker", "--url", mr, "-q")
    check(rc == 0, f"weft send two-cubes-klipper.gcode: {err}")
    back = get(f"{mr}/server/files/gcodes/{os.path.basename(k_path)}")
    check(back == k_text.encode(), f"Moonraker holds {len(back)} bytes, weft wrote {len(k_text.encode())}")
    check(moonraker_processing(k_path, os.path.join(out, "mr-klipper")) == k_text,
          "Moonraker's object processing changed a file that has Klipper's labels")
    # M486 labels, turned into Klipper's by Moonraker's processing: the same two objects.
    m_path, m_text, m_objects = files["m486"]
    processed = moonraker_processing(m_path, os.path.join(out, "mr-m486"))
    theirs = defined_objects(processed)
    check(len(theirs) == 2, f"Moonraker's processing found {len(theirs)} objects in weft's M486 labels: {theirs}")
    for i, (name, c) in enumerate(sorted(theirs.items())):
        w = weft_centres[f"two-cubes_{i + 1}"]
        check(abs(c[0] - w[0]) < 1.0 and abs(c[1] - w[1]) < 1.0, f"object {name}: Moonraker's centre {c}, weft's {w}")
    processed_path = os.path.join(out, "mr-m486", "processed.gcode")
    with open(processed_path, "w", encoding="utf-8") as f:
        f.write(processed)
    rc, js, err = weft(binary, "analyze", processed_path, "--json")
    check(rc == 0, f"weft analyze of Moonraker's processed file: {err}")
    read = json.loads(js)["objects"]
    check([o["name"] for o in read] == sorted(theirs), f"weft's analyzer reads {[o['name'] for o in read]} from Moonraker's labels")
    for a, b in zip(read, m_objects):
        check(abs(a["extruded_mm"] - b["extruded_mm"]) < 1e-6 * b["extruded_mm"] + 1e-6,
              f"object {a['name']}: {a['extruded_mm']} mm extruded under Moonraker's labels, {b['extruded_mm']} under weft's")
    print(f"Objects: two cubes as {sorted(weft_centres)} at {sorted(weft_centres.values())}; Klipper's labels kept byte for byte "
          f"on Moonraker; M486 turned by Moonraker's processing into {sorted(theirs)} at the same centres and extrusion")


def post(url, body, headers):
    req = urllib.request.Request(url, data=json.dumps(body).encode(), headers={**headers, "Content-Type": "application/json"}, method="POST")
    with urllib.request.urlopen(req, timeout=15) as r:
        return r.status


def check_busy(binary, out, op, key):
    """A print running on OctoPrint: the same name again is busy, another is stored but not started."""
    h = {"X-Api-Key": key}
    env = dict(os.environ, WEFT_HOST_KEY=key)
    design = os.path.join(ROOT, "examples/sphere-30mm.json")
    path = os.path.join(out, "busy-sphere.gcode")
    rc, _, err = weft(binary, "run", design, "-q", "-o", path)
    check(rc == 0, f"weft run sphere-30mm: {err}")
    rc, _, err = weft(binary, "send", path, "--to", "octoprint", "--url", op, "--start", "-q", env=env)
    check(rc == 0, f"weft send busy-sphere.gcode --start: {err}")
    deadline = time.monotonic() + 60
    state = {}
    while time.monotonic() < deadline:
        state = json.loads(get(f"{op}/api/job", h))
        if state.get("state") == "Printing":
            break
        time.sleep(0.2)
    check(state.get("state") == "Printing", f"OctoPrint is not printing busy-sphere.gcode: {json.dumps(state)[:300]}")
    try:
        # The sphere's 42k lines take the virtual printer about 12 s (longer under load).
        rc, _, same = weft(binary, "send", path, "--to", "octoprint", "--url", op, "--start", "-q", env=env)
        check(rc == 1 and "busy" in same and "being printed" in same and same.count("\n") == 1,
              f"the file being printed, sent again: exit {rc}, {same!r}")
        other = os.path.join(out, "busy-other.gcode")
        with open(other, "wb") as f:
            f.write(open(path, "rb").read())
        rc, _, started = weft(binary, "send", other, "--to", "octoprint", "--url", op, "--start", "-q", env=env)
        check(rc == 1 and "Uploaded busy-other.gcode" in started and "did not start: it is busy (Printing)" in started,
              f"another file while printing: exit {rc}, {started!r}")
        job = json.loads(get(f"{op}/api/job", h))
        check(job["job"]["file"]["name"] == "busy-sphere.gcode", f"the job changed to {job['job']['file']['name']}")
    finally:
        post(f"{op}/api/job", {"command": "cancel"}, h)
        while time.monotonic() < deadline + 60:
            if json.loads(get(f"{op}/api/job", h)).get("state") == "Operational":
                break
            time.sleep(0.2)
    print(f"OctoPrint busy: {same.strip()} / {started.strip()}")


def thumbnail_blocks(text, tag):
    """(width, height, image bytes) of each `; TAG begin WxH LEN` … `; TAG end` block."""
    import base64

    out = []
    for m in re.finditer(r"^; %s begin (\d+)x(\d+) (\d+)\n((?:; .*\n)*?); %s end$" % (tag, tag), text, re.M):
        b64 = "".join(line[2:] for line in m.group(4).splitlines())
        check(len(b64) == int(m.group(3)), f"{tag} {m.group(1)}x{m.group(2)}: {len(b64)} base64 characters, the block says {m.group(3)}")
        out.append((int(m.group(1)), int(m.group(2)), base64.b64decode(b64)))
    return out


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

    # The Prusa MK4 profile: QOI thumbnails for its screen (Pillow decodes them: the printer's
    # sizes, the preview's colours), one PNG for PrusaLink; its .bgcode read back by libbgcode.
    mk4_text, mk4_bg = os.path.join(args.out, "mk4.gcode"), os.path.join(args.out, "mk4.bgcode")
    for path in (mk4_text, mk4_bg):
        rc, _, err = weft(args.weft, "run", design, "--printer", "prusa-mk4", "-q", "-o", path)
        check(rc == 0, f"weft run --printer prusa-mk4 -o {os.path.basename(path)}: {err}")
    colours = feature_colours()
    qoi = thumbnail_blocks(open(mk4_text, encoding="utf-8").read(), "thumbnail_QOI")
    check([(w, h) for w, h, _ in qoi] == [(16, 16), (313, 173), (440, 240), (480, 240)], f"MK4 QOI thumbnails {[(w, h) for w, h, _ in qoi]}")
    for w, h, image in qoi:
        check(image[:4] == b"qoif", f"QOI thumbnail {w}x{h} does not start with qoif")
        check_thumbnail(image, (w, h), colours)
    p = subprocess.run([sys.executable, os.path.join(ROOT, "tests/bgcode/check_bgcode.py"), mk4_bg, mk4_text],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120)
    check(p.returncode == 0, f"check_bgcode (MK4): {p.stdout.strip()}")
    print(f"MK4: {len(qoi)} QOI thumbnails decoded by Pillow in preview colours; {p.stdout.strip()}")

    # Moonraker.
    mr = hosts["moonraker"]
    rc, out, err = weft(args.weft, "send", gcode_path, "--to", "moonraker", "--url", mr)
    check(rc == 0, f"weft send --to moonraker: exit {rc}: {err}")
    # `weft run … --send`: written, then sent; Moonraker holds the bytes written.
    run_sent = os.path.join(args.out, "run-sent.gcode")
    rc, _, err = weft(args.weft, "run", design, "-q", "-o", run_sent, "--send", "moonraker", "--send-url", mr)
    check(rc == 0, f"weft run --send moonraker: exit {rc}: {err}")
    check(get(f"{mr}/server/files/gcodes/run-sent.gcode") == open(run_sent, "rb").read() == text.encode(),
          "weft run --send: Moonraker's run-sent.gcode is not the bytes written (or not the run's G-code)")
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
    check_busy(args.weft, args.out, op, key)
    check_objects(args.weft, args.out, mr)
    print(f"check_weft: OK ({time.monotonic() - t0:.1f} s)")


if __name__ == "__main__":
    main()

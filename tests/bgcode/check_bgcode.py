#!/usr/bin/env python3
"""Checks a weft .bgcode against the G-code text it was made from, decoding it with libbgcode (pybgcode).

usage: check_bgcode.py FILE.bgcode ORIGINAL.gcode [THUMB.png ...]

1. Container, read here with struct/zlib: header GCDE v1 CRC32, every block's CRC32, block order (file
   metadata?, printer metadata, thumbnails*, print metadata, slicer metadata, G-code+), compressions (file,
   printer, print metadata and thumbnails none; slicer metadata none or Deflate; G-code Heatshrink 12/4 with
   MeatPack-with-comments in every block).
2. pybgcode (libbgcode's reader) converts it to ASCII with checksum verification; the metadata and the
   thumbnails it reads make the expected head and tail of that ASCII; the rest is the G-code.
3. That G-code must equal ORIGINAL.gcode after MeatPack's normalisation (normalise() below): whole-line
   comments kept as they are; comments after a command, blank lines and outer spaces/tabs dropped; G lines
   (G + digit) written with one space before each parameter letter (libbgcode's reader re-spaces them);
   libbgcode's converter also drops lines that are only ';' and blanks.
4. Thumbnails are PNG or QOI, as their block says, with the width and height of their block; given image
   files (or the text's own blocks), equal byte for byte.

Prints one summary line; exits 1 on any mismatch, 2 on bad usage or a missing pybgcode.
"""

import base64
import os
import re
import struct
import sys
import tempfile
import zlib

try:
    import pybgcode
except ImportError:
    print("check_bgcode: FAIL: pybgcode is not installed (pip install pybgcode-jneilliii)")
    sys.exit(2)

# Parameter letters before which libbgcode's MeatPack reader puts a space in a line starting with 'G'.
G_PARAMS = "XYZEFIJRSGPWHCA"
BLANKS = " \t"


def fail(msg):
    print("check_bgcode: FAIL: " + msg)
    sys.exit(1)


def walk_blocks(data):
    """Returns [(type, compression, uncompressed_size, params, payload)] after checking header and CRCs."""
    if len(data) < 10 or data[:4] != b"GCDE":
        fail("no GCDE magic")
    version, checksum = struct.unpack_from("<IH", data, 4)
    if version != 1 or checksum != 1:
        fail("header version %d checksum type %d (want 1, 1)" % (version, checksum))
    blocks, pos = [], 10
    while pos < len(data):
        if pos + 8 > len(data):
            fail("truncated block header at %d" % pos)
        btype, comp, usize = struct.unpack_from("<HHI", data, pos)
        hlen = 8
        size = usize
        if comp != 0:
            (size,) = struct.unpack_from("<I", data, pos + 8)
            hlen = 12
        plen = {5: 6}.get(btype, 2)
        end = pos + hlen + plen + size
        if end + 4 > len(data):
            fail("block at %d runs past the end of the file" % pos)
        (crc,) = struct.unpack_from("<I", data, end)
        if zlib.crc32(data[pos:end]) != crc:
            fail("CRC32 mismatch in block at %d" % pos)
        blocks.append((btype, comp, usize, data[pos + hlen:pos + hlen + plen], data[pos + hlen + plen:end]))
        pos = end + 4
    return blocks


def check_layout(blocks):
    types = "".join("FGSRPT"[b[0]] if b[0] < 6 else "?" for b in blocks)
    if not re.fullmatch(r"F?RT*PSG+", types):
        fail("block order %s (want F?RT*PSG+; F file, R printer, T thumbnail, P print, S slicer, G G-code)" % types)
    for btype, comp, _, params, _ in blocks:
        if btype in (0, 3, 4, 5) and comp != 0:
            fail("block type %d compressed (%d); the firmware reads these uncompressed" % (btype, comp))
        if btype == 2 and comp not in (0, 1):
            fail("slicer metadata compression %d" % comp)
        if btype == 1 and (comp != 3 or params != b"\x02\x00"):
            fail("G-code block compression %d params %s (want 3, MeatPack with comments)" % (comp, params.hex()))
        if btype in (0, 2, 3, 4) and params != b"\x00\x00":
            fail("metadata encoding %s (want INI)" % params.hex())
    return types


def read_block(path, block_type, cls):
    """Reads the first block of a type with pybgcode; returns the block object or None."""
    f = pybgcode.open(path, "rb")
    try:
        _, header = pybgcode.get_header(f)
        bh = pybgcode.get_block_header(f, header, block_type)
        if bh is None:
            return None
        block = cls()
        res = block.read_data(f, header, bh)
        if res != pybgcode.EResult.Success:
            fail("pybgcode could not read block type %s: %s" % (block_type, pybgcode.translate_result(res)))
        return block
    finally:
        pybgcode.close(f)


def to_ascii(path):
    fd, out_path = tempfile.mkstemp(suffix=".gcode")
    os.close(fd)
    try:
        src = pybgcode.open(path, "rb")
        dst = pybgcode.open(out_path, "wb")
        res = pybgcode.from_binary_to_ascii(src, dst, True)
        pybgcode.close(src)
        pybgcode.close(dst)
        if res != pybgcode.EResult.Success:
            fail("pybgcode could not convert: " + pybgcode.translate_result(res))
        with open(out_path, "rb") as fh:
            return fh.read().decode("utf-8")
    finally:
        os.unlink(out_path)


def meta_lines(pairs):
    return "".join("; %s = %s\n" % (k, v) for k, v in pairs)


def converter_keeps(line):
    """libbgcode's converter drops lines that are blank or only ';' and blanks."""
    t = line.strip(BLANKS)
    if t.startswith(";"):
        t = t[1:].strip(BLANKS)
    return t != ""


def normalise(text):
    """The G-code text libbgcode's reader gives back for `text` after weft's MeatPack encoding."""
    out = []
    for line in text.split("\n"):
        if line.startswith(";"):
            res = line
        elif line == "" or line.startswith("\r"):
            continue
        else:
            code = line.split(";", 1)[0].strip(BLANKS)
            if not code:
                continue
            if code[0] == "G" and len(code) > 1 and "0" <= code[1] <= "9":
                code = "".join(c.upper() if c in "exg" else c for c in code if c not in BLANKS)
            res = code
            if code[0] == "G":  # the reader re-spaces every line that starts with 'G'
                res = "G"
                for c in code[1:]:
                    if c in G_PARAMS and res[-1] != " ":
                        res += " "
                    res += c
        if converter_keeps(res):
            out.append(res + "\n")
    return "".join(out)


def decode(path, pngs=()):
    """Checks the container and the thumbnails; returns (G-code text libbgcode decodes, block type string, thumbnails)."""
    with open(path, "rb") as fh:
        data = fh.read()
    types = check_layout(walk_blocks(data))

    # Metadata and thumbnails as libbgcode reads them.
    file_md = read_block(path, pybgcode.EBlockType.FileMetadata, pybgcode.FileMetadataBlock)
    printer = read_block(path, pybgcode.EBlockType.PrinterMetadata, pybgcode.PrinterMetadataBlock)
    prnt = read_block(path, pybgcode.EBlockType.PrintMetadata, pybgcode.PrintMetadataBlock)
    slicer = read_block(path, pybgcode.EBlockType.SlicerMetadata, pybgcode.SlicerMetadataBlock)
    f = pybgcode.open(path, "rb")
    thumbs = pybgcode.read_thumbnails(f)
    pybgcode.close(f)
    for i, t in enumerate(thumbs):
        img = bytes(t["bytes"])
        fmt = int(t["meta"].format)
        if fmt == int(pybgcode.EThumbnailFormat.PNG):
            if img[:8] != b"\x89PNG\r\n\x1a\n" or img[12:16] != b"IHDR":
                fail("thumbnail %d is marked PNG and is not one" % i)
            w, h = struct.unpack(">II", img[16:24])
        elif fmt == int(pybgcode.EThumbnailFormat.QOI):
            if img[:4] != b"qoif":
                fail("thumbnail %d is marked QOI and is not one" % i)
            w, h = struct.unpack(">II", img[4:12])
        else:
            fail("thumbnail %d has format %d (weft writes PNG and QOI)" % (i, fmt))
        if (w, h) != (t["meta"].width, t["meta"].height):
            fail("thumbnail %d is %dx%d, its block says %dx%d" % (i, w, h, t["meta"].width, t["meta"].height))
    if pngs:
        if len(pngs) != len(thumbs):
            fail("%d thumbnails in the file, %d given" % (len(thumbs), len(pngs)))
        for i, p in enumerate(pngs):
            with open(p, "rb") as fh:
                if fh.read() != bytes(thumbs[i]["bytes"]):
                    fail("thumbnail %d differs from %s" % (i, p))

    # Head and tail of libbgcode's ASCII rendering, rebuilt from those blocks.
    head = ""
    if file_md is not None:
        kv = dict(file_md.raw_data)
        producer = kv.get("Producer", "Unknown")
        if "Produced on" in kv:
            producer += " on " + kv["Produced on"]
        if "Prepared by" in kv:
            producer += "\n; prepared by " + kv["Prepared by"]
        head += "; generated by " + producer + "\n\n\n"
    head += meta_lines(printer.raw_data)
    for t in thumbs:
        enc = base64.b64encode(bytes(t["bytes"])).decode("ascii")
        tag = "thumbnail_QOI" if int(t["meta"].format) == int(pybgcode.EThumbnailFormat.QOI) else "thumbnail"
        head += "\n;\n; %s begin %dx%d %d\n" % (tag, t["meta"].width, t["meta"].height, len(enc))
        head += "".join("; %s\n" % enc[i:i + 78] for i in range(0, len(enc), 78))
        head += "; %s end\n;\n" % tag
    head += "\n"
    tail = "\n" + meta_lines(prnt.raw_data)
    if slicer is not None:
        tail += "\n; prusaslicer_config = begin\n" + meta_lines(slicer.raw_data) + "; prusaslicer_config = end\n\n"

    text = to_ascii(path)
    if not text.startswith(head):
        fail("libbgcode's ASCII does not start with the expected metadata/thumbnail head")
    if not text.endswith(tail) or len(text) < len(head) + len(tail):
        fail("libbgcode's ASCII does not end with the expected print/slicer metadata tail")
    return text[len(head):len(text) - len(tail)], types, thumbs, len(data)


def compare(got, want):
    if got != want:
        g, w = got.split("\n"), want.split("\n")
        for i in range(max(len(g), len(w))):
            a = g[i] if i < len(g) else "<end>"
            b = w[i] if i < len(w) else "<end>"
            if a != b:
                fail("G-code differs at decoded line %d: got %r, want %r" % (i + 1, a, b))
        fail("G-code differs")


def split_thumbnails(text):
    """The text without its `; thumbnail[_QOI] begin WxH LEN` … `; thumbnail[_QOI] end` blocks, and their images."""
    out, pngs, b64, tag = [], [], None, None
    for line in text.split("\n"):
        if b64 is not None:
            if line.strip() == "; %s end" % tag:
                pngs.append(base64.b64decode("".join(b64)))
                b64 = None
            else:
                b64.append(line.lstrip(";").strip())
            continue
        m = re.match(r"^; (thumbnail|thumbnail_QOI) begin \d+x\d+ \d+$", line)
        if m:
            b64, tag = [], m.group(1)
            continue
        out.append(line)
    return "\n".join(out), pngs


def main():
    if len(sys.argv) < 3:
        print(__doc__.split("\n\n")[1])
        sys.exit(2)
    path, original_path, pngs = sys.argv[1], sys.argv[2], list(sys.argv[3:])
    with open(original_path, "rb") as fh:
        original = fh.read().decode("utf-8")
    # A text file with thumbnail blocks (weft's own, PrusaSlicer's): the blocks are the binary
    # file's thumbnail blocks, so they leave the text and their PNGs are what the thumbnails
    # must equal.
    original, embedded = split_thumbnails(original)
    if embedded and not pngs:
        tmp = tempfile.mkdtemp()
        for i, png in enumerate(embedded):
            p = os.path.join(tmp, "thumb%d.png" % i)
            with open(p, "wb") as fh:
                fh.write(png)
            pngs.append(p)
    got, types, thumbs, size = decode(path, pngs)
    compare(got, normalise(original))

    orig_lines = original.split("\n")
    if orig_lines and orig_lines[-1] == "":
        orig_lines.pop()
    same = sum(1 for line in orig_lines if normalise(line + "\n") == line + "\n")
    n = len(original.encode("utf-8"))
    print(
        "check_bgcode: OK: %s: %d B G-code -> %d B (%.3f), %d G-code blocks, %d thumbnails; "
        "decoded G-code = original after MeatPack normalisation (%d of %d lines byte-identical, rest normalised)"
        % (os.path.basename(path), n, size, size / max(1, n), types.count("G"), len(thumbs), same, len(orig_lines))
    )


if __name__ == "__main__":
    main()

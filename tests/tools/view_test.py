#!/usr/bin/env python3
"""palpable view in a real browser (headless chromium): the page loads with no error, and a
screenshot at a given instant shows the followed body where the camera puts it (the centre of the
screen) and the background elsewhere. Usage: view_test.py PALPABLE SCENARIOS_DIR CHROMIUM"""
import os
import struct
import subprocess
import sys
import tempfile
import zlib


def read_png(path):
    """Width, height and RGB rows of a non-interlaced 8-bit RGB or RGBA PNG (stdlib only)."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            width, height, depth, ctype = struct.unpack(">IIBB", chunk[:10])
            assert depth == 8 and ctype in (2, 6), "unsupported PNG"
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += chunk
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = width * bpp
    rows, prev = [], bytearray(stride)
    for y in range(height):
        ftype, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if ftype == 1: line[i] = (line[i] + a) & 255
            elif ftype == 2: line[i] = (line[i] + b) & 255
            elif ftype == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif ftype == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[x * bpp:x * bpp + 3]) for x in range(width)])
        prev = line
    return width, height, rows


def saturation(rgb):
    return max(rgb) - min(rgb)


def main():
    palpable, scenes, chromium = sys.argv[1:4]
    work = tempfile.mkdtemp()
    trace, page, shot = (os.path.join(work, n) for n in ("t.csv", "v.html", "s.png"))
    subprocess.run([palpable, "run", os.path.join(scenes, "sphere_slide_to_roll.json"),
                    "--trace", trace], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([palpable, "view", trace, "--scene", os.path.join(scenes, "sphere_slide_to_roll.json"),
                    "--out", page], check=True, stderr=subprocess.DEVNULL)
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--use-gl=swiftshader",
             "--enable-unsafe-swiftshader", "--window-size=640,480"]
    url = "file://" + page + "#t=0.5&follow=ball"
    dom = subprocess.run([chromium] + flags + ["--virtual-time-budget=3000", "--dump-dom", url],
                         capture_output=True, text=True, timeout=120).stdout
    ok = True
    if '<div id="status">ready</div>' not in dom:
        print("FAIL the page did not report ready:", dom[dom.find('id="status"'):][:120])
        ok = False
    else:
        print("ok   the page loads and renders with no error")
    subprocess.run([chromium] + flags + ["--screenshot=" + shot, url], capture_output=True, timeout=120)
    w, h, rows = read_png(shot)
    centre = rows[h // 2][w // 2]
    corner = rows[h - 5][5]
    print("     centre pixel", centre, "corner pixel", corner)
    # The followed ball is at the centre: a saturated colour; the corner is the grey table or the
    # pale background.
    if saturation(centre) < 60:
        print("FAIL no body at the centre of the screen where the camera follows it"); ok = False
    else:
        print("ok   the followed body is drawn where the trace puts it")
    if saturation(corner) > 30:
        print("FAIL the corner is not background"); ok = False
    else:
        print("ok   background where there is no body")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

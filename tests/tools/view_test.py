#!/usr/bin/env python3
"""palpable view in a real browser (headless chromium).

1. The page loads with no error: --dump-dom shows status "ready" and no error flag (the page sets
   one on any error or console.error), and chromium's log (--enable-logging=stderr) has no console
   message. Checked to fail on a copy of the page with an injected console.error.
2. Screenshots at given instants, arrows and marks off (#arrows=0&marks=0): each dynamic body's
   centre, projected with the page's own camera (read from the DOM), shows that body's colour, and
   pixels away from every body show no body's colour. Checked to fail: the same test run against
   the bodies' positions at another instant must find mismatches.

Usage: view_test.py PALPABLE SCENARIOS_DIR CHROMIUM"""
import colorsys
import html
import json
import math
import os
import re
import struct
import subprocess
import sys
import tempfile
import zlib

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--use-gl=swiftshader",
         "--enable-unsafe-swiftshader", "--window-size=1200,900", "--virtual-time-budget=5000"]


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


def hue(rgb):
    return colorsys.rgb_to_hsv(*(c / 255.0 for c in rgb))[0] * 360.0


def hue_distance(a, b):
    d = abs(a - b) % 360.0
    return min(d, 360.0 - d)


def load(chromium, url):
    """The page's DOM and chromium's log after loading url."""
    run = subprocess.run([chromium] + FLAGS + ["--enable-logging=stderr", "--v=0", "--dump-dom", url],
                         capture_output=True, text=True, timeout=180)
    return run.stdout, run.stderr


def load_errors(chromium, url):
    """What is wrong with loading the page: an empty list when it loads cleanly."""
    dom, log = load(chromium, url)
    errors = []
    if '<div id="status">ready</div>' not in dom:
        errors.append("status is not ready: " + dom[dom.find('id="status"'):][:160])
    if "data-error" in dom:
        errors.append("error flag set: " + dom[dom.find("data-error"):][:160])
    errors += ["console: " + line for line in log.splitlines() if ":CONSOLE(" in line or "Uncaught" in line]
    return errors


def probe(dom):
    """The camera and body centres the page wrote into <pre id="probe">."""
    m = re.search(r'<pre id="probe">(.*?)</pre>', dom, re.S)
    assert m, "no probe in the page"
    return json.loads(html.unescape(m.group(1)))


def project(p, cam, width, height):
    """Pixel (x, y), depth and pixels per metre of world point p for three.js' camera."""
    eye, target, up = cam["position"], cam["target"], cam["up"]
    sub = lambda a, b: [a[i] - b[i] for i in range(3)]
    dot = lambda a, b: sum(a[i] * b[i] for i in range(3))
    cross = lambda a, b: [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    unit = lambda a: [x / math.sqrt(dot(a, a)) for x in a]
    forward = unit(sub(target, eye))
    right = unit(cross(forward, up))
    upward = cross(right, forward)
    d = sub(p, eye)
    z = dot(d, forward)
    half = math.tan(math.radians(cam["fov"]) / 2)
    x = dot(d, right) / (z * half * cam["aspect"])
    y = dot(d, upward) / (z * half)
    return (x + 1) / 2 * width, (1 - y) / 2 * height, z, height / 2 / (z * half)


def check_bodies(rows, info, centres):
    """Checks the screenshot against body centres (name -> world point). Returns (checked, failures)."""
    width, height, cam = info["width"], info["height"], info["camera"]
    bodies = {b["name"]: b for b in info["bodies"] if b["motion"] == "dynamic"}
    discs = {}
    for name, b in bodies.items():
        x, y, z, scale = project(centres[name], cam, width, height)
        discs[name] = (x, y, z, b["radius"] * scale)
    checked, failures = 0, []
    for name, (x, y, z, r) in discs.items():
        # Bodies drawn big enough to hit, inside the picture, whose centre no nearer body hides.
        if z <= 0 or r < 4 or not (r < x < width - r and r < y < height - r):
            continue
        if any(o != name and oz < z and math.hypot(x - ox, y - oy) < orr + 2
               for o, (ox, oy, oz, orr) in discs.items()):
            continue
        pixel = rows[int(y)][int(x)]
        checked += 1
        want = hue(bodies[name]["colour"])
        if saturation(pixel) < 40 or hue_distance(hue(pixel), want) > 20:
            failures.append("%s at pixel (%d, %d): %s, expected hue %.0f" % (name, x, y, pixel, want))
    # Away from every body (3 radii from every disc): no body's colour there.
    away = 0
    for py in range(10, height - 10, 37):
        for px in range(10, width - 10, 41):
            if any(math.hypot(px - x, py - y) < 3 * r + 4 for (x, y, z, r) in discs.values()):
                continue
            if any(l - 2 <= px <= r + 2 and t - 2 <= py <= b + 2 for (l, t, r, b) in info["overlays"]):
                continue  # the panel and the legend
            away += 1
            pixel = rows[py][px]
            if saturation(pixel) > 40:
                failures.append("pixel (%d, %d) away from every body is %s" % (px, py, pixel))
    return checked, away, failures


def screenshot_test(palpable, chromium, work, scene_path, t, least, fragment=""):
    name = os.path.splitext(os.path.basename(scene_path))[0]
    trace, events, page, shot = (os.path.join(work, name + n) for n in (".csv", "_ev.csv", ".html", ".png"))
    subprocess.run([palpable, "run", scene_path, "--trace", trace, "--events", events],
                   check=True, stdout=subprocess.DEVNULL)
    subprocess.run([palpable, "view", trace, "--scene", scene_path, "--events", events, "--out", page],
                   check=True, stderr=subprocess.DEVNULL)
    # A fixed picture size: --dump-dom's window is shorter than --screenshot's.
    fragment += "&size=1200x900"
    url = "file://%s#t=%s&arrows=0&marks=0%s" % (page, t, fragment)
    info = probe(load(chromium, url)[0])
    subprocess.run([chromium] + FLAGS + ["--screenshot=" + shot, url], capture_output=True, timeout=180)
    w, h, rows = read_png(shot)
    assert (w, h) == (info["width"], info["height"]), "screenshot %dx%d, page %dx%d" % (w, h, info["width"], info["height"])
    centres = {b["name"]: b["centre"] for b in info["bodies"]}
    checked, away, failures = check_bodies(rows, info, centres)
    ok = True
    label = "%s at t = %s s" % (name, t)
    if failures or checked < least or away < 20:
        print("FAIL %s: %d bodies and %d background pixels checked (want >= %d, >= 20)" % (label, checked, away, least))
        for f in failures[:10]:
            print("     " + f)
        ok = False
    else:
        print("ok   %s: %d bodies where the trace puts them, %d pixels away from them free of body colours"
              % (label, checked, away))
    # The check must be able to fail: the bodies where they were at the start (or, for one body,
    # moved by four of its radii) are not where the picture shows them.
    first = {b["name"]: b for b in probe(load(chromium, "file://%s#t=0&arrows=0&marks=0%s" % (page, fragment))[0])["bodies"]}
    wrong = {}
    for b in info["bodies"]:
        c = first[b["name"]]["centre"]
        if math.dist(c, b["centre"]) < 2 * b["radius"]:
            c = [b["centre"][0] + 4 * b["radius"], b["centre"][1] + 4 * b["radius"], b["centre"][2]]
        wrong[b["name"]] = c
    _, _, wrong_failures = check_bodies(rows, info, wrong)
    if not wrong_failures:
        print("FAIL %s: the check did not notice bodies drawn at wrong positions" % label)
        ok = False
    else:
        print("ok   %s: wrong positions are noticed (%d mismatches)" % (label, len(wrong_failures)))
    return ok, page


def main():
    palpable, scenes, chromium = sys.argv[1:4]
    work = tempfile.mkdtemp()
    ok = True
    good, page = screenshot_test(palpable, chromium, work, os.path.join(scenes, "pool_break.json"), 0.4, 5)
    ok &= good
    good, _ = screenshot_test(palpable, chromium, work, os.path.join(scenes, "sphere_slide_to_roll.json"), 0.5, 1,
                              "&follow=ball")
    ok &= good
    errors = load_errors(chromium, "file://" + page)
    if errors:
        print("FAIL the page does not load cleanly:\n     " + "\n     ".join(errors[:10]))
        ok = False
    else:
        print("ok   the page loads with no error and nothing on the console")
    broken = os.path.join(work, "broken.html")
    with open(page) as f, open(broken, "w") as g:
        g.write(f.read().replace("</body>", "<script>console.error('injected')</script></body>"))
    if not load_errors(chromium, "file://" + broken):
        print("FAIL an injected console.error went unnoticed")
        ok = False
    else:
        print("ok   an injected console.error is noticed")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

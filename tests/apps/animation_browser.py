#!/usr/bin/env python3
"""animation.html in a real browser (Debian's chromium, headless): the page of the paper scene
loads with no console message and no script error, and its screenshots at t = 0.2 s and 1.5 s
both show the four links (their colours) and differ where the linkage moved; an odd run (elbow
down, no friction, gravity or loads, 2 frames) loads without error too; so does a four-bar's
page, showing its crank, coupler and rocker.

Usage: animation_browser.py FIVEBAR PAPER_YAML WORK_DIR
Exits 77 (ctest: skipped) when no chromium is installed (scripts/test.sh installs it).
"""
import os
import re
import shutil
import struct
import subprocess
import sys
import zlib

FIVEBAR, PAPER, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if CHROMIUM is None:
    print("chromium not installed: skipped (scripts/test.sh installs it)")
    sys.exit(77)
LINK_COLOURS = {"crank O-B": (0x1f, 0x77, 0xb4), "crank D0-D": (0xff, 0x7f, 0x0e),
                "coupler B-C": (0x2c, 0xa0, 0x2c), "coupler D-C": (0x94, 0x67, 0xbd)}
failures = []


def chromium(url, *args):
    """stdout and stderr of one headless chromium run on `url`."""
    profile = os.path.join(WORK, "profile")
    p = subprocess.run([CHROMIUM, "--headless", "--disable-gpu", "--no-sandbox",
                        "--user-data-dir=" + profile, "--enable-logging=stderr", "--v=0",
                        "--window-size=1000,760"] + list(args) + [url],
                       capture_output=True, text=True, timeout=180)
    return p.stdout, p.stderr


def png_pixels(path):
    """(width, height, rows of (r, g, b)) of an 8-bit RGB or RGBA, non-interlaced PNG."""
    data = open(path, "rb").read()
    pos, idat, width, height, channels = 8, b"", 0, 0, 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, ctype = struct.unpack(">IIBB", chunk[:10])
            assert depth == 8 and ctype in (2, 6) and chunk[12] == 0, "unsupported PNG"
            channels = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += chunk
        pos += 12 + length
    raw, stride, rows, prev = zlib.decompress(idat), width * channels, [], bytearray(width * channels)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - channels] if x >= channels else 0
            b, c = prev[x], prev[x - channels] if x >= channels else 0
            if f == 1: line[x] = (line[x] + a) & 255
            elif f == 2: line[x] = (line[x] + b) & 255
            elif f == 3: line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[i:i + 3]) for i in range(0, stride, channels)])
        prev = line
    return width, height, rows


def colour_pixels(rows, colour):
    """Positions of the pixels within 30 of `colour` in each channel."""
    return {(x, y) for y, row in enumerate(rows) for x, px in enumerate(row)
            if all(abs(px[i] - colour[i]) <= 30 for i in range(3))}


os.makedirs(WORK, exist_ok=True)
run = os.path.join(WORK, "paper")
p = subprocess.run([FIVEBAR, "simulate", PAPER, "--out", run, "--no-plots"], capture_output=True, text=True)
if p.returncode != 0:
    print("simulate failed:", p.stderr)
    sys.exit(1)
url = "file://" + os.path.abspath(os.path.join(run, "animation.html"))

dom, log = chromium(url + "#t=0.2", "--dump-dom")
status = re.search(r'<body data-status="([^"]*)"', dom)
if status is None or status.group(1) != "ok":
    failures.append("page status %r (expected ok)" % (status.group(1) if status else None))
console = [l for l in log.splitlines() if ":CONSOLE" in l]
if console:
    failures.append("console messages: %s" % console)

shots = {}
for t in ("0.2", "1.5"):
    png = os.path.join(WORK, "t%s.png" % t)
    if os.path.exists(png):
        os.remove(png)
    chromium(url + "#t=" + t, "--screenshot=" + png)
    if not os.path.exists(png):
        failures.append("no screenshot at t = %s" % t)
        continue
    _, _, rows = png_pixels(png)
    shots[t] = {name: colour_pixels(rows, c) for name, c in LINK_COLOURS.items()}
    for name, pixels in shots[t].items():
        if len(pixels) < 300:  # the legend's sample line alone has about 160
            failures.append("t = %s: %s: %d pixels of its colour" % (t, name, len(pixels)))
if len(shots) == 2:
    moved = len(shots["0.2"]["coupler B-C"] ^ shots["1.5"]["coupler B-C"])
    if moved < 500:
        failures.append("the coupler B-C moved over %d pixels between t = 0.2 and 1.5 s" % moved)
    print("coupler B-C pixels at 0.2 s: %d, at 1.5 s: %d, changed: %d"
          % (len(shots["0.2"]["coupler B-C"]), len(shots["1.5"]["coupler B-C"]), moved))

# an odd run: elbow down with other link lengths, no friction, no gravity, no loads (F arrow of
# length 0, every friction power 0), 1 ms (2 frames): still drawn with no error
odd = os.path.join(WORK, "odd")
sets = ["mechanism.assembly=elbow_down", "mechanism.links.0.length=0.12",
        "mechanism.links.2.length=0.3", "friction.model=none", "gravity=0", "loads.M1=0",
        "loads.M2=0", "loads.M3=0", "loads.F=0", "simulation.duration=0.001"]
p = subprocess.run([FIVEBAR, "simulate", PAPER, "--out", odd, "--no-plots"]
                   + [a for s in sets for a in ("--set", s)], capture_output=True, text=True)
if p.returncode != 0:
    failures.append("simulate of the odd run failed: %s" % p.stderr)
else:
    dom, log = chromium("file://" + os.path.abspath(os.path.join(odd, "animation.html")),
                        "--dump-dom")
    status = re.search(r'<body data-status="([^"]*)"', dom)
    if status is None or status.group(1) != "ok":
        failures.append("odd run: page status %r" % (status.group(1) if status else None))
    if "no joint dissipates friction power" not in dom:
        failures.append("odd run: the note does not say that no friction power is dissipated")
    console = [l for l in log.splitlines() if ":CONSOLE" in l]
    if console:
        failures.append("odd run: console messages: %s" % console)

# a four-bar (datasets/reference/four_bar/crank_rocker.yaml): its three links in their colours
four_bar = os.path.join(os.path.dirname(os.path.abspath(PAPER)), "..", "reference", "four_bar",
                        "crank_rocker.yaml")
run = os.path.join(WORK, "crank_rocker")
p = subprocess.run([FIVEBAR, "simulate", four_bar, "--out", run, "--no-plots"],
                   capture_output=True, text=True)
if p.returncode != 0:
    failures.append("simulate of the four-bar failed: %s" % p.stderr)
else:
    url = "file://" + os.path.abspath(os.path.join(run, "animation.html"))
    dom, log = chromium(url + "#t=0.5", "--dump-dom")
    status = re.search(r'<body data-status="([^"]*)"', dom)
    if status is None or status.group(1) != "ok":
        failures.append("four-bar: page status %r" % (status.group(1) if status else None))
    console = [l for l in log.splitlines() if ":CONSOLE" in l]
    if console:
        failures.append("four-bar: console messages: %s" % console)
    png = os.path.join(WORK, "four_bar.png")
    if os.path.exists(png):
        os.remove(png)
    chromium(url + "#t=0.5", "--screenshot=" + png)
    if not os.path.exists(png):
        failures.append("four-bar: no screenshot")
    else:
        _, _, rows = png_pixels(png)
        for name, colour in (("crank O-B", LINK_COLOURS["crank O-B"]),
                             ("coupler B-C", LINK_COLOURS["coupler B-C"]),
                             ("rocker D0-C", LINK_COLOURS["crank D0-D"])):
            count = len(colour_pixels(rows, colour))
            print("four-bar: %s: %d pixels" % (name, count))
            if count < 300:
                failures.append("four-bar: %s: %d pixels of its colour" % (name, count))

for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)

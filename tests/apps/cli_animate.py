#!/usr/bin/env python3
"""End-to-end checks of animation.html without a browser: simulate writes it, self-contained and
small; `fivebar animate` remakes it from a run folder, one per task of an optimize-like folder
(the baseline as the ghost when present), labels an inverse run as such, and refuses bad folders
(no run, a trajectory.csv without rows or cut short) with one line and exit 2.

Usage: cli_animate.py FIVEBAR PAPER_YAML WORK_DIR
"""
import json
import os
import re
import shutil
import sys

from cli_common import Cli

FIVEBAR, PAPER, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
cli = Cli(FIVEBAR)
failures, run = cli.failures, cli.run


def expect_error(pattern, args):
    cli.expect_error(2, pattern, args)


def page_data(path):
    """The JSON the page carries (between 'const DATA = ' and the line's ';')."""
    text = open(path).read()
    m = re.search(r"const DATA = (.*);\n", text)
    return text, json.loads(m.group(1))


def check_page(path, expect_ghost):
    text, data = page_data(path)
    size = os.path.getsize(path)
    if size > 1_000_000:
        failures.append("%s: %d bytes (a 2 s run at 1 kHz must stay under 1 MB)" % (path, size))
    # offline: no external script, style, font or image
    for pattern in (r"<script[^>]+src", r"<link", r"https?://", r"@import"):
        if re.search(pattern, text):
            failures.append("%s: references something outside the file (%s)" % (path, pattern))
    motion = data["motion"]
    n = len(motion["t"])
    if not 2 <= n <= 1000 or motion["samples"] != 2001:
        failures.append("%s: %d frames of %d samples (expected at most 1000 of 2001)"
                        % (path, n, motion["samples"]))
    if motion["t"][-1] != 2 or any(len(motion[k]) != n for k in ("th1", "p5", "stuck", "F", "E_diss")):
        failures.append("%s: frames do not end at t = 2 s or columns differ in length" % path)
    if (data["ghost"] is not None) != expect_ghost:
        failures.append("%s: ghost %s, expected %s" % (path, data["ghost"] is not None, expect_ghost))
    return data


os.makedirs(WORK, exist_ok=True)
paper = os.path.join(WORK, "paper")
code, out, err = run(["simulate", PAPER, "--out", paper, "--no-plots"])
if code != 0:
    print("simulate failed: %d %s" % (code, err))
    sys.exit(1)
written = check_page(os.path.join(paper, "animation.html"), False)
# the paper run at rest at t = 0: every joint stuck or at rest there, none stuck later on
if written["motion"]["stuck"][len(written["motion"]["stuck"]) // 2] != 0:
    failures.append("paper run: a joint marked stuck mid-run (the run never sticks)")

# `animate` from the folder: the scene named by summary.json, the same frames
os.remove(os.path.join(paper, "animation.html"))
code, out, err = run(["animate", paper])
if code != 0 or "animation.html" not in out:
    failures.append("animate %s: exit %d, %s %s" % (paper, code, out, err))
else:
    remade = check_page(os.path.join(paper, "animation.html"), False)
    if remade["motion"]["th3"] != written["motion"]["th3"] or remade["motion"]["p2"] != written["motion"]["p2"]:
        failures.append("animate: frames differ from those simulate wrote")
    # stuck read from the rates of trajectory.csv as the simulator's modes had it (the start
    # from rest, where every rate is 0 for one row, is no stick on the paper scene)
    if remade["motion"]["stuck"] != written["motion"]["stuck"]:
        failures.append("animate: stuck joints differ from simulate's (first frames %s, %s)"
                        % (remade["motion"]["stuck"][:3], written["motion"]["stuck"][:3]))

# stick-slip: the stick scene with a crank torque that grows past breakaway; the stuck joints read
# back from trajectory.csv's rates (an inner joint's within the integration's error of 0) are
# those the simulator's modes gave
slip = os.path.join(WORK, "stick_slip")
stick_scene = os.path.join(os.path.dirname(PAPER), "stick_below_breakaway.yaml")
code, out, err = run(["simulate", stick_scene, "--out", slip, "--no-plots",
                      "--set", "loads.M1=-1.3057 - 0.3*t"])
if code != 0:
    failures.append("simulate stick_slip: exit %d %s" % (code, err))
else:
    written_slip = page_data(os.path.join(slip, "animation.html"))[1]["motion"]["stuck"]
    code, out, err = run(["animate", slip])
    remade_slip = page_data(os.path.join(slip, "animation.html"))[1]["motion"]["stuck"]
    if len(set(written_slip)) < 3:
        failures.append("stick_slip: expected all-stuck, partly stuck and free frames, got %s"
                        % sorted(set(written_slip)))
    if code != 0 or remade_slip != written_slip:
        failures.append("stick_slip: animate's stuck joints differ from simulate's in %d frames"
                        % sum(a != b for a, b in zip(remade_slip, written_slip)))

# an optimize-like folder: two task folders, one with a baseline (the frictionless twin stands in)
tasks = os.path.join(WORK, "tasks")
shutil.rmtree(tasks, ignore_errors=True)
for task in ("with_baseline", "without_baseline"):
    os.makedirs(os.path.join(tasks, task))
    shutil.copy(os.path.join(paper, "trajectory.csv"), os.path.join(tasks, task))
shutil.copy(os.path.join(paper, "trajectory_frictionless.csv"),
            os.path.join(tasks, "with_baseline", "baseline.csv"))
expect_error("--scene", ["animate", tasks])  # no summary.json names the scene
code, out, err = run(["animate", tasks, "--scene", PAPER])
if code != 0 or "no minimum-jerk ghost" not in out:
    failures.append("animate %s --scene: exit %d, %s %s" % (tasks, code, out, err))
else:
    check_page(os.path.join(tasks, "with_baseline", "animation.html"), True)
    check_page(os.path.join(tasks, "without_baseline", "animation.html"), False)

# bad input: one line, exit 2, no page written
expect_error("not a directory", ["animate", os.path.join(WORK, "missing")])
empty = os.path.join(WORK, "empty")
os.makedirs(empty, exist_ok=True)
expect_error("trajectory.csv", ["animate", empty])
os.remove(os.path.join(tasks, "without_baseline", "animation.html"))
expect_error("does not close", ["animate", tasks, "--scene", PAPER,
                                "--set", "mechanism.links.2.length=0.3"])
if os.path.exists(os.path.join(tasks, "without_baseline", "animation.html")):
    failures.append("a refused animate wrote a page")

# a run folder whose trajectory.csv lost its rows (header only) or its tail (cut mid-line):
# refused, and the page from before is left as it was
broken = os.path.join(WORK, "broken")
shutil.rmtree(broken, ignore_errors=True)
shutil.copytree(paper, broken)
page = os.path.join(broken, "animation.html")
before = open(page).read()
lines = open(os.path.join(paper, "trajectory.csv")).read().split("\n")
with open(os.path.join(broken, "trajectory.csv"), "w") as f:
    f.write(lines[0] + "\n")
expect_error("no data rows", ["animate", broken])
with open(os.path.join(broken, "trajectory.csv"), "w") as f:
    f.write("\n".join(lines[:40]) + "\n" + lines[40][:25])
expect_error("trajectory.csv: line 41", ["animate", broken])
if open(page).read() != before:
    failures.append("a refused animate changed the page of %s" % broken)

# an inverse run: the page names it as inverse dynamics, not as a simulation
inverse = os.path.join(WORK, "inverse")
code, out, err = run(["inverse", PAPER, "--motion", os.path.join(paper, "trajectory.csv"),
                      "--out", inverse, "--no-plots"])
code2, out2, err2 = run(["animate", inverse])
if code != 0 or code2 != 0:
    failures.append("inverse then animate: exit %d, %d: %s %s" % (code, code2, err, err2))
elif page_data(os.path.join(inverse, "animation.html"))[1]["label"] != "inverse dynamics":
    failures.append("animate of an inverse run: not labelled 'inverse dynamics'")

for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)

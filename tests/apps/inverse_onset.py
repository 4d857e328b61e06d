#!/usr/bin/env python3
"""End-to-end check (ctest apps.inverse_onset): a pose held still, then a quintic move, then held
again, given as angles only. The 5-point rates overshoot by ~3e-6 rad/s on the row before the
move starts; that row must still read as at rest and carry the equilibrium torque inside its
holding range. Usage: inverse_onset.py FIVEBAR SCENE WORKDIR"""
import csv
import os
import subprocess
import sys

from cli_common import write_hold_move

fivebar, scene, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
motion = os.path.join(work, "holdmove.csv")
write_hold_move(motion)
out = os.path.join(work, "out")
subprocess.run([fivebar, "inverse", scene, "--motion", motion, "--out", out, "--no-plots"],
               check=True, stdout=subprocess.DEVNULL)
rows = {round(float(r["t"]), 6): r for r in csv.DictReader(open(os.path.join(out, "trajectory.csv")))}
failures = []
for t in (0.498, 0.499, 1.001, 1.002):
    r = rows[t]
    M1, lo, hi = float(r["M1"]), float(r["M1_hold_min"]), float(r["M1_hold_max"])
    if r["at_rest"] != "1" or not (lo <= M1 <= hi):
        failures.append("t=%g: at_rest %s, M1 %g outside [%g, %g]" % (t, r["at_rest"], M1, lo, hi))
if abs(float(rows[0.499]["M1"]) - float(rows[0.0]["M1"])) > 1e-9:
    failures.append("t=0.499: M1 differs from the held pose's equilibrium")
if failures:
    print("\n".join(failures))
    sys.exit(1)
print("1 passed, 0 failed")

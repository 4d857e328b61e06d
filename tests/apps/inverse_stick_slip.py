#!/usr/bin/env python3
"""End-to-end check (ctest apps.inverse_stick_slip): a Stribeck five-bar started from rest sticks
and slips, its passive joints held while a crank moves; `inverse` of the simulated motion gives
back every row's torques within its holding range (the simulator holds a stuck joint's rate
within its tolerance, and the holding torque of a passive joint is not fixed by the motion).
Usage: inverse_stick_slip.py FIVEBAR SCENE WORKDIR (SCENE unused: the scene is written here)"""
import csv
import json
import os
import subprocess
import sys

fivebar, _, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
scene = os.path.join(work, "sticky.yaml")
with open(scene, "w") as f:
    f.write("""mechanism:
  ground_length: 0.3
  links:
    - {length: 0.1, mass: 1.2, inertia: 0.02, com_offset: 0.05}
    - {length: 0.08, mass: 1.0, inertia: 0.015, com_offset: 0.04}
    - {length: 0.28, mass: 1.1, inertia: 0.03, com_offset: 0.14}
    - {length: 0.26, mass: 0.9, inertia: 0.025, com_offset: 0.13}
  point_p: 0.15
  assembly: elbow_down
gravity: 9.81
friction: {model: stribeck, pin_radius: 0.02, coulomb: 0.25, static_coulomb: 0.45, viscous: 0.02,
           stribeck_velocity: 0.1}
loads: {M1: "0.8*sin(2*t)", M2: "0.6*cos(1.5*t)", M3: "0", F: "5", F_angle: 0.5}
initial: {theta1: 1.5, theta2: 1.7, omega1: 0.0, omega2: 0.0}
simulation: {duration: 3.6, output_step: 0.001}
""")
run = os.path.join(work, "run")
inv = os.path.join(work, "inv")
for args in (["simulate", scene, "--out", run, "--no-plots"],
             ["inverse", scene, "--motion", os.path.join(run, "trajectory.csv"), "--out", inv,
              "--no-plots"]):
    subprocess.run([fivebar] + args, check=True, stdout=subprocess.DEVNULL)
summary = json.load(open(os.path.join(inv, "summary.json")))
failures = []
error = summary["inverse_dynamics_max_abs_error"]
if not error < 1e-9:
    failures.append("inverse_dynamics_max_abs_error %g N m (at most 1e-9)" % error)
passive = 0
for r in csv.DictReader(open(os.path.join(inv, "trajectory.csv"))):
    moving = r["stuck1"] != "1" or r["stuck5"] != "1"
    passive += moving and any(r["stuck%d" % k] == "1" for k in (2, 3, 4))
if passive < 100:
    failures.append("%d rows with a passive joint stuck while a crank moves (expected many)" % passive)
if failures:
    print("\n".join(failures))
    sys.exit(1)
print("1 passed, 0 failed (%d rows with a passive joint stuck, error %.3g N m)" % (passive, error))

#!/usr/bin/env python3
"""End-to-end check of identify's window rule on a log sampled too slowly for its motion.

Usage: cli_fast_design.py FIVEBAR PAPER_YAML WORK_DIR

excite designs a 4 s per-joint motion of a small five-bar at a 1.5 N m torque limit; synth-log
follows it at 1 kHz with 1e-5 rad of angle noise and no logged rates. No Savitzky-Golay window
estimates its accelerations without bias (the angle noise's through the reactions at the small
windows, the smoothing's at the large: the per-joint coefficients came out 4-35 std off with
status ok): identify --per-joint exits 3, the reason naming the motion too fast for the log's
rate and the advice to log the rates, and still writes its outputs (status failed).
"""
import json
import os
import shutil
import sys

from cli_common import Cli

FIVEBAR, PAPER, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
cli = Cli(FIVEBAR)
failures, run = cli.failures, cli.run

shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)

SCENE = """mechanism:
  ground_length: 0.22
  links:
    - {length: 0.09, mass: 0.6, inertia: 0.002, com_offset: 0.04, com_angle: 0.1}
    - {length: 0.07, mass: 0.5, inertia: 0.0015, com_offset: 0.03, com_angle: 0.0}
    - {length: 0.24, mass: 0.8, inertia: 0.005, com_offset: 0.12, com_angle: 0.05}
    - {length: 0.22, mass: 0.7, inertia: 0.004, com_offset: 0.10, com_angle: 0.0}
  point_p: 0.24
  assembly: elbow_up
gravity: 9.81
friction: {model: coulomb_viscous, pin_radius: 0.008, coulomb: 0.09, viscous: 0.015}
loads: {M1: "0.8 + 0.6*sin(5*pi*t)", M2: "0.5 + 0.5*cos(3*pi*t)", M3: "0.1", F: "3", F_angle: 1.5707963267948966}
initial: {theta1: 1.5707963267948966, theta2: 1.5707963267948966}
simulation: {duration: 2.0, output_step: 0.001}
"""
scene = os.path.join(WORK, "small.yaml")
with open(scene, "w") as f:
    f.write(SCENE)

design = os.path.join(WORK, "design")
code, _, err = run(["excite", scene, "--duration", "4", "--torque-limit", "1.5", "--per-joint",
                    "--out", design, "--no-plots"])
if code != 0:
    failures.append("excite: exit %d: %s" % (code, err))
log = os.path.join(WORK, "fast.csv")
code, _, err = run(["synth-log", scene, "--out", log, "--torque-noise", "0.02", "--angle-noise",
                    "1e-05", "--seed", "1", "--excitation", "scene", "--motion",
                    os.path.join(design, "excitation.csv")])
if code != 0:
    failures.append("synth-log: exit %d: %s" % (code, err))

out = os.path.join(WORK, "id")
code, _, err = run(["identify", scene, "--log", log, "--per-joint", "--out", out,
                    "--no-validation", "--no-plots"])
reason = err.strip().split("\n")[-1] if err.strip() else ""
if code != 3 or "too fast for accelerations estimated from its angles" not in reason \
        or "log the rates" not in reason:
    failures.append("per-joint fit of the fast design: exit %d (expected 3), last line %r"
                    % (code, reason))
try:
    with open(os.path.join(out, "identification.json")) as f:
        j = json.load(f)
    if j["status"] != "failed":
        failures.append("identification.json status %r (expected failed)" % j["status"])
except (OSError, ValueError, KeyError) as e:
    failures.append("identification.json not written: %s" % e)

for line in failures:
    print("FAIL:", line)
sys.exit(1 if failures else 0)

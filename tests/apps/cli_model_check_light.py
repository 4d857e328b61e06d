#!/usr/bin/env python3
"""End-to-end check of the five-bar identify's model check on a light mechanism's clean log.

Usage: cli_model_check_light.py FIVEBAR PAPER_YAML WORK_DIR

A light five-bar (links of 0.1-0.15 kg, no gravity, loads of 0.02 N m), 3 s at 1 kHz, angle noise
1e-5 rad, seed 1: the window rule chooses a half-window of 4 samples, where the estimated
accelerations' noise reaches the angle offsets' columns (d r / d theta holds the accelerations) as
it reaches the residual. Without that path in the score's expectation the clean log read the
encoders' zeros 0.079, -0.040 rad off (a fall of 92 against 2 +- 2 from noise alone) and exited 3.
The clean log: exit 0, no warning naming the encoders' zeros. Its theta1 +0.05 rad: exit 3, the
reason naming the logged angles' zeros.
"""
import os
import shutil
import sys

from cli_common import Cli, rewrite_log, zero

FIVEBAR, WORK = sys.argv[1], sys.argv[3]
cli = Cli(FIVEBAR)
failures = cli.failures

shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)

LINK = "    - {length: %g, mass: %g, inertia: %g, com_offset: %g, com_angle: 0.0}\n"
SCENE = os.path.join(WORK, "light.yaml")
with open(SCENE, "w") as f:
    f.write("mechanism:\n  ground_length: 0.15\n  links:\n" +
            LINK % (0.06, 0.1, 0.0001, 0.03) + LINK % (0.06, 0.1, 0.0001, 0.03) +
            LINK % (0.15, 0.15, 0.0003, 0.07) + LINK % (0.15, 0.15, 0.0003, 0.07) +
            "  point_p: 0.15\n  assembly: elbow_up\ngravity: 0\n"
            "friction: {model: coulomb_viscous, pin_radius: 0.004, coulomb: 0.12, "
            "viscous: 0.02}\n"
            "loads: {M1: \"0.02*sin(4*pi*t)\", M2: \"0.02*cos(3*pi*t)\", M3: \"0.001\", "
            "F: \"0.05\", F_angle: 1.5707963267948966}\n"
            "initial: {theta1: 1.5707963267948966, theta2: 1.5707963267948966}\n"
            "simulation: {duration: 2.0, output_step: 0.001}\n")

clean = os.path.join(WORK, "clean.csv")
code, _, err = cli.run(["synth-log", SCENE, "--out", clean, "--rate", "1000", "--duration", "3",
                        "--torque-noise", "0.02", "--angle-noise", "1e-05", "--seed", "1",
                        "--excitation", "scene"])
if code != 0:
    failures.append("synth-log: exit %d: %s" % (code, err))


def identify(name, log):
    return cli.identify(name, SCENE, log, os.path.join(WORK, "id_" + name),
                        ["--no-validation", "--no-plots"])


code, j = identify("clean", clean)
named = [w for w in j.get("warnings", []) if "encoder's zero" in w]
if code != 0 or j.get("status") != "ok" or named:
    failures.append("clean: exit %d, status %s, warnings %s (expected exit 0, no encoder named)"
                    % (code, j.get("status"), j.get("warnings")))

code, j = identify("zero", rewrite_log(clean, os.path.join(WORK, "zero.csv"), zero(0.05)))
reason = j.get("status_reason", "")
if code != 3 or "angles' zeros" not in reason:
    failures.append("zero: exit %d, reason %r (expected exit 3 naming the angles' zeros)"
                    % (code, reason))

for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)

#!/usr/bin/env python3
"""End-to-end checks of the actuator terms: scene section, synth-log, identify.

Usage: cli_actuator.py FIVEBAR PAPER_YAML WORK_DIR

synth-log writes a log whose tau1 sensor reads 0.05 N m high and whose motors have friction,
with the truth in its header; identify --estimate friction,actuator recovers the terms within
3.5 std and writes them to scene_fitted.yaml, which simulate and inverse read back; inverse of
the simulated motion returns the applied torques with the actuator friction on; bad input
exits 2 with one line.
"""
import json
import os
import shutil
import sys

from cli_common import Cli, read_csv

FIVEBAR, PAPER, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
cli = Cli(FIVEBAR)
failures, run, expect_error = cli.failures, cli.run, cli.expect_error


shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
log = os.path.join(WORK, "act.csv")
expect_error(2, "--torque-offset: expected two values", ["synth-log", PAPER, "--out", log, "--torque-offset", "0.05"])
expect_error(2, "--actuator-coulomb: must be >= 0",
             ["synth-log", PAPER, "--out", log, "--actuator-coulomb", "-0.1,0"])
expect_error(2, "actuators.M1.coulomb", ["simulate", PAPER, "--set", "friction.model=none",
                                          "--set", "actuators.M1.coulomb=0.1", "--out", os.path.join(WORK, "bad")])

code, out, err = run(["synth-log", PAPER, "--out", log, "--duration", "4", "--seed", "4", "--with-rates",
                      "--excitation", "multisine",
                      "--torque-offset", "0.05,0", "--actuator-coulomb", "0.02,0.02",
                      "--actuator-viscous", "0.001,0.001"])
if code != 0:
    failures.append("synth-log: exit %d %s" % (code, err))
with open(log) as f:
    header = [l for l in f if l.startswith("#")]
for want in ["true.offset = 0.05,0", "true.actuator_coulomb = 0.02,0.02", "true.actuator_viscous = 0.001,0.001"]:
    if not any(want in l for l in header):
        failures.append("header lacks '%s'" % want)

expect_error(2, "group actuator needs --method inverse-dynamics",
             ["identify", PAPER, "--log", log, "--estimate", "friction,actuator", "--method", "output-error",
              "--out", os.path.join(WORK, "bad")])
expect_error(2, "'actuators' is not a group",
             ["identify", PAPER, "--log", log, "--estimate", "friction,actuators", "--out", os.path.join(WORK, "bad")])

fit = os.path.join(WORK, "fit")
code, out, err = run(["identify", PAPER, "--log", log, "--estimate", "friction,actuator", "--out", fit,
                      "--no-plots", "--no-delay", "--no-validation"])
if code != 0:
    failures.append("identify: exit %d %s" % (code, err))
else:
    res = json.load(open(os.path.join(fit, "identification.json")))
    params = {p["name"]: p for p in res["parameters"]}
    for name in ["coulomb", "viscous", "offset_1", "offset_2", "actuator_coulomb_1", "actuator_coulomb_2",
                 "actuator_viscous_1", "actuator_viscous_2"]:
        p = params.get(name)
        if p is None or "true" not in p or p["std"] is None or abs(p["error_in_std"]) > 3.5:
            failures.append("%s: %r" % (name, p))
    fitted = open(os.path.join(fit, "scene_fitted.yaml")).read()
    if "actuators:\n  M1: {offset: " not in fitted:
        failures.append("scene_fitted.yaml has no actuators section:\n" + fitted)
    code, out, err = run(["simulate", os.path.join(fit, "scene_fitted.yaml"), "--out", os.path.join(WORK, "sim"),
                          "--set", "simulation.duration=0.2", "--no-plots"])
    if code != 0:
        failures.append("simulate scene_fitted.yaml: exit %d %s" % (code, err))

# inverse of a simulated motion with the actuator friction on returns the applied torques
sets = ["--set", "actuators.M1.coulomb=0.2", "--set", "actuators.M2.viscous=0.01", "--set",
        "simulation.duration=0.3"]
sim = os.path.join(WORK, "sim_act")
code, out, err = run(["simulate", PAPER, "--out", sim, "--no-plots"] + sets)
if code != 0:
    failures.append("simulate with actuators: exit %d %s" % (code, err))
else:
    inv = os.path.join(WORK, "inv")
    code, out, err = run(["inverse", PAPER, "--motion", os.path.join(sim, "trajectory.csv"), "--out", inv,
                          "--no-plots"] + sets)
    if code != 0:
        failures.append("inverse: exit %d %s" % (code, err))
    else:
        a, b = read_csv(os.path.join(sim, "trajectory.csv")), read_csv(os.path.join(inv, "trajectory.csv"))
        worst = max(abs(float(x["M1"]) - float(y["M1"])) for x, y in zip(a[5:-5], b[5:-5]))
        if not worst < 1e-3:
            failures.append("inverse of simulate: |M1 difference| up to %g N m" % worst)

for f in failures:
    print("FAIL:", f)
print("%d passed, %d failed" % (0 if failures else 1, len(failures)))
sys.exit(1 if failures else 0)

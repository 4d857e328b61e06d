#!/usr/bin/env python3
"""End-to-end checks of `fivebar simulate`, `inverse`, `identify` and `excite` on four-bar scenes.

Usage: cli_four_bar.py FIVEBAR PAPER_YAML WORK_DIR

The two scenes of datasets/reference/four_bar/ run with exit 0; their trajectory.csv has the
four-bar's columns and agrees with the independent reference trajectories (within 1e-7 rad and
the run's own error estimate); summary.json says ok. Bad input exits 2 with one line naming the
key and the mechanism type. accuracy's work-precision study runs on a four-bar, its own reference
within 1e-9 rad of the independent one.
synth-log writes a four-bar log of one crank; following the simulated motion it gives back M1.
identify fits a four-bar's log end to end (the true coefficients inside its intervals) and
refuses the five-bar's options and logs naming them; with the crank motor's terms (synth-log's
actuator options) it fits them with --estimate friction,actuator and does not use a fit
without them. A log whose torque has the opposite sign
gets the five-bar's sign check: exit 3 advising --flip-torque-sign 1, which then fits it; the
flip on a log that did not need it is advised away. excite designs a crank motion within its
limit that synth-log --motion follows, and refuses the five-bar's options naming them.
"""
import json
import math
import os
import re
import shutil
import subprocess
import sys

from cli_common import Cli, read_csv

FIVEBAR, PAPER, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
REFERENCE = os.path.join(os.path.dirname(os.path.abspath(PAPER)), "..", "reference", "four_bar")
TASKS = os.path.join(os.path.dirname(os.path.abspath(PAPER)), "..", "tasks", "four_bar_tasks.yaml")
cli = Cli(FIVEBAR)
failures, run, expect_error = cli.failures, cli.run, cli.expect_error


COLUMNS = (["t"] + ["%s%d" % (q, i) for q in ("theta", "omega", "alpha") for i in (1, 2, 3)] + ["M1"]
           + ["%s%d" % (q, k) for q in ("N", "Mf") for k in (1, 2, 3, 4)]
           + ["P_diss", "E_diss", "W_in", "W_ext"])

shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
for name in ("crank_rocker", "double_rocker"):
    scene = os.path.join(REFERENCE, name + ".yaml")
    out = os.path.join(WORK, name)
    code, stdout, err = run(["simulate", scene, "--out", out])
    if code != 0:
        failures.append("%s: exit %d: %s" % (name, code, err))
        continue
    if "four-bar" not in stdout:
        failures.append("%s: the report does not name the four-bar: %r" % (name, stdout))
    with open(os.path.join(out, "trajectory.csv")) as f:
        header = f.readline().strip().split(",")
    if header != COLUMNS + ["M1_inverse"]:
        failures.append("%s: columns %s" % (name, header))
    rows = read_csv(os.path.join(out, "trajectory.csv"))
    ref = read_csv(os.path.join(REFERENCE, name + ".csv"))
    if len(rows) != len(ref):
        failures.append("%s: %d rows against the reference's %d" % (name, len(rows), len(ref)))
        continue
    worst = max(abs(float(a["theta%d" % i]) - float(b["theta%d" % i]))
                for a, b in zip(rows, ref) for i in (1, 2, 3))
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    estimate = summary.get("estimated_max_error_rad")
    if summary.get("status") != "ok":
        failures.append("%s: summary status %r" % (name, summary.get("status")))
    if not worst < 1e-7:
        failures.append("%s: max |theta - reference| = %.3g rad" % (name, worst))
    if estimate is None or not worst < 3 * estimate + 1e-10:
        failures.append("%s: error %.3g rad beyond 3x the run's estimate %r" % (name, worst, estimate))
    power = min(float(r["Mf%d" % k]) * w for r in rows
                for k, w in zip((1, 2, 3, 4), (float(r["omega1"]), float(r["omega2"]) - float(r["omega1"]),
                                               float(r["omega3"]) - float(r["omega2"]), float(r["omega3"]))))
    if power < -1e-9:
        failures.append("%s: friction supplies power: %.3g W" % (name, power))
    print("%s: max |theta - reference| %.3g rad, estimate %.3g rad" % (name, worst, estimate or float("nan")))

# inverse of the simulated crank-rocker: the file carries the exact rates, so M1 comes back
scene = os.path.join(REFERENCE, "crank_rocker.yaml")
# synth-log: a four-bar's log has one crank; following the simulated motion without noise gives
# back the run's M1 (inverse of forward)
log = os.path.join(WORK, "crank_rocker_log.csv")
code, _, err = run(["synth-log", scene, "--out", log, "--duration", "1", "--with-rates"])
if code != 0:
    failures.append("synth-log: exit %d: %s" % (code, err))
else:
    with open(log) as f:
        header = next(line for line in f if not line.startswith("#")).strip()
    if header != "t,theta1,tau1,omega1,alpha1":
        failures.append("synth-log: header %r" % header)
followed = os.path.join(WORK, "followed.csv")
code, _, err = run(["synth-log", scene, "--out", followed, "--torque-noise", "0", "--angle-noise", "0",
                    "--motion", os.path.join(WORK, "crank_rocker", "trajectory.csv")])
if code != 0:
    failures.append("synth-log --motion: exit %d: %s" % (code, err))
else:
    sim = read_csv(os.path.join(WORK, "crank_rocker", "trajectory.csv"))
    worst = max(abs(float(a["tau1"]) - float(b["M1"])) for a, b in zip(read_csv(followed), sim))
    print("synth-log --motion: max |tau1 - M1| %.3g N m" % worst)
    if not worst <= 1e-9:
        failures.append("synth-log --motion: max |tau1 - M1| = %.3g N m" % worst)
# the run's figures and page, and `animate` on its folder (the scene from summary.json)
cr = os.path.join(WORK, "crank_rocker")
for name in ("fig2_angles.png", "fig5_inverse_torques.png", "fig6_friction_torques.png",
             "animation.html"):
    if not os.path.exists(os.path.join(cr, name)):
        failures.append("simulate of the four-bar wrote no %s" % name)
os.remove(os.path.join(cr, "animation.html"))
code, _, err = run(["animate", cr])
if code != 0 or not os.path.exists(os.path.join(cr, "animation.html")):
    failures.append("animate of the four-bar's folder: exit %d: %s" % (code, err))
expect_error(2, "mechanism: a four_bar run, and the scene", ["animate", cr, "--scene", PAPER])
expect_error(2, "column theta3: a four-bar's motion",
             ["synth-log", PAPER, "--out", os.path.join(WORK, "bad.csv"), "--motion",
              os.path.join(cr, "trajectory.csv")])
# hold: the range of M1 static friction holds at the start pose, checked by simulate from rest
# just inside (every row at the start angle) and just outside it (the crank moves)
held = os.path.join(WORK, "hold")
code, _, err = run(["hold", scene, "--out", held, "--set", "friction.pin_radius=0.02",
                    "--set", "friction.coulomb=0.3"])
if code != 0:
    failures.append("hold: exit %d: %s" % (code, err))
else:
    h = json.load(open(os.path.join(held, "hold.json")))
    lo, hi = h["range_M1"]
    if not (h["mechanism"] == "four_bar" and lo < h["M1"] < hi):
        failures.append("hold.json: %r" % h)
    for frac, stays in ((0.99, True), (1.01, False)):
        m1 = h["M1"] + frac * (hi - h["M1"])
        out = os.path.join(WORK, "hold_sim_%g" % frac)
        code, _, err = run(["simulate", scene, "--out", out, "--no-plots", "--set",
                            "friction.pin_radius=0.02", "--set", "friction.coulomb=0.3", "--set",
                            "loads.M1=%r" % m1, "--set", "simulation.duration=0.1"])
        rows = read_csv(os.path.join(out, "trajectory.csv")) if code == 0 else []
        moved = max((abs(float(r["theta1"]) - float(rows[0]["theta1"])) for r in rows), default=-1)
        if code != 0 or (moved != 0) == stays:
            failures.append("hold range vs simulate at %g of the way to M1_max: exit %d, moved %g rad"
                            % (frac, code, moved))
code, _, err = run(["hold", os.path.join(REFERENCE, "double_rocker.yaml"), "--grid", "36",
                    "--out", os.path.join(WORK, "hold_map")])
if code != 0 or not os.path.exists(os.path.join(WORK, "hold_map", "hold_map.csv")):
    failures.append("hold --grid on the double rocker: exit %d: %s" % (code, err))
else:
    status = [float(r["status"]) for r in read_csv(os.path.join(WORK, "hold_map", "hold_map.csv"))]
    if not (status.count(0.0) > 0 and status.count(1.0) > 0):
        failures.append("hold --grid on the double rocker: statuses %s" % sorted(set(status)))
expect_error(2, "--pose: expected THETA1 (a four-bar has one crank angle",
             ["hold", scene, "--pose", "1,2", "--out", os.path.join(WORK, "bad")])
bad = os.path.join(WORK, "bad")
expect_error(2, "--excitation: multisine drives the five-bar's two cranks",
             ["synth-log", scene, "--out", bad, "--excitation", "multisine"])
expect_error(2, "--torque-offset: expected one value (tau1), got 2 (a four_bar scene has one motor",
             ["synth-log", scene, "--out", bad, "--torque-offset", "0.1,0.1"])
simulated = os.path.join(WORK, "crank_rocker", "trajectory.csv")
inv = os.path.join(WORK, "inverse")
code, stdout, err = run(["inverse", scene, "--motion", simulated, "--out", inv])
if code != 0:
    failures.append("inverse: exit %d: %s" % (code, err))
else:
    with open(os.path.join(inv, "trajectory.csv")) as f:
        header = f.readline().strip().split(",")
    rest = ["at_rest", "stuck1", "stuck2", "stuck3", "stuck4", "M1_hold_min", "M1_hold_max"]
    if header != COLUMNS + ["M1_input"] + rest:
        failures.append("inverse: columns %s" % header)
    with open(os.path.join(inv, "summary.json")) as f:
        summary = json.load(f)
    error = summary.get("inverse_dynamics_max_abs_error")
    if summary.get("mechanism") != "four_bar" or "max_abs_M2" in summary:
        failures.append("inverse: summary %s" % summary)
    if error is None or not error <= 1e-9:
        failures.append("inverse: max |M1 - M1_input| = %r N m" % error)
    rows, sim_rows = read_csv(os.path.join(inv, "trajectory.csv")), read_csv(simulated)
    worst = max(abs(float(a[c]) - float(b[c])) for a, b in zip(rows, sim_rows)
                for c in ("theta2", "theta3", "N2", "Mf3"))
    if not worst < 1e-6:
        failures.append("inverse: coupler, rocker and reactions differ from the run by %.3g" % worst)
    print("inverse of the crank-rocker: max |M1 - M1_input| %.3g N m" % error)

# a crank held still: every row at rest, and its M1 range is what the simulator's lock holds
still = os.path.join(WORK, "still.csv")
with open(still, "w") as f:
    f.write("t,theta1\n" + "".join("%g,1.2\n" % (0.01 * i) for i in range(11)))
code, _, err = run(["inverse", scene, "--motion", still, "--out", inv])
if code != 0:
    failures.append("inverse of a still crank: exit %d: %s" % (code, err))
else:
    rows = read_csv(os.path.join(inv, "trajectory.csv"))
    lo, hi, m1 = (float(rows[0][c]) for c in ("M1_hold_min", "M1_hold_max", "M1"))
    if not all(r["at_rest"] == "1" and r["stuck4"] == "1" for r in rows) or not lo < m1 < hi:
        failures.append("inverse of a still crank: at rest %s, M1 %g in [%g, %g]"
                        % ([r["at_rest"] for r in rows], m1, lo, hi))
    for torque, moves in ((lo + 0.02 * (hi - lo), False), (hi - 0.02 * (hi - lo), False),
                          (hi + 0.02 * (hi - lo), True), (lo - 0.02 * (hi - lo), True)):
        out = os.path.join(WORK, "held")
        code, _, err = run(["simulate", scene, "--set", "loads.M1=%.17g" % torque,
                            "--set", "loads.F=5", "--set", "initial.theta1=1.2",
                            "--set", "simulation.duration=0.05", "--out", out])
        if code != 0:
            failures.append("held crank at M1 = %g: exit %d: %s" % (torque, code, err))
            continue
        drift = max(abs(float(r["theta1"]) - 1.2) for r in read_csv(os.path.join(out, "trajectory.csv")))
        if (drift > 1e-6) != moves:
            failures.append("M1 = %g (range [%g, %g]): the crank %s (drift %.3g rad)"
                            % (torque, lo, hi, "stays" if not moves else "moves", drift))
    print("still crank: M1 %.6g N m holds in [%.6g, %.6g]" % (m1, lo, hi))

bad = os.path.join(WORK, "bad")
five = os.path.join(WORK, "five_bar_motion.csv")
with open(five, "w") as f:
    f.write("t,theta1,theta2\n" + "".join("%g,1.2,0.3\n" % (0.01 * i) for i in range(6)))
expect_error(2, "theta2: is a five-bar motion column (the second crank), not one of mechanism.type "
             "four_bar", ["inverse", scene, "--motion", five, "--out", bad])
far = os.path.join(WORK, "far.csv")
with open(far, "w") as f:
    f.write("t,theta1\n" + "".join("%g,%g\n" % (0.01 * i, 3.0 - 0.01 * i) for i in range(6)))
expect_error(2, "line 2: the mechanism cannot assemble at theta1 = 3",
             ["inverse", os.path.join(REFERENCE, "double_rocker.yaml"), "--motion", far, "--out", bad])
expect_error(2, "loads.M2: is a five-bar key, not one of mechanism.type four_bar",
             ["simulate", scene, "--set", "loads.M2=1", "--out", bad])
expect_error(2, "friction.coulomb: expected 1 or 4 numbers (O, B, C, D0), got 5",
             ["simulate", scene, "--set", "friction.coulomb=[0.1,0.1,0.1,0.1,0.1]", "--out", bad])
expect_error(2, "initial: four-bar cannot assemble",
             ["simulate", scene, "--set", "mechanism.links.2.length=0.01", "--out", bad])
# excite: a small Fourier design of the crank (exit 0, the four-bar's columns, within its limit,
# every joint reversing); synth-log --motion along it gives back its M1; with the inertial group
# its 14 parameters; the five-bar's options refused naming the option and the mechanism type
design = os.path.join(WORK, "excite")
code, _, err = run(["excite", scene, "--duration", "4", "--torque-limit", "2", "--design-samples",
                    "100", "--harmonics", "3", "--periods", "2", "--max-evaluations", "30",
                    "--starts", "1", "--min-reversals", "2", "--no-plots", "--out", design])
if code != 0:
    failures.append("excite: exit %d: %s" % (code, err))
else:
    rows = read_csv(os.path.join(design, "excitation.csv"))
    if list(rows[0].keys()) != ["t", "theta1", "omega1", "alpha1", "M1"]:
        failures.append("excite: excitation.csv columns %s" % list(rows[0].keys()))
    if max(abs(float(r["M1"])) for r in rows) > 2:
        failures.append("excite: |M1| above the limit")
    summary = json.load(open(os.path.join(design, "excitation.json")))
    designed = summary["designed"]
    if summary["status"] != "ok" or len(designed["reversals"]) != 4 or min(designed["reversals"]) < 2:
        failures.append("excite: status %s, reversals %s" % (summary["status"], designed["reversals"]))
    names = [r["name"] for r in read_csv(os.path.join(design, "predicted_std.csv"))]
    if names != ["coulomb", "viscous"] or not 0 < designed["worst_relative_std"] <= 1:
        failures.append("excite: parameters %s, worst relative std %s"
                        % (names, designed["worst_relative_std"]))
    follow = os.path.join(WORK, "excite_log.csv")
    code, _, err = run(["synth-log", scene, "--motion", os.path.join(design, "excitation.csv"),
                        "--torque-noise", "0", "--angle-noise", "0", "--out", follow])
    worst = max([abs(float(a["tau1"]) - float(b["M1"])) for a, b in zip(read_csv(follow), rows)]
                if code == 0 else [float("inf")])
    if worst > 1e-9:
        failures.append("excite: synth-log --motion along the design differs by %g N m (exit %d %s)"
                        % (worst, code, err))
def small_design(groups):
    """excite's predicted std by name of a short design for `groups`, or None (a failure noted)"""
    design = os.path.join(WORK, "excite_" + groups.replace(",", "_"))
    code, _, err = run(["excite", scene, "--duration", "4", "--torque-limit", "2",
                        "--design-samples", "100", "--harmonics", "3", "--periods", "2",
                        "--max-evaluations", "30", "--starts", "1", "--min-reversals", "2",
                        "--estimate", groups, "--no-plots", "--out", design])
    if code not in (0, 3):
        failures.append("excite --estimate %s: exit %d: %s" % (groups, code, err))
        return None
    return {r["name"]: float(r["std"]) for r in read_csv(os.path.join(design, "predicted_std.csv"))}


def all_finite(std):
    return all(0 < v < float("inf") for v in std.values())


# with the links' inertial parameters: their 12 columns after the friction's, each std finite
# (identify's prior holds what the motion does not determine) and at most the prior's
std = small_design("friction,inertia")
expected = ["coulomb", "viscous"] + ["%s_%d" % (n, l) for l in (1, 2, 3)
                                     for n in ("m", "mx", "my", "J")]
if std is not None and (list(std) != expected or not all_finite(std)
                        or not std["m_1"] <= 0.2 * 0.5):
    failures.append("excite --estimate friction,inertia: predicted std %s" % std)
# with the crank motor's terms: offset_1, actuator_coulomb_1, actuator_viscous_1 after the
# friction's, each std finite where the design reverses the crank
std = small_design("friction,actuator")
expected = ["coulomb", "viscous", "offset_1", "actuator_coulomb_1", "actuator_viscous_1"]
if std is not None and (list(std) != expected or not all_finite(std)):
    failures.append("excite --estimate friction,actuator: predicted std %s" % std)
for option, args in (("--family: torque drives the five-bar's two motors", ["--family", "torque"]),
                     ("--theta2-range: a four-bar has one crank", ["--theta2-range", "0:1"]),
                     ("--start: multisine", ["--start", "multisine"])):
    for pattern in (option, "(mechanism.type four_bar)"):
        expect_error(2, pattern, ["excite", scene, "--torque-limit", "2", "--out", bad] + args)
# accuracy: the work-precision study of a four-bar, checked against its independent reference
out = os.path.join(WORK, "accuracy")
code, stdout, err = run(["accuracy", os.path.join(REFERENCE, "crank_rocker.yaml"), "--out", out,
                         "--repeats", "1", "--tolerances", "1e-6,1e-9",
                         "--methods", "cvode_adams,arkode_erk45", "--no-plots",
                         "--reference", os.path.join(REFERENCE, "crank_rocker.csv")])
if code != 0:
    failures.append("accuracy on a four-bar: exit %d: %s" % (code, err))
else:
    with open(os.path.join(out, "summary.json")) as f:
        reference = json.load(f)["reference"]
    points = read_csv(os.path.join(out, "work_precision.csv"))
    if not reference["max_abs_difference_external"] < 1e-9:
        failures.append("accuracy: the own reference differs from the independent one by %r"
                        % reference["max_abs_difference_external"])
    ok = [p for p in points if p["status"] == "ok"]
    if len(points) != 12 or len(ok) != 12:  # 3 treatments x 2 methods x 2 tolerances
        failures.append("accuracy: %d points, %d ok (expected 12)" % (len(points), len(ok)))
    errors = {(p["method"], p["tolerance"]): float(p["error"])
              for p in ok if p["treatment"] == "exact_located"}
    for method in ("cvode_adams", "arkode_erk45"):  # a tighter tolerance, a smaller error
        tight, loose = errors.get((method, "1e-09")), errors.get((method, "1e-06"))
        if tight is None or loose is None or not tight < loose:
            failures.append("accuracy: %s: error %r at 1e-9 against %r at 1e-6"
                            % (method, tight, loose))
    if reference.get("external_times_compared") != len(read_csv(os.path.join(REFERENCE, "crank_rocker.csv"))) \
            or reference.get("external_agrees") is not True:
        failures.append("accuracy: the independent reference: %r" % reference)
# another mechanism's trajectory as the reference: a warning, and the summary says so
out = os.path.join(WORK, "accuracy_other")
code, _, err = run(["accuracy", os.path.join(REFERENCE, "crank_rocker.yaml"), "--out", out,
                    "--repeats", "1", "--tolerances", "1e-6", "--methods", "cvode_adams",
                    "--no-plots", "--reference", os.path.join(REFERENCE, "double_rocker.csv")])
if code != 0 or "it is not a run of this scene" not in err:
    failures.append("accuracy with the double rocker's reference: exit %d: %s" % (code, err))
else:
    with open(os.path.join(out, "summary.json")) as f:
        if json.load(f)["reference"].get("external_agrees") is not False:
            failures.append("accuracy: the double rocker's reference read as agreeing")
# identify's validation of a four-bar: on a noise-free log (exact rates) the fitted scene driven
# by the logged torque follows the logged crank angle to the interpolation of the torque between
# samples, restarted every 0.1 s (--window) and over the whole log
exact_log = os.path.join(WORK, "crank_rocker_exact.csv")
run(["synth-log", scene, "--out", exact_log, "--duration", "2", "--seed", "5", "--torque-noise",
     "0", "--angle-noise", "0", "--with-rates"])
code, _, err = run(["identify", scene, "--log", exact_log, "--window", "0.1", "--no-plots",
                    "--out", os.path.join(WORK, "identify_exact")])
if code != 0:
    failures.append("identify of the exact four-bar log: exit %d: %s" % (code, err))
else:
    with open(os.path.join(WORK, "identify_exact", "identification.json")) as f:
        validation = json.load(f).get("validation", {})
    windowed = validation.get("windowed_rms_angle_error", [1.0])
    full = validation.get("full_run_rms_angle_error", [1.0])
    if validation.get("window_s") != 0.1 or len(windowed) != 1 or not windowed[0] < 1e-5 \
            or not full[0] < 1e-4:
        failures.append("identify of the exact four-bar log: validation %r" % validation)
# excite on a frictionless four-bar: nothing to design for, refused naming friction
expect_error(2, "friction: every parameter to design for is 0",
             ["excite", scene, "--set", "friction.coulomb=0", "--set", "friction.viscous=0",
              "--duration", "2", "--torque-limit", "2", "--out", bad])
# identify: a four-bar's log fitted end to end (2 s, angles only, synth-log's default noise); the
# five-bar's options and a five-bar's log refused naming them
id_log = os.path.join(WORK, "crank_rocker_id.csv")
code, _, err = run(["synth-log", scene, "--out", id_log, "--duration", "2", "--seed", "5"])
fit = os.path.join(WORK, "identify")
code, stdout, err = run(["identify", scene, "--log", id_log, "--out", fit])
if code != 0:
    failures.append("identify of the four-bar: exit %d: %s" % (code, err))
else:
    with open(os.path.join(fit, "identification.json")) as f:
        result = json.load(f)
    if result.get("status") != "ok" or result.get("mechanism") != "four_bar":
        failures.append("identify of the four-bar: status %r, mechanism %r"
                        % (result.get("status"), result.get("mechanism")))
    for p in result.get("parameters", []):
        if not p["ci95_low"] - 1e-12 <= p["true"] <= p["ci95_high"] + 1e-12 or \
                abs(p["error_in_std"]) > 4:
            failures.append("identify of the four-bar: %s = %.4g, true %.4g outside [%.4g, %.4g]"
                            % (p["name"], p["value"], p["true"], p["ci95_low"], p["ci95_high"]))
    if [p["name"] for p in result.get("parameters", [])] != ["coulomb", "viscous"]:
        failures.append("identify of the four-bar: parameters %r" % result.get("parameters"))
    if len(result.get("rms_torque_residual", [])) != 1:
        failures.append("identify of the four-bar: rms_torque_residual %r"
                        % result.get("rms_torque_residual"))
    with open(os.path.join(fit, "residuals.csv")) as f:
        header = f.readline().strip()
    if header != ("t,theta1,tau1,omega1,alpha1,predicted_tau1,residual_tau1,used,"
                  "simulated_theta1,windowed_theta1"):
        failures.append("identify of the four-bar: residuals.csv header %r" % header)
    with open(os.path.join(fit, "scene_fitted.yaml")) as f:
        fitted = f.read()
    if "four_bar" not in fitted:
        failures.append("identify of the four-bar: scene_fitted.yaml is not a four-bar's")
    validation = result.get("validation", {})
    if len(validation.get("windowed_rms_angle_error", [])) != 1 or \
            not os.path.exists(os.path.join(fit, "fig_validation.png")):
        failures.append("identify of the four-bar: validation %r" % validation)
    # the fitted scene simulates
    code, _, err = run(["simulate", os.path.join(fit, "scene_fitted.yaml"), "--out",
                        os.path.join(WORK, "fitted_run"), "--set", "simulation.duration=0.2"])
    if code != 0:
        failures.append("simulate of the fitted four-bar: exit %d: %s" % (code, err))
expect_error(2, "--estimate: group actuator needs --method inverse-dynamics",
             ["identify", scene, "--log", id_log, "--estimate", "friction,actuator", "--method",
              "output-error", "--out", bad])
# the crank motor's terms: synth-log's options (one value each) and header truth, identify's
# actuator group on the double rocker (its crank reverses), the fitted scene's actuators.M1, and
# the log fitted without the group not used (exit 3)
rocker = os.path.join(REFERENCE, "double_rocker.yaml")
motor_log = os.path.join(WORK, "double_rocker_motor.csv")
code, _, err = run(["synth-log", rocker, "--out", motor_log, "--duration", "4", "--seed", "1",
                    "--torque-offset", "0.03", "--actuator-coulomb", "0.04",
                    "--actuator-viscous", "0.005"])
with open(motor_log) as f:
    header = f.read(4000)
if code != 0 or "# true.offset = 0.03\n" not in header or \
        "# true.actuator_coulomb = 0.04\n" not in header:
    failures.append("synth-log with the motor's terms: exit %d: %s" % (code, err))
motor_fit = os.path.join(WORK, "identify_motor")
code, _, err = run(["identify", rocker, "--log", motor_log, "--estimate", "friction,actuator",
                    "--no-plots", "--out", motor_fit])
if code != 0:
    failures.append("identify --estimate friction,actuator of the four-bar: exit %d: %s"
                    % (code, err))
else:
    with open(os.path.join(motor_fit, "identification.json")) as f:
        result = json.load(f)
    names = [p["name"] for p in result["parameters"]]
    if names[2:] != ["offset_1", "actuator_coulomb_1", "actuator_viscous_1"]:
        failures.append("identify of the four-bar's motor: parameters %s" % names)
    for p in result["parameters"]:
        if not abs(p.get("error_in_std", 99)) < 3:
            failures.append("identify of the four-bar's motor: %s %s" % (p["name"], p))
    with open(os.path.join(motor_fit, "scene_fitted.yaml")) as f:
        fitted = f.read()
    if not re.search(r"actuators:\n  M1: \{offset: 0\.0", fitted):
        failures.append("identify of the four-bar's motor: scene_fitted.yaml %r" % fitted)
code, _, err = run(["identify", rocker, "--log", motor_log, "--no-plots", "--out",
                    os.path.join(WORK, "identify_no_motor")])
if code != 3:
    failures.append("identify of a log with the motor's terms, without the group: exit %d "
                    "(expected 3): %s" % (code, err))
expect_error(2, "--smooth-sign: must be at least 1e-09 rad/s",
             ["identify", scene, "--log", id_log, "--smooth-sign", "1e-10", "--out", bad])
expect_error(2, "--smooth-sign: 500 rad/s is beyond the log's largest rate",
             ["identify", scene, "--log", id_log, "--smooth-sign", "500", "--out", bad])
expect_error(2, "friction.smoothing_velocity: 500 rad/s is beyond the log's largest rate",
             ["identify", scene, "--log", id_log, "--set", "friction.smoothing_velocity=500",
              "--out", bad])
# the inertial group: the three links' 12 standard parameters after the friction, each truth
# (synth-log's true.inertial) inside its interval on this log; the fitted links simulate
inert = os.path.join(WORK, "fit_inertia")
code, _, err = run(["identify", scene, "--log", id_log, "--estimate", "friction,inertia",
                    "--out", inert, "--no-plots"])
if code != 0:
    failures.append("identify --estimate friction,inertia of the four-bar: exit %d: %s" % (code, err))
else:
    with open(os.path.join(inert, "identification.json")) as f:
        params = json.load(f)["parameters"]
    names = [p["name"] for p in params]
    if len(names) != 14 or names[2] != "m_1" or names[-1] != "J_3":
        failures.append("identify --estimate friction,inertia of the four-bar: names %r" % names)
    for p in params:
        if not p["ci95_low"] <= p.get("true", math.nan) <= p["ci95_high"]:
            failures.append("four-bar inertia: %s's truth outside its interval" % p["name"])
    code, _, err = run(["simulate", os.path.join(inert, "scene_fitted.yaml"), "--out",
                        os.path.join(WORK, "fitted_inertia_run"), "--set",
                        "simulation.duration=0.2"])
    if code != 0:
        failures.append("simulate of the four-bar's fitted links: exit %d: %s" % (code, err))
# the validation window as the five-bar's: within the log, at least 2 samples
expect_error(2, "--window: 100 s is longer than the log",
             ["identify", scene, "--log", id_log, "--window", "100", "--out", bad])
expect_error(2, "--window: 1e-09 s holds fewer than 2 samples",
             ["identify", scene, "--log", id_log, "--window", "1e-9", "--out", bad])
# the sign check: the log with tau1 negated
neg_log = os.path.join(WORK, "crank_rocker_negated.csv")
with open(id_log) as f, open(neg_log, "w") as g:
    for line in f:
        if line[0].isdigit() or line[0] == "-":
            cells = line.rstrip("\n").split(",")
            cells[2] = repr(-float(cells[2]))
            line = ",".join(cells) + "\n"
        g.write(line)


def expect_unusable(pattern, args):
    """exit 3, one error line matching `pattern`, identification.json written and failed"""
    p = subprocess.run([FIVEBAR] + args, capture_output=True, text=True)
    errors = [l for l in p.stderr.splitlines() if l.startswith("fivebar: error:")]
    if p.returncode != 3 or len(errors) != 1 or not re.search(pattern, errors[0]):
        failures.append("%s: exit %d, %s (expected 3, /%s/)" % (args, p.returncode, errors,
                                                               pattern))
        return
    with open(os.path.join(args[args.index("--out") + 1], "identification.json")) as f:
        status = json.load(f).get("status")
    if status != "failed":
        failures.append("%s: identification.json status %r" % (args, status))


expect_unusable(r"the logged torque fits far better negated .*rerun with --flip-torque-sign 1$",
                ["identify", scene, "--log", neg_log, "--out", os.path.join(WORK, "negated"),
                 "--no-plots"])
code, _, err = run(["identify", scene, "--log", neg_log, "--flip-torque-sign", "1", "--out",
                    os.path.join(WORK, "flipped"), "--no-plots"])
if code != 0:
    failures.append("identify --flip-torque-sign 1 of the negated four-bar log: exit %d: %s"
                    % (code, err))
expect_unusable(r"the flipped torque fits far better negated .*remove --flip-torque-sign$",
                ["identify", scene, "--log", id_log, "--flip-torque-sign", "1", "--out",
                 os.path.join(WORK, "flipped_wrongly"), "--no-plots"])
expect_error(2, "--flip-torque-sign: 2: a four_bar's log has one torque",
             ["identify", scene, "--log", id_log, "--flip-torque-sign", "2", "--out", bad])
# the same log with its angles in degrees: named as such from the motion (the crank-rocker
# assembles at any angle, so the model alone would only say that no sample is left)
deg_log = os.path.join(WORK, "crank_rocker_deg.csv")
with open(id_log) as f, open(deg_log, "w") as g:
    for line in f:
        if line[0].isdigit() or line[0] == "-":
            cells = line.rstrip("\n").split(",")
            cells[1] = repr(float(cells[1]) * 180 / math.pi)
            line = ",".join(cells) + "\n"
        g.write(line)
expect_error(2, "column theta1: angles look like degrees, expected radians (read as radians, the "
             "motion (median crank rate",
             ["identify", scene, "--log", deg_log, "--out", bad])
# study: a five-bar key swept on a four-bar is refused up front, not a study of designs that
# "cannot assemble"
expect_error(2, "--sweep initial.theta2: is a five-bar key",
             ["study", scene, "--tasks", TASKS, "--sweep", "initial.theta2=0:1:2", "--out", bad])
expect_error(2, "column 3: column 'theta2' does not belong to this mechanism",
             ["identify", scene, "--log", os.path.join(os.path.dirname(os.path.abspath(PAPER)), "..",
                                                       "logs", "paper_angles.csv"), "--out", bad])
if os.path.exists(bad):
    failures.append("a failed run left %s behind" % bad)

for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)

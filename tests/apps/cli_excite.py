#!/usr/bin/env python3
"""End-to-end checks of `fivebar excite` and `synth-log --motion`.

Usage: cli_excite.py FIVEBAR PAPER_YAML WORK_DIR

Bad input exits 2 with one error line and writes nothing; an unreachable reversal count exits 3
with a status; a small design honours its constraints (torque limit, singularity margin, angle
range, reversals) on the 1 kHz grid, its rates and accelerations are those of its angles, and
synth-log --motion along it reproduces its torques. On the light mechanism: the predicted std is
identify's on a log along the design (within 1.5x), and the default --min-reversals is named as
what makes the design unusable.
"""
import json
import math
import os
import shutil
import sys

from cli_common import Cli, read_csv

FIVEBAR, PAPER, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
cli = Cli(FIVEBAR)
failures, run = cli.failures, cli.run


def expect_error(status, pattern, args, out_dir=None):
    cli.expect_error(status, pattern, args)
    if out_dir and os.path.exists(os.path.join(out_dir, "excitation.csv")):
        failures.append("%s: wrote excitation.csv after failing" % args)


def design_columns(label, out, args):
    """Runs excite into out; the columns of its excitation.csv (None when it failed)."""
    code, _, err = run(["excite", PAPER, "--out", out] + args)
    if code != 0:
        failures.append("%s: exit %d: %s" % (label, code, err))
        return None
    rows = read_csv(os.path.join(out, "excitation.csv"))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def motion_log_error(out, log, col):
    """synth-log --motion along out/excitation.csv, noise-free: (exit, rows, largest torque
    difference from the motion's M1, M2)."""
    code, _, err = run(["synth-log", PAPER, "--motion", os.path.join(out, "excitation.csv"),
                        "--out", log, "--torque-noise", "0", "--angle-noise", "0", "--with-rates"])
    lrows = read_csv(log) if code == 0 else []
    worst = max([max(abs(float(a["tau1"]) - b), abs(float(a["tau2"]) - c))
                 for a, b, c in zip(lrows, col["M1"], col["M2"])] or [float("inf")])
    return code, len(lrows), worst


shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
bad = os.path.join(WORK, "bad")
base = ["excite", PAPER, "--out", bad, "--torque-limit", "13.4"]
expect_error(2, "--duration: must be > 0", base + ["--duration", "0"], bad)
expect_error(2, "--duration: must be > 0", base + ["--duration", "-3"], bad)
expect_error(2, "initial: the start pose (theta1 = 3.1, theta2 = 0.05) is within the design's singular margin",
             base + ["--set", "initial.theta1=3.1", "--set", "initial.theta2=0.05", "--set",
                     "mechanism.ground_length=0.2", "--set", "mechanism.links.0.length=0.1",
                     "--set", "mechanism.links.1.length=0.1", "--set", "mechanism.links.2.length=0.2",
                     "--set", "mechanism.links.3.length=0.2", "--set", "mechanism.point_p=0.2"], bad)
expect_error(2, "below what holding the start pose needs",
             ["excite", PAPER, "--out", bad, "--torque-limit", "0.5"], bad)
expect_error(2, "excludes the start pose theta1", base + ["--theta1-range", "2:3"], bad)
expect_error(2, "--theta2-range: expected LO:HI", base + ["--theta2-range", "3:2"], bad)
expect_error(2, "--theta1-range: expected LO:HI", base + ["--theta1-range", "1x:2"], bad)
expect_error(2, "--estimate", base + ["--estimate", "friction,mass"], bad)
expect_error(3, "reversals_unreachable", base + ["--family", "fourier", "--min-reversals", "1000"], bad)
# an option of the other family is bad input, not silently ignored (the default family is torque)
expect_error(2, "--harmonics: applies to --family fourier only", base + ["--harmonics", "3"], bad)
expect_error(2, "--singular-margin: must be a finite number", base + ["--singular-margin", "nan"], bad)
expect_error(2, "--singular-margin: expected a number in", base + ["--singular-margin", "1"], bad)
expect_error(2, "--min-reversals: must be >= 0", base + ["--min-reversals", "-1"], bad)
expect_error(2, "--reversal-rate: must be in [1e-6, 1e5] rad/s", base + ["--family", "fourier", "--reversal-rate", "0"], bad)
expect_error(2, "--reversal-rate: must be in [1e-6, 1e5] rad/s", base + ["--family", "fourier", "--reversal-rate", "1e-300"], bad)
expect_error(2, "--reversal-rate: applies to --family fourier only", base + ["--reversal-rate", "1"], bad)
expect_error(2, "loads.M3: '1e300' at t = 0: must be at most 1e+09 N m",
             base + ["--set", "loads.M3=1e300"], bad)
expect_error(2, "--tones: applies to --family torque only",
             base + ["--family", "fourier", "--tones", "3"], bad)
expect_error(2, "--family: expected fourier or torque", base + ["--family", "spline"], bad)
expect_error(2, "expected d-optimal, condition or worst-std", base + ["--criterion", "a-optimal"], bad)
expect_error(2, "--duration: must be > 0", base + ["--duration", "0", "--family", "torque"], bad)
# a design started at rest alone cannot leave it (no information there): refused, not run
expect_error(2, "--start: rest with --starts 1", base + ["--family", "fourier", "--start", "rest", "--starts", "1"], bad)
if os.path.exists(bad):
    failures.append("a run rejected for bad input created its output directory")

# a design that cannot reach the reversals asked (at most 6 with 3 harmonics over 1 period):
# exit 3 with the status, the summary says so, and no excitation.csv
missed = os.path.join(WORK, "missed")
expect_error(3, "status reversals_not_met", ["excite", PAPER, "--out", missed, "--torque-limit", "13.4",
             "--family", "fourier", "--duration", "2", "--periods", "1", "--harmonics", "3", "--design-samples", "120",
             "--starts", "1", "--max-evaluations", "15", "--min-reversals", "6", "--no-plots",
             "--no-baseline", "--method", "slsqp"], missed)
if json.load(open(os.path.join(missed, "excitation.json")))["status"] != "reversals_not_met":
    failures.append("excitation.json of a missed design does not say reversals_not_met")

# a small design
out = os.path.join(WORK, "design")
limit, margin = 13.4, 0.1
col = design_columns("small design", out, [
    "--torque-limit", str(limit), "--family", "fourier", "--duration", "2", "--periods", "1",
    "--harmonics", "3",
    "--design-samples", "120", "--starts", "1", "--max-evaluations", "15", "--min-reversals", "1",
    "--theta1-range", "0.5:3", "--no-plots", "--no-baseline", "--start", "swing", "--method", "slsqp"])
if col:
    t = col["t"]
    if len(t) != 2001 or abs(t[1] - 0.001) > 1e-12 or t[0] != 0:
        failures.append("excitation.csv is not a 1 kHz grid over 2 s (%d rows)" % len(t))
    h = 0.001
    ramp = 0.5  # the default fade-in: the jerk jumps there (stencils skip it)
    for i in range(2, len(t) - 2, 7):
        if abs(t[i] - ramp) < 0.003:
            continue
        for q, w in (("theta1", "omega1"), ("theta2", "omega2"), ("omega1", "alpha1"),
                     ("omega2", "alpha2")):
            f = col[q]
            d = (f[i - 2] - 8 * f[i - 1] + 8 * f[i + 1] - f[i + 2]) / (12 * h)
            if abs(d - col[w][i]) > 1e-6 * (1 + abs(d)) + 1e-4:
                failures.append("row %d: %s = %g, d %s/dt = %g" % (i, w, col[w][i], q, d))
                break
    peak = max(max(abs(x) for x in col["M1"]), max(abs(x) for x in col["M2"]))
    if peak > limit:
        failures.append("peak torque %g above the limit %g" % (peak, limit))
    if min(col["theta1"]) < 0.5 or max(col["theta1"]) > 3:
        failures.append("theta1 leaves --theta1-range 0.5:3")
    j = json.load(open(os.path.join(out, "excitation.json")))
    d = j["designed"]
    if j["status"] != "ok" or d["min_coupler_sine"] < margin * (1 - 1e-3) or min(d["reversals"]) < 1:
        failures.append("design summary: status %s, min sine %g, reversals %s" %
                        (j["status"], d["min_coupler_sine"], d["reversals"]))
    std = read_csv(os.path.join(out, "predicted_std.csv"))
    if [r["name"] for r in std] != ["coulomb", "viscous"] or not all(float(r["std"]) > 0 for r in std):
        failures.append("predicted_std.csv: %s" % std)
    # synth-log along the motion, noise-free: the torques of excitation.csv
    code, n, worst = motion_log_error(out, os.path.join(WORK, "log.csv"), col)
    if code != 0 or n != len(t) or worst > 1e-9:
        failures.append("synth-log --motion: exit %d, %d rows, torques differ by %g" % (code, n, worst))
    expect_error(2, "missing column", ["synth-log", PAPER, "--motion", PAPER.replace("paper.yaml", "../logs/paper_angles.csv"),
                                       "--out", os.path.join(WORK, "log2.csv")])
    # --duration takes the motion's first seconds; a longer one, or a --rate, is refused
    motion = os.path.join(out, "excitation.csv")
    half = 0.5 * (t[-1] - t[0])
    code, _, err = run(["synth-log", PAPER, "--motion", motion, "--duration", repr(half), "--out",
                        os.path.join(WORK, "log3.csv"), "--torque-noise", "0", "--angle-noise", "0"])
    cut = read_csv(os.path.join(WORK, "log3.csv")) if code == 0 else []
    if code != 0 or abs(float(cut[-1]["t"]) - t[0] - half) > 1e-9 or len(cut) >= len(t):
        failures.append("synth-log --motion --duration %g: exit %d, %d rows: %s" % (half, code, len(cut), err))
    expect_error(2, "longer than the motion",
                 ["synth-log", PAPER, "--motion", motion, "--duration", repr(3 * half), "--out", os.path.join(WORK, "log4.csv")])
    expect_error(2, "--rate: the motion's own grid",
                 ["synth-log", PAPER, "--motion", motion, "--rate", "100", "--out", os.path.join(WORK, "log4.csv")])
    if os.path.exists(os.path.join(WORK, "log4.csv")):
        failures.append("synth-log wrote log4.csv after failing")

# the torque family cannot meet 1000 reversals in 1 s: exit 3 with the status, no excitation.csv
tmiss = os.path.join(WORK, "torque_missed")
expect_error(3, "status reversals_not_met", ["excite", PAPER, "--out", tmiss, "--torque-limit", "13.4",
             "--duration", "1", "--family", "torque", "--design-samples", "50", "--max-evaluations", "9",
             "--min-reversals", "1000", "--no-plots", "--no-baseline"], tmiss)

# a small torque-driven design (--family torque): the free motion under clipped tone torques
tout = os.path.join(WORK, "torque")
col = design_columns("torque design", tout, [
    "--torque-limit", str(limit), "--duration", "2", "--family", "torque", "--criterion",
    "worst-std", "--per-joint", "--design-samples", "100", "--max-evaluations", "13",
    "--min-reversals", "1", "--no-plots", "--seed", "2"])
if col:
    rows = col["t"]
    # the rates and accelerations are the derivatives of the angles and rates, except next to
    # the events of the free motion (a joint reversing makes the acceleration jump): a few rows
    h, off, checked = 0.001, {"theta": 0, "omega": 0}, 0
    for i in range(2, len(rows) - 2, 3):
        checked += 1
        for q, w, tol in (("theta1", "omega1", 1e-5), ("theta2", "omega2", 1e-5),
                          ("omega1", "alpha1", 1e-3), ("omega2", "alpha2", 1e-3)):
            f = col[q]
            d = (f[i - 2] - 8 * f[i - 1] + 8 * f[i + 1] - f[i + 2]) / (12 * h)
            if abs(d - col[w][i]) > tol * (1 + abs(d)) + 1e-4:
                off[q[:5]] += 1
    if off["theta"] > 0.03 * checked or off["omega"] > 0.15 * checked:
        failures.append("torque design: of %d rows, %d rates and %d accelerations are not derivatives"
                        % (checked, off["theta"], off["omega"]))
    peak = max(max(abs(x) for x in col["M1"]), max(abs(x) for x in col["M2"]))
    j = json.load(open(os.path.join(tout, "excitation.json")))
    if peak > limit * (1 + 1e-9) or j["status"] != "ok" or j["family"] != "torque" \
            or min(j["designed"]["reversals"]) < 1 or j["designed"]["min_coupler_sine"] < margin:
        failures.append("torque design: peak %g, status %s, reversals %s" %
                        (peak, j["status"], j["designed"]["reversals"]))
    # the search never ends worse than its first start, the multi-sine's tones, on the design's
    # objective; the design is one of its finalists, evaluated again at the scene's settings
    sv = j["solver"]
    if sv["finalist_objectives"][0] > sv["start_objectives"][0] + 1e-12 \
            or sv["objective"] != sv["finalist_objectives"][sv["finalist"]] \
            or len(sv["finalist_objectives"]) < 2:
        failures.append("torque design worse than the multi-sine start, or not a finalist: %s" % sv)
    code, n, worst = motion_log_error(tout, os.path.join(WORK, "tlog.csv"), col)
    if code != 0 or n != len(rows) or worst > 1e-9:
        failures.append("synth-log --motion along the torque design: exit %d, torques differ by %g" % (code, worst))

# a light mechanism (datasets/scenes/light.yaml) at a 0.2 N m limit: the baseline multi-sine is
# scaled to the limit (it ran into a singular pose unscaled), both families give a status (ok, or
# exit 3 naming it), never ok with a std of 0, and no empty figure
LIGHT = PAPER.replace("paper.yaml", "light.yaml")
for family in ("torque", "fourier"):
    for extra in ([], ["--no-baseline"]):
        lout = os.path.join(WORK, "light_%s%s" % (family, "_nb" if extra else ""))
        args = ["excite", LIGHT, "--out", lout, "--torque-limit", "0.2", "--duration", "2",
                "--family", family, "--design-samples", "100", "--min-reversals", "2"] + extra
        args += ["--max-evaluations", "20"] if family == "torque" else ["--max-evaluations", "15", "--starts", "1"]
        code, out, err = run(args)
        label = "light %s %s" % (family, extra)
        j = json.load(open(os.path.join(lout, "excitation.json"))) if os.path.exists(os.path.join(lout, "excitation.json")) else None
        if code not in (0, 3) or j is None:
            failures.append("%s: exit %d without a status: %s" % (label, code, err))
            continue
        if (code == 0) != (j["status"] == "ok"):
            failures.append("%s: exit %d with status %s" % (label, code, j["status"]))
        if code == 0:
            std = read_csv(os.path.join(lout, "predicted_std.csv"))
            if not all(float(r["std"]) > 0 and math.isfinite(float(r["std"])) for r in std):
                failures.append("%s: ok with predicted std %s" % (label, [r["std"] for r in std]))
            if any(float(r["relative_std"]) > 10 for r in std):
                failures.append("%s: ok with relative std %s" % (label, [r["relative_std"] for r in std]))
        base = j.get("multisine_baseline", {})
        if extra and base.get("status") != "skipped":
            failures.append("%s: baseline %s" % (label, base))
        if not extra:
            if base.get("status") != "ok" or not 0 < base.get("tones_factor", 0) < 0.05 \
                    or j["multisine"]["peak_torque"] > 0.2 * (1 + 1e-9):
                failures.append("%s: baseline %s, peak %s" % (label, base, j.get("multisine", {}).get("peak_torque")))
        for name in os.listdir(lout):
            if os.path.getsize(os.path.join(lout, name)) == 0:
                failures.append("%s: %s is empty" % (label, name))

# the light mechanism's 10 s Fourier design predicts viscous at 179 times its value (the
# multi-sine: 0.093): no design, exit 3 naming the status
expect_error(3, "status std_too_large", ["excite", LIGHT, "--out", os.path.join(WORK, "light_absurd"),
                                         "--torque-limit", "0.2", "--duration", "10", "--family",
                                         "fourier", "--no-plots"], os.path.join(WORK, "light_absurd"))

# the predicted std is what identify reports for a log along the design: its errors-in-variables
# std (the angle noise through the rates it estimates), not the torque noise's alone (which on
# the light mechanism's 10 s design was 7 times smaller than identify's)
eiv = os.path.join(WORK, "light_eiv")
code, _, err = run(["excite", LIGHT, "--out", eiv, "--torque-limit", "0.2", "--duration", "5",
                    "--min-reversals", "0", "--no-plots", "--no-baseline", "--max-evaluations", "40"])
if code != 0:
    failures.append("light design for the std check: exit %d: %s" % (code, err))
else:
    predicted = {r["name"]: r for r in read_csv(os.path.join(eiv, "predicted_std.csv"))}
    if any(not float(r["torque_noise_std"]) <= float(r["std"]) for r in predicted.values()):
        failures.append("predicted std below the torque noise's alone: %s" % predicted)
    log, fit = os.path.join(WORK, "light_eiv.csv"), os.path.join(WORK, "light_eiv_fit")
    code, _, err = run(["synth-log", LIGHT, "--motion", os.path.join(eiv, "excitation.csv"), "--seed", "1",
                        "--out", log])
    code2, _, err2 = run(["identify", LIGHT, "--log", log, "--no-plots", "--no-validation", "--out", fit])
    if code != 0 or code2 != 0:
        failures.append("log and fit along the light design: exit %d, %d: %s %s" % (code, code2, err, err2))
    else:
        for p in json.load(open(os.path.join(fit, "identification.json")))["parameters"]:
            ratio = float(predicted[p["name"]]["std"]) / p["std"]
            if not 1 / 1.5 < ratio < 1.5:
                failures.append("%s: predicted std %s, identify's %g" % (p["name"], predicted[p["name"]]["std"], p["std"]))

# the default --min-reversals 6 on the light mechanism at 0.2 N m: only small motions reverse
# every joint that often; the status names what the constraint costs and what to change
rev6 = os.path.join(WORK, "light_rev6")
code, _, err = run(["excite", LIGHT, "--out", rev6, "--torque-limit", "0.2", "--duration", "10",
                    "--no-plots", "--no-baseline"])
for part in ("status std_too_large", "--min-reversals 6 costs it: within --torque-limit 0.2 N m the "
             "motions found that reverse every joint 6 times are small, while the best motion found that "
             "reverses fewer", "a lower --min-reversals (0 accepts any) or a higher --torque-limit"):
    if code != 3 or part not in err:
        failures.append("light design at the default --min-reversals: exit %d, %r (expected 3 and '%s')"
                        % (code, err, part))
if os.path.exists(os.path.join(rev6, "excitation.csv")):
    failures.append("light design at the default --min-reversals wrote excitation.csv")

# synth-log's multi-sine is the same fit: within --torque-limit on the light mechanism; the limit
# is for the multi-sine only, and > 0
llog = os.path.join(WORK, "light_multisine.csv")
code, _, err = run(["synth-log", LIGHT, "--excitation", "multisine", "--torque-limit", "0.2",
                    "--duration", "2", "--torque-noise", "0", "--out", llog])
if code != 0:
    failures.append("synth-log --excitation multisine on the light mechanism: exit %d: %s" % (code, err))
else:
    rows = read_csv(llog)
    peak = max(max(abs(float(r["tau1"])), abs(float(r["tau2"]))) for r in rows)
    if not 0.1 < peak <= 0.2 * (1 + 1e-12):
        failures.append("synth-log multisine --torque-limit 0.2: peak %g" % peak)
for bad in ("0", "-1", "nan"):
    expect_error(2, "--torque-limit", ["synth-log", LIGHT, "--excitation", "multisine", "--torque-limit", bad,
                                       "--out", os.path.join(WORK, "bad.csv")])
expect_error(2, "--torque-limit", ["synth-log", LIGHT, "--torque-limit", "0.2", "--out", os.path.join(WORK, "bad.csv")])

for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)

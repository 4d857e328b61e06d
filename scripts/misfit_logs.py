#!/usr/bin/env python3
"""Logs whose torques misfit the law: does `identify` refuse them (docs/identification.md, 8)?

    python3 scripts/misfit_logs.py [--fivebar build/release/apps/fivebar] [--work DIR] [--designs]
    python3 scripts/misfit_logs.py --only light --work DIR --reuse --logs angles
    python3 scripts/misfit_logs.py --shipped OTHER_FIVEBAR

Builds clean synthetic logs (seeded) and, of each, a copy with both torques negated and one with
them halved, runs `fivebar identify SCENE --log LOG --no-plots --no-validation` on every log
and prints, per log, the exit status, the chosen Savitzky-Golay half-window, the residual over
its noise floor and the first line of the error. Then the counts: clean logs rejected (should
be 0) and bad logs accepted with exit 0 (should be 0).

The logs: `synth-log --excitation multisine --duration 4 --seed 1|2` on paper.yaml,
offset_friction.yaml and hard_drive.yaml; light.yaml 10 s under two multi-sine loads
(LIGHT_LOADS, seeds 1|2); each angles only and `--with-rates`. offset_friction.yaml's joints
have friction coefficients of their own: its logs are identified with `--per-joint` (their
correct model), and once more with the shared law (the `shared` copy, a misfit that should be
rejected naming `--per-joint`). `--designs` adds the light
mechanism's designed motions: `excite --family fourier --torque-limit 0.2` followed by
synth-log along it, and the built-in multi-sine at `--torque-limit 0.2`. `--shipped` instead
compares the shipped logs' runs (datasets/logs/README.md) with another build.
Standard library only.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "datasets", "scenes")
LIGHT_LOADS = [
    "loads.M1=0.06*sin(2*pi*0.31*t)+0.045*sin(2*pi*0.83*t+1.57)+0.03*sin(2*pi*1.7*t)",
    "loads.M2=0.06*sin(2*pi*0.43*t+1)+0.045*sin(2*pi*1.1*t+2.57)+0.03*sin(2*pi*2.3*t)",
]


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


REUSE = False  # --reuse: keep logs already in --work


def synth(fivebar, scene, out, extra):
    if REUSE and os.path.exists(out):
        return
    rc, _, err = run([fivebar, "synth-log", scene, "--out", out] + extra)
    if rc != 0:
        sys.exit("synth-log failed: " + " ".join(extra) + "\n" + err)


def clean_logs(fivebar, work, only, designs):
    """(name, scene, log path) of every clean log, written to `work`."""
    logs = []
    for name in ["paper", "offset_friction", "hard_drive", "light"]:
        if only and only != name:
            continue
        scene = os.path.join(SCENES, name + ".yaml")
        for seed in (1, 2):
            if name == "light":
                base = ["--duration", "10", "--seed", str(seed)]
                for s in LIGHT_LOADS:
                    base += ["--set", s]
            else:
                base = ["--excitation", "multisine", "--duration", "4", "--seed", str(seed)]
            for rates in (False, True):
                tag = "%s_s%d_%s" % (name, seed, "rates" if rates else "angles")
                path = os.path.join(work, tag + ".csv")
                synth(fivebar, scene, path, base + (["--with-rates"] if rates else []))
                logs.append((tag, scene, path))
    if designs and (not only or only == "light"):
        scene = os.path.join(SCENES, "light.yaml")
        exc = os.path.join(work, "excite_light")
        motion = os.path.join(exc, "excitation.csv")
        rc, err = 0, ""
        if not (REUSE and os.path.exists(motion)):
            rc, _, err = run([fivebar, "excite", scene, "--duration", "10", "--torque-limit", "0.2",
                              "--no-baseline", "--family", "fourier", "--no-plots", "--out", exc])
        if os.path.exists(motion):
            for seed in (1, 2):
                for rates in (False, True):
                    tag = "light_fourier_s%d_%s" % (seed, "rates" if rates else "angles")
                    path = os.path.join(work, tag + ".csv")
                    synth(fivebar, scene, path, ["--motion", motion, "--seed", str(seed)] +
                          (["--with-rates"] if rates else []))
                    logs.append((tag, scene, path))
        else:
            print("excite (fourier) wrote no motion (exit %d): %s" % (rc, err.strip()))
        for seed in (1, 2):
            for rates in (False, True):
                tag = "light_multisine_s%d_%s" % (seed, "rates" if rates else "angles")
                path = os.path.join(work, tag + ".csv")
                synth(fivebar, scene, path, ["--excitation", "multisine", "--torque-limit", "0.2",
                                             "--duration", "10", "--seed", str(seed)] +
                      (["--with-rates"] if rates else []))
                logs.append((tag, scene, path))
    return logs


def scaled_copy(path, factor, out):
    """The log with tau1, tau2 multiplied by `factor` (comments kept)."""
    with open(path) as f, open(out, "w") as g:
        cols = None
        for line in f:
            if line.startswith("#"):
                g.write(line)
                continue
            if cols is None:
                cols = line.strip().split(",")
                idx = [cols.index("tau1"), cols.index("tau2")]
                g.write(line)
                continue
            v = line.strip().split(",")
            for k in idx:
                v[k] = repr(factor * float(v[k]))
            g.write(",".join(v) + "\n")


# scenes whose joints' friction differs: their logs' correct model is one coefficient per joint
# (the shared law's fit of them is a misfit, to be named as such: the `shared` copy)
PER_JOINT_SCENES = ("offset_friction",)


def identify(fivebar, scene, log, out, extra=()):
    rc, _, err = run([fivebar, "identify", scene, "--log", log, "--no-plots", "--no-validation",
                      "--out", out] + list(extra))
    errors = [line for line in err.splitlines() if line.startswith("fivebar: error")]
    res = {"rc": rc, "error": errors[0] if errors else ""}
    try:
        with open(os.path.join(out, "identification.json")) as f:
            j = json.load(f)
        ratio = max(a / b for a, b in zip(j["rms_torque_residual"], j["residual_noise_floor"]))
        res.update(ratio=ratio, floor=max(j["residual_noise_floor"]),
                   window=j.get("rate_source", {}).get("sg_half_window_samples", "-"))
    except (OSError, KeyError, ValueError, TypeError, ZeroDivisionError):
        res.update(ratio=float("nan"), floor=float("nan"), window="?")
    return res


SHIPPED = [  # the shipped logs' runs (datasets/logs/README.md)
    ("paper_rates.csv", []), ("paper_angles.csv", []),
    ("per_joint_multisine.csv", ["--per-joint"]), ("stribeck_multisine.csv", []),
    ("stribeck_multisine.csv", ["--law", "stribeck"]),
]


def shipped(fivebar, baseline, work):
    """The shipped logs through `fivebar` and `baseline`: the largest relative difference of the
    estimates and their std, the chosen windows and the statuses."""
    scene = os.path.join(SCENES, "paper.yaml")
    for k, (name, extra) in enumerate(SHIPPED):
        res = []
        for tag, exe in (("new", fivebar), ("old", baseline)):
            out = os.path.join(work, "shipped_%d_%s" % (k, tag))
            rc, _, _ = run([exe, "identify", scene, "--log",
                            os.path.join(ROOT, "datasets", "logs", name), "--no-plots",
                            "--no-validation", "--out", out] + extra)
            with open(os.path.join(out, "identification.json")) as f:
                j = json.load(f)
            res.append((rc, j))
        diff = 0.0
        for a, b in zip(res[0][1]["parameters"], res[1][1]["parameters"]):
            for key in ("value", "std"):
                x, y = a.get(key), b.get(key)
                if isinstance(x, float) and isinstance(y, float) and y != 0:
                    diff = max(diff, abs(x / y - 1))
        windows = [r[1].get("rate_source", {}).get("sg_half_window_samples", "-") for r in res]
        print("%-26s %-16s exit %d/%d window %s/%s  largest relative difference %.2g" %
              (name, " ".join(extra), res[0][0], res[1][0], windows[0], windows[1], diff))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fivebar", default=os.path.join(ROOT, "build", "release", "apps", "fivebar"))
    ap.add_argument("--work", help="directory of the logs and outputs (default: a temporary one)")
    ap.add_argument("--only", help="one scene: paper, offset_friction, hard_drive, light")
    ap.add_argument("--designs", action="store_true", help="add the light mechanism's designs")
    ap.add_argument("--reuse", action="store_true", help="keep the logs already in --work")
    ap.add_argument("--logs", help="only the logs whose name contains this")
    ap.add_argument("--shipped", metavar="BASELINE",
                    help="only compare the shipped logs' runs with another fivebar build")
    args = ap.parse_args()
    global REUSE
    REUSE = args.reuse
    work = args.work or tempfile.mkdtemp(prefix="misfit_")
    os.makedirs(work, exist_ok=True)
    if args.shipped:
        shipped(args.fivebar, args.shipped, work)
        return
    logs = clean_logs(args.fivebar, work, args.only, args.designs)
    clean_rejected, bad_accepted, bad_total, shared_named, shared_total = 0, 0, 0, 0, 0
    print("%-32s %-8s %3s %6s %9s %9s  %s" % ("log", "copy", "rc", "window", "res/floor",
                                               "floor", "error"))
    logs = [x for x in logs if not args.logs or args.logs in x[0]]
    for tag, scene, path in logs:
        per_joint = any(n in tag for n in PER_JOINT_SCENES)
        copies = [("clean", 1.0), ("negated", -1.0), ("halved", 0.5)]
        for copy, factor in copies + ([("shared", 1.0)] if per_joint else []):
            log = path
            if factor != 1.0:
                log = os.path.join(work, "%s_%s.csv" % (tag, copy))
                scaled_copy(path, factor, log)
            extra = ["--per-joint"] if per_joint and copy != "shared" else []
            r = identify(args.fivebar, scene, log, os.path.join(work, "out_%s_%s" % (tag, copy)),
                         extra)
            print("%-32s %-8s %3d %6s %9.3g %9.3g  %s" % (tag, copy, r["rc"], r["window"],
                                                         r["ratio"], r["floor"],
                                                         r["error"][:150]))
            if copy == "clean":
                clean_rejected += r["rc"] != 0
            elif copy == "shared":
                shared_total += 1
                shared_named += r["rc"] == 3 and "--per-joint" in r["error"]
            else:
                bad_total += 1
                bad_accepted += r["rc"] == 0
    print("clean logs rejected: %d of %d" % (clean_rejected, len(logs)))
    print("negated/halved logs accepted (exit 0): %d of %d" % (bad_accepted, bad_total))
    if shared_total:
        print("per-joint scenes' logs fitted with the shared law, rejected naming --per-joint: "
              "%d of %d" % (shared_named, shared_total))
    print("logs and outputs in " + work)


if __name__ == "__main__":
    main()

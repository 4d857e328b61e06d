#!/usr/bin/env python3
"""Monte-Carlo check of `fivebar excite`: predicted against empirical std.

For a design directory written by `fivebar excite` (excitation.csv, predicted_std.csv), logs
are made along the designed motion (`synth-log --motion`) and along the built-in multi-sine
(`synth-log --excitation multisine`) with seeds 1..N, each identified by `fivebar identify`;
the std of the estimates over the seeds is compared with the predicted std of
predicted_std.csv (columns std and multisine_std: identify's errors-in-variables std of a log
whose rates it estimates from the angles). With --with-rates the logs carry exact rates
(synth-log --with-rates): design with `excite --angle-noise 0` for a prediction of such logs.

  python3 scripts/excitation_report.py --design results/excite --seeds 50 --per-joint \\
      --out results/excite_mc

Options --estimate (passed to identify, for designs with --estimate friction,inertia) and
--duration (the multi-sine logs' length; the designed logs have the motion's). Writes
OUT/monte_carlo.csv (one row per parameter and motion) and prints a table. Not part of ctest:
50 seeds of two motions take minutes.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit("failed (%d): %s\n%s" % (p.returncode, " ".join(cmd), p.stderr))
    return p


def identify(args, log, work):
    # only the estimates are read: no validation runs
    cmd = [args.fivebar, "identify", args.scene, "--log", log, "--out", work, "--no-plots",
           "--no-validation"]
    if args.per_joint:
        cmd.append("--per-joint")
    if args.estimate:
        cmd += ["--estimate", args.estimate]
    run(cmd)
    with open(os.path.join(work, "identification.json")) as f:
        return {p["name"]: p["value"] for p in json.load(f)["parameters"]}


def estimates(args, motion, work):
    out = []
    for seed in range(1, args.seeds + 1):
        log = os.path.join(work, "%s_%d.csv" % (motion, seed))
        cmd = [args.fivebar, "synth-log", args.scene, "--out", log,
               "--seed", str(seed), "--torque-noise", str(args.torque_noise)]
        if args.with_rates:
            cmd.append("--with-rates")
        if motion == "designed":
            cmd += ["--motion", os.path.join(args.design, "excitation.csv")]
        else:
            cmd += ["--excitation", "multisine", "--duration", str(args.duration)]
        run(cmd)
        out.append(identify(args, log, os.path.join(work, "run_" + motion)))
        os.remove(log)
        print("  %s seed %d" % (motion, seed), file=sys.stderr)
    return out


def std(values):
    m = sum(values) / len(values)
    return math.sqrt(sum((v - m) ** 2 for v in values) / (len(values) - 1))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fivebar", default="build/release/apps/fivebar")
    ap.add_argument("--scene", default="datasets/scenes/paper.yaml")
    ap.add_argument("--design", required=True, help="output directory of fivebar excite")
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--per-joint", action="store_true")
    ap.add_argument("--estimate", default="")
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--torque-noise", type=float, default=0.02)
    ap.add_argument("--with-rates", action="store_true",
                    help="logs with exact rates (a design made with excite --angle-noise 0)")
    ap.add_argument("--out", default="results/excite_mc")
    ap.add_argument("--motions", default="designed,multisine",
                    help="which motions to run (designed, multisine or both)")
    args = ap.parse_args()
    work = os.path.join(args.out, "work")
    os.makedirs(work, exist_ok=True)
    with open(os.path.join(args.design, "predicted_std.csv")) as f:
        predicted = {r["name"]: r for r in csv.DictReader(f)}
    rows = []
    for motion, column in (("designed", "std"), ("multisine", "multisine_std")):
        if motion not in args.motions.split(","):
            continue
        est = estimates(args, motion, work)
        for name in est[0]:
            if name not in predicted:
                continue
            emp = std([e[name] for e in est])
            pred = float(predicted[name][column])
            value = float(predicted[name]["value"])
            rows.append({"motion": motion, "parameter": name, "predicted_std": "%.4g" % pred,
                         "empirical_std": "%.4g" % emp, "ratio": "%.3f" % (emp / pred),
                         "predicted_relative_std": "%.4g" % (pred / abs(value)) if value else "",
                         "empirical_relative_std": "%.4g" % (emp / abs(value)) if value else ""})
    with open(os.path.join(args.out, "monte_carlo.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print("| motion | parameter | predicted std | empirical std (%d seeds) | ratio |" % args.seeds)
    print("|---|---|---|---|---|")
    for r in rows:
        print("| %s | %s | %s | %s | %s |" % (r["motion"], r["parameter"], r["predicted_std"],
                                            r["empirical_std"], r["ratio"]))
    worst = max(abs(float(r["ratio"]) - 1) for r in rows)
    print("\nlargest |empirical / predicted - 1|: %.3f" % worst)


if __name__ == "__main__":
    main()

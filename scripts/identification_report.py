#!/usr/bin/env python3
"""Identification reports of issue 4, driving the `fivebar` executable.

  error-vs-time: parameter error against identification wall time as the log length and the
                 method vary (inverse-dynamics with logged rates, inverse-dynamics from angles
                 only, output-error), on the paper scene (torque noise 0.02 N m, angle 1e-5 rad).
  coverage:      per-joint fit on logs with distinct coefficients (multisine excitation) over N
                 seeds: the fraction of 95 % intervals (value +- 1.96 std) that cover the truth.

Usage (from the repository root, after building `fivebar`):
  scripts/identification_report.py error-vs-time [--fivebar PATH] [--out DIR]
  scripts/identification_report.py coverage [--seeds 50] [--duration 10] [--fivebar PATH] [--out DIR]
Writes DIR/<report>.csv and prints a Markdown table. Logs and runs go to DIR/work/.
"""
import argparse
import csv
import json
import os
import subprocess
import sys

SCENE = "datasets/scenes/paper.yaml"
PER_JOINT_SETS = ["--set", "friction.coulomb=[0.08,0.10,0.12,0.14,0.16]",
                  "--set", "friction.viscous=[0.010,0.015,0.020,0.025,0.030]"]


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        sys.exit("failed (%d): %s\n%s" % (r.returncode, " ".join(cmd), r.stderr))
    return r.stdout


def synth(fivebar, out, duration, seed, rates, extra=()):
    cmd = [fivebar, "synth-log", SCENE, "--out", out, "--duration", str(duration),
           "--seed", str(seed)] + list(extra)
    if rates:
        cmd.append("--with-rates")
    run(cmd)


def identify(fivebar, log, out, extra=()):
    run([fivebar, "identify", SCENE, "--log", log, "--out", out, "--no-plots",
         "--no-validation"] + list(extra))
    with open(os.path.join(out, "identification.json")) as f:
        return json.load(f)


def error_vs_time(args):
    work = os.path.join(args.out, "work")
    os.makedirs(work, exist_ok=True)
    cases = [("inverse-dynamics", True, []), ("inverse-dynamics", False, []),
             ("output-error", True, ["--method", "output-error"])]
    rows = []
    for duration in args.durations:
        for rates in (True, False):
            synth(args.fivebar, os.path.join(work, "log_%g_%d.csv" % (duration, rates)),
                  duration, 1, rates)
        for method, rates, extra in cases:
            if method == "output-error" and duration > args.max_output_error_duration:
                continue
            log = os.path.join(work, "log_%g_%d.csv" % (duration, rates))
            j = identify(args.fivebar, log, os.path.join(work, "run"), extra)
            p = {q["name"]: q for q in j["parameters"]}
            rows.append({
                "duration_s": duration, "method": method,
                "rates": "logged" if rates else "savitzky-golay",
                "wall_time_s": round(j["identification_wall_time_s"], 3),
                "coulomb_rel_error": "%.2e" % p["coulomb"]["relative_error"],
                "viscous_rel_error": "%.2e" % p["viscous"]["relative_error"],
                "coulomb_error_in_std": "%.2f" % p["coulomb"]["error_in_std"],
                "viscous_error_in_std": "%.2f" % p["viscous"]["error_in_std"],
            })
            print("  %s" % rows[-1], file=sys.stderr)
    return rows


def coverage(args):
    work = os.path.join(args.out, "work")
    os.makedirs(work, exist_ok=True)
    covered, total, rows = {}, {}, []
    for seed in range(1, args.seeds + 1):
        log = os.path.join(work, "pj_%d.csv" % seed)
        synth(args.fivebar, log, args.duration, seed, True,
              ["--excitation", "multisine"] + PER_JOINT_SETS)
        j = identify(args.fivebar, log, os.path.join(work, "run"), ["--per-joint"])
        within3 = True
        for q in j["parameters"]:
            hit = abs(q["error"]) <= 1.96 * q["std"]
            covered[q["name"]] = covered.get(q["name"], 0) + int(hit)
            total[q["name"]] = total.get(q["name"], 0) + 1
            within3 = within3 and abs(q["error"]) <= 3 * q["std"]
        rows.append({"seed": seed, "wall_time_s": round(j["identification_wall_time_s"], 3),
                     "all_within_3_std": within3,
                     "max_abs_error_in_std": "%.2f" % max(abs(q["error_in_std"])
                                                          for q in j["parameters"])})
        os.remove(log)
        print("  seed %d: %s" % (seed, rows[-1]), file=sys.stderr)
    summary = [{"parameter": n, "covered": covered[n], "seeds": total[n],
                "coverage": "%.3f" % (covered[n] / total[n])} for n in covered]
    hits = sum(covered.values())
    summary.append({"parameter": "all", "covered": hits, "seeds": sum(total.values()),
                    "coverage": "%.3f" % (hits / sum(total.values()))})
    return rows, summary


def table(rows):
    keys = list(rows[0].keys())
    out = "| " + " | ".join(keys) + " |\n|" + "---|" * len(keys) + "\n"
    for r in rows:
        out += "| " + " | ".join(str(r[k]) for k in keys) + " |\n"
    return out


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("report", choices=["error-vs-time", "coverage"])
    ap.add_argument("--fivebar", default="build/release/apps/fivebar")
    ap.add_argument("--out", default="results/identification_report")
    ap.add_argument("--durations", type=float, nargs="+", default=[1, 2, 5, 10])
    ap.add_argument("--max-output-error-duration", type=float, default=10)
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--duration", type=float, default=10)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.report == "error-vs-time":
        rows = error_vs_time(args)
        write_csv(os.path.join(args.out, "error_vs_time.csv"), rows)
        print(table(rows))
    else:
        rows, summary = coverage(args)
        write_csv(os.path.join(args.out, "coverage_runs.csv"), rows)
        write_csv(os.path.join(args.out, "coverage.csv"), summary)
        print(table(summary))
        print("runs with every coefficient within 3 std: %d / %d"
              % (sum(r["all_within_3_std"] for r in rows), len(rows)))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Identification reports, driving the `fivebar` executable.

  error-vs-time: parameter error against identification wall time as the log length and the
                 method vary (inverse-dynamics with logged rates, inverse-dynamics from angles
                 only, output-error), on the paper scene (torque noise 0.02 N m, angle 1e-5 rad).
  coverage:      per-joint fit on logs with distinct coefficients (multisine excitation) over N
                 seeds: the fraction of 95 % intervals (value +- 1.96 std) that cover the truth.
  coverage-angles: angles-only logs (or noisy measured rates) over N seeds, for a case:
                 shared (paper loads, 1 kHz), shared200 (200 Hz), per-joint (multisine),
                 stribeck (500 Hz, 6 s), noisy-rates (--with-rates --rate-noise 0.05),
                 output-error (--method output-error, rates logged; output-error-angles
                 from angles only). Also reports the mean error in reported std (the bias) and
                 the rms of the errors in reported std (1 when the std are honest). An interval
                 covers when the reported ci95_low..ci95_high (profile likelihood or Wald with
                 the reported quantile) holds the truth; value +- 1.96 std without them.
  fixed-motion:  Monte Carlo on one fixed motion: a noise-free log of the case is
                 written once, then only the noise is redrawn (Python's random, seeded by --seed:
                 white Gaussian torque noise --torque-noise, angle noise --angle-noise; logged
                 rates, if the case has them, stay exact) over
                 --draws logs, each identified as coverage-angles does. Reports coverage, the
                 mean and rms of error/std, the spread over the draws against the mean reported
                 std, the quantiles of error/std and the tail counts (|z| > 2.5, > 2.8) against
                 those of a standard normal: whether the reported std is honest, without the
                 luck of a few seeds.
  coverage-inertia: logs whose true links are 3-6 % off the scene (CAD_MISMATCH_SETS),
                 identified with the nominal scene and --estimate friction,inertia, over N seeds,
                 --case shared (paper loads) or per-joint (multisine, distinct coefficients):
                 coverage of the 95 % intervals of the friction coefficients (and of the
                 inertial parameters), |error| <= 3 std, reported std against the Cramer-Rao
                 bound and against the spread over the seeds, wall time.
  fuzz:          N seeded corruptions of a short log (1e300, wrapped, spikes, constant
                 angles, degrees, offsets, ...) through `fivebar identify`; counts the exit
                 statuses and fails if any run ends by a signal or without its one-line message.

Usage (from the repository root, after building `fivebar`):
  scripts/identification_report.py error-vs-time [--fivebar PATH] [--out DIR]
  scripts/identification_report.py coverage [--seeds 50] [--duration 10] [--fivebar PATH] [--out DIR]
  scripts/identification_report.py coverage-angles --case shared [--seeds 30] [--duration 2]
  scripts/identification_report.py fixed-motion --case shared [--draws 300] [--duration 2]
  scripts/identification_report.py coverage-inertia --case per-joint [--seeds 50] [--duration 10]
  scripts/identification_report.py fuzz [--runs 1000] [--seed 16]
Writes DIR/<report>.csv and prints a Markdown table. Logs and runs go to DIR/work/.
"""
import argparse
import csv
import json
import math
import os
import random
import subprocess
import sys

SCENE = "datasets/scenes/paper.yaml"
PER_JOINT_SETS = ["--set", "friction.coulomb=[0.08,0.10,0.12,0.14,0.16]",
                  "--set", "friction.viscous=[0.010,0.015,0.020,0.025,0.030]"]

# the true mechanism of a CAD-mismatch log: masses, COM offsets and inertias 3-6 % off paper.yaml
CAD_MISMATCH_SETS = sum([["--set", kv] for kv in [
    "mechanism.links.0.mass=1.04", "mechanism.links.1.mass=0.95",
    "mechanism.links.2.mass=1.05", "mechanism.links.3.mass=0.96",
    "mechanism.links.0.inertia=0.106", "mechanism.links.1.inertia=0.095",
    "mechanism.links.2.inertia=0.104", "mechanism.links.3.inertia=0.103",
    "mechanism.links.0.com_offset=0.052", "mechanism.links.1.com_offset=0.0285",
    "mechanism.links.2.com_offset=0.19", "mechanism.links.3.com_offset=0.156"]], [])


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
            hit = covers(q, q["std"])
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


def coverage_inertia(args):
    work = os.path.join(args.out, "work")
    os.makedirs(work, exist_ok=True)
    per_joint = args.case == "per-joint"
    synth_extra = CAD_MISMATCH_SETS + (["--excitation", "multisine"] + PER_JOINT_SETS
                                       if per_joint else [])
    id_extra = ["--estimate", "friction,inertia"] + (["--per-joint"] if per_joint else [])
    stats, rows = {}, []
    for seed in range(1, args.seeds + 1):
        log = os.path.join(work, "cad_%d.csv" % seed)
        synth(args.fivebar, log, args.duration, seed, True, synth_extra)
        j = identify(args.fivebar, log, os.path.join(work, "run"), id_extra)
        within3 = True
        for q in j["parameters"]:
            e = stats.setdefault(q["name"], {"hit": 0, "n": 0, "values": [], "std": [],
                                             "crb": [], "inertial": "_" in q["name"] and
                                             q["name"].split("_")[0] in ("m", "mx", "my", "J")})
            e["n"] += 1
            e["hit"] += int(covers(q, q["std"]))
            e["values"].append(q["value"] - q["true"])
            e["std"].append(q["std"])
            e["crb"].append(q.get("cramer_rao_std") or float("nan"))
            if not e["inertial"]:
                within3 = within3 and abs(q["error"]) <= 3 * q["std"]
        friction = [q for q in j["parameters"] if not stats[q["name"]]["inertial"]]
        rows.append({"seed": seed, "wall_time_s": round(j["identification_wall_time_s"], 3),
                     "friction_within_3_std": within3,
                     "max_abs_friction_error_in_std": "%.2f" % max(abs(q["error_in_std"])
                                                                   for q in friction),
                     "residual_to_noise": "%.3f" % max(j["residual_to_noise_ratio"])})
        os.remove(log)
        print("  seed %d: %s" % (seed, rows[-1]), file=sys.stderr)
    summary = []
    for group in (False, True):
        hits = n = 0
        for name, e in stats.items():
            if e["inertial"] != group:
                continue
            mean_std = sum(e["std"]) / len(e["std"])
            spread = math.sqrt(sum(v * v for v in e["values"]) / len(e["values"]))
            summary.append({"parameter": name, "coverage": "%.3f" % (e["hit"] / e["n"]),
                            "mean_std": "%.3g" % mean_std,
                            "rms_error_over_seeds": "%.3g" % spread,
                            "std_over_cramer_rao": "%.2f" % (mean_std / (sum(e["crb"]) /
                                                                         len(e["crb"])))})
            hits += e["hit"]
            n += e["n"]
        summary.append({"parameter": "all inertial" if group else "all friction",
                        "coverage": "%.3f" % (hits / n), "mean_std": "",
                        "rms_error_over_seeds": "", "std_over_cramer_rao": ""})
    times = sorted(r["wall_time_s"] for r in rows)
    summary.append({"parameter": "wall time s (median, max)",
                    "coverage": "%.2f, %.2f" % (times[len(times) // 2], times[-1]),
                    "mean_std": "", "rms_error_over_seeds": "", "std_over_cramer_rao": ""})
    return rows, summary


CASES = {
    # name: (synth-log options, identify options, parameters checked)
    "shared": (["--rate", "1000"], [], None),
    "shared200": (["--rate", "200"], [], None),
    "per-joint": (["--excitation", "multisine"] + PER_JOINT_SETS, ["--per-joint"], None),
    "stribeck": (["--excitation", "multisine", "--rate", "500", "--law", "stribeck",
                  "--static-coulomb", "0.2", "--stribeck-velocity", "0.5"],
                 ["--law", "stribeck"], None),
    "noisy-rates": (["--with-rates", "--rate-noise", "0.05"], [], None),
    # for diagnosis: the shared case's torque noise alone (exact angles; the draws of a seed
    # are the same as in `shared`), and with exact logged rates (plain least squares)
    "torque-noise-only": (["--angle-noise", "0"], [], None),
    "exact-rates": (["--with-rates", "--angle-noise", "0"], [], None),
    # the output-error method (windows of 0.2 s restarted from the logged state)
    "output-error": (["--with-rates"], ["--method", "output-error"], None),
    "output-error-angles": ([], ["--method", "output-error"], None),
}


def covers(q, std):
    """Whether the reported 95 % interval of parameter q covers its true value: ci95_low..
    ci95_high when identification.json gives them (null with ci95_unbounded: open on that side),
    else value +- 1.96 std. A missing std covers nothing."""
    if q.get("ci95_method"):
        open_side = q.get("ci95_unbounded", "")
        low = -math.inf if open_side in ("low", "both") else q["ci95_low"]
        high = math.inf if open_side in ("high", "both") else q["ci95_high"]
        if low is not None and high is not None:
            return low <= q["true"] <= high
    return abs(q["error"]) <= 1.96 * std


def coverage_angles(args):
    work = os.path.join(args.out, "work")
    os.makedirs(work, exist_ok=True)
    synth_opts, id_opts, _ = CASES[args.case]
    covered, total, errors, rows = {}, {}, {}, []
    in_std = {}
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        log = os.path.join(work, "%s_%d.csv" % (args.case, seed))
        synth(args.fivebar, log, args.duration, seed, False, synth_opts)
        j = identify(args.fivebar, log, os.path.join(work, "run_" + args.case),
                     id_opts + args.identify_args.split())
        for q in j["parameters"]:
            std = q["std"] if q["std"] is not None else float("nan")
            hit = covers(q, std)
            covered[q["name"]] = covered.get(q["name"], 0) + int(hit)
            total[q["name"]] = total.get(q["name"], 0) + 1
            errors.setdefault(q["name"], []).append(q["relative_error"])
            in_std.setdefault(q["name"], []).append(q["error"] / std)
        rows.append({"seed": seed, "window": j["rate_source"].get("sg_half_window_samples", ""),
                     "wall_time_s": round(j["identification_wall_time_s"], 3),
                     "std_method": j.get("std_method", ""),
                     "max_abs_error_in_std": "%.2f" % max(
                         abs(q["error_in_std"]) if q["error_in_std"] is not None else float("inf")
                         for q in j["parameters"])})
        rows[-1].update({"error_in_std_" + q["name"]: "%.2f" % (q["error"] / (q["std"] or math.nan))
                         for q in j["parameters"]})
        os.remove(log)
        print("  seed %d: %s" % (seed, rows[-1]), file=sys.stderr)
    summary = []
    for n in covered:
        e = errors[n]
        mean = sum(e) / len(e)
        z = in_std[n]
        summary.append({"parameter": n, "covered": covered[n], "seeds": total[n],
                        "coverage": "%.3f" % (covered[n] / total[n]),
                        "mean_rel_error": "%+.4f" % mean,
                        "max_abs_rel_error": "%.4f" % max(abs(x) for x in e),
                        # the bias in reported std, and the rms of the errors in reported std
                        # (1 when the std are honest)
                        "mean_error_in_std": "%+.2f" % (sum(z) / len(z)),
                        "rms_error_in_std": "%.2f" % math.sqrt(sum(x * x for x in z) / len(z)),
                        "abs_z_over_2.8": sum(abs(x) > 2.8 for x in z)})
    hits = sum(covered.values())
    summary.append({"parameter": "all", "covered": hits, "seeds": sum(total.values()),
                    "coverage": "%.3f" % (hits / sum(total.values())), "mean_rel_error": "",
                    "max_abs_rel_error": "", "mean_error_in_std": "",
                    "rms_error_in_std": "", "abs_z_over_2.8": ""})
    return rows, summary


def z_tail(k):
    """P(|Z| > k) for a standard normal Z."""
    return math.erfc(k / math.sqrt(2))


def fixed_motion_summary(name, errors, stds, hits):
    """One row of the fixed-motion report: coverage, error/std statistics and tails."""
    n = len(errors)
    z = sorted(e / s for e, s in zip(errors, stds))
    mean_e = sum(errors) / n
    spread = math.sqrt(sum((e - mean_e) ** 2 for e in errors) / (n - 1))
    q = lambda f: z[min(n - 1, int(f * n))]
    return {"parameter": name, "draws": n, "coverage": "%.3f" % (hits / n),
            "mean_z": "%+.2f" % (sum(z) / n),
            "rms_z": "%.2f" % math.sqrt(sum(x * x for x in z) / n),
            "spread_over_mean_std": "%.3f" % (spread / (sum(stds) / n)),
            "z_1_5_50_95_99_pct": " ".join("%.2f" % q(f) for f in (0.01, 0.05, 0.5, 0.95, 0.99)),
            "abs_z_over_2.5": "%d (normal %.1f)" % (sum(abs(x) > 2.5 for x in z), n * z_tail(2.5)),
            "abs_z_over_2.8": "%d (normal %.1f)" % (sum(abs(x) > 2.8 for x in z), n * z_tail(2.8))}


def noisy_copy(header, data, rng, torque_noise, angle_noise):
    """The lines of a log: the noise-free rows with fresh Gaussian noise on angles and torques."""
    out = list(header)
    for r in data:
        r = list(r)
        for c, s in ((3, torque_noise), (4, torque_noise), (1, angle_noise), (2, angle_noise)):
            if s > 0:
                r[c] += s * rng.gauss(0.0, 1.0)
        out.append(",".join(repr(x) for x in r) + "\n")
    return out


def fixed_motion(args):
    work = os.path.join(args.out, "work")
    os.makedirs(work, exist_ok=True)
    synth_opts, id_opts, _ = CASES[args.case]
    # the case's motion without noise (its own noise options dropped: only the draws here count)
    noise_opts = ("--torque-noise", "--angle-noise", "--rate-noise")
    synth_opts = [o for i, o in enumerate(synth_opts)
                  if o not in noise_opts and (i == 0 or synth_opts[i - 1] not in noise_opts)]
    base = os.path.join(work, "fixed_%s_clean.csv" % args.case)
    synth(args.fivebar, base, args.duration, 1, False,
          synth_opts + ["--torque-noise", "0", "--angle-noise", "0"])
    header, data = read_log(base)
    rng = random.Random(args.seed)
    errors, stds, hits, rows = {}, {}, {}, []
    log = os.path.join(work, "fixed_%s.csv" % args.case)
    for draw in range(args.draws):
        with open(log, "w") as f:
            f.writelines(noisy_copy(header, data, rng, args.torque_noise, args.angle_noise))
        j = identify(args.fivebar, log, os.path.join(work, "run_fixed_" + args.case),
                     id_opts + args.identify_args.split())
        row = {"draw": draw, "window": j["rate_source"].get("sg_half_window_samples", "")}
        for q in j["parameters"]:
            std = q["std"] if q["std"] is not None else float("nan")
            errors.setdefault(q["name"], []).append(q["error"])
            stds.setdefault(q["name"], []).append(std)
            hits[q["name"]] = hits.get(q["name"], 0) + int(covers(q, std))
            row["error_in_std_" + q["name"]] = "%.3f" % (q["error"] / std)
        rows.append(row)
        if (draw + 1) % 50 == 0:
            print("  %d draws" % (draw + 1), file=sys.stderr)
    summary = [fixed_motion_summary(n, errors[n], stds[n], hits[n]) for n in errors]
    return rows, summary


def read_log(path):
    """A log's header lines and its data rows (lists of floats)."""
    header, data = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or line.startswith("t,"):
                header.append(line)
            else:
                data.append([float(x) for x in line.split(",")])
    return header, data


def corrupt(lines, rng):
    """One fuzzed log from the data lines of a log (lists of floats: t, theta1, theta2, tau1,
    tau2): one to three corruptions of the kinds the fuzz mode's description lists, and more."""
    rows = [list(r) for r in lines]
    n = len(rows)
    kinds = []
    for _ in range(rng.randint(1, 3)):
        kind = rng.choice(["huge", "wrap", "spike", "constant", "degrees", "offset", "noise",
                           "scale", "zero_torque", "huge_torque", "spikes", "step"])
        kinds.append(kind)
        i, c = rng.randrange(n), rng.choice([1, 2, 3, 4])
        if kind == "huge":
            rows[i][c] = rng.choice([1e300, -1e300, 1e308, 1e100, 1e3, 100.0])
        elif kind == "wrap":
            for r in rows:
                for k in (1, 2):
                    r[k] = math.atan2(math.sin(r[k]), math.cos(r[k]))
        elif kind == "spike":
            rows[i][c] += rng.choice([-1, 1]) * 10 ** rng.uniform(-3, 3)
        elif kind == "spikes":
            for _ in range(rng.randint(2, 20)):
                rows[rng.randrange(n)][c] += 10 ** rng.uniform(-2, 2)
        elif kind == "constant":
            for r in rows:
                r[c if c <= 2 else 1] = rows[i][c if c <= 2 else 1]
        elif kind == "degrees":
            for r in rows:
                r[1] *= 180 / math.pi
                r[2] *= 180 / math.pi
        elif kind == "offset":
            for r in rows[i:]:
                r[c] += rng.choice([2 * math.pi, 4 * math.pi, 1.0, 1e6])
        elif kind == "noise":
            s = 10 ** rng.uniform(-4, 1)
            for r in rows:
                r[c] += rng.gauss(0, s)
        elif kind == "scale":
            f = 10 ** rng.uniform(-3, 3)
            for r in rows:
                r[c] *= f
        elif kind == "zero_torque":
            for r in rows:
                r[3] = r[4] = 0.0
        elif kind == "huge_torque":
            for r in rows:
                r[c if c >= 3 else 3] *= 1e150
        elif kind == "step":
            for r in rows[i:]:
                r[c] += 10 ** rng.uniform(-2, 2)
    return rows, kinds


def fuzz(args):
    work = os.path.join(args.out, "work")
    os.makedirs(work, exist_ok=True)
    base = os.path.join(work, "fuzz_base.csv")
    synth(args.fivebar, base, args.fuzz_duration, 1, False)
    header, data = read_log(base)
    rng = random.Random(args.seed)
    counts, bad, rows = {}, [], []
    log = os.path.join(work, "fuzz.csv")
    for run_i in range(args.runs):
        rows_, kinds = corrupt(data, rng)
        with open(log, "w") as f:
            f.writelines(header)
            for r in rows_:
                f.write(",".join(repr(x) for x in r) + "\n")
        cmd = [args.fivebar, "identify", SCENE, "--log", log, "--out",
               os.path.join(work, "fuzz_run"), "--no-plots"]
        try:
            r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               timeout=args.timeout)
            code = r.returncode
            err = [l for l in r.stderr.splitlines() if l.startswith("fivebar: error: ")]
        except subprocess.TimeoutExpired:
            code, err = "timeout", []
        key = str(code)
        counts[key] = counts.get(key, 0) + 1
        ok = code in (0, 2, 3) and (code == 0 or len(err) == 1)
        if not ok:
            bad.append((run_i, kinds, code))
            keep = os.path.join(work, "fuzz_bad_%d.csv" % run_i)
            os.replace(log, keep)
            print("  run %d %s: exit %s (kept %s)" % (run_i, kinds, code, keep), file=sys.stderr)
        rows.append({"run": run_i, "kinds": "+".join(kinds), "exit": code,
                     "message": err[0][len("fivebar: error: "):] if err else ""})
        if (run_i + 1) % 100 == 0:
            print("  %d runs: %s" % (run_i + 1, counts), file=sys.stderr)
    summary = [{"exit": k, "runs": v} for k, v in sorted(counts.items())]
    summary.append({"exit": "signal, timeout or no message", "runs": len(bad)})
    return rows, summary, bad


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


# reports that write a per-run table and a summary: function, file stem (with the case), and
# the per-run column counting runs within 3 std with what it counts
SUMMARY_REPORTS = {
    "coverage": (coverage, "coverage", ("all_within_3_std", "coefficient")),
    "coverage-angles": (coverage_angles, "coverage_%s", None),
    "fixed-motion": (fixed_motion, "fixed_motion_%s", None),
    "coverage-inertia": (coverage_inertia, "coverage_inertia_%s",
                         ("friction_within_3_std", "friction coefficient")),
}


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("report", choices=["error-vs-time", "coverage", "coverage-angles",
                                       "coverage-inertia", "fixed-motion", "fuzz"])
    ap.add_argument("--case", choices=sorted(CASES), default="shared",
                    help="coverage-angles: any; coverage-inertia: shared or per-joint")
    ap.add_argument("--identify-args", default="",
                    help="coverage-angles, fixed-motion: more options for identify (e.g. '--classical-std')")
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=16)
    ap.add_argument("--fuzz-duration", type=float, default=0.3)
    ap.add_argument("--timeout", type=float, default=120)
    ap.add_argument("--fivebar", default="build/release/apps/fivebar")
    ap.add_argument("--out", default="results/identification_report")
    ap.add_argument("--durations", type=float, nargs="+", default=[1, 2, 5, 10])
    ap.add_argument("--max-output-error-duration", type=float, default=10)
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--first-seed", type=int, default=1, help="coverage-angles: seeds from this one")
    ap.add_argument("--draws", type=int, default=300, help="fixed-motion: noise draws")
    ap.add_argument("--torque-noise", type=float, default=0.02, help="fixed-motion [N m]")
    ap.add_argument("--angle-noise", type=float, default=1e-5, help="fixed-motion [rad]")
    ap.add_argument("--duration", type=float, default=10)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.report == "error-vs-time":
        rows = error_vs_time(args)
        write_csv(os.path.join(args.out, "error_vs_time.csv"), rows)
        print(table(rows))
    elif args.report == "fuzz":
        rows, summary, bad = fuzz(args)
        write_csv(os.path.join(args.out, "fuzz_runs.csv"), rows)
        write_csv(os.path.join(args.out, "fuzz.csv"), summary)
        print(table(summary))
        if bad:
            sys.exit("%d of %d fuzzed runs ended by a signal, a timeout or without a message"
                     % (len(bad), args.runs))
    else:
        report, stem, within3 = SUMMARY_REPORTS[args.report]
        rows, summary = report(args)
        stem = stem % args.case if "%s" in stem else stem
        write_csv(os.path.join(args.out, stem + "_runs.csv"), rows)
        write_csv(os.path.join(args.out, stem + ".csv"), summary)
        print(table(summary))
        if within3:
            print("runs with every %s within 3 std: %d / %d"
                  % (within3[1], sum(r[within3[0]] for r in rows), len(rows)))


if __name__ == "__main__":
    main()

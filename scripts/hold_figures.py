#!/usr/bin/env python3
"""Figures of rest and holding (docs/hold.md), measured end to end with the fivebar executable.

1. The paper start pose (pi/2, pi/2) held still for 1 s at 1 kHz, angles only: `fivebar inverse`
   must give the frictionless equilibrium torques (those of the frictionless scene) to 1e-9 N m
   on every row, with a holding range that contains them; angle noise of 1e-12 rad (seeded,
   Gaussian) must change nothing.
2. `fivebar hold` at that pose; `fivebar simulate` from rest with constant torques inside the
   ranges (99 % of the way to each end, the other actuator at its equilibrium; and corners of the
   crank joints' rectangle) must move less than 1e-12 rad over 1 s, and just outside (101 %) must
   break away.

Usage: python3 scripts/hold_figures.py [--fivebar build/release/apps/fivebar] [--work DIR]
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
FRICTIONLESS = "datasets/scenes/paper_frictionless.yaml"


def run(fivebar, *args):
    subprocess.run([fivebar, *args], check=True, stdout=subprocess.DEVNULL)


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def static_motion(path, noise, seed=14):
    rng = random.Random(seed)
    with open(path, "w") as f:
        f.write("t,theta1,theta2\n")
        for i in range(1001):
            a = math.pi / 2 + (rng.gauss(0, noise) if noise else 0.0)
            b = math.pi / 2 + (rng.gauss(0, noise) if noise else 0.0)
            f.write("%.17g,%.17g,%.17g\n" % (i * 1e-3, a, b))


def inverse_figures(fivebar, work):
    static_motion(f"{work}/static.csv", 0.0)
    static_motion(f"{work}/static_noise.csv", 1e-12)
    run(fivebar, "inverse", FRICTIONLESS, "--motion", f"{work}/static.csv", "--out",
        f"{work}/frictionless", "--no-plots")
    reference = rows(f"{work}/frictionless/trajectory.csv")
    results = {}
    for name in ("static", "static_noise"):
        run(fivebar, "inverse", SCENE, "--motion", f"{work}/{name}.csv", "--out", f"{work}/{name}",
            "--no-plots")
        r = rows(f"{work}/{name}/trajectory.csv")
        err = max(max(abs(float(x["M1"]) - float(y["M1"])), abs(float(x["M2"]) - float(y["M2"])))
                  for x, y in zip(r, reference))
        contains = all(float(x["M1_hold_min"]) <= float(y["M1"]) <= float(x["M1_hold_max"]) and
                       float(x["M2_hold_min"]) <= float(y["M2"]) <= float(x["M2_hold_max"])
                       for x, y in zip(r, reference))
        at_rest = sum(int(float(x["at_rest"])) for x in r)
        print(f"inverse {name}: {at_rest}/{len(r)} rows at rest; M1 = {r[0]['M1']}, "
              f"M2 = {r[0]['M2']} N m; max |M - frictionless equilibrium| = {err:.3g} N m; "
              f"range [{r[0]['M1_hold_min']}, {r[0]['M1_hold_max']}] x "
              f"[{r[0]['M2_hold_min']}, {r[0]['M2_hold_max']}] contains it: {contains}")
        results[name] = r
    change = max(abs(float(x[c]) - float(y[c]))
                 for x, y in zip(results["static"], results["static_noise"])
                 for c in ("M1", "M2", "M1_hold_min", "M1_hold_max", "M2_hold_min", "M2_hold_max"))
    flags = all(x[c] == y[c] for x, y in zip(results["static"], results["static_noise"])
                for c in ("at_rest", "stuck1", "stuck2", "stuck3", "stuck4", "stuck5"))
    print(f"1e-12 rad angle noise: max change of torques and ranges {change:.3g} N m; "
          f"rest and stuck flags identical: {flags}")


def displacement(path):
    r = rows(path)
    return max(abs(float(x[c]) - float(r[0][c])) for x in r for c in ("theta1", "theta2"))


def simulate_figures(fivebar, work):
    run(fivebar, "hold", SCENE, "--out", f"{work}/hold")
    with open(f"{work}/hold/hold.json") as f:
        h = json.load(f)
    M1, M2 = h["M1"], h["M2"]
    (lo1, hi1), (lo2, hi2) = h["range_M1"], h["range_M2"]
    (c1, d1), (c2, d2) = h["crank_joint_range_M1"], h["crank_joint_range_M2"]
    cases = {
        "equilibrium": (M1, M2),
        "inside M1 +99%": (M1 + 0.99 * (hi1 - M1), M2),
        "inside M1 -99%": (M1 - 0.99 * (M1 - lo1), M2),
        "inside M2 +99%": (M1, M2 + 0.99 * (hi2 - M2)),
        "inside M2 -99%": (M1, M2 - 0.99 * (M2 - lo2)),
        "inside crank corner (+99%, -99%)": (M1 + 0.99 * (d1 - M1), M2 - 0.99 * (M2 - c2)),
        "inside crank corner (-99%, +99%)": (M1 - 0.99 * (M1 - c1), M2 + 0.99 * (d2 - M2)),
        "outside M1 +101%": (M1 + 1.01 * (hi1 - M1), M2),
        "outside M1 -101%": (M1 - 1.01 * (M1 - lo1), M2),
        "outside M2 +101%": (M1, M2 + 1.01 * (hi2 - M2)),
        "outside M2 -101%": (M1, M2 - 1.01 * (M2 - lo2)),
    }
    for name, (a, b) in cases.items():
        out = f"{work}/sim_" + "".join(ch if ch.isalnum() else "_" for ch in name)
        run(fivebar, "simulate", SCENE, "--set", f"loads.M1={a!r}", "--set", f"loads.M2={b!r}",
            "--set", "simulation.duration=1", "--out", out, "--no-plots")
        print(f"simulate from rest, {name}: M1 = {a:.12g}, M2 = {b:.12g} N m -> "
              f"max |theta - theta(0)| over 1 s = {displacement(out + '/trajectory.csv'):.3g} rad")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fivebar", default="build/release/apps/fivebar")
    p.add_argument("--work", default="results/hold_figures")
    a = p.parse_args()
    os.makedirs(a.work, exist_ok=True)
    inverse_figures(a.fivebar, a.work)
    simulate_figures(a.fivebar, a.work)


if __name__ == "__main__":
    sys.exit(main())

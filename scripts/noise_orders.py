#!/usr/bin/env python3
"""Noise estimates of sampled series by difference order (series_noise, docs/hold.md).

    python3 scripts/noise_orders.py results/opt/swing_right/trajectory.csv omega1 omega2
    python3 scripts/noise_orders.py --colored

For each named column of a CSV (lines starting with '#' skipped), prints
s_k = median |k-th difference| / (0.6745 sqrt(C(2k, k))) for k = 1..8, the fourth-difference
estimate s_4 (the simpler one) and the estimate series_noise gives: s_k at the
first order whose successor is not below 0.9 s_k. --colored prints both estimates, relative to
the deviation, for white and coloured noise (5000 samples, seeded). A mirror of
model/include/fivebar/model/rest_rule.h for measurement; fivebar itself uses the C++.
Standard library only.
"""
import argparse
import csv
import math
import random
import statistics
import sys

MAX_ORDER, FLAT_RATIO = 8, 0.9


def order_estimates(f):
    """s_1 .. s_8 (orders with at least 5 differences)."""
    out, d = [], list(f)
    for k in range(1, MAX_ORDER + 1):
        if len(d) < 6:
            break
        d = [d[i + 1] - d[i] for i in range(len(d) - 1)]
        upper_median = sorted(abs(x) for x in d)[len(d) // 2]
        out.append(upper_median / 0.6745 / math.sqrt(math.comb(2 * k, k)))
    return out


def walk(s):
    """(estimate, order): the first s_k whose successor is not below FLAT_RATIO s_k."""
    for k in range(len(s) - 1):
        if s[k + 1] >= FLAT_RATIO * s[k]:
            return s[k], k + 1
    return s[-1], len(s)


def colored():
    rng = random.Random(2)
    n = 5000
    e = [rng.gauss(0, 1) for _ in range(n + 10)]
    low, y = [], 0.0
    for x in e:
        y = 0.7 * y + 0.3 * x
        low.append(y)
    cases = {
        "white": e[:n],
        "central difference": [(e[i + 2] - e[i]) / 2 for i in range(n)],
        "5-point difference": [(-e[i + 4] + 8 * e[i + 3] - 8 * e[i + 1] + e[i]) / 12
                               for i in range(n)],
        "first-order filter 0.7": low[10:n + 10],
        "moving average 3": [(e[i] + e[i + 1] + e[i + 2]) / 3 for i in range(n)],
    }
    for name, f in cases.items():
        sd, s = statistics.pstdev(f), order_estimates(f)
        w, k = walk(s)
        print(f"{name:24s} estimate/std {w / sd:.3f} (order {k}), fourth difference {s[3] / sd:.3f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("csv", nargs="?")
    parser.add_argument("columns", nargs="*")
    parser.add_argument("--colored", action="store_true", help="the coloured-noise table")
    args = parser.parse_args()
    if args.colored:
        colored()
        return 0
    if not args.csv or not args.columns:
        parser.print_usage(sys.stderr)
        return 2
    with open(args.csv, newline="") as handle:
        rows = list(csv.DictReader(line for line in handle if not line.startswith("#")))
    for name in args.columns:
        s = order_estimates([float(row[name]) for row in rows])
        w, k = walk(s)
        print(f"{name}: estimate {w:.3e} (order {k}), fourth difference {s[3]:.3e}; s_k "
              + " ".join(f"{x:.2e}" for x in s))
    return 0


if __name__ == "__main__":
    sys.exit(main())

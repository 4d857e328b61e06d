#!/usr/bin/env python3
"""Largest angle difference between a fivebar trajectory.csv and a reference trajectory.

    python3 scripts/compare_reference.py results/paper/trajectory.csv \
        datasets/reference/paper_friction.csv --tol 1e-6

Both files are CSV with a header row (lines starting with '#' are skipped) and at least the
columns t, theta1, theta2, theta3, theta4. Rows are paired by time (to the nearest nanosecond);
for every pair the four angle differences are taken, and the largest one over all pairs is
printed with where it happened.

--columns picks other columns to compare, e.g. the torques of an optimize trajectory.csv
against `fivebar inverse` of the same motion (the count of rows beyond --tol is printed too):

    python3 scripts/compare_reference.py results/inv/trajectory.csv \
        results/opt/swing_right/trajectory.csv --columns M1,M2 --tol 1e-9

Exit status: 0 when that difference is at most --tol (default 1e-6 rad), 1 when it is larger or
when fewer than 90% of the reference times appear in the trajectory, 2 on bad usage or an
unreadable file. Standard library only.
"""
import argparse
import csv
import sys

ANGLES = ("theta1", "theta2", "theta3", "theta4")


def read_rows(path, columns=ANGLES):
    """The file's rows as dicts of floats (empty cells left out)."""
    with open(path, newline="") as handle:
        lines = [line for line in handle if not line.startswith("#")]
    reader = csv.reader(lines)
    header = [name.strip() for name in next(reader)]
    missing = [name for name in ("t",) + tuple(columns) if name not in header]
    if missing:
        raise ValueError(f"{path}: missing column(s) {', '.join(missing)}")
    rows = []
    for cells in reader:
        rows.append({name: float(cell) for name, cell in zip(header, cells) if cell.strip()})
    return rows


def time_key(t):
    return round(t * 1e9)  # pair rows whose times agree to 1 ns


def compare(trajectory, reference, columns=ANGLES, tol=float("inf")):
    """(rows paired, largest difference, its time, its column, rows with a difference > tol)."""
    by_time = {time_key(row["t"]): row for row in trajectory}
    paired, worst, where, beyond = 0, 0.0, (None, None), 0
    for ref in reference:
        row = by_time.get(time_key(ref["t"]))
        if row is None:
            continue
        paired += 1
        gaps = [(abs(row[name] - ref[name]), name) for name in columns]
        beyond += any(gap > tol for gap, _ in gaps)
        for gap, name in gaps:
            if gap > worst:
                worst, where = gap, (ref["t"], name)
    return paired, worst, where[0], where[1], beyond


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trajectory", help="trajectory.csv written by fivebar")
    parser.add_argument("reference", help="reference CSV, e.g. datasets/reference/paper_friction.csv")
    parser.add_argument("--tol", type=float, default=1e-6, help="pass threshold [rad] (1e-6)")
    parser.add_argument("--columns", help="comma-separated columns to compare "
                        "(default theta1,theta2,theta3,theta4)")
    args = parser.parse_args()
    columns = tuple(args.columns.split(",")) if args.columns else ANGLES
    try:
        trajectory = read_rows(args.trajectory, columns)
        reference = read_rows(args.reference, columns)
    except (OSError, ValueError, StopIteration) as error:
        print(f"compare_reference: {error}", file=sys.stderr)
        return 2
    paired, worst, t, name, beyond = compare(trajectory, reference, columns, args.tol)
    if paired < 0.9 * len(reference):
        print(f"only {paired} of the {len(reference)} reference times are in the trajectory")
        return 1
    where = f" at t = {t:g} s ({name})" if name else ""
    verdict = "ok" if worst <= args.tol else "above tolerance"
    if columns == ANGLES:
        print(f"{paired} times paired; max |d theta| = {worst:.3e} rad{where}; "
              f"tolerance {args.tol:g}: {verdict}")
    else:
        print(f"{paired} times paired; max |d {','.join(columns)}| = {worst:.3e}{where}; "
              f"{beyond} rows beyond tolerance {args.tol:g}: {verdict}")
    return 0 if worst <= args.tol else 1


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Fuzz every subcommand's numeric options and scene keys with nan, inf, -inf, 0, -1, 1e300, 1e-300.

    python3 scripts/fuzz_options.py build/release/apps/fivebar [--timeout 10] [--only identify]
        [--what options|scene|both]

Scene keys (SCENE_KEYS) are given with --set to every command that reads a scene, on the
five-bar (paper.yaml) and the four-bar (datasets/reference/four_bar/crank_rocker.yaml); a run
is refused when its one error line names the key.

The numeric options are read from each command's --help (types FLOAT, INT, UINT, N, NM, T,
A,B, THETA1,THETA2). Each option gets each value, on top of a short, valid base command line
(BASE below: short runs, no plots). Every run is classed by its exit status:

  refused   2 (bad input) with exactly one `fivebar: error:` line naming the option
  vague     2 or 3 without the option's name in the error line
  numerics  3 naming the option
  accepted  0, and the value is listed as valid for that option in VALID (with why)
  silent    0, and the value is not listed: a bad value accepted silently
  crash     any other status (signal, abort, 1 for a value), or several error lines
  timeout   the run did not end within --timeout s on a value not listed as valid
  slow-valid  the same on a valid value (the base command's cost on a changed scene)

Prints one line per run that is silent, crash, vague or timeout, then the counts. Exit status 1
when any run is silent or a crash. Standard library only.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAPER = os.path.join(ROOT, "datasets", "scenes", "paper.yaml")
MOTORS = os.path.join(ROOT, "datasets", "scenes", "paper_motors.yaml")
TASKS = os.path.join(ROOT, "datasets", "tasks", "paper_tasks.yaml")
LOG = os.path.join(ROOT, "datasets", "logs", "paper_rates.csv")
SHORT = ["--set", "simulation.duration=0.05"]

VALUES = ["nan", "inf", "-inf", "0", "-1", "1e300", "1e-300"]
ROCKER = os.path.join(ROOT, "datasets", "reference", "four_bar", "crank_rocker.yaml")

SCENE_KEYS = ["mechanism.ground_length", "mechanism.links.0.length", "mechanism.links.1.mass",
              "mechanism.links.2.inertia", "mechanism.links.0.com_offset",
              "mechanism.links.0.com_angle", "mechanism.point_p", "gravity", "friction.pin_radius",
              "friction.coulomb", "friction.viscous", "friction.static_coulomb", "loads.M3",
              "loads.F", "loads.F_angle", "initial.omega1", "simulation.duration",
              "simulation.output_step", "simulation.rtol", "simulation.target_error",
              "simulation.friction_tol"]

# scene keys whose 0, -1 or 1e-300 (as good as 0) describe a machine: exit 0 is right
SIGNED = {"mechanism.links.0.com_angle", "mechanism.point_p", "gravity", "loads.M3", "loads.F",
          "loads.F_angle", "initial.omega1"}
ZERO_OK = SIGNED | {"mechanism.links.0.com_offset", "friction.coulomb", "friction.viscous",
                    "friction.static_coulomb"}


def scene_value_valid(key, value):
    if value in ("0", "1e-300"):
        return key in ZERO_OK
    return value == "-1" and key in SIGNED
TYPES = {"FLOAT", "INT", "UINT", "N", "NM", "T", "A,B", "THETA1,THETA2", "INT:INT"}

# a short, valid command line per subcommand ({out} is a fresh directory)
BASE = {
    "simulate": [PAPER, *SHORT, "--no-plots", "--out", "{out}"],
    "synth-log": [PAPER, "--duration", "0.05", "--out", "{out}/log.csv"],
    "identify": [PAPER, "--log", LOG, "--no-plots", "--no-validation", "--out", "{out}"],
    "hold": [PAPER, "--no-plots", "--out", "{out}"],
    "inverse": [PAPER, "--no-plots", "--out", "{out}"],
    "excite": [PAPER, "--torque-limit", "20", "--duration", "2", "--no-baseline", "--family", "fourier", "--starts", "1",
               "--max-evaluations", "5", "--no-plots", "--out", "{out}"],
    # the motors' scene solves every task in a fraction of a second without refinement, so the
    # base exits 0 and an accepted bad value shows as silent
    "optimize": [MOTORS, "--tasks", TASKS, "--no-refine", "--no-continuation", "--no-plots",
                 "--out", "{out}"],
    "study": [PAPER, "--tasks", TASKS, "--sweep", "friction.coulomb=0.1:0.12:2", "--no-plots",
              "--out", "{out}"],
    "design": [PAPER, "--tasks", TASKS, "--vary", "mechanism.point_p=0.18:0.22", "--max-designs",
               "3", "--no-plots", "--out", "{out}"],
    "accuracy": [PAPER, *SHORT, "--repeats", "1", "--tolerances", "1e-6", "--out", "{out}"],
    "stress": ["--out", "{out}"],
}
SCENE_COMMANDS = ["simulate", "synth-log", "identify", "hold", "inverse", "excite", "optimize",
                  "study", "design", "accuracy"]
FOUR_BAR_COMMANDS = ["simulate", "synth-log", "identify", "hold", "excite"]

# (command, option): values for which exit 0 is right, and why
VALID = {
    ("synth-log", "--seed"): {"0": "any seed", "1e300": "n/a"},
    ("excite", "--seed"): {"0": "any seed"},
    ("synth-log", "--torque-noise"): {"0": "noise-free log"},
    ("synth-log", "--angle-noise"): {"0": "noise-free log"},
    ("synth-log", "--rate-noise"): {"0": "noise-free log (the default)"},
    ("synth-log", "--quantization"): {"0": "no quantization (the default)"},
    ("synth-log", "--static-coulomb"): {"0": "applies to --law stribeck only"},
    ("synth-log", "--torque-offset"): {"0": "an offset of 0", "-1": "offsets have either sign"},
    ("synth-log", "--actuator-coulomb"): {"0": "no actuator friction"},
    ("synth-log", "--actuator-viscous"): {"0": "no actuator friction"},
    ("identify", "--loss-scale"): {"0": "0 = from the noise floor (the default)"},
    ("identify", "--smooth-sign"): {"0": "exact sign", "-1": "-1 = the scene's (the default)"},
    ("hold", "--time"): {"0": "the default", "1e-300": "a time"},
    ("hold", "--torque-limit"): {"inf": "no limit (the default)", "1e300": "no limit",
                                 "1e-300": "a threshold: the console says the pose needs more"},
    ("hold", "--pose"): {"0": "a pose that assembles", "-1": "a pose that assembles"},
    ("identify", "--min-rate"): {"0": "the default"},
    ("excite", "--max-evaluations"): {"0": "0 = the default budget"},
    ("excite", "--torque-noise"): {"0": "n/a"},
    ("excite", "--angle-noise"): {"0": "rates logged exactly: the torque noise's std alone"},
    ("excite", "--min-reversals"): {"0": "no reversal requirement"},
    ("excite", "--ramp"): {"0": "no ramp"},
    ("excite", "--spread"): {"1e-300": "starts close to the first"},
    ("excite", "--drift-spread"): {"0": "starts without drift"},
    ("excite", "--singular-margin"): {"0": "no margin beyond the evaluation's"},
    ("optimize", "--singular-margin"): {"0": "no margin beyond the evaluation's"},
    ("accuracy", "--repeats"): {},
}


def numeric_options(fivebar, command):
    """(option, type) of the command's numeric options, from its --help."""
    text = subprocess.run([fivebar, command, "--help"], capture_output=True, text=True).stdout
    found = []
    for line in text.splitlines():
        m = re.match(r"\s+(--[a-z0-9-]+)\s+([A-Z0-9,:]+)", line)
        if m and m.group(2) in TYPES:
            found.append((m.group(1), m.group(2)))
    return found


def classify(command, option, value, status, err, valid=None):
    lines = [l for l in err.splitlines() if l.startswith("fivebar: error:")]
    if status == 0:
        listed = VALID.get((command, option), {})
        # 1e-300 acts as 0 where 0 is valid
        ok = valid if valid is not None else value in listed or (value == "1e-300" and "0" in listed)
        return "accepted" if ok else "silent"
    if status in (2, 3):
        if len(lines) != 1:
            return "crash"
        if option in lines[0]:
            return "refused" if status == 2 else "numerics"
        return "vague"
    return "crash"


def base_args(command, base, out, scene, log):
    args = [x.replace("{out}", out) for x in base]
    if args and args[0] == PAPER:
        args[0] = scene
    if command == "identify":
        args[args.index("--log") + 1] = log
    if command == "inverse":
        args = [scene, "--motion", os.path.join(ROOT, "datasets", "reference",
                                                "paper_friction.csv")] + args[1:]
    if command == "excite" and scene == ROCKER:
        args[args.index("20")] = "2"
    return args


def run_one(a, command, args, tally, label, classify_fn):
    """Runs one case; a timeout on a value that exit 0 would accept is `slow-valid` (the base
    command's own cost on a changed scene, not a bad value's)."""
    try:
        r = subprocess.run([a.fivebar, command, *args], capture_output=True, text=True,
                           timeout=a.timeout)
        cls = classify_fn(r.returncode, r.stderr)
        status, err = r.returncode, r.stderr.strip().splitlines()
    except subprocess.TimeoutExpired:
        status, err = None, []
        cls = "slow-valid" if classify_fn(0, "") == "accepted" else "timeout"
    tally[cls] = tally.get(cls, 0) + 1
    if cls in ("silent", "crash", "vague", "timeout", "slow-valid"):
        last = err[-1] if err else ""
        print(f"{cls:8} {command} {label}: exit {status}: {last[:160]}")
        sys.stdout.flush()
    return cls in ("silent", "crash")


def fuzz_options(a, tmp, counts):
    bad = 0
    for command, base in BASE.items():
        if a.only and command not in a.only:
            continue
        for option, kind in numeric_options(a.fivebar, command):
            for value in VALUES:
                given = value if kind not in ("A,B", "THETA1,THETA2", "INT:INT") else (
                    value + ("," if kind != "INT:INT" else ":") + value)
                args = base_args(command, base, tempfile.mkdtemp(dir=tmp), PAPER, LOG)
                if option in args:  # the base's own value of this option gives way
                    k = args.index(option)
                    del args[k:k + 2]
                bad += run_one(a, command, args + [option, given], counts, f"{option} {given}",
                               lambda st, err: classify(command, option, value, st, err))
    return bad


def fuzz_scene(a, tmp, counts):
    bad = 0
    rocker_log = os.path.join(tmp, "rocker.csv")
    subprocess.run([a.fivebar, "synth-log", ROCKER, "--duration", "2", "--out", rocker_log],
                   capture_output=True)
    for scene, commands, log in ((PAPER, SCENE_COMMANDS, LOG),
                                 (ROCKER, FOUR_BAR_COMMANDS, rocker_log)):
        for command in commands:
            if a.only and command not in a.only:
                continue
            for key in SCENE_KEYS:
                for value in VALUES:
                    args = base_args(command, BASE[command], tempfile.mkdtemp(dir=tmp), scene, log)
                    label = f"{os.path.basename(scene)} --set {key}={value}"
                    bad += run_one(a, command, args + ["--set", f"{key}={value}"], counts, label,
                                   lambda st, err: classify(command, key, value, st, err,
                                                            scene_value_valid(key, value)))
    return bad


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("fivebar")
    ap.add_argument("--timeout", type=float, default=10)
    ap.add_argument("--only", action="append", help="fuzz this subcommand only (repeatable)")
    ap.add_argument("--what", choices=["options", "scene", "both"], default="both")
    a = ap.parse_args()
    bad = 0
    global LOG
    with tempfile.TemporaryDirectory() as tmp:
        # identify's base: a 2 s log of the paper scene (the shipped 10 s log takes ~10 s to fit)
        LOG = os.path.join(tmp, "paper.csv")
        subprocess.run([a.fivebar, "synth-log", PAPER, "--duration", "2", "--out", LOG],
                       capture_output=True)
        for what, fn in (("options", fuzz_options), ("scene", fuzz_scene)):
            if a.what not in (what, "both"):
                continue
            counts = {}
            bad += fn(a, tmp, counts)
            print(f"counts ({what}): " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
            sys.stdout.flush()
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

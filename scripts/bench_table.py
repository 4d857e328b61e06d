#!/usr/bin/env python3
"""Measures what users wait for, side by side in one run, and writes docs/benchmarks.md.

    python3 scripts/bench_table.py [--baseline OTHER_FIVEBAR] [--baseline-bench OTHER_BENCH_MODEL]
        [--baseline-rhs-calls OTHER_RHS_CALLS] [--baseline-name NAME] [--baseline-about TEXT]
        [--repeats 3] [--skip-optimize]

Rows: the right-hand side with and without friction (bench_model), the paper scene simulated to
1e-6 and 1e-8 rad and with arkode_erk45 at rtol = atol = 1e-10, and with its figures, identify
(per joint, friction and inertia; also with its figures), excite (per joint, worst std, 10 s) and optimize per task of
datasets/tasks/paper_tasks.yaml; the peers' five-bar benchmarks (MuJoCo, Simbody) when they are
built. With --baseline, every command runs alternately with this build's binary and the other
one, and the table gives both medians and their ratio; --baseline-bench does the same for the
right-hand side (the machine may be shared: ratios of interleaved runs are what to compare, not
absolute times; the load average is written with the table). Where valgrind is installed, the
right-hand side is also counted in instructions (rhs_calls under callgrind: the same on a loaded
machine as on an idle one), for this build and --baseline-rhs-calls.
"""
import argparse
import csv
import json
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILD = os.path.join(ROOT, "build", "release")
FIVEBAR = os.path.join(BUILD, "apps", "fivebar")
BENCH_MODEL = os.path.join(BUILD, "tests", "bench", "bench_model")
RHS_CALLS = os.path.join(BUILD, "tests", "bench", "rhs_calls")
RHS_MODES = ("friction", "frictionless", "actuators", "friction_warm", "friction_path",
             "frictionless_path")
PEERS = os.path.join(BUILD, "tests", "bench", "peers")
SCENE = os.path.join(ROOT, "datasets", "scenes", "paper.yaml")
LOG = os.path.join(ROOT, "datasets", "logs", "per_joint_multisine.csv")
TASKS = os.path.join(ROOT, "datasets", "tasks", "paper_tasks.yaml")
OUT = os.path.join(ROOT, "docs", "benchmarks.md")
OTHER = "another build"  # the other binaries' name on the page (--baseline-name)
ABOUT = ""  # what they are (--baseline-about)


def cpu_children():
    """User + system CPU time [s] of the finished children so far."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(cmd, allowed=(0,)):
    """Runs cmd; returns its wall time and its CPU time (user + system, every thread) [s] (raises
    on an exit status not in `allowed`)."""
    start, cpu = time.perf_counter(), cpu_children()
    done = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    elapsed = time.perf_counter() - start
    if done.returncode not in allowed:
        raise RuntimeError(f"{' '.join(cmd)} exited {done.returncode}: {done.stderr.strip()[-400:]}")
    return elapsed, cpu_children() - cpu


def commands(out):
    """(name, arguments after the binary, function reading the time [s] from `out`, or None: the
    command's wall time, or "cpu": its CPU time, user + system over its threads)."""
    def summary_time(key, name="summary.json"):
        return lambda: json.load(open(os.path.join(out, name)))[key]

    sims = []
    for target in ("1e-6", "1e-8"):
        sims.append((f"simulate paper scene to {target} rad (solver time)",
                     ["simulate", SCENE, "--set", f"simulation.target_error={target}",
                      "--no-plots", "--out", out], summary_time("wall_time_s")))
    sims.append(("simulate paper scene, arkode_erk45 at rtol = atol = 1e-10 (solver time)",
                 ["simulate", SCENE, "--set", "simulation.integrator=arkode_erk45", "--set",
                  "simulation.rtol=1e-10", "--set", "simulation.atol=1e-10", "--no-plots",
                  "--out", out], summary_time("wall_time_s")))
    # what a user waits for at the first command: the run, its checks and its five figures
    sims.append(("simulate paper scene with its figures (whole command, CPU with gnuplot's)",
                 ["simulate", SCENE, "--out", out], "cpu"))
    identify = ["identify", SCENE, "--log", LOG, "--per-joint", "--estimate", "friction,inertia",
                "--no-plots", "--out", out]
    # a 10 s angle log of the paper mechanism with its link inertias 3-6 % off, identified with
    # the nominal scene (written once, by this build's synth-log)
    off_log = os.path.join(out, "inertias_off.csv")
    off = [f"mechanism.links.{k}.inertia={0.1 * f}" for k, f in enumerate((1.03, 0.96, 1.05, 0.94))]
    run([FIVEBAR, "synth-log", SCENE, "--out", off_log, "--excitation", "multisine", "--duration",
         "10", "--seed", "11"] + [a for o in off for a in ("--set", o)])
    identify_off = ["identify", SCENE, "--log", off_log, "--per-joint", "--estimate",
                    "friction,inertia", "--no-plots", "--out", out]
    excite = ["excite", SCENE, "--per-joint", "--criterion", "worst-std", "--duration", "10",
              "--torque-limit", "13.4", "--no-plots", "--out", out]
    return sims + [
        ("identify --per-joint --estimate friction,inertia (fit)", identify,
         summary_time("identification_wall_time_s", "identification.json")),
        ("identify --per-joint --estimate friction,inertia (whole command, CPU)", identify, "cpu"),
        ("the same identify with its figures (whole command, CPU with gnuplot's)",
         [a for a in identify if a != "--no-plots"], "cpu"),
        ("the same identify, 10 s log from angles of link inertias x 1.03, 0.96, 1.05, 0.94 "
         "(whole command, CPU)", identify_off, "cpu"),
        ("excite --per-joint --criterion worst-std, 10 s (whole command)", excite, None),
        ("excite --per-joint --criterion worst-std, 10 s (whole command, CPU)", excite, "cpu"),
    ]


def measure(binaries, repeats, skip_optimize):
    """rows: (name, [median time per binary]) measured alternately."""
    rows = []
    with tempfile.TemporaryDirectory() as out:
        for name, args, read in commands(out):
            times = [[] for _ in binaries]
            for _ in range(repeats):
                for i, binary in enumerate(binaries):
                    # identify's 3: a fit its checks reject (the inertias-off log), timed alike
                    wall, cpu = run([binary] + args, (0, 3) if args[0] == "identify" else (0,))
                    times[i].append(cpu if read == "cpu" else read() if read else wall)
            rows.append((name, [statistics.median(t) for t in times]))
        if not skip_optimize:  # each task's wall time, medians over batches run alternately
            per_task = [{} for _ in binaries]
            for _ in range(repeats):
                for i, binary in enumerate(binaries):
                    run([binary, "optimize", SCENE, "--tasks", TASKS, "--out", out])
                    with open(os.path.join(out, "summary.csv")) as f:
                        for r in csv.DictReader(f):
                            per_task[i].setdefault(r["task"], []).append(float(r["wall_time_s"]))
            for task in per_task[0]:
                rows.append((f"optimize task {task}",
                             [statistics.median(p.get(task, [float("nan")])) for p in per_task]))
    return rows


def bench_once(bench):
    """{name: median ns} of one run of a bench_model binary's RightHandSide benchmarks."""
    done = subprocess.run([bench, "--benchmark_filter=RightHandSide",
                           "--benchmark_repetitions=5", "--benchmark_report_aggregates_only",
                           "--benchmark_format=json"], stdout=subprocess.PIPE, text=True,
                          check=True)
    out = {}
    for b in json.loads(done.stdout)["benchmarks"]:
        if b.get("aggregate_name") == "median":
            out[b["run_name"].split("/")[-1]] = b["cpu_time"]
    return out


def right_hand_side(benches, repeats):
    """[{name: ns}] per bench_model binary (medians over `repeats` alternate runs), or None when
    this build's bench_model is not built."""
    if not os.path.exists(benches[0]):
        return None
    runs = [[] for _ in benches]
    for _ in range(repeats):
        for i, bench in enumerate(benches):
            runs[i].append(bench_once(bench))
    return [{k: statistics.median(r[k] for r in rs) for k in rs[0]} for rs in runs]


def instructions(rhs_calls, mode):
    """Instructions of one right-hand side: callgrind's totals of 2000 and 1000 calls, apart
    (None where the binary has no such mode: an older rhs_calls)."""
    totals = []
    for n in (1000, 2000):
        done = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
                               rhs_calls, mode, str(n)], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True)
        found = re.search(r"Collected : (\d+)", done.stderr)
        if done.returncode != 0 or not found:
            return None
        totals.append(int(found.group(1)))
    return (totals[1] - totals[0]) / 1000


def right_hand_side_instructions(binaries):
    """[{mode: instructions}] per rhs_calls binary, or None without valgrind or rhs_calls."""
    if not os.path.exists(binaries[0]) or subprocess.run(
            ["which", "valgrind"], stdout=subprocess.DEVNULL).returncode != 0:
        return None
    return [{m: instructions(b, m) for m in RHS_MODES} for b in binaries]


def instruction_lines(counts):
    """The table of right_hand_side_instructions."""
    lines = ["", "Instructions of one evaluation (`valgrind --tool=callgrind`, `rhs_calls MODE N`: "
             "the totals of N = 2000 and N = 1000 calls, apart; `friction_warm`: consecutive "
             "states 1e-5 s apart, the loop warm-started as in the simulator; `friction_path`: "
             "the same states and loads started cold; `frictionless_path`: the same states and "
             "loads without friction):", ""]

    def fmt(x):  # (None: a mode the binary lacks)
        return "n/a" if x is None else f"{x:.0f}"

    if len(counts) == 2:
        lines += [f"Other: {OTHER}'s rhs_calls.", "",
                  "| evaluation | this build | other | other / this |", "|---|---|---|---|"]
        for m in RHS_MODES:
            this, other = counts[0][m], counts[1][m]
            ratio = "n/a" if this is None or other is None else f"{other / this:.2f}"
            lines.append(f"| {m} | {fmt(this)} | {fmt(other)} | {ratio} |")
    else:
        lines += ["| evaluation | instructions |", "|---|---|"]
        for m in RHS_MODES:
            lines.append(f"| {m} | {fmt(counts[0][m])} |")
    c = counts[0]
    lines += ["", f"In instructions, with friction the right-hand side costs "
              f"{c['friction'] / c['frictionless']:.2f} times the frictionless one "
              f"({c['friction_warm'] / c['frictionless']:.2f} warm-started)"
              + (f"; in the simulator's conditions (`friction_warm` against `frictionless_path`, "
                 f"the same states and loads) {c['friction_warm'] / c['frictionless_path']:.2f} "
                 f"times." if c["frictionless_path"] else ".")]
    return lines


def peers():
    """Lines on the peers' benchmarks: their own output, or why there is none."""
    found = sorted(f for f in os.listdir(PEERS) if f.startswith("bench_peers_")) \
        if os.path.isdir(PEERS) else []
    if not found:
        return ["MuJoCo and Simbody are not built on this machine (their benchmarks build only "
                "when libmujoco-dev / libsimbody-dev are installed), so no peer rows."]
    lines = []
    for f in found:
        done = subprocess.run([os.path.join(PEERS, f)], stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True)
        lines += [f"`{f}`:", "```", done.stdout.strip(), "```"]
    return lines


def about_other():
    """A sentence on what OTHER is: its commit's date where it names a commit of this repository,
    and --baseline-about."""
    done = subprocess.run(["git", "-C", ROOT, "log", "-1", "--format=%cd",
                           "--date=format-local:%Y-%m-%d %H:%M UTC", OTHER + "^{commit}", "--"],
                          stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                          env=dict(os.environ, TZ="UTC"))
    parts = []
    if done.returncode == 0 and done.stdout.strip():
        parts.append(f"{OTHER} is the commit of {done.stdout.strip()}")
    if ABOUT:
        parts.append(ABOUT if parts else f"{OTHER}: {ABOUT}")
    return [", ".join(parts) + "."] if parts else []


def seconds(x):
    return f"{x * 1e3:.1f} ms" if x < 1 else f"{x:.2f} s"


def write(rows, rhs, counts, binaries, benches, repeats, load):
    lines = ["# Benchmarks", "",
             "Written by `python3 scripts/bench_table.py` (run it again after a change: it "
             "rebuilds nothing, it measures `build/release`). Times are medians of "
             f"{repeats} runs; the machine it ran on may be shared, so compare ratios measured "
             "in the same run rather than absolute times.", "",
             f"Measured {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} on "
             f"{os.cpu_count()} cores, load average {load[0]:.1f} at the start and "
             f"{load[1]:.1f} at the end."]
    if len(binaries) == 2 or len(benches) == 2:
        lines += [""] + about_other()
    lines += ["", "## Right-hand side", ""]
    if rhs:
        lines += ["CPU time of one evaluation (`bench_model --benchmark_filter=RightHandSide`, median of "
                  "5 repetitions per run):", ""]
        if len(rhs) == 2:
            lines += [f"This build against {OTHER}'s bench_model (`--baseline-bench`), run "
                      "alternately.", "",
                      "| evaluation | this build [ns] | other [ns] | other / this |",
                      "|---|---|---|---|"]
            for k, v in rhs[0].items():
                other = rhs[1].get(k, float("nan"))
                lines.append(f"| {k} | {v:.0f} | {other:.0f} | {other / v:.2f} |")
        else:
            lines += ["| evaluation | ns |", "|---|---|"]
            for k, v in rhs[0].items():
                lines.append(f"| {k} | {v:.0f} |")
        if "friction" in rhs[0] and "frictionless" in rhs[0]:
            lines += ["", f"With friction the right-hand side costs "
                      f"{rhs[0]['friction'] / rhs[0]['frictionless']:.2f} times the frictionless "
                      "one."]
    else:
        lines.append("bench_model is not built (`cmake --build --preset release --target "
                     "bench_model`).")
    if counts:
        lines += instruction_lines(counts)
    lines += ["", "## Commands", ""]
    if rows is None:
        lines.append(f"Not measured: `{os.path.relpath(FIVEBAR, ROOT)}` was not built when the "
                     "table was written (`scripts/build.sh`, then run the script again).")
    elif len(binaries) == 2:
        lines += [f"This build against {OTHER}'s fivebar (`--baseline`), run alternately.", "",
                  "| what | this build | other | other / this |", "|---|---|---|---|"]
        for name, t in rows:
            lines.append(f"| {name} | {seconds(t[0])} | {seconds(t[1])} | {t[1] / t[0]:.2f} |")
    else:
        lines += ["| what | time |", "|---|---|"]
        for name, t in rows:
            lines.append(f"| {name} | {seconds(t[0])} |")
    lines += ["", "## Peers", ""] + peers()
    with open(OUT, "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baseline", help="another fivebar binary to run alternately with this one")
    ap.add_argument("--baseline-name", default="another build",
                    help="what the page calls the other binaries (e.g. their commit)")
    ap.add_argument("--baseline-about", default="",
                    help="what the other binaries are, in a few words (for the page)")
    ap.add_argument("--baseline-bench",
                    help="another bench_model binary to run alternately with this one")
    ap.add_argument("--baseline-rhs-calls",
                    help="another rhs_calls binary to count instructions of (with valgrind)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--skip-optimize", action="store_true", help="leave out optimize (minutes)")
    a = ap.parse_args()
    global OTHER, ABOUT
    OTHER, ABOUT = a.baseline_name, a.baseline_about
    binaries = [FIVEBAR] + ([a.baseline] if a.baseline else [])
    benches = [BENCH_MODEL] + ([a.baseline_bench] if a.baseline_bench else [])
    load_start = os.getloadavg()[0]
    rhs = right_hand_side(benches, a.repeats)
    counts = right_hand_side_instructions(
        [RHS_CALLS] + ([a.baseline_rhs_calls] if a.baseline_rhs_calls else []))
    rows = measure(binaries, a.repeats, a.skip_optimize) if os.path.exists(FIVEBAR) else None
    write(rows, rhs, counts, binaries, benches, a.repeats, (load_start, os.getloadavg()[0]))
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()

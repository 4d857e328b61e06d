#!/usr/bin/env python3
"""Throughput and per-call overhead of fivebar.inverse (friction-aware inverse dynamics).

    /usr/bin/python3 python/bench_inverse.py [--states 1000000] [--repeats 5]

1. Vectorized: the 2001 states of a simulation of the paper scene (friction on), tiled to
   --states rows, through fivebar.inverse with threads=1 and threads=0 (all cores); the best of
   --repeats calls, in states per second of wall time, and the process CPU time per state
   (what the states cost whatever else runs on the machine).
2. Single state: fivebar.inverse on (1, 2) arrays, against the same C++ work called in a C++ loop
   (fivebar._core._time_inverse_cpp); the fastest of 7 batches of 20000 calls each, in 3
   interleaved rounds, in wall time and in CPU time. The difference is what Python costs per
   call (argument checks, output arrays, the dict, releasing the GIL).
Prints the load average first: on a busy machine wall times are longer than CPU times.
"""
import argparse
import os
import pathlib
import time
import timeit

import numpy as np

import fivebar

ROOT = pathlib.Path(__file__).resolve().parents[1]
CALLS = 20000


def states(run, n):
    pick = lambda q: np.stack([run[f"{q}1"], run[f"{q}2"]], axis=1)
    reps = -(-n // len(run["t"]))
    return [np.ascontiguousarray(np.tile(pick(q), (reps, 1))[:n])
            for q in ("theta", "omega", "alpha")]


def vectorized(scene, theta, omega, alpha, threads, repeats):
    """Best wall time and best CPU time of `repeats` calls [s]."""
    wall = cpu = float("inf")
    for _ in range(repeats):
        w, c = time.perf_counter(), time.process_time()
        fivebar.inverse(scene, theta, omega, alpha, threads=threads)
        wall = min(wall, time.perf_counter() - w)
        cpu = min(cpu, time.process_time() - c)
    return wall, cpu


def single(scene, run, cpu_time):
    """Seconds per one-state fivebar.inverse call and per C++ call."""
    i = 1000  # t = 1 s: every joint slipping, friction loop active
    state = [run[f"{q}{k}"][i] for q in ("theta", "omega", "alpha") for k in (1, 2)]
    th, om, al = (np.array([[state[j], state[j + 1]]]) for j in (0, 2, 4))
    timer = time.process_time if cpu_time else time.perf_counter
    python = cpp = float("inf")
    for _ in range(3):
        python = min(python, min(timeit.repeat(lambda: fivebar.inverse(scene, th, om, al),
                                               number=CALLS, repeat=7, timer=timer)) / CALLS)
        cpp = min(cpp, fivebar._core._time_inverse_cpp(scene, tuple(state), calls=CALLS,
                                                       repeats=7, cpu_time=cpu_time))
    return python, cpp


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--states", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    scene = fivebar.load_scene(ROOT / "datasets/scenes/paper.yaml")
    run = fivebar.simulate(scene)
    theta, omega, alpha = states(run, args.states)
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    print(f"fivebar.inverse, paper scene with friction, {args.states} states, "
          f"{os.cpu_count()} cores, load average {load}; best of {args.repeats}")
    for threads, label in ((1, "1 thread"), (0, "all cores")):
        wall, cpu = vectorized(scene, theta, omega, alpha, threads, args.repeats)
        print(f"  vectorized, {label:9s}: {args.states / wall / 1e6:.2f} M states/s wall "
              f"({wall / args.states * 1e9:.0f} ns/state); CPU time {cpu / args.states * 1e9:.0f} "
              f"ns/state summed over threads")
    for cpu_time, label in ((False, "wall"), (True, "CPU ")):
        python, cpp = single(scene, run, cpu_time)
        print(f"  single state ({label}): fivebar.inverse {python * 1e6:.2f} us, C++ call "
              f"{cpp * 1e6:.2f} us, overhead {(python - cpp) * 1e6:.2f} us")


if __name__ == "__main__":
    main()

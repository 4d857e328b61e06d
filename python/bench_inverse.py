#!/usr/bin/env python3
"""Throughput and per-call overhead of fivebar.inverse (friction-aware inverse dynamics).

    /usr/bin/python3 python/bench_inverse.py [--states 1000000] [--repeats 5]

1. Vectorized: the 2001 states of a simulation of the paper scene (friction on), tiled to
   --states rows, through fivebar.inverse with threads=1 and threads=0 (all cores); the best of
   --repeats calls, in states per second.
2. Single state: fivebar.inverse on (1, 2) arrays, against the same C++ work called in a C++ loop
   (fivebar._core._time_inverse_cpp); the fastest of 7 batches of 20000 calls each, in 3
   interleaved rounds (the least disturbed by other processes). The difference is what Python
   costs per call (argument checks, output arrays, the dict, releasing the GIL).
"""
import argparse
import os
import pathlib
import time
import timeit

import numpy as np

import fivebar

ROOT = pathlib.Path(__file__).resolve().parents[1]


def states(run, n):
    pick = lambda q: np.stack([run[f"{q}1"], run[f"{q}2"]], axis=1)
    reps = -(-n // len(run["t"]))
    return [np.ascontiguousarray(np.tile(pick(q), (reps, 1))[:n]) for q in ("theta", "omega",
                                                                             "alpha")]


def vectorized(scene, theta, omega, alpha, threads, repeats):
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fivebar.inverse(scene, theta, omega, alpha, threads=threads)
        best = min(best, time.perf_counter() - start)
    return len(theta) / best


def single(scene, run, calls=20000):
    i = 1000  # t = 1 s: every joint slipping, friction loop active
    state = [run[f"{q}{k}"][i] for q in ("theta", "omega", "alpha") for k in (1, 2)]
    th, om, al = (np.array([[state[j], state[j + 1]]]) for j in (0, 2, 4))
    python = cpp = float("inf")
    for _ in range(3):
        python = min(python, min(timeit.repeat(lambda: fivebar.inverse(scene, th, om, al),
                                               number=calls, repeat=7)) / calls)
        cpp = min(cpp, fivebar._core._time_inverse_cpp(scene, tuple(state), calls=calls,
                                                       repeats=7))
    return python, cpp


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--states", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    scene = fivebar.load_scene(ROOT / "datasets/scenes/paper.yaml")
    run = fivebar.simulate(scene)
    theta, omega, alpha = states(run, args.states)
    print(f"fivebar.inverse, paper scene with friction, {args.states} states, "
          f"{os.cpu_count()} cores, best of {args.repeats}")
    for threads, label in ((1, "1 thread"), (0, "all cores")):
        rate = vectorized(scene, theta, omega, alpha, threads, args.repeats)
        print(f"  vectorized, {label:9s}: {rate / 1e6:.2f} M states/s ({1e9 / rate:.0f} ns/state)")
    python, cpp = single(scene, run)
    print(f"  single state: fivebar.inverse {python * 1e6:.2f} us, C++ call {cpp * 1e6:.2f} us, "
          f"overhead {(python - cpp) * 1e6:.2f} us")


if __name__ == "__main__":
    main()

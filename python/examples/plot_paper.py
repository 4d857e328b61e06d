#!/usr/bin/env python3
"""The paper scene with and without joint friction: crank angles and friction torques.

    /usr/bin/python3 python/examples/plot_paper.py --out paper.png
"""
import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import fivebar  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default=ROOT / "datasets/scenes/paper.yaml")
    parser.add_argument("--out", default="paper.png")
    args = parser.parse_args()

    scene = fivebar.load_scene(args.scene)
    friction = fivebar.simulate(scene)
    free = fivebar.simulate(fivebar.load_scene(args.scene,
                                               overrides={"friction.model": "none"}))

    fig, (angles, torques) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for i, color in ((1, "tab:blue"), (2, "tab:red")):
        angles.plot(friction["t"], friction[f"theta{i}"], color=color,
                    label=f"theta{i}, friction")
        angles.plot(free["t"], free[f"theta{i}"], color=color, linestyle="--",
                    label=f"theta{i}, frictionless")
    angles.set_ylabel("crank angle [rad]")
    angles.legend(ncol=2, fontsize="small")
    for k, joint in enumerate(("O", "B", "C", "D", "D0"), start=1):
        torques.plot(friction["t"], friction[f"Mf{k}"], label=f"Mf{k} ({joint})")
    torques.set_xlabel("t [s]")
    torques.set_ylabel("friction torque [N m]")
    torques.legend(ncol=5, fontsize="small")
    summary = friction["summary"]
    fig.suptitle(f"{pathlib.Path(str(args.scene)).name}: {summary['friction_events']} friction "
                 f"events, E_diss = {summary['E_diss']:.4g} J")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()

#!/usr/bin/env bash
# Quickstart 1: install what is missing, build, and run the canonical paper scene.
# Output: results/paper/ (trajectory.csv, summary.json, fig2..fig6 PNGs).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
./build/release/apps/fivebar simulate datasets/scenes/paper.yaml --out results/paper

#!/usr/bin/env bash
# Quickstart 1: install what is missing, build the executable and the Python module only (not
# the tests and benchmarks: scripts/test.sh builds those), and run the canonical paper scene.
# Output: results/paper/ (trajectory.csv, summary.json, fig2..fig6 PNGs, animation.html).
set -euo pipefail
cd "$(dirname "$0")/.."
echo "paper: [1/2] installing what is missing and building fivebar and its Python module"
bash scripts/build.sh fivebar fivebar_python
echo "paper: [2/2] simulating datasets/scenes/paper.yaml -> results/paper/"
./build/release/apps/fivebar simulate datasets/scenes/paper.yaml --out results/paper

#!/usr/bin/env bash
# Quickstart 1: install what is missing, build the executable and the Python module only (not
# the tests and benchmarks: scripts/test.sh builds those), and run the canonical paper scene.
# Output: results/paper/ (trajectory.csv, summary.json, fig2..fig6 PNGs, animation.html).
set -euo pipefail
cd "$(dirname "$0")/.."
echo "paper: [1/2] installing what is missing and building fivebar and its Python module"
targets=(fivebar)
# the Python module, when this configuration builds it (FIVEBAR_BUILD_PYTHON, pybind11 found)
bash scripts/install-deps.sh
cmake --preset release >/dev/null
if cmake --build --preset release --target help 2>/dev/null | grep -q fivebar_python; then
  targets+=(fivebar_python)
fi
bash scripts/build.sh "${targets[@]}"
echo "paper: [2/2] simulating datasets/scenes/paper.yaml -> results/paper/"
./build/release/apps/fivebar simulate datasets/scenes/paper.yaml --out results/paper

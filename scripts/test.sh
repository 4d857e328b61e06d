#!/usr/bin/env bash
# Quickstart 2: install what is missing, build, and run the whole test suite (ctest, 2 cores).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
ctest --test-dir build/release --output-on-failure -j2

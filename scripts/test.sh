#!/usr/bin/env bash
# Quickstart 2: install what is missing (with the test-only packages: chromium for the viewer's
# test), build everything (tests and benchmarks included), and run the whole suite (ctest, 2 cores).
set -euo pipefail
cd "$(dirname "$0")/.."
FIVEBAR_TEST_DEPS=1 bash scripts/build.sh
ctest --test-dir build/release --output-on-failure -j2

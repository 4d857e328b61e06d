#!/usr/bin/env bash
# Installs the Debian packages fivebar needs, only those that are missing (idempotent).
# Usage: scripts/install-deps.sh        (as root, or with sudo available)
#        FIVEBAR_TEST_DEPS=1 scripts/install-deps.sh   also installs what only the test suite
#        uses: GoogleTest, Google Benchmark, pytest, matplotlib (python/examples/plot_paper.py and
#        its test) and Debian's chromium, which opens animation.html headless (scripts/test.sh
#        sets it; scripts/paper.sh does not)
#        FIVEBAR_PEERS=1 scripts/install-deps.sh   also installs the optional peers (MuJoCo 2.2.2,
#        Simbody 3.7) for tests/bench/peers/ (bench_peers_mujoco, bench_peers_simbody); the default
#        install does not pull them.
set -euo pipefail
pkgs=(build-essential cmake ninja-build pkg-config python3
      libeigen3-dev libceres-dev libnlopt-cxx-dev libsundials-dev
      libyaml-cpp-dev libcli11-dev libmuparser-dev
      gnuplot-nox openmpi-bin libopenmpi-dev
      pybind11-dev python3-pybind11 python3-dev python3-numpy)
if [ "${FIVEBAR_TEST_DEPS:-0}" = "1" ]; then
  pkgs+=(libgtest-dev libgmock-dev libbenchmark-dev python3-pytest python3-matplotlib chromium)
fi
if [ "${FIVEBAR_PEERS:-0}" = "1" ]; then
  pkgs+=(libmujoco-dev libsimbody-dev)
fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"

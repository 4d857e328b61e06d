#!/usr/bin/env bash
# Installs what is missing, then configures and builds fivebar (Release, build/release, -j2),
# and points Debian's /usr/bin/python3 at the Python module of this build (docs/python.md).
# Usage: scripts/build.sh [TARGET...]   the named CMake targets only (scripts/paper.sh: the
#        executable and the Python module); without arguments everything, tests and benchmarks
#        included (scripts/test.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
# the release preset generates Ninja files (both cores stay busy across the libraries); a
# build/release configured with another generator is configured anew (a full rebuild)
cache=build/release/CMakeCache.txt
if [ -f "$cache" ] && ! grep -q '^CMAKE_GENERATOR:INTERNAL=Ninja$' "$cache"; then
  echo "build: build/release was configured with another generator: configuring it anew"
  rm -rf "$cache" build/release/CMakeFiles
fi
echo "build: configuring (cmake --preset release)"
cmake --preset release >/dev/null
targets=()
if [ $# -gt 0 ]; then
  # a named target this configuration does not define (the Python module without pybind11,
  # FIVEBAR_BUILD_PYTHON=OFF) is left out with a note
  known=$(cmake --build --preset release --target help 2>/dev/null)
  for t in "$@"; do
    if grep -qE "^(\.\.\. )?$t(:| |$)" <<<"$known"; then
      targets+=(--target "$t")
    else
      echo "build: target $t is not configured here: skipped"
    fi
  done
fi
echo "build: compiling ${*:-everything} on 2 cores (progress in [done/total] below)"
cmake --build --preset release "${targets[@]}"

# `import fivebar` from any directory: a .pth file in Debian's site directory for locally
# installed packages names build/release/python (the module of this build, not a copy)
if [ -f build/release/python/fivebar/__init__.py ]; then
  site=$(/usr/bin/python3 -c 'import site; print(site.getsitepackages()[0])')
  if mkdir -p "$site" 2>/dev/null && echo "$PWD/build/release/python" >"$site/fivebar.pth" 2>/dev/null; then
    echo "build: /usr/bin/python3 imports fivebar from $PWD/build/release/python ($site/fivebar.pth)"
  else
    echo "build: cannot write $site/fivebar.pth (run as root, or set PYTHONPATH=$PWD/build/release/python)"
  fi
fi

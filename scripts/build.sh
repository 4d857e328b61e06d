#!/usr/bin/env bash
# Installs what is missing, then configures and builds fivebar (Release, build/release, -j2),
# the Python module included, and points Debian's /usr/bin/python3 at that module (docs/python.md).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release

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

#!/usr/bin/env bash
# Configures and builds into build/ (Release); the engine is build/dem, the Python module
# build/python/dem.*.so. Then, where it may (root), it installs build/dem.pth into Debian's
# site folder for local packages, so that `/usr/bin/python3 -c "import dem, compare"` works from
# any folder: the .pth names this build's module and this checkout's compare/ (the checkout
# built last is the one imported). DEM_NO_PTH=1 leaves the site folder alone.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DDEM_PYTHON=/usr/bin/python3 >/dev/null
cmake --build build -j "$(nproc)"
if [ -f build/dem.pth ] && [ "${DEM_NO_PTH:-}" != "1" ]; then
  site=$(/usr/bin/python3 -c 'import site; print(site.getsitepackages()[0])')
  if mkdir -p "$site" 2>/dev/null && [ -w "$site" ]; then
    cp build/dem.pth "$site/dem.pth"
  else
    echo "build.sh: $site is not writable: add $PWD/build/python and $PWD to PYTHONPATH to import dem, compare" >&2
  fi
fi

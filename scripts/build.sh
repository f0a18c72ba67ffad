#!/usr/bin/env bash
# Configures and builds into build/ (Release); the engine is build/dem, the Python package
# build/python/dem (the engine module dem._engine, and dem.compare linked to this checkout's
# compare/). Then, where it may (root), it installs build/dem.pth into Debian's site folder for
# local packages, so that `/usr/bin/python3 -c "import dem"` works from any folder: the .pth
# names build/python (the checkout built last is the one imported). DEM_NO_PTH=1 leaves the site
# folder alone.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DDEM_PYTHON=/usr/bin/python3 >/dev/null
cmake --build build -j "$(nproc)"
if [ -f build/dem.pth ] && [ "${DEM_NO_PTH:-}" != "1" ]; then
  site=$(/usr/bin/python3 -c 'import site; print(site.getsitepackages()[0])')
  if mkdir -p "$site" 2>/dev/null && [ -w "$site" ]; then
    cp build/dem.pth "$site/dem.pth"
  else
    echo "build.sh: $site is not writable: add $PWD/build/python to PYTHONPATH to import dem" >&2
  fi
fi

#!/usr/bin/env bash
# Configures and builds into build/ (Release); the engine is build/dem.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DDEM_PYTHON=/usr/bin/python3 >/dev/null
cmake --build build -j "$(nproc)"

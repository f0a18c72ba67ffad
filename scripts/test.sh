#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test (GoogleTest + pytest through ctest).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
/usr/bin/python3 scripts/make_paper_scenes.py --check
ctest --test-dir build --output-on-failure -j "$(nproc)"

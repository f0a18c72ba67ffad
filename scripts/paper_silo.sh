#!/usr/bin/env bash
# The main job: installs what is missing, builds, and runs the paper's static silo study
# (8 arrangements x 3 schemes x 2 time steps), writing out/paper_silo/report.md and its PNGs.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
/usr/bin/python3 -m compare.paper_static --out "${1:-out/paper_silo}"

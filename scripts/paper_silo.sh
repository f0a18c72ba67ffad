#!/usr/bin/env bash
# The main job: installs what is missing, builds, and runs the paper's static silo study
# (8 arrangements x 3 schemes x 2 time steps) and the discharge ensembles (17/18, 11/12),
# writing out/paper_silo/report.md, out/paper_silo/discharge/report.md and their PNGs.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
OUT="${1:-out/paper_silo}"
export PYTHONPATH="$PWD/build/python${PYTHONPATH:+:$PYTHONPATH}"   # this build's package dem (dem.compare)
/usr/bin/python3 -m dem.compare.papers.paper_static --out "$OUT"
/usr/bin/python3 -m dem.compare.papers.paper_discharge --out "$OUT/discharge"

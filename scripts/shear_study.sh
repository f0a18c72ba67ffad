#!/bin/bash
# Paper 2's simple shear study (Sumita, Kiyama & Nishimura): every alpha with and without
# clusters, native and YADE -> out/shear/report.md with the Fig. 7 analogue, the networks of
# Figs. 5 and 6 and the peak tau/sigma table. About 6 minutes on 2 cores once built (the YADE
# runs take most of it). Usage: bash scripts/shear_study.sh [--no-yade] [extra dem.compare.papers.shear_study options]
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x build/dem ]; then
  bash scripts/build.sh
fi
if ! command -v yade >/dev/null && [[ " $* " != *" --no-yade "* ]]; then
  echo "shear_study: yade not found (apt-get install -y yade, or pass --no-yade)" >&2
  exit 1
fi
export PYTHONPATH="$PWD/build/python${PYTHONPATH:+:$PYTHONPATH}"   # this build's package dem (dem.compare)
DEM_BINARY=build/dem /usr/bin/python3 -m dem.compare.papers.shear_study --out out/shear --dem build/dem "$@"

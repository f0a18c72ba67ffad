#!/usr/bin/env bash
# Installs what the engine, its tests and its figures need, from Debian's archive (run as root).
set -euo pipefail
PKGS=(cmake g++ make pkg-config libeigen3-dev libtomlplusplus-dev nlohmann-json3-dev
      libgtest-dev googletest libbenchmark-dev
      libcli11-dev   # the command line's declarations (engine/src/cli)
      python3-dev pybind11-dev python3-pybind11 python3-setuptools    # the Python module dem (engine/python)
      python3-numpy python3-scipy python3-matplotlib python3-pil python3-meshio python3-pytest
      python3-pytest-xdist   # pytest on every core (tests/CMakeLists.txt)
      liggghts yade lammps   # the reference codes of the comparison layer (compare/); lammps gives lmp
      procps           # pgrep: scripts/test.sh stops its studies' process trees when a test phase fails
      time)            # GNU time: benchmarks/speed.py measures each run's peak memory with it
missing=()
for p in "${PKGS[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if [ "${#missing[@]}" -gt 0 ] || [ "${CI:-}" = "true" ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  if [ "${#missing[@]}" -gt 0 ]; then
    echo "install_deps: installing ${missing[*]} from Debian's archive (a few minutes on a fresh machine)" >&2
  else
    echo "install_deps: checking ${#PKGS[@]} packages with apt-get (CI)" >&2
  fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${PKGS[@]}" >/dev/null
  echo "install_deps: done" >&2
fi

#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test (GoogleTest + pytest through ctest),
# then the same tests on a sanitizer build (build-asan/), with the agreement studies beside them.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
phase() { echo "test.sh: $1 done, ${SECONDS} s since the start"; }  # where CI's time goes
bash scripts/build.sh
phase "release build"
export PYTHONPATH="$PWD/build/python${PYTHONPATH:+:$PYTHONPATH}"   # this build's package dem (dem.compare)
/usr/bin/python3 scripts/make_paper_scenes.py --check
/usr/bin/python3 scripts/make_janssen_scene.py --check
/usr/bin/python3 scripts/make_calibration_scenes.py --check
DEM_BINARY="$PWD/build/dem" /usr/bin/python3 -m dem.compare translate --check

# The agreement studies need only the release build, so they run beside the tests and the
# sanitizer build: each of the test phases leaves a core idle part of its time (a build's link, a
# test run's slowest items), which the studies fill. Three independent studies, each in its own
# folder and each single-threaded:
# - the quick agreement study: native vs the real LIGGGHTS and YADE (fails unless every metric
#   agrees), with the two mutants that prove the designed discharge's statistical metrics (each must
#   end disagree by a statistical metric: docs/compare.md, "Mutants");
# - the mutants (deliberately wrong translations; fails unless every one is caught);
# - LAMMPS on the scenes it expresses, with its mutants.
# Each one's output is printed, in this order, once the tests have ended; any failure fails the script.
mkdir -p out
study() {  # NAME ARGS...: dem compare ARGS --out out/NAME, its output kept in out/NAME.log
  local name=$1; shift
  build/dem compare "$@" --out "out/$name" > "out/$name.log" 2>&1
}
study agreement reference_inputs/agreement/quick.list --mutant liggghts_slit_ends_1r \
  --mutant liggghts_density_x1.25 & pids=("agreement:$!")
study mutants reference_inputs/agreement/mutants.list --mutants & pids+=("mutants:$!")
study lammps reference_inputs/agreement/lammps.list --codes lammps --mutants & pids+=("lammps:$!")
kill_tree() { local c; for c in $(pgrep -P "$1"); do kill_tree "$c"; done; kill "$1" 2>/dev/null || true; }
stop_studies() { for entry in "${pids[@]}"; do kill_tree "${entry#*:}"; done; }
trap stop_studies EXIT   # a failed test phase leaves no study (nor its reference runs) running

ctest --test-dir build --output-on-failure -j "$(nproc)"
phase "release tests"

# The same tests on an AddressSanitizer + UndefinedBehaviorSanitizer build (any report fails).
# -O1 -g1 (line tables for the reports' stack traces) compiles in half the time of -O2 -g; only
# what the tests run is built (not the benchmarks).
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DDEM_SANITIZE=ON -DDEM_PYTHON=/usr/bin/python3 >/dev/null
cmake --build build-asan -j "$(nproc)" --target dem dem_tests
phase "sanitizer build"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
  ctest --test-dir build-asan --output-on-failure -j "$(nproc)"
phase "sanitizer tests"

failed=()
for entry in "${pids[@]}"; do
  name=${entry%%:*}
  wait "${entry#*:}" || failed+=("$name")
  cat "out/$name.log"
done
trap - EXIT
phase "agreement studies"
if [ "${#failed[@]}" -gt 0 ]; then
  echo "test.sh: dem compare failed: ${failed[*]} (out/NAME.log, out/NAME/report.md)" >&2
  exit 1
fi

#!/usr/bin/env bash
# Fuzzes the scene reader (engine/fuzz/fuzz_scene.cpp) with libFuzzer for SECONDS (default 300):
# builds build-fuzz/ with clang (ASan + UBSan + coverage), seeds the corpus with the paper's
# scenes and the malformed scenes of tests/corpus/scenes, and runs one fuzzing process.
# The growing corpus stays in build-fuzz/corpus (reused by the next run); a crash, sanitizer
# report, timeout (10 s per input) or allocation beyond 2 GB stops the run with a reproducer in
# build-fuzz/artifacts/ (replay: build-fuzz/engine/fuzz/fuzz_scene FILE). Not part of the tests.
# Needs clang and libFuzzer (Debian: apt-get install clang libfuzzer-14-dev).
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_TO_RUN="${1:-300}"
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ not found (apt-get install clang libfuzzer-14-dev)" >&2; exit 2; }
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DDEM_FUZZ=ON \
      -DDEM_PYTHON=/usr/bin/python3 >/dev/null
cmake --build build-fuzz --target fuzz_scene -j "$(nproc)"
mkdir -p build-fuzz/corpus build-fuzz/artifacts build-fuzz/seeds
# Seeds: the paper's scenes (not the 1e5/1e6-disc benchmarks) and the malformed corpus.
for f in reference_inputs/scenes/*.toml tests/corpus/scenes/*.toml; do
  case "$f" in *bench_*) continue ;; esac
  cp "$f" build-fuzz/seeds/
done
ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
  build-fuzz/engine/fuzz/fuzz_scene build-fuzz/corpus build-fuzz/seeds \
  -dict=engine/fuzz/scene.dict -max_len=8192 -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 \
  -max_total_time="$SECONDS_TO_RUN" -print_final_stats=1 -artifact_prefix=build-fuzz/artifacts/
echo "fuzz.sh: corpus build-fuzz/corpus: $(ls build-fuzz/corpus | wc -l) inputs"

#!/bin/bash
# Runs every committed scene (not the 100k/1M benchmarks) into $1 and writes digests to $2.
set -u
out=$1; dig=$2
mkdir -p $out
for s in reference_inputs/scenes/*.toml reference_inputs/agreement/user/hopper.toml; do
  n=$(basename $s .toml)
  case $n in bench_silo_100k|bench_silo_1m) continue;; esac
  /usr/bin/time -f "$n %e s" build/dem run $s --out $out/$n --quiet > $out/$n.stdout 2>> $out/times.txt || echo "$n rc=$?" >> $out/times.txt
done
# resume / checkpoint runs of a discharge
build/dem run reference_inputs/scenes/discharge_17_18.toml --out $out/ck_discharge --quiet --checkpoint-every 0.5 > /dev/null 2>&1
/usr/bin/python3 scripts/output_digest.py $out/*/ > $dig

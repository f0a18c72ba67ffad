"""Disc order: the settled 100k silo started from its packing listed row by row (as settled) and
in a seeded random order (speed.py --start shuffled), the engine's re-sort on (integrator.disc_order
= "auto", the default) and off; one thread, the paper's law (eq. 19, dt = 1e-4 s), 200 steps of
fill and 400 of discharge, as speed.py's settled 100k point.

    /usr/bin/python3 benchmarks/disc_order.py --out out/disc_order            # 3 interleaved repeats
    /usr/bin/python3 benchmarks/disc_order.py --out out/disc_order --repeats 5 --size 10k

Each run is a fresh `dem run --quiet --threads 1`; the configurations are interleaved (sorted,
shuffled, shuffled with the re-sort off, then again). Time: summary.json wall_time_s (the step
loop) over particle_steps, nanoseconds per particle-step; median [min-max] over the repeats.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "build" / "python"))
sys.path.insert(0, str(ROOT / "benchmarks"))

import speed  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/disc_order")
    ap.add_argument("--size", default="100k", choices=("10k", "100k", "1m"))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--dem", default=os.environ.get("DEM_BINARY", str(ROOT / "build" / "dem")))
    args = ap.parse_args()
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    file, settle, dis, _ = speed.SIZES[args.size]
    settled = speed.settled_scene(speed.SCENES / file, args.dem, out)
    shuffled = speed.shuffled_scene(settled, out)
    scenes = {"sorted": speed.scene_with_phases(settled, settle, dis, speed.DT_PAPER, out / f"bench_{args.size}_sorted.toml"),
              "shuffled": speed.scene_with_phases(shuffled, settle, dis, speed.DT_PAPER, out / f"bench_{args.size}_shuffled.toml")}
    configs = [("sorted", "sorted", []), ("shuffled", "shuffled", []),
               ("shuffled, re-sort off", "shuffled", ["--set", "integrator.disc_order=off"])]
    ns: dict[str, list[float]] = {name: [] for name, _, _ in configs}
    for rep in range(args.repeats):
        for k, (name, scene, extra) in enumerate(configs):
            run = out / "runs" / f"c{k}_r{rep}"
            p = subprocess.run([args.dem, "run", str(scenes[scene]), "--out", str(run), "--quiet", "--threads", "1", *extra],
                               capture_output=True, text=True)
            if p.returncode != 0:
                print(p.stderr, file=sys.stderr)
                return 2
            s = json.loads((run / "summary.json").read_text())
            ns[name].append(s["wall_time_s"] / s["particle_steps"] * 1e9)
            print(f"{name} r{rep}: {ns[name][-1]:.1f} ns per particle-step, {s['disc_resorts']} re-sorts", flush=True)
    print(f"\n{args.size} settled, one thread, ns per particle-step, median [min-max] of {args.repeats}:")
    base = statistics.median(ns["sorted"])
    for name, v in ns.items():
        m = statistics.median(v)
        print(f"| {name} | {m:.1f} [{min(v):.1f}-{max(v):.1f}] | {m / base:.2f}x |")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""A disc rattling with a period of two steps, at the end of a run, against the time step.

Usage:
  /usr/bin/python3 benchmarks/rattle_study.py COMPARE_DIR [--dt 2e-5,1.8e-5,1.6e-5] [--jobs 2]

COMPARE_DIR is the output of a `dem compare` run (any kind): every member scene the engine ran
(COMPARE_DIR/**/m*/native/scene.toml) is run again from its start with each --dt (forced, so that
steps above the engine's bound run too) to its end.time, and its last --steps steps are taken one
at a time. At each of them the load the walls and points carry along gravity is measured against
the discs' weight. A disc rattling at the step's own frequency (its contacts' dashpots past their
explicit limit, the rattle bounded by the Coulomb cap) makes that load alternate from step to step
while its mean stays at the weight: a run sampled every even step then reports a steady excess.
Prints, per dt, the members whose alternation exceeds --threshold of the weight, the largest
alternation (with the radius of that member's disc whose force changes most between the last two
steps, and half that change over its weight) and the largest mean excess; writes
COMPARE_DIR/rattle.json.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
from multiprocessing import Pool
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _module():
    sys.path.insert(0, os.environ.get("DEM_PYTHON_DIR", str(ROOT / "build" / "python")))
    import dem  # noqa: PLC0415 (the engine's module, built by CMake)
    return dem


def member_end(args: tuple[str, float, int]) -> dict:
    """One member scene at one dt: the load carried along gravity over the weight, minus 1, at
    each of the last `steps` steps."""
    path, dt, steps = args
    dem = _module()
    os.chdir(Path(path).parent)  # the scene's files are named relative to it
    scene = dem.load(Path(path).name)
    scene.set("integrator.dt", dt)
    scene.set("integrator.force_dt", True)
    res = scene.resolved()
    gx, gy = res["gravity"]
    g = math.hypot(gx, gy)
    sim = dem.Simulation(scene)
    end = float(res["end"]["time"])
    sim.step(max(0, int(round(end / dt)) - steps))
    weight = float(sum(sim.masses)) * g
    balance, forces = [], []
    for _ in range(steps):
        sim.step(1)
        carried = 0.0
        for obstacles in (sim.walls(), sim.points()):
            carried += sum((fx * gx + fy * gy) / g for fx, fy in zip(obstacles["fx"], obstacles["fy"]))
        balance.append(carried / weight - 1)
        forces = forces[-1:] + [sim.forces]
    alternation = sum(abs(b - a) for a, b in zip(balance, balance[1:])) / (2 * (len(balance) - 1))
    # The disc whose resultant changes most between the last two steps: half that change against
    # its weight (a rattling disc's force flips sign every step).
    change = [math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(forces[0], forces[1])]
    k = max(range(len(change)), key=change.__getitem__)
    return {"scene": path, "dt": dt, "balance": balance, "alternation": alternation,
            "mean": sum(balance) / len(balance), "kinetic_energy": sim.kinetic_energy(),
            "rattler": {"id": int(sim.ids[k]), "r": float(sim.radii[k]),
                        "force_over_weight": 0.5 * change[k] / (float(sim.masses[k]) * g)}}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("compare_dir", type=Path)
    ap.add_argument("--dt", default="2e-5,1.8e-5,1.6e-5", help="time steps [s], comma-separated")
    ap.add_argument("--steps", type=int, default=8, help="last steps measured one at a time")
    ap.add_argument("--threshold", type=float, default=1e-6, help="alternation counted as a rattle [of the weight]")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    scenes = sorted(str(p.resolve()) for p in a.compare_dir.glob("**/m*/native/scene.toml"))
    if not scenes:
        print(f"rattle_study: no member scenes (**/m*/native/scene.toml) under {a.compare_dir}", file=sys.stderr)
        return 2
    if a.steps < 2:
        print("rattle_study: --steps must be at least 2", file=sys.stderr)
        return 2
    dts = [float(x) for x in a.dt.split(",")]
    with Pool(a.jobs) as pool:
        runs = pool.map(member_end, [(s, dt, a.steps) for dt in dts for s in scenes])
    print(f"{len(scenes)} members, last {a.steps} steps each; load carried / weight - 1")
    print("dt [s]     rattling (> {:g})  largest alternation  largest |mean|  its disc: r [cm], force / weight"
          .format(a.threshold))
    for dt in dts:
        rs = [r for r in runs if r["dt"] == dt]
        n = sum(r["alternation"] > a.threshold for r in rs)
        worst = max(rs, key=lambda r: r["alternation"])
        print(f"{dt:<10.3g} {n:>3} of {len(rs):<14} {worst['alternation']:<20.2e} "
              f"{max(abs(r['mean']) for r in rs):<15.2e} {worst['rattler']['r']:.3f}, "
              f"{worst['rattler']['force_over_weight']:.3g}")
    (a.compare_dir / "rattle.json").write_text(json.dumps(runs, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

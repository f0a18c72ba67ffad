"""The paper's silo (Fig. 5, the 17/18 arrangement) filled to rest through the Python module dem,
printing the forces of the discs on each wall and point and how they carry the discs' weight.

    /usr/bin/python3 examples/paper_silo.py [SCENE] [--end-time S] [--out DIR]
"""
import argparse
from pathlib import Path

import dem

REPO = Path(__file__).resolve().parents[1]
ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("scene", nargs="?", default=REPO / "reference_inputs" / "scenes" / "silo_17_18.toml")
ap.add_argument("--end-time", type=float, help="stop there if rest comes later [s] (the scene's end.time)")
ap.add_argument("--out", help="also write the outputs of the filled silo here, as `dem run` does")
args = ap.parse_args()

scene = dem.Scene(args.scene)
if args.end_time:
    scene.set("end.time", args.end_time)
sim = dem.Simulation(scene)
status = sim.fill()
print(f"{scene.name}: {status} at t = {sim.time:.4f} s after {sim.steps} steps, {sim.n_discs} discs")

walls, points = sim.walls(), sim.points()
force = scene.resolved()["units"]["force"]   # the scene's unit system: dyn/cm (cgs) or N/m (si)
print(f"{'wall':14} {'group':12} {'normal':>12} {'shear':>12} {'contacts':>8}   [{force}]")
for name, group, normal, shear, n in zip(walls["name"], walls["group"], walls["normal"], walls["shear"],
                                          walls["contacts"]):
    print(f"{name:14} {group:12} {normal:12.6g} {shear:12.6g} {n:8d}")
for name, fy, n in zip(points["name"], points["fy"], points["contacts"]):
    print(f"{'point ' + name:27} {0.0 - fy:12.6g} {'':12} {n:8d}")  # downward push, as the walls' normal
gx, gy = scene.resolved()["gravity"]
weight = sim.masses.sum() * -gy
carried = -(walls["fy"].sum() + points["fy"].sum())  # forces of the discs on them: downward
print(f"weight of the discs {weight:.6g} {force}; walls and points carry {carried:.6g} ({carried / weight:.6f})")
if args.out:
    sim.write(args.out)
    print(f"outputs in {args.out}")

"""A dt sweep of the paper's silo through the Python module dem: each scheme at each time step,
filled to rest, with its rest time and the normal force on the side walls.

    /usr/bin/python3 examples/dt_sweep.py [SCENE] [END_TIME]
"""
import sys
from pathlib import Path

import dem

scene = dem.Scene(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parents[1] / "reference_inputs/scenes/silo_17_18.toml")
if len(sys.argv) > 2:
    scene.set("end.time", float(sys.argv[2]))
scene.set("integrator.force_dt", True)  # past the bound on purpose: where each scheme blows up
force = scene.resolved()["units"]["force"]   # the scene's unit system: dyn/cm (cgs) or N/m (si)
print(f"{'scheme':16} {'dt [s]':>8} {'status':>9} {'t [s]':>7} {'side walls [' + force + ']':>20}")
for scheme in ("paper_eq19", "velocity_verlet"):
    for dt in (2.5e-5, 5e-5, 1e-4):
        scene.set("integrator.scheme", scheme)
        scene.set("integrator.dt", dt)
        sim = dem.Simulation(scene)
        status = sim.fill()
        walls = sim.walls()
        side = sum(n for n, g in zip(walls["normal"], walls["group"]) if g.startswith("side"))
        print(f"{scheme:16} {dt:8.2g} {status:>9} {sim.time:7.4f} {side if status != 'unstable' else float('nan'):20.6g}")

#!/usr/bin/env python3
"""Writes the flat-bottom silos designed for the discharge agreement study
(reference_inputs/agreement/user/silo_<N>.toml and silo_<N>_fill.csv).

Each silo is sized to flow steadily and not jam during its discharge: the slit is 6 mean disc
diameters (2D silos of monodisperse discs jam seldom above 5), the fill is polydisperse (radii
uniform in 0.9 .. 1.1 cm, so that the rested packing is not a crystal whose flow goes in bursts)
and tall enough (H / W >= 1.5) that the pressure over the slit has saturated (Janssen). The discs
start on a loose jittered grid; the scene's end.time is the fall and rest of that grid (compare
--start frozen: the native engine's one fill). Constants are the hopper's (user/hopper.toml).

Run: python3 scripts/make_design_silos.py [--check]   (--check: fail if a committed file differs)
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "reference_inputs" / "agreement" / "user"

# name: discs, width [cm], slit [cm], flow time [s], end.time (the fill's fall and rest) [s]
DESIGNS = {
    "silo_1000": dict(n=1000, width=40.0, slit=12.0, flow=1.0, fill_time=1.5),
    "silo_2400": dict(n=2400, width=60.0, slit=12.0, flow=1.5, fill_time=2.0),
}
R_LO, R_HI = 0.9, 1.1          # cm
PITCH = 2.3                    # cm between grid sites: every pair of discs starts 0.1 cm apart or more
JITTER = 0.04                  # cm, uniform in x and y: no disc starts exactly above another


TEMPLATE = """# Written by scripts/make_design_silos.py: a flat-bottom silo designed for the discharge
# agreement study. {n} polydisperse discs (r {R_LO}-{R_HI} cm, a loose jittered grid in
# {csv_name}) fall and rest in a {w:g} cm wide silo, then discharge through a {s:g} cm slit
# (6 mean diameters: steady flow, no jam) for {flow:g} s. Compared from the native engine's
# rested packing: build/dem compare reference_inputs/agreement/user/{name}.toml --out DIR
[scene]
name = "{name}"
description = "flat-bottom silo, {n} polydisperse discs, {w:g} cm wide, {s:g} cm slit"

[physics]
gravity = [0.0, -981.0]          # cm/s^2

[integrator]
scheme = "velocity_verlet"
dt = 5e-5                        # s: t_c / 16 (t_c 7.9e-4 s), a sixth of the stability bound

[contact]                        # the law LIGGGHTS and YADE share with the engine
normal_spring = "overlap"
no_tension = "total"
friction_cap = "total"

[materials.glass]
density = 2.5                    # g/cm^3

[materials.steel]

[[pairs]]
materials = ["glass", "glass"]
kn = 5e7                         # g/s^2 per cm
ks = 1.5e7
eta_n = 800.0                    # g/s per cm: damping ratio 0.03 (dem run prints zeta_n)
eta_s = 400.0
mu = 0.4

[[pairs]]
materials = ["glass", "steel"]
kn = 1e8
ks = 3e7
eta_n = 1200.0
eta_s = 600.0
mu = 0.3

[[walls]]
name = "left"
group = "side_left"
from = [0.0, {top:g}]
to = [0.0, 0.0]
material = "steel"

[[walls]]
name = "right"
group = "side_right"
from = [{w:g}, {top:g}]
to = [{w:g}, 0.0]
material = "steel"

[[walls]]
name = "bottom_left"
group = "bottom"
from = [0.0, 0.0]
to = [{lo:g}, 0.0]
material = "steel"

[[walls]]
name = "gate"
group = "bottom"
from = [{lo:g}, 0.0]
to = [{hi:g}, 0.0]
material = "steel"

[[walls]]
name = "bottom_right"
group = "bottom"
from = [{hi:g}, 0.0]
to = [{w:g}, 0.0]
material = "steel"

[[points]]
name = "L"
at = [{lo:g}, 0.0]
material = "steel"

[[points]]
name = "R"
at = [{hi:g}, 0.0]
material = "steel"

[fill]
type = "file"
file = "{csv_name}"
material = "glass"

[end]
time = {fill_time:g}                       # s: the grid's fall and rest (the frozen packing's fill)
stop_at_rest = false

[output]
profile_bin = 4.0                # cm

[discharge]
time = {flow:g}                       # s after opening: a fraction of the fill leaves, the flow is steady
gate = "gate"
outlet_depth = 4.0               # cm below the slit: removed
jam_time = 0.3
series_interval = 0.005
"""


def fill(n: int, width: float, seed: int) -> np.ndarray:
    """n discs (x, y, r) on a jittered grid above the floor, rows filled left to right."""
    rng = np.random.default_rng(seed)
    per_row = int((width - 2 * R_HI - 2 * JITTER) // PITCH) + 1
    x0 = (width - (per_row - 1) * PITCH) / 2
    k = np.arange(n)
    x = x0 + (k % per_row) * PITCH + rng.uniform(-JITTER, JITTER, n)
    y = R_HI + 0.1 + (k // per_row) * PITCH + rng.uniform(-JITTER, JITTER, n)
    r = rng.uniform(R_LO, R_HI, n)
    return np.column_stack([x, y, r])


def scene_text(name: str, d: dict, csv_name: str, top: float) -> str:
    w, s = d["width"], d["slit"]
    return TEMPLATE.format(name=name, n=d["n"], flow=d["flow"], fill_time=d["fill_time"], w=w, s=s,
                           lo=(w - s) / 2, hi=(w + s) / 2, top=top, csv_name=csv_name, R_LO=R_LO, R_HI=R_HI)


def files() -> dict:
    out = {}
    for i, (name, d) in enumerate(DESIGNS.items()):
        xyr = fill(d["n"], d["width"], seed=20 + i)
        top = float(np.ceil(xyr[:, 1].max() + 2 * R_HI + 2))
        csv = "x,y,r\n" + "".join(f"{x:.4f},{y:.4f},{r:.4f}\n" for x, y, r in xyr)
        out[f"{name}_fill.csv"] = csv
        out[f"{name}.toml"] = scene_text(name, d, f"{name}_fill.csv", top)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true")
    a = ap.parse_args()
    stale = []
    for fname, text in files().items():
        p = OUT / fname
        if a.check:
            if not p.exists() or p.read_text() != text:
                stale.append(fname)
        else:
            p.write_text(text)
    if stale:
        print("out of date (run scripts/make_design_silos.py):", ", ".join(stale), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

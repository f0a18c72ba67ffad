#!/usr/bin/python3
"""Writes the calibration scenes, reference_inputs/agreement/calibration/NAME.toml + NAME.csv:
Chung & Ooi's (2011) DEM verification tests restated for linear 2D discs (docs/validation.md),
each a scene any user could run (``dem run NAME.toml``) and every code runs the same.

All scenes use the law the three codes share (overlap spring, total-force no-tension, Coulomb cap
on the total normal force), velocity Verlet at dt = 1e-5 s, discs of sand (rho = 2.65 g/cm^3)
from a CSV disc file with start velocities, free wall segments, gravity off except in the floor
tests. Springs and friction are Table 2's; the dashpots give a stated damping ratio zeta for a
pair of r = 1 cm discs (disc-disc: m* = m / 2; disc-wall: m* = m), eta = 2 zeta sqrt(k m*), so
that collisions rebound (the paper's dashpots are critical). The head-on disc-wall test with a
second wall material (``steel``) has disc-wall constants that are not Table 2's.

``--check``: exit 1 when the committed files differ from what this script writes.
"""
import math
import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent
OUT = HERE.parent / "reference_inputs" / "agreement" / "calibration"
sys.path.insert(0, str(HERE.parent / "build" / "python"))

from dem.compare.io import scene_toml  # noqa: E402

RHO, G = 2.65, 980.0           # g/cm^3, cm/s^2: the paper's sand and gravity (constants per rho g)
R = 1.0                        # cm, disc radius
MASS = RHO * math.pi * R ** 2  # g per cm of thickness
DT = 1e-5                      # s
ZETA = 0.3                     # damping ratio of the collisions (restitution tests: swept)
GAP = 1.2345e-3                # cm: the contact starts inside a step, not on its edge
V = 50.0                       # cm/s, impact speed

# Table 2 springs and friction (X/(rho g): cm; written absolute, K = X rho g, so that scenes
# without gravity take them); disc-wall = twice disc-disc; steel: a second wall
# material with its own constants (below 2 x disc-disc, which YADE's series rule can express).
SAND = {"kn_rho_g": 3.64e4, "ks_rho_g": 0.91e4, "mu": 0.577}
WALL = {"kn_rho_g": 7.28e4, "ks_rho_g": 1.82e4, "mu": 0.176}
STEEL = {"kn_rho_g": 5.46e4, "ks_rho_g": 1.365e4, "mu": 0.3}


def eta(k: float, m_eff: float, zeta: float) -> float:
    """Dashpot [g/s per cm] for the damping ratio zeta of a spring k with mass m_eff."""
    return float(f"{2 * zeta * math.sqrt(k * m_eff):.9g}")


def pair(a: str, b: str, c: dict, m_eff: float, zeta: float) -> dict:
    """One [[pairs]] entry: Table 2's springs (absolute) and the dashpots for zeta at m_eff."""
    kn, ks = c["kn_rho_g"] * RHO * G, c["ks_rho_g"] * RHO * G
    return {"materials": [a, b], "kn": kn, "ks": ks, "eta_n": eta(kn, m_eff, zeta), "eta_s": eta(ks, m_eff, zeta),
            "mu": c["mu"]}


def pair_comments(k: int, c: dict, m_eff: float, zeta: float, note: str) -> dict:
    return {f"pairs[{k}]": note,
            f"pairs[{k}].kn": f"K_n/(rho g) = {c['kn_rho_g']:g} cm",
            f"pairs[{k}].ks": f"K_s/(rho g) = {c['ks_rho_g']:g} cm",
            f"pairs[{k}].eta_n": f"zeta = {zeta} for m* = {m_eff / MASS:g} m (r = 1 cm)"}


def scene(name, test, description, discs, duration, walls, points=(), gravity=(0.0, 0.0), zeta=ZETA,
          wall_material="wall"):
    """(toml text, csv text) of one scene; discs: rows x, y, r, vx, vy, omega."""
    wc = {"wall": WALL, "steel": STEEL}[wall_material]
    doc = {
        "scene": {"name": name, "description": description},
        "physics": {"gravity": [float(gravity[0]), float(gravity[1])]},
        "integrator": {"scheme": "velocity_verlet", "dt": DT},
        "contact": {"normal_spring": "overlap", "no_tension": "total", "friction_cap": "total",
                    "lever_arm": "contact_point"},
        "materials": {"sand": {"density": RHO}, wall_material: {}},
        "pairs": [pair("sand", "sand", SAND, MASS / 2, zeta), pair("sand", wall_material, wc, MASS, zeta)],
        "walls": [{"name": w[0], "from": list(w[1]), "to": list(w[2]), "material": wall_material} for w in walls],
        "points": [{"name": p[0], "at": list(p[1]), "material": wall_material} for p in points],
        "fill": {"type": "file", "file": f"{name}.csv", "material": "sand", "velocities": True, "count": len(discs)},
        "end": {"time": duration, "stop_at_rest": False},
        "output": {"profile_bin": 2.0, "progress": False},
    }
    if not points:
        del doc["points"]
    comments = {"physics.gravity": "cm/s^2", "integrator.dt": "s",
                "contact": "the law LIGGGHTS, YADE and the engine share",
                "materials.sand.density": "g/cm^3", "end.time": "s",
                **pair_comments(0, SAND, MASS / 2, zeta, "Table 2 springs and friction, disc-disc"),
                **pair_comments(1, wc, MASS, zeta,
                                "Table 2, disc-wall" if wall_material == "wall" else "a second wall material")}
    text = scene_toml.dumps(doc, comments=comments, header=(
        f"Calibration, Chung & Ooi test {test}: {description}\n"
        "Generated by scripts/make_calibration_scenes.py -- edit the generator, not this file."))
    csv = ["x,y,r,vx,vy,omega"] + [",".join(repr(float(v)) for v in row) for row in discs]
    return text, "\n".join(csv) + "\n"


FLOOR = [("floor", (-20.0, 0.0), (20.0, 0.0))]


def _wall_impact(vt, vn, omega=0.0):
    """One disc a gap above the floor, moving down at vn and along it at vt."""
    return [[0.0, R + GAP, R, vt, -vn, omega]]


def scenes():
    """{name: (toml, csv)}."""
    out = {}

    def add(name, *a, **k):
        out[name] = scene(name, *a, **k)

    T = 0.004   # s: about 6 contact durations (t_c ~ 6.6e-4 s), then free flight
    add("head_on_disc_disc", 1, "head-on impact of two identical discs at 50 cm/s",
        [[-R - GAP / 2, 0.0, R, V, 0.0, 0.0], [R + GAP / 2, 0.0, R, 0.0, 0.0, 0.0]], T,
        [("floor", (-20.0, -50.0), (20.0, -50.0))])
    add("head_on_disc_wall_steel", 2, "head-on impact of a disc on a wall of a second material",
        _wall_impact(0.0, V), T, FLOOR, wall_material="steel")
    for z in (0.0, 0.3, 0.6, 0.9):
        add(f"restitution_zeta_{round(100 * z):03d}", 3, f"head-on disc-wall impact, damping ratio {z}",
            _wall_impact(0.0, V), T, FLOOR, zeta=z)
    for a in (10, 20, 30, 45, 60, 75):
        th = math.radians(a)
        add(f"oblique_wall_{a:02d}deg", 4, f"oblique disc-wall impact at 50 cm/s, {a} degrees from the normal",
            _wall_impact(V * math.sin(th), V * math.cos(th)), T, FLOOR)
    for vt in (5.0, 20.0, 60.0):
        add(f"tangential_vn20_vt{int(vt):02d}", 5, f"disc-wall impact, normal speed 20 cm/s, tangential {vt:g} cm/s",
            _wall_impact(vt, 20.0), T, FLOOR)
    add("spin_top", 6, "disc-wall impact with topspin (contact point sliding backwards)",
        _wall_impact(20.0, V, -100.0), T, FLOOR)
    add("spin_back", 6, "disc-wall impact with backspin (contact point sliding forwards)",
        _wall_impact(20.0, V, 30.0), T, FLOOR)
    far = [("floor", (-20.0, -50.0), (20.0, -50.0))]
    add("oblique_disc_disc", 7, "oblique impact of two identical discs (normal 50, tangential 30 cm/s)",
        [[-R - GAP / 2, 0.0, R, V, 30.0, 0.0], [R + GAP / 2, 0.0, R, 0.0, 0.0, 0.0]], T, far)
    r2 = 0.6
    add("unequal_discs", 8, "oblique impact of discs of radius 1 and 0.6 cm (mass ratio 2.8)",
        [[-r2 - GAP / 2, 0.0, r2, V, 20.0, 0.0], [R + GAP / 2, 0.0, R, 0.0, 0.0, 0.0]], T, far)
    # no dashpots: LAMMPS's cap on the total tangential force is then the shared law's cap on the
    # spring (docs/compare.md, "LAMMPS"), so the sliding is one law in every code
    add("sliding_disc_disc_undamped", 7, "undamped grazing disc-disc impact that slides throughout (normal 20, "
        "tangential 150 cm/s)",
        [[-R - GAP / 2, 0.0, R, 20.0, 150.0, 0.0], [R + GAP / 2, 0.0, R, 0.0, 0.0, 0.0]], T, far, zeta=0.0)
    add("grazing_disc_disc", 7, "grazing disc-disc impact that slides throughout (normal 20, tangential 150 cm/s)",
        [[-R - GAP / 2, 0.0, R, 20.0, 150.0, 0.0], [R + GAP / 2, 0.0, R, 0.0, 0.0, 0.0]], T, far)
    g = (0.0, -G)
    # 1e-5 cm above the floor: no contact at the start (LIGGGHTS's first force pass adds an
    # uncapped tangential dashpot to a contact that exists before the run); the first touch
    # slides at once, and the normal impulse is m g t however the disc lands, so the closed forms hold
    launch = [[0.0, R + 1e-5, R, 100.0, 0.0, 0.0]]
    add("floor_launch", "F1", "disc launched along the floor at 100 cm/s: slides, then rolls at 2/3 v0",
        launch, 0.3, [("floor", (-10.0, 0.0), (40.0, 0.0))], gravity=g)
    add("slit_end_launch", "F2", "as floor_launch on a floor of three walls meeting at points (slit ends) "
        "crossed while sliding (x = 3) and while rolling (x = 20)",
        launch, 0.3, [("floor_left", (-10.0, 0.0), (3.0, 0.0)), ("gate", (3.0, 0.0), (20.0, 0.0)),
                      ("floor_right", (20.0, 0.0), (40.0, 0.0))],
        points=[("L", (3.0, 0.0)), ("R", (20.0, 0.0))], gravity=g)
    # an open slit (x = 3 .. 3.5) bridged by the disc, launched without spin so that it still slides
    # when it reaches the slit: it pivots over the slit end L with the friction at its cap, strikes
    # the far end R (a point contact) below its centre, hops and rolls over R onto the floor beyond
    add("slit_roll_over", "F4", "disc launched at 15 cm/s onto an open slit 0.5 cm wide: slides over the slit end L, "
        "strikes the far end R (a point contact) and rolls over it",
        [[2.8, R + 1e-5, R, 15.0, 0.0, 0.0]], 0.1,
        [("floor_left", (-10.0, 0.0), (3.0, 0.0)), ("floor_right", (3.5, 0.0), (40.0, 0.0))],
        points=[("L", (3.0, 0.0)), ("R", (3.5, 0.0))], gravity=g)
    # tan 45 deg > 3 mu: the contact point slides down the incline throughout, the friction at mu F_n.
    # Launched at 20 cm/s so that the first touch's spring increment k_s v dt is above the cap at
    # once (from rest the slip at the touch is 0.1 cm/s and the uncapped tangential dashpot of the
    # shared law acts for several steps: 3e-3 of the friction impulse)
    th = math.radians(45.0)
    t_, n_ = (math.cos(th), -math.sin(th)), (math.sin(th), math.cos(th))
    add("incline_slide_45deg", "F5", "disc launched at 20 cm/s down a 45 degree incline: slides at its Coulomb cap "
        "throughout (tan 45 > 3 mu)",
        [[2 * t_[0] + (R + 1e-5) * n_[0], 2 * t_[1] + (R + 1e-5) * n_[1], R, 20 * t_[0], 20 * t_[1], 0.0]], 0.1,
        [("incline", (0.0, 0.0), (20 * t_[0], 20 * t_[1]))], gravity=g)
    add("rest_on_floor", "F3", "disc dropped from touching onto the floor, at rest: floor force = rho pi r^2 g",
        [[0.0, R, R, 0.0, 0.0, 0.0]], 0.03, [("floor", (-10.0, 0.0), (10.0, 0.0))], gravity=g)
    return out


def files():
    """{file name: text} of every scene and disc file."""
    out = {}
    for name, (toml, csv) in scenes().items():
        out[f"{name}.toml"] = toml
        out[f"{name}.csv"] = csv
    return out


def main(argv):
    if "--check" in argv:  # CI: the committed scenes must be what the generator writes
        want = files()
        stale = [n for n, t in want.items() if not (OUT / n).exists() or (OUT / n).read_text() != t]
        extra = [p.name for p in OUT.glob("*") if p.name not in want] if OUT.exists() else []
        if stale or extra:
            print("stale calibration scenes (run scripts/make_calibration_scenes.py):",
                  ", ".join(stale + extra), file=sys.stderr)
            return 1
        return 0
    OUT.mkdir(parents=True, exist_ok=True)
    for name, text in files().items():
        (OUT / name).write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

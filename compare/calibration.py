"""Calibration proof: the same collisions in every code at the same dt give the same
restitution, contact duration and rebound spin (issue 4, point 2).

Four collisions, gravity off, starting a small gap apart so that every code sees the contact
begin inside a step: disc-disc head-on, disc-disc oblique (45 degrees), disc-wall head-on,
disc-wall oblique (45 degrees). Everything is measured from the end state only (after the
discs separated, motion is free): with d(T) the gap at the end and v' the separation speed,
the contact ended at T - d(T)/v' and began at gap0 / v0, so t_c is their difference; e is
v'/v0 along the normal; the spin is the end omega.

The contact constants are the scene's springs and friction with the dashpots scaled to a
damping ratio of 0.3 (the paper's are critical, so a head-on collision would not rebound and
there would be no restitution to compare); this is a translation test, not the paper's
physics. An independent reference for the head-on cases is the ODE of the shared variant
(m x'' = -(k x + c x'), contact while the total force is positive) integrated with RK4 at
dt / 1000.
"""
from __future__ import annotations

import copy
import math

import numpy as np

from .common import SHARED_VARIANT, Case, disc_material, pair

ZETA = 0.3
SPEED = 50.0       # [cm/s] approach speed
GAP = 1.2345e-3    # [cm] initial gap: the contact starts inside a step, not on its edge
DT = 1e-5          # [s]
DURATION = 0.01    # [s]: several contact durations, then free flight


def _scaled(resolved: dict) -> dict:
    r = copy.deepcopy(resolved)
    r["contact"] = dict(SHARED_VARIANT)
    r["gravity"] = [0.0, 0.0]
    dm = disc_material(r)
    rho = {m["name"]: m["density"] for m in r["materials"]}[dm]
    mass = rho * math.pi * 1.0 ** 2          # the calibration discs have r = 1 cm
    for p in r["pairs"]:
        wall_pair = p["materials"][0] != p["materials"][1]
        m_eff = mass if wall_pair else mass / 2
        p["eta_n"] = 2 * ZETA * math.sqrt(p["kn"] * m_eff)
        p["eta_s"] = 2 * ZETA * math.sqrt(p["ks"] * m_eff)
    r["points"] = []
    r["walls"] = [{"name": "floor", "group": "floor", "from": [-20.0, 0.0], "to": [20.0, 0.0],
                   "material": next(m["name"] for m in r["materials"] if m["density"] == 0), "active": True}]
    r["profile_bin"] = 2.0
    return r


def cases(resolved: dict) -> list[tuple[Case, dict]]:
    """(case, geometry) for the four collisions; geometry says how to measure them."""
    r = _scaled(resolved)
    rad = 1.0
    out = []
    for name, angle in (("disc_disc_head_on", 0.0), ("disc_disc_oblique", 45.0)):
        rr = copy.deepcopy(r)
        rr["walls"][0].update({"from": [-20.0, -50.0], "to": [20.0, -50.0]})  # out of reach
        vt = SPEED * math.tan(math.radians(angle))
        # disc 0 moves +x (normal) with a tangential +y component; disc 1 at rest
        d = np.array([[-rad - GAP / 2, 0.0, rad, SPEED, vt, 0.0], [rad + GAP / 2, 0.0, rad, 0.0, 0.0, 0.0]])
        out.append((Case(name=name, resolved=rr, discs=d, dt=DT, duration=DURATION),
                    {"kind": "dd", "v_n": SPEED, "v_t": vt}))
    for name, angle in (("disc_wall_head_on", 0.0), ("disc_wall_oblique", 45.0)):
        vt = SPEED * math.tan(math.radians(angle))
        d = np.array([[0.0, rad + GAP, rad, vt, -SPEED, 0.0]])
        out.append((Case(name=name, resolved=copy.deepcopy(r), discs=d, dt=DT, duration=DURATION),
                    {"kind": "dw", "v_n": SPEED, "v_t": vt}))
    return out


def measure(case: Case, geo: dict, discs_end: list) -> dict:
    """Restitution, contact duration, tangential rebound and spin from the end state."""
    d = np.asarray(discs_end, float)
    T = case.duration
    if geo["kind"] == "dd":
        if len(d) != 2:
            raise ValueError(f"{case.name}: expected 2 discs at the end, got {len(d)}")
        rel = d[1, 3] - d[0, 3]                  # separation speed along x (the normal)
        gap_end = (d[1, 0] - d[0, 0]) - (d[0, 2] + d[1, 2])
        vt_rel = (d[1, 4] - d[0, 4])             # tangential relative velocity (centres)
        spin = d[0, 5]
    else:
        if len(d) != 1:
            raise ValueError(f"{case.name}: expected 1 disc at the end, got {len(d)}")
        rel = d[0, 4]                            # rebound speed (+y)
        gap_end = d[0, 1] - d[0, 2]
        vt_rel = d[0, 3]
        spin = d[0, 5]
    e = rel / geo["v_n"]
    t_c = (T - gap_end / rel - GAP / geo["v_n"]) if rel > 0 else float("nan")
    return {"e": float(e), "t_c": float(t_c), "v_t_end": float(vt_rel), "omega_end": float(spin)}


def ode_reference(case: Case, geo: dict) -> dict:
    """Head-on e and t_c of the shared variant from the contact ODE (RK4 at dt / 1000)."""
    r = case.resolved
    dm = disc_material(r)
    rho = {m["name"]: m["density"] for m in r["materials"]}[dm]
    mass = rho * math.pi * case.discs[0, 2] ** 2
    if geo["kind"] == "dd":
        p = pair(r, dm, dm)
        m = mass / 2
    else:
        wm = r["walls"][0]["material"]
        p = pair(r, dm, wm)
        m = mass
    k, c = p["kn"], p["eta_n"]
    h = case.dt / 1000
    x, v, t = 0.0, geo["v_n"], 0.0          # overlap and its rate

    def acc(x, v):
        f = k * x + c * v
        return -max(f, 0.0) / m

    while True:
        k1x, k1v = v, acc(x, v)
        k2x, k2v = v + h / 2 * k1v, acc(x + h / 2 * k1x, v + h / 2 * k1v)
        k3x, k3v = v + h / 2 * k2v, acc(x + h / 2 * k2x, v + h / 2 * k2v)
        k4x, k4v = v + h * k3v, acc(x + h * k3x, v + h * k3v)
        x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x)
        v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        t += h
        if x <= 0 or (k * x + c * v <= 0 and v < 0):
            break
        if t > 1.0:
            break
    # After the force vanishes with x > 0 the bodies fly apart at the speed reached; the
    # geometric contact (what the end state measures) ends when the overlap is gone.
    if x > 0 and v < 0:
        t += x / -v
    return {"e": float(-v / geo["v_n"]), "t_c": float(t)}


# Tolerances between codes at the same dt (and against the ODE for head-on cases).
TOL = {"e": 0.01, "t_c_steps": 1.0, "omega_rel": 0.02, "v_t_rel": 0.02}

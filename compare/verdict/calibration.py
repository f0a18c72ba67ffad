"""Calibration: Chung & Ooi's (2011) verification tests restated for linear 2D discs, as scene
files (reference_inputs/agreement/calibration/, written by scripts/make_calibration_scenes.py),
measured in every code and judged against closed forms or an independent integration.

``measure`` reads a run's end state (and, for the rest test, its wall profiles); ``reference``
gives the value of every measured quantity from the scene alone:
- collisions (gravity off, one disc and a wall, or two discs): the normal n is the wall's inward
  normal or the line of centres at the start, the tangent t the wall's from -> to direction or n
  turned +90 degrees. e = -(u_end . n) / (u_start . n) with u the relative velocity of the centres
  (disc 1 - disc 0; the disc for a wall); t_c from the end state: motion outside the contact is
  free flight, so the contact began when the start state's straight path first touches and ended
  when the end state's path, traced back, last touched (exact for a wall and for two discs);
  v_t_end = u_end . t; omega_end_k each disc's spin.
  Reference: head-on, the closed form of the clamped spring-dashpot (Schwager & Poeschel 2007:
  the total force vanishes at omega t* = atan2(c omega, -(k - c gamma)), e = -v(t*)/v0, and the
  discs part geometrically x(t*)/|v(t*)| later); oblique impacts, the continuous one-contact
  equations of the shared law integrated with RK4 at dt / 1000 (``integrate``): normal
  spring-dashpot clamped >= 0, tangential spring (its displacement accumulating the contact
  point's slip) + dashpot, the spring capped at mu |F_n| with the dashpot off while capped,
  torque -r F_t on each disc, I = m r^2 / 2. Beside it, for disc-wall impacts, the rigid-body
  Coulomb impact as ``coulomb_limit`` (normal impulse m (1 + e) v_n; tangential impulse mu times
  it if the contact point slides throughout, i.e. |slip| >= 3 mu (1 + e) v_n, else the impulse
  m |slip| / 3 that stops the slip): the shared law departs from it, by its tangential spring
  (the slip reverses) and by its tangential dashpot, which acts uncapped while the spring is below
  the cap (the first moments of a contact, where F_n is small), so that a sliding impact takes
  more than mu times the normal impulse.
- a disc launched along the floor (gravity on, moving at the start): it slides with deceleration
  mu g until its contact point stops, after t_roll = |slip_0| / (3 mu g), then rolls at
  v0 - mu g t_roll (2 v0 / 3 without spin). Measured from the end state: v_end and omega_end, and
  t_roll from the distance travelled, x(T) - x0 = v_end T + (v0 - v_end) t_roll / 2 (constant
  deceleration while sliding, constant speed after), which needs no time series.
- a disc at rest on the floor: the floor force (sum of the wall profiles' normal force) is the
  weight rho pi r^2 g exactly.
- a disc launched down an incline steeper than atan(3 mu) (gravity has a component g_t along the
  wall): its contact point slides throughout, so friction is mu m g_n and v and omega change at
  constant rates (``incline``); v_end and omega_end_0 from the end state. The friction impulse is
  mu times the normal impulse, m g_n T, however the disc lands.
- a disc crossing an open slit (a scene point that ends one wall only: a point contact): no
  closed form; v_end, vn_end, omega_end_0 and the distance s_end are judged between the codes
  only (``slit_reference``).

Tolerances (``tolerances``): the codes step an explicit scheme whose error in a collision is
first order in dt / t_c (the contact switches on and off inside a step and the dashpot force
jumps there), so a quantity that the collision changes by Delta (its ``scale``) is within
K dt / t_c x Delta of the continuous answer, and t_c within one step more (the contact starts
inside a step). A sliding contact adds one error of its own: at the first touch the normal
dashpot makes the cap mu eta_n v_n while the tangential spring starts at 0, so the tangential
dashpot acts uncapped (eta_s |slip|, several times the cap) for the time the spring takes to
reach the cap, a few microseconds, which a scheme resolves only to a step: the tangential
velocity and the spins get K eta_s |slip| dt / m* (x r / I for a spin) more. Floor tests: K dt
on t_roll, K dt / t_roll of the launch speed on the final motion; the incline: K dt / T of each
quantity's change; the weight at rest: 1e-9. K = 1: every code is within it on every scene here
at dt = 1e-5 s (the measured ratio is at most about 0.7 of the tolerance; on the incline YADE's
leapfrog, half a step behind in v, is at 0.5), while a 10 % error in mu or k_n moves t_roll or
t_c beyond it.
Between codes that run the same discrete law the tolerance is CODE_REL = 1e-4 of the scale.

``python3 -m dem.compare.verdict.calibration --out DIR [--codes native,liggghts,yade[,lammps]]`` runs every
scene in each code and writes DIR/calibration.md and DIR/calibration.json; exit 1 when a code is outside a
tolerance, differs from another code, or fails to run. A code that cannot express a scene (LAMMPS:
the open slit) is listed as refused and not run.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from dem.compare.codes import backends
from dem.compare.cases.common import ROOT, Case, CaseError, disc_material, pair, resolve, Result
from dem.compare.verdict import study

SCENES = ROOT / "reference_inputs" / "agreement" / "calibration"
K_DT = 1.0            # code vs reference: K_DT x (dt / t_c x scale + the sliding term), module text
CODE_REL = 1e-4       # code vs code: this x the quantity's scale
WEIGHT_REL = 1e-9     # the weight at rest: exact up to the decay of the drop
TOL = {"k": K_DT, "code_vs_code_rel": CODE_REL, "t_c_steps": 1.0, "weight_rel": WEIGHT_REL}


# ---------------------------------------------------------------------------------------- scenes

def scene_names() -> list[str]:
    return sorted(p.stem for p in SCENES.glob("*.toml"))


def start_discs(resolved: dict) -> np.ndarray:
    """(n, 6) x, y, r, vx, vy, omega at the start (``dem resolve``'s discs and velocities)."""
    d = np.array([row[:3] for row in resolved["discs"]], float).reshape(-1, 3)
    v = np.array(resolved.get("velocities") or np.zeros((len(d), 3)), float).reshape(-1, 3)
    return np.column_stack([d, v])


def case(name: str) -> Case:
    """The comparison case of one calibration scene (the scene as ``dem resolve`` gives it)."""
    r = resolve(SCENES / f"{name}.toml")
    return Case(name=name, resolved=r, discs=start_discs(r), dt=float(r["integrator"]["dt"]),
                duration=float(r["end"]["time"]))


# -------------------------------------------------------------------------------------- geometry

def _mass(resolved: dict, radius: float) -> float:
    rho = {m["name"]: m["density"] for m in resolved["materials"]}[disc_material(resolved)]
    return rho * math.pi * radius ** 2


def _wall_distance(w: dict, p) -> float:
    a, b = np.array(w["from"], float), np.array(w["to"], float)
    s = np.clip(np.dot(np.asarray(p) - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
    return float(np.linalg.norm(np.asarray(p) - (a + s * (b - a))))


def geometry(resolved: dict, discs_start: np.ndarray) -> dict:
    """What kind of test the scene is, and its normal n and tangent t (see the module text)."""
    d = np.asarray(discs_start, float).reshape(-1, 6)
    g = np.array(resolved["gravity"], float)
    walls = [w for w in resolved["walls"] if w.get("active", True)]
    if len(d) == 2:
        n = d[1, :2] - d[0, :2]
        n /= np.linalg.norm(n)
        return {"kind": "disc_disc", "n": n, "t": np.array([-n[1], n[0]])}
    if len(d) != 1:
        raise CaseError(f"calibration: one or two discs, got {len(d)}")
    w = min(walls, key=lambda w: _wall_distance(w, d[0, :2]))
    a, b = np.array(w["from"], float), np.array(w["to"], float)
    t = (b - a) / np.linalg.norm(b - a)
    n = np.array([-t[1], t[0]])
    if np.dot(d[0, :2] - a, n) < 0:
        n = -n
    if _open_points(resolved):
        kind = "slit"
    elif np.linalg.norm(g) > 0 and abs(float(g @ t)) > 1e-12 * np.linalg.norm(g):
        kind = "incline"
    elif np.linalg.norm(g) > 0:
        kind = "floor_launch" if np.linalg.norm(d[0, 3:5]) > 0 or d[0, 5] else "floor_rest"
    else:
        kind = "disc_wall"
    return {"kind": kind, "n": n, "t": t, "wall": w, "wall_point": a}


def _open_points(resolved: dict) -> list[dict]:
    """Scene points that end one active wall only: the ends of an open slit, which act as point
    contacts (a point where two walls meet never acts: a disc touches a wall first)."""
    ends = [tuple(e) for w in resolved["walls"] if w.get("active", True) for e in (w["from"], w["to"])]
    return [p for p in resolved.get("points", []) if ends.count(tuple(p["at"])) == 1]


def _pair_of(resolved: dict, geo: dict) -> dict:
    dm = disc_material(resolved)
    return pair(resolved, dm, geo["wall"]["material"] if "wall" in geo else dm)


def _relative(d: np.ndarray, geo: dict):
    """Relative position and velocity of the centres (disc 1 - disc 0; for a wall, the disc's)
    and the distance at which they touch (r0 + r1; for a wall, r)."""
    if geo["kind"] == "disc_disc":
        return d[1, :2] - d[0, :2], d[1, 3:5] - d[0, 3:5], d[0, 2] + d[1, 2]
    return d[0, :2], d[0, 3:5], d[0, 2]


def _touch(p, u, reach: float, geo: dict, backwards: bool) -> float:
    """Free-flight time s >= 0 until |p + u s| = reach (two discs) or the height over the wall
    = reach; backwards: |p - u s| = reach, traced back from the end."""
    u = -np.asarray(u) if backwards else np.asarray(u)
    if geo["kind"] == "disc_disc":
        a, b, c = float(u @ u), 2 * float(p @ u), float(p @ p) - reach ** 2
        disc = b * b - 4 * a * c
        if a == 0 or disc < 0:
            return float("nan")
        return float((-b - math.sqrt(disc)) / (2 * a))
    h = float((np.asarray(p) - geo["wall_point"]) @ geo["n"]) - reach
    un = float(u @ geo["n"])
    return h / -un if un < 0 else float("nan")


# -------------------------------------------------------------------------------------- measure

def measure(resolved: dict, discs_start: np.ndarray, discs_end: np.ndarray, duration: float,
            profiles: dict | None = None) -> dict:
    """The calibration quantities of one run from its start and end states (module text)."""
    d0 = np.asarray(discs_start, float).reshape(-1, 6)
    d1 = np.asarray(discs_end, float).reshape(-1, 6)
    if d1.shape != d0.shape:
        raise ValueError(f"calibration: {len(d0)} discs at the start, {len(d1)} at the end")
    geo = geometry(resolved, d0)
    n, t = geo["n"], geo["t"]
    if geo["kind"] == "floor_rest":
        if profiles is None:
            raise ValueError("calibration: the rest test needs the wall profiles")
        return {"floor_force": float(sum(sum(p["normal"]) for p in profiles.values()))}
    if geo["kind"] in ("incline", "slit"):
        out = {"v_end": float(d1[0, 3:5] @ t), "omega_end_0": float(d1[0, 5])}
        if geo["kind"] == "slit":
            out.update({"vn_end": float(d1[0, 3:5] @ n), "s_end": float((d1[0, :2] - d0[0, :2]) @ t)})
        return out
    if geo["kind"] == "floor_launch":
        v0, v1 = float(d0[0, 3:5] @ t), float(d1[0, 3:5] @ t)
        dx = float((d1[0, :2] - d0[0, :2]) @ t)
        t_roll = 2 * (dx - v1 * duration) / (v0 - v1) if v0 != v1 else float("nan")
        return {"v_end": v1, "omega_end_0": float(d1[0, 5]), "t_roll": float(t_roll)}
    p0, u0, reach = _relative(d0, geo)
    p1, u1, _ = _relative(d1, geo)
    un0, un1 = float(u0 @ n), float(u1 @ n)
    out = {"e": -un1 / un0 if un0 else float("nan")}
    s0 = _touch(p0, u0, reach, geo, backwards=False)
    s1 = _touch(p1, u1, reach, geo, backwards=True)
    out["t_c"] = float(duration - s1 - s0) if un1 > 0 else float("nan")
    out["v_t_end"] = float(u1 @ t)
    for k in range(len(d1)):
        out[f"omega_end_{k}"] = float(d1[k, 5])
    return out


# ------------------------------------------------------------------------------------- reference

def head_on(k: float, c: float, m: float, v0: float) -> dict:
    """Closed form of a head-on impact on the clamped linear spring-dashpot (module text):
    restitution e and the geometric contact duration t_c (until the overlap is gone)."""
    gamma = c / (2 * m)
    w = math.sqrt(k / m - gamma ** 2)
    theta = math.atan2(c * w, -(k - c * gamma))
    ts = theta / w
    decay = math.exp(-gamma * ts)
    e = -decay * (math.cos(theta) - gamma / w * math.sin(theta))
    x = v0 / w * decay * math.sin(theta)
    return {"e": e, "t_c": ts + (x / (e * v0) if x > 0 else 0.0), "t_force": ts}


def integrate(resolved: dict, discs_start: np.ndarray, duration: float, h: float,
              lever: str = "radius") -> np.ndarray:
    """End state (n, 6) of a one-contact collision from the continuous equations of the shared
    law, RK4 with step h during the contact and exact free flight outside it (module text).
    lever: "radius" (torque arm r, the engine's eq. 15) or "contact_point" (r - overlap/2)."""
    d = np.array(discs_start, float).reshape(-1, 6)
    geo = geometry(resolved, d)
    p = _pair_of(resolved, geo)
    kn, ks, cn, cs, mu = p["kn"], p["ks"], p["eta_n"], p["eta_s"], p["mu"]
    two = geo["kind"] == "disc_disc"
    rad = d[:, 2].copy()
    m = np.array([_mass(resolved, r) for r in rad])
    inv_m, inv_i = 1 / m, 2 / (m * rad ** 2)
    p0, u0, reach = _relative(d, geo)
    s0 = _touch(p0, u0, reach, geo, backwards=False)
    if not (s0 >= 0) or s0 > duration:
        d[:, :2] += d[:, 3:5] * duration
        return d
    d[:, :2] += d[:, 3:5] * s0
    wn, wp = geo["n"], geo.get("wall_point")

    def forces(y):
        """Accelerations and d(spring)/dt for the state y = [x, y, vx, vy, w] per disc + [s]."""
        if two:
            dx, dy = y[5] - y[0], y[6] - y[1]
            dist = math.hypot(dx, dy)
            nx, ny = dx / dist, dy / dist
            ovl = rad[0] + rad[1] - dist
            vx, vy = y[7] - y[2], y[8] - y[3]
        else:
            nx, ny = wn
            ovl = rad[0] - ((y[0] - wp[0]) * nx + (y[1] - wp[1]) * ny)
            vx, vy = y[2], y[3]
        tx, ty = -ny, nx
        arm = [r - ovl / 2 if lever == "contact_point" else r for r in rad]
        j = 1 if two else 0
        spin = arm[j] * y[5 * j + 4] + (arm[0] * y[4] if two else 0.0)
        vt = vx * tx + vy * ty - spin
        fn = max(0.0, kn * ovl - cn * (vx * nx + vy * ny))
        s = y[-1]
        cap = mu * fn
        # at the cap (within rounding: the clamp below sets ks |s| = cap): sliding, dashpot off
        if ks * abs(s) >= cap * (1 - 1e-9):
            ft = -math.copysign(cap, s)
        else:
            ft = -(ks * s + cs * vt)
        fx, fy = fn * nx + ft * tx, fn * ny + ft * ty      # on disc j (the moving disc for a wall)
        out = [0.0] * len(y)
        out[5 * j:5 * j + 5] = [y[5 * j + 2], y[5 * j + 3], fx * inv_m[j], fy * inv_m[j], -arm[j] * ft * inv_i[j]]
        if two:
            out[0:5] = [y[2], y[3], -fx * inv_m[0], -fy * inv_m[0], -arm[0] * ft * inv_i[0]]
        out[-1] = vt
        return out, ovl, fn

    y = [v for row in d for v in (row[0], row[1], row[3], row[4], row[5])] + [0.0]
    t = s0
    while t < duration:
        k1, ovl, fn = forces(y)
        if ovl <= 0 and t > s0:
            break
        y2 = [a + h / 2 * b for a, b in zip(y, k1)]
        k2 = forces(y2)[0]
        y3 = [a + h / 2 * b for a, b in zip(y, k2)]
        k3 = forces(y3)[0]
        y4 = [a + h * b for a, b in zip(y, k3)]
        k4 = forces(y4)[0]
        y = [a + h / 6 * (b1 + 2 * b2 + 2 * b3 + b4) for a, b1, b2, b3, b4 in zip(y, k1, k2, k3, k4)]
        t += h
        _, ovl, fn = forces(y)
        cap = mu * fn / ks
        if abs(y[-1]) > cap:
            y[-1] = math.copysign(cap, y[-1])
    for i in range(len(d)):
        d[i, 0], d[i, 1], d[i, 3], d[i, 4], d[i, 5] = y[5 * i:5 * i + 5]
    d[:, :2] += d[:, 3:5] * max(0.0, duration - t)
    return d


def incline(disc, n, t, gravity, mu: float, duration: float) -> dict:
    """A disc sliding on an incline throughout (module text): the friction mu m g_n opposes the
    contact point's slip, so v and omega change at constant rates; ValueError when the slip
    would stop within ``duration`` (the disc would then roll: not this closed form)."""
    g_n, g_t = -float(gravity @ n), float(gravity @ t)
    r, v0, w0 = disc[2], float(disc[3:5] @ t), disc[5]
    kappa = float(np.cross(t, n))
    slip = v0 + r * w0 * kappa
    sign = math.copysign(1.0, slip if slip else g_t)
    rate = g_t - 3 * sign * mu * g_n                  # d(slip)/dt while sliding
    if rate * sign < 0 and abs(slip / rate) < duration:
        raise ValueError(f"calibration: the slip stops after {abs(slip / rate):.4g} s < {duration:g} s")
    a, alpha = g_t - sign * mu * g_n, -sign * 2 * mu * g_n * kappa / r
    return {"v_end": v0 + a * duration, "omega_end_0": w0 + alpha * duration,
            "how": "slides throughout: dv/dt = g_t - mu g_n, r domega/dt = 2 mu g_n",
            "scale": {"v_end": abs(a) * duration, "omega_end_0": abs(alpha) * duration}, "t_slide": duration}


def slit_reference(d: np.ndarray, duration: float) -> dict:
    """No closed form for a disc crossing an open slit (it pivots, strikes the far slit end and
    rolls over it): the codes are judged against the native engine only, within CODE_REL of the
    scales (the launch speed, its spin and the distance it would roll at that speed)."""
    v0 = float(np.linalg.norm(d[0, 3:5]))
    return {"how": "no closed form: each code against the native engine", "cross_code_only": True,
            "scale": {"v_end": v0, "vn_end": v0, "omega_end_0": v0 / d[0, 2], "s_end": v0 * duration}}


def reference(resolved: dict, discs_start: np.ndarray, dt: float, lever: str | None = None,
              integrate_all: bool = False) -> dict:
    """The closed-form or independent value of every quantity ``measure`` gives (module text),
    with ``how`` (which formula) and ``scale`` (per quantity: the change the test makes, for the
    tolerances) and ``t_c_ref``."""
    lever = lever or resolved["contact"].get("lever_arm", "radius")
    d = np.asarray(discs_start, float).reshape(-1, 6)
    geo = geometry(resolved, d)
    n, t = geo["n"], geo["t"]
    p = _pair_of(resolved, geo)
    g = float(np.linalg.norm(resolved["gravity"]))
    duration = float(resolved["end"]["time"])
    m = np.array([_mass(resolved, r) for r in d[:, 2]])
    if geo["kind"] == "floor_rest":
        return {"floor_force": float(m[0] * g), "how": "weight rho pi r^2 g", "scale": {"floor_force": m[0] * g}}
    if geo["kind"] == "slit":
        return slit_reference(d, duration)
    if geo["kind"] == "incline":
        return incline(d[0], n, t, np.asarray(resolved["gravity"], float), p["mu"], duration)
    if geo["kind"] == "floor_launch":
        v0 = float(d[0, 3:5] @ t)
        slip = v0 + d[0, 2] * d[0, 5] * float(np.cross(t, n))   # contact point's speed along t
        t_roll = abs(slip) / (3 * p["mu"] * g)
        v_end = v0 - math.copysign(p["mu"] * g * t_roll, slip)
        omega = -v_end / d[0, 2] * float(np.cross(t, n))
        return {"v_end": v_end, "omega_end_0": omega, "t_roll": t_roll,
                "how": "slide at mu g until the contact point stops, then roll",
                "scale": {"v_end": abs(v0), "omega_end_0": abs(v0) / d[0, 2], "t_roll": t_roll}}
    two = geo["kind"] == "disc_disc"
    m_eff = m[0] * m[1] / (m[0] + m[1]) if two else m[0]
    p0, u0, reach = _relative(d, geo)
    v_n = -float(u0 @ n)
    ho = head_on(p["kn"], p["eta_n"], m_eff, v_n)
    t_c = ho["t_c"]
    # slip of the contact point along t (disc 1 relative to disc 0, or the disc on the wall)
    tt = np.array([-n[1], n[0]])
    arm = d[:, 2] * d[:, 5]
    slip = float(u0 @ tt) - (arm[1] + arm[0] if two else arm[0])
    j_n = m_eff * (1 + ho["e"]) * v_n
    vt0 = float(u0 @ t)
    scale = {"e": 1.0, "t_c": t_c, "v_t_end": max(abs(vt0), p["mu"] * (1 + ho["e"]) * v_n)}
    for k in range(len(d)):
        scale[f"omega_end_{k}"] = max(abs(d[k, 5]), 2 * p["mu"] * j_n / (m[k] * d[k, 2]))
    # the uncapped tangential dashpot at the first touch, resolved to one step (module text)
    window = {"v": p["eta_s"] * abs(slip) * dt / m_eff}
    for k in range(len(d)):
        window[f"omega_end_{k}"] = p["eta_s"] * abs(slip) * dt * d[k, 2] / (m[k] * d[k, 2] ** 2 / 2)
    out = {"t_c_ref": t_c, "scale": scale, "window": window}
    head = abs(slip) == 0 and vt0 == 0
    sliding = abs(slip) >= 3 * p["mu"] * (1 + ho["e"]) * v_n
    if head and not integrate_all:
        out.update({"e": ho["e"], "t_c": t_c, "v_t_end": 0.0, "how": "closed form, head-on"})
        out.update({f"omega_end_{k}": float(d[k, 5]) for k in range(len(d))})
        return out
    if not two:
        # Rigid-body Coulomb impact: tangential impulse mu x the normal impulse if the contact
        # point slides throughout, else what stops its slip (m |slip| / 3). The shared law's
        # tangential spring and its uncapped dashpot at the first touch (module text) depart
        # from it: the reference is the integration, this limit is reported beside it.
        jt = -math.copysign(min(p["mu"] * j_n, m[0] * abs(slip) / 3), slip)   # along tt, on the disc
        v1 = d[0, 3:5] + (j_n * n + jt * tt) / m[0]
        out["coulomb_limit"] = {"v_t_end": float(v1 @ t),
                                "omega_end_0": float(d[0, 5] - d[0, 2] * jt / (m[0] * d[0, 2] ** 2 / 2)),
                                "slides_throughout": bool(sliding)}
    end = integrate(resolved, d, duration, dt / 1000, lever)
    out.update(measure(resolved, d, end, duration))
    out["how"] = "RK4 at dt/1000 of the continuous law" + (" (slides throughout)" if sliding else "")
    return out


# ------------------------------------------------------------------------------------- judging

def tolerances(ref: dict, dt: float) -> dict:
    """{quantity: absolute tolerance} of a code against the reference (module text)."""
    sc, k = ref["scale"], K_DT
    if ref.get("cross_code_only"):
        return {}                          # no reference: judged against the native engine only
    if "t_slide" in ref:                   # the sliding incline: K dt x each constant rate
        return {q: k * dt / ref["t_slide"] * s for q, s in sc.items()}
    if "floor_force" in sc:
        return {"floor_force": WEIGHT_REL * sc["floor_force"]}
    if "t_roll" in sc:
        return {"v_end": k * dt / sc["t_roll"] * sc["v_end"],
                "omega_end_0": k * dt / sc["t_roll"] * sc["omega_end_0"], "t_roll": k * dt}
    r = dt / ref["t_c_ref"]
    w = ref["window"]
    out = {"e": k * r, "t_c": TOL["t_c_steps"] * dt + k * r * sc["t_c"], "v_t_end": k * (r * sc["v_t_end"] + w["v"])}
    for q in sc:
        if q.startswith("omega_end_"):
            out[q] = k * (r * sc[q] + w[q])
    return out


def code_tolerances(ref: dict) -> dict:
    """{quantity: absolute tolerance} between two codes: CODE_REL x the quantity's scale."""
    return {q: CODE_REL * s for q, s in ref["scale"].items()}


def within(measured: dict, ref: dict, dt: float, other: dict | None = None) -> dict:
    """{quantity: pass} of a code against the reference (other=None: ``tolerances``) or against
    another code's measures (CODE_REL x the quantity's scale)."""
    tol = tolerances(ref, dt) if other is None else code_tolerances(ref)
    out = {}
    for q, t in tol.items():
        if q not in measured:
            continue
        a, b = measured[q], (ref if other is None else other).get(q, float("nan"))
        out[q] = bool(math.isfinite(a) and math.isfinite(b) and abs(a - b) <= t)
    return out


# ----------------------------------------------------------------------------------------- runs

def _refusal(code: str, c: Case) -> str:
    """Why the code cannot express the scene (its own translation, dry-run), or ''."""
    return backends.refusal(code, c)


def run_scene(name: str, codes, out: Path, timeout: float = 300, reuse: bool = False) -> dict:
    """Runs one scene in each code (reuse: read a run's result.json when there is one); the
    reference, each code's measures (or {"failed": reason}), each code's pass per quantity
    against the reference, and each pair of codes' agreement."""
    c = case(name)
    ref = reference(c.resolved, c.discs, c.dt)
    row = {"scene": name, "reference": ref, "tolerance": tolerances(ref, c.dt), "codes": {}}
    for code in codes:
        why = _refusal(code, c)
        if why:                            # not run and not counted: LAMMPS's planes and the open slit
            row["codes"][code] = {"refused": why}
            continue
        cached = Path(out) / name / code / "result.json"
        res = Result.load(cached) if reuse and cached.exists() else study.run_code(code, c, cached.parent, timeout)
        if not res.ok:
            row["codes"][code] = {"failed": res.reason}
            continue
        try:
            row["codes"][code] = measure(c.resolved, c.discs, res.discs_end, c.duration, res.profiles)
        except ValueError as e:
            row["codes"][code] = {"failed": str(e)}
    ok = {code: m for code, m in row["codes"].items() if "failed" not in m and "refused" not in m}
    row["pass"] = {code: within(m, ref, c.dt) for code, m in ok.items()}
    row["agree"] = {f"{a} vs {b}": within(ok[a], ref, c.dt, other=ok[b])
                    for i, a in enumerate(ok) for b in list(ok)[i + 1:]}
    return row


def table(rows: list, codes) -> str:
    """Markdown: scene, quantity, reference, tolerance, each code (x: outside the tolerance), and
    for disc-wall impacts Coulomb's impulse limits; then the code pairs that differ by more than
    CODE_REL x the scale."""
    lines = ["| scene | quantity | reference | tol | " + " | ".join(codes) + " |",
             "|---|---|---|---|" + "---|" * len(codes)]
    for row in rows:
        ref = row["reference"]
        # without a reference (the open slit) the rows show the cross-code tolerance
        for q, tol in (row["tolerance"] or code_tolerances(ref)).items():
            cells = []
            for c in codes:
                m = row["codes"].get(c, {})
                if "failed" in m or "refused" in m:
                    cells.append("failed" if "failed" in m else "refused")
                elif q in m:
                    cells.append(f"{m[q]:.6g}" + ("" if row["pass"][c].get(q, True) else " **x**"))
                else:
                    cells.append("")
            want = f"{ref[q]:.6g}" if q in ref else "(native)"
            lines.append(f"| {row['scene']} | {q} | {want} | {tol:.2g} | " + " | ".join(cells) + " |")
        if "coulomb_limit" in ref:
            cl = ref["coulomb_limit"]
            lines.append(f"| {row['scene']} | rigid Coulomb impact ({'slides' if cl['slides_throughout'] else 'sticks'}): "
                         f"v_t_end {cl['v_t_end']:.6g}, omega_end_0 {cl['omega_end_0']:.6g} | | |" + " |" * len(codes))
    diff = [f"{row['scene']} {pair_}: {', '.join(q for q, ok in a.items() if not ok)}"
            for row in rows for pair_, a in row["agree"].items() if not all(a.values())]
    lines += ["", f"Code pairs differing by more than {CODE_REL:g} x the scale: " + ("; ".join(diff) or "none")]
    fails = [f"{row['scene']} ({c}): {m['failed']}" for row in rows for c, m in row["codes"].items() if "failed" in m]
    if fails:
        lines += ["", "Failed runs: " + "; ".join(fails)]
    refused = [f"{row['scene']}: {m['refused']}" for row in rows for m in row["codes"].values() if "refused" in m]
    if refused:
        lines += ["", "Refused (not run): " + "; ".join(refused)]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python3 -m dem.compare.verdict.calibration", description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--codes", default="native,liggghts,yade")
    ap.add_argument("--scenes", default="", help="comma-separated scene names (default: all)")
    ap.add_argument("--timeout", type=float, default=300)
    ap.add_argument("--reuse", action="store_true", help="measure the runs already in --out (result.json)")
    a = ap.parse_args(argv)
    codes = [c for c in a.codes.split(",") if c]
    names = [s for s in a.scenes.split(",") if s] or scene_names()
    rows = [run_scene(n, codes, a.out, a.timeout, a.reuse) for n in names]
    a.out.mkdir(parents=True, exist_ok=True)
    (a.out / "calibration.md").write_text(table(rows, codes))
    (a.out / "calibration.json").write_text(json.dumps(rows, indent=1, default=float) + "\n")
    print(table(rows, codes))
    ok = all(all(p.values()) for r in rows for p in list(r["pass"].values()) + list(r["agree"].values())) and \
        all("failed" not in m for r in rows for m in r["codes"].values())
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

"""Each code's effective constants, read back from the code itself, against the resolved scene.

For one comparison case, ``probe(code, case, out_dir, timeout)`` runs the code on a probe
configuration built from the case through the backend's own translation (LIGGGHTS:
``liggghts_backend.write_inputs``, the script it writes with its ``property/global`` matrices,
``pair_style``, ``wall/gran``, ``timestep`` and ``gravity`` lines; YADE: ``yade_backend.case_data``
and the YADE script's own ``setup``; native: ``native_backend.write_inputs`` and ``dem resolve`` of
the scene it writes), and reads back, for every material pair that can touch (every pair of the
case's disc materials, and every disc material with every wall material) k_n, k_s, eta_n, eta_s,
mu, the mass and moment of inertia of each disc material's radii, gravity and dt.
``expected_constants(resolved, discs, dt, materials)`` gives the same quantities from the
resolved scene; ``compare_constants`` lists each quantity's relative difference.

The probe configuration (``layout``) replaces the case's discs, keeping radii, materials, walls
and points: pairs of discs of each pair of disc materials far above the container with a known
overlap and relative velocity, three discs of each disc material touching a wall of each wall
material, one free disc. How each code is read:

- YADE (``yade -n -j1 -x``): the case's translated setup runs one step; the constants are the
  ones YADE stored: ``phys.kn, ks, cn, cs, tangensOfFrictionAngle`` of a disc-disc interaction and
  of a disc-facet interaction per wall material (after the series combination of the materials),
  ``state.mass`` and ``state.inertia``, ``O.dt``, the ``NewtonIntegrator``'s gravity.
- LIGGGHTS: the translated script runs ``run 1`` with per-atom dumps (``%.17g``) at steps 0 and 1,
  and the constants are solved from the forces (``normal_model_hooke_stiffness``,
  ``tangential_model_history``): at step 0 the shear history is zero and not updated, so a pair
  at rest in the normal direction gives F_n = k_n delta and F_t = -eta_t v_t, a pair closing at
  v_n gives eta_n = (k_n delta - F_n) / v_n; at step 1 (velocity Verlet: the shear displacement
  is v_t(t + dt/2) dt, positions at t + dt) the sticking pair gives k_t from
  F_t = -(k_t dt + eta_t) v_t(t + dt/2), and a sliding pair gives mu = |F_t| / F_n. The half-step
  velocities are rebuilt from the dumped step-0 forces and the stored masses; the rotational
  part of v_t uses the contact radius r - delta/2 (LIGGGHTS's surface model). Mass from the
  spin pair's one-step velocity change under the dumped forces, m = dt (F_0 + F_1) / (2 dv);
  inertia from its spin change, I = dt (T_0 + T_1) / (2 d omega); gravity from the free disc's
  velocity change over one step; dt from ``thermo`` time at step 1.
- LAMMPS: as LIGGGHTS (``probe_lammps``), with LAMMPS's slip (the full radii) and the sticking
  pairs kept below its cap on spring + dashpot; the probe case is static, so its walls are the
  backend's planes (a discharge's blocks carry the same model words).
- native: the scene the native backend writes is resolved again by ``dem resolve`` (pairs,
  density, gravity, dt); the engine is the reference, so its masses are rho pi r^2 and its
  inertias m r^2 / 2 by definition (the engine prints neither).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import re
import signal
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from dem.compare.codes import lammps_backend, liggghts_backend, native_backend, yade_backend, yade_session
from dem.compare.cases.common import Case, CaseError, disc_material, inward_normal, material_names, pair, resolve
from dem.compare.io.atomic_file import write_text as write_text_atomic
from dem.compare.verdict import translate

CODES = ("native", "liggghts", "yade", "lammps")
FIELDS = ("kn", "ks", "eta_n", "eta_s", "mu")
MAX_RADII = 16          # distinct radii probed for mass and inertia (evenly spaced, min and max kept)
OVERLAP = 2e-3          # probe overlap / radius


# ---------------------------------------------------------------------------------------------
# What the resolved scene says
def _radius_key(material: str, r: float) -> str:
    return f"{material}@r={float(r)!r}"


def _radii(discs: np.ndarray) -> list[float]:
    rs = sorted({float(r) for r in np.asarray(discs, float).reshape(-1, 6)[:, 2]})
    if len(rs) > MAX_RADII:
        idx = np.unique(np.round(np.linspace(0, len(rs) - 1, MAX_RADII)).astype(int))
        rs = [rs[i] for i in idx]
    return rs


def _main_radius(discs: np.ndarray) -> float:
    r = np.asarray(discs, float).reshape(-1, 6)[:, 2]
    vals, counts = np.unique(r, return_counts=True)
    return float(vals[np.argmax(counts)])


def wall_materials(resolved: dict) -> list[str]:
    """Materials of the active walls and the points: the disc-wall pairs that can touch."""
    return sorted({w["material"] for w in resolved["walls"] if w.get("active", True)}
                  | {p["material"] for p in resolved["points"]})


def _disc_names(resolved: dict, discs, materials) -> tuple[list[str], list[str]]:
    """Each disc's material name (``materials``: per-disc indices into resolved["materials"], None:
    the scene's one disc material) and the disc materials in the order of resolved["materials"]."""
    n = len(np.asarray(discs, float).reshape(-1, 6))
    idx = np.full(n, [m["name"] for m in resolved["materials"]].index(disc_material(resolved))) \
        if materials is None else np.asarray(materials).astype(int).reshape(-1)
    names = material_names(resolved, idx)
    return names, material_names(resolved, sorted(set(idx.tolist())))


def disc_pair_keys(disc_mats: list[str]) -> list[tuple[str, str]]:
    """Every pair of disc materials that can touch (a, b), a <= b in the given order."""
    return [(a, b) for i, a in enumerate(disc_mats) for b in disc_mats[i:]]


def expected_constants(resolved: dict, discs, dt: float, materials=None) -> dict:
    """The constants every code must have, from the resolved scene (``common.resolve``): every
    disc-disc and disc-wall material pair, the mass and inertia of each disc material's radii
    (``materials``: each disc's material index, None: the scene's one disc material)."""
    names, mats = _disc_names(resolved, discs, materials)
    rho = {m["name"]: m["density"] for m in resolved["materials"]}
    pairs = {}
    for a, b in disc_pair_keys(mats):
        pairs[f"{a}|{b}"] = {k: float(pair(resolved, a, b)[k]) for k in FIELDS}
    for dm in mats:
        for wm in wall_materials(resolved):
            pairs[f"{dm}|{wm}"] = {k: float(pair(resolved, dm, wm)[k]) for k in FIELDS}
    mass, inertia = {}, {}
    d = np.asarray(discs, float).reshape(-1, 6)
    for dm in mats:
        for r in _radii(d[[n == dm for n in names]]):
            m = rho[dm] * math.pi * r * r
            mass[_radius_key(dm, r)] = m
            inertia[_radius_key(dm, r)] = 0.5 * m * r * r
    return {"pairs": pairs, "mass": mass, "inertia": inertia,
            "gravity": [float(g) for g in resolved["gravity"]], "dt": float(dt)}


def _flatten(c: dict) -> dict:
    out = {}
    for p, vals in c.get("pairs", {}).items():
        for k, v in vals.items():
            out[f"pairs[{p}].{k}"] = v
    for what in ("mass", "inertia"):
        for k, v in c.get(what, {}).items():
            out[f"{what}[{k}]"] = v
    g = c.get("gravity")
    if g is not None:
        out["gravity[x]"], out["gravity[y]"] = g[0], g[1]
    if "dt" in c:
        out["dt"] = c["dt"]
    return out


def compare_constants(expected: dict, probed: dict, rel: float = 1e-9) -> list[dict]:
    """One row per expected quantity: {quantity, expected, probed, rel_diff, pass}. rel_diff is
    |probed - expected| / |expected|; for an expected 0 the scale is the vector's magnitude
    (gravity) or 1 (an absolute difference). A quantity the probe did not read fails. The probe's
    second readings (``probed["checks"]``, same quantity names) add rows named "<quantity> (check)"."""
    e, p = _flatten(expected), _flatten(probed.get("constants", probed))
    checks = probed.get("checks", {})
    g = expected.get("gravity") or [0.0, 0.0]
    gscale = math.hypot(*g)
    rows = []
    todo = [(q, q, ev) for q, ev in e.items()] + [(f"{q} (check)", q, e[q]) for q in checks if q in e]
    for name, q, ev in todo:
        pv = p.get(q) if name == q else checks[q]
        if pv is None or not isinstance(pv, (int, float)) or not math.isfinite(pv):
            rows.append({"quantity": name, "expected": ev, "probed": pv, "rel_diff": math.inf, "pass": False})
            continue
        scale = abs(ev) or (gscale if q.startswith("gravity") and gscale else 1.0)
        d = abs(pv - ev) / scale
        rows.append({"quantity": name, "expected": ev, "probed": pv, "rel_diff": d, "pass": bool(d <= rel)})
    return rows


# ---------------------------------------------------------------------------------------------
# The probe configuration
@dataclasses.dataclass
class Layout:
    """Probe discs (rows x, y, r, vx, vy, omega), each disc's material, and what each one is for.

    disc_pairs: "A|B" (disc materials) -> role -> (i, j) disc rows (i of A, j of B): "rest" (no
    normal velocity, sticking tangential velocity), "closing" (normal velocity), "sliding"
    (tangential velocity beyond the Coulomb cap after one step); spins: disc material -> radius ->
    (i, j), a pair of that material like "rest" (for mass and inertia; at the probe radius it is
    the A|A rest pair); walls: "A|wall material" -> {role: (row, wall name)}; free: the free disc's
    row. Tangential slip comes from spin, closing from translation."""
    discs: np.ndarray
    materials: list
    disc_pairs: dict
    spins: dict
    walls: dict
    free: int
    radius: float
    delta: float

    @property
    def pairs(self) -> dict:
        """The first disc material's pair roles and its "spin:<r>" pairs of the other radii."""
        first = next(iter(self.disc_pairs))
        out = dict(self.disc_pairs[first])
        for rad, ij in self.spins[first.split("|")[0]].items():
            if rad != self.radius:
                out[f"spin:{rad!r}"] = ij
        return out


def _seg_dist(p, a, b) -> float:
    a, b, p = np.asarray(a, float), np.asarray(b, float), np.asarray(p, float)
    t = b - a
    u = float(np.clip(np.dot(p - a, t) / np.dot(t, t), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + u * t)))


def _speeds(c: dict, delta: float, dt: float) -> tuple[float, float, float]:
    """(closing, sticking, sliding) speeds for one pair's constants: the closing dashpot force about
    the spring force; the sticking shear spring after one step 1/5 of the Coulomb cap; the sliding
    one 5 x the cap (design magnitudes only: the probe reads the constants, whatever they are)."""
    kn, ks, en, mu = float(c["kn"]), float(c["ks"]), float(c["eta_n"]), float(c["mu"])
    v_close = kn * delta / en if en > 0 else 1.0
    cap = mu * kn * delta
    v_stick = 0.2 * cap / (ks * dt) if ks > 0 and cap > 0 else 1.0
    v_slide = 5.0 * cap / (ks * dt) if ks > 0 and cap > 0 else 1.0
    return min(v_close, 0.5 * delta / dt), v_stick, v_slide


def layout(case: Case) -> Layout:
    """Probe discs for ``case``: for every pair of disc materials a rest, a closing and a sliding
    pair, a spin pair per other radius of each disc material, and the free disc, all above
    everything; for every disc material three discs on a wall of each wall material (at a quarter
    of a LIGGGHTS strip, away from other walls, points and wall ends), on the side of the case's
    discs."""
    r = case.resolved
    names = case.material_names()
    mats = case.disc_materials()
    r0 = _main_radius(case.discs)
    delta = OVERLAP * r0
    dt = float(case.dt)
    walls = [w for w in r["walls"] if w.get("active", True)]
    ys = [float(v) for w in walls for v in (w["from"][1], w["to"][1])] + [float(p["at"][1]) for p in r["points"]]
    xs = [float(v) for w in walls for v in (w["from"][0], w["to"][0])] + [float(p["at"][0]) for p in r["points"]]
    d0 = np.asarray(case.discs, float).reshape(-1, 6)
    rmax = float(d0[:, 2].max())
    ys += list(d0[:, 1])
    xs += list(d0[:, 0])
    y_row = max(ys) + 20 * rmax
    x = min(xs)
    rows, of = [], []

    def add(row, material):
        rows.append([float(v) for v in row])
        of.append(material)
        return len(rows) - 1

    def disc_pair(a, b, rad, vn, vt):
        """Closing at vn; slipping at vt by spin (both discs turning alike: the contact normal
        does not turn during the step, so no normal velocity appears)."""
        nonlocal x
        gap = 2 * rad - OVERLAP * rad
        i = add([x, y_row, rad, 0.5 * vn, 0.0, 0.5 * vt / rad], a)
        j = add([x + gap, y_row, rad, -0.5 * vn, 0.0, 0.5 * vt / rad], b)
        x += gap + 8 * rmax
        return i, j

    disc_pairs, spins = {}, {m: {} for m in mats}
    for a, b in disc_pair_keys(mats):
        vc, vs, vl = _speeds(pair(r, a, b), delta, dt)
        disc_pairs[f"{a}|{b}"] = {"rest": disc_pair(a, b, r0, 0.0, vs), "closing": disc_pair(a, b, r0, vc, 0.0),
                                  "sliding": disc_pair(a, b, r0, 0.0, vl)}
        if a == b:
            spins[a][r0] = disc_pairs[f"{a}|{b}"]["rest"]
    for m in mats:
        for rad in _radii(d0[[n == m for n in names]]):
            if rad != r0:
                spins[m][rad] = disc_pair(m, m, rad, 0.0, _speeds(pair(r, m, m), OVERLAP * rad, dt)[1])
    free = add([x, y_row, r0, 0.0, 0.0, 0.0], mats[0])

    on_walls = {}
    taken = [np.array(row[:2]) for row in rows]
    centre = case.centre
    for wm in wall_materials(r):
        cands = sorted((w for w in walls if w["material"] == wm),
                       key=lambda w: -float(np.linalg.norm(np.subtract(w["to"], w["from"]))))
        slots = [(m, role) for m in mats for role in ("rest", "closing", "sliding")]
        filled = []
        for w in cands:
            a, t, s = liggghts_backend._strips(w, case.profile_bin)
            n = inward_normal(w, centre)
            length = float(s[-1])
            for k in range(len(s) - 1):
                if len(filled) == len(slots):
                    break
                q = float(s[k] + 0.25 * (s[k + 1] - s[k]))
                c = a + q * t + n * (r0 - delta)
                if q < 2 * r0 or length - q < 2 * r0:
                    continue
                if any(_seg_dist(c, o["from"], o["to"]) < 2 * r0 for o in walls if o is not w):
                    continue
                if any(np.linalg.norm(c - np.asarray(p["at"], float)) < 2 * r0 for p in r["points"]):
                    continue
                if any(np.linalg.norm(c - o) < 4 * rmax for o in taken):
                    continue
                m, role = slots[len(filled)]
                vc, vs, vl = _speeds(pair(r, m, wm), delta, dt)
                v = -n * vc if role == "closing" else np.zeros(2)
                spin = {"rest": vs, "closing": 0.0, "sliding": vl}[role] / r0
                on_walls.setdefault(f"{m}|{wm}", {})[role] = (add([c[0], c[1], r0, v[0], v[1], spin], m), w["name"])
                filled.append((m, role))
                taken.append(c)
            if len(filled) == len(slots):
                break
        if len(filled) < len(slots):
            raise CaseError(f"probe: no room for {len(slots)} probe discs (three per disc material) on the walls "
                            f"of material {wm!r} (radius {r0!r}, away from other walls, points and wall ends)")
    return Layout(discs=np.array(rows, float), materials=of, disc_pairs=disc_pairs, spins=spins, walls=on_walls,
                  free=free, radius=r0, delta=delta)


def _probe_case(case: Case, lay: Layout) -> Case:
    index = {m["name"]: k for k, m in enumerate(case.resolved["materials"])}
    # one name for every case: the probe's inputs, and so its cache key (their bytes), depend on
    # what is translated only
    return dataclasses.replace(case, name="probe", discs=lay.discs, mode="static", settle=0.0,
                               duration=case.dt, series_interval=case.dt, snapshot_interval=0.0,
                               materials=np.array([index[m] for m in lay.materials], int))


def _result(code: str, constants: dict, method: dict, status: str = "ok", reason: str = "", **extra) -> dict:
    return dict({"code": code, "constants": constants, "method": method, "status": status, "reason": reason},
                **extra)


def _run(cmd: list[str], cwd: Path, timeout: float, log: Path) -> tuple[int | None, str]:
    with open(log, "w") as f:
        p = subprocess.Popen(cmd, cwd=cwd, stdout=f, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                             start_new_session=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
        try:
            rc = p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
            return None, f"timed out after {timeout:.0f} s"
    return rc, log.read_text(errors="replace")


def run_yade(script: str, cwd: Path, timeout: float, log: Path) -> tuple[int | None, str]:
    """``_run`` of a YADE script, in a kept YADE process (compare/codes/yade_session.py)."""
    rc = yade_session.run(script, cwd, log, timeout)
    text = log.read_text(errors="replace") if log.exists() else ""
    return rc, (text if rc is not None else f"timed out after {timeout:.0f} s")


# ---------------------------------------------------------------------------------------------
# native
def probe_native(case: Case, out_dir: Path, timeout: float = 60) -> dict:
    out_dir = Path(out_dir)
    scene = native_backend.write_inputs(case, out_dir)
    r = resolve(scene)
    # each disc's material as the engine read it back from the packing's material column
    d = np.asarray(r["discs"], float)
    discs = np.column_stack([d[:, :3], np.zeros((len(d), 3))])
    read = expected_constants(r, discs, float(r["integrator"]["dt"]), d[:, 3].astype(int))
    how = "dem resolve of the scene native_backend writes"
    return _result("native", read,
                   {"pairs": how, "gravity": how, "dt": how + " (integrator.dt)",
                    "mass": "rho pi r^2 of each disc's material as dem resolve reads it from the packing "
                            "(the engine's definition; not printed)",
                    "inertia": "m r^2 / 2 (the engine's definition; not printed)"})


# ---------------------------------------------------------------------------------------------
# YADE
YADE_PROBE_SCRIPT = "yade_probe.py"
YADE_PROBE_OUT = "yade_probe.json"
YADE_ROLES = "probe_roles.json"

_YADE_PROBE = '''# Probe of the effective constants: the translated case's own setup (yade_script.py), one step,
# then what YADE stored. Run as `yade -n -j1 -x yade_probe.py` next to yade_case.json.
import json
_src = open("yade_script.py").read()
globals()["__name__"] = "yade_case_script"
exec(compile(_src, "yade_script.py", "exec"), globals())
globals()["__name__"] = "__main__"
setup()
for _e in O.engines:
    if isinstance(_e, PyRunner):
        _e.dead = True
O.run(1, True)
_roles = json.load(open("probe_roles.json"))
_ids = S["disc_ids"]
_walls = {w["name"]: w["id"] for w in S["walls"]}


def _phys(a, b):
    if not O.interactions.has(a, b):
        return None
    i = O.interactions[a, b]
    if not i.isReal:
        return None
    p = i.phys
    return {"kn": p.kn, "ks": p.ks, "cn": p.cn, "cs": p.cs, "tan_phi": p.tangensOfFrictionAngle,
            "penetration": i.geom.penetrationDepth, "fn": i.phys.normalForce.norm()}


_out = {"dt": O.dt, "gravity": [O.engines[-1].gravity[0], O.engines[-1].gravity[1], O.engines[-1].gravity[2]],
        "integrator": type(O.engines[-1]).__name__, "iter": O.iter, "pairs": {}, "bodies": {}}
for _key, (_i, _j) in _roles["disc_pairs"].items():
    _out["pairs"][_key] = _phys(_ids[_i], _ids[_j])
for _key, (_i, _w) in _roles["wall_pairs"].items():
    _out["pairs"][_key] = _phys(_walls[_w], _ids[_i])
for _key, _i in _roles["bodies"].items():
    _s = O.bodies[_ids[_i]].state
    _out["bodies"][_key] = {"mass": _s.mass, "inertia": [_s.inertia[0], _s.inertia[1], _s.inertia[2]]}
with open("yade_probe.json", "w") as _f:
    json.dump(_out, _f, indent=1)
'''


def probe_yade(case: Case, out_dir: Path, timeout: float = 120) -> dict:
    out_dir = Path(out_dir)
    _lay, roles = write_probe_inputs("yade", case, out_dir)
    (out_dir / YADE_PROBE_OUT).unlink(missing_ok=True)
    rc, log = run_yade(YADE_PROBE_SCRIPT, out_dir, timeout, out_dir / "yade_probe.log")
    if rc != 0 or not (out_dir / YADE_PROBE_OUT).exists():
        tail = " | ".join(log.strip().splitlines()[-5:])
        return _result("yade", {}, {}, "failed", f"yade probe failed (exit {rc}): {tail}")
    got = json.loads((out_dir / YADE_PROBE_OUT).read_text())
    pairs, missing = {}, []
    for key, p in got["pairs"].items():
        if p is None:
            missing.append(key)
            continue
        pairs[key] = {"kn": p["kn"], "ks": p["ks"], "eta_n": p["cn"], "eta_s": p["cs"], "mu": p["tan_phi"]}
    mass = {k: b["mass"] for k, b in got["bodies"].items()}
    inertia = {k: b["inertia"][2] for k, b in got["bodies"].items()}
    consts = {"pairs": pairs, "mass": mass, "inertia": inertia, "gravity": got["gravity"][:2], "dt": got["dt"]}
    how = "ViscElPhys of a real {} interaction after one step (kn, ks, cn, cs, tangensOfFrictionAngle)"
    method = {"pairs": {k: how.format("disc-disc" if k in roles["disc_pairs"] else "disc-facet")
                        for k in roles["disc_pairs"] | roles["wall_pairs"]},
              "mass": "body.state.mass", "inertia": "body.state.inertia[2] (z: the disc's spin axis)",
              "gravity": f"{got['integrator']}.gravity", "dt": "O.dt"}
    if missing:
        return _result("yade", consts, method, "failed", f"no interaction formed for {missing}")
    # The stored kn is the one the law used: |F_n| / overlap of the same contact (no normal velocity).
    checks = {f"pairs[{k}].kn": p["fn"] / p["penetration"] for k, p in got["pairs"].items()}
    method["checks"] = "kn again as |F_n| / overlap of the same contact (no normal velocity: spin only)"
    return _result("yade", consts, method, checks=checks)


# ---------------------------------------------------------------------------------------------
# LIGGGHTS
LIGGGHTS_DUMP = "probe_*.dump"
_DUMP_COLS = ("id", "mass", "radius", "x", "y", "vx", "vy", "omegaz", "fx", "fy", "tqz")


def liggghts_script(base: str) -> str:
    """The backend's script for the probe case with its dumps and run replaced by per-atom dumps
    at full precision, thermo every step and ``run 1``; every other line is the backend's."""
    keep = [l for l in base.splitlines() if not re.match(r"\s*(dump|dump_modify|run|thermo)\s", l)]
    keep += ["thermo_style custom step time atoms",
             "thermo_modify format float %.17g lost error norm no",
             "thermo 1",
             f"dump probe all custom 1 {LIGGGHTS_DUMP} {' '.join(_DUMP_COLS)}",
             'dump_modify probe format "%d' + " %.17g" * (len(_DUMP_COLS) - 1) + '" sort id',
             "run 1"]
    return "\n".join(keep) + "\n"


def _read_probe_dump(path: Path) -> dict:
    lines = path.read_text().splitlines()
    k = next(i for i, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
    cols = lines[k].split()[2:]
    out = {}
    for l in lines[k + 1:]:
        if l.strip():
            v = dict(zip(cols, (float(x) for x in l.split())))
            out[int(v["id"]) - 1] = v
    return out


def _zcross(e: np.ndarray) -> np.ndarray:
    """z x e for an in-plane vector e."""
    return np.array([-e[1], e[0]])


def _kinematics(xi, vi, wi, ri, other) -> dict:
    """Contact normal (towards disc i), overlap, normal and tangential relative velocity at the
    contact (rotation with the contact radius r - delta/2) of disc i against ``other``: a disc
    (x, v, omega, r) or a wall ("wall", a point of it, unit normal towards the disc side)."""
    xi, vi = np.asarray(xi, float), np.asarray(vi, float)
    if isinstance(other[0], str):
        a, n = np.asarray(other[1], float), np.asarray(other[2], float)
        dist = float(np.dot(xi - a, n))
        en, delta, vr = n, ri - dist, vi
        spin = (ri - 0.5 * delta) * wi
    else:
        xj, vj, wj, rj = other
        d = xi - np.asarray(xj, float)
        dist = float(np.hypot(d[0], d[1]))
        en, delta, vr = d / dist, ri + rj - dist, vi - np.asarray(vj, float)
        spin = (ri - 0.5 * delta) * wi + (rj - 0.5 * delta) * wj
    vn = float(np.dot(vr, en))
    vtr = vr - vn * en - spin * _zcross(en)
    return {"en": en, "delta": delta, "vn": vn, "vtr": vtr}


def _solve_one_step(case: Case, lay: Layout, s0: dict, s1: dict, dt: float, kinematics) -> tuple[dict, dict]:
    """The constants from the step-0 and step-1 dumps of a probe (``probe_liggghts``'s equations);
    ``kinematics``: the code's relative velocity at the contact (its rotational arm)."""
    dtf = 0.5 * dt
    r = case.resolved

    def vec(s, k, a, b):
        return np.array([s[k][a], s[k][b]])

    fr = lay.free
    gforce = vec(s0, fr, "fx", "fy") / s0[fr]["mass"]       # gravity force per mass, as applied
    gravity = (vec(s1, fr, "vx", "vy") - vec(s0, fr, "vx", "vy")) / dt

    def contact_force(s, k):
        return vec(s, k, "fx", "fy") - s[k]["mass"] * gforce

    def state(s, k):
        return vec(s, k, "x", "y"), vec(s, k, "vx", "vy"), s[k]["omegaz"], s[k]["radius"]

    partners = {}
    for roles in lay.disc_pairs.values():
        for a, b in roles.values():
            partners[a], partners[b] = b, a
    for by in lay.spins.values():
        for a, b in by.values():
            partners[a], partners[b] = b, a

    # mass and inertia of each disc material's radii: the spin pair's first disc (normal force
    # along the pair)
    mass, inertia, inertia_of = {}, {}, {}
    for m, by in lay.spins.items():
        for rad, (i, _j) in by.items():
            e = vec(s0, partners[i], "x", "y") - vec(s0, i, "x", "y")
            e /= np.linalg.norm(e)
            df = float(np.dot(vec(s0, i, "fx", "fy") + vec(s1, i, "fx", "fy"), e))
            dv = float(np.dot(vec(s1, i, "vx", "vy") - vec(s0, i, "vx", "vy"), e))
            key = _radius_key(m, rad)
            mass[key] = dtf * df / dv
            inertia[key] = dtf * (s0[i]["tqz"] + s1[i]["tqz"]) / (s1[i]["omegaz"] - s0[i]["omegaz"])
            if rad == lay.radius:
                inertia_of[m] = inertia[key]

    def half_step(k):
        """x(t + dt) as dumped; v and omega at t + dt/2 from the step-0 forces (velocity Verlet)."""
        x1, _v, _w, rad = state(s1, k)
        m = s0[k]["mass"]
        v = vec(s0, k, "vx", "vy") + (dtf / m) * vec(s0, k, "fx", "fy")
        # every contact probe disc has radius lay.radius: its material's inertia at that radius
        w = s0[k]["omegaz"] + dtf * s0[k]["tqz"] / inertia_of[lay.materials[k]]
        return x1, v, w, rad

    def solve(role_rows, other_of):
        """role_rows: role -> disc row; other_of(row, step) -> the other body for _kinematics."""
        k0 = {role: kinematics(*state(s0, i)[:4], other_of(i, 0)) for role, i in role_rows.items()}
        fn = {role: float(np.dot(contact_force(s0, i), k0[role]["en"])) for role, i in role_rows.items()}
        # F_n = k_n delta - eta_n v_n (rest and closing discs)
        A = np.array([[k0[q]["delta"], -k0[q]["vn"]] for q in ("rest", "closing")])
        kn, eta_n = np.linalg.solve(A, np.array([fn["rest"], fn["closing"]]))
        i = role_rows["rest"]
        ft0 = contact_force(s0, i) - fn["rest"] * k0["rest"]["en"]
        vt0 = k0["rest"]["vtr"]
        eta_t = -float(np.dot(ft0, vt0)) / float(np.dot(vt0, vt0))
        x1, vh, wh, rad = half_step(i)
        k1 = kinematics(x1, vh, wh, rad, other_of(i, 1))
        shear = k1["vtr"] * dt
        shear = shear - float(np.dot(shear, k1["en"])) * k1["en"]
        fc1 = contact_force(s1, i)
        ft1 = fc1 - float(np.dot(fc1, k1["en"])) * k1["en"]
        kt = -float(np.dot(ft1 + eta_t * k1["vtr"], shear)) / float(np.dot(shear, shear))
        j = role_rows["sliding"]
        x1, _v, _w, rad = state(s1, j)
        ks_ = kinematics(x1, np.zeros(2), 0.0, rad, other_of(j, 1))
        fc = contact_force(s1, j)
        fnl = float(np.dot(fc, ks_["en"]))
        if not fnl > 0:
            raise ValueError(f"the sliding probe pair has normal force {fnl!r} after one step (no contact)")
        mu = float(np.linalg.norm(fc - fnl * ks_["en"])) / fnl
        if mu < 1e-12:    # mu = 0 (to the rounding of f - m g) caps every shear force at 0: k_t never acts
            kt = None
        return {"kn": float(kn), "ks": kt, "eta_n": float(eta_n), "eta_s": eta_t, "mu": mu}

    pairs = {}
    for key, roles in lay.disc_pairs.items():
        pairs[key] = solve({q: roles[q][0] for q in ("rest", "closing", "sliding")},
                           lambda i, st: half_step(partners[i]) if st else state(s0, partners[i]))
    walls = {w["name"]: w for w in r["walls"]}
    for key, roles in lay.walls.items():
        def wall_of(i, _st, roles=roles):
            name = next(n for q, (row, n) in roles.items() if row == i)
            return ("wall", walls[name]["from"], inward_normal(walls[name], case.centre))
        pairs[key] = solve({q: row for q, (row, _n) in roles.items()}, wall_of)
    consts = {"pairs": pairs, "mass": mass, "inertia": inertia, "gravity": [float(g) for g in gravity], "dt": dt}
    checks = {f"mass[{_radius_key(m, rad)}]": s0[i]["mass"] for m, by in lay.spins.items()
              for rad, (i, _j) in by.items()}
    return consts, checks


def probe_liggghts(case: Case, out_dir: Path, timeout: float = 120) -> dict:
    out_dir = Path(out_dir)
    lay, probe_in = write_probe_inputs("liggghts", case, out_dir)
    for old in out_dir.glob(LIGGGHTS_DUMP):
        old.unlink()
    rc, log = _run(liggghts_backend.command(probe_in), out_dir, timeout, out_dir / "liggghts_probe.log")
    if rc != 0 or "ERROR" in log:
        err = next((l for l in log.splitlines() if "ERROR" in l), f"exit code {rc}")
        return _result("liggghts", {}, {}, "failed", f"liggghts probe failed: {err.strip()}")
    dumps = {int(re.findall(r"(\d+)", p.name)[-1]): p for p in out_dir.glob(LIGGGHTS_DUMP)}
    if set(dumps) != {0, 1}:
        return _result("liggghts", {}, {}, "failed", f"probe dumps at steps {sorted(dumps)}, expected 0 and 1")
    s0, s1 = _read_probe_dump(dumps[0]), _read_probe_dump(dumps[1])
    times = [float(m.group(1)) for m in re.finditer(r"^\s*1\s+(\S+)\s+\d+\s*$", log, re.M)]
    if not times:
        return _result("liggghts", {}, {}, "failed", "no thermo line at step 1 in the probe log")
    consts, checks = _solve_one_step(case, lay, s0, s1, times[-1], _kinematics)
    method = {
        "kn, eta_n": "step 0 (no shear history): F_n = k_n delta - eta_n v_n of a pair at rest and a closing pair",
        "eta_s": "step 0: F_t = -eta_t v_t (zero shear history) of the pair at rest",
        "ks": "step 1: F_t = -(k_t dt + eta_t) v_t(t + dt/2), sticking pair, half-step velocities rebuilt "
              "from the step-0 forces",
        "mu": "step 1: |F_t| / F_n of a pair sliding beyond the Coulomb cap (mu = 0: k_t is not read, "
              "the cap holds every shear force at 0)",
        "mass": "m = dt (F_0 + F_1) / (2 dv) along the pair normal of a spin pair disc",
        "inertia": "I = dt (T_0 + T_1) / (2 d omega) of a spin pair disc",
        "gravity": "(v_1 - v_0) / dt of the free disc",
        "dt": "thermo time at step 1 (%.17g)",
        "contact forces": "per-atom f minus m g (g as applied to the free disc), dumped with %.17g",
        "checks": "mass again as the stored per-atom mass (dump custom mass)",
    }
    return _result("liggghts", consts, method, checks=checks)


# ---------------------------------------------------------------------------------------------
# LAMMPS
LAMMPS_DUMP = "probe_*.dump"


def lammps_script(base: str) -> str:
    """The backend's script for the probe case with its dumps, thermo and run replaced by per-atom
    dumps at full precision, thermo every step and ``run 1``; every other line is the backend's."""
    keep = [l for l in base.splitlines() if not re.match(r"\s*(dump|dump_modify|run|thermo|thermo_style|thermo_modify)\s", l)]
    keep += ["thermo_style custom step time atoms",
             "thermo_modify format float %.17g lost error norm no",
             "thermo 1",
             f"dump probe all custom 1 {LAMMPS_DUMP} {' '.join(_DUMP_COLS)}",
             "dump_modify probe format float %.17g sort id",
             "run 1"]
    return "\n".join(keep) + "\n"


def _lammps_layout(case: Case) -> Layout:
    """``layout`` with the sticking speeds lowered so that spring + dashpot stay at 1/5 of the
    Coulomb cap after one step: LAMMPS caps the total tangential force (and gives none at a first
    step beyond the cap), where LIGGGHTS caps the spring alone."""
    lay = layout(case)
    r = case.resolved
    dt = float(case.dt)

    def lower(row: int, c: dict) -> None:
        ks, es = float(c["ks"]), float(c["eta_s"])
        if ks > 0:
            lay.discs[row, 5] *= ks * dt / (ks * dt + es)

    for key, roles in lay.disc_pairs.items():
        a, b = key.split("|")
        for row in roles["rest"]:
            lower(row, pair(r, a, b))
    for m, by in lay.spins.items():
        for rad, ij in by.items():
            if ij not in [roles["rest"] for roles in lay.disc_pairs.values()]:
                for row in ij:
                    lower(row, pair(r, m, m))
    for key, roles in lay.walls.items():
        dm, wm = key.split("|")
        lower(roles["rest"][0], pair(r, dm, wm))
    return lay


def _kinematics_full_arm(xi, vi, wi, ri, other) -> dict:
    """As ``_kinematics``, with LAMMPS's rotational slip: r omega with the full radii."""
    xi, vi = np.asarray(xi, float), np.asarray(vi, float)
    if isinstance(other[0], str):
        a, n = np.asarray(other[1], float), np.asarray(other[2], float)
        en, delta, vr = n, ri - float(np.dot(xi - a, n)), vi
        spin = ri * wi
    else:
        xj, vj, wj, rj = other
        d = xi - np.asarray(xj, float)
        dist = float(np.hypot(d[0], d[1]))
        en, delta, vr = d / dist, ri + rj - dist, vi - np.asarray(vj, float)
        spin = ri * wi + rj * wj
    vn = float(np.dot(vr, en))
    return {"en": en, "delta": delta, "vn": vn, "vtr": vr - vn * en - spin * _zcross(en)}


def probe_lammps(case: Case, out_dir: Path, timeout: float = 120) -> dict:
    """As ``probe_liggghts`` (the same equations of one step) with LAMMPS's law: the rotational slip
    with the full radii, the sticking pairs below the total cap (``_lammps_layout``); each wall
    plane acts on its own probe discs only (the discs of the other probes lie beyond the walls'
    ends, where LAMMPS's infinite plane would still act)."""
    out_dir = Path(out_dir)
    lay, probe_in = write_probe_inputs("lammps", case, out_dir)
    for old in out_dir.glob(LAMMPS_DUMP):
        old.unlink()
    rc, log = _run(lammps_backend.command(probe_in), out_dir, timeout, out_dir / "lammps_probe.log")
    if rc != 0 or "ERROR" in log:
        err = next((l for l in log.splitlines() if "ERROR" in l), f"exit code {rc}")
        return _result("lammps", {}, {}, "failed", f"lammps probe failed: {err.strip()}")
    dumps = {int(re.findall(r"(\d+)", p.name)[-1]): p for p in out_dir.glob(LAMMPS_DUMP)}
    if set(dumps) != {0, 1}:
        return _result("lammps", {}, {}, "failed", f"probe dumps at steps {sorted(dumps)}, expected 0 and 1")
    s0, s1 = _read_probe_dump(dumps[0]), _read_probe_dump(dumps[1])
    times = [float(m.group(1)) for m in re.finditer(r"^\s*1\s+(\S+)\s+\d+\s*$", log, re.M)]
    if not times:
        return _result("lammps", {}, {}, "failed", "no thermo line at step 1 in the probe log")
    consts, checks = _solve_one_step(case, lay, s0, s1, times[-1], _kinematics_full_arm)
    method = {
        "kn, eta_n": "step 0 (no shear history): F_n = k_n delta - eta_n v_n of a pair at rest and a closing pair",
        "eta_s": "step 0: F_t = -eta_t v_t (zero shear history, below the cap) of the pair at rest",
        "ks": "step 1: F_t = -(k_t dt + eta_t) v_t(t + dt/2), sticking pair (spring + dashpot at 1/5 of the "
              "cap), half-step velocities rebuilt from the step-0 forces; v_t with the full radii (LAMMPS's slip)",
        "mu": "step 1: |F_t| / F_n of a pair sliding beyond the Coulomb cap",
        "mass": "m = dt (F_0 + F_1) / (2 dv) along the pair normal of a spin pair disc",
        "inertia": "I = dt (T_0 + T_1) / (2 d omega) of a spin pair disc (fix nve/sphere disc)",
        "gravity": "(v_1 - v_0) / dt of the free disc",
        "dt": "thermo time at step 1 (%.17g)",
        "contact forces": "per-atom f minus m g (g as applied to the free disc), dumped with %.17g",
        "checks": "mass again as the stored per-atom mass (dump custom mass)",
    }
    return _result("lammps", consts, method, checks=checks)


# ---------------------------------------------------------------------------------------------
def write_probe_inputs(code: str, case: Case, out_dir: Path) -> tuple:
    """Writes every file the probe of ``code`` runs into out_dir, through the backend's own
    translation (the cache key of a probe is their bytes); returns (layout, the probe's script)
    for LIGGGHTS and LAMMPS, (layout, roles) for YADE."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if code == "yade":
        lay = layout(case)
        yade_backend._write(yade_backend.case_data(_probe_case(case, lay)), out_dir, 1)
        roles = {"disc_pairs": {key: ij["rest"] for key, ij in lay.disc_pairs.items()},
                 "wall_pairs": {key: roles["rest"] for key, roles in lay.walls.items()},
                 "bodies": {_radius_key(m, rad): ij[0] for m, by in lay.spins.items() for rad, ij in by.items()}}
        write_text_atomic(out_dir / YADE_ROLES, json.dumps(roles) + "\n")
        write_text_atomic(out_dir / YADE_PROBE_SCRIPT, _YADE_PROBE)
        return lay, roles
    if code == "liggghts":
        lay = layout(case)
        script = liggghts_backend.write_inputs(_probe_case(case, lay), out_dir)
        write_text_atomic(out_dir / "in.probe", liggghts_script(script.read_text()))
        return lay, out_dir / "in.probe"
    if code == "lammps":
        lay = _lammps_layout(case)
        rows_of = {}
        for roles in lay.walls.values():
            for row, wname in roles.values():
                rows_of.setdefault(wname, []).append(row)
        script = lammps_backend.write_inputs(_probe_case(case, lay), out_dir, wall_rows=rows_of, centre=case.centre)
        write_text_atomic(out_dir / "in.probe", lammps_script(script.read_text()))
        return lay, out_dir / "in.probe"
    if code == "native":
        return None, native_backend.write_inputs(case, out_dir)
    raise ValueError(f"code: {code!r} is not one of {CODES}")


def probe(code: str, case: Case, out_dir: Path, timeout: float = 120) -> dict:
    """The effective constants of ``code`` for ``case`` (see the module doc); never raises for a
    failed probe: status "failed" and the reason."""
    out_dir = Path(out_dir)
    t0 = time.perf_counter()
    try:
        if code == "native":
            res = probe_native(case, out_dir, timeout)
        elif code == "yade":
            res = probe_yade(case, out_dir, timeout)
        elif code == "liggghts":
            res = probe_liggghts(case, out_dir, timeout)
        elif code == "lammps":
            res = probe_lammps(case, out_dir, timeout)
        else:
            raise ValueError(f"code: {code!r} is not one of {CODES}")
    except (CaseError, OSError, ValueError, KeyError, ArithmeticError, np.linalg.LinAlgError) as e:
        res = _result(code, {}, {}, "failed", f"{type(e).__name__}: {e}")
    res["wall_time_s"] = time.perf_counter() - t0
    return res


def check_case(case: Case, out_root: Path, codes=CODES, timeout: float = 120, rel: float = 1e-9) -> dict:
    """Probes ``case`` in each code against ``expected_constants``: {code: {status, reason,
    wall_time_s, rows (compare_constants), max_rel_diff, pass}}; a failed probe does not pass."""
    expected = expected_constants(case.resolved, case.discs, case.dt, case.material_index())
    out = {}
    for code in codes:
        res = probe(code, case, Path(out_root) / code, timeout)
        rows = compare_constants(expected, res, rel)
        out[code] = {"status": res["status"], "reason": res["reason"], "wall_time_s": res["wall_time_s"],
                     "method": res["method"], "rows": rows,
                     "max_rel_diff": max((r["rel_diff"] for r in rows), default=math.inf),
                     "pass": res["status"] == "ok" and all(r["pass"] for r in rows)}
    return out


def main(argv=None) -> int:
    """python3 -m dem.compare.verdict.probe [--out DIR] [--codes ...]: probes the paper's translated cases
    (dem.compare.verdict.translate.cases) and prints each code's largest relative difference and wall time."""

    ap = argparse.ArgumentParser(prog="python3 -m dem.compare.verdict.probe")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--codes", default=",".join(CODES))
    a = ap.parse_args(argv)
    root = a.out or Path(tempfile.mkdtemp(prefix="probe_"))
    codes = [c for c in a.codes.split(",") if c]
    ok = True
    for case in translate.cases():
        for code, r in check_case(case, root / case.name, codes).items():
            worst = max(r["rows"], key=lambda x: x["rel_diff"]) if r["rows"] else {"quantity": "-"}
            print(f"{case.name:18s} {code:9s} {'PASS' if r['pass'] else 'FAIL'} max rel {r['max_rel_diff']:.2e} "
                  f"({worst['quantity']}) {r['wall_time_s']:.2f} s {r['reason']}", flush=True)
            ok &= r["pass"]
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())

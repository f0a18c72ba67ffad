"""YADE 2023.02a as a compared code: translator (yade_case.json + the script
compare/codes/yade_template.py), runner (``yade -n -jN -x yade_script.py``) and reader.

What the translation does (measured facts: docs/compare.md):
- true 2D: spheres at z = 0 with ``blockedDOFs = 'zXY'``, mass rho pi r^2 (per 1 cm of thickness)
  and inertia m r^2 / 2 set by hand after creation;
- law: ``ViscElMat`` + ``Ip2_ViscElMat_ViscElMat_ViscElPhys`` + ``Law2_ScGeom_ViscElPhys_Basic``:
  F_n = kn overlap + cn v_n, the TOTAL normal force clamped >= 0, elastic shear history
  (ks dt v_s increments, rotated with the contact), Coulomb cap mu |F_n| on the total normal force,
  shear dashpot cs v_s only while sticking, velocities and torques at the contact point (the
  middle of the overlap, r - overlap/2 from the centre, on spheres and facets alike): the
  engine's SHARED_VARIANT;
- constants: materials combine IN SERIES, k = k1 k2 / (k1 + k2), a 0 meaning "absent" (the
  contact then takes the other material's value). Disc material A = 2 x the A-A pair, so
  A-A contacts get the pair exactly; an A-B pair of two disc materials must be
  series(2 x A-A, 2 x B-B) for kn, ks, eta_n, eta_s (otherwise CaseError naming the field and the
  series value). Each wall material is solved against the first disc material so that
  series(disc, wall) is the resolved disc-wall pair: w = k_dw k_d / (k_d - k_dw), or 0 when
  k_dw = k_d (the paper's case: disc-wall = 2 x disc-disc); k_dw > k_d cannot be expressed, and
  every other disc material's pair with that wall must equal its series with the same wall
  values (CaseError naming the field otherwise). Friction per material pair with a MatchMaker
  (tan(atan(mu))); each disc's mass from its own material's density;
- walls: one facet per wall segment (edge = the segment at z = 0, apex out of the plane): the
  interior gives plane contacts, the ends vertex contacts (the slit ends L and R). A guard
  switches vertex contacts off where the engine has none: at ends that are not scene points, and
  at points owned by an adjacent wall (the engine's rule: a point acts only where no adjacent
  wall's projection holds the disc centre; e.g. the closed gate owns L and R);
- time integration: NewtonIntegrator(damping=0) (leapfrog, velocities at half steps), fixed dt;
- records: wall contact forces BY THE DISC ON THE WALL (normal + elastic shear + the viscous
  shear the law added, rebuilt from the same velocities before the integrator) at every
  ``series_interval`` and at the end; the contact point reported is the disc centre's projection
  on the segment clamped to its ends (the engine's contact point: a vertex contact counts in the
  end bin of its wall). The per-wall sum is checked against YADE's own wall force;
- moving walls (a scene's walls[].velocity): the wall's facet gets the prescribed velocity during
  the steps of its window (whole steps of dt: common.motion_steps) and NewtonIntegrator moves
  it; the contacts see its velocity and keep their history;
- discharge: settle, erase the gate body, run on; discs whose centre is below outlet_depth under
  the gate (common.outlet_y, the engine's rule) are
  erased at the start of the step in which they are found (per-step check while any disc is
  near the outlet plane) and their times logged.
- failures (``run`` never raises; the Result says why): translation refused (CaseError from
  write_inputs), yade exit != 0 (python error, SIGABRT from an inconsistent material set),
  timeout (the process group is killed), missing or unreadable outputs, non-finite state, a disc
  outside the container (only when gravity holds discs in a box of walls with an area: the box of
  the walls and the initial discs, enlarged by 2 r_max; below it is allowed after the opening),
  kinetic + potential energy above 1.5 x the initial budget (kinetic + potential + elastic), lost
  discs. The in-script checks run every SCAN_TIME (or series interval, if shorter).
- particle snapshots (Case.snapshot_interval): YADE's own VTKRecorder (spheres, velocity, id)
  writes snapshots/discs_spheres.ITER.vtu, read with meshio by ``read_snapshots``;
- files in out_dir: yade_case.json (the translated case), yade_script.py (copy of
  yade_template.py), yade.log, yade_process.json (exit code, wall time), yade_result.json and
  yade_series.csv (written by the script, full precision).

- shear (``case.mode == "shear"``: paper 2's shear box, compare/cases/shear.py): ``shear_case_data``
  gives the same materials, friction and masses (``materials``) to the script
  compare/codes/shear_yade_template.py (copied as yade_script.py): the floor and side walls are fixed
  boxes, the side walls turned about their lower inner corners by RotationEngines, the plate a
  dynamic box of the plate's mass free in x and y (no rotation), placed plate_gap above the case's
  highest disc; compression to the engine's rest criterion (mean |du| and |dv| per step below
  rest_factor g dt^2) for at most ``case.settle``, then the shear to shear.max_strain. Clusters
  (``case.clusters``): "bonds", every bonded pair of the engine's bond list an interaction made at
  the start with a CohFrictPhys of that pair's kn and ks and adhesion 1e30 (elastic, in tension,
  no Coulomb cap, never broken; no dashpots: YADE's cohesive law has none; normal spring on the
  distance change since bonding; shear force rotated with the contact frame; lever arms to the
  mid-gap point with avoidGranularRatcheting = False); "clumps", rigid YADE clumps. It writes the
  engine's shear outputs (shear_series.csv, shear_planes.csv, summary.json, snapshots/), read by
  dem.compare.cases.shear.read_outputs into ``Result.extra["shear"]``.

What YADE cannot express exactly (see also the module's ``LIMITATIONS``): the paper's incremental
normal spring and elastic-force rules (only the shared variant); the engine's integration
schemes (eq. 18/19, Verlet): YADE is leapfrog with velocities half a step behind the positions;
the lever arm of the tangential force is |contact point - centre| = r - overlap/2 (the engine
uses r); a contact passing from one wall to a neighbouring wall's end point is another YADE
interaction and does not inherit the shear history (the engine passes it on).
"""
from __future__ import annotations

import csv
import functools
import json
import math
import os
import re
import shutil
import signal
import subprocess
import time
from pathlib import Path

import meshio  # VTKRecorder snapshots (VTU)
import numpy as np

from dem.compare.cases.common import outlet_y as common_outlet_y
from dem.compare.cases.common import (SHARED_VARIANT, Case, CaseError, Result, Snapshot, disc_material, failed, motion_steps,
                     moved_wall, pair, profiles_from_contacts)
from dem.compare.io.atomic_file import write_text as write_text_atomic
from dem.compare.cases import shear
from dem.compare.codes import yade_session

NAME = "yade"
TEMPLATE = Path(__file__).resolve().parent / "yade_template.py"
SHEAR_TEMPLATE = Path(__file__).resolve().parent / "shear_yade_template.py"
SHEAR_FILES = ("summary.json", "shear_series.csv", "shear_planes.csv")
SCRIPT = "yade_script.py"
CASE_FILE = "yade_case.json"
RESULT_FILE = "yade_result.json"
SERIES_FILE = "yade_series.csv"
PROCESS_FILE = "yade_process.json"
LOG_FILE = "yade.log"
SNAPSHOT_DIR = "snapshots"   # VTKRecorder output: discs_spheres.ITER.vtu
SCAN_TIME = 0.005          # [s] longest interval between the in-script checks
EQUAL_REL = 1e-12          # disc-wall constant equal to the disc material's: wall value 0

LIMITATIONS = [
    "contact law: only the shared variant (e_n = kn overlap, total-force no-tension clamp, "
    "Coulomb cap on the total normal force); the paper's incremental spring and elastic-force "
    "rules are not expressible",
    "integration: leapfrog (velocities half a step behind positions), not the engine's "
    "eq. 18/19 or Verlet schemes; initial velocities are taken as v(-dt/2)",
    "tangential lever arm and contact point: r - overlap/2 from the centre (engine: r)",
    "shear history: a contact moving from one wall to a neighbouring wall's end point starts a "
    "new history (the engine passes it on between neighbours); within one wall it is kept",
    "constants: disc materials combine in series (an A-B pair other than series(2 x A-A, 2 x B-B) "
    "cannot be expressed), one wall material serves every disc material; a disc-wall constant larger "
    "than 2 x the disc-disc one (k_dw > k_d) or a zero disc-wall damping with non-zero disc-disc "
    "damping cannot be expressed",
    "points: only at wall ends (facet vertices), with the material of the walls ending there",
    "friction coefficient passes through tan(atan(mu)) (1 ulp)",
    "shear box: cluster bonds (CohFrictPhys) have no dashpots (the engine's bonds keep the pair's "
    "dashpots); the walls and plate are boxes; the plate moves only by the forces on it",
]


def available() -> bool:
    return shutil.which("yade") is not None


@functools.lru_cache(maxsize=1)
def version() -> str:
    try:
        p = subprocess.run(["yade", "--version"], capture_output=True, text=True, timeout=60)
        for line in (p.stdout + p.stderr).splitlines():
            if "version" in line.lower():
                return "yade " + line.split(":", 1)[-1].strip()
        return "yade (version not printed)"
    except (OSError, subprocess.TimeoutExpired):
        return "yade (not runnable)"


# ---------------------------------------------------------------------------------------------
# Translation
def _check_variant(case: Case) -> None:
    c = case.resolved.get("contact")
    if c != SHARED_VARIANT:
        raise CaseError(f"contact: YADE's ViscEl law expresses only {SHARED_VARIANT}, the case asks for {c}")


def _series_partner(field: str, k_d: float, k_dw: float) -> float:
    """Wall material value w with series(k_d, w) = k_dw (YADE: 0 = absent -> the other value)."""
    if not (math.isfinite(k_d) and math.isfinite(k_dw)) or k_d < 0 or k_dw < 0:
        raise CaseError(f"{field}: non-finite or negative constant (disc material {k_d!r}, disc-wall {k_dw!r})")
    if k_d == 0.0:
        return k_dw                       # series(absent, w) = w
    if k_dw == 0.0:
        raise CaseError(f"{field}: the disc-wall value is 0 but the disc-disc value is not; YADE's series "
                        "combination cannot give 0 against a non-zero disc material")
    if abs(k_dw - k_d) <= EQUAL_REL * k_d:
        return 0.0                        # series(k_d, absent) = k_d
    if k_dw > k_d:
        raise CaseError(f"{field}: disc-wall value {k_dw!r} exceeds the disc material's {k_d!r} "
                        "(= 2 x disc-disc); YADE's series combination cannot reach it")
    return k_dw * k_d / (k_d - k_dw)


def series(a: float, b: float) -> float:
    """YADE's contactParameterCalculation: 1 / (1/a + 1/b), a 0 counting as absent."""
    s = (1.0 / a if a else 0.0) + (1.0 / b if b else 0.0)
    return 1.0 / s if s else 0.0


_FIELDS = (("kn", "kn"), ("cn", "eta_n"), ("ks", "ks"), ("cs", "eta_s"))   # YADE name, scene name


def _same(a: float, b: float) -> bool:
    return abs(a - b) <= EQUAL_REL * max(abs(a), abs(b))


def materials(resolved: dict, disc_names: list[str] | None = None) -> tuple[dict, dict, list]:
    """Disc materials, wall materials (by name) and friction per material pair of the translation
    (``disc_names``: the case's disc materials, None: the scene's one); raises CaseError.

    Disc material A = 2 x the A-A pair. YADE combines two disc materials in series, so an A-B pair
    is expressed only when it is series(2 x A-A, 2 x B-B) for kn, ks, eta_n and eta_s (relative
    EQUAL_REL). Each wall material is solved against the first disc material; every other disc
    material B must then get its B-wall pair from the same wall values. Friction: one MatchMaker
    entry per pair, [a, b, mu]."""
    if disc_names is None:
        disc_names = [disc_material(resolved)]
    rho = {m["name"]: float(m["density"]) for m in resolved["materials"]}
    discs, friction = {}, []
    for a in disc_names:
        aa = pair(resolved, a, a)
        discs[a] = dict({k: 2.0 * float(aa[f]) for k, f in _FIELDS}, density=rho[a])
    for i, a in enumerate(disc_names):
        for b in disc_names[i:]:
            ab = pair(resolved, a, b)
            friction.append([a, b, float(ab["mu"])])
            if a == b:
                continue
            for k, f in _FIELDS:
                want, got = series(discs[a][k], discs[b][k]), float(ab[f])
                if not _same(got, want):
                    raise CaseError(f"pairs[{a},{b}].{f}: YADE combines the disc materials {a!r} and {b!r} in "
                                    f"series, which gives series(2 x pairs[{a},{a}], 2 x pairs[{b},{b}]) = {want!r}; "
                                    f"the scene has {got!r}")
    walls = {}
    names = {w["material"] for w in resolved["walls"]} | {p["material"] for p in resolved["points"]}
    first = disc_names[0]
    for wm in sorted(names):
        dw = pair(resolved, first, wm)
        label = f"pairs[{first},{wm}]"
        walls[wm] = {k: _series_partner(f"{label}.{f}", discs[first][k], float(dw[f])) for k, f in _FIELDS}
        for b in disc_names:
            bw = pair(resolved, b, wm)
            friction.append([b, wm, float(bw["mu"])])
            for k, f in _FIELDS:
                want, got = series(discs[b][k], walls[wm][k]), float(bw[f])
                if not _same(got, want):
                    raise CaseError(f"pairs[{b},{wm}].{f}: YADE has one {wm!r} wall material for every disc "
                                    f"material; solved from {label}.{f} it gives the {b}-{wm} pair "
                                    f"{want!r}, the scene has {got!r}")
    for a, b, mu in friction:
        if not (math.isfinite(mu) and mu >= 0):
            raise CaseError(f"pairs[{a},{b}].mu: must be finite and >= 0")
    return discs, walls, friction


def _points(resolved: dict, walls: list[dict]) -> list[list[float]]:
    """Scene points; each must be a wall end (a facet vertex) of a wall with the same constants."""
    out = []
    for p in resolved["points"]:
        at = [float(p["at"][0]), float(p["at"][1])]
        ends = [w for w in resolved["walls"]
                for e in (w["from"], w["to"]) if math.hypot(e[0] - at[0], e[1] - at[1]) <= 1e-9]
        if not ends:
            raise CaseError(f"points: {p['name']} at {at} is not a wall end; the YADE translation makes "
                            "points from facet vertices")
        for w in ends:
            if w["material"] != p["material"]:
                raise CaseError(f"points: {p['name']} has material {p['material']!r} but wall {w['name']!r} "
                                f"ending there has {w['material']!r}; a facet vertex has its wall's material")
        out.append(at)
    return out


def _steps(x: float, dt: float, what: str) -> int:
    n = x / dt
    k = int(round(n))
    if x < 0 or abs(n - k) > 1e-6 * max(1.0, n):
        raise CaseError(f"{what}: {x!r} s is not a whole number of steps of dt = {dt!r} s")
    return k


def shear_case_data(case: Case) -> dict:
    """Everything the shear script (compare/codes/shear_yade_template.py) needs (yade_case.json)."""
    _check_variant(case)
    r = case.resolved
    if not shear.is_shear(r):
        raise CaseError("mode shear: the scene has no [shear_box] with [shear]")
    dt = float(case.dt)
    if not (math.isfinite(dt) and dt > 0):
        raise CaseError(f"dt: {dt!r} must be finite and > 0")
    d = np.asarray(case.discs, float)
    if d.ndim != 2 or d.shape[1] != 6 or len(d) == 0 or not np.all(np.isfinite(d)) or np.any(d[:, 2] <= 0):
        raise CaseError("discs: need finite rows x, y, r > 0, vx, vy, omega")
    disc_of = case.material_names()
    discs_m, wall_mats, friction = materials(r, case.disc_materials())
    b = shear.box(r, d)
    sh = dict(r["shear"])
    if not float(sh.get("rate", 0)) > 0:
        raise CaseError("shear.rate: must be > 0")
    if b["plate_horizontal"] != "free":
        raise CaseError(f"shear_box.plate_horizontal: {b['plate_horizontal']!r}: the YADE translation moves the "
                        "plate by the forces on it only ('free')")
    mode = case.clusters if "clusters" in r else "none"
    if mode not in ("bonds", "clumps", "none"):
        raise CaseError(f"clusters: {case.clusters!r} is not 'bonds' or 'clumps'")
    cl = {"mode": mode}
    if mode == "bonds":
        bonds = []
        for i, j in shear.bonds_of(d, r["clusters"]):
            p = pair(r, disc_of[i], disc_of[j])
            bonds.append([i, j, float(p["kn"]), float(p["ks"])])
        cl["bonds"] = bonds
        cl["bond_set"] = r["clusters"]["bonds"]
    elif mode == "clumps":
        cl["members"] = r["clusters"]["members"]
    walls = {w["name"]: w["material"] for w in r["walls"]}
    return {
        "name": case.name, "mode": "shear", "dt": dt,
        "gravity": [float(v) for v in r["gravity"]],
        "discs": [[float(v) for v in row] for row in d],
        "disc_materials": discs_m, "disc_material_of": disc_of,
        "wall_materials": wall_mats, "friction": friction,
        "wall_material_of": {"floor": walls["floor"], "left": walls["left"], "right": walls["right"],
                             "plate": walls["plate"]},
        "box": {k: b[k] for k in ("width", "wall_length", "plate_y", "plate_mass", "plate_overhang")},
        "shear": sh,
        "compress": {"max_time": float(case.settle), "rest_factor": float(r["end"]["rest_factor"])},
        "clusters": cl,
    }


def case_data(case: Case) -> dict:
    """Everything the YADE script needs (yade_case.json)."""
    if case.mode == "shear":
        return shear_case_data(case)
    _check_variant(case)
    r = case.resolved
    if case.mode not in ("static", "discharge"):
        raise CaseError(f"mode: {case.mode!r} is not 'static' or 'discharge'")
    dt = float(case.dt)
    if not (math.isfinite(dt) and dt > 0):
        raise CaseError(f"dt: {dt!r} must be finite and > 0")
    d = np.asarray(case.discs, float)
    if d.ndim != 2 or d.shape[1] != 6 or len(d) == 0:
        raise CaseError("discs: need an (n, 6) array x, y, r, vx, vy, omega")
    disc_of = case.material_names()
    discs_m, wall_mats, friction = materials(r, case.disc_materials())
    walls = [{"name": w["name"], "from": [float(v) for v in w["from"]], "to": [float(v) for v in w["to"]],
              "material": w["material"]} for w in r["walls"] if w.get("active", True)]
    for w in walls:
        if math.hypot(w["to"][0] - w["from"][0], w["to"][1] - w["from"][1]) <= 0:
            raise CaseError(f"walls: {w['name']} has zero length")
    for w, src in zip(walls, [w for w in r["walls"] if w.get("active", True)]):
        if src.get("motion"):   # a prescribed translation: velocity during the steps [i_from, i_until)
            k0, k1 = motion_steps(src, dt)
            w["motion"] = {"velocity": [float(v) for v in src["motion"]["velocity"]], "i_from": k0, "i_until": k1}
    reach = walls + [moved_wall(w, case.end_time) for w in r["walls"] if w.get("active", True) and w.get("motion")]
    points = _points(r, walls)
    g = [float(v) for v in r["gravity"]]
    n_settle = _steps(case.settle, dt, "settle") if case.mode == "discharge" else 0
    n_run = _steps(case.duration, dt, "duration")
    if n_run < 1:
        raise CaseError("duration: at least one step")
    sample_every = max(1, int(round(case.series_interval / dt)))
    # checks and candidate lists for the guard and the remover: at least every SCAN_TIME
    scan_every = max(1, min(sample_every, int(SCAN_TIME / dt)))
    gate, outlet_y = None, None
    if case.mode == "discharge":
        dis = r.get("discharge") or {}
        gate = dis.get("gate")
        if gate not in {w["name"] for w in walls}:
            raise CaseError(f"discharge.gate: {gate!r} is not an active wall")
        outlet_y = common_outlet_y(r)
    finite = np.all(np.isfinite(d))
    rmax = float(np.nanmax(d[:, 2])) if np.any(np.isfinite(d[:, 2])) else 1.0
    xs = [c for w in reach for c in (w["from"][0], w["to"][0])]
    ys = [c for w in reach for c in (w["from"][1], w["to"][1])]
    if finite:
        xs_all, ys_all = xs + list(d[:, 0]), ys + list(d[:, 1])
    else:
        xs_all, ys_all = xs or [0.0], ys or [0.0]
    box = [min(xs_all) - 2 * rmax, max(xs_all) + 2 * rmax, min(ys_all) - 2 * rmax, max(ys_all) + 2 * rmax]
    # A container: gravity holds the discs in a box of walls with an area.
    contained = bool(walls) and math.hypot(*g) > 0 and (max(xs) - min(xs)) > 0 and (max(ys) - min(ys)) > 0
    low = box[2] if outlet_y is None else min(box[2], outlet_y - rmax)
    corners = [(box[0], low), (box[1], low), (box[0], box[3]), (box[1], box[3])]
    pe_ref = min(-(g[0] * x + g[1] * y) for x, y in corners)
    rho = np.array([discs_m[m]["density"] for m in disc_of])
    mass = rho * math.pi * d[:, 2] ** 2 if finite else np.zeros(len(d))
    diag = math.hypot(box[1] - box[0], box[3] - low)
    energy_scale = float(np.sum(mass) * math.hypot(*g) * diag
                         + np.sum(0.5 * mass * (d[:, 3] ** 2 + d[:, 4] ** 2))) if finite else 1.0
    return {
        "name": case.name, "mode": case.mode, "dt": dt,
        "n_settle": n_settle, "n_run": n_run, "sample_every": sample_every,
        "scan_every": scan_every,
        "gravity": g,
        "discs": [[float(v) for v in row] for row in d],
        "disc_materials": discs_m, "disc_material_of": disc_of,
        "wall_materials": wall_mats, "friction": friction,
        "walls": walls, "points": points,
        "gate": gate, "outlet_y": outlet_y,
        "snapshot_every": case.snapshot_steps(),
        "rmax": rmax, "box": box, "contained": contained, "pe_ref": pe_ref,
        "energy_scale": energy_scale or 1.0,
    }


def write_inputs(case: Case, out_dir: Path, threads: int = 1) -> Path:
    """Writes yade_case.json and the script yade_script.py into out_dir; returns the script."""
    data = case_data(case)
    d = np.asarray(case.discs, float)
    if not np.all(np.isfinite(d)) or np.any(d[:, 2] <= 0):
        raise CaseError("discs: need finite rows x, y, r > 0, vx, vy, omega")
    return _write(data, Path(out_dir), threads, SHEAR_TEMPLATE if case.mode == "shear" else TEMPLATE)


def _write(data: dict, out_dir: Path, threads: int, template: Path = TEMPLATE) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    data = dict(data, threads=int(threads))
    write_text_atomic(out_dir / CASE_FILE, json.dumps(data, indent=1) + "\n")
    script = out_dir / SCRIPT
    write_text_atomic(script, Path(template).read_text())
    for f in (RESULT_FILE, SERIES_FILE, PROCESS_FILE) + SHEAR_FILES:   # no stale outputs
        (out_dir / f).unlink(missing_ok=True)
    for f in (out_dir / SNAPSHOT_DIR).glob("discs_spheres.*.vtu"):
        f.unlink()
    return script


# ---------------------------------------------------------------------------------------------
# Running
def _log_tail(out_dir: Path, lines: int = 8) -> str:
    try:
        text = (out_dir / LOG_FILE).read_text(errors="replace").strip().splitlines()
    except OSError:
        return ""
    return " | ".join(text[-lines:])


def execute(out_dir: Path, timeout: float = 600, threads: int = 1, wrap: list[str] | None = None) -> dict:
    """Runs the written script with the real yade; returns {rc, wall_time_s, timed_out}. One thread
    and no wrap: in a kept YADE process (compare/codes/yade_session.py); else its own `yade -n -jN
    -x` (wrap: a command to run it under; benchmarks/speed.py measures its memory with /usr/bin/time)."""
    out_dir = Path(out_dir)
    cmd = list(wrap or []) + ["yade", "-n", f"-j{int(threads)}", "-x", SCRIPT]
    t0 = time.perf_counter()
    timed_out = False
    if int(threads) == 1 and not wrap:
        rc = yade_session.run(SCRIPT, out_dir, out_dir / LOG_FILE, timeout)
        timed_out = rc is None
        cmd = ["yade session:"] + cmd[-4:]
    else:
        with open(out_dir / LOG_FILE, "w") as log:
            try:
                p = subprocess.Popen(cmd, cwd=out_dir, stdout=log, stderr=subprocess.STDOUT,
                                     stdin=subprocess.DEVNULL, start_new_session=True)
            except OSError as e:
                info = {"rc": None, "wall_time_s": 0.0, "timed_out": False, "error": f"cannot start yade: {e}"}
                write_text_atomic(out_dir / PROCESS_FILE, json.dumps(info) + "\n")
                return info
            try:
                rc = p.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                timed_out = True
                try:
                    os.killpg(p.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                rc = p.wait()
    info = {"rc": rc, "wall_time_s": time.perf_counter() - t0, "timed_out": timed_out,
            "timeout": timeout, "command": " ".join(cmd)}
    write_text_atomic(out_dir / PROCESS_FILE, json.dumps(info) + "\n")
    return info


def run(case: Case, out_dir: Path, timeout: float = 600, threads: int = 1, wrap: list[str] | None = None) -> Result:
    """write_inputs, run yade, read. Never raises: a case YADE cannot express (write_inputs'
    CaseError) and a run that fails in any way are failed Results with the reason."""
    out_dir = Path(out_dir)
    try:
        write_inputs(case, out_dir, threads)
    except CaseError as e:
        return failed(NAME, case.name, f"translation: {e}", version=version(), out_dir=str(out_dir))
    except Exception as e:          # noqa: BLE001 - a run never raises
        return failed(NAME, case.name, f"could not write the YADE inputs: {e!r}", out_dir=str(out_dir))
    return run_written(case, out_dir, timeout, threads, wrap)


def run_written(case: Case, out_dir: Path, timeout: float = 600, threads: int = 1,
                wrap: list[str] | None = None) -> Result:
    """Runs the script already written in out_dir and reads it (never raises)."""
    out_dir = Path(out_dir)
    try:
        execute(out_dir, timeout, threads, wrap)
    except Exception as e:          # noqa: BLE001 - a run never raises
        return failed(NAME, case.name, f"could not run yade: {e!r}", out_dir=str(out_dir))
    return read(case, out_dir)


# ---------------------------------------------------------------------------------------------
# Reading
def _fail(case: Case, out_dir: Path, reason: str, **kw) -> Result:
    return failed(NAME, case.name, reason, version=version(), out_dir=str(out_dir), **kw)


def read(case: Case, out_dir: Path) -> Result:
    """The common Result from the files the YADE script wrote (never raises)."""
    out_dir = Path(out_dir)
    try:
        return _read(case, out_dir)
    except Exception as e:          # noqa: BLE001 - corrupt outputs are a failed run
        return _fail(case, out_dir, f"unreadable YADE outputs: {e!r}")


def _wall_series(case: Case, out_dir: Path, res: dict, walls: list) -> dict:
    """The wall-force series: SERIES_FILE's per-contact rows grouped by sample time, binned like
    the profiles (a moving wall's bins where it is at that time)."""
    pb, centre = case.profile_bin, case.centre
    by_t: dict[float, list] = {float(t): [] for t in res["series_t"]}
    with open(out_dir / SERIES_FILE, newline="") as fh:
        for row in csv.DictReader(fh):
            t = float(row["t"])
            by_t.setdefault(t, []).append((row["wall"], float(row["px"]), float(row["py"]),
                                           float(row["fx"]), float(row["fy"])))
    ts = sorted(by_t)
    series = {"t": ts, "walls": {w["name"]: {"normal": [], "shear": []} for w in walls}}
    for t in ts:
        t_run = t + (case.settle if case.mode == "discharge" else 0.0)
        prof = profiles_from_contacts([moved_wall(w, t_run) for w in walls], pb, centre, by_t[t])
        for name, p in prof.items():
            series["walls"][name]["normal"].append(p["normal"])
            series["walls"][name]["shear"].append(p["shear"])
    return series


def _read(case: Case, out_dir: Path) -> Result:
    proc = {}
    if (out_dir / PROCESS_FILE).exists():
        proc = json.loads((out_dir / PROCESS_FILE).read_text())
    if case.mode == "shear":
        return _read_shear(case, out_dir, proc)
    res_path = out_dir / RESULT_FILE
    res = json.loads(res_path.read_text()) if res_path.exists() else None
    wall = float(proc.get("wall_time_s", res["script_time_s"] if res else float("nan")))
    common = {"wall_time_s": wall}
    if proc.get("error"):
        return _fail(case, out_dir, proc["error"], **common)
    if proc.get("timed_out"):
        return _fail(case, out_dir, f"timeout: yade killed after {proc.get('timeout')} s "
                     f"(log: {_log_tail(out_dir, 3)})", **common)
    rc = proc.get("rc", 0)
    if rc not in (0, None):
        what = {134: " (abort: SIGABRT, e.g. YADE's inconsistent material set)",
                -6: " (abort: SIGABRT)", 139: " (segmentation fault)", -11: " (segmentation fault)",
                1: " (python error or uncaught exception)"}.get(rc, "")
        inner = f"; script says: {res['reason'].strip()[-600:]}" if res and res.get("reason") else ""
        return _fail(case, out_dir, f"yade exited with code {rc}{what}{inner}; log: {_log_tail(out_dir)}",
                     **common)
    if res is None:
        return _fail(case, out_dir, f"missing output {RESULT_FILE} (yade exit {rc}); log: {_log_tail(out_dir)}",
                     **common)
    if res["status"] != "complete":
        return _fail(case, out_dir, res["reason"] or res["status"], steps=int(res.get("steps", 0)),
                     n_initial=int(res.get("n_initial", 0)), n_final=int(res.get("n_final", 0)), **common)
    if not (out_dir / SERIES_FILE).exists():
        return _fail(case, out_dir, f"missing output {SERIES_FILE}", **common)

    walls = [w for w in case.resolved["walls"]]
    centre = case.centre
    pb = case.profile_bin
    n0, n1 = int(res["n_initial"]), int(res["n_final"])
    removals = sorted(float(x["t"]) for x in res["removals"])
    if n0 != len(case.discs):
        return _fail(case, out_dir, f"YADE started with {n0} discs, the case has {len(case.discs)}", **common)
    if case.mode == "static" and n1 != n0:
        return _fail(case, out_dir, f"lost discs: {n0 - n1} of {n0} discs missing in a closed container", **common)
    if case.mode == "discharge" and n1 + len(removals) != n0:
        return _fail(case, out_dir, f"lost discs: {n0 - n1 - len(removals)} discs missing besides the "
                     f"{len(removals)} removed at the outlet", **common)
    discs_end = [list(map(float, row)) for row in res["discs_end"]]
    if len(discs_end) != n1:
        return _fail(case, out_dir, f"discs_end has {len(discs_end)} rows for {n1} discs", **common)
    flat = np.array(discs_end, float).ravel()
    if flat.size and not np.all(np.isfinite(flat)):
        return _fail(case, out_dir, "NaN or inf in the final discs", **common)

    final = [(c[0], float(c[1]), float(c[2]), float(c[3]), float(c[4])) for c in res["final_contacts"]]
    if not all(math.isfinite(v) for c in final for v in c[1:]):
        return _fail(case, out_dir, "NaN or inf in the final wall contact forces", **common)
    # a moving wall's bins run along it where it is (the contact points are on the moved facet)
    profiles = profiles_from_contacts([moved_wall(w, case.end_time) for w in walls], pb, centre, final)

    series = _wall_series(case, out_dir, res, walls)
    bad = [name for name, s in series["walls"].items() for key in ("normal", "shear")
           if s[key] and not np.all(np.isfinite(np.array(s[key], float)))]
    if bad:
        return _fail(case, out_dir, f"NaN or inf in the wall-force series of {bad[0]}", **common)

    ps = res.get("particle_steps") or 0
    loop = float(res.get("loop_time_s", float("nan")))
    extra = {
        "kept_index": res["kept_index"],
        "removal_index": [x["index"] for x in sorted(res["removals"], key=lambda x: x["t"])],
        "loop_time_s": loop,
        "script_time_s": res.get("script_time_s"),
        "particle_steps": ps,
        "us_per_particle_step": loop / ps * 1e6 if ps else float("nan"),
        "wall_force_mismatch_rel": res.get("wall_force_mismatch_rel"),
        "guard_steps": res.get("guard_steps"),
        "guard_flips": res.get("guard_flips"),
        "pairs_seen": res.get("pairs_seen", {}),
        "kinetic_energy_max_sampled": res.get("kinetic_energy_max_sampled"),
        "energy_budget": res.get("energy_budget"),
        "threads": res.get("threads"),
        "yade_log": str(out_dir / LOG_FILE),
        "limitations": LIMITATIONS,
    }
    return Result(code=NAME, case=case.name, status="ok", version=res.get("yade_version") or version(),
                  wall_time_s=wall, steps=int(res["steps"]), n_initial=n0, n_final=n1,
                  profiles=profiles, series=series, removals=removals,
                  kinetic_energy_end=float(res["kinetic_energy_end"]), discs_end=discs_end,
                  extra=extra, out_dir=str(out_dir))


def _read_shear(case: Case, out_dir: Path, proc: dict) -> Result:
    """A shear run: the script's summary.json and shear_series.csv (dem.compare.cases.shear.read_outputs)."""
    common = {"wall_time_s": float(proc.get("wall_time_s", float("nan")))}
    if proc.get("error"):
        return _fail(case, out_dir, proc["error"], **common)
    if proc.get("timed_out"):
        return _fail(case, out_dir, f"timeout: yade killed after {proc.get('timeout')} s "
                     f"(log: {_log_tail(out_dir, 3)})", **common)
    rc = proc.get("rc", 0)
    if rc not in (0, None) or not (out_dir / "summary.json").exists():
        return _fail(case, out_dir, f"yade exited with code {rc}; log: {_log_tail(out_dir)}", **common)
    summary = json.loads((out_dir / "summary.json").read_text())
    if summary.get("status") != "sheared":
        return _fail(case, out_dir, f"shear: status {summary.get('status')!r} (non-finite velocities)", **common)
    discs_end = summary.get("discs_end") or []
    flat = np.array(discs_end, float).ravel()
    if len(discs_end) != len(case.discs) or not np.all(np.isfinite(flat)):
        return _fail(case, out_dir, f"shear: {len(discs_end)} finite discs at the end for {len(case.discs)}", **common)
    extra = {"shear": shear.read_outputs(out_dir), "yade_log": str(out_dir / LOG_FILE),
             "script_time_s": summary.get("wall_time_s"), "limitations": LIMITATIONS}
    return Result(code=NAME, case=case.name, status="ok", version=summary.get("engine") or version(),
                  wall_time_s=common["wall_time_s"], steps=int(summary.get("steps", 0)),
                  n_initial=len(case.discs), n_final=len(discs_end), discs_end=discs_end,
                  kinetic_energy_end=float(summary.get("kinetic_energy_end", float("nan"))),
                  extra=extra, out_dir=str(out_dir))


def read_snapshots(case: Case, out_dir: Path) -> list[Snapshot]:
    """Particle snapshots in the common form from YADE's VTKRecorder files (VTU, read with meshio),
    times since the start (static) or the opening (discharge). Recorded before the integrator, like
    the wall forces: positions at t; velocities are leapfrog's v(t - dt/2) (an error of g dt / 2 in
    free fall); points are Float32 in these files (YADE writes them so: about 1e-7 relative).
    Ids: YADE body ids mapped to the rows of the case's packing (disc_body_ids of yade_result.json)."""
    out_dir = Path(out_dir)
    res = json.loads((out_dir / RESULT_FILE).read_text())
    index = {int(b): k for k, b in enumerate(res["disc_body_ids"])}
    case_data_ = json.loads((out_dir / CASE_FILE).read_text())
    i_open = int(case_data_["n_settle"])
    out = []
    for f in (out_dir / SNAPSHOT_DIR).glob("discs_spheres.*.vtu"):
        m = re.fullmatch(r"discs_spheres\.(\d+)\.vtu", f.name)
        if not m:
            continue
        mesh = meshio.read(str(f))
        pd = mesh.point_data
        ids = [index[int(round(b))] for b in np.asarray(pd["id"], float).reshape(-1)]
        v = np.asarray(pd["linVelVec"], float).reshape(-1, 3)
        w = np.asarray(pd["angVelVec"], float).reshape(-1, 3)
        out.append(Snapshot.from_columns((int(m.group(1)) - i_open) * case.dt, ids, x=mesh.points[:, 0],
                                         y=mesh.points[:, 1], r=pd["radii"], vx=v[:, 0], vy=v[:, 1], omega=w[:, 2]))
    return sorted(out, key=lambda s: s.t)

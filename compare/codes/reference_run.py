"""``dem run SCENE.toml --engine liggghts|lammps|yade [--np N] --out DIR``: one scene run in a
reference code, written as the engine's own run folder (docs/outputs.md), so that
dem.compare.io.run_dir (strict) and ``python3 -m dem.compare.figures run DIR`` read it unchanged.

The scene becomes one comparison case (compare/cases/plan.py): the shared law (common.SHARED_VARIANT),
the scene's dt, and

- a static scene: the scene's own start (its lattice or disc file, its velocities, no jitter)
  run for ``end.time``; the reference codes do not evaluate the engine's rest criterion, so the
  run always lasts ``end.time`` (status ``end_time``; ``rest`` says it was not checked);
- a discharge scene: the same start settles for ``--settle`` s (the comparison's default), the
  gate opens, ``discharge.time`` s of flow, discs below the outlet removed (as ``dem compare
  --kind discharge`` runs each member). The code dumps its discs at every wall-series sample;
  compare/codes/frame_measures.py measures flow_series.csv, the pattern, the jams and the dead fraction
  from those frames, and the snapshots are the frames at ``discharge.snapshots``.

``--set KEY=VALUE`` changes the scene as ``dem run --set`` does; ``--member-start FILE`` starts
from an ensemble member's perturbed centres (``dem ensemble --member K --engine CODE``).

What the code cannot express is refused before any run (exit 2, the field named: the backend's
own translation). LIGGGHTS and LAMMPS run under ``mpirun -np N`` when N > 1, YADE with ``-j N``.
The program's inputs, log and dumps stay in ``DIR/<code>/``. A run that blows up or loses discs
exits 3 (unstable), one that crashes or times out exits 4, the program's message on stderr.

Quantities the codes' results do not give are written as null (JSON), ``nan`` or ``-1`` (CSV) and
listed in summary.json's ``absent``; none is estimated: contacts.csv and contacts.vtu (no contact
list is read back), the rest measures, the stability bounds and the pair table, the slit ends'
forces (each code counts them in the end bin of the wall that ends there), per-bin contact counts
where the code gives none (LIGGGHTS), and for a discharge the contact snapshots and the removed
discs' velocities where the code does not log them (LAMMPS, YADE).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import meshio
import numpy as np

from dem.compare.codes.backends import backend
from dem.compare.codes import frame_measures
from dem.compare.cases.common import (SHARED_VARIANT, Case, CaseError, Result, Snapshot, densities, inward_normal, moved_wall,
                     outlet_y, resolve, scene_material_index, tangent)
from dem.compare.io import atomic_file, scene_toml
from dem.compare.io.atomic_file import write_text as write_text_atomic
from dem.compare.cases.plan import Entry, Options, PlanError, make_plan, start_discs
from dem.compare.cases.mutants import Mutation

CODES = ("liggghts", "lammps", "yade")
EXIT_BAD, EXIT_UNSTABLE, EXIT_FAILED = 2, 3, 4
# Failure reasons (the backends' words and the programs' own) that mean the dynamics went wrong
# rather than the program: exit 3 like the engine's stability guard.
UNSTABLE_WORDS = ("blow-up", "blew up", "lost discs", "lost atoms", "non-finite", "nan or inf",
                  "left the closed container", "at the end:", "out of range atoms")
# The integrators the codes run (docs/compare.md): LIGGGHTS' and LAMMPS' nve/sphere is velocity
# Verlet; YADE's NewtonIntegrator is a leapfrog.
SCHEME = {"liggghts": "velocity_verlet", "lammps": "velocity_verlet", "yade": "leapfrog"}
REST_NOTE = ("not checked: the reference codes do not evaluate the engine's rest criterion "
             "(end.rest_factor); the run lasts end.time")


def _fail_exit(code: str, message: str, status: int) -> int:
    sys.stderr.write(f"dem run --engine {code}: {message}\n")
    return status


def law_note(code: str, own: dict) -> str:
    """What the run's law is, said where the user reads: the reference codes run the comparison
    layer's shared law (common.SHARED_VARIANT), and each option in which the scene's [contact]
    differs from it is named with both values."""
    diff = [f"{k} = {own.get(k)!r} -> {v!r}" for k, v in SHARED_VARIANT.items() if own.get(k) != v]
    if not diff:
        return f"law: {code} runs the scene's own contact law (it is the shared law of the comparison layer)"
    return (f"law: {code} cannot run the scene's [contact]; it runs the shared law of the comparison layer "
            f"instead (docs/compare.md, \"What runs\"), which differs in: " + "; ".join(diff))


def make_case(scene: Path, settle: float) -> Case:
    """The one case a scene runs as: the plan's shared law and dt, the scene's own start."""
    plan = make_plan(Entry(Path(scene), Options(start="scene", settle=settle)))
    if plan.kind not in ("static", "discharge"):
        raise PlanError(f"{scene}: shear_box: dem run --engine runs static and discharge scenes; the shear box "
                        "runs in YADE through `dem compare --kind shear`")
    r = plan.shared
    discs = start_discs(r)
    mats = scene_material_index(r)
    if plan.kind == "discharge":
        d = r["discharge"]
        interval = float(d.get("series_interval", 0.005))
        # the discs dumped at every sample of the wall series (a whole number of steps, as the
        # backends sample): flow_series.csv, the pattern and the snapshots are measured from them
        every = max(1, round(interval / plan.dt)) * plan.dt
        return Case(name=scene.stem, resolved=r, discs=discs, dt=plan.dt, duration=plan.duration,
                    mode="discharge", settle=plan.settle, materials=mats, series_interval=interval,
                    snapshot_interval=every)
    return Case(name=scene.stem, resolved=r, discs=discs, dt=plan.dt, duration=float(r["end"]["time"]),
                materials=mats)


def with_set(scene: Path, assignments: list[str], folder: Path) -> Path:
    """The scene with the ``--set`` assignments applied (dem.compare.io.scene_toml, as `dem compare
    --set`), written into ``folder`` under the scene's own name (its relative paths rebased), for
    the engine to validate as it resolves it; the scene itself without assignments."""
    if not assignments:
        return scene
    path = folder / scene.name
    try:
        doc = scene_toml.rebase_paths(scene_toml.load(scene), scene.parent, folder)
        scene_toml.write(path, scene_toml.with_assignments(doc, assignments))
    except (KeyError, ValueError) as e:
        raise PlanError(f"{scene}: --set: {e}") from None
    return path


# A deliberately wrong translation, for the tests that must be able to fail (as compare/cases/mutants.py
# does for the comparison): DEM_ENGINE_MUTANT=WHAT:FACTOR scales one constant of what the code is
# given (WHAT: density, gravity, or a pair constant kn, ks, eta_n, eta_s, mu of every pair); the
# outputs are still measured against the scene as it is.
MUTANT_ENV = "DEM_ENGINE_MUTANT"
MUTANT_WHATS = ("density", "gravity", "kn", "ks", "eta_n", "eta_s", "mu")


def mutated(case: Case, spec: str) -> Case:
    """The case the code runs: ``case`` itself, or with the DEM_ENGINE_MUTANT constant scaled."""
    if not spec:
        return case
    what, _, factor = spec.partition(":")
    try:
        f = float(factor)
    except ValueError:
        f = math.nan
    if what not in MUTANT_WHATS or not (math.isfinite(f) and f > 0):
        raise CaseError(f"{MUTANT_ENV}={spec!r}: expected WHAT:FACTOR, WHAT one of {', '.join(MUTANT_WHATS)}, "
                        "FACTOR a number > 0")
    return dataclasses.replace(case, resolved=Mutation("testing", "", what, "all", f, "all").apply(case.resolved))


def member_start(case: Case, path: Path) -> Case:
    """The case started from an ensemble member's disc centres (x, y per disc, the scene's order)."""
    try:
        xy = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except (OSError, ValueError) as e:
        raise CaseError(f"--member-start {path}: {e}") from None
    if xy.shape != (len(case.discs), 2) or not np.all(np.isfinite(xy)):
        raise CaseError(f"--member-start {path}: needs x,y of each of the scene's {len(case.discs)} discs "
                        f"(finite), found an array of shape {xy.shape}")
    discs = np.array(case.discs, float, copy=True)
    discs[:, :2] = xy
    return dataclasses.replace(case, discs=discs)


def classify(reason: str) -> int:
    low = reason.lower()
    if "timed out" in low or "timeout" in low:
        return EXIT_FAILED
    return EXIT_UNSTABLE if any(w in low for w in UNSTABLE_WORDS) else EXIT_FAILED


# ------------------------------------------------------------------------------- outputs

def _fmt(v) -> str:
    return "nan" if v is None or (isinstance(v, float) and not math.isfinite(v)) else repr(float(v))


def _wall_geometry(case: Case) -> tuple[list[dict], float]:
    """The walls as they are at the end of the run (a prescribed translation applied), and the top
    of the walls and points (depth = top - y, as the engine measures it)."""
    r = case.resolved
    walls = {w["name"]: moved_wall(w, case.end_time) for w in r["walls"]}
    ys = [c[1] for w in walls.values() for c in (w["from"], w["to"])] + [p["at"][1] for p in r["points"]]
    return list(walls.values()), max(ys) if ys else 0.0


def _bins(w: dict, p: dict, top: float) -> dict:
    a, t = np.array(w["from"], float), tangent(w)
    mid = 0.5 * (np.array(p["s_lo"], float) + np.array(p["s_hi"], float))
    xy = a[None, :] + mid[:, None] * t[None, :]
    return {"s_mid": mid, "x_mid": xy[:, 0], "y_mid": xy[:, 1], "depth_mid": top - xy[:, 1]}


def _wall_force(w: dict, centre, normal: float, shear: float) -> np.ndarray:
    """Force of the discs on a straight wall from its normal (pushing positive) and shear totals."""
    return -normal * inward_normal(w, centre) + shear * tangent(w)


def disc_rows(case: Case, res: Result) -> tuple[np.ndarray, np.ndarray]:
    """The discs at the end (x, y, r, vx, vy, omega) and their ids (rows of the case's start)."""
    rows = np.array(res.discs_end, float).reshape(-1, 6)
    kept = res.extra.get("kept_index")
    ids = np.arange(len(rows)) if kept is None else np.array(kept, int).reshape(-1)
    if len(ids) != len(rows):
        raise CaseError(f"the result has {len(rows)} discs and {len(ids)} ids")
    return rows, ids


def write_discs(out: Path, case: Case, rows: np.ndarray, ids: np.ndarray) -> None:
    names = [m["name"] for m in case.resolved["materials"]]
    mats = case.material_index()[ids]
    lines = ["id,x,y,r,vx,vy,omega,material"]
    for i, row, m in zip(ids, rows, mats):
        lines.append(f"{int(i)}," + ",".join("%.17g" % v for v in row) + f",{names[int(m)]}")
    write_text_atomic(out / "discs.csv", "\n".join(lines) + "\n")
    pts = np.column_stack([rows[:, :2], np.zeros(len(rows))])
    vel = np.column_stack([rows[:, 3:5], np.zeros(len(rows))])
    mesh = meshio.Mesh(pts, [("vertex", np.arange(len(rows)).reshape(-1, 1))],
                       point_data={"radius": rows[:, 2], "velocity": vel, "omega": rows[:, 5],
                                   "id": ids.astype(np.int64)})
    with atomic_file.replacing(out / "discs.vtu") as tmp:
        meshio.write(tmp, mesh, file_format="vtu")


def wall_entries(case: Case, res: Result) -> tuple[list[dict], list[str]]:
    """summary.json's walls (the engine's keys) and wall_profiles.csv's rows."""
    walls, top = _wall_geometry(case)
    rows, entries = [], []
    for w in walls:
        p = res.profiles.get(w["name"])
        if p is None:       # an opened gate: the code no longer has the wall
            continue
        b = _bins(w, p, top)
        normal, shear = np.array(p["normal"], float), np.array(p["shear"], float)
        counts = p.get("contacts")
        f = _wall_force(w, case.centre, float(normal.sum()), float(shear.sum()))
        entries.append({"name": w["name"], "group": w["group"], "from": list(w["from"]), "to": list(w["to"]),
                        "normal_total": float(normal.sum()), "shear_total": float(shear.sum()),
                        "force": f.tolist(), "contacts": int(sum(counts)) if counts is not None else None,
                        "profile": {"s_lo": list(p["s_lo"]), "s_hi": list(p["s_hi"]),
                                    "depth_mid": b["depth_mid"].tolist(), "x_mid": b["x_mid"].tolist(),
                                    "y_mid": b["y_mid"].tolist(), "normal": normal.tolist(),
                                    "shear": shear.tolist(),
                                    "contacts": list(counts) if counts is not None else None}})
        for k in range(len(normal)):
            rows.append(f"{w['name']},{w['group']},{k},{_fmt(p['s_lo'][k])},{_fmt(p['s_hi'][k])},"
                        f"{_fmt(b['x_mid'][k])},{_fmt(b['y_mid'][k])},{_fmt(b['depth_mid'][k])},"
                        f"{_fmt(normal[k])},{_fmt(shear[k])},{int(counts[k]) if counts is not None else -1}")
    return entries, rows


def write_series(out: Path, case: Case, res: Result) -> None:
    """wall_series.csv and wall_totals_series.csv of a discharge (t since opening)."""
    walls, top = _wall_geometry(case)
    ser, ts = res.series.get("walls", {}), res.series.get("t", [])
    per_bin = ["t,wall,bin,s_mid,x_mid,y_mid,depth_mid,normal,shear"]
    totals = ["t,name,normal,shear,fx,fy"]
    geo = {w["name"]: w for w in walls}
    for k, t in enumerate(ts):
        for name, s in ser.items():
            if name not in geo or name not in res.profiles or k >= len(s["normal"]):
                continue
            w = geo[name]
            b = _bins(w, res.profiles[name], top)
            nrm, shr = np.array(s["normal"][k], float), np.array(s["shear"][k], float)
            for j in range(len(nrm)):
                per_bin.append(f"{_fmt(t)},{name},{j},{_fmt(b['s_mid'][j])},{_fmt(b['x_mid'][j])},"
                               f"{_fmt(b['y_mid'][j])},{_fmt(b['depth_mid'][j])},{_fmt(nrm[j])},{_fmt(shr[j])}")
            f = _wall_force(w, case.centre, float(nrm.sum()), float(shr.sum()))
            totals.append(f"{_fmt(t)},{name},{_fmt(nrm.sum())},{_fmt(shr.sum())},{_fmt(f[0])},{_fmt(f[1])}")
    write_text_atomic(out / "wall_series.csv", "\n".join(per_bin) + "\n")
    write_text_atomic(out / "wall_totals_series.csv", "\n".join(totals) + "\n")


def _masses(case: Case) -> np.ndarray:
    return densities(case.resolved, case.material_index()) * math.pi * case.discs[:, 2] ** 2


def peak_ratios(case: Case, res: Result, window: float | None) -> dict:
    """docs/outputs.md's peak ratios from the wall series: over the bottom (gate excluded) and side
    bins whose static load (the first sample, at opening) is at least a quarter of that wall's
    largest static bin, the largest ratio of the normal force to the static one; windowed: of its
    moving average over ``window`` s."""
    t = np.array(res.series.get("t", []), float)
    gate = case.resolved["discharge"]["gate"]
    groups = {w["name"]: w["group"] for w in case.resolved["walls"]}
    out = {}
    for key, prefix in (("bottom", "bottom"), ("side", "side")):
        raw = win = None
        for name, s in res.series.get("walls", {}).items():
            if name == gate or not str(groups.get(name, "")).startswith(prefix) or not s["normal"]:
                continue
            m = np.array(s["normal"], float)
            static = m[0]
            if not np.any(static > 0):
                continue
            sel = static >= 0.25 * static.max()
            ratio = m[:, sel] / static[sel]
            raw = max(raw or -math.inf, float(ratio.max()))
            if window and len(t) > 1:
                n = max(1, int(round(window / (t[1] - t[0]))))
                if n <= len(ratio):
                    kernel = np.ones(n) / n
                    avg = np.array([np.convolve(ratio[:, j], kernel, mode="valid") for j in range(ratio.shape[1])])
                    win = max(win or -math.inf, float(avg.max()))
        out[f"peak_ratio_{key}"] = raw
        out[f"peak_ratio_{key}_windowed"] = win
    return out


def removal_rows(case: Case, res: Result, frames: list[Snapshot]) -> list[tuple[float, int, tuple]]:
    """(t, id, (vx, vy)) of every disc out, in time order: the id where the code names it
    (LIGGGHTS, YADE), else from the disc frames (frame_measures.removal_ids); the velocity where the
    code logs it (LIGGGHTS), else nan."""
    rem = sorted(float(x) for x in res.removals)
    idx = res.extra.get("removal_index")
    vel = res.extra.get("removal_velocity")
    if idx is None or len(idx) != len(rem):
        idx = frame_measures.removal_ids(frames, rem, case.dt)
    return [(t, int(idx[k]), tuple(vel[k]) if vel is not None and k < len(vel) else (None, None))
            for k, t in enumerate(rem)]


def flow_rate(rows, mass: np.ndarray) -> float | None:
    """The engine's flow_rate: least-squares slope of the cumulative removed mass against time,
    from the 5th removal on; None with fewer than 10 removals (or one of unknown mass)."""
    if len(rows) < 10 or any(i < 0 for _t, i, _v in rows):
        return None
    t = np.array([r[0] for r in rows])
    m = np.cumsum([mass[r[1]] for r in rows])
    return float(np.polyfit(t[4:], m[4:], 1)[0])


def write_walls_vtu(path: Path, case: Case, t_world: float, wall_names: list[str]) -> None:
    """The walls present at world time t (the opened gate gone, a moving wall where it stands) as
    VTK_LINE cells with cell data ``wall``: the index in summary.json's ``walls``."""
    gate = case.resolved["discharge"]["gate"]
    pts, cells, index = [], [], []
    for w in case.resolved["walls"]:
        if not w.get("active", True) or w["name"] == gate or w["name"] not in wall_names:
            continue
        m = moved_wall(w, t_world)
        cells.append([len(pts), len(pts) + 1])
        pts += [[*m["from"], 0.0], [*m["to"], 0.0]]
        index.append(wall_names.index(w["name"]))
    mesh = meshio.Mesh(np.array(pts, float).reshape(-1, 3), [("line", np.array(cells, int).reshape(-1, 2))],
                       cell_data={"wall": [np.array(index, np.int32)]})
    with atomic_file.replacing(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")


def write_snapshots(out: Path, case: Case, frames: list[Snapshot], wall_names: list[str]) -> list[float]:
    """snapshots/discs_NNNN.{csv,vtu} (the engine's columns, with dx, dy since the opening) and
    snapshots/walls_NNNN.vtu at the scene's discharge.snapshots times, each the disc frame at that
    time (frames lie every sample: the nearest, within half a sample), indexed by
    discharge_discs.pvd (times since opening) and snapshots.pvd (world times, parts 0 discs and 1
    walls). The contact files are absent (no contact list is read back). Returns the times written."""
    names = [m["name"] for m in case.resolved["materials"]]
    mats = case.material_index()
    want = case.resolved["discharge"].get("snapshots", [])
    half = 0.5 * max(case.snapshot_interval, case.dt)
    open_at = {int(i): (x, y) for i, x, y in zip(frames[0].id, frames[0].x, frames[0].y)} if frames else {}
    t_open = round(case.settle / case.dt) * case.dt
    (out / "snapshots").mkdir(exist_ok=True)
    entries, times = [], []
    for k, tw in enumerate(want):
        near = min(frames, key=lambda s: abs(s.t - tw), default=None)
        if near is None or abs(near.t - tw) > half + 1e-12:
            continue
        stem = f"discs_{k:04d}"
        x0 = np.array([open_at.get(int(i), (math.nan, math.nan)) for i in near.id], float).reshape(-1, 2)
        lines = ["id,x,y,r,vx,vy,omega,material,dx,dy"]
        for j, i in enumerate(near.id):
            vals = (near.x[j], near.y[j], near.r[j], near.vx[j], near.vy[j], near.omega[j])
            lines.append(f"{int(i)}," + ",".join("%.17g" % v for v in vals) + f",{names[int(mats[int(i)])]},"
                         + "%.17g,%.17g" % (near.x[j] - x0[j, 0], near.y[j] - x0[j, 1]))
        write_text_atomic(out / "snapshots" / f"{stem}.csv", "\n".join(lines) + "\n")
        n = len(near.id)
        mesh = meshio.Mesh(np.column_stack([near.x, near.y, np.zeros(n)]), [("vertex", np.arange(n).reshape(-1, 1))],
                           point_data={"radius": near.r, "velocity": np.column_stack([near.vx, near.vy, np.zeros(n)]),
                                       "omega": near.omega, "id": near.id.astype(np.int64),
                                       "dx": near.x - x0[:, 0], "dy": near.y - x0[:, 1]})
        with atomic_file.replacing(out / "snapshots" / f"{stem}.vtu") as tmp:
            meshio.write(tmp, mesh, file_format="vtu")
        write_walls_vtu(out / "snapshots" / f"walls_{k:04d}.vtu", case, t_open + near.t, wall_names)
        entries.append((near.t, f"snapshots/{stem}.vtu", f"snapshots/walls_{k:04d}.vtu"))
        times.append(near.t)
    head = '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n'
    tail = "  </Collection>\n</VTKFile>\n"
    write_text_atomic(out / "discharge_discs.pvd", head + "".join(
        f'    <DataSet timestep="{"%.17g" % t}" file="{f}"/>\n' for t, f, _w in entries) + tail)
    write_text_atomic(out / "snapshots.pvd", head + "".join(
        f'    <DataSet timestep="{"%.17g" % (t + t_open)}" part="0" file="{f}"/>\n'
        f'    <DataSet timestep="{"%.17g" % (t + t_open)}" part="1" file="{w}"/>\n' for t, f, w in entries) + tail)
    return times


def _peaks(v: np.ndarray, win: int) -> tuple[float, float]:
    """The engine's PeakTracker: the largest sample (at least 0) and the largest mean of win
    consecutive samples (0 with fewer)."""
    raw = max(0.0, float(np.max(v))) if len(v) else 0.0
    means = np.convolve(v, np.ones(win) / win, mode="valid") if len(v) >= win else []
    return raw, max(0.0, float(np.max(means))) if len(means) else 0.0


def wall_ratios(case: Case, res: Result) -> list[dict]:
    """summary.json's discharge.walls: each wall's static (first sample) and peak normal force,
    total and per bin, raw and windowed, and their ratios (bins with a static load of at least a
    quarter of the wall's largest), from the wall series."""
    d = case.resolved["discharge"]
    win = max(1, round(float(d.get("peak_window", 0.05)) / case.snapshot_interval)) if case.snapshot_interval else 1
    groups = {w["name"]: w["group"] for w in case.resolved["walls"]}
    out = []
    for name, sr in res.series.get("walls", {}).items():
        m = np.array(sr["normal"], float)
        if m.ndim != 2 or not len(m):
            continue
        tot = m.sum(axis=1)
        raw, wnd = _peaks(tot, win)
        static, smax = m[0], float(np.max(m[0])) if m.shape[1] else 0.0
        bins = []
        for b in range(m.shape[1]):
            br, bw = _peaks(m[:, b], win)
            ok = smax > 0 and static[b] >= 0.25 * smax
            bins.append({"bin": b, "static": float(static[b]), "peak": br, "peak_windowed": bw,
                         "ratio": br / static[b] if ok else None, "ratio_windowed": bw / static[b] if ok else None})
        out.append({"name": name, "group": groups.get(name, ""), "static_normal": float(tot[0]), "peak_normal": raw,
                    "peak_normal_windowed": wnd, "ratio": raw / tot[0] if tot[0] > 0 else None,
                    "ratio_windowed": wnd / tot[0] if tot[0] > 0 else None, "bins": bins})
    return out


def discharge_block(case: Case, res: Result, out: Path, frames: list[Snapshot], status: str,
                    wall_names: list[str]) -> dict:
    d = case.resolved["discharge"]
    mass = _masses(case)
    rows = removal_rows(case, res, frames)
    lines = ["t,id,mass,vx,vy,how"]
    for t, i, v in rows:
        lines.append(f"{_fmt(t)},{i},{_fmt(mass[i]) if i >= 0 else 'nan'},{_fmt(v[0])},{_fmt(v[1])},outlet")
    write_text_atomic(out / "removals.csv", "\n".join(lines) + "\n")
    write_series(out, case, res)
    f = frame_measures.silo_frame(case.resolved)
    fl = frame_measures.flow(frames, [(t, i) for t, i, _v in rows], mass, len(case.discs), f, case.resolved, case.dt)
    write_text_atomic(out / "flow_series.csv", "\n".join(fl["rows"]) + "\n")
    snaps = write_snapshots(out, case, frames, wall_names)
    jam_at, jams = frame_measures.jams([t for t, _i, _v in rows], frames, f, float(d["jam_time"]), case.duration,
                                    case.dt)
    rem = [t for t, _i, _v in rows]
    q = flow_rate(rows, mass)
    left = res.extra.get("kept_index")
    m_disc = float(mass[int(left[0])]) if left else (float(mass[rows[0][1]]) if rows and rows[0][1] >= 0 else None)
    gate = next(w for w in case.resolved["walls"] if w["name"] == d["gate"])
    top = max(c[1] for w in case.resolved["walls"] for c in (w["from"], w["to"]))
    units = case.resolved.get("units", {}).get("system", "cgs")
    block = {"status": status, "n_initial": len(case.discs), "removed": len(rem), "removed_by_hand": 0,
             "discs_out_at_1s": sum(1 for t in rem if t <= 1.0 + 1e-12),
             "duration": case.duration, "t_open": round(case.settle / case.dt) * case.dt,
             "flow_rate_mass": q, "flow_rate_discs": q / m_disc if q is not None and m_disc else None,
             "flow_rate_note": "slope of cumulative removed mass [" + ("kg/s per m" if units == "si" else "g/s per cm")
                               + "] from the 5th removal on (least squares)",
             "jammed": jam_at is not None, "jam_at": jam_at, "jams": jams,
             "jam_note": "read off the removal log: the code ran on to the end (no stop, no keystone removed)",
             "pattern": fl["pattern"],
             "surface_sink_time": {"left_wall": fl["sink"][0], "centre": fl["sink"][1], "right_wall": fl["sink"][2]},
             "pattern_note": "funnel: the top surface first sinks (by one mean radius) at a wall column; piping: "
                             "first at the centre column (from the code's disc frames every series_interval)",
             "moved_fraction_end": fl["moved_fraction_end"], "dead_fraction_end": 1.0 - fl["moved_fraction_end"],
             "gate": d["gate"], "slit": [min(gate["from"][0], gate["to"][0]), max(gate["from"][0], gate["to"][0])],
             "outlet_y": outlet_y(case.resolved), "outlet_depth": d["outlet_depth"], "settle": case.settle,
             "fill_top": float(np.max(frames[0].y)) if frames and len(frames[0].y) else None, "top": top,
             "snapshots": snaps, "width": f.x_right - f.x_left,
             "gravity": float(np.linalg.norm(case.resolved["gravity"])),
             "ratio_note": "max over the bins (static >= 1/4 of the wall's largest) of peak / static normal force; "
                           "windowed: moving average over peak_window"}
    block.update(peak_ratios(case, res, d.get("peak_window")))
    block["walls"] = wall_ratios(case, res)
    return block


def summary(case: Case, res: Result, code: str, np_: int, scene: Path, walls: list[dict],
            rows: np.ndarray, ids: np.ndarray) -> dict:
    r = case.resolved
    gvec = np.array(r["gravity"], float)
    g = float(np.linalg.norm(gvec))
    gh = gvec / g if g > 0 else np.zeros(2)
    mass = _masses(case)
    weight = float(mass[ids].sum() * g)
    vertical = float(sum(np.dot(w["force"], gh) for w in walls))
    groups: dict = {}
    for w in walls:
        G = groups.setdefault(w["group"], {"normal_total": 0.0, "shear_total": 0.0, "force": [0.0, 0.0]})
        G["normal_total"] += w["normal_total"]
        G["shear_total"] += w["shear_total"]
        G["force"] = [G["force"][0] + w["force"][0], G["force"][1] + w["force"][1]]
    xs = [c[0] for w in walls for c in (w["from"], w["to"])]
    ys = [c[1] for w in walls for c in (w["from"], w["to"])]
    steps = int(res.steps)
    n0 = len(case.discs)
    # discs x steps summed over the steps: every disc until its removal
    settle_steps = round(case.settle / case.dt) if case.mode == "discharge" else 0
    psteps = n0 * steps - sum(max(0, steps - settle_steps - round(t / case.dt)) for t in res.removals)
    wall_s = float(res.wall_time_s)
    status = "end_time"
    if case.mode == "discharge":
        status = "emptied" if len(rows) == 0 else "discharged"
    absent = {
        "contacts.csv, contacts.vtu": "the codes' contact lists are not read back",
        "rest": REST_NOTE,
        "derived, stability": "the engine's pair table and dt bounds are not computed for a reference code",
        "points[].force": f"{code} counts a contact on a slit end in the end bin of the wall ending there",
        "options.skin, options.cell, neighbor_rebuilds, neighbor_patches": f"{code}'s own neighbour lists",
    }
    if not any(w["profile"]["contacts"] is not None for w in walls):
        absent["walls[].contacts, wall_profiles.csv contacts (-1)"] = f"{code}'s wall forces come without contact counts"
    if case.mode == "discharge":
        absent["snapshots/contacts_NNNN, discharge_contacts.pvd"] = "the codes' contact lists are not read back"
        absent["flow_series.csv arch_discs, arch_crown_y"] = \
            "the arch runs over overlapping discs of the code's frames (its pair forces are not read back)"
        if code == "lammps":
            absent["removals.csv vx, vy (nan)"] = ("LAMMPS's outlet log is a count of removals; each removal's disc "
                                                   "is the one gone from the frames, the lowest first")
        elif code == "yade":
            absent["removals.csv vx, vy (nan)"] = "YADE's outlet log gives each removal's time and disc"
    s = {
        "engine": f"{code} {res.version}".strip(),
        "engine_name": code, "engine_version": res.version,
        "translated_by": "compare/codes/reference_run.py (the shared law of the comparison layer)",
        "np": np_, "ranks": np_ if code != "yade" else 1, "threads": np_ if code == "yade" else 1,
        "scene": {"name": r.get("name", scene.stem), "file": str(scene), "description": r.get("description", "")},
        "status": status,
        "status_note": REST_NOTE if case.mode == "static" else
        "the gate opened after the settling time; the run lasts discharge.time (jams are read off the removal log)",
        "options": {"scheme": SCHEME[code], "dt": case.dt, "dt_forced": False, "threads": 1,
                    **{k: r["contact"][k] for k in ("normal_spring", "no_tension", "friction_cap", "lever_arm")},
                    "gravity": gvec.tolist(), "skin": None, "cell": None, "profile_bin": case.profile_bin,
                    "law": "the shared law (compare/cases/common.py SHARED_VARIANT), whatever the scene's [contact]"},
        "n_discs": int(len(rows)), "steps": steps, "time": steps * case.dt,
        "wall_time_s": wall_s, "particle_steps": psteps,
        "particle_steps_per_s": psteps / wall_s if wall_s > 0 else None,
        "neighbor_rebuilds": None, "neighbor_patches": None,
        "rest": {"reached": None, "time": None, "criterion": REST_NOTE, "mean_abs_du": None,
                 "mean_abs_dv": None, "threshold": None},
        "weight": weight, "disc_weight": float(mass[0] * g) if len(mass) else 0.0,
        "height": (max(ys) - min(ys)) if ys else 0.0, "width": (max(xs) - min(xs)) if xs else 0.0,
        "walls": walls,
        "points": [{"name": p["name"], "group": p["group"], "at": list(p["at"]), "force": None, "contacts": None}
                   for p in r["points"]],
        "groups": groups,
        "balance": {"weight": weight, "walls_vertical": vertical,
                    "residual_relative": abs(weight - vertical) / weight if weight > 0 else 0.0,
                    "note": "weight of all discs against the vertical load on the walls (slit ends folded in)"},
        "derived": [],
        "stability": {k: None for k in ("dt_bound", "limited_by", "dt_single_contact", "dt_rotation_z4",
                                        "dt_rotation_z6", "dt_clusters", "cluster_shapes",
                                        "clusters_not_examined")},
        "absent": absent,
        "kinetic_energy_end": res.kinetic_energy_end,
    }
    return s


def write_outputs(out: Path, case: Case, res: Result, code: str, np_: int, scene: Path,
                  frames: list[Snapshot] | None = None) -> dict:
    rows, ids = disc_rows(case, res)
    walls, prof_rows = wall_entries(case, res)
    write_text_atomic(out / "wall_profiles.csv",
                      "wall,group,bin,s_lo,s_hi,x_mid,y_mid,depth_mid,normal,shear,contacts\n"
                      + "".join(r + "\n" for r in prof_rows))
    write_discs(out, case, rows, ids)
    s = summary(case, res, code, np_, scene, walls, rows, ids)
    if case.mode == "discharge":
        s["discharge"] = discharge_block(case, res, out, frames or [], s["status"], [w["name"] for w in walls])
    write_text_atomic(out / "summary.json", json.dumps(s, indent=1, default=_json) + "\n")
    return s


def _json(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o))


# ------------------------------------------------------------------------------- command line

def _withdraw_member(start: str) -> None:
    """A refused ensemble member (dem ensemble --member K --engine) leaves nothing: the start and
    member.json that `dem ensemble` put into its folder go, and the folder when that empties it."""
    folder = Path(start).parent
    for f in (Path(start), folder / "member.json"):
        f.unlink(missing_ok=True)
    try:
        folder.rmdir()
    except OSError:
        pass


def main(argv=None) -> int:
    status = _main(argv)
    if status == EXIT_BAD and _MEMBER_START:
        _withdraw_member(_MEMBER_START[0])
    return status


_MEMBER_START: list[str] = []   # the --member-start of this process's run


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="dem run SCENE.toml --engine CODE",
                                 description="Run a scene in a reference code; write the engine's run folder.")
    ap.add_argument("scene")
    ap.add_argument("--engine", required=True, choices=CODES)
    ap.add_argument("--np", type=int, default=1, help="MPI ranks (LIGGGHTS, LAMMPS) or threads (YADE -j)")
    ap.add_argument("--out", required=True)
    ap.add_argument("--settle", type=float, default=0.0,
                    help="[s] discharge: settling before the gate opens (default: the comparison's 1 s)")
    ap.add_argument("--timeout", type=float, default=3600.0, help="[s] wall-clock limit of the program (exit 4)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="one value of the scene changed, as dem run --set (repeatable)")
    ap.add_argument("--member-start", default="",
                    help="CSV x,y of each disc's start, in the scene's order (dem ensemble --member K --engine: "
                         "the member's perturbed start)")
    ap.add_argument("--quiet", action="store_true")
    ap.add_argument("--pictures", action="store_true",
                    help="also draw the run's pictures into OUT (python3 -m dem.compare.figures run OUT), as dem run --pictures")
    return ap


def _unstable_summary(out: Path, case, res, code: str, np_: int) -> None:
    """What a run that blew up still tells: the scene's walls and discs, no loads (non-strict readers)."""
    walls, _top = _wall_geometry(case)
    g = float(np.linalg.norm(case.resolved["gravity"]))
    write_text_atomic(out / "summary.json", json.dumps(
        {"engine": f"{code} {res.version}".strip(), "engine_name": code, "status": "unstable",
         "reason": res.reason, "np": np_, "n_discs": len(case.discs), "steps": res.steps or None,
         "disc_weight": float(_masses(case)[0] * g) if len(case.discs) else 0.0,
         "walls": [{k: w[k] for k in ("name", "group", "from", "to")} for w in walls]},
        indent=1, default=_json) + "\n")


def _pictures(out: Path, code: str, quiet: bool) -> int:
    """--pictures: python3 -m dem.compare.figures run OUT; 0, or the failure's exit status."""
    drawn = subprocess.run([sys.executable, "-m", "dem.compare.figures", "run", str(out)] + (["--quiet"] if quiet else []),
                           capture_output=True, text=True)
    sys.stderr.write(drawn.stderr)
    if drawn.returncode != 0:
        return _fail_exit(code, f"--pictures: the pictures were not drawn: {drawn.stderr.strip()}", EXIT_FAILED)
    sys.stdout.write(drawn.stdout)
    return 0


def _main(argv=None) -> int:
    ap = _parser()
    try:
        a = ap.parse_args(argv)
    except SystemExit as e:
        return 0 if e.code == 0 else EXIT_BAD
    code = a.engine
    if a.member_start and Path(a.member_start).name == "member_start.csv" and \
            (Path(a.member_start).parent / "member.json").is_file():
        _MEMBER_START[:] = [a.member_start]
    if a.np < 1 or a.timeout <= 0 or a.settle < 0:
        return _fail_exit(code, "--np needs an integer >= 1, --timeout a number > 0, --settle >= 0", EXIT_BAD)
    scene = Path(a.scene).resolve()
    if not scene.is_file():
        return _fail_exit(code, f"{a.scene}: no such scene file", EXIT_BAD)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            changed = with_set(scene, a.set, Path(tmp))
            case = make_case(changed, a.settle)
            note = law_note(code, resolve(changed)["contact"])
    except (PlanError, CaseError) as e:
        return _fail_exit(code, str(e), EXIT_BAD)
    except FileNotFoundError as e:      # no engine binary to resolve the scene with
        return _fail_exit(code, str(e), EXIT_FAILED)
    try:
        if a.member_start:
            case = member_start(case, Path(a.member_start))
        run_case = mutated(case, os.environ.get(MUTANT_ENV, ""))
    except CaseError as e:
        return _fail_exit(code, str(e), EXIT_BAD)
    if run_case is not case:
        sys.stderr.write(f"dem run --engine {code}: {MUTANT_ENV}={os.environ[MUTANT_ENV]}: a deliberately wrong "
                         "translation (testing)\n")
    be = backend(code)
    with tempfile.TemporaryDirectory() as tmp:
        try:
            be.write_inputs(run_case, Path(tmp))
        except CaseError as e:
            return _fail_exit(code, f"{scene}: {code} cannot express it: {e}", EXIT_BAD)
    if not be.available():
        return _fail_exit(code, f"{code} is not installed", EXIT_FAILED)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if not a.quiet:
        print(note, flush=True)
    write_text_atomic(out / "run.log", f"dem run {scene} --engine {code} --np {a.np}\n{note}\n")
    res = be.run(run_case, out / code, timeout=a.timeout, threads=a.np)
    if not res.ok:
        status = classify(res.reason)
        if status == EXIT_UNSTABLE:
            _unstable_summary(out, case, res, code, a.np)
        return _fail_exit(code, f"{'unstable run' if status == EXIT_UNSTABLE else 'the run failed'}: "
                                f"{res.reason} (program files in {out / code})", status)
    frames = []
    if case.mode == "discharge":
        try:
            frames = be.read_snapshots(run_case, out / code)
        except (OSError, ValueError, KeyError) as e:
            return _fail_exit(code, f"the run failed: its disc frames cannot be read: {e} (program files in "
                                    f"{out / code})", EXIT_FAILED)
        if not frames or abs(frames[0].t) > 0.5 * case.dt:
            return _fail_exit(code, f"the run failed: no disc frame at the opening (program files in {out / code})",
                              EXIT_FAILED)
    s = write_outputs(out, case, res, code, a.np, scene, frames)
    if run_case is not case:      # the folder says so
        s["mutant"] = os.environ[MUTANT_ENV]
        write_text_atomic(out / "summary.json", json.dumps(s, indent=1, default=_json) + "\n")
    if not a.quiet:
        print(f"{code}: {s['status']} at t = {s['time']:.6g} s, {s['steps']} steps, {s['n_discs']} discs, "
              f"{s['wall_time_s']:.3g} s wall; outputs in {out} (pictures: python3 -m dem.compare.figures run {out})")
    return _pictures(out, code, a.quiet) if a.pictures else 0


if __name__ == "__main__":
    raise SystemExit(main())

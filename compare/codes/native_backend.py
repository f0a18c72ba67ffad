"""The native engine as one of the compared codes: a Case becomes a scene (written by
dem.compare.io.scene_toml) with the case's packing as a disc file, ``build/dem run`` runs it, and its
run directory (read by dem.compare.io.run_dir, every key docs/outputs.md promises checked) becomes the
common Result form.

The engine reports the slit ends (scene points L, R) apart from the walls; the reader folds a
point's force into the end bin of the wall that ends there (the opened gate excluded), which is
where LIGGGHTS (a mesh edge) and YADE (a facet vertex) count it (common.fold_points).

A shear case (``case.mode == "shear"``, compare/cases/shear.py) becomes a scene with the case's
``[shear_box]`` (the engine builds its walls and plate), ``[shear]`` and ``[clusters]``, the case's
discs as the disc file, the compression to rest for at most ``case.settle`` (``[end]``); the
engine's shear outputs are read into ``Result.extra["shear"]`` (dem.compare.cases.shear.read_outputs).

Particle snapshots (``read_snapshots``): the engine writes them only during a discharge
(``discharge.snapshots`` times: ``snapshots/discs_NNNN.vtu`` indexed by
``discharge_discs.pvd``, docs/outputs.md); a static run writes only the final ``discs.vtu``,
which is then the one snapshot. Both are VTU files read with meshio.
"""
from __future__ import annotations

import csv
import subprocess
import time
from pathlib import Path

import meshio
import numpy as np

from dem.compare.cases.common import (Case, CaseError, Result, Snapshot, dem_binary, failed, fold_points,
                     kinetic_energy)
from dem.compare.io.atomic_file import write_text as write_text_atomic
from dem.compare.io.run_dir import RunDir, RunDirError, read_pvd
from dem.compare.io.scene_toml import dumps
from dem.compare.cases import shear

NAME = "native"


def available() -> bool:
    try:
        dem_binary()
        return True
    except FileNotFoundError:
        return False


def version() -> str:
    p = subprocess.run([str(dem_binary()), "--help"], capture_output=True, text=True)
    first = (p.stdout or "").splitlines()[0] if p.stdout else "dem"
    return first.split(" - ")[0].strip()


def law_doc(case: Case) -> dict:
    """The tables every case's scene starts with: name, gravity, Verlet at the case's dt, the
    contact options, the materials and the pairs' constants."""
    r = case.resolved
    return {"scene": {"name": case.name},
            "physics": {"gravity": list(r["gravity"])},
            "integrator": {"scheme": "velocity_verlet", "dt": case.dt},
            "contact": dict(r["contact"]),
            "materials": {m["name"]: ({"density": m["density"]} if m["density"] > 0 else {})
                          for m in r["materials"]},
            "pairs": [{"materials": list(p["materials"]), **{k: p[k] for k in ("kn", "ks", "eta_n", "eta_s", "mu")}}
                      for p in r["pairs"]]}


def wall_entry(w: dict) -> dict:
    """A resolved wall as a scene's [[walls]] entry, with its prescribed translation if it has one."""
    e = {k: w[k] for k in ("name", "group", "from", "to", "material")}
    if w.get("motion"):   # a prescribed translation, from the run's start
        m = w["motion"]
        e.update(velocity=list(m["velocity"]), move_from=m["from"], move_until=m["until"])
    return e


def scene_doc(case: Case, disc_file: str) -> tuple[dict, dict]:
    """The scene (dict) that makes ``dem run`` run the case (walls and points listed
    explicitly), and the comments of its lines."""
    r = case.resolved
    mat = case.disc_materials()[0]      # each disc's own is the packing's material column
    doc = dict(law_doc(case),
               walls=[wall_entry(w) for w in r["walls"]],
               points=[{k: p[k] for k in ("name", "group", "at", "material")} for p in r["points"]])
    if not doc["walls"]:
        del doc["walls"]
    if not doc["points"]:
        del doc["points"]
    # The frozen packing rested with overlaps; a scene that starts from a packing allows its own.
    overlap = max(0.05, float(r.get("fill", {}).get("max_initial_overlap", 0.0)))
    doc["fill"] = {"type": "file", "file": disc_file, "material": mat, "velocities": True,
                   "max_initial_overlap": overlap}
    doc["end"] = {"time": case.settle if case.mode == "discharge" else case.duration, "stop_at_rest": False,
                  "max_overlap": r["end"]["max_overlap"]}
    doc["neighbor"] = {"skin": r["neighbor"]["skin"]}
    doc["output"] = {"profile_bin": case.profile_bin, "progress": False}
    comments = {"fill.max_initial_overlap": "the frozen packing rested with overlaps"}
    if case.mode == "discharge":
        d = r["discharge"]
        if len(case.snapshot_times()) > 10_000:
            raise CaseError("snapshot_interval: more than the engine's 1e4 discharge.snapshots")
        doc["discharge"] = {"time": case.duration, "gate": d["gate"], "outlet_depth": d["outlet_depth"],
                            "jam_time": case.duration + 1.0, "series_interval": case.series_interval,
                            "snapshots": case.snapshot_times()}
        comments["discharge.jam_time"] = "never stop: jams are judged from removals"
    return doc, comments


def scene_toml(case: Case, disc_file: str) -> str:
    """The scene file's text (scene_doc, or shear_scene_doc for a shear case, written by
    dem.compare.io.scene_toml)."""
    doc, comments = shear_scene_doc(case, disc_file) if case.mode == "shear" else scene_doc(case, disc_file)
    try:
        return dumps(doc, comments=comments,
                     header=f"Generated by compare/codes/native_backend.py for the comparison case {case.name}.")
    except (TypeError, ValueError) as e:
        raise CaseError(f"scene of {case.name}: {e}") from None


def shear_scene_doc(case: Case, disc_file: str) -> tuple[dict, dict]:
    """A shear case's scene: the shared law, velocity Verlet at the case's dt, the box for the
    case's discs, the compression to rest for at most case.settle, the shear, the clusters as
    bonds (the engine has no other cluster model: ``clusters = "clumps"`` is refused)."""
    r = case.resolved
    if not shear.is_shear(r):
        raise CaseError("mode shear: the scene has no [shear_box] with [shear]")
    if case.clusters != "bonds":
        raise CaseError(f"clusters: the engine's clusters are elastic bonds; {case.clusters!r} is YADE's alone")
    b = shear.box(r, case.discs)
    mat = case.disc_materials()[0]
    doc = dict(law_doc(case),
               shear_box={k: b[k] for k in ("width", "height", "wall_length", "wall_material", "plate_material",
                                            "plate_volume", "plate_density", "plate_gap", "plate_overhang",
                                            "plate_horizontal")},
               shear={k: r["shear"][k] for k in ("rate", "max_strain", "sample_strain", "snapshots")})
    if "clusters" in r:
        c = r["clusters"]
        doc["clusters"] = {"bonds": c["bonds"], "touch_tolerance": c["touch_tolerance"], "members": c["members"]}
    doc["fill"] = {"type": "file", "file": disc_file, "material": mat, "velocities": True,
                   "max_initial_overlap": float(r.get("fill", {}).get("max_initial_overlap", 0.0))}
    doc["end"] = {"time": case.settle, "stop_at_rest": True, "rest_factor": r["end"]["rest_factor"],
                  "max_overlap": r["end"]["max_overlap"]}
    doc["neighbor"] = {"skin": r["neighbor"]["skin"]}
    doc["output"] = {"profile_bin": case.profile_bin, "progress": False}
    return doc, {"end.time": "the compression to rest, at most"}


def write_inputs(case: Case, out_dir: Path, threads: int = 1) -> Path:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with open(out_dir / "packing.csv", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["x", "y", "r", "vx", "vy", "omega", "material"])
        for row, name in zip(case.discs, case.material_names()):
            w.writerow([repr(float(v)) for v in row] + [name])
    scene = out_dir / "scene.toml"
    write_text_atomic(scene, scene_toml(case, "packing.csv"))
    return scene


def run(case: Case, out_dir: Path, timeout: float = 600, threads: int = 1) -> Result:
    out_dir = Path(out_dir)
    try:
        scene = write_inputs(case, out_dir)
    except CaseError as e:
        return failed(NAME, case.name, f"translation: {e}")
    cmd = [str(dem_binary()), "run", str(scene), "--out", str(out_dir / "run"), "--quiet"]
    t0 = time.monotonic()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return failed(NAME, case.name, f"timed out after {timeout:.0f} s", out_dir=str(out_dir))
    wall = time.monotonic() - t0
    (out_dir / "dem.log").write_text(p.stdout + p.stderr)
    if p.returncode != 0:
        tail = (p.stderr.strip().splitlines() or ["(no message)"])[-1]
        why = {2: "bad input", 3: "unstable run"}.get(p.returncode, "crashed")
        return failed(NAME, case.name, f"dem exited with {p.returncode} ({why}): {tail}", out_dir=str(out_dir),
                      wall_time_s=wall)
    res = read(case, out_dir)
    res.wall_time_s = wall
    return res


def _profiles(summary: dict) -> dict:
    out = {}
    for w in summary["walls"]:
        p = w["profile"]
        out[w["name"]] = {"s_lo": p["s_lo"], "s_hi": p["s_hi"], "normal": p["normal"], "shear": p["shear"],
                          "contacts": p["contacts"]}
    return out


def read(case: Case, out_dir: Path) -> Result:
    rd = RunDir(Path(out_dir) / "run", strict=True)
    try:
        summary = rd.summary
        discs = rd.discs()
        if case.mode == "discharge":
            removals = rd.removals() if rd.has("removals.csv") else None
            wall_series = rd.wall_series() if rd.has("wall_series.csv") else None
            totals = rd.wall_totals_series() if rd.has("wall_totals_series.csv") else None
    except RunDirError as e:
        return failed(NAME, case.name, f"run directory: {e}", out_dir=str(out_dir))
    res = Result(code=NAME, case=case.name, version=summary["engine"], out_dir=str(out_dir))
    res.steps = int(summary["steps"])
    res.n_initial = len(case.discs)
    res.profiles = _profiles(summary)
    folds = _folds(case)
    for pt in summary["points"]:
        _fold(res.profiles, folds, pt["name"], pt["force"])
    order = np.argsort(discs["id"])
    d = {k: v[order] for k, v in discs.items()}
    res.discs_end = np.column_stack([d["x"], d["y"], d["r"], d["vx"], d["vy"], d["omega"]]).tolist()
    res.n_final = len(d["id"])
    res.kinetic_energy_end = kinetic_energy(case.resolved, np.array(res.discs_end, float).reshape(-1, 6),
                                            case.material_index()[d["id"]])
    status = summary["status"]
    if status == "unstable":
        return failed(NAME, case.name, f"unstable: {summary.get('reason', '')}", out_dir=str(out_dir))
    if case.mode == "shear":
        if status != "sheared":
            return failed(NAME, case.name, f"shear: status {status!r}: {summary.get('reason', '')}",
                          out_dir=str(out_dir))
        res.extra["shear"] = shear.read_outputs(rd.path)
    if case.mode == "discharge":
        if removals is not None:
            res.removals = [float(t) for t, how in zip(removals["t"], removals["how"]) if how == "outlet"]
        res.series = _wall_series(wall_series, res.profiles)
        _fold_series(res.series, folds, totals)
        res.extra["native_discharge"] = summary.get("discharge", {})
    return res


def _folds(case: Case) -> dict:
    r = case.resolved
    gate = [r["discharge"]["gate"]] if case.mode == "discharge" else []
    return fold_points(r["walls"], r["points"], case.centre, exclude=gate)


def _fold(profiles: dict, folds: dict, point: str, force, k: int | None = None) -> None:
    """Adds a point's force (by the discs on it) to the end bin of its wall (profile, or sample k
    of a series)."""
    if point not in folds or not (force[0] or force[1]):
        return
    wall, end, n, t = folds[point]
    prof = profiles[wall]
    nrm, shr = (prof["normal"], prof["shear"]) if k is None else (prof["normal"][k], prof["shear"][k])
    b = 0 if end == "from" else len(nrm) - 1
    f = np.array(force, float)
    nrm[b] += -float(f @ n)
    shr[b] += float(f @ t)


def _fold_series(series: dict, folds: dict, totals: dict | None) -> None:
    """The points' rows of wall_totals_series.csv folded into the wall series (same times)."""
    if not series or not folds or totals is None:
        return
    index = {t: k for k, t in enumerate(series["t"])}
    for name, t, fx, fy in zip(totals["name"], totals["t"], totals["fx"], totals["fy"]):
        if name in folds and float(t) in index:
            _fold(series["walls"], folds, name, (float(fx), float(fy)), index[float(t)])


def _wall_series(rows: dict | None, profiles: dict) -> dict:
    """wall_series.csv's columns (t, wall, bin, ..., normal, shear) -> the common series form."""
    if rows is None:
        return {}
    times = np.unique(rows["t"])
    series = {"t": times.tolist(), "walls": {}}
    tindex = {t: k for k, t in enumerate(times)}
    for name, prof in profiles.items():
        nb = len(prof["normal"])
        nrm = np.zeros((len(times), nb))
        shr = np.zeros((len(times), nb))
        sel = rows["wall"] == name
        for t, b, fn, fs in zip(rows["t"][sel], rows["bin"][sel], rows["normal"][sel], rows["shear"][sel]):
            k, b = tindex[t], int(b)
            if b < nb:
                nrm[k, b] = fn
                shr[k, b] = fs
        series["walls"][name] = {"normal": nrm.tolist(), "shear": shr.tolist()}
    return series


def _read_disc_vtu(path: Path, t: float) -> Snapshot:
    m = meshio.read(str(path))          # the engine's VTU: Float64 points, full precision
    pd = m.point_data
    vel = np.asarray(pd["velocity"], float).reshape(-1, 3)
    return Snapshot.from_columns(t, pd["id"], x=m.points[:, 0], y=m.points[:, 1], r=pd["radius"],
                                 vx=vel[:, 0], vy=vel[:, 1], omega=pd["omega"])


def read_snapshots(case: Case, out_dir: Path) -> list[Snapshot]:
    """Particle snapshots in the common form (times since the opening of a discharge).

    Discharge: the files ``discharge_discs.pvd`` lists (a ParaView collection, which
    dem.compare.io.run_dir.read_pvd parses; each VTU it names is read with meshio). Static: the engine
    writes no snapshots during the run, only the final ``discs.vtu`` (t = the case's duration)."""
    rd = RunDir(Path(out_dir) / "run")
    if case.mode != "discharge":
        return [_read_disc_vtu(rd.file("discs.vtu"), case.duration)]
    if not rd.has("discharge_discs.pvd"):
        return []
    out = [_read_disc_vtu(rd.file(name), t) for t, name in read_pvd(rd.file("discharge_discs.pvd"))]
    return sorted(out, key=lambda s: s.t)

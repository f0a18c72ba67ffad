"""LIGGGHTS 3.8.0 as a compared code: translator (data file, STL wall strips written with
meshio, input script), runner (serial or ``mpirun -np N``) and reader.

What the translation does (docs/compare.md gives the measured facts):
- true 2D: ``dimension 2``, ``boundary f f p``, z in [-2, 2], ``fix enforce2d``;
- materials: one atom type per disc material of the case (1..nd, in the order of the resolved
  materials) and one per wall material (nd+1..: the ``type`` of each wall's mesh fix); the
  ``property/global ... peratomtypepair`` matrices of kn, kt, gamman_abs, gammat_abs and
  coefficientFriction hold every disc-disc and disc-wall pair of the scene (a missing one is a
  CaseError naming ``pairs`` and both materials); wall-wall entries never act. A scene point is
  the mesh edge of the walls ending there, so it must have their material;
- discs: each of its material's type and density; with ``dimension 2`` LIGGGHTS sets mass =
  density x pi r^2 (checked: a disc resting on the floor loads it with exactly rho pi r^2 g,
  and the probe reads each type's mass back), the engine's mass per 1 cm;
  ``fix nve/sphere`` in 2D gives the disc inertia m r^2 / 2 (checked by the calibration runs);
- law: ``hooke/stiffness``, ``tangential history``, ``absolute_damping on`` (eta absolute),
  ``limitForce on`` (total normal force clamped >= 0): the engine's SHARED_VARIANT
  (e_n = K_n overlap, no_tension = total, Coulomb cap on the total normal force; the shear
  force and the contact's rotational velocity at the contact radius r - overlap/2, disc-disc and
  disc-wall: lever_arm = contact_point);
- walls: every wall segment is a mesh of strips (2 triangles each, z = +-2, at most
  profile_bin / 2 long, aligned with the profile bins from the wall's ``from`` end); the strip
  forces (``mesh/surface/stress``, dumped with ``dump mesh/vtk``) give the binned profile;
- the slit ends L and R are mesh edges, which LIGGGHTS treats as point contacts; their force
  lands on the strip that owns the edge (the engine reports points apart: the comparison folds
  them into the neighbouring bin);
- particle snapshots (``Case.snapshot_interval``): ``dump custom/vtk`` to ``snap_STEP.vtu``
  (XML UnstructuredGrid, read with meshio in ``read_snapshots``); its points are Float32, so the
  positions are also dumped as per-atom variables (Float64 point data);
- moving walls (a scene's walls[].velocity): ``fix move/mesh linear/variable`` moves the wall's
  mesh at the prescribed velocity during the steps of its window (whole steps of dt:
  common.motion_steps); the wall/gran contacts see the mesh's velocity and keep their history;
- discharge: the gate mesh jumps 200 cm down in one step at the opening (same run: a new
  ``run`` would recompute forces without history updates); discs crossing the outlet plane
  ``outlet_depth`` below the gate (common.outlet_y, the engine's rule) are deleted by
  ``massflow/mesh`` and logged with their time.

What LIGGGHTS cannot express exactly: the paper's incremental normal spring and its no-tension
rule on the elastic force (eqs. 7a, 8), and the Coulomb cap on the elastic normal force (eq.
13): the comparison runs use the shared variant in every code. Walls are meshes, so a wall's
end acts as a point contact where the engine has explicit points.
"""
from __future__ import annotations

import glob
import math
import re
import subprocess
import sys
from pathlib import Path
from shutil import which

import meshio  # STL meshes and VTU snapshots; the POLYDATA mesh dumps (meshio reads none) are parsed here
import numpy as np

from dem.compare.cases.common import (mpi_prefix, run_translated, outlet_y, SHARED_VARIANT, Case, CaseError, Result, Snapshot, bin_edges, failed,
                     motion_steps, moved_wall,
                     inward_normal, kinetic_energy, pair, tangent)
from dem.compare.io.atomic_file import write_text as write_text_atomic
from dem.compare.cases import shear

NAME = "liggghts"
Z_HALF = 2.0          # [cm] half thickness of the periodic z slab
BOX_BELOW = 220.0     # [cm] room below the floor for the opened gate and the falling discs


def available() -> bool:
    return which("liggghts") is not None


def version() -> str:
    try:
        # -log none: no log.liggghts in the caller's folder (dem run --engine runs from anywhere)
        p = subprocess.run(["liggghts", "-log", "none", "-h"], capture_output=True, text=True, timeout=30)
        m = re.search(r"LIGGGHTS \(?([^\n]*?Version[^\n]*)", p.stdout) or re.search(r"(LIGGGHTS[^\n]*)", p.stdout)
        return m.group(1).strip() if m else "liggghts (version not printed)"
    except (OSError, subprocess.TimeoutExpired):
        return "liggghts (not runnable)"


def _check_variant(case: Case) -> None:
    c = case.resolved["contact"]
    if c != SHARED_VARIANT:
        raise CaseError(f"contact: LIGGGHTS expresses only {SHARED_VARIANT}, the case asks for {c}")


def _strips(wall: dict, profile_bin: float):
    """Strip ends along the wall, at most profile_bin / 2 long, bins' edges included."""
    a, b = np.array(wall["from"], float), np.array(wall["to"], float)
    length = float(np.linalg.norm(b - a))
    edges = bin_edges(wall, profile_bin)
    s = [0.0]
    for lo, hi in zip(edges[:-1], edges[1:]):
        n = max(1, int(math.ceil((hi - lo) / min(1.6, profile_bin / 2) - 1e-9)))
        s += [lo + (hi - lo) * (k + 1) / n for k in range(n)]
    s[-1] = length
    return a, (b - a) / length, np.array(s)


def write_wall_stl(wall: dict, profile_bin: float, path: Path) -> int:
    """A wall segment as strips of 2 triangles spanning z = -Z_HALF..Z_HALF (ASCII STL)."""
    a, t, s = _strips(wall, profile_bin)
    pts, tris = [], []
    for k in range(len(s)):
        p = a + s[k] * t
        pts += [[p[0], p[1], -Z_HALF], [p[0], p[1], Z_HALF]]
    for k in range(len(s) - 1):
        i = 2 * k
        tris += [[i, i + 2, i + 3], [i, i + 3, i + 1]]
    meshio.write(str(path), meshio.Mesh(np.array(pts), [("triangle", np.array(tris))]), file_format="stl",
                 binary=False)
    return len(tris)


def wall_materials(case: Case) -> list[str]:
    """Materials of the active walls, sorted; a point (a mesh edge here) must have the material of
    every wall ending at it."""
    r = case.resolved
    walls = [w for w in r["walls"] if w.get("active", True)]
    for p in r["points"]:
        for w in walls:
            if any(math.hypot(e[0] - p["at"][0], e[1] - p["at"][1]) <= 1e-9 for e in (w["from"], w["to"])) \
                    and w["material"] != p["material"]:
                raise CaseError(f"points: {p['name']} has material {p['material']!r} but wall {w['name']!r} ending "
                                f"there has {w['material']!r}; LIGGGHTS makes the point from the wall mesh's edge")
    return sorted({w["material"] for w in walls})


def atom_types(case: Case) -> dict:
    """Atom type of each material: the case's disc materials 1..nd (in the order of the resolved
    materials), then the wall materials nd+1.. (the ``type`` of each wall's mesh fix)."""
    discs = case.disc_materials()
    names = discs + [w for w in wall_materials(case) if w not in discs]
    return {name: k + 1 for k, name in enumerate(names)}


def _matrix(case: Case, key: str) -> str:
    """The ``peratomtypepair`` matrix of ``key`` (row-major, complete and symmetric): each disc-disc
    and disc-wall entry from the scene's pairs (CaseError naming both materials when a pair is
    missing); wall-wall entries never act and repeat the first disc material's pair with the
    lower-typed of the two wall materials (symmetric)."""
    r = case.resolved
    first = case.disc_materials()[0]
    discs = set(case.disc_materials())
    types = atom_types(case)
    names = sorted(types, key=types.get)
    vals = []
    for a in names:
        for b in names:
            lo = a if types[a] <= types[b] else b
            vals.append(pair(r, a, b)[key] if a in discs or b in discs else pair(r, first, lo)[key])
    return " ".join(repr(float(v)) for v in vals)


def _wall_names(case: Case):
    return [w["name"] for w in case.resolved["walls"] if w.get("active", True)]


def _mesh_id(name: str) -> str:
    return "w_" + re.sub(r"[^A-Za-z0-9_]", "_", name)


def write_inputs(case: Case, out_dir: Path, threads: int = 1) -> Path:
    """Writes discs.data, one STL per wall (and the outlet), and in.liggghts into out_dir."""
    if case.mode == "shear" or "clusters" in case.resolved:
        raise CaseError(shear.liggghts_refusal(case.resolved))
    _check_variant(case)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    r = case.resolved
    d = np.asarray(case.discs, float)
    if d.ndim != 2 or d.shape[1] != 6 or not np.all(np.isfinite(d)) or np.any(d[:, 2] <= 0):
        raise CaseError("discs: need finite rows x, y, r > 0, vx, vy, omega")
    walls = [w for w in r["walls"] if w.get("active", True)]
    for w in walls:
        if w.get("motion"):
            motion_steps(w, case.dt)       # refuses a window that is not whole steps
    reach = walls + [moved_wall(w, case.end_time) for w in walls if w.get("motion")]   # where they end up too
    xs = [c for w in reach for c in (w["from"][0], w["to"][0])] + [p["at"][0] for p in r["points"]]
    ys = [c for w in reach for c in (w["from"][1], w["to"][1])] + [p["at"][1] for p in r["points"]]
    types = atom_types(case)
    rho = {m["name"]: float(m["density"]) for m in r["materials"]}
    rmax = float(d[:, 2].max())
    xlo = min(xs + list(d[:, 0])) - 4 * rmax
    xhi = max(xs + list(d[:, 0])) + 4 * rmax
    ylo = min(ys + list(d[:, 1])) - 4 * rmax - (BOX_BELOW if case.mode == "discharge" else 0)
    yhi = max(ys + list(d[:, 1])) + 4 * rmax
    lines = ["LIGGGHTS data file written by compare/codes/liggghts_backend.py", "",
             f"{len(d)} atoms", f"{len(types)} atom types", "",
             f"{xlo!r} {xhi!r} xlo xhi", f"{ylo!r} {yhi!r} ylo yhi", f"{-Z_HALF!r} {Z_HALF!r} zlo zhi", "",
             "Atoms", ""]
    # atom_style granular: id type diameter density x y z; in 2D mass = density pi r^2, each disc
    # with its own material's type and density.
    for k, ((x, y, rad, *_v), name) in enumerate(zip(d, case.material_names())):
        lines.append(f"{k + 1} {types[name]} {2 * rad!r} {rho[name]!r} {x!r} {y!r} 0.0")
    lines += ["", "Velocities", ""]
    for k, (_x, _y, _r, vx, vy, om) in enumerate(d):
        lines.append(f"{k + 1} {vx!r} {vy!r} 0.0 0.0 0.0 {om!r}")
    write_text_atomic(out_dir / "discs.data", "\n".join(lines) + "\n")

    meshes = []
    for w in walls:
        mid = _mesh_id(w["name"])
        write_wall_stl(w, case.profile_bin, out_dir / f"{mid}.stl")
        meshes.append((mid, types[w["material"]]))
    if case.mode == "discharge":  # the outlet plane spans the box (inside it by 1e-3 cm)
        write_outlet_stl(out_dir, xlo + 1e-3, xhi - 1e-3, outlet_y(r))
    script = _script(case, meshes, xlo, xhi, threads)
    path = out_dir / "in.liggghts"
    write_text_atomic(path, script)
    return path


def _script(case: Case, meshes: list[tuple[str, int]], xlo: float, xhi: float, threads: int) -> str:
    r = case.resolved
    g = np.array(r["gravity"], float)
    gmag = float(np.linalg.norm(g))
    dt = case.dt
    sample = max(1, int(round(case.series_interval / dt)))
    settle_steps = int(round(case.settle / dt)) if case.mode == "discharge" else 0
    run_steps = int(round(case.duration / dt))
    total = settle_steps + run_steps
    skin = float(r["neighbor"]["skin"]) or 0.2
    law = "model hooke/stiffness tangential history absolute_damping on limitForce on"
    nt = len(atom_types(case))
    wall_type = max([t for _m, t in meshes], default=nt)   # the outlet (no contacts): any wall type
    s = [f"# LIGGGHTS input for the comparison case {case.name}; generated by compare/codes/liggghts_backend.py.",
         "# Units cgs; forces per 1 cm of thickness. Do not edit: regenerate.",
         "echo none", "atom_style granular", "atom_modify map array", "dimension 2",
         "boundary f f p", "newton off", "communicate single vel yes", "units cgs",
         "read_data discs.data",
         f"neighbor {skin!r} bin", "neigh_modify delay 0",
         f"pair_style gran {law}", "pair_coeff * *",
         f"fix m_kn all property/global kn peratomtypepair {nt} {_matrix(case, 'kn')}",
         f"fix m_kt all property/global kt peratomtypepair {nt} {_matrix(case, 'ks')}",
         f"fix m_gn all property/global gamman_abs peratomtypepair {nt} {_matrix(case, 'eta_n')}",
         f"fix m_gt all property/global gammat_abs peratomtypepair {nt} {_matrix(case, 'eta_s')}",
         f"fix m_mu all property/global coefficientFriction peratomtypepair {nt} {_matrix(case, 'mu')}",
         f"timestep {dt!r}"]
    if gmag > 0:
        s.append(f"fix gravi all gravity {gmag!r} vector {g[0] / gmag!r} {g[1] / gmag!r} 0.0")
    for mid, t in meshes:
        s.append(f"fix {mid} all mesh/surface/stress file {mid}.stl type {t}")
    gate = _mesh_id(r["discharge"]["gate"]) if case.mode == "discharge" else None
    if meshes:
        s.append(f"fix walls all wall/gran model hooke/stiffness tangential history mesh n_meshes {len(meshes)} "
                 f"meshes {' '.join(m for m, _t in meshes)} absolute_damping on limitForce on")
    if case.mode == "discharge":
        s += [f"fix outlet all mesh/surface/planar file outlet.stl type {wall_type}",
              "fix mf all massflow/mesh mesh outlet vec_side 0 -1 0 count once delete_atoms yes "
              "file removals.txt writeTime screen no",
              # The gate jumps 200 cm down during the first step after settling (same run).
              f"variable gate_v equal (step=={settle_steps})*{-200.0 / dt!r}",
              "variable zero equal 0.0",
              f"fix gate_move all move/mesh mesh {gate} linear/variable v_zero v_gate_v v_zero"]
    moving = [w for w in r["walls"] if w.get("active", True) and w.get("motion")]
    if moving and case.mode != "discharge":
        s.append("variable zero equal 0.0")
    for w in moving:
        # The step that takes the run from (n - 1) dt to n dt has step == n: the window's steps
        # are from < step <= until (in steps).
        mid = _mesh_id(w["name"])
        k0, k1 = motion_steps(w, dt)
        vx, vy = (float(v) for v in w["motion"]["velocity"])
        s += [f"variable {mid}_vx equal (step>{k0})*(step<={k1})*{vx!r}",
              f"variable {mid}_vy equal (step>{k0})*(step<={k1})*{vy!r}",
              f"fix {mid}_move all move/mesh mesh {mid} linear/variable v_{mid}_vx v_{mid}_vy v_zero"]
    s += ["fix integr all nve/sphere", "fix e2d all enforce2d",
          "compute rke all erotate/sphere",
          "thermo_style custom step time atoms ke c_rke",
          # discharge deletes discs at the outlet; anywhere else a lost disc is an error
          f"thermo_modify lost {'ignore' if case.mode == 'discharge' else 'error'} norm no",
          f"thermo {sample}"]
    for mid, _t in meshes:
        s.append(f"dump d_{mid} all mesh/vtk {sample} mesh_{mid}_*.vtk output face stresscomponents area {mid}")
    snap = case.snapshot_steps()
    if snap:
        # custom/vtk writes the points as Float32: the positions again as Float64 point data
        s += ["variable snap_x atom x", "variable snap_y atom y",
              f"dump d_snap all custom/vtk {snap} snap_*.vtu id x y radius vx vy omegaz v_snap_x v_snap_y",
              "dump_modify d_snap binary yes"]
        if settle_steps:  # from the opening on: next dump step = opening + a whole number of intervals
            s += [f'variable snap_next equal "(step<{settle_steps})*{settle_steps}+(step>={settle_steps})*'
                  f'({settle_steps}+{snap}*(floor((step-{settle_steps})/{snap})+1))"',
                  "dump_modify d_snap every v_snap_next"]
    s += [f"dump d_end all custom {total} discs_*.dump id x y radius vx vy omegaz",
          "dump_modify d_end format \"%d %.17g %.17g %.17g %.17g %.17g %.17g\" sort id",
          f"run {total}"]
    return "\n".join(s) + "\n"


def write_outlet_stl(out_dir: Path, xlo: float, xhi: float, y: float) -> None:
    """The outlet plane at height y as strips at most 2 Z_HALF wide (2 triangles each, smallest
    angle >= 45 deg). Two triangles spanning the whole box are rejected by LIGGGHTS once the box is
    wider than ~900 cm ("Fix mesh: Bad mesh": smallest angle below the 0.256 deg curvature limit)."""
    n = max(1, int(math.ceil((xhi - xlo) / (2 * Z_HALF) - 1e-9)))
    xs = np.linspace(xlo, xhi, n + 1)
    pts = np.array([[x, y, z] for x in xs for z in (-Z_HALF, Z_HALF)])
    # strip k: corners 2k (x_k, -Z), 2k+2 (x_k+1, -Z), 2k+3 (x_k+1, Z), 2k+1 (x_k, Z); normal -y as before
    tris = np.array([t for k in range(n) for t in ([2 * k, 2 * k + 2, 2 * k + 3], [2 * k, 2 * k + 3, 2 * k + 1])])
    meshio.write(str(out_dir / "outlet.stl"), meshio.Mesh(pts, [("triangle", tris)]), file_format="stl",
                 binary=False)


def command(script: Path, ranks: int = 1) -> list[str]:
    # stdbuf -o0: LIGGGHTS prints its ERROR lines to the screen without flushing before MPI_Abort;
    # with stdout buffered into a file they are lost and the log ends in a bare MPI_ABORT.
    return ["stdbuf", "-o0"] + mpi_prefix(ranks) + ["liggghts", "-echo", "none", "-in", script.name]


def run(case: Case, out_dir: Path, timeout: float = 600, threads: int = 1) -> Result:
    """Runs the real liggghts (``threads`` > 1: MPI ranks); never raises for a failed run."""
    return run_translated(sys.modules[__name__], case, out_dir, "liggghts.log",
                          ("mesh_*.vtk", "discs_*.dump", "snap_*.vt[ur]"), timeout, threads)


def read_polydata_vtk(path: str) -> tuple[np.ndarray, list[np.ndarray], dict]:
    """Legacy VTK 5.1 ASCII POLYDATA as LIGGGHTS writes it (meshio reads no POLYDATA):
    points, polygons (OFFSETS/CONNECTIVITY), and the FIELD arrays of CELL_DATA."""
    tok = Path(path).read_text().split()
    if "POLYDATA" not in tok[:20]:
        raise ValueError(f"{path}: not a POLYDATA VTK file")
    k = tok.index("POINTS")
    n = int(tok[k + 1])
    pts = np.array(tok[k + 3:k + 3 + 3 * n], float).reshape(n, 3)
    k = tok.index("POLYGONS")
    o = tok.index("OFFSETS", k)
    c = tok.index("CONNECTIVITY", o)
    offsets = np.array(tok[o + 2:c], int)
    nconn = int(offsets[-1])
    conn = np.array(tok[c + 2:c + 2 + nconn], int)
    polys = [conn[a:b] for a, b in zip(offsets[:-1], offsets[1:])]
    fields = {}
    if "CELL_DATA" in tok:
        k = tok.index("CELL_DATA")
        f = tok.index("FIELD", k)
        nf = int(tok[f + 2])
        i = f + 3
        for _ in range(nf):
            name, ncomp, ntup = tok[i], int(tok[i + 1]), int(tok[i + 2])
            i += 4
            fields[name] = np.array(tok[i:i + ncomp * ntup], float).reshape(ntup, ncomp)
            i += ncomp * ntup
    return pts, polys, fields


def _read_mesh_vtk(path: str) -> tuple[np.ndarray, np.ndarray]:
    """Cell centroids and forces (stress x area: force by the discs on the wall) of one dump."""
    pts, polys, data = read_polydata_vtk(path)
    cen = np.array([pts[p].mean(axis=0) for p in polys])
    if "stress" not in data or "area" not in data:
        raise ValueError(f"{path}: no stress/area cell data (has {sorted(data)})")
    return cen, data["stress"][:, :2] * data["area"].reshape(-1)[:, None]


def _bin_forces(wall: dict, case: Case, cen: np.ndarray, force: np.ndarray):
    edges = bin_edges(wall, case.profile_bin)
    a = np.array(wall["from"], float)
    t = tangent(wall)
    n = inward_normal(wall, case.centre)
    s = (cen[:, :2] - a) @ t
    k = np.clip(np.searchsorted(edges, s, side="right") - 1, 0, len(edges) - 2)
    normal = np.bincount(k, weights=-(force @ n), minlength=len(edges) - 1)
    shear = np.bincount(k, weights=force @ t, minlength=len(edges) - 1)
    return edges, normal, shear


def _thermo(text: str) -> list[tuple[int, float, int, float, float]]:
    rows, on = [], False
    for line in text.splitlines():
        f = line.split()
        if f[:4] == ["Step", "Time", "Atoms", "KinEng"]:
            on = True
            continue
        if on:
            try:
                rows.append((int(f[0]), float(f[1]), int(f[2]), float(f[3]), float(f[4])))
            except (ValueError, IndexError):
                on = False
    return rows


def read(case: Case, out_dir: Path) -> Result:
    out_dir = Path(out_dir)
    res = Result(code=NAME, case=case.name, version=version(), out_dir=str(out_dir))
    res.n_initial = len(case.discs)
    text = (out_dir / "liggghts.log").read_text(errors="replace") if (out_dir / "liggghts.log").exists() else ""
    thermo = _thermo(text)
    if not thermo:
        return failed(NAME, case.name, "no thermo output in liggghts.log", out_dir=str(out_dir))
    res.steps = thermo[-1][0]
    ke = np.array([t[3] + t[4] for t in thermo])
    if not np.all(np.isfinite(ke)):
        return failed(NAME, case.name, "non-finite kinetic energy (blow-up)", out_dir=str(out_dir))
    dumps = sorted(glob.glob(str(out_dir / "discs_*.dump")), key=lambda p: int(re.findall(r"(\d+)", p)[-1]))
    if not dumps:
        return failed(NAME, case.name, "missing final disc dump", out_dir=str(out_dir))
    ids, rows = _read_dump(dumps[-1])
    res.discs_end = rows.tolist()
    res.extra["kept_index"] = (ids - 1).tolist()     # rows of the case's start (atom ids from 1)
    res.n_final = len(rows)
    res.kinetic_energy_end = kinetic_energy(case.resolved, rows, case.material_index()[ids - 1])
    if case.mode != "discharge" and res.n_final != res.n_initial:
        return failed(NAME, case.name, f"lost discs: {res.n_initial} at the start, {res.n_final} at the end",
                      out_dir=str(out_dir))
    walls = [w for w in case.resolved["walls"] if w.get("active", True)]
    # Blow-up: a disc outside the walls' box (closed container) or kinetic energy growth.
    if len(rows) and case.mode != "discharge":
        reach = walls + [moved_wall(w, case.end_time) for w in walls if w.get("motion")]
        xs = [c for w in reach for c in (w["from"][0], w["to"][0])]
        ys = [c for w in reach for c in (w["from"][1], w["to"][1])]
        pad = 2 * float(np.max(rows[:, 2]))
        if walls and (np.any(rows[:, 0] < min(xs) - pad) or np.any(rows[:, 0] > max(xs) + pad)
                      or np.any(rows[:, 1] < min(ys) - pad)):
            return failed(NAME, case.name, "discs left the closed container (blow-up)", out_dir=str(out_dir))
    dt = case.dt
    settle_steps = int(round(case.settle / dt)) if case.mode == "discharge" else 0
    series_t, series = [], {w["name"]: {"normal": [], "shear": []} for w in walls}
    for w in walls:
        mid = _mesh_id(w["name"])
        files = sorted(glob.glob(str(out_dir / f"mesh_{mid}_*.vtk")), key=lambda p: int(re.findall(r"(\d+)", p)[-1]))
        if not files:
            return failed(NAME, case.name, f"missing wall-force dumps of {w['name']}", out_dir=str(out_dir))
        steps = []
        for f in files:
            step = int(re.findall(r"(\d+)", f)[-1])
            if step < settle_steps:
                continue
            cen, force = _read_mesh_vtk(f)
            edges, nrm, shr = _bin_forces(moved_wall(w, step * dt), case, cen, force)   # where it was then
            series[w["name"]]["normal"].append(nrm.tolist())
            series[w["name"]]["shear"].append(shr.tolist())
            steps.append(step)
        if not series_t:
            series_t = [(st - settle_steps) * dt for st in steps]
        res.profiles[w["name"]] = {"s_lo": edges[:-1].tolist(), "s_hi": edges[1:].tolist(),
                                   "normal": series[w["name"]]["normal"][-1],
                                   "shear": series[w["name"]]["shear"][-1]}
    res.series = {"t": series_t, "walls": series}
    if case.mode == "discharge":
        res.removals = _removals(out_dir / "removals.txt", settle_steps * dt)
        rem = _removal_rows(out_dir / "removals.txt")
        res.extra["removal_index"] = [int(f[0]) - 1 for f in rem]
        res.extra["removal_velocity"] = [[f[6], f[7]] for f in rem]
    res.extra["ke_max_second_half"] = float(np.max(ke[len(ke) // 2:]))
    return res


def read_snapshots(case: Case, out_dir: Path) -> list[Snapshot]:
    """Particle snapshots in the common form from the ``dump custom/vtk`` files (VTU, read with
    meshio), times since the start (static) or the opening (discharge; dumps while settling are
    left out). Ids: LIGGGHTS atom id - 1 = the row in the case's packing."""
    out_dir = Path(out_dir)
    settle_steps = int(round(case.settle / case.dt)) if case.mode == "discharge" else 0
    out = []
    for f in glob.glob(str(out_dir / "snap_*.vtu")):
        m = re.fullmatch(r"snap_(\d+)\.vtu", Path(f).name)
        if not m or int(m.group(1)) < settle_steps:
            continue
        mesh = meshio.read(f)
        pd = mesh.point_data
        out.append(Snapshot.from_columns((int(m.group(1)) - settle_steps) * case.dt, np.asarray(pd["id"]) - 1,
                                         x=pd["snap_x"], y=pd["snap_y"], r=pd["radius"], vx=pd["vx"],
                                         vy=pd["vy"], omega=pd["omegaz"]))
    return sorted(out, key=lambda s: s.t)


def _read_dump(path: str) -> tuple[np.ndarray, np.ndarray]:
    with open(path) as f:
        lines = f.read().splitlines()
    k = next(i for i, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
    data = np.array([[float(v) for v in l.split()] for l in lines[k + 1:] if l.strip()]).reshape(-1, 7)
    data = data[np.argsort(data[:, 0])]
    return data[:, 0].astype(int), data[:, 1:7]


def _removals(path: Path, t_open: float) -> list[float]:
    """Times (since opening) of the discs the outlet deleted (massflow/mesh file, writeTime)."""
    if not path.exists():
        return []
    out = []
    for line in path.read_text().splitlines():  # "ID time diameter x y z u v w" (writeTime)
        f = line.split()
        if len(f) < 2 or line.lstrip().startswith("#"):
            continue
        out.append(float(f[1]) - t_open)
    return sorted(out)


def _removal_rows(path: Path) -> list[list[float]]:
    """The outlet's log rows (ID time diameter x y z u v w) in the order of their times."""
    if not path.exists():
        return []
    rows = [[float(v) for v in line.split()] for line in path.read_text().splitlines()
            if len(line.split()) >= 9 and not line.lstrip().startswith("#")]
    return sorted(rows, key=lambda f: f[1])

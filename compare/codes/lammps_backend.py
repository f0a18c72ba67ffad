"""LAMMPS (Debian's ``lammps``, binary ``lmp``, GRANULAR package) as a compared code: translator
(data file and input script), runner (serial or ``mpirun -np N``) and reader.

What the translation does:
- true 2D: ``dimension 2``, ``boundary f f p``, z in [-2, 2], ``fix enforce2d``;
- discs: ``atom_style sphere``, one atom type per disc material (1..nd, in the order of the
  resolved materials); ``set type k density/disc rho`` makes each mass rho pi r^2, the engine's
  mass per 1 cm (``read_data`` alone would give the sphere's 4/3 pi r^3 rho), and ``fix nve/sphere
  disc`` integrates with the disc inertia m r^2 / 2 (velocity Verlet); the probe reads both back;
- law: ``pair_style granular`` with, for every pair of disc types, ``hooke kn eta_n tangential
  linear_history kt x mu damping velocity limit_damping``: the normal force kn delta - eta_n v_n
  with a plain dashpot coefficient (``damping velocity``), the total normal force clamped >= 0
  (``limit_damping``: no_tension = total), the Coulomb cap on the total normal force; the
  tangential dashpot is x eta_n, so x = eta_s / eta_n;
- walls, static and collision cases: the active walls lying on one line with the discs on one side
  are one infinite plane, ``region ... plane`` with ``fix wall/gran/region`` (same model words,
  the disc-wall pair's constants), one fix per plane and disc material (a wall fix has one set of
  constants for every atom of its group); ``contacts`` stores each disc's wall force and contact
  point, dumped every sample and binned onto the scene's wall segments as the engine bins them;
- walls, discharge: each wall a block region BLOCK thick on its outer side (``side out``), so that
  its ends are corners acting as point contacts, the slit ends L and R once the gate is open; the
  gate block drops GATE_DROP cm in the first step after settling (``move`` with a step variable,
  the same run: no setup in between); ``fix evaporate`` removes each disc whose centre is below
  ``common.outlet_y``, and ``fix print`` writes the count every step (the removal times);
- particle snapshots (``Case.snapshot_interval``): ``dump custom`` to ``snap_STEP.dump`` at full
  precision, every interval from the start (static) or the opening (discharge), read by
  ``read_snapshots``.

What LAMMPS cannot express, refused before any run (CaseError naming the field):
- static and collision cases: walls whose union on one line has a gap, walls of different
  materials on one line, a disc of the case beyond the end of its plane's walls (the plane would
  act there), and a point that can act (not the joint of two walls on one line: LAMMPS has no
  point contact but a block's corner);
- discharge: a wall neither horizontal nor vertical (a block's faces are axis-aligned; the hopper),
  a point that is not the end of walls of its material;
- a tangential dashpot without a normal one (x eta_n cannot be eta_s > 0 when eta_n = 0);
- the shear box (paper 2's bonds and the free plate), any contact variant but the shared one.

Where the run differs from the shared law (measured by the calibration collisions, docs/compare.md):
- the Coulomb cap holds the TOTAL tangential force (spring + dashpot) at mu F_n, and while capped
  the stored spring is set to mu F_n minus the dashpot; the shared law caps the spring alone and
  switches the dashpot off, so its dashpot acts uncapped at a sliding contact's first touch;
- a contact whose first step (zero history, at a ``run``'s setup only) is already beyond the cap
  gets no tangential force in that step;
- the rotational slip is r omega with the full radii (the shared law: r - overlap/2), and the
  torque arm is r - overlap/2 disc-disc but r disc-wall.
At rest (dashpots idle, the springs below the cap) only the arms differ, by overlap / 2r ~ 1e-3.
"""
from __future__ import annotations

import glob
import math
import re
import subprocess
import sys
from pathlib import Path
from shutil import which

import numpy as np

from dem.compare.cases.common import (mpi_prefix, run_translated, SHARED_VARIANT, Case, CaseError, Result, Snapshot, failed, inward_normal, kinetic_energy, outlet_y, pair,
                     profiles_from_contacts, tangent)
from dem.compare.io.atomic_file import write_text as write_text_atomic

NAME = "lammps"
Z_HALF = 2.0          # [cm] half thickness of the periodic z slab
ON_LINE = 1e-9        # [cm] two walls are on one line (and a point at a joint) within this
BLOCK = 1e-6          # [cm] thickness of a discharge's wall blocks (their corners: the slit ends)
GATE_DROP = 200.0     # [cm] the gate block jumps this far down in the first step after settling


def available() -> bool:
    return which("lmp") is not None


def version() -> str:
    try:
        p = subprocess.run(["lmp", "-h"], capture_output=True, text=True, timeout=30)
        m = re.search(r"Simulator - ([^\n]+)", p.stdout)
        return f"LAMMPS {m.group(1).strip()}" if m else "lammps (version not printed)"
    except (OSError, subprocess.TimeoutExpired):
        return "lammps (not runnable)"


# ------------------------------------------------------------------------------- translation

def planes(case: Case, centre=None) -> list[dict]:
    """The active walls grouped into infinite planes: walls on one line with the discs (centre:
    default the case's) on the same side. Each plane: id, a point, the inward normal n, the
    tangent t, the material, and its walls with their extent (lo, hi) along t from the point.
    CaseError for what a plane cannot express (module text)."""
    r = case.resolved
    centre = case.centre if centre is None else centre
    out = []
    for w in (w for w in r["walls"] if w.get("active", True)):
        a = np.array(w["from"], float)
        n = inward_normal(w, centre) + 0.0          # + 0.0: no -0.0 in the deck
        t = np.array([n[1], -n[0]]) + 0.0
        s = sorted(float(np.dot(np.array(w[e], float) - a, t)) for e in ("from", "to"))
        for p in out:
            if np.allclose(p["n"], n, rtol=0, atol=1e-12) and abs(float(np.dot(a - p["point"], n))) <= ON_LINE:
                if w["material"] != p["material"]:
                    raise CaseError(f"walls: {w['name']!r} ({w['material']}) and {p['walls'][0][0]['name']!r} "
                                    f"({p['material']}) lie on one line; LAMMPS makes one infinite plane of them "
                                    "(fix wall/gran/region, region plane), which has one material")
                off = float(np.dot(a - p["point"], t))
                p["walls"].append((w, s[0] + off, s[1] + off))
                break
        else:
            out.append({"id": f"p{len(out)}", "point": a, "n": n, "t": t, "material": w["material"],
                        "walls": [(w, s[0], s[1])]})
    for p in out:
        p["walls"].sort(key=lambda e: e[1])
        hi = p["walls"][0][2]
        for (w0, _l0, _h0), (w, lo, h) in zip(p["walls"][:-1], p["walls"][1:]):
            if lo > hi + ON_LINE:
                raise CaseError(f"walls: {w0['name']!r} and {w['name']!r} lie on one line with a gap of "
                                f"{lo - hi:.6g} cm between them (an opened slit); LAMMPS's walls are infinite planes "
                                "(fix wall/gran/region, region plane), so the gap cannot be expressed")
            hi = max(hi, h)
        p["lo"], p["hi"] = p["walls"][0][1], hi
        p["region"] = (f"plane {p['point'][0]!r} {p['point'][1]!r} 0.0 {p['n'][0]!r} {p['n'][1]!r} 0.0 side in")
    return out


def blocks(case: Case) -> list[dict]:
    """A discharge's walls, each finite: a block region BLOCK thick on the side away from the discs
    (``side out``: the discs interact with its surface), so that a wall's end is a corner that acts
    as a point contact, as the engine's slit ends L and R do once the gate is open. Each block:
    id, its wall (extent 0..length along the wall's from -> to), point (the ``from`` end), n, t,
    material, region words, and whether it is the gate. CaseError for a wall that is neither
    horizontal nor vertical (a block has axis-aligned faces)."""
    r = case.resolved
    gate = r.get("discharge", {}).get("gate")
    out = []
    for k, w in enumerate(w for w in r["walls"] if w.get("active", True)):
        a, b = np.array(w["from"], float), np.array(w["to"], float)
        t = tangent(w)
        if min(abs(t[0]), abs(t[1])) > 1e-12:
            raise CaseError(f"walls: {w['name']!r} from {w['from']} to {w['to']} is neither horizontal nor vertical; "
                            "a finite LAMMPS wall (what a discharge needs: its slit) is a block region, with "
                            "axis-aligned faces")
        n = inward_normal(w, case.centre) + 0.0
        corners = np.array([a, b, a - BLOCK * n, b - BLOCK * n])
        lo, hi = corners.min(axis=0), corners.max(axis=0)
        out.append({"id": f"b{k}", "walls": [(w, 0.0, float(np.linalg.norm(b - a)))], "point": a, "n": n, "t": t + 0.0,
                    "material": w["material"], "lo": 0.0, "hi": float(np.linalg.norm(b - a)),
                    "region": f"block {lo[0]!r} {hi[0]!r} {lo[1]!r} {hi[1]!r} INF INF side out",
                    "gate": w["name"] == gate})
    for pt in r["points"]:
        at = np.array(pt["at"], float)
        ends = [u["walls"][0][0] for u in out
                if any(np.linalg.norm(np.array(u["walls"][0][0][e], float) - at) <= ON_LINE for e in ("from", "to"))]
        if not ends or any(w["material"] != pt["material"] for w in ends):
            raise CaseError(f"points: {pt['name']} at {pt['at']} is not the end of walls of its material "
                            f"({pt['material']}); LAMMPS makes a point contact only as a block wall's corner")
    return out


def _check_points(case: Case, pls: list[dict]) -> None:
    """A point acts where no wall ending there does; at the joint of two walls of one plane it
    never acts (a disc touching it touches a wall first), anywhere else LAMMPS cannot express it."""
    for pt in case.resolved["points"]:
        at = np.array(pt["at"], float)
        inert = False
        for p in pls:
            ends = [e for w, _lo, _hi in p["walls"] for e in (w["from"], w["to"])
                    if np.linalg.norm(np.array(e, float) - at) <= ON_LINE]
            if len(ends) >= 2:
                inert = True
        if not inert:
            raise CaseError(f"points: {pt['name']} at {pt['at']} can act (it is not the joint of two walls on one "
                            "line); LAMMPS has no point contact (a frozen atom would add its radius to the overlap)")


def _check_reach(case: Case, pls: list[dict], discs: np.ndarray) -> None:
    """Every disc that the plane can reach lies within its walls' extent (the plane would act beyond)."""
    for p in pls:
        for k, (x, y, rad, *_v) in enumerate(discs):
            c = np.array([x, y]) - p["point"]
            s = float(np.dot(c, p["t"]))
            if (s < p["lo"] - ON_LINE or s > p["hi"] + ON_LINE) and float(np.dot(c, p["n"])) < 4 * rad:
                names = ", ".join(repr(w["name"]) for w, _lo, _hi in p["walls"])
                raise CaseError(f"walls: disc {k} at ({x:.6g}, {y:.6g}) is beyond the end of {names} but within reach "
                                "of its line; LAMMPS's wall is the infinite plane (fix wall/gran/region, region plane)")


def _check_case(case: Case) -> None:
    if case.mode == "shear" or "clusters" in case.resolved:
        raise CaseError("shear_box: the LAMMPS backend does not translate paper 2's shear box (its bonds with shear "
                        "springs and the free plate); compare it with --codes native,yade")
    if case.mode == "discharge" and not any(w["name"] == case.resolved["discharge"]["gate"]
                                            for w in case.resolved["walls"] if w.get("active", True)):
        raise CaseError(f"discharge.gate: {case.resolved['discharge']['gate']!r} is not an active wall")
    c = case.resolved["contact"]
    if c != SHARED_VARIANT:
        raise CaseError(f"contact: the LAMMPS translation runs only {SHARED_VARIANT}, the case asks for {c}")


def _coeffs(p: dict, where: str) -> str:
    """The granular model words of one pair: hooke, linear_history, damping velocity, limit_damping."""
    kn, ks, en, es, mu = (float(p[k]) for k in ("kn", "ks", "eta_n", "eta_s", "mu"))
    if es > 0 and not en > 0:
        raise CaseError(f"{where}.eta_s: LAMMPS's tangential dashpot is x eta_n (linear_history's x_gamma_t); "
                        f"eta_n = {en!r} cannot give eta_s = {es!r}")
    x = es / en if en > 0 else 0.0
    return (f"hooke {kn!r} {en!r} tangential linear_history {ks!r} {x!r} {mu!r} "
            "damping velocity limit_damping")


def _fix_id(plane: dict, material: str) -> str:
    return f"w{plane['id']}_{re.sub(r'[^A-Za-z0-9_]', '_', material)}"


def write_inputs(case: Case, out_dir: Path, threads: int = 1, wall_rows: dict | None = None,
                 centre=None) -> Path:
    """Writes discs.data and in.lammps into out_dir. The probe's ``wall_rows``: wall name -> the
    disc rows its plane acts on (default: every disc, each within its planes' extent) and
    ``centre``: the side of the walls the discs are on (default: the case's discs' centre)."""
    _check_case(case)
    r = case.resolved
    d = np.asarray(case.discs, float)
    if d.ndim != 2 or d.shape[1] != 6 or not np.all(np.isfinite(d)) or np.any(d[:, 2] <= 0):
        raise CaseError("discs: need finite rows x, y, r > 0, vx, vy, omega")
    if case.mode == "discharge":
        pls = blocks(case)
    else:
        pls = planes(case, centre)
        _check_points(case, pls)
    if wall_rows is not None:     # by plane
        wall_rows = {p["id"]: [k for w, _lo, _hi in p["walls"] for k in wall_rows.get(w["name"], [])] for p in pls}
    elif case.mode != "discharge":
        _check_reach(case, pls, d)
    mats = case.disc_materials()
    types = {m: k + 1 for k, m in enumerate(mats)}
    names = case.material_names()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    walls = [w for w in r["walls"] if w.get("active", True)]
    xs = [c for w in walls for c in (w["from"][0], w["to"][0])] + list(d[:, 0])
    ys = [c for w in walls for c in (w["from"][1], w["to"][1])] + list(d[:, 1])
    if case.mode == "discharge":       # removed at outlet_y: the box holds every disc until then
        ys.append(outlet_y(r))
    pad = 4 * float(d[:, 2].max())
    lines = ["LAMMPS data file written by compare/codes/lammps_backend.py", "",
             f"{len(d)} atoms", f"{len(mats)} atom types", "",
             f"{min(xs) - pad!r} {max(xs) + pad!r} xlo xhi", f"{min(ys) - pad!r} {max(ys) + pad!r} ylo yhi",
             f"{-Z_HALF!r} {Z_HALF!r} zlo zhi", "", "Atoms # sphere", ""]
    # id type diameter density x y z: the density is overwritten by set density/disc below
    for k, ((x, y, rad, *_v), name) in enumerate(zip(d, names)):
        lines.append(f"{k + 1} {types[name]} {2 * rad!r} 1.0 {x!r} {y!r} 0.0")
    lines += ["", "Velocities", ""]
    for k, (_x, _y, _r, vx, vy, om) in enumerate(d):
        lines.append(f"{k + 1} {vx!r} {vy!r} 0.0 0.0 0.0 {om!r}")
    write_text_atomic(out_dir / "discs.data", "\n".join(lines) + "\n")
    path = out_dir / "in.lammps"
    write_text_atomic(path, _script(case, pls, types, wall_rows))
    return path


def _script(case: Case, pls: list[dict], types: dict, wall_rows: dict | None) -> str:
    r = case.resolved
    rho = {m["name"]: float(m["density"]) for m in r["materials"]}
    g = np.array(r["gravity"], float)
    gmag = float(np.linalg.norm(g))
    dt = case.dt
    sample = max(1, int(round(case.series_interval / dt)))
    settle_steps = int(round(case.settle / dt)) if case.mode == "discharge" else 0
    total = settle_steps + int(round(case.duration / dt))
    skin = float(r["neighbor"]["skin"]) or 0.2
    mats = sorted(types, key=types.get)
    s = [f"# LAMMPS input for the comparison case {case.name}; generated by compare/codes/lammps_backend.py.",
         "# Units cgs; forces per 1 cm of thickness. Do not edit: regenerate.",
         "units cgs", "dimension 2", "atom_style sphere", "atom_modify map array", "boundary f f p",
         "newton off", "comm_modify vel yes", "read_data discs.data"]
    s += [f"set type {types[m]} density/disc {rho[m]!r}" for m in mats]     # mass = rho pi r^2
    s += [f"neighbor {skin!r} bin", "neigh_modify delay 0", "pair_style granular"]
    for i, a in enumerate(mats):
        for b in mats[i:]:
            s.append(f"pair_coeff {types[a]} {types[b]} {_coeffs(pair(r, a, b), f'pairs[{a},{b}]')}")
    s.append(f"timestep {dt!r}")
    if gmag > 0:
        s.append(f"fix gravi all gravity {gmag!r} vector {g[0] / gmag!r} {g[1] / gmag!r} 0.0")
    for m in mats:
        s.append(f"group d_{types[m]} type {types[m]}")
    fixes = []
    if case.mode == "discharge":     # the gate drops out of reach in the first step after settling (same run)
        s += ["variable zero equal 0.0", f"variable gate_dy equal (step>{settle_steps})*{-GATE_DROP!r}"]
    for p in pls:
        move = " move v_zero v_gate_dy NULL" if p.get("gate") else ""
        s.append(f"region r_{p['id']} {p['region']}{move}")
        for m in mats:
            grp = f"d_{types[m]}"
            if wall_rows is not None:       # the probe: this plane acts on its own probe discs only
                rows = [k for k in wall_rows.get(p["id"], []) if case.material_names()[k] == m]
                if not rows:
                    continue
                grp = f"g_{_fix_id(p, m)}"
                s.append(f"group {grp} id {' '.join(str(k + 1) for k in rows)}")
            fid = _fix_id(p, m)
            wname = f"pairs[{m},{p['material']}]"
            s.append(f"fix {fid} {grp} wall/gran/region granular {_coeffs(pair(r, m, p['material']), wname)} "
                     f"region r_{p['id']} contacts")
            fixes.append((fid, grp))
    if case.mode == "discharge":     # removed once the centre is below outlet_y; the count every step
        s += [f"region outlet block INF INF INF {outlet_y(r)!r} INF INF",
              f"fix outlet all evaporate 1 {len(case.discs) + 1} outlet 4242",
              "variable st equal step", "variable nout equal f_outlet",
              'fix removals all print 1 "${st} ${nout}" file removals.txt screen no']
    s += ["fix integr all nve/sphere disc", "fix e2d all enforce2d",
          "thermo_style custom step time atoms ke",
          "thermo_modify lost error norm no flush yes", f"thermo {sample}"]
    for fid, grp in fixes:
        cols = " ".join(f"f_{fid}[{k}]" for k in (1, 2, 3, 5, 6))
        s += [f"dump d_{fid} {grp} custom {sample} wall_{fid}_*.dump id {cols}",
              f"dump_modify d_{fid} format float %.17g thresh f_{fid}[1] > 0"]
    snap = case.snapshot_steps()
    if snap:     # particle snapshots every snap steps from the start, or from the opening on
        s += [f"dump d_snap all custom {snap} snap_*.dump id x y radius vx vy omegaz",
              "dump_modify d_snap format float %.17g sort id"]
        if settle_steps:  # the next dump step: the opening, then the opening + whole intervals
            s += [f'variable snap_next equal "(step<{settle_steps})*{settle_steps}+(step>={settle_steps})*'
                  f'({settle_steps}+{snap}*(floor((step-{settle_steps})/{snap})+1))"',
                  "dump_modify d_snap every v_snap_next"]
    s += [f"dump d_end all custom {total} discs_*.dump id x y radius vx vy omegaz",
          "dump_modify d_end format float %.17g sort id",
          f"run {total}"]
    return "\n".join(s) + "\n"


def command(script: Path, ranks: int = 1) -> list[str]:
    return mpi_prefix(ranks) + ["lmp", "-echo", "none", "-log", "none", "-in", script.name]


def run(case: Case, out_dir: Path, timeout: float = 600, threads: int = 1) -> Result:
    """Runs the real lmp (``threads`` > 1: MPI ranks); never raises for a failed run."""
    return run_translated(sys.modules[__name__], case, out_dir, "lammps.log",
                          ("wall_*.dump", "discs_*.dump", "snap_*.dump"), timeout, threads)


# ------------------------------------------------------------------------------------ reading

def _steps(pattern: str) -> list[tuple[int, str]]:
    return sorted((int(re.findall(r"(\d+)", Path(f).name)[-1]), f) for f in glob.glob(pattern))


def _read_rows(path: str, ncol: int) -> np.ndarray:
    lines = Path(path).read_text().splitlines()
    k = next(i for i, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
    return np.array([[float(v) for v in l.split()] for l in lines[k + 1:] if l.strip()], float).reshape(-1, ncol)


def _thermo(text: str) -> list[tuple[int, float, int, float]]:
    rows, on = [], False
    for line in text.splitlines():
        f = line.split()
        if f[:4] == ["Step", "Time", "Atoms", "KinEng"]:
            on = True
            continue
        if on:
            try:
                rows.append((int(f[0]), float(f[1]), int(f[2]), float(f[3])))
            except (ValueError, IndexError):
                on = False
    return rows


def read(case: Case, out_dir: Path) -> Result:
    out_dir = Path(out_dir)
    res = Result(code=NAME, case=case.name, version=version(), out_dir=str(out_dir))
    res.n_initial = len(case.discs)
    text = (out_dir / "lammps.log").read_text(errors="replace") if (out_dir / "lammps.log").exists() else ""
    thermo = _thermo(text)
    if not thermo:
        return failed(NAME, case.name, "no thermo output in lammps.log", out_dir=str(out_dir))
    res.steps = thermo[-1][0]
    if not all(math.isfinite(t[3]) for t in thermo):
        return failed(NAME, case.name, "non-finite kinetic energy (blow-up)", out_dir=str(out_dir))
    dumps = _steps(str(out_dir / "discs_*.dump"))
    if not dumps:
        return failed(NAME, case.name, "missing final disc dump", out_dir=str(out_dir))
    data = _read_rows(dumps[-1][1], 7)
    data = data[np.argsort(data[:, 0])]
    ids, rows = data[:, 0].astype(int), data[:, 1:7]
    res.discs_end = rows.tolist()
    res.extra["kept_index"] = (ids - 1).tolist()     # rows of the case's start (atom ids from 1)
    res.n_final = len(rows)
    res.kinetic_energy_end = kinetic_energy(case.resolved, rows, case.material_index()[ids - 1])
    settle_steps = int(round(case.settle / case.dt)) if case.mode == "discharge" else 0
    if case.mode == "discharge":
        pls = blocks(case)
        res.removals = _removals(out_dir / "removals.txt", settle_steps, case.dt)
        if res.n_final + len(res.removals) != res.n_initial:
            return failed(NAME, case.name, f"lost discs: {res.n_initial} at the start, {len(res.removals)} removed, "
                          f"{res.n_final} at the end", out_dir=str(out_dir))
    else:
        if res.n_final != res.n_initial:
            return failed(NAME, case.name, f"lost discs: {res.n_initial} at the start, {res.n_final} at the end",
                          out_dir=str(out_dir))
        pls = planes(case)
        try:
            _check_reach(case, pls, rows)
        except CaseError as e:
            return failed(NAME, case.name, f"at the end: {e}", out_dir=str(out_dir))
    walls = [w for w in case.resolved["walls"] if w.get("active", True)]
    mats = case.disc_materials()
    per_step: dict[int, list] = {}
    for p in pls:
        for m in mats:
            for step, f in _steps(str(out_dir / f"wall_{_fix_id(p, m)}_*.dump")):
                if step < settle_steps:
                    continue
                per_step.setdefault(step, [])
                for _id, _flag, fx, fy, px, py in _read_rows(f, 6):
                    s = float(np.dot(np.array([px, py]) - p["point"], p["t"]))
                    # the wall segment holding the contact point (the first one at a joint)
                    w = next((w for w, lo, hi in p["walls"] if lo - ON_LINE <= s <= hi + ON_LINE), None)
                    if w is not None:       # force BY THE DISC ON THE WALL: minus the fix's force on the disc
                        per_step[step].append((w["name"], px, py, -fx, -fy))
    if not per_step:
        return failed(NAME, case.name, "missing wall-contact dumps", out_dir=str(out_dir))
    series = {w["name"]: {"normal": [], "shear": []} for w in walls}
    steps = sorted(per_step)
    prof = {}
    for step in steps:
        prof = profiles_from_contacts(walls, case.profile_bin, case.centre, per_step[step])
        for w in walls:
            series[w["name"]]["normal"].append(prof[w["name"]]["normal"])
            series[w["name"]]["shear"].append(prof[w["name"]]["shear"])
    res.profiles = {k: {q: v[q] for q in ("s_lo", "s_hi", "normal", "shear")} for k, v in prof.items()}
    res.series = {"t": [(st - settle_steps) * case.dt for st in steps], "walls": series}
    ke = [t[3] for t in thermo]
    res.extra["ke_max_second_half"] = float(np.max(ke[len(ke) // 2:]))
    return res


def _removals(path: Path, settle_steps: int, dt: float) -> list[float]:
    """Times (since the opening) of the discs the outlet removed, from the count printed every step."""
    out, last = [], 0
    if path.exists():
        for line in path.read_text().splitlines():
            f = line.split()
            if len(f) != 2 or line.startswith("#"):
                continue
            step, count = int(f[0]), int(float(f[1]))
            out += [(step - settle_steps) * dt] * (count - last)
            last = count
    return out


def read_snapshots(case: Case, out_dir: Path) -> list[Snapshot]:
    """Particle snapshots in the common form from the ``dump custom`` files (``snap_STEP.dump``,
    full precision), times since the start (static) or the opening (discharge; dumps while settling
    are left out). Ids: LAMMPS atom id - 1 = the row in the case's packing."""
    settle_steps = int(round(case.settle / case.dt)) if case.mode == "discharge" else 0
    out = []
    for step, f in _steps(str(Path(out_dir) / "snap_*.dump")):
        if step < settle_steps:
            continue
        d = _read_rows(f, 7)
        out.append(Snapshot.from_columns((step - settle_steps) * case.dt, d[:, 0].astype(int) - 1, x=d[:, 1],
                                         y=d[:, 2], r=d[:, 3], vx=d[:, 4], vy=d[:, 5], omega=d[:, 6]))
    return out

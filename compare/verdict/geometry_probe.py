"""Each code's geometry, read back from the code itself after its setup, against the case.

``probe(code, case, out_dir, timeout)`` runs the backend's own translation of the case (its
``write_inputs``, with probe discs appended where walls are read through contacts) for zero
steps and reads back what the code built:

- discs: every case disc's radius and start position (x, y, z) as the code holds them;
- LIGGGHTS (``run 0``): the atoms dumped with ``%.17g``; each wall mesh through
  ``compute wall/gran/local pos id``: the mesh point nearest to a probe disc, which LIGGGHTS
  computes from the triangles it holds (its mesh dumps print 6 digits, too few for 1e-9). One
  probe disc outside the container at the middle of every strip reads the face, one beyond each
  end reads the end edge (the mesh's end: a scene point is a mesh end, so the points are the
  ends read at them);
- YADE: the translated script's own ``setup()``, then each wall's facet vertices (``state.pos``
  + ``state.ori`` x ``shape.vertices``), each disc's ``state.pos`` and ``shape.radius``; the
  points are the facet ends that the script's guard lets act as point contacts;
- LAMMPS (``run 0``): the atoms dumped with ``%.17g``; a wall is an infinite plane (``region
  plane``), whose position LAMMPS prints nowhere: it is read through two probe discs on each
  plane, beyond its walls' ends, as the contact point that ``fix wall/gran/region ... contacts``
  stores (the nearest point of the plane); LAMMPS has no point contact (a static scene's points
  are joints of one plane), so no point is read.

``expected_geometry(case)`` gives the same from the case (its resolved walls and points, its
discs) and the length scale L: the diagonal of the box holding the walls, points and discs.
``compare_geometry`` lists each item's deviation / L against 1e-9.
"""
from __future__ import annotations

import dataclasses
import json
import math
import re
import time
from pathlib import Path

import numpy as np

from dem.compare.codes import lammps_backend, liggghts_backend, yade_backend
from dem.compare.io.atomic_file import write_text as write_text_atomic
from dem.compare.cases.common import Case, CaseError, inward_normal
from dem.compare.verdict.probe import OVERLAP, _main_radius, _run, run_yade

CODES = ("liggghts", "yade", "lammps")
REL = 1e-9            # deviation / the scene's length scale
ON_END = 1e-9         # [cm] a wall end at a point (the backends' rule)


# ---------------------------------------------------------------------------------------------
# What the case says, and the comparison
def _active(resolved: dict) -> list[dict]:
    return [w for w in resolved["walls"] if w.get("active", True)]


def length_scale(resolved: dict, discs) -> float:
    """Diagonal of the box holding the active walls, the points and the discs (x +- r, y +- r)."""
    d = np.asarray(discs, float).reshape(-1, 6)
    xs = [e[0] for w in _active(resolved) for e in (w["from"], w["to"])] + [p["at"][0] for p in resolved["points"]]
    ys = [e[1] for w in _active(resolved) for e in (w["from"], w["to"])] + [p["at"][1] for p in resolved["points"]]
    xs += list(d[:, 0] - d[:, 2]) + list(d[:, 0] + d[:, 2])
    ys += list(d[:, 1] - d[:, 2]) + list(d[:, 1] + d[:, 2])
    return float(math.hypot(max(xs) - min(xs), max(ys) - min(ys)))


def expected_geometry(case: Case) -> dict:
    """The case's active walls (from, to), points and discs (x, y, r), and its length scale."""
    r = case.resolved
    return {"walls": {w["name"]: {"from": [float(v) for v in w["from"]], "to": [float(v) for v in w["to"]]}
                      for w in _active(r)},
            "points": {p["name"]: [float(v) for v in p["at"]] for p in r["points"]},
            "discs": [[float(v) for v in row[:3]] for row in np.asarray(case.discs, float)],
            "length": length_scale(r, case.discs)}


def _dist(a, b) -> float:
    """Distance of two points; a third coordinate (z) of either counts against 0."""
    a, b = list(a) + [0.0] * (3 - len(a)), list(b) + [0.0] * (3 - len(b))
    return float(math.dist(a, b))


def _seg_dist(p, a, b) -> float:
    """Distance of point p (z counting) from the segment a-b at z = 0."""
    p3 = np.array(list(p) + [0.0] * (3 - len(p)), float)
    a3, b3 = np.array(list(a) + [0.0], float), np.array(list(b) + [0.0], float)
    t = b3 - a3
    u = float(np.clip(np.dot(p3 - a3, t) / np.dot(t, t), 0.0, 1.0))
    return float(np.linalg.norm(p3 - (a3 + u * t)))


def _line_dist(p, a, b) -> float:
    """Distance of point p from the infinite line through a and b (in the plane)."""
    a, b, p = (np.asarray(v, float)[:2] for v in (a, b, p))
    t = (b - a) / np.linalg.norm(b - a)
    d = p - a
    return float(abs(d[0] * t[1] - d[1] * t[0]))


def _wall_rows(name: str, e: dict, got) -> list[tuple[str, float, str]]:
    """(item, deviation, note) of one wall: its ends (either order: a reversed segment is the same
    wall), the face points read on it, or, for a plane, its ends' distance from the code's line."""
    if got is None:
        return [(f"walls[{name}]", math.inf, "not read back")]
    if "line" in got:
        a, b = got["line"]
        return [(f"walls[{name}].{end} (plane)", _line_dist(e[end], a, b), "distance from the code's plane")
                for end in ("from", "to")]
    rows = []
    ends = [got.get("from"), got.get("to")]
    if None in ends:
        rows += [(f"walls[{name}].{k}", math.inf, "not read back") for k, v in zip(("from", "to"), ends) if v is None]
    else:
        straight = (_dist(ends[0], e["from"]), _dist(ends[1], e["to"]))
        swapped = (_dist(ends[1], e["from"]), _dist(ends[0], e["to"]))
        best = straight if max(straight) <= max(swapped) else swapped
        rows += [(f"walls[{name}].from", best[0], ""), (f"walls[{name}].to", best[1], "")]
    if got.get("face"):
        dev = [_seg_dist(p, e["from"], e["to"]) for p in got["face"]]
        k = int(np.argmax(dev))
        rows.append((f"walls[{name}].face", dev[k], f"worst of {len(dev)} face points: {got['face'][k]}"))
    return rows


def compare_geometry(expected: dict, read: dict, rel: float = REL) -> list[dict]:
    """One row per item: {item, deviation [length], rel (deviation / L), pass, note}. Items: each
    wall's ends (or its distance from the code's plane) and face, each point (unless the code has
    none: read["points"] None), the discs' count, worst position and worst radius. What the code
    did not give back fails; so does a wall the case has not."""
    L = float(expected["length"])
    out = []
    walls = read.get("walls", {})
    for name, e in expected["walls"].items():
        out += _wall_rows(name, e, walls.get(name))
    out += [(f"walls[{name}]", math.inf, "the code has a wall the case has not") for name in walls
            if name not in expected["walls"]]
    if read.get("points") is not None:
        for name, at in expected["points"].items():
            got = read["points"].get(name)
            out.append((f"points[{name}]", math.inf if got is None else _dist(got, at),
                        "no point of the code there" if got is None else ""))
    want, got = expected["discs"], read.get("discs")
    if got is None or len(got) != len(want):
        out.append(("discs", math.inf, f"{'no' if got is None else len(got)} discs read back, {len(want)} in the case"))
    elif want:
        pos = [_dist(g[:-1], w[:2]) for g, w in zip(got, want)]
        rad = [abs(g[-1] - w[2]) for g, w in zip(got, want)]
        for what, dev in (("position", pos), ("radius", rad)):
            k = int(np.argmax(dev))
            out.append((f"discs[{k}].{what}", dev[k], f"worst of {len(dev)}"))
    return [{"item": item, "deviation": d, "rel": d / L, "pass": bool(d / L <= rel), "note": note}
            for item, d, note in out]


def summary(rows: list[dict]) -> dict:
    """The worst row's rel and item (infinite first), and the failing items."""
    worst = max(rows, key=lambda r: r["rel"]) if rows else {"rel": math.inf, "item": "-"}
    return {"items": len(rows), "max_rel_diff": worst["rel"], "worst": worst["item"],
            "failing": [r["item"] for r in rows if not r["pass"]]}


# ---------------------------------------------------------------------------------------------
# The run: the backend's translation of the case with probe discs appended, zero steps
ROLES = "geometry_roles.json"
ATOMS_DUMP = "geom_atoms_0.dump"


def _probe_case(case: Case, rows: list) -> Case:
    """The case with probe discs (rows x, y, r, 0, 0, 0, the first disc material) after its own
    discs, static, one step long (the runs stop after setup); one name for every case, so that
    the inputs' bytes (the cache key) depend on what is translated only."""
    idx = case.material_index()
    d = np.asarray(case.discs, float)
    if rows:
        d = np.vstack([d, np.asarray(rows, float)])
        idx = np.concatenate([idx, np.full(len(rows), min(idx.tolist()), int)])
    return dataclasses.replace(case, name="geometry", discs=d, materials=idx, mode="static", settle=0.0,
                               duration=case.dt, series_interval=case.dt, snapshot_interval=0.0)


def _keep(script: str) -> list[str]:
    """The backend's script without its dumps and its run."""
    return [l for l in script.splitlines() if not re.match(r"\s*(dump|dump_modify|run)\s", l)]


def _liggghts_probes(case: Case) -> tuple[list, list]:
    """Probe discs outside the container (away from the case's discs), overlapping each wall's mesh
    by OVERLAP r: one at the middle of every strip (the face) and one beyond each end, on the
    diagonal outwards (the end edge is its nearest mesh point)."""
    r0 = _main_radius(case.discs)
    gap = r0 * (1 - OVERLAP)
    rows, roles = [], []
    for w in _active(case.resolved):
        a, t, s = liggghts_backend._strips(w, case.profile_bin)
        n = inward_normal(w, case.centre)
        for k in range(len(s) - 1):
            c = a + 0.5 * (s[k] + s[k + 1]) * t - gap * n
            rows.append([c[0], c[1], r0, 0.0, 0.0, 0.0])
            roles.append((w["name"], "face"))
        for end, out in (("from", -t), ("to", t)):
            c = np.asarray(w[end], float) + gap * (out - n) / math.sqrt(2.0)
            rows.append([c[0], c[1], r0, 0.0, 0.0, 0.0])
            roles.append((w["name"], end))
    return rows, roles


def _write_liggghts(case: Case, out_dir: Path) -> Path:
    rows, roles = _liggghts_probes(case)
    script = liggghts_backend.write_inputs(_probe_case(case, rows), out_dir)
    s = _keep(script.read_text())
    if roles:
        s += ["compute geom_walls all wall/gran/local pos id",
              "dump geom_walls all local 1 geom_walls_*.dump " + " ".join(f"c_geom_walls[{k}]" for k in range(1, 10)),
              'dump_modify geom_walls format "' + " ".join(["%.17g"] * 9) + '"']
    s += ["dump geom_atoms all custom 1 geom_atoms_*.dump id x y z radius",
          'dump_modify geom_atoms format "%d %.17g %.17g %.17g %.17g" sort id', "run 0"]
    write_text_atomic(out_dir / "in.geometry", "\n".join(s) + "\n")
    write_text_atomic(out_dir / ROLES, json.dumps({"n": len(case.discs), "roles": roles}) + "\n")
    return out_dir / "in.geometry"


def _lammps_probes(case: Case) -> tuple[list, dict, list]:
    """Two probe discs on each plane, beyond its walls' ends by 3 r (the plane is infinite and
    acts on its own probe discs only), overlapping it by OVERLAP r."""
    r0 = _main_radius(case.discs)
    gap = r0 * (1 - OVERLAP)
    n_case = len(case.discs)
    rows, wall_rows, planes = [], {}, []
    for p in lammps_backend.planes(case):
        ks = []
        for s in (p["lo"] - 3 * r0, p["hi"] + 3 * r0):
            c = p["point"] + s * p["t"] + gap * p["n"]
            rows.append([c[0], c[1], r0, 0.0, 0.0, 0.0])
            ks.append(n_case + len(rows) - 1)
        wall_rows[p["walls"][0][0]["name"]] = ks
        planes.append({"id": p["id"], "material": p["material"], "rows": ks,
                       "walls": [w["name"] for w, _lo, _hi in p["walls"]]})
    return rows, wall_rows, planes


def _write_lammps(case: Case, out_dir: Path) -> Path:
    rows, wall_rows, planes = _lammps_probes(case)
    pc = _probe_case(case, rows)
    script = lammps_backend.write_inputs(pc, out_dir, wall_rows=wall_rows, centre=case.centre)
    s = _keep(script.read_text())
    m0 = pc.material_names()[-1] if rows else None
    for p in planes:
        fid = lammps_backend._fix_id(p, m0)
        p["fix"] = fid
        s += [f"dump geom_{fid} g_{fid} custom 1 geom_{fid}_*.dump id f_{fid}[1] f_{fid}[5] f_{fid}[6] f_{fid}[7]",
              f"dump_modify geom_{fid} format float %.17g sort id"]
    s += ["dump geom_atoms all custom 1 geom_atoms_*.dump id x y z radius",
          "dump_modify geom_atoms format float %.17g sort id", "run 0"]
    write_text_atomic(out_dir / "in.geometry", "\n".join(s) + "\n")
    write_text_atomic(out_dir / ROLES, json.dumps({"n": len(case.discs), "planes": planes}) + "\n")
    return out_dir / "in.geometry"


_YADE_GEOMETRY = '''# The geometry YADE built: the translated case's own setup (yade_script.py), no step, then the
# facets, the discs and the guard's point ends. Run as `yade -n -j1 -x yade_geometry.py`.
import json
_src = open("yade_script.py").read()
globals()["__name__"] = "yade_case_script"
exec(compile(_src, "yade_script.py", "exec"), globals())
globals()["__name__"] = "__main__"
setup()


def _at(b, v):
    p = b.state.pos + b.state.ori * v
    return [p[0], p[1], p[2]]


_out = {"walls": {}, "discs": [], "not_points": [[P[0], P[1]] for P, is_point, _ws in S["guarded"] if not is_point]}
for _w in S["walls"]:
    _b = O.bodies[_w["id"]]
    _out["walls"][_w["name"]] = [_at(_b, _v) for _v in _b.shape.vertices]
for _i in S["disc_ids"]:
    _b = O.bodies[_i]
    _out["discs"].append([_b.state.pos[0], _b.state.pos[1], _b.state.pos[2], _b.shape.radius])
with open("yade_geometry.json", "w") as _f:
    json.dump(_out, _f)
'''


def _write_yade(case: Case, out_dir: Path) -> Path:
    yade_backend.write_inputs(_probe_case(case, []), out_dir)
    write_text_atomic(out_dir / "yade_geometry.py", _YADE_GEOMETRY)
    return out_dir / "yade_geometry.py"


def write_inputs(code: str, case: Case, out_dir: Path) -> Path:
    """Every file the geometry run of ``code`` uses, written into out_dir; returns its script."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    writers = {"liggghts": _write_liggghts, "lammps": _write_lammps, "yade": _write_yade}
    if code not in writers:
        raise ValueError(f"code: {code!r} is not one of {CODES}")
    return writers[code](case, out_dir)


# ---------------------------------------------------------------------------------------------
# Reading what the code built
def _dump_rows(path: Path) -> np.ndarray:
    """The rows after ``ITEM: ATOMS`` or ``ITEM: ENTRIES`` of a LAMMPS/LIGGGHTS dump."""
    lines = path.read_text().splitlines()
    k = next(i for i, l in enumerate(lines) if l.startswith(("ITEM: ATOMS", "ITEM: ENTRIES")))
    rows = [[float(v) for v in l.split()] for l in lines[k + 1:] if l.strip()]
    return np.array(rows, float).reshape(len(rows), -1)


def _case_discs(out_dir: Path, n: int) -> list:
    """The case's discs (atom ids 1..n) as dumped: x, y, z, r."""
    a = _dump_rows(out_dir / ATOMS_DUMP)
    a = a[a[:, 0] <= n]
    return [[float(v) for v in row[1:5]] for row in a[np.argsort(a[:, 0])]]


def _end_points(walls: dict, expected_walls: dict, points: dict) -> dict:
    """Each scene point as the code has it: the read ends of the walls ending there (the one
    farthest from the point); a point where no wall ends is missing."""
    out = {}
    for name, at in points.items():
        got = [walls[w][end] for w, e in expected_walls.items() for end in ("from", "to")
               if w in walls and walls[w].get(end) is not None and _dist(e[end], at) <= ON_END]
        if got:
            out[name] = max(got, key=lambda q: _dist(q, at))
    return out


def _read_liggghts(case: Case, out_dir: Path) -> dict:
    roles = json.loads((out_dir / ROLES).read_text())
    n = roles["n"]
    script = (out_dir / "in.geometry").read_text()
    m = re.search(r"n_meshes \d+ meshes (.*?) absolute_damping", script)
    by_mesh = {liggghts_backend._mesh_id(w["name"]): w["name"] for w in _active(case.resolved)}
    mesh_names = [by_mesh[x] for x in m.group(1).split()] if m else []
    hits = _dump_rows(out_dir / "geom_walls_0.dump") if roles["roles"] else np.zeros((0, 9))
    walls = {name: {"from": None, "to": None, "face": []} for name in mesh_names}
    for k, (wname, role) in enumerate(roles["roles"]):
        pid = n + k + 1
        mine = [h for h in hits if int(h[8]) == pid and mesh_names[int(h[6])] == wname]
        if not mine:
            continue
        # the mesh point nearest to the probe disc's centre: its contact with this mesh
        best = min(mine, key=lambda h: _dist(h[0:3], h[3:6]))
        pt = [float(v) for v in best[0:3]]
        if role == "face":
            walls[wname]["face"].append(pt)
        else:
            walls[wname][role] = pt
    exp = expected_geometry(case)
    return {"walls": walls, "points": _end_points(walls, exp["walls"], exp["points"]),
            "discs": _case_discs(out_dir, n)}


def _read_lammps(case: Case, out_dir: Path) -> dict:
    roles = json.loads((out_dir / ROLES).read_text())
    walls = {}
    for p in roles["planes"]:
        rows = _dump_rows(out_dir / f"geom_{p['fix']}_0.dump")
        cps = {int(r[0]) - 1: [float(v) for v in r[2:5]] for r in rows if r[1] == 1.0}
        got = [cps.get(k) for k in p["rows"]]
        for w in p["walls"]:
            walls[w] = {"line": got} if None not in got else None
    return {"walls": walls, "points": None, "discs": _case_discs(out_dir, roles["n"])}


def _read_yade(case: Case, out_dir: Path) -> dict:
    got = json.loads((out_dir / "yade_geometry.json").read_text())
    walls = {name: {"from": v[0], "to": v[1]} for name, v in got["walls"].items()}
    ends = [v for name, w in walls.items() for v in (w["from"], w["to"])
            if not any(_dist(v[:2], q) <= ON_END for q in got["not_points"])]
    points = {}
    for name, at in ((p["name"], p["at"]) for p in case.resolved["points"]):
        if ends:
            points[name] = min(ends, key=lambda v: _dist(v, at))
    return {"walls": walls, "points": points, "discs": got["discs"]}


METHOD = {
    "liggghts": "run 0 of the translated script with probe discs appended outside the container: each mesh's "
                "nearest point to a probe disc from compute wall/gran/local pos id (%.17g), one per strip (face) "
                "and one beyond each end (the end edge); points: the mesh ends at them; discs: dump custom "
                "x y z radius (%.17g)",
    "yade": "setup() of the translated script, no step: facet vertices state.pos + state.ori * shape.vertices; "
            "points: the facet ends the guard lets act as points; discs: state.pos, shape.radius",
    "lammps": "run 0 of the translated script with two probe discs per plane beyond its walls' ends: the contact "
              "point fix wall/gran/region ... contacts stores (LAMMPS prints no region's position); no points "
              "(LAMMPS has no point contact); discs: dump custom x y z radius (%.17g)",
}


def probe(code: str, case: Case, out_dir: Path, timeout: float = 120) -> dict:
    """What ``code`` built for ``case`` (the module doc): {code, status, reason, geometry, method,
    wall_time_s}; never raises for a failed run (status "failed" and the reason)."""
    out_dir = Path(out_dir)
    t0 = time.perf_counter()
    res = {"code": code, "status": "ok", "reason": "", "geometry": {}, "method": METHOD.get(code, "")}
    try:
        script = write_inputs(code, case, out_dir)
        for old in list(out_dir.glob("geom_*.dump")) + [out_dir / "yade_geometry.json"]:
            old.unlink(missing_ok=True)
        log_file = out_dir / f"{code}_geometry.log"
        if code == "yade":
            rc, log = run_yade(script.name, out_dir, timeout, log_file)
        else:
            be = liggghts_backend if code == "liggghts" else lammps_backend
            rc, log = _run(be.command(script), out_dir, timeout, log_file)
        if rc != 0 or "ERROR" in log:
            err = next((l for l in log.splitlines() if "ERROR" in l), f"exit code {rc}")
            raise CaseError(f"{code} geometry run failed: {err.strip()}")
        reader = {"liggghts": _read_liggghts, "lammps": _read_lammps, "yade": _read_yade}[code]
        res["geometry"] = reader(case, out_dir)
    except (CaseError, OSError, ValueError, KeyError, IndexError, StopIteration) as e:
        res.update(status="failed", reason=f"{type(e).__name__}: {e}")
    res["wall_time_s"] = time.perf_counter() - t0
    return res

"""The comparison layer's common ground: the resolved scene, a comparison case, and the one
result form every code's reader produces.

A *case* is what all three codes run: the engine's resolved scene (``dem resolve``: absolute
pair constants, walls, points), a packing (the discs every code starts from), the contact
variant that all three codes can express, a time step, a duration and what to record.
A *result* holds, for one run of one code, the wall profiles at the end, the wall-force series,
the removals, the final discs and the status; ``status != "ok"`` is never agreement.

Sign conventions are the engine's (docs/outputs.md): forces BY THE DISCS ON THE WALL; normal
positive when the discs push; shear along the wall's from -> to direction; profiles bin each
wall from its ``from`` end in bins of ``profile_bin``, a contact counting in the bin of its
contact point.
"""
from __future__ import annotations

import dataclasses
import glob
import json
import math
import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import numpy as np

from dem.compare.io import atomic_file

ROOT = Path(__file__).resolve().parents[2]
PYTHON = "/usr/bin/python3"

# The contact variant every code expresses: e_n = K_n * overlap (LIGGGHTS hooke/stiffness,
# YADE ViscEl), the total normal force clamped >= 0 (LIGGGHTS limitForce on, YADE), the Coulomb
# cap on the total normal force, shear dashpot off while sliding (all three), and the shear force
# acting at the middle of the overlap, r - overlap/2 from each centre (LIGGGHTS' contact radius
# cri = radi - deltan/2 in surface_model_default.h, YADE's ScGeom contactPoint).
SHARED_VARIANT = {"normal_spring": "overlap", "no_tension": "total", "friction_cap": "total",
                  "lever_arm": "contact_point"}


class CaseError(ValueError):
    """A case that cannot be translated faithfully (names the field and the reason)."""


def dem_binary() -> Path:
    b = Path(os.environ.get("DEM_BINARY", ROOT / "build" / "dem"))
    if not b.exists():
        raise FileNotFoundError(f"engine binary {b} not found: run scripts/build.sh (or set DEM_BINARY)")
    return b


def resolve(scene: str | Path) -> dict:
    """The engine's validated scene, every value resolved (``dem resolve``)."""
    p = subprocess.run([str(dem_binary()), "resolve", str(scene)], capture_output=True, text=True)
    if p.returncode != 0:
        raise CaseError(p.stderr.strip() or f"dem resolve {scene} failed with exit {p.returncode}")
    return json.loads(p.stdout)


def stability(scene: str | Path, sets: dict | None = None, dem: str | Path | None = None) -> dict:
    """The engine's time-step bounds of the scene with the ``--set`` assignments ``sets``
    (``dem resolve --stability``): those a run prints and enforces (summary.json's "stability")
    and the bonded clusters' bound for every scheme (``dt_clusters_by_scheme``)."""
    args = [a for k, v in (sets or {}).items() for a in ("--set", f"{k}={v}")]
    p = subprocess.run([str(dem or dem_binary()), "resolve", str(scene), "--stability", *args], capture_output=True,
                       text=True)
    if p.returncode != 0:
        raise CaseError(p.stderr.strip() or f"dem resolve {scene} --stability failed with exit {p.returncode}")
    return json.loads(p.stdout)["stability"]


def pair(resolved: dict, a: str, b: str) -> dict:
    for p in resolved["pairs"]:
        if sorted(p["materials"]) == sorted([a, b]):
            return p
    raise CaseError(f"pairs: no constants for materials {a!r} and {b!r}")


def disc_material(resolved: dict) -> str:
    """The one disc material of a scene (for what is defined for one disc material only)."""
    mats = {d[3] for d in resolved["discs"]}
    if len(mats) != 1:
        raise CaseError("fill: this comparison supports one disc material, "
                        f"this scene has {len(mats)}")
    return resolved["materials"][mats.pop()]["name"]


def scene_material_index(resolved: dict) -> np.ndarray:
    """Each scene disc's material index (into resolved["materials"]): resolved["discs"][:, 3]."""
    d = np.asarray(resolved["discs"], float).reshape(-1, 4)
    return d[:, 3].astype(int)


def material_names(resolved: dict, index) -> list[str]:
    """Material names of the indices (into resolved["materials"])."""
    names = [m["name"] for m in resolved["materials"]]
    return [names[int(k)] for k in np.asarray(index).reshape(-1)]


def densities(resolved: dict, index) -> np.ndarray:
    """Density of each index's material."""
    rho = [float(m["density"]) for m in resolved["materials"]]
    return np.array([rho[int(k)] for k in np.asarray(index).reshape(-1)], float)


def kinetic_energy(resolved: dict, discs: np.ndarray, materials=None) -> float:
    """Translational + rotational energy of discs rows (x, y, r, vx, vy, omega), per 1 cm; each
    disc with the density of its material (``materials``: per-disc indices into
    resolved["materials"]; None: the scene's one disc material)."""
    d = np.asarray(discs, float).reshape(-1, 6)
    if materials is None:
        rho = {m["name"]: m["density"] for m in resolved["materials"]}[disc_material(resolved)]
    else:
        rho = densities(resolved, materials)
        if len(rho) != len(d):
            raise CaseError(f"materials: {len(rho)} material indices for {len(d)} discs")
    m = rho * math.pi * d[:, 2] ** 2
    return float(np.sum(0.5 * m * (d[:, 3] ** 2 + d[:, 4] ** 2) + 0.25 * m * d[:, 2] ** 2 * d[:, 5] ** 2))


def outlet_y(resolved: dict) -> float:
    """Height below which a discharge removes discs: ``discharge.outlet_depth`` below the gate
    (the engine's rule: below the floor of the slit the gate closes; docs/scene.md)."""
    gate = next((w for w in resolved["walls"] if w["name"] == resolved["discharge"]["gate"]), None)
    if gate is None:
        raise CaseError(f"discharge.gate: {resolved['discharge']['gate']!r} is not a wall of the scene")
    return min(float(gate["from"][1]), float(gate["to"][1])) - float(resolved["discharge"]["outlet_depth"])


def wall_displacement(wall: dict, t: float) -> np.ndarray:
    """How far a wall has moved by time ``t`` [s] of a run: its prescribed translation
    (``motion``: velocity, from, until; docs/scene.md walls[].velocity) over the part of
    [from, until] before ``t``; zero for a wall that stays put."""
    m = wall.get("motion")
    if not m:
        return np.zeros(2)
    span = min(max(float(t) - float(m["from"]), 0.0), float(m["until"]) - float(m["from"]))
    return np.array(m["velocity"], float) * span


def moved_wall(wall: dict, t: float) -> dict:
    """The wall where it is at time ``t`` (``from`` and ``to`` displaced)."""
    d = wall_displacement(wall, t)
    if not d.any():
        return wall
    return dict(wall, **{"from": (np.array(wall["from"], float) + d).tolist(),
                         "to": (np.array(wall["to"], float) + d).tolist()})


def motion_steps(wall: dict, dt: float) -> tuple[int, int]:
    """The steps (from, until) of a wall's translation window: the steps n with from <= n dt and
    (n + 1) dt <= until move it by v dt (the engine moves it over the part of a step inside the
    window; the reference translations express windows of whole steps and refuse others)."""
    m = wall["motion"]
    out = []
    for key in ("from", "until"):
        n = float(m[key]) / dt
        k = int(round(n))
        if not (math.isfinite(n) and abs(n - k) <= 1e-6 * max(1.0, n)):
            raise CaseError(f"walls: {wall['name']}.move_{key} = {m[key]!r} s is not a whole number of steps of "
                            f"dt = {dt!r} s")
        out.append(k)
    return out[0], out[1]


def inward_normal(wall: dict, centre: tuple[float, float]) -> np.ndarray:
    """Unit normal of a wall pointing to the side where ``centre`` (the discs) lies."""
    a, b = np.array(wall["from"], float), np.array(wall["to"], float)
    t = (b - a) / np.linalg.norm(b - a)
    n = np.array([-t[1], t[0]])
    return n if np.dot(np.array(centre) - a, n) >= 0 else -n


def tangent(wall: dict) -> np.ndarray:
    a, b = np.array(wall["from"], float), np.array(wall["to"], float)
    return (b - a) / np.linalg.norm(b - a)


def bin_edges(wall: dict, profile_bin: float) -> np.ndarray:
    length = float(np.linalg.norm(np.subtract(wall["to"], wall["from"])))
    n = max(1, int(math.ceil(length / profile_bin - 1e-9)))
    return np.minimum(np.arange(n + 1) * profile_bin, length)


@dataclasses.dataclass
class Case:
    """One comparison run, the same for every code."""
    name: str
    resolved: dict              # dem resolve output, with the shared variant and dt applied
    discs: np.ndarray           # (n, 6): x, y, r [cm], vx, vy [cm/s], omega [1/s] at the start
    dt: float                   # [s]
    duration: float             # [s] simulated (static: settling time; discharge: after opening)
    mode: str = "static"        # "static" | "discharge" | "shear" (compare/cases/shear.py)
    settle: float = 0.0         # [s] discharge: settling before the gate opens
    series_interval: float = 0.005  # [s] wall-force sampling
    seed: int = 0               # ensemble member (perturbation already applied to discs)
    # [s] particle snapshots every snapshot_interval from the start (static) or the opening
    # (discharge), read back by each backend's read_snapshots; 0: none (the study's default).
    snapshot_interval: float = 0.0
    # Each disc's material index (into resolved["materials"]), in the order of ``discs``; None:
    # the scene's own discs' materials when the case has as many discs as the scene, else the
    # scene's one disc material (a scene with several refuses: see ``material_index``).
    materials: np.ndarray | None = None
    # A shear case's clusters: "bonds" (the scene's [clusters] as elastic bonds: what every code
    # runs) or "clumps" (rigid YADE clumps: the shear study's YADE variant; the engine refuses it).
    clusters: str = "bonds"

    @property
    def profile_bin(self) -> float:
        return float(self.resolved["profile_bin"])

    @property
    def centre(self) -> tuple[float, float]:
        return (float(np.mean(self.discs[:, 0])), float(np.mean(self.discs[:, 1])))

    def material_index(self) -> np.ndarray:
        """Each disc's material index (into resolved["materials"])."""
        n = len(self.discs)
        if self.materials is not None:
            m = np.asarray(self.materials).astype(int).reshape(-1)
            if len(m) != n:
                raise CaseError(f"materials: {len(m)} material indices for {n} discs")
            return m
        scene = scene_material_index(self.resolved)
        if len(scene) == n:
            return scene
        used = set(scene.tolist())
        if len(used) != 1:
            raise CaseError(f"materials: the scene has {len(used)} disc materials and {len(scene)} discs; "
                            f"a case of {n} discs must give each disc's material")
        return np.full(n, used.pop(), int)

    def material_names(self) -> list[str]:
        """Each disc's material name."""
        return material_names(self.resolved, self.material_index())

    def disc_materials(self) -> list[str]:
        """The case's disc material names, in the order of resolved["materials"]."""
        return material_names(self.resolved, sorted(set(self.material_index().tolist())))

    @property
    def end_time(self) -> float:
        """[s] the run's simulated time: the duration, after the settling of a discharge."""
        return self.settle + self.duration if self.mode == "discharge" else self.duration

    def to_json(self) -> dict:
        return {"name": self.name, "dt": self.dt, "duration": self.duration, "mode": self.mode,
                "settle": self.settle, "series_interval": self.series_interval, "seed": self.seed,
                "snapshot_interval": self.snapshot_interval, "n_discs": int(len(self.discs)),
                "clusters": self.clusters}

    def snapshot_steps(self) -> int:
        """Steps between snapshots (0: none); the interval must be a whole number of steps."""
        if not self.snapshot_interval:
            return 0
        n = self.snapshot_interval / self.dt
        k = int(round(n))
        if not (math.isfinite(n) and k >= 1 and abs(n - k) <= 1e-6 * n):
            raise CaseError(f"snapshot_interval: {self.snapshot_interval!r} s is not a whole number of "
                            f"steps of dt = {self.dt!r} s")
        return k

    def snapshot_times(self) -> list[float]:
        """Times of the snapshots (since the start, or since the opening of a discharge)."""
        k = self.snapshot_steps()
        if not k:
            return []
        n = int(round(self.duration / self.dt))
        return [j * self.dt for j in range(0, n + 1, k)]


@dataclasses.dataclass
class Result:
    """One run of one code, in the common form."""
    code: str                       # "native" | "liggghts" | "yade"
    case: str
    status: str = "ok"              # "ok" | "failed"
    reason: str = ""                # why it failed (blow-up, lost discs, timeout, crash, ...)
    version: str = ""
    wall_time_s: float = float("nan")
    steps: int = 0
    n_initial: int = 0
    n_final: int = 0
    # Final wall profiles: wall name -> {"s_lo","s_hi","normal","shear"} (lists, force units).
    profiles: dict = dataclasses.field(default_factory=dict)
    # Wall-force series every case.series_interval: {"t": [...], "walls": {name: {"normal":
    # [[per bin] per sample], "shear": [[...]]}}}, same bins as the profiles; t since opening
    # for a discharge (negative while settling is not recorded), since the start otherwise.
    series: dict = dataclasses.field(default_factory=dict)
    # Times (s since opening) of the discs that left through the outlet.
    removals: list = dataclasses.field(default_factory=list)
    kinetic_energy_end: float = float("nan")
    # Discs at the end, in the starting order (removed discs left out): x, y, r, vx, vy, omega.
    discs_end: list = dataclasses.field(default_factory=list)
    extra: dict = dataclasses.field(default_factory=dict)
    out_dir: str = ""

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def to_json(self) -> dict:
        return dataclasses.asdict(self)

    def save(self, path: Path) -> None:
        atomic_file.write_text(path, json.dumps(self.to_json(), indent=1, default=_json_default) + "\n")

    @staticmethod
    def load(path: Path) -> "Result":
        return Result(**json.loads(Path(path).read_text()))


@dataclasses.dataclass
class Snapshot:
    """The discs at one time, in the form every code's ``read_snapshots`` returns.

    ``t``: seconds since the start (static) or since the opening (discharge); ``id``: each disc's
    row in the case's starting packing (``Case.discs``), so that the same disc has the same id in
    every code; x, y [cm], r [cm], vx, vy [cm/s], omega [1/s]: arrays in the order of ``id``
    (ascending), NaN where a code does not write the quantity. Removed discs are absent."""
    t: float
    id: np.ndarray
    x: np.ndarray
    y: np.ndarray
    r: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    omega: np.ndarray

    @staticmethod
    def from_columns(t: float, ids, **cols) -> "Snapshot":
        ids = np.asarray(ids).astype(int).reshape(-1)
        order = np.argsort(ids, kind="stable")
        out = {"t": float(t), "id": ids[order]}
        for k in ("x", "y", "r", "vx", "vy", "omega"):
            v = cols.get(k)
            v = np.full(len(ids), np.nan) if v is None else np.asarray(v, float).reshape(-1)
            if len(v) != len(ids):
                raise ValueError(f"snapshot at t = {t}: {len(v)} values of {k} for {len(ids)} discs")
            out[k] = v[order]
        return Snapshot(**out)

    def rows(self) -> np.ndarray:
        """(n, 6): x, y, r, vx, vy, omega (the Result.discs_end form)."""
        return np.column_stack([self.x, self.y, self.r, self.vx, self.vy, self.omega])


def fold_points(walls: list[dict], points: list[dict], centre, exclude=()) -> dict:
    """For each point (slit end) the wall it is folded into: the first wall that ends at the point
    and is not in ``exclude`` (e.g. an opened gate); {point name: (wall name, "from" | "to": the
    end, hence the wall's first or last bin, inward normal, tangent)}. LIGGGHTS (a mesh edge) and
    YADE (a facet vertex) count a contact on a wall's end point in that wall's end bin; the engine
    reports points apart, and its reader folds them in the same way."""
    out = {}
    for p in points:
        at = np.array(p["at"], float)
        for w in walls:
            if w["name"] in exclude or not w.get("active", True):
                continue
            for end in ("from", "to"):
                if np.linalg.norm(np.array(w[end], float) - at) <= 1e-9:
                    out[p["name"]] = (w, end)
                    break
            if p["name"] in out:
                break
    return {name: (w["name"], end, inward_normal(w, centre), tangent(w)) for name, (w, end) in out.items()}


def failed(code: str, case: str, reason: str, **kw) -> Result:
    return Result(code=code, case=case, status="failed", reason=reason, **kw)


def mpi_prefix(ranks: int) -> list[str]:
    """``mpirun -np N`` before a LIGGGHTS or LAMMPS command (none for one rank)."""
    return ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(ranks)] if ranks > 1 else []


def run_translated(be, case: "Case", out_dir: Path, log_name: str, stale: tuple, timeout: float,
                   threads: int = 1) -> "Result":
    """A LIGGGHTS or LAMMPS run of a case (backend module ``be``: NAME, write_inputs, command,
    read): translate, remove the dumps of an earlier run (glob patterns ``stale``), run under
    ``run_logged`` (``threads`` > 1: MPI ranks) and read back; never raises for a failed run."""
    out_dir = Path(out_dir)
    try:
        script = be.write_inputs(case, out_dir, threads)
    except CaseError as e:
        return failed(be.NAME, case.name, f"translation: {e}", out_dir=str(out_dir))
    for old in (f for pattern in stale for f in glob.glob(str(out_dir / pattern))):
        os.remove(old)
    bad, wall = run_logged(be.NAME, case.name, be.command(script, threads), out_dir, out_dir / log_name, timeout)
    if bad is not None:
        return bad
    res = be.read(case, out_dir)
    res.wall_time_s = wall
    res.extra["ranks"] = threads
    return res


def run_logged(code: str, case: str, cmd: list, out_dir: Path, log: Path, timeout: float):
    """Runs a reference program in out_dir with its output in ``log`` (one thread of OpenMP a
    rank), killing its whole process group (mpirun and ranks) after ``timeout`` seconds.
    Returns (None, wall seconds) when it ended cleanly, else (the failed Result, wall seconds):
    a timeout, a non-zero exit or an ERROR line (quoted)."""
    t0 = time.monotonic()
    env = dict(os.environ, OMP_NUM_THREADS="1")
    with open(log, "w") as f:
        p = subprocess.Popen(cmd, cwd=out_dir, stdout=f, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                             start_new_session=True, env=env)
        try:
            rc = p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
            return failed(code, case, f"timed out after {timeout:.0f} s", out_dir=str(out_dir)), timeout
    wall = time.monotonic() - t0
    text = Path(log).read_text(errors="replace")
    if rc != 0 or "ERROR" in text:
        err = next((line for line in text.splitlines() if "ERROR" in line), f"exit code {rc}")
        return failed(code, case, f"{code} failed (exit {rc}): {err.strip()}", out_dir=str(out_dir),
                      wall_time_s=wall), wall
    return None, wall


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o))


def profiles_from_contacts(walls: list[dict], profile_bin: float, centre, contacts) -> dict:
    """Bins contact forces on walls into the common profile form.

    ``contacts``: iterable of (wall name, px, py, fx, fy): contact point and force BY THE DISC
    ON THE WALL.
    """
    out, geo = {}, {}
    for w in walls:
        edges = bin_edges(w, profile_bin)
        out[w["name"]] = {"s_lo": edges[:-1].tolist(), "s_hi": edges[1:].tolist(),
                          "normal": [0.0] * (len(edges) - 1), "shear": [0.0] * (len(edges) - 1),
                          "contacts": [0] * (len(edges) - 1)}
        geo[w["name"]] = (np.array(w["from"], float), tangent(w), inward_normal(w, centre), edges)
    for name, px, py, fx, fy in contacts:
        if name not in geo:
            continue
        a, t, n, edges = geo[name]
        s = float(np.dot(np.array([px, py]) - a, t))
        k = int(np.clip(np.searchsorted(edges, s, side="right") - 1, 0, len(edges) - 2))
        prof = out[name]
        prof["normal"][k] += -float(np.dot([fx, fy], n))
        prof["shear"][k] += float(np.dot([fx, fy], t))
        prof["contacts"][k] += 1
    return out


def which(program: str) -> str | None:
    return shutil.which(program)

"""Shared helpers of the work-precision and stability studies.

Both studies drive the engine binary (``--dem PATH``, else ``$DEM_BINARY``, else
``build/dem``) as a subprocess, write their scenes with ``dem.compare.io.scene_toml``, read its
``summary.json`` and ``discs.csv`` with ``dem.compare.io.run_dir``, and write
``results.json`` + ``report.md`` (+ PNGs) under ``--out``. Python is Debian's
``/usr/bin/python3`` (numpy, matplotlib). Nothing here edits the engine or ``compare/``.
"""
from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "reference_inputs" / "scenes"
SCHEMES = ("paper_eq18", "paper_eq19", "velocity_verlet")
PAPER_LAW = {"normal_spring": "incremental", "no_tension": "elastic", "friction_cap": "elastic"}

if str(ROOT / "build" / "python") not in sys.path:      # the package dem (dem.compare) of this checkout's build
    sys.path.insert(0, str(ROOT / "build" / "python"))

from dem.compare.io import scene_toml  # noqa: E402
from dem.compare.io.atomic_file import replacing, write_text  # noqa: E402,F401 (the studies' writer)
from dem.compare.io.run_dir import RunDir, RunDirError  # noqa: E402


def setup_binary(path: str | None) -> Path:
    """The engine binary: --dem, else $DEM_BINARY, else build/dem. Exported as DEM_BINARY so
    that compare/ (dem resolve, the native backend) uses the same one."""
    b = Path(path or os.environ.get("DEM_BINARY") or ROOT / "build" / "dem").resolve()
    if not b.exists():
        raise SystemExit(f"engine binary {b} not found: build it (README) or pass --dem PATH")
    os.environ["DEM_BINARY"] = str(b)
    return b


def dem() -> str:
    return os.environ["DEM_BINARY"]


def engine_version() -> str:
    p = subprocess.run([dem(), "--help"], capture_output=True, text=True)
    line = (p.stdout or p.stderr or "dem").splitlines()[0]
    return line.split(" - ")[0].strip()


def set_autogroup_nice(pid, nice: int) -> None:
    """Gives process pid's autogroup the niceness `nice` (root). With autogroups on (Debian's
    default), the kernel shares the cores between sessions first: a process's own nice counts only
    within its session, and mpirun starts its ranks in sessions of their own."""
    try:
        f = Path(f"/proc/{pid}/autogroup")
        if f"nice {nice}" not in f.read_text():
            f.write_text(str(nice))
    except OSError:
        pass


# A LIGGGHTS or LAMMPS log: a line for each `run`, and after it the timing breakdown whose Output
# row (min | avg | max) is the writing of dumps and thermo within that loop.
LOOP_LINE = re.compile(r"Loop time of ([\d.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms")
OUTPUT_ROW = re.compile(r"^Output\s*\|\s*[\d.eE+-]+\s*\|\s*([\d.eE+-]+)", re.M)


def loop_times(text: str, n0: int | None = None) -> dict:
    """What a LIGGGHTS or LAMMPS log says of its runs, summed over them: `loop_s` the loop time less
    its output (the average over ranks of the Output row), `output_s`, `steps`, `runs`, and
    `particle_steps`: each run's steps x the mean of its atoms at its start and end (a discharge
    loses atoms; the first run starts with n0 atoms, or its end's count when n0 is None)."""
    loops = LOOP_LINE.findall(text)
    outs = [float(x) for x in OUTPUT_ROW.findall(text)]
    ps, before = 0.0, n0
    for _t, _procs, steps, atoms in loops:
        start = int(atoms) if before is None else before
        ps += int(steps) * 0.5 * (start + int(atoms))
        before = int(atoms)
    total = sum(float(t) for t, *_ in loops)
    return {"loop_s": total - sum(outs), "output_s": sum(outs), "steps": sum(int(s) for _, _, s, _ in loops),
            "runs": len(loops), "particle_steps": ps}


# A run counts as at rest (not blown up, not self-excited) when its kinetic energy at the end is
# below KE_REST x (total weight x mean radius): the energy of every disc dropped by one radius.
KE_REST = 1e-6


def energy_scale(out_dir: Path, summary: dict) -> float:
    """Total weight x mean radius (force x length per unit thickness) of the run's discs."""
    d = RunDir(out_dir).discs()
    return float(summary["weight"]) * (float(np.mean(d["r"])) if d["r"].size else 1.0)


def kinetic_energy_run(out_dir: Path, summary: dict) -> float:
    """Translational + rotational energy [force x length per unit thickness] of the run's
    discs.csv (I = m r^2 / 2); the density comes from summary.json's disc_weight (m g of disc
    0) and disc 0's radius. One disc material is assumed (true of every scene here)."""
    d = RunDir(out_dir).discs()
    if d["r"].size == 0:
        return 0.0
    g = math.hypot(*summary["options"]["gravity"])
    r0 = float(d["r"][d["id"] == 0][0]) if np.any(d["id"] == 0) else float(d["r"][0])
    rho = float(summary["disc_weight"]) / (g * math.pi * r0 ** 2)
    m = rho * math.pi * d["r"] ** 2
    ke = 0.5 * m * (d["vx"] ** 2 + d["vy"] ** 2) + 0.25 * m * d["r"] ** 2 * d["omega"] ** 2
    return float(np.sum(ke))


def run_dem(scene: Path, out: Path, scheme: str, dt: float, end_time: float | None = None,
            timeout: float = 900, extra: list | None = None) -> dict:
    """``dem run SCENE --out OUT --scheme S --dt DT --force-dt --quiet``.

    Returns rc, status, loop time (summary wall_time_s), process time, steps, the summary
    (or None) and the message of a failed run. --force-dt is always given: these studies go
    past the engine's enforced bound on purpose."""
    cmd = [dem(), "run", str(scene), "--out", str(out), "--scheme", scheme, "--dt", repr(float(dt)),
           "--force-dt", "--quiet"]
    if end_time is not None:
        cmd += ["--end-time", repr(float(end_time))]
    cmd += list(extra or [])
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        rc, err = p.returncode, p.stderr
    except subprocess.TimeoutExpired:
        rc, err = None, f"timed out after {timeout} s"
    proc = time.perf_counter() - t0
    s, why = None, ""
    try:
        s = RunDir(out, strict=True).summary
    except RunDirError as e:
        why = str(e)
    message = " ".join(err.strip().splitlines()[-2:]) if rc not in (0,) else ""
    if s is None and rc == 0:
        message = why
    return {"rc": rc, "status": (s or {}).get("status", "no_summary"), "loop_s": (s or {}).get("wall_time_s"),
            "process_s": proc, "steps": (s or {}).get("steps"), "summary": s, "message": message}


def timed(fn, repeats: int, cheap_below_s: float = 1.0):
    """Runs fn() (which returns a dict with 'loop_s' and 'process_s'); repeats it up to
    ``repeats`` times while one run is cheaper than ``cheap_below_s``; returns the last result
    with the medians and every sample."""
    res = fn()
    loops, procs = [res.get("loop_s")], [res.get("process_s")]
    while len(loops) < repeats and (res.get("loop_s") or 0) < cheap_below_s and res.get("rc") == 0:
        r2 = fn()
        loops.append(r2.get("loop_s"))
        procs.append(r2.get("process_s"))
    good = [x for x in loops if x is not None]
    res["loop_s"] = float(np.median(good)) if good else None
    res["process_s"] = float(np.median([x for x in procs if x is not None]))
    res["loop_samples"] = loops
    res["repeats"] = len(loops)
    return res


def fit_order(dts, errs, lo_err: float = 0.0, hi_err: float = math.inf, dt_max: float = math.inf):
    """Least-squares slope of log(err) against log(dt) over the points with
    lo_err < err < hi_err and dt <= dt_max (the asymptotic range). Returns (order, n_points,
    (dt_min, dt_max) used) or (None, n, None) with fewer than 3 points."""
    pts = [(d, e) for d, e in zip(dts, errs)
           if e is not None and math.isfinite(e) and lo_err < e < hi_err and d <= dt_max * (1 + 1e-9)]
    if len(pts) < 3:
        return None, len(pts), None
    x = np.log([p[0] for p in pts])
    y = np.log([p[1] for p in pts])
    slope = float(np.polyfit(x, y, 1)[0])
    return slope, len(pts), (min(p[0] for p in pts), max(p[0] for p in pts))


def write_json(path: Path, data) -> None:
    write_text(path, json.dumps(data, indent=1, default=_default) + "\n")


def _default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(type(o))


def md_table(header: list, rows: list) -> str:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def g(v, digits: int = 3) -> str:
    """Compact number for tables ('-' for None/nan)."""
    if v is None:
        return "-"
    if isinstance(v, str):
        return v
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if not math.isfinite(float(v)):
        return "-"
    return f"{float(v):.{digits}g}"


def savefig(fig, path: Path) -> None:
    with replacing(path) as tmp:  # NAME.png.tmp: the format named, not read from the suffix
        fig.savefig(tmp, dpi=110, bbox_inches="tight", format=Path(path).suffix[1:])


def scene_with(base: Path, out: Path, changes: dict | None = None, add: dict | None = None, remove=(),
               pairs_scale: dict | None = None) -> Path:
    """Writes the scene ``base`` to ``out`` with keys changed, added and removed by dotted path
    (dem.compare.io.scene_toml.edit: a key to change or remove that the scene does not have is an
    error) and the constants of every [[pairs]] entry scaled (pairs_scale: key -> factor, e.g.
    {"ks_rho_g": 2.0}; each entry must have the key). Returns out."""
    changes = dict(changes or {})
    if pairs_scale:
        for k, pair in enumerate(scene_toml.load(base).get("pairs", [])):
            for name, factor in pairs_scale.items():
                if name not in pair:
                    raise KeyError(f"{base}: pairs[{k}] has no '{name}' to scale")
                changes[f"pairs[{k}].{name}"] = pair[name] * factor
    return scene_toml.edit(base, changes, out, add=add, remove=remove)

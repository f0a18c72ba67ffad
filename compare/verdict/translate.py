"""The paper's scenes translated for LIGGGHTS, YADE and LAMMPS, committed under reference_inputs/
(``python3 -m dem.compare translate``; ``--check`` in CI fails when they are stale).

YADE's folders hold only ``yade_case.json``, the case's data: its script is one template
(compare/codes/yade_template.py) for every case, so it is not committed ten times. ``python3 -m
compare translate --out DIR`` writes complete folders, each runnable there with
``yade -n -x yade_script.py``.

Each scene becomes the case the agreement study runs from the scene's own lattice: static
(silo_*) or discharge (discharge_*, settle 1 s then open), with the shared contact law and the
study's dt for that lattice. The study itself writes the same inputs for its frozen packings
under its output directory.
"""
from __future__ import annotations

import filecmp
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

from dem.compare.codes import lammps_backend, liggghts_backend, yade_backend
from dem.compare.cases.common import ROOT, SHARED_VARIANT, Case, resolve
from dem.compare.verdict.study import DEFAULT_DT, LATTICE_DT, SCENES

OUT = ROOT / "reference_inputs"
SUBDIRS = ("liggghts", "yade", "lammps")


def cases() -> list[Case]:
    out = []
    for path in sorted(SCENES.glob("silo_*.toml")) + sorted(SCENES.glob("discharge_*.toml")):
        r = resolve(path.relative_to(ROOT) if path.is_relative_to(ROOT) else path)
        r["contact"] = dict(SHARED_VARIANT)
        r["file"] = path.name
        s = int(path.stem.split("_")[-1])
        d = np.array(r["discs"], float)
        discs = np.column_stack([d[:, :3], np.zeros((len(d), 3))])
        dt = LATTICE_DT.get(s, DEFAULT_DT)
        if path.stem.startswith("discharge"):
            out.append(Case(name=path.stem, resolved=r, discs=discs, dt=dt, duration=1.0, mode="discharge", settle=1.0))
        else:
            out.append(Case(name=path.stem, resolved=r, discs=discs, dt=dt, duration=1.0))
    return out


def write_all(root: Path, runnable: bool = False) -> None:
    """runnable: with YADE's script beside each yade_case.json (the committed tree leaves it out)."""
    for case in cases():
        liggghts_backend.write_inputs(case, root / "liggghts" / case.name)
        script = yade_backend.write_inputs(case, root / "yade" / case.name)
        if not runnable:
            script.unlink()
        lammps_backend.write_inputs(case, root / "lammps" / case.name)


def _same(a: Path, b: Path) -> list[str]:
    diff = []
    for f in sorted(set(p.relative_to(a) for p in a.rglob("*") if p.is_file()) |
                    set(p.relative_to(b) for p in b.rglob("*") if p.is_file())):
        if not (a / f).exists() or not (b / f).exists() or not filecmp.cmp(a / f, b / f, shallow=False):
            diff.append(str(f))
    return diff


def main(check: bool, out: Path | None = None) -> int:
    if out is not None:
        write_all(Path(out), runnable=True)
        print(f"wrote {out}/liggghts, {out}/yade, {out}/lammps (each folder runnable by its code)")
        return 0
    if not check:
        for sub in SUBDIRS:
            shutil.rmtree(OUT / sub, ignore_errors=True)
        write_all(OUT)
        print("wrote " + ", ".join(str(OUT / s) for s in SUBDIRS))
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        write_all(Path(tmp))
        stale = [f"{sub}/{f}" for sub in SUBDIRS for f in _same(Path(tmp) / sub, OUT / sub)]
    if stale:
        print("stale reference inputs (run python3 -m dem.compare translate): " + ", ".join(stale[:10]), file=sys.stderr)
        return 1
    print("reference_inputs/" + ", reference_inputs/".join(SUBDIRS) + " are up to date")
    return 0

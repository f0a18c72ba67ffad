"""Pre-flight: what the native engine refuses is refused before any reference code runs.

The engine checks a scene's dt against its stability bound when it builds the world (docs/outputs.md,
"stability"). Each plan's first case is built by the engine for one step, with the law, dt and
packing every code would run; a refusal becomes a PlanError (exit 2) that names the largest dt
that passes, found by asking the engine again.
"""
from __future__ import annotations

import dataclasses
import math
import re
import subprocess
import tempfile
from pathlib import Path

from dem.compare.codes import native_backend
from dem.compare.cases.common import Case, dem_binary
from dem.compare.io.scene_toml import dumps

BOUND = re.compile(r"above the stability bound ([0-9.eE+-]+) s")


def one_step(case: Case, folder: Path, dt: float | None = None) -> subprocess.CompletedProcess:
    """The engine builds the case (its fill, walls, law, dt) and runs one step, nothing else."""
    case = dataclasses.replace(case, dt=dt if dt is not None else case.dt)
    native_backend.write_inputs(case, folder)          # the packing file, as the native run writes it
    doc, _ = native_backend.scene_doc(case, "packing.csv")
    doc.pop("discharge", None)
    doc["end"] = dict(doc["end"], time=case.dt)
    (folder / "preflight.toml").write_text(dumps(doc))
    return subprocess.run([str(dem_binary()), "run", str(folder / "preflight.toml"), "--out", str(folder / "run"),
                           "--quiet", "--no-vtu"], capture_output=True, text=True, timeout=600)


def largest_passing(bound: float, case: Case, folder: Path) -> float:
    """The bound as printed, floored to three significant digits and confirmed by the engine."""
    dt = float(f"{bound:.3g}")
    for _ in range(4):
        if dt <= bound * (1 - 1e-12):
            p = one_step(case, folder, dt)
            if p.returncode == 0:
                return dt
        step = 10 ** (math.floor(math.log10(dt)) - 2)
        dt = round(dt - step, 15)
    return dt


def refusal(plan, case: Case) -> str | None:
    """Why the engine refuses this plan's case (its message, and for a dt above the bound the
    largest dt that passes), or None when it builds and steps."""
    if case.mode == "shear":           # the shear box takes a dt stable with its clusters (plan.make_plan)
        return None
    with tempfile.TemporaryDirectory() as t:
        p = one_step(case, Path(t))
        if p.returncode == 0:
            return None
        msg = (p.stderr.strip().splitlines() or [f"dem exited with {p.returncode}"])[-1]
        m = BOUND.search(msg)
        if p.returncode == 2 and m:
            ok = largest_passing(float(m.group(1)), case, Path(t))
            return (f"{plan.entry.scene}: --dt {plan.dt:g}: the native engine refuses it: above its stability bound "
                    f"{float(m.group(1)):g} s for this scene; the largest dt that passes is {ok:g} s (--dt {ok:g})")
        return f"{plan.entry.scene}: the native engine refuses the case: {msg}"

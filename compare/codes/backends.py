"""Every compared code's backend by its name (native_backend for the engine), and what each
reference code refuses to translate in a plan."""
from __future__ import annotations

import tempfile
from pathlib import Path

from dem.compare.cases.common import CaseError
from dem.compare.cases.plan import Plan, member_case
from dem.compare.codes import lammps_backend, liggghts_backend, native_backend, yade_backend

BACKENDS = {"native": native_backend, "liggghts": liggghts_backend, "yade": yade_backend, "lammps": lammps_backend}


def backend(code: str):
    """The backend module of a code (native, liggghts, yade or lammps)."""
    return BACKENDS[code]


def refusal(code: str, case) -> str:
    """Why a reference code cannot express a case (its own translation, dry-run), or ''."""
    if code == "native":
        return ""
    with tempfile.TemporaryDirectory() as tmp:
        try:
            BACKENDS[code].write_inputs(case, Path(tmp))
        except CaseError as e:
            return f"{code} cannot express it: {e}"
    return ""


def refusals(plan: Plan, codes) -> list[str]:
    """What each reference code refuses to translate in this plan (its own translation, dry-run on
    the first case); empty when every code can express the scene."""
    out = []
    case = member_case(plan, 0)
    if plan.kind == "discharge" and not plan.shared.get("discharge", {}).get("gate"):
        out.append(f"{plan.entry.scene}: discharge.gate: the comparison opens a gate wall; the scene has none")
    out += [f"{plan.entry.scene}: {why}" for why in (refusal(code, case) for code in codes) if why]
    return out

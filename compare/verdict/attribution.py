"""Attribution: when the native engine runs the scene's own law (``--native-law scene``) against
the references' shared law and metrics fail, re-run the native side with each law option that
differs switched to the shared value, one at a time, and name the option that closes the gap.

The built-in demonstration is the paper's 17/18 discharge: with the paper's law the silo flows,
with the shared law every code jams after about two discs; switching ``friction_cap`` alone
(the Coulomb cap on the total normal force, dashpot included) closes the gap.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

from dem.compare.verdict import pipeline
from dem.compare.cases.common import SHARED_VARIANT


@dataclasses.dataclass
class LawSwitch:
    """One contact option of the native side set to the shared value (a 'mutation' of native)."""
    key: str
    value: str
    code: str = "native"

    @property
    def name(self) -> str:
        return f"native_{self.key}_{self.value}"

    def applies(self, code: str, case) -> bool:
        return code == "native"

    def apply(self, resolved: dict) -> dict:
        r = dict(resolved)
        r["contact"] = dict(resolved["contact"], **{self.key: self.value})
        return r

    def folder(self, out: Path, code: str) -> Path:
        return Path(out) / "attribution" / self.name / code


def attribute(plans, report: dict, out: Path, log=print) -> list:
    rows_out = []
    for p in plans:
        if p.options.native_law != "scene":
            continue
        failing = sorted({m["metric"] for m in report["metrics"] if m["scene"] == p.name and m["verdict"] == "disagree"
                          and not m["metric"].startswith(("translation constants", "translation geometry"))})
        diff = {k: v for k, v in SHARED_VARIANT.items() if p.resolved["contact"].get(k) != v}
        entry = {"scene": p.name, "failing": len(failing), "failing_metrics": failing,
                 "scene_law": p.resolved["contact"], "rows": []}
        if not failing:
            entry["verdict"] = "nothing to attribute: the scene's law agrees within the tolerances"
            rows_out.append(entry)
            continue
        for k, v in diff.items():
            sw = LawSwitch(k, v)
            log(f"attribution {p.name}: native with {k} = {v} ...")
            rep = pipeline.run([], out, report["codes"].keys(), log=log, mutation=sw, plans=[p],
                               check_translation=False)
            still = sorted({m["metric"] for m in rep["metrics"] if m["metric"] in failing and m["verdict"] != "agree"})
            entry["rows"].append({"option": f"{k} = {v}", "failing": len(still), "still_failing": still})
        best = min(entry["rows"], key=lambda r: r["failing"]) if entry["rows"] else None
        if best and best["failing"] == 0:
            entry["verdict"] = f"{best['option']} alone closes every failing metric"
        elif best and best["failing"] < len(failing):
            entry["verdict"] = f"{best['option']} closes the most ({len(failing) - best['failing']} of {len(failing)})"
        else:
            entry["verdict"] = "no single law option closes the gap"
        rows_out.append(entry)
    return rows_out

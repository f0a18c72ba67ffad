"""The verdict on a collision scene (compare/verdict/calibration.py measures it): each code against the
analytic or independent reference within the scheme's first-order error in dt / t_c
(calibration.tolerances), and each reference code against the native engine within
calibration.CODE_REL of each quantity's scale (the codes run the same discrete law at the same dt);
a scene without a reference (the open slit) is judged by the latter alone.
"""
from __future__ import annotations

import math

import numpy as np

from dem.compare.verdict import calibration as cal
from dem.compare.cases.common import Case
from dem.compare.verdict.study import failures, metric
from dem.compare.verdict.verdict import unjudged


def _worst(measured: dict, target: dict, tol: dict) -> float:
    """Largest |measured - target| / tolerance over the quantities both have."""
    w = 0.0
    for q, t in tol.items():
        if q in measured and q in target and t > 0:
            a, b = measured[q], target[q]
            w = max(w, abs(a - b) / t if math.isfinite(a) and math.isfinite(b) else math.inf)
    return w


def judge(name: str, case: Case, results: dict) -> tuple[list, dict]:
    start = np.asarray(case.discs, float)
    lever = case.resolved["contact"].get("lever_arm", "radius")
    ref = cal.reference(case.resolved, start, case.dt, lever=lever)
    tol = cal.tolerances(ref, case.dt)
    row = {"scene": name, "reference": ref, "tolerance": tol, "codes": {}}
    for c, r in results.items():
        if not r.ok:
            row["codes"][c] = {"failed": r.reason}
            continue
        try:
            row["codes"][c] = cal.measure(case.resolved, start, np.asarray(r.discs_end, float), case.duration,
                                          r.profiles)
        except ValueError as e:
            row["codes"][c] = {"failed": str(e)}
    ok = {c: m for c, m in row["codes"].items() if "failed" not in m}
    row["pass"] = {c: cal.within(m, ref, case.dt) for c, m in ok.items()}
    row["agree"] = {f"{c} vs native": cal.within(ok[c], ref, case.dt, other=ok["native"])
                    for c in ok if c != "native" and "native" in ok}
    row["failures"] = failures(results)
    metrics = []
    for c in results if tol else []:       # a scene without a reference: the codes against native only
        mname = f"collision against the reference ({c})"
        if c not in ok:
            metrics.append(unjudged(mname, name, f"run failed: {row['codes'][c]['failed']}"))
            continue
        bad = [f"{q} {ok[c][q]:.7g} vs {ref[q]:.7g} (tol {tol[q]:.2g})" for q, p in row["pass"][c].items() if not p]
        metrics.append(metric(mname, name, {"max_diff_over_tolerance": _worst(ok[c], ref, tol)},
                              "K dt/t_c x the quantity's change (+ sliding term)", not bad, "; ".join(bad)))
    code_tol = cal.code_tolerances(ref)
    for c in results:
        if c == "native":
            continue
        mname = f"collision ({c} vs native)"
        if c not in ok or "native" not in ok:
            metrics.append(unjudged(mname, name, "run failed: " + row["failures"]))
            continue
        agree = row["agree"][f"{c} vs native"]
        bad = [f"{q} {ok[c][q]:.9g} vs {ok['native'][q]:.9g}" for q, p in agree.items() if not p]
        metrics.append(metric(mname, name, {"max_diff_over_tolerance": _worst(ok[c], ok["native"], code_tol)},
                              f"{cal.CODE_REL:g} x the quantity's change", not bad, "; ".join(bad)))
    return metrics, row

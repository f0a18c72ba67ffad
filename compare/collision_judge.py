"""The verdict on a collision scene: each code's measured rebound (compare/calibration.py) against
the analytic or independent reference, and each reference code against the native engine.

Two tolerances (calibration.TOL): against the reference, the explicit schemes' first-order error
in dt / t_c; between codes, which run the same discrete law at the same dt, the codes' own
measured agreement.
"""
from __future__ import annotations

import math

import numpy as np

from . import calibration as cal
from .common import Case
from .study import failures, metric


def _close(a: float, b: float, rel: float, abs_: float) -> bool:
    if not (math.isfinite(a) and math.isfinite(b)):
        return a == b or (math.isnan(a) and math.isnan(b))
    return abs(a - b) <= max(abs_, rel * max(abs(a), abs(b)))


def judge(name: str, case: Case, results: dict) -> tuple[list, dict]:
    start = np.asarray(case.discs, float)
    ref = cal.reference(case.resolved, start, case.dt)
    meas = {}
    for c, r in results.items():
        if r.ok:
            try:
                meas[c] = cal.measure(case.resolved, start, np.asarray(r.discs_end, float), case.duration, result=r)
            except ValueError as e:
                r.status, r.reason = "failed", str(e)
    metrics = []
    for c in results:
        if c not in meas:
            metrics.append(metric(f"collision against the reference ({c})", name, {}, "", False,
                                  "run failed: " + failures(results)))
            continue
        bad, worst = [], 0.0
        for q, v in ref.items():
            if q not in meas[c] or not isinstance(v, (int, float)):
                continue
            tol = cal.tolerance(q, case, against="reference")
            if tol is None:
                continue
            ok = _close(meas[c][q], v, *tol)
            scale = max(tol[0] * max(abs(v), abs(meas[c][q])), tol[1])
            worst = max(worst, abs(meas[c][q] - v) / scale if scale > 0 else 0.0)
            if not ok:
                bad.append(f"{q} {meas[c][q]:.6g} vs {v:.6g}")
        metrics.append(metric(f"collision against the reference ({c})", name,
                              {"max_diff_over_tolerance": worst}, "calibration.TOL (reference)", not bad,
                              "; ".join(bad)))
    nat = meas.get("native")
    for c in results:
        if c == "native" or c not in meas or nat is None:
            if c != "native" and (c not in meas or nat is None):
                metrics.append(metric(f"collision ({c} vs native)", name, {}, "", False,
                                      "run failed: " + failures(results)))
            continue
        bad, worst = [], 0.0
        for q, v in nat.items():
            if q not in meas[c] or not isinstance(v, (int, float)):
                continue
            tol = cal.tolerance(q, case, against="code")
            if tol is None:
                continue
            scale = max(tol[0] * max(abs(v), abs(meas[c][q])), tol[1])
            worst = max(worst, abs(meas[c][q] - v) / scale if scale > 0 else 0.0)
            if not _close(meas[c][q], v, *tol):
                bad.append(f"{q} {meas[c][q]:.8g} vs {v:.8g}")
        metrics.append(metric(f"collision ({c} vs native)", name, {"max_diff_over_tolerance": worst},
                              "calibration.TOL (between codes)", not bad, "; ".join(bad)))
    return metrics, {"case": name, "reference": ref, "codes": meas, "failures": failures(results)}

"""The verdict on a shear case (compare/cases/shear.py reads and measures every code's runs).

The judge (``judge``): per member, the initial normal stress sigma0 (at the start of the shear),
the windowed peak of tau/sigma (largest centred moving average over WINDOW of strain), the mean
tau/sigma in each strain band of BANDS (the curve against shear displacement) and the dilation
(the plate's rise from the start of the shear to its end); each an equivalence metric of the
ensemble means against the shear margin (compare/cases/stats.py, compare/cases/margins.py); and, per code,
whether every member came to rest before the shear (a member sheared from motion is not the
paper's test).

``plot`` draws tau/sigma and the plate's rise against shear strain, each code's ensemble mean.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from dem.compare.cases import stats
from dem.compare.cases.shear import band_key, bands, curve, label, measures
from dem.compare.verdict import verdict
from dem.compare.verdict.report import COLORS, _savefig
from dem.compare.verdict.study import metric


def judge(name: str, per_code: dict, max_strain: float, sample_strain: float, options) -> tuple[list, dict]:
    """per_code: code -> [Result] over the members (Result.extra["shear"] from read_outputs).
    Returns the metrics and the detail for the report (ensemble means, curves)."""
    keys = ["sigma0", "peak_windowed"] + [band_key(lo, hi) for lo, hi in bands(max_strain)] + ["dilation"]
    codes = list(per_code)
    refs = [c for c in codes if c != "native"]
    meas, failed = {}, {}
    for c, runs in per_code.items():
        meas[c], failed[c] = [], []
        for k, r in enumerate(runs):
            m = measures(r.extra["shear"], max_strain) if r.ok and "shear" in r.extra else {}
            if not m:
                failed[c].append(f"member {k}: {r.reason or 'no shear series'}")
            meas[c].append(m)
    summary = {c: {k: stats.mean_se([m.get(k) for m in meas[c] if m]) for k in
                   keys + ["peak_raw", "strain_at_peak", "strain_end"]} for c in codes}
    for c in codes:
        summary[c]["failed"] = failed[c]
        summary[c]["rested"] = [bool(m.get("rest_reached")) for m in meas[c] if m]
    metrics = []
    for c in codes:                       # every member sheared from rest
        rested = summary[c]["rested"]
        ok = not failed[c] and all(rested) and len(rested) == len(per_code[c])
        metrics.append(dict(metric(f"shear: every member at rest before the shear ({c})", name,
                                   {"at_rest": sum(rested), "members": len(per_code[c])}, "all", ok,
                                   "; ".join(failed[c][:2]) if failed[c] else
                                   ("" if ok else "a member was sheared before it came to rest (end.time, --settle)")),
                            kind="deterministic"))
    for c in refs:
        for k in keys:
            mname = f"shear {label(k)} ({c} vs native)"
            if failed[c] or failed.get("native"):
                metrics.append(verdict.unjudged(mname, name, "failed members: " + "; ".join(
                    (failed[c] + failed.get("native", []))[:2]), "statistical"))
                continue
            st = stats.difference([m.get(k) if m else None for m in meas["native"]],
                                  [m.get(k) if m else None for m in meas[c]], relative=True, paired=True)
            a, b = summary["native"][k], summary[c][k]
            metrics.append(verdict.statistical(mname, name, st, "shear", options,
                                               {"native": [a[0], a[1]], c: [b[0], b[1]]}))
    grid = np.round(np.arange(0.0, max_strain + 0.5 * sample_strain, sample_strain), 12)
    curves = {}
    for c, runs in per_code.items():
        ok = [r.extra["shear"] for r, m in zip(runs, meas[c]) if m]
        if not ok:
            continue
        cur = {}
        for col in ("ratio", "plate_y"):
            ys = np.array([curve(e, grid, col) - (curve(e, grid[:1], col)[0] if col == "plate_y" else 0.0)
                           for e in ok])
            n = np.sum(np.isfinite(ys), axis=0)
            mean = np.nanmean(ys, axis=0)
            se = np.nanstd(ys, axis=0, ddof=1) / np.sqrt(np.maximum(n, 1)) if len(ok) > 1 else np.full(len(grid), np.nan)
            cur[col] = {"mean": mean.tolist(), "se": se.tolist()}
        curves[c] = cur
    detail = {"case": name, "members": max(len(r) for r in per_code.values()), "keys": keys,
              "summary": summary, "strain": grid.tolist(), "curves": curves}
    return metrics, detail


def plot(detail: dict, png: Path) -> None:
    """tau/sigma and the plate's rise against shear strain: each code's ensemble mean +- 1 s.e."""
    g = np.asarray(detail["strain"], float)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for c, cur in detail["curves"].items():
        for ax, col in zip(axes, ("ratio", "plate_y")):
            m, se = np.asarray(cur[col]["mean"], float), np.nan_to_num(np.asarray(cur[col]["se"], float))
            ax.plot(g, m, color=COLORS.get(c, "k"), lw=1.2, label=f"{c} ({len(detail['summary'][c]['rested'])} members)")
            ax.fill_between(g, m - se, m + se, color=COLORS.get(c, "k"), alpha=0.25, lw=0)
    for lo, hi in bands(g[-1] if len(g) else 0.0):
        axes[0].axvline(lo, color="0.8", lw=0.8)
    axes[0].set_ylabel("tau / sigma")
    axes[1].set_ylabel("plate rise since the start of the shear [cm]")
    for ax in axes:
        ax.set_xlabel("shear strain gamma = tan(wall angle)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"{detail['case']}: ensemble mean ± 1 s.e. of every code", fontsize=10)
    fig.tight_layout()
    _savefig(fig, Path(png))

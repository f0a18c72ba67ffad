#!/usr/bin/env python3
"""The members a discharge ensemble needs for an equivalence verdict, from measured members.

Reads the members' measures of one or more `dem compare` runs of a discharge
(OUT/discharge/NAME/series.json, OUT/discharge/NAME/mK/CODE/result.json for the wall time) and
prints, per metric: each code's per-member coefficient of variation (CV), the correlation of
member k of the native engine with member k of each reference code (the same jittered start
under --start frozen), and the members per code whose 90 % interval of the relative difference
(code vs native) fits in a margin (10 %, 5 %) when the true difference is 0 or 3 %, unpaired
(half-width t_{0.95,2n-2} CV sqrt(2/n)) and paired (t_{0.95,n-1} sd(b_k - R a_k) / sqrt(n) / mean a).

  python3 benchmarks/discharge_design.py OUT/discharge/NAME [more folders of the same scene]
      [--peak-windows=0.1,0.2]   (also the windowed peak ratios with these windows [s])
      [--keep=discs_out,flow_rate,...]   (the metrics whose joint pass probability is printed)
"""
from __future__ import annotations

import json
import math
import sys
import types
from pathlib import Path

import numpy as np
from scipy import stats as sps

METRICS = ("discs_out", "flow_rate", "flow_side_normal", "flow_side_shear", "flow_bottom_normal",
           "peak_window_side", "peak_window_bottom")
MARGINS = (0.10, 0.05)
TRUE_DIFFS = (0.0, 0.03)


def other_peaks(res_path: Path, resolved: dict, windows) -> dict:
    """The windowed peak ratios of one member recomputed with other windows [s] (what a longer
    PEAK_WINDOW would give: peak_window_side@0.2 ...)."""
    from dem.compare.verdict import study
    from dem.compare.cases.common import Result
    res = Result.load(res_path)
    case = types.SimpleNamespace(series_interval=0.005, resolved=resolved)
    out, keep = {}, study.PEAK_WINDOW
    try:
        for w in windows:
            study.PEAK_WINDOW = w
            out.update({f"{k}@{w:g}": v for k, v in study.windowed_peaks(res, case).items()})
    finally:
        study.PEAK_WINDOW = keep
    return out


def load(folders, windows=()) -> tuple[dict, dict]:
    """code -> {member: measures}, code -> [wall seconds a member]."""
    per, secs = {}, {}
    for f in map(Path, folders):
        ser = json.loads((f / "series.json").read_text())
        resolved = None
        for code, runs in ser.items():
            for k, r in enumerate(runs):
                res = f / f"m{k}" / code / "result.json"
                if r["status"] == "ok" or r["measures"]:
                    m = per.setdefault(code, {})[(str(f), k)] = dict(r["measures"])
                    if windows and res.exists():
                        if resolved is None:
                            from dem.compare.cases.common import resolve
                            resolved = resolve(f / "m0" / "native" / "scene.toml")   # the walls and the gate
                        m.update(other_peaks(res, resolved, windows))
                if res.exists():
                    secs.setdefault(code, []).append(json.loads(res.read_text()).get("wall_time_s", float("nan")))
    return per, secs


def members_needed(sd_rel: float, margin: float, delta: float, paired: bool) -> int:
    """Fewest members per code whose expected 90 % half-width plus |delta| fits in the margin."""
    if not math.isfinite(sd_rel) or margin <= delta:
        return -1
    for n in range(2, 100_000):
        df, f = (n - 1, 1.0) if paired else (2 * n - 2, math.sqrt(2.0))
        if sps.t.ppf(0.95, df) * sd_rel * f / math.sqrt(n) + delta <= margin:
            return n
    return 100_000


def pass_probability(diffs_cvs, n: int, margin: float) -> float:
    """Probability that every metric's unpaired 90 % interval of the relative difference lies in
    +-margin with n members per code, each metric's true difference and pooled CV as measured
    (the estimates independent, normal)."""
    p = 1.0
    for d, cv in diffs_cvs:
        se = cv * math.sqrt(2.0 / n)
        room = margin - sps.t.ppf(0.95, 2 * n - 2) * se    # |estimate| must stay below this
        p *= max(0.0, sps.norm.cdf((room - d) / se) - sps.norm.cdf((-room - d) / se)) if room > 0 else 0.0
    return p


def main(argv) -> int:
    windows = [float(w) for a in argv if a.startswith("--peak-windows=") for w in a.split("=", 1)[1].split(",")]
    folders = [a for a in argv if not a.startswith("--")]
    keep = next((a.split("=", 1)[1].split(",") for a in argv if a.startswith("--keep=")), list(METRICS))
    per, secs = load(folders, windows)
    metrics = METRICS + tuple(f"peak_window_{g}@{w:g}" for w in windows for g in ("side", "bottom"))
    print("| code | members | wall s a member (mean, max) |")
    print("|---|---|---|")
    for c, s in secs.items():
        print(f"| {c} | {len(per.get(c, {}))} | {np.nanmean(s):.1f}, {np.nanmax(s):.1f} |")
    print()
    head = " | ".join(f"n unpaired / paired, {m:.0%} margin, diff {d:.0%}" for m in MARGINS for d in TRUE_DIFFS)
    print(f"| metric | code | mean | CV | corr with native (pairs) | sd(b-Ra)/mean a | {head} |")
    print("|" + "---|" * (6 + len(MARGINS) * len(TRUE_DIFFS)))
    nat = per.get("native", {})
    verdict = []        # (measured relative difference, pooled CV) of each kept metric and code
    for key in metrics:
        a_all = np.array([m.get(key, np.nan) for m in nat.values()], float)
        cv_a = np.nanstd(a_all, ddof=1) / abs(np.nanmean(a_all))
        print(f"| {key} | native | {np.nanmean(a_all):.4g} | {cv_a:.2%} | | | "
              + " | ".join(f"{members_needed(cv_a, m, d, False)} / -" for m in MARGINS for d in TRUE_DIFFS) + " |")
        for c, mem in per.items():
            if c == "native":
                continue
            b_all = np.array([m.get(key, np.nan) for m in mem.values()], float)
            cv_b = np.nanstd(b_all, ddof=1) / abs(np.nanmean(b_all))
            pairs = [(nat[k].get(key, np.nan), mem[k].get(key, np.nan)) for k in mem if k in nat]
            a, b = np.array(pairs, float).T if pairs else (np.array([]), np.array([]))
            ok = np.isfinite(a) & np.isfinite(b)
            a, b = a[ok], b[ok]
            r = float(np.corrcoef(a, b)[0, 1]) if len(a) > 2 else float("nan")
            ratio = b.mean() / a.mean() if len(a) else float("nan")
            sd_p = float(np.std(b - ratio * a, ddof=1) / abs(a.mean())) if len(a) > 1 else float("nan")
            cv_u = math.sqrt((cv_a ** 2 + cv_b ** 2) / 2)     # the pooled CV the unpaired interval sees
            cells = [f"{members_needed(cv_u, m, d, False)} / {members_needed(sd_p, m, d, True)}"
                     for m in MARGINS for d in TRUE_DIFFS]
            print(f"| {key} | {c} | {np.nanmean(b_all):.4g} (ratio {ratio:.3f}) | {cv_b:.2%} | {r:+.2f} ({len(a)}) | "
                  f"{sd_p:.2%} | " + " | ".join(cells) + " |")
            if key in keep:
                verdict.append((np.nanmean(b_all) / np.nanmean(a_all) - 1.0, cv_u))
    print_pass_probabilities(keep, verdict)
    return 0


def print_pass_probabilities(keep, verdict) -> None:
    print()
    print(f"Probability that every kept metric passes ({', '.join(keep)}; unpaired, CVs as measured):")
    zero = [(0.0, c) for _, c in verdict]
    for margin, ns in ((0.10, (4, 6, 8, 10, 12, 16)), (0.05, (8, 12, 16, 24, 32, 48))):
        for label, v in (("true differences as measured", verdict), ("true differences 0", zero)):
            print(f"  +-{margin:.0%}, {label}: "
                  + ", ".join(f"n={n}: {pass_probability(v, n, margin):.2f}" for n in ns))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

"""The runners and the judges of the comparison (compare/verdict/pipeline.py drives them): one run of
one code, and the metrics of a static case (deterministic: every code rests from the same frozen
packing) and of a discharge ensemble (statistical: compare/cases/stats.py).

A failed run of any code (crash, timeout, blow-up, lost discs, missing output) makes every
metric that needs it fail, with the code's reason: a failure is never agreement.
"""
from __future__ import annotations

import json
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from dem.compare.codes import backends
from dem.compare.cases import stats
from dem.compare.verdict import verdict
from dem.compare.cases.common import ROOT, SHARED_VARIANT, Case, Result, failed, resolve

CODES = ("native", "liggghts", "yade", "lammps")
SCENES = ROOT / "reference_inputs" / "scenes"
# Stable dt with velocity Verlet and the paper's constants (reference-codes.md; the engine's
# bound for 11/12-type loose lattices is lower than for the dense ones).
LATTICE_DT = {12: 2.5e-5, 13: 4e-5}  # durations must be whole numbers of steps (YADE)
DEFAULT_DT = 5e-5

# Static tolerances of a frozen-packing comparison (relative): compare/verdict/pipeline.py passes those
# matched to the codes' agreement; these defaults are the loose ones of a first look.
TOL_TOTAL = 0.03        # wall normal totals
TOL_SHEAR_TOTAL = 0.10  # side-wall friction totals
TOL_CUMULATIVE = 0.05   # cumulative profile: max difference / wall total
# The flow window: from FLOW_START after the opening (the discs over the slit have fallen and the
# first arches broken: the flow rate is steady from about the 5th removal, ~0.07 s in 11/12) to
# the end of the run, the same window in every code. The flow rate is the slope of the removed
# count over it (steady_flow_rate); the time-averaged wall forces during flow are the mean of
# every wall-force sample in it. Totals per wall group are judged like the other discharge means;
# the cumulative profile of each wall (from its 'from' end) point by point, the level split over
# the points.
FLOW_START = 0.1        # [s] since opening
FLOW_MIN_SAMPLES = 10


def backend(code: str):
    return backends.backend(code)


def run_code(code: str, case: Case, out: Path, timeout: float, threads: int = 1,
             reuse: bool = False, resume: bool = False) -> Result:
    """One run of one code; a missing backend or binary is a failure, never a skip. ``resume``:
    a finished run (result.json ok) in ``out`` whose translated inputs are byte for byte the ones
    this case translates to is read back instead of run again (a failed run runs again)."""
    try:
        be = backend(code)
    except ImportError as e:
        return failed(code, case.name, f"backend not importable: {e}")
    if not be.available():
        return failed(code, case.name, f"{code} is not installed")
    cached = out / "result.json"
    if reuse and cached.exists():    # a mutant or attribution run: the unchanged codes' baseline
        return Result.load(cached)
    if resume and cached.exists():
        old = Result.load(cached)
        if old.ok and same_inputs(be, case, out, threads):
            return old
    t0 = time.monotonic()
    try:
        res = be.run(case, out, timeout=timeout, threads=threads)
    except Exception as e:  # noqa: BLE001 - any backend error is that code's failure
        res = failed(code, case.name, f"backend error: {type(e).__name__}: {e}", out_dir=str(out))
    if not math.isfinite(res.wall_time_s):
        res.wall_time_s = time.monotonic() - t0
    out.mkdir(parents=True, exist_ok=True)
    res.save(cached)
    return res


def same_inputs(be, case: Case, out: Path, threads: int = 1) -> bool:
    """Whether the backend's translation of ``case`` (every file its write_inputs writes) equals,
    byte for byte, the files of the same names in ``out``."""
    with tempfile.TemporaryDirectory() as t:
        try:
            be.write_inputs(case, Path(t), threads)
        except Exception:  # noqa: BLE001 - a case that no longer translates runs (and fails) anew
            return False
        files = [f for f in Path(t).rglob("*") if f.is_file()]
        return bool(files) and all((out / f.relative_to(t)).is_file()
                                   and (out / f.relative_to(t)).read_bytes() == f.read_bytes() for f in files)


def metric(name, scene, values: dict, tol, passed, note="", unit="") -> dict:
    """A deterministic metric: agree within its tolerance, else disagree (compare/verdict/verdict.py)."""
    return {"metric": name, "scene": scene, "values": values, "tolerance": tol, "pass": bool(passed),
            "verdict": "agree" if passed else "disagree", "note": note, "unit": unit}


def failures(results: dict) -> str:
    return "; ".join(f"{c}: {r.reason}" for c, r in results.items() if not r.ok)


# ---------------------------------------------------------------- static cases

def _edge_flips(d: np.ndarray, scale: float) -> int | None:
    """Number of contacts that moved across one bin edge if ``d`` (bin differences) is made of
    such moves only (pairs k, k+1 of equal and opposite values), else None."""
    nz = list(np.nonzero(np.abs(d) > 1e-3 * scale)[0])  # above the codes' 1e-5 agreement
    flips = 0
    while nz:
        k = nz.pop(0)
        if nz and nz[0] == k + 1 and abs(d[k] + d[k + 1]) <= 1e-2 * max(abs(d[k]), 1e-300):
            nz.pop(0)
            flips += 1
        else:
            return None
    return flips


def cumulative_diff(a: dict, b: dict, key: str = "normal") -> tuple[float, int]:
    """Largest difference of the cumulative profiles (force from the wall's ``from`` end up to
    each bin edge), relative to that wall's total in ``a``, and the number of contacts that sit
    on a bin edge and count on the other side in ``b`` (the disc over the centre of the gate in
    the symmetric lattices: LIGGGHTS's mesh gives it to the other strip). Walls whose whole
    difference is such edge moves are left out of the largest difference."""
    worst, flips = 0.0, 0
    for w in a:
        if w in b and len(a[w][key]) == len(b[w][key]):
            x, y = np.array(a[w][key], float), np.array(b[w][key], float)
            tot = abs(x.sum())
            if tot == 0:
                continue
            f = _edge_flips(y - x, max(np.abs(x).max(), 1e-300))
            if f:
                flips += f
                continue
            worst = max(worst, float(np.max(np.abs(np.cumsum(x) - np.cumsum(y))) / tot))
    return worst, flips


def profile_diff(a: dict, b: dict, key: str = "normal") -> float:
    """RMS of the bin differences over all walls, relative to the mean |bin| of ``a``."""
    da, db = [], []
    for w in a:
        if w in b:
            x, y = np.array(a[w][key]), np.array(b[w][key])
            if len(x) == len(y):
                da.append(x)
                db.append(y)
    if not da:
        return float("nan")
    x, y = np.concatenate(da), np.concatenate(db)
    scale = np.mean(np.abs(x))
    return float(np.sqrt(np.mean((x - y) ** 2)) / scale) if scale > 0 else float("nan")


def wall_totals(res: Result) -> dict:
    out = {}
    for w, p in res.profiles.items():
        out[w] = {"normal": float(np.sum(p["normal"])), "shear": float(np.sum(p["shear"]))}
    return out


def static_compare(case: Case, results: dict, tolerances=(TOL_TOTAL, TOL_SHEAR_TOTAL, TOL_CUMULATIVE)
                   ) -> tuple[list, dict]:
    """Every code from the same packing: the largest relative difference of the wall normal
    totals, of the side-wall friction totals and of the cumulative normal profiles, each against
    its tolerance (tol_total, tol_shear, tol_cumulative)."""
    TOL_TOTAL, TOL_SHEAR_TOTAL, TOL_CUMULATIVE = tolerances
    metrics = []
    ref = results.get("native")
    detail = {"case": case.name, "n_discs": len(case.discs), "dt": case.dt, "duration": case.duration,
              "results": {c: {"status": r.status, "reason": r.reason, "wall_time_s": r.wall_time_s,
                              "kinetic_energy_end": r.kinetic_energy_end, "totals": wall_totals(r) if r.ok else {}}
                          for c, r in results.items()}}
    side = [w["name"] for w in case.resolved["walls"] if w["group"].startswith("side")]
    for c, r in results.items():
        if c == "native":
            continue
        if not (r.ok and ref is not None and ref.ok):
            metrics.append(verdict.unjudged(f"static wall totals ({c} vs native)", case.name,
                                    "run failed: " + failures(results)))
            metrics.append(verdict.unjudged(f"static profile ({c} vs native)", case.name, "run failed: " + failures(results)))
            continue
        ta, tb = wall_totals(ref), wall_totals(r)
        worst, worst_s = 0.0, 0.0
        for w in ta:
            if w in tb and abs(ta[w]["normal"]) > 0:
                worst = max(worst, abs(tb[w]["normal"] - ta[w]["normal"]) / abs(ta[w]["normal"]))
        for w in side:
            if w in tb and abs(ta[w]["shear"]) > 0:
                worst_s = max(worst_s, abs(tb[w]["shear"] - ta[w]["shear"]) / abs(ta[w]["shear"]))
        metrics.append(metric(f"static wall normal totals ({c} vs native)", case.name,
                              {"max_rel_diff": worst}, TOL_TOTAL, worst <= TOL_TOTAL))
        metrics.append(metric(f"static side-wall friction totals ({c} vs native)", case.name,
                              {"max_rel_diff": worst_s}, TOL_SHEAR_TOTAL, worst_s <= TOL_SHEAR_TOTAL))
        pd = profile_diff(ref.profiles, r.profiles)
        cd, flips = cumulative_diff(ref.profiles, r.profiles)
        metrics.append(metric(f"static normal profile, cumulative from the 'from' end ({c} vs native)", case.name,
                              {"max_rel": cd, "per_bin_rms_rel": pd, "edge_contacts": flips}, TOL_CUMULATIVE,
                              cd <= TOL_CUMULATIVE,
                              f"{flips} contact(s) on a bin edge counted in the neighbouring bin" if flips else ""))
    return metrics, detail


# ---------------------------------------------------------------- discharge

def discharge_case(scene: Path, dt: float, settle: float, duration: float, member: int, perturb: float) -> Case:
    r = resolve(scene)
    r["contact"] = dict(SHARED_VARIANT)
    d = np.array(r["discs"], float)
    rng = np.random.default_rng(1000 + member)
    xy = d[:, :2] + (rng.uniform(-perturb, perturb, size=(len(d), 2)) if member else 0.0)
    discs = np.column_stack([xy, d[:, 2], np.zeros((len(d), 3))])
    return Case(name=f"{r['name']}_m{member}", resolved=r, discs=discs, dt=dt, duration=duration,
                mode="discharge", settle=settle, seed=member)


FLOW_MIN_REMOVALS = 10   # removals in the flow window for a flow rate (fewer: a jam, judged as such)


def steady_flow_rate(removals, t0: float, t1: float) -> float:
    """[discs/s] the least-squares slope of the removed count against time over the steady window
    t0 <= t <= t1 (removal times since the opening): the rate of the steady flow, the opening's
    transient (the fall of the first discs to the outlet depth, the arch's first breaks) before t0
    left out. NaN with fewer than FLOW_MIN_REMOVALS removals in the window."""
    t = np.sort(np.asarray(removals, float))
    sel = (t >= t0 - 1e-12) & (t <= t1 + 1e-12)
    if sel.sum() < FLOW_MIN_REMOVALS:
        return float("nan")
    return float(np.polyfit(t[sel], np.nonzero(sel)[0] + 1.0, 1)[0])


def discharge_measures(res: Result, case: Case) -> dict:
    """Flow rate (discs/s over the flow window, steady_flow_rate), discs out, jam, peak ratios."""
    t = np.sort(np.array(res.removals, float))
    out = {"discs_out": int(len(t)), "flow_rate": steady_flow_rate(t, *flow_window(case)), "jammed": False}
    last = t[-1] if len(t) else 0.0
    out["jammed"] = bool(case.duration - last > float(case.resolved["discharge"]["jam_time"])
                         and res.n_final > 0)
    # Peak ratio: bottom and side walls, bins loaded at rest at >= 1/4 of the wall's largest bin.
    ser = res.series
    peaks = {}
    if ser and ser.get("t"):
        for group in ("side", "bottom"):
            best = 0.0
            for w in case.resolved["walls"]:
                if not w["group"].startswith(group) or w["name"] == case.resolved["discharge"]["gate"]:
                    continue
                s = np.array(ser["walls"].get(w["name"], {}).get("normal", []), float)
                if s.ndim != 2 or len(s) < 2:
                    continue
                static = s[0]
                if static.max() <= 0:
                    continue
                sel = static >= 0.25 * static.max()
                best = max(best, float(np.max(s[1:, sel] / static[sel])))
            peaks[group] = best
    out["peak_ratio_side"] = peaks.get("side", float("nan"))
    out["peak_ratio_bottom"] = peaks.get("bottom", float("nan"))
    out.update(windowed_peaks(res, case))
    out.update(flow_profile(res, case))
    return out


PEAK_WINDOW = 0.05   # [s] moving average of a wall group's total before its maximum is taken


def windowed_peaks(res: Result, case: Case) -> dict:
    """Per wall group (side, bottom; gate left out): the largest PEAK_WINDOW moving average of the
    group's total normal force after the opening, over its value at the opening. A time-averaged
    maximum, far less heavy-tailed than one sample of one bin."""
    out = {"peak_window_side": float("nan"), "peak_window_bottom": float("nan")}
    ser = res.series
    if not ser or not ser.get("t") or len(ser["t"]) < 2:
        return out
    t = np.array(ser["t"], float)
    k = max(1, int(round(PEAK_WINDOW / max(case.series_interval, 1e-300))))
    gate = case.resolved["discharge"]["gate"]
    for group in ("side", "bottom"):
        tot = np.zeros(len(t))
        for w in case.resolved["walls"]:
            if not w["group"].startswith(group) or w["name"] == gate:
                continue
            s = np.array(ser["walls"].get(w["name"], {}).get("normal", []), float)
            if s.ndim == 2 and len(s) == len(t):
                tot += s.sum(axis=1)
        if tot[0] <= 0 or len(tot) < k + 1:
            continue
        avg = np.convolve(tot[1:], np.ones(k) / k, mode="valid")
        out[f"peak_window_{group}"] = float(avg.max() / tot[0])
    return out


def flow_window(case: Case) -> tuple[float, float]:
    return FLOW_START, float(case.duration)


def flow_profile(res: Result, case: Case) -> dict:
    """Wall forces per bin averaged over the flow window (every sample with FLOW_START <= t <=
    the end), gate left out: ``flow_profile`` {wall: {group, s_lo, s_hi, normal, shear}} and the
    totals of the side walls (normal, shear) and of the bottom (normal)."""
    t0, t1 = flow_window(case)
    nan = float("nan")
    out = {"flow_profile": {}, "flow_side_normal": nan, "flow_side_shear": nan, "flow_bottom_normal": nan,
           "flow_samples": 0, "flow_window": [t0, t1]}
    ser = res.series
    if not ser or not ser.get("t"):
        return out
    t = np.array(ser["t"], float)
    sel = (t >= t0 - 1e-9) & (t <= t1 + 1e-9)
    out["flow_samples"] = int(sel.sum())
    if sel.sum() < FLOW_MIN_SAMPLES:
        return out
    gate = case.resolved["discharge"]["gate"]
    tot = {"side_normal": 0.0, "side_shear": 0.0, "bottom_normal": 0.0}
    for w in case.resolved["walls"]:
        if w["name"] == gate or w["name"] not in ser["walls"]:
            continue
        nrm = np.array(ser["walls"][w["name"]]["normal"], float)
        shr = np.array(ser["walls"][w["name"]]["shear"], float)
        if nrm.ndim != 2 or len(nrm) != len(t):
            continue
        prof = res.profiles.get(w["name"], {})
        n_avg, s_avg = nrm[sel].mean(axis=0), shr[sel].mean(axis=0)
        out["flow_profile"][w["name"]] = {"group": w["group"], "s_lo": prof.get("s_lo"), "s_hi": prof.get("s_hi"),
                                          "normal": n_avg.tolist(), "shear": s_avg.tolist()}
        if w["group"].startswith("side"):
            tot["side_normal"] += float(n_avg.sum())
            tot["side_shear"] += float(s_avg.sum())
        elif w["group"].startswith("bottom"):
            tot["bottom_normal"] += float(n_avg.sum())
    for k, v in tot.items():
        out["flow_" + k] = v
    return out


FLOW_TOTALS = ("flow_side_normal", "flow_side_shear", "flow_bottom_normal")


def ensemble_profile(members: list) -> dict:
    """Per wall: ensemble mean and standard error of each bin of the time-averaged profiles and of
    the cumulative profile from the wall's 'from' end (members: flow_profile of each member)."""
    out = {}
    members = [m for m in members if m]
    if not members:
        return out
    for w, p0 in members[0].items():
        rows = [m[w] for m in members if w in m and len(m[w]["normal"]) == len(p0["normal"])]
        n = np.array([r["normal"] for r in rows], float)
        sh = np.array([r["shear"] for r in rows], float)
        cum = np.cumsum(n, axis=1)

        def se(a):
            return (np.std(a, axis=0, ddof=1) / math.sqrt(len(a))).tolist() if len(a) > 1 else [float("nan")] * a.shape[1]
        out[w] = {"group": p0["group"], "s_lo": p0["s_lo"], "s_hi": p0["s_hi"], "members": len(rows),
                  "normal": n.mean(axis=0).tolist(), "normal_se": se(n),
                  "shear": sh.mean(axis=0).tolist(), "shear_se": se(sh),
                  "cumulative": cum.mean(axis=0).tolist(), "cumulative_se": se(cum)}
    return out


def profile_stat(ref: dict, other: dict, group: str, n_a: int, n_b: int) -> dict:
    """The cumulative time-averaged normal profiles of the walls of ``group`` (side or bottom) as a
    profile statistic: at each point the difference of the ensemble means (Welch), relative to its
    wall's total in the reference (compare/cases/stats.py judges every point against the margin)."""
    walls = [w for w, p in ref.items() if p["group"].startswith(group)]
    base = {"type": "profile", "relative": True, "n": [n_a, n_b], "walls": walls}
    if not walls or any(w not in other or len(other[w]["normal"]) != len(ref[w]["normal"]) for w in walls):
        return dict(base, reason="time-averaged profile missing in one code")
    points = []
    for w in walls:
        a, b = ref[w], other[w]
        total = abs(a["cumulative"][-1]) or 1.0
        for k in range(len(a["cumulative"])):
            sa, sb = a["cumulative_se"][k], b["cumulative_se"][k]
            df = stats.welch_df(sa, n_a, sb, n_b)
            points.append([(b["cumulative"][k] - a["cumulative"][k]) / total, math.hypot(sa, sb) / total, df])
    if any(not math.isfinite(p[1]) for p in points):
        return dict(base, reason="needs 2 members in each code for a profile's spread")
    return dict(base, points=points)


DISCHARGE_MEANS = ("discs_out", "flow_rate") + FLOW_TOTALS + ("peak_window_side", "peak_window_bottom")
MARGIN_KIND = {"discs_out": "discs_out", "flow_rate": "flow_rate", "flow_side_normal": "wall_load",
               "flow_side_shear": "wall_friction", "flow_bottom_normal": "wall_load", "peak_window_side": "peak",
               "peak_window_bottom": "peak"}


def discharge_summary(runs: list) -> dict:
    """One code's members [(Result, measures)]: means, jams, medians and the ensemble profile."""
    ok = [m for r, m in runs if r.ok]
    fails = [r.reason for r, _ in runs if not r.ok]
    return {"members": len(runs), "failed": len(fails), "failures": fails,
            **{k: stats.mean_se([m.get(k, float("nan")) for m in ok]) for k in DISCHARGE_MEANS},
            "values": {k: [m.get(k, float("nan")) if r.ok else None for r, m in runs] for k in DISCHARGE_MEANS},
            "jammed": sum(bool(m["jammed"]) for m in ok), "ok_members": len(ok),
            "jam_fraction": (sum(m["jammed"] for m in ok) / len(ok)) if ok else float("nan"),
            "peak_ratio_side": stats.bootstrap_median([m["peak_ratio_side"] for m in ok]),
            "peak_ratio_bottom": stats.bootstrap_median([m["peak_ratio_bottom"] for m in ok]),
            "flow_profile": ensemble_profile([m.get("flow_profile", {}) for m in ok]),
            "flow_window": next((m["flow_window"] for m in ok if "flow_window" in m), None)}


def discharge_compare(scene_name: str, per_code: dict, options) -> tuple[list, dict]:
    """per_code: code -> list of (Result, measures), members in the same order in every code (member
    k of every code starts from the same state: paired where that narrows the interval). Every
    kept metric kind (options.metrics, default all) is an equivalence metric with its margin
    (compare/cases/margins.py): the means, the cumulative profiles point by point, the jam fraction."""
    keep = set(options.metrics) if options.metrics else None
    summary = {c: discharge_summary(runs) for c, runs in per_code.items()}
    ref = summary.get("native")
    metrics = []
    for c in (c for c in summary if c != "native"):
        s = summary[c]
        if s["failed"] or not ref or ref["failed"]:
            why = "; ".join(s["failures"][:2] + (ref["failures"][:2] if ref else []))
            metrics.append(verdict.unjudged(f"discharge ensemble ({c} vs native)", scene_name,
                                            f"failed members: {why}", "statistical"))
            continue
        for key in DISCHARGE_MEANS:
            if keep is not None and MARGIN_KIND[key] not in keep:
                continue
            st = stats.difference(ref["values"][key], s["values"][key], relative=True, paired=True)
            note = ""
            if key in FLOW_TOTALS and ref.get("flow_window"):
                note = "time average over t = {:g} .. {:g} s after opening".format(*ref["flow_window"])
            elif key.startswith("peak_window"):
                note = f"largest {PEAK_WINDOW:g} s average of the group total / its value at the opening"
            metrics.append(verdict.statistical(f"discharge {key} ({c} vs native)", scene_name, st, MARGIN_KIND[key],
                                               options, {"native": list(ref[key][:2]), c: list(s[key][:2])}, note))
        if keep is None or "wall_profile" in keep:
            for group in ("side", "bottom"):
                st = profile_stat(ref["flow_profile"], s["flow_profile"], group, ref["ok_members"], s["ok_members"])
                metrics.append(verdict.statistical(
                    f"discharge time-averaged {group}-wall normal profile during flow, cumulative ({c} vs native)",
                    scene_name, st, "wall_profile", options, {},
                    f"walls {', '.join(st['walls'])} (gate left out); each point / its wall's total"))
        if keep is None or "jam_fraction" in keep:
            st = stats.proportions(ref["jammed"], ref["ok_members"], s["jammed"], s["ok_members"])
            metrics.append(verdict.statistical(
                f"discharge jam fraction ({c} vs native)", scene_name, st, "jam_fraction", options,
                {"native": f"{ref['jammed']}/{ref['ok_members']} jammed", c: f"{s['jammed']}/{s['ok_members']} jammed"},
                "Newcombe's interval of the difference of the fractions"))
    return metrics, summary


# ---------------------------------------------------------------- saved series for the plots

def save_profiles(path: Path, case: Case, res: dict) -> None:
    data = {"case": case.name, "walls": case.resolved["walls"],
            "codes": {c: {"status": r.status, "reason": r.reason, "profiles": r.profiles} for c, r in res.items()}}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data))


def save_series(path: Path, per_code: dict) -> None:
    data = {c: [{"status": r.status, "removals": r.removals, "measures": m} for r, m in runs]
            for c, runs in per_code.items()}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, default=float))

#!/usr/bin/python3
"""Stability stress test: the largest stable dt of every scheme on the
paper's silo (all eight arrangements 11/12 ... 18/19) and on packings with other stiffness
ratios K_s/K_n, damping ratios and coordination numbers, beside the theoretical bounds the
engine prints (single contact, rotation on 4 and 6 sticking contacts, eq. 26, eq. 21); and the
paper's question: is eq. 19 what makes dt = 1e-4 s usable, and what does it cost in accuracy.

    /usr/bin/python3 benchmarks/stability_study.py --out out/stability [--quick] [--dem PATH]
        [--wp out/work_precision/results.json] [--jobs 2]

Criterion (per run): the scene's fill from its initial packing, run for a fixed time T (2 s;
--quick 1 s) with stop_at_rest off and --force-dt. A run is
  - "rest"    (stable): exit code 0 and kinetic energy at the end <= 1e-6 x (weight x mean
              radius) -- the silo fills rest in 0.3-0.5 s, so at least 1.5 s at rest remain for
              an instability to grow from round-off;
  - "moving"  : exit 0 but the kinetic energy at the end is above that (a self-excited
              rattle: bounded, never at rest; or a blow-up that has not reached the engine's
              detection yet);
  - "blow-up" : exit code 3 (the engine's detection) or kinetic energy above 1e-2 x (weight x
              mean radius).
A "moving" run is run again for 2T: if its kinetic energy fell tenfold it was a slow decay
(weak damping) and counts as at rest. The largest stable dt is found by scanning dt upward by a
factor 1.25 from half the smallest bound the engine prints until the run blows up, then bisecting (geometric mean) each transition to 2 %: the
largest dt at rest (below which every tested dt rested) and the largest dt without blow-up.
Outputs: DIR/results.json, DIR/report.md, DIR/stability.png, derived scenes in DIR/scenes/.
"""
from __future__ import annotations

import argparse
import concurrent.futures as cf
import csv
import json
import math
import os
import shutil
import sys
import threading
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common_study as cs  # noqa: E402
from dem.compare.io.run_dir import RunDir, RunDirError  # noqa: E402

KE_BLOWUP = 1e-2      # x (weight x mean radius): a blow-up even without exit 3
PAPER_ZETA = 1.0015   # damping ratio of the paper's disc-disc pair (eta_n/(rho g) = 15.3, m* = m/2)
PAPER_S = 0.25        # K_s / K_n of the paper (eq. 24)

PROFILES = {
    "full": {"T": 2.0, "scan": 1.25, "tol": 0.02, "silos": [12, 13, 14, 15, 16, 17, 18, 19],
             "ks": [0.1, 0.5, 1.0], "zeta": [0.1, 0.3, 0.5], "coordination": ["hexagonal", "square", "loose"]},
    "quick": {"T": 1.0, "scan": 1.5, "tol": 0.06, "silos": [12, 18, 19],
              "ks": [1.0], "zeta": [0.3], "coordination": ["hexagonal"]},
}
_lock = threading.Lock()


def log(msg: str) -> None:
    with _lock:
        print(f"[{time.strftime('%H:%M:%S')}] {msg}", flush=True)


# ------------------------------------------------------------------ cases

def base_scene() -> Path:
    return cs.SCENES / "silo_17_18.toml"


def write_discs(path: Path, discs) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["x", "y", "r"])
        for x, y, r in discs:
            w.writerow([repr(float(x)), repr(float(y)), repr(float(r))])


def square_lattice(width=40.0, r=1.0, gap=0.004, count=350):
    pitch = 2 * r + gap
    ncol = int((width - gap) // pitch)
    x0 = (width - ncol * pitch + gap) / 2 + r - gap / 2
    out, row = [], 0
    while len(out) + ncol <= count:
        y = r + gap + row * pitch
        out += [(x0 + k * pitch, y, r) for k in range(ncol)]
        row += 1
    return out


def loose_random(width=40.0, height=40.0, r=1.0, n=250, sep=0.05, seed=5):
    """Random sequential addition: n discs with gaps >= sep to each other and to the walls."""
    rng = np.random.default_rng(seed)
    pts = []
    tries = 0
    while len(pts) < n:
        tries += 1
        if tries > 2_000_000:
            raise RuntimeError("loose packing: could not place the discs")
        x = rng.uniform(r + sep, width - r - sep)
        y = rng.uniform(r + sep, height - r - sep)
        if all((x - a) ** 2 + (y - b) ** 2 >= (2 * r + sep) ** 2 for a, b in pts):
            pts.append((x, y))
    return [(x, y, r) for x, y in pts]


def make_cases(cfg, out: Path, T: float) -> list[dict]:
    """Scenes (paths) with descriptions; every scene ends at T without stopping at rest."""
    d = out / "scenes"
    d.mkdir(parents=True, exist_ok=True)
    end = {"end.time": T, "end.stop_at_rest": False}
    cases = []

    def add(name, group, what, base, changes=None, **edits):
        p = cs.scene_with(base, d / f"{name}.toml", {**end, **(changes or {})}, **edits)
        cases.append({"name": name, "group": group, "scene": p, "what": what})

    for s in cfg["silos"]:
        name = f"silo_{s - 1}_{s}"
        add(name, "paper silo", f"paper's silo, ({s - 1})/{s} lattice, paper's constants (K_s/K_n = 0.25, zeta = 1.0)",
            cs.SCENES / f"{name}.toml")
    for ratio in cfg["ks"]:
        k = ratio / PAPER_S
        add(f"ks_ratio_{ratio:g}", "stiffness ratio",
            f"17/18 with K_s/K_n = {ratio:g} (eta_s = eta_n sqrt(K_s/K_n), eq. 25; walls likewise)",
            base_scene(), pairs_scale={"ks_rho_g": k, "eta_s_rho_g": math.sqrt(k)})
    for z in cfg["zeta"]:
        f = z / PAPER_ZETA
        add(f"zeta_{z:g}", "damping ratio",
            f"17/18 with both dashpots scaled to a disc-disc normal damping ratio {z:g} (paper: 1.0)",
            base_scene(), pairs_scale={"eta_n_rho_g": f, "eta_s_rho_g": f})
    for kind in cfg["coordination"]:
        if kind == "hexagonal":
            add(kind, "coordination", "19/20 lattice with gap 0: every disc touches its 6 neighbours (hexagonal, 351 discs)",
                base_scene(), {"fill.s": 20, "fill.gap": 0.0}, add={"fill.max_initial_overlap": 1e-6})
            continue
        if kind == "square":
            discs = square_lattice()
            write_discs(d / "square.csv", discs)
            what = f"square lattice, pitch 2r + 0.004 cm, {len(discs)} discs: 4 neighbours (stacked columns)"
        else:
            discs = loose_random()
            write_discs(d / "loose.csv", discs)
            what = (f"loose random packing: {len(discs)} discs placed at random (gaps >= 0.05 cm, seed 5) "
                    "falling and settling")
        add(kind, "coordination", what, base_scene(),
            {"fill": {"type": "file", "material": "sand", "file": f"{'square' if kind == 'square' else 'loose'}.csv"}})
    return cases


# ------------------------------------------------------------------ runs

def classify(scene: Path, scheme: str, dt: float, out: Path, T: float, recheck: bool = True) -> dict:
    d = out / f"dt_{dt:.6g}"
    if d.exists():
        shutil.rmtree(d)
    r = cs.run_dem(scene, d, scheme, dt, end_time=T)
    s = r["summary"]
    rec = {"dt": dt, "rc": r["rc"], "status": r["status"], "loop_s": r["loop_s"], "message": r["message"][:300]}
    if r["rc"] == 3 or r["status"] == "unstable":
        rec["class"] = "blow-up"
        rec["t_end"] = (s or {}).get("time")
        return rec
    if r["rc"] != 0 or s is None:
        rec["class"] = "error"
        return rec
    ke = cs.kinetic_energy_run(d, s)
    scale = cs.energy_scale(d, s)
    rec.update({"kinetic_energy_end": ke, "energy_scale": scale, "ke_rel": ke / scale,
                "rest_reached": (s.get("rest") or {}).get("reached"), "rest_time": (s.get("rest") or {}).get("time")})
    rec["class"] = "rest" if ke <= cs.KE_REST * scale else ("moving" if ke <= KE_BLOWUP * scale else "blow-up")
    if rec["class"] == "moving" and recheck:
        # Slow decay (weak damping) or a self-excited rattle? Run twice as long: decaying by 10x is
        # counted as stable ("rest (slow)"), anything else stays "moving" (or becomes a blow-up).
        r2 = classify(scene, scheme, dt, out / "twice", 2 * T, recheck=False)
        rec["recheck_2T"] = {k: r2.get(k) for k in ("class", "ke_rel", "rc")}
        if r2["class"] == "blow-up":
            rec["class"] = "blow-up"
        elif r2["class"] == "rest" or (r2.get("ke_rel") is not None and r2["ke_rel"] < 0.1 * rec["ke_rel"]):
            rec["class"] = "rest"
            rec["slow"] = True
            rec["coordination"] = r2.get("coordination")
    if rec["class"] == "rest":
        rec["coordination"] = coordination(d, s)
    return rec


def coordination(run_dir: Path, summary: dict) -> float | None:
    """Mean number of disc-disc contacts carrying force per disc (2 N_dd / N)."""
    try:
        c = RunDir(run_dir).contacts()
        n_dd = int(np.count_nonzero((c["kind"] == "dd") & (c["f_n"] > 0)))
        return 2.0 * n_dd / max(1, int(summary["n_discs"]))
    except (RunDirError, KeyError, ValueError):
        return None


def bounds_of(scene: Path, scheme: str, out: Path) -> dict:
    """The engine's time-step bounds for this scene and scheme (summary.json of a 10-step run)."""
    d = out / "bounds"
    if d.exists():
        shutil.rmtree(d)
    r = cs.run_dem(scene, d, scheme, 1e-6, end_time=1e-5)
    s = r["summary"] or {}
    b = {"enforced": (s.get("stability") or {}).get("dt_bound"),
         "limited_by": (s.get("stability") or {}).get("limited_by")}
    for p in s.get("derived", []):
        key = "dd" if p["kind"] == "disc-disc" else "dw"
        b[f"{key}_single"] = min(p["dt_bound_normal"], p["dt_bound_tangential"])
        b[f"{key}_rot_z4"] = p["dt_bound_rotation_z4"]
        b[f"{key}_rot_z6"] = p["dt_bound_rotation_z6"]
        b[f"{key}_eq26"] = p["dt_bound_eq26"]
        b[f"{key}_eq21"] = p["dt_bound_eq21"]
        b[f"{key}_zeta_n"] = p["zeta_n"]
    return b


def search(case: dict, scheme: str, cfg, out: Path) -> dict:
    """Upward scan from half the enforced bound until a blow-up, then bisection of the two
    transitions (rest -> not rest, no blow-up -> blow-up)."""
    T, f, tol = cfg["T"], cfg["scan"], cfg["tol"]
    base = out / "runs" / case["name"] / scheme
    b = bounds_of(case["scene"], scheme, base)
    runs = []

    def run(dt):
        rec = classify(case["scene"], scheme, dt, base, T)
        runs.append(rec)
        return rec["class"]

    printed = [v for k, v in b.items() if k != "enforced" and isinstance(v, float) and "zeta" not in k and v > 0]
    start = 0.5 * min(printed + [b["enforced"] or 1e-4])   # half the smallest printed bound
    dt = start
    # go down until the start rests
    for _ in range(8):
        if run(dt) == "rest":
            break
        dt /= 2
    else:
        return {"case": case["name"], "scheme": scheme, "bounds": b, "runs": runs, "max_rest": None,
                "max_no_blowup": None, "note": "no tested dt rested"}
    last_rest, first_not_rest = dt, None
    last_ok, first_blow = dt, None
    while dt < 50 * start:
        dt *= f
        c = run(dt)
        if c == "error":
            break
        if c != "rest" and first_not_rest is None:
            first_not_rest = dt
        if first_not_rest is None:
            last_rest = dt
        if c == "blow-up":
            first_blow = dt
            break
        last_ok = dt

    def bisect(lo, hi, good):
        while hi / lo > 1 + tol:
            mid = math.sqrt(lo * hi)
            if good(run(mid)):
                lo = mid
            else:
                hi = mid
        return lo, hi

    if first_not_rest is not None:
        last_rest, first_not_rest = bisect(last_rest, first_not_rest, lambda c: c == "rest")
    if first_blow is not None:
        lo = max(last_ok, last_rest)
        last_ok, first_blow = bisect(lo, first_blow, lambda c: c in ("rest", "moving"))
    # monotonicity check: every tested dt below the reported limit rested
    non_mono = sorted(r["dt"] for r in runs if r["dt"] < last_rest and r["class"] != "rest")
    rest_rec = min((r for r in runs if r["class"] == "rest"), key=lambda r: abs(r["dt"] - last_rest))
    res = {"case": case["name"], "scheme": scheme, "bounds": b, "runs": sorted(runs, key=lambda r: r["dt"]),
           "max_rest": last_rest, "first_not_rest": first_not_rest, "class_above": None,
           "max_no_blowup": last_ok if first_blow else None, "first_blowup": first_blow,
           "non_monotonic_below": non_mono, "coordination": rest_rec.get("coordination"),
           "rest_time": rest_rec.get("rest_time")}
    above = [r for r in runs if first_not_rest and abs(r["dt"] - first_not_rest) < 1e-15]
    res["class_above"] = above[0]["class"] if above else None
    log(f"{case['name']:>16} {scheme:>15}: max dt at rest {last_rest:.3g} s (enforced bound {b['enforced']:.3g}), "
        f"blow-up from {first_blow if first_blow else float('nan'):.3g} s, {len(runs)} runs")
    return res


def paper_question(cases, cfg, out: Path, jobs: int) -> list:
    """Every paper silo with every scheme at exactly dt = 1e-4 s."""
    tasks = [(c, s) for c in cases if c["group"] == "paper silo" for s in cs.SCHEMES]

    def one(cs_):
        c, s = cs_
        rec = classify(c["scene"], s, 1e-4, out / "dt_1e-4" / c["name"] / s, cfg["T"])
        rec.update({"case": c["name"], "scheme": s})
        return rec

    with cf.ThreadPoolExecutor(max_workers=jobs) as ex:
        return list(ex.map(one, tasks))


# ------------------------------------------------------------------ report

def accuracy_at_1e4(wp_path: Path) -> dict | None:
    """From the work-precision results: errors at dt = 1e-4 s and at smaller dt."""
    try:
        wp = json.loads(Path(wp_path).read_text())
    except (OSError, ValueError):
        return None
    out = {"source": str(wp_path), "profile": wp.get("profile")}

    def pick(points, **kw):
        return [p for p in points if all(p.get(k) == v for k, v in kw.items())]

    col = wp.get("collision", {}).get("points", [])
    out["collision"] = {s: {f"{p['dt']:g}": p["error"] for p in pick(col, case="disc_disc_head_on", law="paper",
                                                                      code="native", scheme=s) if p["ok"]}
                        for s in cs.SCHEMES}
    sp = wp.get("static_paper", {})
    out["static"] = {s: {f"{p['dt']:g}": (p["error"] if p["ok"] else "unstable") for p in pick(sp.get("points", []), scheme=s)}
                     for s in cs.SCHEMES}
    out["static_floor"] = (sp.get("floor") or {}).get("l2_rel")
    fl = wp.get("flow", {})
    out["flow"] = {s: {f"{p['dt']:g}": ((p["diff"], p["diff_se"]) if p["ok"] else "unstable")
                       for p in pick(fl.get("points", []), scheme=s)} for s in cs.SCHEMES}
    out["flow_reference"] = {k: fl.get("reference", {}).get(k) for k in ("mean", "stderr", "members")}
    return out


def plot(results: list, cases: list, out: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = [c["name"] for c in cases]
    fig, axes = plt.subplots(1, 3, figsize=(20, 5.5), sharey=True)
    for ax, scheme in zip(axes, cs.SCHEMES):
        rs = {r["case"]: r for r in results if r["scheme"] == scheme}
        x = np.arange(len(names))
        def series(fn):
            return [fn(rs[n]) if n in rs else np.nan for n in names]
        ax.plot(x, series(lambda r: r["max_rest"] or np.nan), "o", color="tab:blue", ms=8, label="measured: largest dt at rest")
        ax.plot(x, series(lambda r: r["max_no_blowup"] or np.nan), "^", color="tab:red", mfc="none", ms=8,
                label="measured: largest dt without blow-up")
        for key, style, lab in (("enforced", "k_", "engine's enforced bound"), ("dd_rot_z6", "g_", "disc-disc rotation z=6"),
                                ("dw_rot_z4", "m_", "disc-wall rotation z=4"), ("dd_eq26", "c_", "eq. 26 (eta_n/K_n)"),
                                ("dd_eq21", "y_", "eq. 21")):
            ax.plot(x, series(lambda r: r["bounds"].get(key) or np.nan), style, ms=22, mew=2, label=lab)
        ax.axhline(1e-4, color="gray", ls=":", lw=1)
        ax.text(len(names) - 0.5, 1.05e-4, "paper's dt = 1e-4 s", fontsize=7, ha="right", color="gray")
        ax.set_xticks(x)
        ax.set_xticklabels(names, rotation=60, ha="right", fontsize=8)
        ax.set_yscale("log")
        ax.set_title(scheme)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("dt [s]")
    axes[0].legend(fontsize=7, loc="lower left")
    fig.suptitle("Measured largest stable dt against the theoretical bounds (each case's fill run for a fixed time; "
                 "see report.md)", fontsize=10)
    cs.savefig(fig, out / "stability.png")
    plt.close(fig)


def write_report(res: dict, out: Path) -> None:
    cfg = res["config"]
    L = ["# Stability stress test", "",
         f"Engine `{res['engine']}` (`{res['dem']}`), profile `{res['profile']}`; {res['n_runs']} runs in "
         f"{res['elapsed_s']:.0f} s ({res['jobs']} at a time) on a shared 2-core machine. Command: `{res['command']}`.", "",
         "![stability](stability.png)", "",
         "## Criterion", "",
         f"Each run fills the scene from its initial packing for T = {cfg['T']} s of simulated time (stop at rest "
         "off, `--force-dt`). **rest** (stable): exit code 0 and kinetic energy at the end <= "
         f"{cs.KE_REST:g} x (total weight x mean radius); the paper's silos rest within 0.3-0.5 s, so an "
         "instability has the remaining time to grow from round-off. **moving**: exit 0, kinetic energy "
         f"above that but below {KE_BLOWUP:g} x the scale (a self-excited rattle that never rests, or a slow "
         "blow-up not yet caught). **blow-up**: exit code 3 (the engine's detection: overlap beyond "
         f"end.max_overlap x r_min, non-finite values, or energy growth where the build has it) or kinetic "
         f"energy above {KE_BLOWUP:g} x the scale. A moving run is repeated for 2T: if its kinetic energy fell "
         "tenfold it was a slow decay (weak damping) and counts as at rest. Search: dt scanned upward by "
         f"x{cfg['scan']} from half the smallest bound the engine prints until a blow-up, then both transitions bisected (geometric) to {cfg['tol']:.0%}. An "
         "instability slower than the run length cannot be seen: near the threshold the growth rate tends to "
         "zero, so the measured limits are upper estimates within the bisection tolerance and the run length. "
         "Theoretical bounds (from the engine's summary.json, `derived` and `stability`): the engine's enforced "
         "bound min(single contact, rotation held by 4 sticking disc-disc contacts) of the scheme's step; the "
         "rotation bounds for 6 disc-disc contacts and for 4 disc-wall contacts (wall pairs have twice the "
         "stiffness); eq. 26 (dt < eta_n/K_n) and eq. 21 (2 sqrt(m/K)), scheme-independent.", ""]
    L += ["## Cases", "", cs.md_table(["case", "group", "scene"], [[c["name"], c["group"], c["what"]] for c in res["cases"]]), ""]
    L += ["## Largest stable dt against the bounds", "",
          "Measured: largest dt at rest / largest dt without blow-up (`-`: no blow-up up to the scan's end). "
          "Ratio: measured at rest / engine's enforced bound. z: disc-disc contacts carrying force per disc at "
          "rest (at the largest dt at rest).", ""]
    rows = []
    for r in res["results"]:
        b = r["bounds"]
        rows.append([r["case"], r["scheme"], cs.g(r["max_rest"]), cs.g(r["max_no_blowup"]),
                     r.get("class_above") or "-", cs.g(b.get("enforced")),
                     cs.g((r["max_rest"] or math.nan) / (b.get("enforced") or math.nan), 2),
                     cs.g(b.get("dd_single")), cs.g(b.get("dd_rot_z4")), cs.g(b.get("dd_rot_z6")), cs.g(b.get("dw_rot_z4")),
                     cs.g(b.get("dd_eq26")), cs.g(b.get("dd_eq21")), cs.g(r.get("coordination"), 2),
                     ", ".join(cs.g(x) for x in r.get("non_monotonic_below") or []) or "-"])
    L += [cs.md_table(["case", "scheme", "max dt at rest [s]", "max dt no blow-up [s]", "just above", "enforced bound",
                       "ratio", "single contact (dd)", "rot z=4 (dd)", "rot z=6 (dd)", "rot z=4 (disc-wall)", "eq. 26",
                       "eq. 21", "z", "failures below"], rows), ""]
    L += ["## The paper's question: is eq. 19 what makes dt = 1e-4 s usable?", ""]
    pq = res["paper_dt_1e4"]
    rows = []
    for c in sorted({p["case"] for p in pq}):
        row = [c]
        for s in cs.SCHEMES:
            p = next(p for p in pq if p["case"] == c and p["scheme"] == s)
            extra = f" (t = {p['t_end']:.2f} s)" if p["class"] == "blow-up" and p.get("t_end") else (
                f" (KE/scale {p['ke_rel']:.1e})" if p["class"] == "moving" else "")
            row.append(p["class"] + extra)
        rows.append(row)
    L += [f"Every paper silo filled for {cfg['T']} s at exactly dt = 1e-4 s:", "",
          cs.md_table(["silo"] + list(cs.SCHEMES), rows), ""]
    L += answer(res) + [""]
    cs.write_text(out / "report.md", "\n".join(L) + "\n")


def answer(res: dict) -> list:
    pq = res["paper_dt_1e4"]
    n = len({p["case"] for p in pq})
    rest = {s: sum(1 for p in pq if p["scheme"] == s and p["class"] == "rest") for s in cs.SCHEMES}
    R = res["results"]
    silo = [r for r in R if r["case"].startswith("silo_")]

    def col(rows, s, fn):
        return [fn(r) for r in rows if r["scheme"] == s and fn(r) is not None]

    mr = {s: col(silo, s, lambda r: r["max_rest"]) for s in cs.SCHEMES}
    wall = {s: col(silo, s, lambda r: r["bounds"].get("dw_rot_z4")) for s in cs.SCHEMES}
    enf = {s: col(silo, s, lambda r: r["bounds"].get("enforced")) for s in cs.SCHEMES}
    eq26 = col(silo, "paper_eq18", lambda r: r["bounds"].get("dd_eq26"))
    eq21 = col(silo, "paper_eq18", lambda r: r["bounds"].get("dd_eq21"))
    rng = lambda v: (f"{cs.g(min(v))}-{cs.g(max(v))} s" if min(v) != max(v) else f"{cs.g(v[0])} s") if v else "-"  # noqa: E731
    L = ["### Answer", ""]
    L.append(f"- **Yes.** At dt = 1e-4 s, eq. 19 comes to rest in {rest['paper_eq19']} of {n} silos, eq. 18 in "
             f"{rest['paper_eq18']} and velocity Verlet in {rest['velocity_verlet']}. The largest dt at rest on the "
             f"paper's silos is {rng(mr['paper_eq19'])} with eq. 19 against {rng(mr['paper_eq18'])} with eq. 18 and "
             f"{rng(mr['velocity_verlet'])} with Verlet (eq. 18 and Verlet have conjugate step maps: the same "
             "positions from a force-free start, one stability limit, found equal here to the bisection's "
             "tolerance and round-off)"
             + (f": eq. 19 allows {cs.g(np.median(mr['paper_eq19']) / np.median(mr['paper_eq18']), 2)}x the step "
                "(medians)." if mr["paper_eq19"] and mr["paper_eq18"] else "."))
    ratio_w = [r["max_rest"] / r["bounds"]["dw_rot_z4"] for r in silo if r["max_rest"] and r["bounds"].get("dw_rot_z4")]
    ratio_wa = [r["max_rest"] / r["bounds"]["dw_rot_z4"] for r in R if r["max_rest"] and r["bounds"].get("dw_rot_z4")]
    ratio_e = [r["max_rest"] / r["bounds"]["enforced"] for r in silo if r["max_rest"] and r["bounds"].get("enforced")]
    gen = [r["bounds"]["dd_eq26"] / r["max_rest"] for r in silo if r["max_rest"] and r["bounds"].get("dd_eq26")]
    L.append(f"- What sets the limit: on the paper's silos the measured limit sits at the **disc-wall** rotation bound "
             f"(4 sticking contacts: {rng(wall['paper_eq18'])} for eq. 18/Verlet, {rng(wall['paper_eq19'])} for eq. 19; "
             f"measured / that bound: {cs.g(min(ratio_w), 2)}-{cs.g(max(ratio_w), 2)} on the silos, "
             f"{cs.g(min(ratio_wa), 2)}-{cs.g(max(ratio_wa), 2)} over all cases), not at the "
             f"disc-disc bound the engine enforces ({rng(enf['paper_eq18'])} and {rng(enf['paper_eq19'])}; measured / "
             f"enforced: {cs.g(min(ratio_e), 2)}-{cs.g(max(ratio_e), 2)}): a dt between the two is accepted without "
             "--force-dt but the fill never comes to rest (a bounded rattle of discs against the walls, whose "
             "contacts are twice as stiff) or blows up. The engine should enforce the wall pairs' rotation bound too. "
             f"Eq. 26 (eta_n/K_n = {rng(eq26)}) and eq. 21 ({rng(eq21)}) are {cs.g(min(gen), 2)}-{cs.g(max(gen), 2)}x "
             "the measured limits on the silos: with the paper's heavy damping they ignore rotation and the "
             "stiffer walls.")
    z19 = [(r["case"], r["max_rest"], r["bounds"].get("dd_eq26")) for r in R
           if r["case"].startswith("zeta_") and r["scheme"] == "paper_eq19" and r["max_rest"]]
    if z19:
        L.append("- Eq. 26 is eq. 19's own single-contact bound when the damping is light: eq. 19's measured limit / "
                 "eq. 26 = " + ", ".join(f"{c.replace('zeta_', 'zeta ')}: {cs.g(m / e, 2)}" for c, m, e in z19)
                 + " (the engine's single-contact bound of eq. 19 equals eta_n/K_n there). The paper's eq. 26 is "
                 "thus the right bound for its modified scheme at damping ratios up to about 0.3, and too generous at its own "
                 "critical damping, where the rotation of discs against the walls limits first.")
    # dependence on the constants
    def lim(case, s):
        r = next((r for r in R if r["case"] == case and r["scheme"] == s), None)
        return r["max_rest"] if r else None
    bits = []
    for r18 in [r for r in R if r["scheme"] == "paper_eq18" and not r["case"].startswith("silo_")]:
        c = r18["case"]
        a, b = lim(c, "paper_eq18"), lim(c, "paper_eq19")
        if a and b:
            bits.append(f"{c}: eq. 18 {cs.g(a)} s, eq. 19 {cs.g(b)} s")
    coord = []
    for c in ("hexagonal", "square", "loose"):
        for s in ("paper_eq18", "paper_eq19"):
            a, b0 = lim(c, s), lim("silo_17_18", s)
            r = next((r for r in R if r["case"] == c and r["scheme"] == s), None)
            if a and b0 and r:
                coord.append(f"{c} {s} {a / b0 - 1:+.0%} (z = {cs.g(r.get('coordination'), 2)})")
    zbase = next((r.get("coordination") for r in R if r["case"] == "silo_17_18" and r["scheme"] == "paper_eq18"), None)
    if bits:
        L.append("- Other packings and constants (largest dt at rest): " + "; ".join(bits) + ". Eq. 19's advantage "
                 "comes from the paper's heavy damping: with weaker dashpots its own bound shrinks (to eta_n/K_n, "
                 "eq. 26) while eq. 18's grows, so at damping ratios 0.1 and 0.3 eq. 18 allows the larger step; "
                 "the shear spring sets the scale (both limits scale about as 1/sqrt(K_s) from K_s/K_n = 0.25 to 1; at 0.1 "
                 "the normal spring takes over); the coordination number "
                 "moves the limits against 17/18 (z = " + cs.g(zbase, 2) + " force-carrying disc-disc contacts per "
                 "disc): " + ", ".join(coord) + " -- fewer sticking neighbours (the square stack's columns) allow "
                 "more, the hexagonal packing's denser contacts less.")
    acc = res.get("accuracy")
    if not acc:
        L.append("- Accuracy cost: no work-precision results found (run benchmarks/work_precision.py first and pass "
                 "--wp).")
        return L
    c, st, fl = acc["collision"], acc["static"], acc["flow"]

    def v(d, s, k):
        return d.get(s, {}).get(k)

    bits = []
    e19, e18s = v(c, "paper_eq19", "0.0001"), v(c, "paper_eq18", "5e-05")
    if e19 is not None:
        bits.append(f"collision (damping ratio 0.3, t_c = 0.69 ms): restitution off by {e19:.0%} with eq. 19 at "
                    f"1e-4 s, {cs.g(e18s, 2)} with eq. 18 at 5e-5 s and {cs.g(v(c, 'paper_eq18', '1e-05'), 2)} at "
                    f"1e-5 s (eq. 19 at 1e-5 s: {cs.g(v(c, 'paper_eq19', '1e-05'), 2)})")
    s19, s18 = v(st, "paper_eq19", "0.0001"), v(st, "paper_eq18", "5e-05")
    if isinstance(s19, float):
        bits.append(f"static side-wall profile (relative L2 against dt -> 0): {cs.g(s19, 2)} with eq. 19 at 1e-4 s, "
                    f"{cs.g(v(st, 'paper_eq19', '5e-05'), 2)} at 5e-5 s, against {cs.g(s18, 2)} with eq. 18 at 5e-5 s "
                    f"(reproducibility floor {cs.g(acc.get('static_floor'), 2)})")
    f19, f18 = v(fl, "paper_eq19", "0.0001"), v(fl, "paper_eq18", "5e-05")
    if isinstance(f19, (list, tuple)):
        ref = acc["flow_reference"]
        bits.append(f"flow rate of 17/18: eq. 19 at 1e-4 s differs from the small-dt reference ({cs.g(ref['mean'], 3)} "
                    f"+- {cs.g(ref['stderr'], 2)} discs/s) by {f19[0]:+.1f} +- {f19[1]:.1f} discs/s"
                    + (f", eq. 18 at 5e-5 s by {f18[0]:+.1f} +- {f18[1]:.1f}" if isinstance(f18, (list, tuple)) else ""))
    L.append("- **What it costs** (work-precision results, `" + acc["source"] + "`, profile " + str(acc["profile"])
             + "): " + "; ".join(bits) + ".")
    if isinstance(s19, float) and isinstance(s18, float) and mr["paper_eq19"] and mr["paper_eq18"]:
        s19h = v(st, "paper_eq19", "5e-05")
        flow = ""
        if isinstance(f19, (list, tuple)) and acc["flow_reference"].get("mean"):
            sig = abs(f19[0]) > 2 * f19[1]
            f19h = v(fl, "paper_eq19", "5e-05")
            more = (f"; at 5e-5 s {f19h[0] / acc['flow_reference']['mean']:+.0%}, {abs(f19h[0]) / f19h[1]:.1f} s.e."
                    if isinstance(f19h, (list, tuple)) else "")
            flow = (f"its flow rate is {f19[0] / acc['flow_reference']['mean']:+.0%} off "
                    + (f"({abs(f19[0]) / f19[1]:.1f} standard errors{more}: a bias, the weakened dashpots "
                       "dissipate less)" if sig else f"(within 2 standard errors{more})"))
        L.append(f"- In short: eq. 19 is what makes the paper's 1e-4 s usable, and it costs accuracy: at 1e-4 s its "
                 f"static profile error is {cs.g(s19 / s18, 2)}x that of eq. 18 at 5e-5 s (twice the steps), and at "
                 f"the same 5e-5 s eq. 19 is still {cs.g(s19h / s18, 2) if isinstance(s19h, float) else '-'}x worse "
                 f"than eq. 18; {flow + '; ' if flow else ''}its collisions are far too elastic. For static wall "
                 f"forces to about {s19:.0%}, eq. 19 at 1e-4 s is adequate and the cheapest stable run; for anything "
                 "finer, or an unbiased flow rate, use eq. 18/Verlet just below the disc-wall rotation bound "
                 "(5e-5 s on the paper's silo).")
    return L


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/stability")
    ap.add_argument("--dem", default=None, help="engine binary (default $DEM_BINARY, else build/dem)")
    ap.add_argument("--quick", action="store_true", help="3 silos, 3 variants, T = 1 s, coarse bisection (1-2 min)")
    ap.add_argument("--jobs", type=int, default=2, help="searches run at a time")
    ap.add_argument("--wp", default="out/work_precision/results.json",
                    help="work-precision results.json for the accuracy at dt = 1e-4 s")
    ap.add_argument("--report-only", action="store_true",
                    help="plot and report again from DIR/results.json (re-reading --wp)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    if args.report_only:
        res = json.loads((out / "results.json").read_text())
        res["accuracy"] = accuracy_at_1e4(Path(args.wp))
        cs.write_json(out / "results.json", res)
        plot(res["results"], res["cases"], out)
        write_report(res, out)
        return 0
    dem = cs.setup_binary(args.dem)
    profile = "quick" if args.quick else "full"
    cfg = PROFILES[profile]
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    cases = make_cases(cfg, out, cfg["T"])
    log(f"{len(cases)} cases x {len(cs.SCHEMES)} schemes, T = {cfg['T']} s, {args.jobs} at a time")
    tasks = [(c, s) for c in cases for s in cs.SCHEMES]
    with cf.ThreadPoolExecutor(max_workers=args.jobs) as ex:
        results = list(ex.map(lambda t: search(t[0], t[1], cfg, out), tasks))
    log("dt = 1e-4 s on every paper silo")
    pq = paper_question(cases, cfg, out / "runs", args.jobs)
    res = {"profile": profile, "config": cfg, "engine": cs.engine_version(), "dem": str(dem), "jobs": args.jobs,
           "command": " ".join(["/usr/bin/python3", "benchmarks/stability_study.py"] + (argv if argv is not None else sys.argv[1:])),
           "criterion": {"ke_rest": cs.KE_REST, "ke_blowup": KE_BLOWUP, "T": cfg["T"]},
           "cases": [{k: (str(v) if isinstance(v, Path) else v) for k, v in c.items()} for c in cases],
           "results": results, "paper_dt_1e4": pq, "accuracy": accuracy_at_1e4(Path(args.wp)),
           "n_runs": sum(len(r["runs"]) + 1 for r in results) + len(pq), "elapsed_s": time.monotonic() - t0}
    cs.write_json(out / "results.json", res)
    plot(results, cases, out)
    write_report(res, out)
    log(f"done in {res['elapsed_s']:.0f} s: {out / 'report.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Writes the agreement report: report.md, agreement.json and PNG plots."""
from __future__ import annotations

import json
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from dem.compare.verdict import calibration  # noqa: E402
from dem.compare.io import atomic_file  # noqa: E402
from dem.compare.io.atomic_file import write_text as write_text_atomic  # noqa: E402
from dem.compare.cases.shear import label
from dem.compare.cases.stats import wilson

COLORS = {"native": "tab:blue", "liggghts": "tab:orange", "yade": "tab:green", "lammps": "tab:red"}
MARKERS = {"native": "o", "liggghts": "s", "yade": "^", "lammps": "D"}


def _savefig(fig, path: Path) -> None:
    try:
        with atomic_file.replacing(path) as tmp:
            fig.savefig(tmp, dpi=110, format="png")
    finally:
        plt.close(fig)


def _fmt(v) -> str:
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return "n/a" if not math.isfinite(v) else f"{v:.4g}"
    if isinstance(v, (list, tuple)) and len(v) and all(isinstance(x, (int, float)) for x in v):
        return " ± ".join(_fmt(float(x)) for x in v[:2])
    if isinstance(v, dict):
        parts = []
        for k, x in v.items():
            if isinstance(x, dict):  # a code's measures: the scalar ones, compactly
                x = "(" + ", ".join(f"{kk} {_fmt(xx)}" for kk, xx in x.items() if isinstance(xx, (int, float))) + ")"
            else:
                x = _fmt(x)
            parts.append(f"{k} {x}")
        return "; ".join(parts)
    return str(v)


def plot_profiles(prof_json: Path, png: Path) -> None:
    data = json.loads(prof_json.read_text())
    walls = [w for w in data["walls"] if w.get("active", True)]
    fig, axes = plt.subplots(1, len(walls), figsize=(3.2 * len(walls), 4.2), squeeze=False)
    for ax, w in zip(axes[0], walls):
        for code, d in data["codes"].items():
            p = d["profiles"].get(w["name"])
            if d["status"] != "ok" or not p:
                continue
            mid = 0.5 * (np.array(p["s_lo"]) + np.array(p["s_hi"]))
            ax.plot(np.array(p["normal"]) / 1e3, mid, MARKERS[code] + "-", ms=3, lw=1, color=COLORS[code],
                    label=code, alpha=0.8)
        ax.set_title(w["name"], fontsize=9)
        ax.set_xlabel("normal force per bin [10^3 dyn/cm]")
        ax.invert_yaxis()
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("distance along the wall from its 'from' end [cm]")
    axes[0][0].legend(fontsize=8)
    failed = [f"{c}: {d['reason']}" for c, d in data["codes"].items() if d["status"] != "ok"]
    fig.suptitle(f"{data['case']}: wall profiles, all codes" + ("\nFAILED " + "; ".join(failed) if failed else ""),
                 fontsize=10)
    fig.tight_layout()
    _savefig(fig, png)


def plot_calibration(rows: list, png: Path) -> None:
    """Each code's largest deviation from the reference per scene, in units of its tolerance."""
    fig, ax = plt.subplots(figsize=(12, 4))
    names = [r["scene"] for r in rows]
    x = np.arange(len(names))
    codes = [c for c in COLORS if any(c in r["codes"] for r in rows)]
    width = 0.8 / max(len(codes), 1)
    for j, code in enumerate(codes):
        vals = []
        for r in rows:
            m = r["codes"].get(code, {})
            dev = [abs(m[q] - r["reference"][q]) / t for q, t in r["tolerance"].items() if q in m and t > 0]
            vals.append(max(dev) if dev else np.nan)
        ax.bar(x + (j - (len(codes) - 1) / 2) * width, vals, width, color=COLORS[code], label=code)
    ax.axhline(1.0, color="k", lw=1, ls="--", label="tolerance")
    ax.set_xticks(x)
    ax.set_xticklabels(names, rotation=60, ha="right", fontsize=7)
    ax.set_ylabel("max |code - reference| / tolerance")
    ax.set_yscale("symlog", linthresh=1e-3)
    ax.set_title("Calibration collisions: each code's largest deviation from the analytic or independent reference",
                 fontsize=10)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=7)
    fig.tight_layout()
    _savefig(fig, png)


def plot_discharge(series_json: Path, png: Path, name: str) -> None:
    data = json.loads(series_json.read_text())
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for code, runs in data.items():
        for k, r in enumerate(runs):
            t = np.sort(np.array(r["removals"], float))
            if r["status"] != "ok":
                continue
            ax.step(np.concatenate([[0], t]), np.arange(len(t) + 1), where="post", color=COLORS[code], alpha=0.7,
                    lw=1, label=code if k == 0 else None)
    ax.set_xlabel("time since opening [s]")
    ax.set_ylabel("discs out")
    ax.set_title(f"{name}: discharge, every member of every code", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    _savefig(fig, png)


def plot_flow_profiles(summary: dict, png: Path, name: str) -> None:
    """Time-averaged wall profiles during flow, ensemble mean of each code with 1 s.e. bars: side
    walls against depth, bottom walls (gate left out) along the floor."""
    ref = next((v["flow_profile"] for v in summary.values() if v.get("flow_profile")), {})
    walls = list(ref)
    side = [w for w in walls if ref[w]["group"].startswith("side")]
    bottom = [w for w in walls if not ref[w]["group"].startswith("side")]
    ncol = max(len(side), len(bottom), 1)
    fig, axes = plt.subplots(2, ncol, figsize=(4.2 * ncol, 8.4), squeeze=False)
    for row, group in enumerate((side, bottom)):
        for col in range(ncol):
            ax = axes[row][col]
            if col >= len(group):
                ax.axis("off")
                continue
            w = group[col]
            for k, (code, v) in enumerate(summary.items()):
                p = (v.get("flow_profile") or {}).get(w)
                if not p:
                    continue
                mid = 0.5 * (np.array(p["s_lo"], float) + np.array(p["s_hi"], float)) + (k - 1) * 0.15
                f, e = np.array(p["normal"]) / 1e3, np.nan_to_num(np.array(p["normal_se"], float)) / 1e3
                lab = f"{code} ({p['members']} members)"
                if row == 0:
                    ax.errorbar(f, mid, xerr=e, fmt=MARKERS[code] + "-", ms=3, lw=1, capsize=2, color=COLORS[code],
                                label=lab, alpha=0.85)
                else:
                    ax.errorbar(mid, f, yerr=e, fmt=MARKERS[code] + "-", ms=3, lw=1, capsize=2, color=COLORS[code],
                                label=lab, alpha=0.85)
            ax.set_title(w, fontsize=9)
            ax.grid(alpha=0.3)
            if row == 0:
                ax.invert_yaxis()
                ax.set_xlabel("normal force per bin [10^3 dyn/cm]")
                ax.set_ylabel("distance from the top of the wall [cm]")
            else:
                ax.set_xlabel("distance along the wall from its 'from' end [cm]")
                ax.set_ylabel("normal force per bin [10^3 dyn/cm]")
            ax.legend(fontsize=7)
    win = next((v.get("flow_window") for v in summary.values() if v.get("flow_window")), None)
    when = f"t = {win[0]:g} .. {win[1]:g} s after opening" if win else "during flow"
    fig.suptitle(f"{name}: wall forces averaged over {when}; ensemble mean ± 1 s.e.", fontsize=10)
    fig.tight_layout()
    _savefig(fig, png)


VERDICT_COLORS = {"agree": "tab:green", "disagree": "tab:red", "inconclusive": "tab:gray"}


def plot_forest(metrics: list, png: Path, scene: str) -> bool:
    """Every statistical metric of a scene: its agree interval (thick) and disagree interval (thin)
    of the difference against its margin band, coloured by verdict. False when there is none."""
    rows = [m for m in metrics if m["scene"] == scene and m.get("kind") == "statistical" and "margin" in m]
    if not rows:
        return False
    fig, ax = plt.subplots(figsize=(8.5, 0.9 + 0.36 * len(rows)))
    sc = 100.0     # relative differences in % of native's mean; a fraction's in percentage points
    for k, m in enumerate(rows):
        y, col = len(rows) - 1 - k, VERDICT_COLORS[m["verdict"]]
        ax.fill_betweenx([y - 0.4, y + 0.4], -m["margin"] * sc, m["margin"] * sc, color="0.9", lw=0)
        ci, cid = m.get("ci") or [np.nan] * 2, m.get("ci_disagree") or [np.nan] * 2
        if all(np.isfinite(ci)):
            ax.plot([cid[0] * sc, cid[1] * sc], [y, y], color=col, lw=1)
            ax.plot([ci[0] * sc, ci[1] * sc], [y, y], color=col, lw=4, solid_capstyle="butt")
            est = m["stat"].get("estimate", np.nan) * sc
            ax.plot([est], [y], "|", color="k", ms=10)
        else:
            ax.text(0, y, "not judged: " + (m.get("note") or "no interval")[:70], ha="center", va="center", fontsize=7)
    ax.axvline(0, color="k", lw=0.6)
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels([_short(m) for m in reversed(rows)], fontsize=7)
    ax.set_xlabel("difference from native [% of its mean; jam fraction: % points]")
    ax.set_title(f"{scene}: each metric's 90 % interval (thick) and disagree interval (thin)\n"
                 "against its margin (grey); green agree, red disagree, grey inconclusive", fontsize=9)
    ax.grid(alpha=0.3, axis="x")
    fig.tight_layout()
    _savefig(fig, png)
    return True


def _short(m: dict) -> str:
    name = m["metric"].replace("discharge ", "").replace(" during flow", "").replace(", cumulative", "")
    return (name[:58] + "…" if len(name) > 59 else name) + f"  [{m['verdict']}]"


def _interval(m: dict) -> str:
    """The metric's interval and margin as the report prints them."""
    if m.get("kind") != "statistical" or "margin" not in m:
        return ""
    ci = m.get("ci") or [float("nan")] * 2
    if not all(math.isfinite(x) for x in ci):
        return "n/a"
    if m.get("relative", True):
        return f"[{ci[0]:+.1%}, {ci[1]:+.1%}] in ±{m['margin']:.0%}"
    return f"[{ci[0]:+.3f}, {ci[1]:+.3f}] in ±{m['margin']:g}"


def _ms(v) -> str:
    """(mean, se, n) as 'mean ± se (n)'."""
    if isinstance(v, (list, tuple)) and len(v) == 3:
        return f"{_fmt(float(v[0]))} ± {_fmt(float(v[1]))} ({int(v[2])})"
    return _fmt(v)


METHOD = [
    "- Each scene (the engine's TOML, resolved by `dem resolve`) is translated for each code; every code "
    "uses the contact law all three express (e_n = K_n x overlap, the total normal force clamped at 0, the "
    "Coulomb cap on the total normal force, shear dashpot off while sliding: `compare/cases/common.py`), velocity "
    "Verlet, the same dt. Whatever a code cannot express is refused before any run.",
    "- Translation check: each reference code's effective constants (k_n, k_t, both dashpots, mu per material "
    "pair, mass and inertia, gravity, dt) are read back from the code itself (compare/verdict/probe.py) and compared "
    "with `dem resolve` to 1e-9 relative.",
    "- Collisions: each code's rebound against the analytic result (or an independent integration of the "
    "contact equations) within the scheme's first-order error in dt/t_c, and the codes against each other "
    "within their measured agreement.",
    "- Static from a frozen packing: every code rests from the native engine's rested packing (velocities "
    "zeroed, no history); wall totals and cumulative profiles within tolerances set at no more than 10x the "
    "codes' measured spread. Static from the scene's start: jittered members per code, wall totals against "
    "their margin.",
    "- Ensembles (discharge, static members, Janssen, shear box): members differ by a seeded jitter of every "
    "position; member k of every code starts alike. Each statistical metric agrees when the 90 % interval "
    "of its difference from native (relative to native's mean; paired by member) lies inside its margin, "
    "disagrees when the interval lies entirely outside (the level split over the report's statistical "
    "metrics), and is inconclusive otherwise, with the members that would decide it. Profiles point by "
    "point; the jam fraction by Newcombe's interval; peaks as the largest 0.05 s average of a wall group's "
    "total; Janssen's K, lambda and mu_w,eff from the ensemble fits.",
    "- A run that crashed, timed out, blew up, lost discs or wrote no output leaves every metric that needs it "
    "inconclusive, never disagree; a dt above the engine's bound is refused before any run.",
]


def _verdict(v: str) -> str:
    return v if v == "agree" else f"**{v}**"


def headline(report: dict) -> list:
    """The report's first lines: the verdict, the count of each, the margins used."""
    ms = report["metrics"]
    n = {v: sum(m["verdict"] == v for m in ms) for v in ("agree", "disagree", "inconclusive")}
    margins = sorted({(m["margin_kind"], m["margin"]) for m in ms if m.get("kind") == "statistical" and "margin_kind" in m})
    L = [f"**Overall: {report['verdict'].upper()}** — {n['agree']} agree, {n['disagree']} disagree, "
         f"{n['inconclusive']} inconclusive of {len(ms)} metrics; {report.get('elapsed_s', float('nan')):.0f} s."]
    if margins:
        L.append("Margins: " + ", ".join(f"{k} ±{d:.0%}" if k != "jam_fraction" else f"{k} ±{d:g}" for k, d in margins)
                 + " (a statistical metric agrees when its 90 % interval lies inside its margin).")
    lk = report.get("looks")
    if lk:
        L.append(f"Sequential: {lk['done']} of at most {lk['planned']} looks (each at alpha / {lk['planned']}); "
                 f"members at the end: " + ", ".join(f"{k} {v}" for k, v in lk["history"][-1]["members"].items()) + ".")
    return L


def _plots(report: dict, out: Path) -> list:
    """Draws the report's plots into out; [(title, PNG name)] of those written."""
    pngs = []
    if report.get("calibration"):
        plot_calibration(report["calibration"], out / "calibration.png")
        if (out / "calibration.png").exists():
            pngs.append(("Calibration: deviation from the reference / tolerance", "calibration.png"))
    for st in report.get("static", []):
        pj = out / "static" / st["case"] / "profiles.json"
        if pj.exists():
            plot_profiles(pj, out / f"profiles_{st['case']}.png")
            pngs.append((f"Wall profiles, {st['case']}", f"profiles_{st['case']}.png"))
    for jd in report.get("janssen", []):
        if jd.get("png") and (out / jd["png"]).exists():
            pngs.append((f"Janssen column, {jd['case']}", jd["png"]))
    for sd in report.get("shear", []):
        if sd.get("png") and (out / sd["png"]).exists():
            pngs.append((f"Shear box, {sd['case']}", sd["png"]))
    for name in report.get("discharge", {}):
        sj = out / "discharge" / name / "series.json"
        if sj.exists():
            plot_discharge(sj, out / f"discharge_{name}.png", name)
            pngs.append((f"Discharge, {name}", f"discharge_{name}.png"))
        if any(v.get("flow_profile") for v in report["discharge"][name].values()):
            plot_flow_profiles(report["discharge"][name], out / f"flow_profiles_{name}.png", name)
            pngs.append((f"Time-averaged wall profiles during flow, {name}", f"flow_profiles_{name}.png"))

    for sc in report.get("scenes", []):
        if plot_forest(report["metrics"], out / f"verdict_{sc['name']}.png", sc["name"]):
            pngs.append((f"Each metric's interval against its margin, {sc['name']}", f"verdict_{sc['name']}.png"))
    return pngs


def _agreement(report: dict, out: Path) -> None:
    """out/agreement.json: the verdict, the scenes and every metric (with looks, mutants, attribution)."""
    agreement = {"verdict": report["verdict"], "profile": report.get("profile"), "codes": report["codes"],
                 "passed": report["passed"], "scenes": report.get("scenes", []), "metrics": report["metrics"]}
    if report.get("looks"):
        agreement["looks"] = report["looks"]
    if report.get("mutants"):
        agreement["mutants"] = report["mutants"]
    if report.get("attribution"):
        agreement["attribution"] = report["attribution"]
    write_text_atomic(out / "agreement.json", json.dumps(agreement, indent=1, default=float) + "\n")


def _mutant_rows(mu: dict) -> list:
    L = []
    L += ["", "## Mutants (one constant of one reference code's translation changed)", "",
          "A mutant is caught when a metric says disagree under it (the baseline agreeing there). Its effect on "
          "each statistical metric is its interval of the difference from native, against the margin.", "",
          "| mutant | code | verdict | caught | by a physical metric | metrics that disagree (tolerances or margins "
          "off) | effect on the statistical metrics |", "|---|---|---|---|---|---|---|"]
    for r in mu["rows"]:
        by = "; ".join(f"{x['scene']}: {x['metric']} ({_fmt(x['by'])})" for x in r["metrics"][:6])
        if not r.get("applicable", True):
            L.append(f"| {r['mutant']} | {r['code']} | | n/a: changes nothing in these scenes | | | |")
            continue
        eff = "; ".join(f"{e['metric']}: {_interval(dict(e, kind='statistical'))} {e['verdict']}"
                        for e in r.get("effects", [])[:8])
        need = r.get("proves") or []
        got = (" (must disagree by " + ", ".join(need) + "; did by " + (", ".join(r.get("proved") or []) or "none")
               + ")") if need else ""
        L.append(f"| {r['mutant']} | {r['code']} | {r.get('verdict', '')} | {'yes' if r['caught'] else '**NO**'}{got} | "
                 f"{'yes' if r['caught_physically'] else 'no'} | {by} | {eff} |")
    return L


def _attribution_and_collisions(report: dict) -> list:
    L = []
    if report.get("attribution"):
        L += ["", "## Attribution: which law option closes a failing metric", "",
              "| scene | native law option switched to the shared value | metrics failing before | after |",
              "|---|---|---|---|"]
        for a in report["attribution"]:
            for row in a["rows"]:
                L.append(f"| {a['scene']} | {row['option']} | {a['failing']} | {row['failing']} |")
            L.append(f"| {a['scene']} | **verdict** | {a['verdict']} | |")
    if report.get("calibration"):
        codes = [c for c in ("native", "liggghts", "yade", "lammps") if c in report["codes"]]
        L += ["", "## Collisions (Chung & Ooi's tests as scenes: compare/verdict/calibration.py)", "",
              "Each code against the reference (**x**: outside the tolerance), and the reference codes against "
              "the native engine.", "", calibration.table(report["calibration"], codes)]
    return L


def _static_rows(report: dict) -> list:
    L = []
    if report.get("static"):
        L += ["", "## Static cases: wall totals (force by the discs on each wall)", ""]
        for st in report["static"]:
            if "results" in st:
                L += [f"{st['case']} (frozen packing, {st['n_discs']} discs):", "",
                      "| code | status | wall | normal | shear | wall time [s] |", "|---|---|---|---|---|---|"]
                for c, r in st["results"].items():
                    if r["status"] != "ok":
                        L.append(f"| {c} | FAILED: {r['reason']} | | | | |")
                        continue
                    for w, t in r["totals"].items():
                        L.append(f"| {c} | ok | {w} | {t['normal']:.9g} | {t['shear']:.9g} | {r['wall_time_s']:.1f} |")
                L.append("")
            else:
                L += [f"{st['case']} ({st['members']} members per code from the scene's start; mean ± s.e. (members)):",
                      "", "| code | " + " | ".join(k for k in st["summary"]["native"] if k != "failed") + " |",
                      "|---|" + "---|" * (len(st["summary"]["native"]) - 1)]
                for c, v in st["summary"].items():
                    L.append(f"| {c} | " + " | ".join(_ms(x) for k, x in v.items() if k != "failed") + " |")
                L.append("")
    return L


def _janssen_and_shear(report: dict) -> list:
    L = []
    for jd in report.get("janssen", []):
        L += ["", f"## Janssen column {jd['case']}", ""] + jd.get("table", [])
    for sd in report.get("shear", []):
        cols = sd["keys"] + ["peak_raw", "strain_at_peak"]
        L += ["", f"## Shear box {sd['case']} (mean ± s.e. (members); dt {sd.get('dt', float('nan')):g} s)", "",
              "| code | at rest before the shear | " + " | ".join(label(k) for k in cols) + " |",
              "|---|---|" + "---|" * len(cols)]
        for c, v in sd["summary"].items():
            L.append(f"| {c} | {sum(v['rested'])}/{len(v['rested'])} | " + " | ".join(_ms(v[k]) for k in cols) + " |")
            for f in v["failed"]:
                L.append(f"| {c} | FAILED {f} |" + " |" * len(cols))
    return L


def _discharge_rows(report: dict) -> list:
    L = []
    if report.get("discharge"):
        L += ["", "## Discharge ensembles (mean ± s.e. (members))", "",
              "| scene | code | members (failed) | discs out | flow rate [discs/s] | jammed (Wilson 95 %) | "
              "windowed peak side | windowed peak bottom | raw peak side, median [95 %] | side normal during flow | "
              "side friction during flow | bottom normal during flow |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for name, s in report["discharge"].items():
            for c, v in s.items():
                lo, hi = wilson(v["jammed"], v["ok_members"]) if v["ok_members"] else (float("nan"),) * 2
                pk = v["peak_ratio_side"]
                L.append(f"| {name} | {c} | {v['members']} ({v['failed']}) | {_ms(v['discs_out'])} | "
                         f"{_ms(v['flow_rate'])} | {v['jammed']}/{v['ok_members']} [{lo:.2f}, {hi:.2f}] | "
                         f"{_ms(v['peak_window_side'])} | {_ms(v['peak_window_bottom'])} | "
                         f"{_fmt(pk[0])} [{_fmt(pk[1])}, {_fmt(pk[2])}] | {_ms(v['flow_side_normal'])} | "
                         f"{_ms(v['flow_side_shear'])} | {_ms(v['flow_bottom_normal'])} |")
                for f in v["failures"]:
                    L.append(f"| {name} | {c} | FAILED member: {f} | | | | | | | | | |")
    return L


def write(report: dict, out: Path) -> None:
    """out/report.md, out/agreement.json and the plots."""
    out.mkdir(parents=True, exist_ok=True)
    pngs = _plots(report, out)
    _agreement(report, out)
    L = [f"# Agreement report ({report.get('profile', 'quick')} profile)", ""] + headline(report)
    mu = report.get("mutants")
    if mu:
        L.append(f"**Mutants: {mu['n_caught']} of {mu['n_applicable']} caught** "
                 f"({sum(r['caught_physically'] for r in mu['rows'])} by a physical metric, the translation check aside; "
                 f"{len(mu['rows']) - mu['n_applicable']} change nothing in these scenes).")
    L += ["", "Codes: " + "; ".join(f"{c}: {v}" for c, v in report["codes"].items()), "", "## Method", ""] + METHOD
    if report.get("scenes"):
        L += ["", "## Scenes", "", "| scene | kind | members | dt [s] | duration [s] | native law | time [s] | verdict |",
              "|---|---|---|---|---|---|---|---|"]
        for s in report["scenes"]:
            L.append(f"| {s['name']} | {s['kind']} | {s['members']} | {s['dt']:g} | {s['duration']:g} | "
                     f"{s['native_law']} | {s['elapsed_s']:.0f} | {_verdict(s['verdict'])} |")
    L += ["", "## Agreement table", "",
          "| scene | metric | values | tolerance or margin | 90 % interval of the difference | verdict | note |",
          "|---|---|---|---|---|---|---|"]
    for m in report["metrics"]:
        need = m.get("members_to_decide")
        note = "; ".join(x for x in (m["note"], f"about {need} members per code would decide it" if need else "") if x)
        L.append(f"| {m['scene']} | {m['metric']} | {_fmt(m['values'])} | {_fmt(m['tolerance'])} | {_interval(m)} | "
                 f"{_verdict(m['verdict'])} | {note} |")
    if mu:
        L += _mutant_rows(mu)
    L += _attribution_and_collisions(report) + _static_rows(report) + _janssen_and_shear(report) + _discharge_rows(report)
    L += ["", "## Plots", ""] + [f"### {t}\n\n![{t}]({p})\n" for t, p in pngs]
    L += ["## What the translations cannot express exactly", "",
          "- The paper's incremental normal spring and its no-tension rule on the elastic force (eqs. 7a, 8) and "
          "the Coulomb cap on the elastic normal force (eq. 13): neither LIGGGHTS nor YADE has them; all codes "
          "run the shared variant (`--native-law scene` runs the engine's own law against them).",
          "- LIGGGHTS walls are triangle meshes: a wall's end acts as a point contact of the mesh that owns it, "
          "where the engine has explicit points.",
          "- YADE combines the two materials of a contact in series; the translation solves the wall material "
          "for the resolved disc-wall constants (compare/codes/yade_backend.py).", ""]
    write_text_atomic(out / "report.md", "\n".join(L) + "\n")

"""Paper 2's simple shear study: every alpha with and without clusters, native and YADE, into
one report (out/shear/report.md) with the Fig. 7 analogue, the contact-force networks (Figs. 5,
6), the peak tau/sigma table, the paper's trends, the cross-checks and the time-step bounds.

    /usr/bin/python3 -m dem.compare.papers.shear_study --out out/shear [--dem build/dem] [--jobs 2] [--no-yade]

Runs (scenes reference_inputs/scenes/shear_a<alpha>_<variant>.toml, variants free, clusters =
every pair of a cluster bonded, touching = only the apex-base contacts bonded):

- native:           the scenes as they are: paper 1's law, eq. (19), dt = 1e-4 s (paper 2);
- native_dt5e-5:    the same at dt = 5e-5 s (time-step sensitivity; the closed-triangle
                    clusters of alpha = 35 do not come to rest at 1e-4 s);
- native_yadelaw:   YADE's contact law in the engine (overlap spring, total-force no-tension
                    and Coulomb cap), velocity Verlet at 2.5e-5 s (bonded clusters with their
                    dashpots need it: `dem resolve --stability`): the bridge between the codes;
- native_platewalls: the plate's horizontal motion tied to the side walls (a reading of the
                    paper's "moves horizontally with the rotation of both sides");
- yade:             YADE 2023.02a at 5e-5 s through the YADE backend's shear path
                    (compare/codes/yade_backend.py shear_case_data, compare/codes/shear_yade_template.py: the
                    translation `dem compare --kind shear` runs; compare/codes/shear_yade.py makes the
                    case from the scene's own start): free discs, clusters as elastic unbreakable
                    cohesive bonds (all pairs, touching pairs), and as clumps.

`dem compare` judges the codes' agreement on a shear-box scene statistically (jittered members,
docs/compare.md); this study runs each scene once per code and variant for the paper's findings.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from dem.compare.io import scene_toml
from dem.compare.figures import shear_figures as sf
from dem.compare.cases import common
from dem.compare.codes import shear_yade
from dem.compare.io.job_pool import JobPool

REPO = Path(__file__).resolve().parents[2]
SCENES = REPO / "reference_inputs" / "scenes"
ALPHAS = (58, 50, 35)
VARIANTS = ("free", "clusters", "touching")
LABEL = {"free": "no clusters", "clusters": "clusters (closed triangles)", "touching": "clusters (contacts bonded)"}
GAMMA_FIG6 = 0.05   # the paper's Fig. 6 strain


def scene(alpha, variant):
    return SCENES / f"shear_a{alpha}_{variant}.toml"


# The native variants' changes to the paper's shear scenes, by key (dem.compare.io.scene_toml refuses a
# key the scene does not have: a variant never runs the base scene by mistake).
VARIANT_CHANGES = {
    "native": {},
    "native_yadelaw": {"contact.normal_spring": "overlap", "contact.no_tension": "total",
                       "contact.friction_cap": "total", "integrator.scheme": "velocity_verlet",
                       "integrator.dt": 2.5e-5},
    "native_dt5e-5": {"integrator.dt": 5e-5},
    "native_platewalls": {"shear_box.plate_horizontal": "with_walls"},
}


def write_variant(src, kind, path):
    """The scene of a native variant, written to path."""
    return scene_toml.edit(src, {**VARIANT_CHANGES[kind], "output.progress": False}, path)


REUSE = False  # --reuse: keep runs whose summary.json exists (report only)


def run_native(dem, kind, alpha, variant, out_root):
    out = out_root / kind / f"a{alpha}_{variant}"
    if REUSE and (out / "summary.json").is_file():
        return {"kind": kind, "alpha": alpha, "variant": variant, "dir": str(out)}
    src = scene(alpha, variant)
    work = out_root / kind / "scenes"
    work.mkdir(parents=True, exist_ok=True)
    path = work / src.name
    write_variant(src, kind, path)
    t0 = time.time()
    proc = subprocess.run([str(dem), "run", str(path), "--out", str(out), "--quiet"],
                          capture_output=True, text=True)
    if proc.returncode != 0:
        return {"kind": kind, "alpha": alpha, "variant": variant, "dir": str(out), "error": proc.stderr.strip()[-500:]}
    return {"kind": kind, "alpha": alpha, "variant": variant, "dir": str(out), "wall_s": time.time() - t0}


def run_yade(dem, mode, alpha, variant, out_root):
    out = out_root / "yade" / f"a{alpha}_{mode}"
    if REUSE and (out / "summary.json").is_file():
        return {"kind": "yade", "alpha": alpha, "variant": mode, "dir": str(out)}
    try:
        shear_yade.run(scene(alpha, variant), out, "bonds" if mode.startswith("bonds") else mode, 5e-5, dem)
    except SystemExit as e:
        return {"kind": "yade", "alpha": alpha, "variant": mode, "dir": str(out), "error": str(e)[-500:]}
    return {"kind": "yade", "alpha": alpha, "variant": mode, "dir": str(out)}


def metrics(run):
    """Peak and other numbers of one run directory."""
    d = Path(run["dir"])
    if "error" in run or not (d / "summary.json").is_file():
        return None
    s = json.loads((d / "summary.json").read_text())
    series = sf.read_series(str(d / "shear_series.csv"))
    raw, at, windowed = sf.peak(series)
    strain, ratio = series["strain"], series["ratio"]
    k5 = int(np.argmin(np.abs(strain - GAMMA_FIG6)))
    upto = {c: v[:k5 + 1] for c, v in series.items()}
    raw5, at5, windowed5 = sf.peak(upto)
    m = {"peak": raw, "at": at, "windowed": windowed, "ratio_5": float(ratio[k5]), "final": float(ratio[-1]),
         "peak5": raw5, "at5": at5, "windowed5": windowed5,
         "strain_final": float(strain[-1]), "sigma0": float(series["sigma"][0]),
         "rest": bool((s.get("rest") or {}).get("reached")), "rest_time": (s.get("rest") or {}).get("time"),
         "status": s.get("status"), "plate_rise": (s.get("shear") or {}).get("plate_final", [0, 0])[1],
         "bond_strain": (s.get("shear") or {}).get("bond_strain_final"),
         "check_static": (s.get("shear") or {}).get("check_static_max_relative"),
         "check_inertia": (s.get("shear") or {}).get("check_with_inertia_max_relative"),
         "planes": (s.get("shear") or {}).get("planes"), "plate_weight": (s.get("shear") or {}).get("plate_weight"),
         "width": (s.get("shear") or {}).get("width"), "discs_weight": (s.get("shear") or {}).get("discs_weight"),
         "wall_s": s.get("wall_time_s")}
    if "sigma_check" in series:  # static equilibrium of the part above each plane, all samples
        m["check_yade"] = float(np.max(np.abs(series["sigma"] - series["sigma_check"]) / np.abs(series["sigma"])))
    return m


def fmt(v, spec=".3f"):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return format(v, spec)


def scene_header(alpha, variant):
    text = scene(alpha, variant).read_text().splitlines()
    return " ".join(line.lstrip("# ").strip() for line in text[2:4])


def run_all(dem, out, jobs, no_yade):
    """Every run of the study (native variants, then YADE's), as tasks of one job pool."""
    with JobPool(jobs) as pool:
        tasks = [pool.run(run_native, dem, kind, al, v, out)
                 for kind in ("native", "native_dt5e-5", "native_yadelaw") for al in ALPHAS for v in VARIANTS]
        tasks += [pool.run(run_native, dem, "native_platewalls", al, v, out) for al in ALPHAS for v in ("free", "clusters")]
        if not no_yade:
            tasks += [pool.run(run_yade, dem, mode, al, v, out) for al in ALPHAS
                      for mode, v in (("none", "free"), ("bonds", "clusters"), ("bonds_touching", "touching"),
                                      ("clumps", "clusters"))]
        return [task.result() for task in tasks]


def at_rest(get, kind, al, v):
    """The run of the scene, or its dt = 5e-5 s run when it never came to rest at 1e-4 s."""
    r = get.get((kind, al, v))
    alt = get.get(("native_dt5e-5", al, v)) if kind == "native" else None
    if r and r["m"] and not r["m"]["rest"] and alt and alt["m"] and alt["m"]["rest"]:
        return alt
    return r


def draw_figures(get, out):
    """The Fig. 7 analogue (tau/sigma against strain) and the contact-force networks (Figs. 5, 6)."""
    figs = {}
    curves = []
    for al in ALPHAS:
        for v in VARIANTS:
            r, label = get.get(("native", al, v)), f"{v} native"
            alt = get.get(("native_dt5e-5", al, v))
            if r and r["m"] and not r["m"]["rest"] and alt and alt["m"] and alt["m"]["rest"]:
                r, label = alt, f"{v} native dt 5e-5"  # not at rest at 1e-4 s: the time-step bound
            if r and r["m"]:
                curves.append((f"{al}", label, sf.read_series(str(Path(r["dir"]) / "shear_series.csv"))))
        for mode, label in (("none", "free"), ("bonds", "clusters"), ("clumps", "clumps")):
            r = get.get(("yade", al, mode))
            if r and r["m"]:
                curves.append((f"{al}", f"{label} YADE", sf.read_series(str(Path(r["dir"]) / "shear_series.csv"))))
    figs["fig7"] = sf.plot_ratio(curves, str(out / "fig7_ratio_strain.png"),
                                 "tau_xy / sigma_x against shear strain, alpha = 58, 50, 35 deg (paper 2, Fig. 7 analogue)")
    for kind, tag in (("native", "native"), ("yade", "yade")):
        items = []
        for al in ALPHAS:
            fr = at_rest(get, kind, al, "free" if kind == "native" else "none")
            cl = at_rest(get, kind, al, "clusters" if kind == "native" else "bonds")
            if al == 58 and cl and cl["m"]:
                items.append((cl["dir"], 0, f"alpha {al}, clusters, compressed (Fig. 5)"))
                items.append((fr["dir"], 0, f"alpha {al}, no clusters, compressed"))
            if cl and cl["m"] and fr and fr["m"]:
                dt_note = " (dt 5e-5)" if "dt5e-5" in cl["dir"] else ""
                items.append((cl["dir"], 1, f"alpha {al}, clusters{dt_note} (Fig. 6a)"))
                items.append((fr["dir"], 1, f"alpha {al}, no clusters (Fig. 6b)"))
        if items:
            figs[f"net_{tag}"] = sf.plot_networks(items, str(out / f"fig5_6_networks_{tag}.png"), ncols=2)
    return figs


def cluster_bounds(dem):
    """{(alpha, variant): {scheme: the dt bound the engine enforces for the scene run with it}}
    (``dem resolve --stability``)."""
    bounds = {}
    for al in ALPHAS:
        for v in VARIANTS:
            try:
                bounds[(al, v)] = {s: common.stability(scene(al, v), {"integrator.scheme": s}, dem)["dt_bound"]
                                   for s in ("paper_eq18", "paper_eq19", "velocity_verlet")}
            except Exception as e:  # noqa: BLE001 -- reported, never fatal
                bounds[(al, v)] = {"error": str(e)}
    return bounds


def setup_section(L, seconds):
    L.append("# Paper 2: clusters and the simple shear test (Sumita, Kiyama & Nishimura)\n")
    L.append(f"Generated by `scripts/shear_study.sh` (`python3 -m dem.compare.papers.shear_study`) in {seconds:.0f} s. "
             "Engine runs: `dem run reference_inputs/scenes/shear_a<alpha>_<variant>.toml`; YADE runs: "
             "the YADE backend's shear path (`compare/codes/yade_backend.py`, the translation `dem compare --kind shear` runs; "
             "YADE 2023.02a), from the scene's own start.\n")
    L.append("## Setup\n")
    L.append("Box b = 40 cm, walls 30 cm long turning clockwise about their lower ends at 0.05 rad/s after the "
             "compression; a plate of F/(rho g) = 1500 cm^3 (3975 g per cm, weight 3.90e6 dyn/cm) on top, free "
             "vertically and horizontally, no rotation. Discs r = 1 cm, rho = 2.65, paper 1's Table 2 constants "
             "(K_n/(rho g) = 3.64e4 cm, K_s = K_n/4, eta_n/(rho g) = 15.3 cm s (paper 2 prints 1.53e4: a misprint), "
             "eta_s/(rho g) = 7.65, mu = tan 30 deg); walls, floor and plate take paper 1's wall values (2 K, 2 eta, "
             "mu_w = tan 10 deg): paper 2 states neither friction. eq. (19), dt = 1e-4 s. Compression: to the paper "
             "1 rest criterion (note 3), at most 4 s. Shear strain gamma = tan(wall angle), to 0.15. Stresses: "
             "the mean over the virtual planes between consecutive rows of the force transmitted across each plane "
             "(contacts and bonds whose centre line crosses it), divided by b.\n")
    for al in ALPHAS:
        L.append(f"- alpha = {al}: {scene_header(al, 'clusters')}")
    L.append("")
    L.append("Clusters tile each pair of rows with triangles pointing up and down in turn (free discs are left at "
             "row ends). `clusters`: all three pairs of a triangle bonded (the base pair across its gap p - 2r, "
             "lever arms R0/2); `touching`: only the two apex-base contacts bonded, the paper's "
             "\"inter-element contacts\" read literally (a V whose base discs do not touch for alpha < 60).\n")



def table(L, get, kind, variants, title, note=""):
    L.append(f"### {title}\n")
    if note:
        L.append(note + "\n")
    L.append("| alpha | variant | peak tau/sigma | at strain | windowed peak | peak to 5 % (windowed) | at 5 % | at 15 % | sigma0 [dyn/cm^2] | rest | plate rise [cm] |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|")
    for al in ALPHAS:
        for v in variants:
            r = get.get((kind, al, v))
            if not r:
                continue
            m = r["m"]
            if not m:
                L.append(f"| {al} | {v} | failed: {r.get('error', '?')[:80]} | | | | | | | | |")
                continue
            rest = "yes" if m["rest"] else "NO"
            L.append(f"| {al} | {v} | {fmt(m['peak'])} | {fmt(m['at'])} | {fmt(m['windowed'])} | "
                     f"{fmt(m['peak5'])} ({fmt(m['windowed5'])}) | {fmt(m['ratio_5'])} | {fmt(m['final'])} | {fmt(m['sigma0'], '.4g')} | {rest} | {fmt(m['plate_rise'])} |")
    L.append("")


def peak_section(L, get, no_yade):
    L.append("## Peak stress ratio\n")
    L.append("Peak = largest sampled tau/sigma (every 0.001 strain) up to 0.15; windowed = largest centred "
             "moving average over 0.011 strain (robust to single-sample spikes). ![Fig. 7](fig7_ratio_strain.png)\n")
    table(L, get, "native", VARIANTS, "Native, paper's law and dt = 1e-4 s (the main result)")
    table(L, get, "native_dt5e-5", VARIANTS, "Native, dt = 5e-5 s")
    table(L, get, "native_yadelaw", VARIANTS, "Native with YADE's contact law, velocity Verlet, dt = 2.5e-5 s")
    table(L, get, "native_platewalls", ("free", "clusters"), "Native, plate moving horizontally with the walls (dt = 1e-4 s)")
    if not no_yade:
        table(L, get, "yade", ("none", "bonds", "bonds_touching", "clumps"), "YADE 2023.02a, dt = 5e-5 s",
              "none: free discs; bonds: every pair of a cluster an elastic unbreakable CohFrictPhys bond; "
              "bonds_touching: the apex-base pairs only; clumps: rigid YADE clumps. A clump carries force "
              "inside itself where no interaction records it, so for clumps sigma and tau are the means over "
              "the planes no clump crosses (between the pairs of rows the clusters tile: half the planes).")

    # --- compact summary table (windowed peaks)
    L.append("### Summary: windowed peak tau/sigma\n")
    cols = [("native", "free"), ("native", "clusters"), ("native", "touching"), ("native_dt5e-5", "free"),
            ("native_dt5e-5", "clusters"), ("native_dt5e-5", "touching"), ("yade", "none"), ("yade", "bonds"),
            ("yade", "bonds_touching"), ("yade", "clumps")]
    L.append("| alpha | " + " | ".join(f"{k} {v}" for k, v in cols) + " |")
    L.append("|---|" + "---|" * len(cols))
    for al in ALPHAS:
        cells = []
        for k, v in cols:
            r = get.get((k, al, v))
            cells.append(fmt(r["m"]["windowed"]) if r and r["m"] else "-")
        L.append(f"| {al} | " + " | ".join(cells) + " |")
    L.append("")



def trend_lines(get, kind, free, clus, name, key="windowed", span="to 15 %"):
    out = []
    ok1 = []
    for al in ALPHAS:
        f, c = get.get((kind, al, free)), get.get((kind, al, clus))
        if f and c and f["m"] and c["m"]:
            ok1.append((al, c["m"][key] > f["m"][key], f["m"][key], c["m"][key]))
    if ok1:
        held = all(x[1] for x in ok1)
        out.append(f"- {name}, {span}: clusters raise the peak for each alpha: **{'holds' if held else 'does not hold'}** (" +
                   "; ".join(f"alpha {al}: {fv:.3f} -> {cv:.3f}" for al, _, fv, cv in ok1) + ")")
    peaks = [(al, get[(kind, al, free)]["m"][key]) for al in ALPHAS
             if get.get((kind, al, free)) and get[(kind, al, free)]["m"]]
    if len(peaks) == 3:
        order = [p for _, p in peaks]  # alphas 58, 50, 35
        held = order[0] < order[1] < order[2]
        out.append(f"- {name}, {span}: without clusters a smaller alpha gives a larger peak: **{'holds' if held else 'does not hold'}** "
                   f"(58: {order[0]:.3f}, 50: {order[1]:.3f}, 35: {order[2]:.3f})")
    return out


def trend_section(L, get, no_yade):
    L.append("## The paper's findings\n")
    L.append("Windowed peaks over the whole shear (to gamma = 15 %) and up to the paper's Fig. 6 strain (5 %).\n")
    for key, span in (("windowed", "to 15 %"), ("windowed5", "to 5 %")):
        L += trend_lines(get, "native", "free", "clusters", "native, closed triangles", key, span)
        L += trend_lines(get, "native", "free", "touching", "native, contacts bonded", key, span)
        L += trend_lines(get, "native_dt5e-5", "free", "clusters", "native dt 5e-5, closed triangles", key, span)
        L += trend_lines(get, "native_yadelaw", "free", "clusters", "native with YADE's law, closed triangles", key, span)
        if not no_yade:
            L += trend_lines(get, "yade", "none", "bonds", "YADE, bonds", key, span)
            L += trend_lines(get, "yade", "none", "clumps", "YADE, clumps", key, span)
    L.append("")
    L.append("NOTES_ON_TRENDS\n")



def checks_section(L, runs):
    L.append("## Cross-checks of the stresses\n")
    L.append("Each plane's sigma and tau (contacts and bonds cut by the plane) against the load of the part above: "
             "its weight and the forces of the side walls and the plate on it. `static` is the largest relative "
             "difference (to sigma) over all samples (the part above's inertia: the run is dynamic); `with inertia` "
             "adds sum(m a) of the part above and must vanish to roundoff. sigma0 (before the shear) lies between the "
             "plate's load / b and (plate + all discs) / b.\n")
    L.append("| run | alpha | variant | planes | static | with inertia | sigma0 / (plate weight / b) | max bond strain |")
    L.append("|---|---|---|---|---|---|---|---|")
    for r in runs:
        m = r["m"]
        if not m or r["kind"] not in ("native", "yade"):
            continue
        pl = m["plate_weight"] / m["width"] if m.get("plate_weight") and m.get("width") else float("nan")
        static = m["check_static"] if m["check_static"] is not None else m.get("check_yade")
        L.append(f"| {r['kind']} | {r['alpha']} | {r['variant']} | {m['planes']} | {fmt(static, '.2e')} | "
                 f"{fmt(m['check_inertia'], '.1e')} | {fmt(m['sigma0'] / pl)} | {fmt(m['bond_strain'], '.2e')} |")
    L.append("")



def bounds_section(L, get, bounds):
    L.append("## Time step and clusters\n")
    L.append("The dt bound the engine enforces with each scheme (`dem resolve SCENE --stability --set "
             "integrator.scheme=S`): the spectral radius of one step on a single contact, on a disc's rotation "
             "held by 4 contacts, and on each distinct cluster (its discs, bonds and the contacts to its touching "
             "neighbours held fixed, every contact sticking). Not a safe bound for the assembly (moving "
             "neighbours raise frequencies), but it ranks the cases.\n")
    L.append("| alpha | variant | eq. 18 | eq. 19 | velocity Verlet | native at 1e-4: rest |")
    L.append("|---|---|---|---|---|---|")
    for al in ALPHAS:
        for v in VARIANTS:
            b = bounds.get((al, v), {})
            r = get.get(("native", al, v))
            rest = ("yes" if r["m"]["rest"] else "NO") if r and r["m"] else "-"
            if "error" in b:
                L.append(f"| {al} | {v} | error | | | {rest} |")
            else:
                L.append(f"| {al} | {v} | {b['paper_eq18']:.3g} | {b['paper_eq19']:.3g} | {b['velocity_verlet']:.3g} | {rest} |")
    L.append("")


def runs_section(L, runs, out, no_yade):
    L.append("NOTES_ON_DIFFERENCES\n")
    L.append("## Contact-force networks\n")
    L.append("Native (one disc diameter = the plate's weight shared by one row, b/2r discs): "
             "![networks](fig5_6_networks_native.png)\n")
    if not no_yade:
        L.append("YADE, same scale: ![networks](fig5_6_networks_yade.png)\n")
    L.append("## Runs\n")
    for r in runs:
        st = "failed" if not r["m"] else f"{r['m']['status']}, {fmt(r['m'].get('wall_s'), '.1f')} s"
        L.append(f"- {r['kind']} alpha {r['alpha']} {r['variant']}: `{os.path.relpath(r['dir'], out)}` ({st})")


def write_report(out, runs, get, bounds, no_yade, seconds):
    """out/report.md (with the notes of compare/papers/shear_notes.md) and out/results.json."""
    L = []
    setup_section(L, seconds)
    peak_section(L, get, no_yade)
    trend_section(L, get, no_yade)
    checks_section(L, runs)
    bounds_section(L, get, bounds)
    runs_section(L, runs, out, no_yade)
    text = "\n".join(L) + "\n"
    notes = Path(__file__).resolve().parent / "shear_notes.md"
    if notes.is_file():  # the interpretation, written from these runs (compare/papers/shear_notes.md)
        parts = notes.read_text().split("<!-- split -->")
        text = text.replace("NOTES_ON_TRENDS\n", parts[0].strip() + "\n")
        text = text.replace("NOTES_ON_DIFFERENCES\n", (parts[1].strip() if len(parts) > 1 else "") + "\n")
    else:
        text = text.replace("NOTES_ON_TRENDS\n", "").replace("NOTES_ON_DIFFERENCES\n", "")
    (out / "report.md").write_text(text)
    summary = {f"{r['kind']}/a{r['alpha']}_{r['variant']}": r["m"] for r in runs}
    (out / "results.json").write_text(json.dumps(summary, indent=1))


def main(argv=None):
    ap = argparse.ArgumentParser(prog="dem.compare.papers.shear_study", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=str(REPO / "out" / "shear"))
    ap.add_argument("--dem", default=os.environ.get("DEM_BINARY", str(REPO / "build" / "dem")))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--no-yade", action="store_true")
    ap.add_argument("--reuse", action="store_true", help="keep runs already in --out (rewrite the report)")
    a = ap.parse_args(argv)
    global REUSE
    REUSE = a.reuse
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.time()
    runs = run_all(a.dem, out, a.jobs, a.no_yade)
    for r in runs:
        r["m"] = metrics(r)
        if "error" in r:
            print(f"FAILED {r['kind']} a{r['alpha']} {r['variant']}: {r['error']}", file=sys.stderr)
    get = {(r["kind"], r["alpha"], r["variant"]): r for r in runs}
    draw_figures(get, out)
    write_report(out, runs, get, cluster_bounds(a.dem), a.no_yade, time.time() - t0)
    print(f"report: {out / 'report.md'} ({time.time() - t0:.0f} s)")
    return 0

if __name__ == "__main__":
    sys.exit(main())

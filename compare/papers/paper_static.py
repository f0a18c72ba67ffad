"""The paper's static filling study (section 5(1), Figs. 6 and 7), run with the native engine.

For each arrangement (s-1)/s, s = 12..19, and each scheme (eq. 18, eq. 19, velocity Verlet) at
dt = 5e-5 s and the paper's 1e-4 s, fills the closed silo to rest and records the side-wall
normal force, whether rest was reached, the force balance and the left/right asymmetry.
Writes OUT/report.md, OUT/study.json and PNGs (network grids, Fig. 7 analogues).

    /usr/bin/python3 -m dem.compare.papers.paper_static --out out/paper_silo [--dem build/dem] [--jobs 2]
"""
import argparse
import concurrent.futures as cf
import json
import os
import subprocess
import sys
from pathlib import Path

from dem.compare.papers import paper_claims
from dem.compare.io.atomic_file import write_text as write_text_atomic
from dem.compare.io.job_pool import JobPool
from dem.compare.io.run_dir import RunDir, RunDirError

REPO = Path(__file__).resolve().parents[2]
SCENES = REPO / "reference_inputs" / "scenes"
ARRANGEMENTS = list(range(12, 20))
SCHEMES = ["paper_eq18", "paper_eq19", "velocity_verlet"]
STEPS = [5e-5, 1e-4]
PAPER = ("paper_eq19", 1e-4)      # the paper's own choice (Table 2, eq. 19)
REFERENCE = ("velocity_verlet", 5e-5)  # the standard scheme at a step stable in LIGGGHTS/YADE


def label(s):
    return f"{s - 1}/{s}"


def run_one(dem, s, scheme, dt, out_root):
    """Runs one case; returns its record (never raises for an engine failure)."""
    scene = SCENES / f"silo_{s - 1}_{s}.toml"
    out = out_root / "runs" / f"{scheme}_dt{dt:g}" / f"silo_{s - 1}_{s}"
    cmd = [str(dem), "run", str(scene), "--out", str(out), "--scheme", scheme, "--dt", repr(dt),
           "--force-dt", "--quiet"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    rec = {"s": s, "arrangement": label(s), "scheme": scheme, "dt": dt, "exit": proc.returncode,
           "dir": str(out.relative_to(out_root))}
    if proc.returncode not in (0, 3):
        rec.update(status="error", note=proc.stderr.strip()[-300:])
        return rec
    try:
        summ = RunDir(out, strict=True).summary
    except RunDirError as e:
        rec.update(status="error", note=str(e))
        return rec
    dw = summ["disc_weight"]
    g = summ["groups"]
    left, right = g["side_left"]["normal_total"] / dw, g["side_right"]["normal_total"] / dw
    rec.update(status=summ["status"], n=summ["n_discs"], time=summ["time"],
               rest=summ["rest"]["reached"], rest_time=summ["rest"]["time"],
               side_left=left, side_right=right, side_mean=0.5 * (left + right),
               side_friction=(g["side_left"]["shear_total"] + g["side_right"]["shear_total"]) / (2 * dw),
               bottom=g["bottom"]["normal_total"] / dw,
               asymmetry=abs(left - right) / max(abs(left) + abs(right), 1e-300),
               balance=summ["balance"]["residual_relative"], wall_s=summ["wall_time_s"],
               psps=summ["particle_steps_per_s"], dt_bound=summ["stability"]["dt_bound"],
               reason=summ.get("reason", ""))
    return rec


def verdict(r):
    """How a case was judged: blow-up, no rest (jitter), or rest."""
    if r["status"] == "unstable":
        return "blew up"
    if r["status"] == "error":
        return "error"
    if not r["rest"]:
        return "no rest by end time"
    return "rest"


def engine_version(dem) -> str:
    """`dem --version`'s first line (name, version, compiler, build type): what a report says of
    its engine, never a path (another machine's reader has none; the second line names the
    binary's Python package)."""
    proc = subprocess.run([str(dem), "--version"], capture_output=True, text=True, timeout=30)
    return (proc.stdout.strip().splitlines() or ["dem (version unknown)"])[0]


def write_report(out_root, records, dem):
    by = {(r["scheme"], r["dt"], r["s"]): r for r in records}
    lines = ["# The paper's silo, static filling (Kiyama & Fujimura, section 5(1))", "",
             "Native engine, the paper's constants (Table 2), closed slit, about 350 discs of r = 1 cm in the",
             "(s-1)/s lattices with the gaps of note 2. Rest: mean |du| and |dv| per step below 1e-4 g dt^2",
             "(note 3). A case is judged `blew up` when the engine stopped it (overlap beyond half a radius or",
             "non-finite values, exit code 3), `no rest` when it still moved at the end time (5 s).",
             f"Engine: {engine_version(dem)}. Forces per 1 cm of thickness, in disc weights (m g = {2.65 * 3.14159265 * 980:.0f} dyn).", "",
             "## Side-wall normal force (sum over both walls / 2, disc weights) and outcome", ""]
    head = "| scheme | dt [s] | " + " | ".join(label(s) for s in ARRANGEMENTS) + " |"
    lines += [head, "|" + "---|" * (2 + len(ARRANGEMENTS))]
    for scheme in SCHEMES:
        for dt in STEPS:
            cells = []
            for s in ARRANGEMENTS:
                r = by.get((scheme, dt, s))
                v = verdict(r) if r else "-"
                if r and v == "rest":
                    cells.append(f"{r['side_mean']:.1f}")
                elif r and v == "no rest by end time":
                    cells.append(f"{r['side_mean']:.1f} (no rest)")
                else:
                    cells.append(v)
            lines.append(f"| {scheme} | {dt:g} | " + " | ".join(cells) + " |")
    lines += ["", "## Time to rest [s] (simulated) and run cost", "",
              "| scheme | dt [s] | " + " | ".join(label(s) for s in ARRANGEMENTS) + " | particle-steps/s (median) |",
              "|" + "---|" * (3 + len(ARRANGEMENTS))]
    for scheme in SCHEMES:
        for dt in STEPS:
            cells, rates = [], []
            for s in ARRANGEMENTS:
                r = by.get((scheme, dt, s))
                if r and r.get("rest"):
                    cells.append(f"{r['rest_time']:.3f}")
                else:
                    cells.append(verdict(r) if r else "-")
                if r and r.get("psps"):
                    rates.append(r["psps"])
            rates.sort()
            med = f"{rates[len(rates) // 2]:.3g}" if rates else "-"
            lines.append(f"| {scheme} | {dt:g} | " + " | ".join(cells) + f" | {med} |")
    lines += ["", "## Checks at rest (paper's scheme and the reference scheme)", "",
              "| case | arrangement | weight balance residual | left/right asymmetry | wall friction (disc weights, + down) | bottom normal |",
              "|---|---|---|---|---|---|"]
    left_out = []
    for scheme, dt in (PAPER, REFERENCE):
        for s in ARRANGEMENTS:
            r = by.get((scheme, dt, s))
            if r and verdict(r) == "rest":
                lines.append(f"| {scheme} {dt:g} | {label(s)} | {r['balance']:.1e} | {r['asymmetry']:.1e} | "
                             f"{r['side_friction']:.2f} | {r['bottom']:.1f} |")
            elif r:
                left_out.append(f"{scheme} {dt:g} {label(s)} ({verdict(r)})")
    if left_out:
        lines += ["", "Left out of this table, the Fig. 7 analogues and the checks of the paper's statements "
                  "(not at rest): " + ", ".join(left_out) + "."]
    lines += ["", "## Pictures", "",
              "Contact-force networks (Fig. 6 analogue: segment = elastic contact force, disc diameter = 50/pi disc weights):", ""]
    for f in sorted(out_root.glob("network_*.png")):
        lines.append(f"![{f.stem}]({f.name})")
    lines += ["", "Side-wall normal force and friction per contact against depth (Fig. 7 analogue, runs at rest):", ""]
    for f in sorted(out_root.glob("fig7_*.png")):
        lines.append(f"![{f.stem}]({f.name})")
    lines += ["", "## The paper's statements against these runs", "",
              "Each statement of section 5(1) (Kiyama & Fujimura 1983) measured on the runs at rest "
              "(`compare/papers/paper_claims.py` says how).", ""]
    for scheme, dt in (PAPER, REFERENCE):
        rested = [by[(scheme, dt, s)] for s in ARRANGEMENTS
                  if (scheme, dt, s) in by and verdict(by[(scheme, dt, s)]) == "rest"]
        if not rested:
            lines += [f"{scheme} at dt = {dt:g} s: no run came to rest.", ""]
            continue
        runs = {r["arrangement"]: out_root / r["dir"] for r in rested}
        lines += [f"**{scheme}, dt = {dt:g} s** ({len(rested)} of {len(ARRANGEMENTS)} arrangements at rest)", ""]
        lines += paper_claims.table([paper_claims.chains(runs), paper_claims.side_force(rested),
                                     paper_claims.depth(runs), paper_claims.corner_friction(runs)])
        lines.append("")
    write_text_atomic(out_root / "report.md", "\n".join(lines) + "\n")


def draw(out_root, case, records):
    """The figures of one pictured case (scheme, dt): the networks of every run that ended (the grid
    marks those not at rest) and Fig. 7 of the runs at rest (a moving fill's wall forces are no
    static profile)."""
    from dem.compare.figures import runs as figures   # here, in the figure processes: the study's own process imports no matplotlib
    records = sorted(records, key=lambda r: r["s"])
    tag = f"{case[0]}_dt{case[1]:g}"
    mine = [r for r in records if r["status"] not in ("unstable", "error")]
    if mine:
        figures.plot_network_grid([out_root / r["dir"] for r in mine], out_root / f"network_{tag}.png",
                                  labels=[r["arrangement"] for r in mine])
    rested = [r for r in mine if verdict(r) == "rest"]
    if rested:
        figures.plot_side_profiles([out_root / r["dir"] for r in rested], out_root / f"fig7_{tag}.png",
                                   labels=[r["arrangement"] for r in rested])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/paper_silo", help="output folder (default out/paper_silo)")
    ap.add_argument("--dem", default=str(REPO / "build" / "dem"), help="engine binary")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="parallel runs")
    args = ap.parse_args(argv)
    out_root = Path(args.out).resolve()
    out_root.mkdir(parents=True, exist_ok=True)
    if not Path(args.dem).exists():
        sys.exit(f"{args.dem}: engine not built (bash scripts/build.sh)")
    cases = [(s, sc, dt) for sc in SCHEMES for dt in STEPS for s in ARRANGEMENTS]
    # The pictured cases first: their figures are drawn in the pool's figure processes while the
    # other runs go on (compare/io/job_pool.py).
    pictured = [c for c in cases if (c[1], c[2]) in (PAPER, REFERENCE)]
    cases = pictured + [c for c in cases if c not in pictured]
    records, drawing = [], []
    with JobPool(args.jobs, figures="dem.compare.figures.runs") as pool:
        futs = [pool.run(run_one, args.dem, s, sc, dt, out_root) for s, sc, dt in cases]
        for k, f in enumerate(cf.as_completed(futs), 1):
            r = f.result()
            records.append(r)
            print(f"[{k:2d}/{len(cases)}] {r['scheme']:16s} dt={r['dt']:<6g} {r['arrangement']:6s} {verdict(r):20s}"
                  + (f" side {r['side_mean']:.1f}" if "side_mean" in r else ""), flush=True)
            key = (r["scheme"], r["dt"])
            if key in (PAPER, REFERENCE):
                mine = [q for q in records if (q["scheme"], q["dt"]) == key]
                if len(mine) == len(ARRANGEMENTS):
                    drawing += [pool.draw(draw, out_root, key, mine)]
        for d in drawing:
            d.result()  # a figure that failed stops the study with its error
    records.sort(key=lambda r: (SCHEMES.index(r["scheme"]), r["dt"], r["s"]))
    write_text_atomic(out_root / "study.json", json.dumps(records, indent=1) + "\n")
    write_report(out_root, records, args.dem)
    print(f"report: {out_root / 'report.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

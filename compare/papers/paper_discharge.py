"""The paper's discharge study (section 5(2), Figs. 8-10), as ensembles of the native engine.

For 17/18 and 11/12, ensembles of M members (seeded perturbations of 1e-4 cm) with the paper's
scheme (eq. 19, dt = 1e-4 s), velocity Verlet at dt = 5e-5 s and eq. 18 at 1e-4 s; plus the
17/18 fill with the contact-law variants of LIGGGHTS/YADE (overlap spring, total-force clamp and
cap), to show which deviation changes the flow. Writes OUT/report.md, OUT/discharge.json and
the pictures of each configuration's median member.

    /usr/bin/python3 -m dem.compare.papers.paper_discharge --out out/paper_silo/discharge [--members 8] [--jobs 2]
"""
import argparse
import concurrent.futures as cf
import json
import os
import subprocess
import sys
from pathlib import Path

from dem.compare.papers import paper_claims
from dem.compare.io import scene_toml
from dem.compare.io.atomic_file import write_text as write_text_atomic
from dem.compare.io.job_pool import JobPool
from dem.compare.io.run_dir import RunDir

REPO = Path(__file__).resolve().parents[2]
SCENES = REPO / "reference_inputs" / "scenes"

CONFIGS = [  # (tag, arrangement, scheme, dt, contact overrides)
    ("17_18_eq19_1e-4", "17_18", "paper_eq19", 1e-4, {}),
    ("17_18_verlet_5e-5", "17_18", "velocity_verlet", 5e-5, {}),
    ("17_18_eq18_1e-4", "17_18", "paper_eq18", 1e-4, {}),
    ("11_12_eq19_1e-4", "11_12", "paper_eq19", 1e-4, {}),
    ("11_12_verlet_5e-5", "11_12", "velocity_verlet", 5e-5, {}),
    ("11_12_eq18_1e-4", "11_12", "paper_eq18", 1e-4, {}),
    ("17_18_verlet_5e-5_liggghts_law", "17_18", "velocity_verlet", 5e-5,
     {"normal_spring": "overlap", "no_tension": "total", "friction_cap": "total"}),
    ("17_18_verlet_5e-5_cap_total", "17_18", "velocity_verlet", 5e-5, {"friction_cap": "total"}),
    ("17_18_verlet_5e-5_overlap_spring", "17_18", "velocity_verlet", 5e-5, {"normal_spring": "overlap"}),
]


def scene_with(arr, contact, folder):
    """The paper's discharge scene with the contact-law keys changed (dem.compare.io.scene_toml: a key
    the scene does not have is an error, never a silent no-op), written into folder."""
    path = folder / f"discharge_{arr}_{'_'.join(contact.values()) or 'paper'}.toml"
    return scene_toml.edit(SCENES / f"discharge_{arr}.toml", {f"contact.{k}": v for k, v in contact.items()}, path)


def fmt(stat, digits=3):
    """'mean ± standard error', the value alone for one member (no spread to state), '-' for none."""
    if not stat or "mean" not in stat:
        return "-"
    if stat.get("n", 2) < 2:
        return f"{stat['mean']:.{digits}g} (1 member)"
    return f"{stat['mean']:.{digits}g} ± {stat['stderr']:.2g}"


def median_member(ensemble):
    """The member whose discs out at 1 s is the median of those that ran (the pictured one), or None."""
    ran = [r for r in ensemble.get("runs", []) if isinstance(r.get("discs_out_at_1s"), (int, float))]
    if not ran:
        return None
    ran.sort(key=lambda r: (r["discs_out_at_1s"], r["member"]))
    return ran[(len(ran) - 1) // 2]


def jam_text(j):
    """The jam fraction of ensemble.json: 'k/n' of the members with a result, '-' when none had one."""
    if j.get("value") is None:
        return "-"
    n = j.get("of")
    return f"{j['value']:.2f}" + (f" ({j['jammed']}/{n})" if n is not None else "")


def member_commands(dem, scene, ens, members, seed, common):
    """The runs of one configuration, each a process of its own: member K alone (`dem ensemble
    --member K`, bit for bit member K of the ensemble, docs/ensembles.md) into ens/member_KK, and
    the scene as written (one member, no perturbation) into ens/as_written/member_00."""
    runs = [[dem, "ensemble", str(scene), "--out", str(ens), "--member", str(k), "--seed", str(seed), *common]
            for k in range(members)]
    runs.append([dem, "ensemble", str(scene), "--out", str(ens / "as_written"), "--member", "0", "--perturb", "0",
                 *common])
    return runs


def gather(dem, scene, ens, members, seed, common):
    """ensemble.json of the configuration from its members' folders (`dem ensemble merge`: the file
    of the ensemble run in one process, byte for byte), and that of the scene as written. A merge
    that is refused (a member that could not run leaves no summary) falls back to the ensemble run
    in one process, whose file and message say what failed. Returns the completed process whose exit
    code and message the record keeps."""
    proc = subprocess.run([dem, "ensemble", "merge", str(ens), "--members", str(members), "--quiet"],
                          capture_output=True, text=True)
    if proc.returncode not in (0, 3, 4):
        proc = subprocess.run([dem, "ensemble", str(scene), "--out", str(ens), "--members", str(members),
                               "--seed", str(seed), *common], capture_output=True, text=True)
    if subprocess.run([dem, "ensemble", "merge", str(ens / "as_written"), "--members", "1", "--quiet"],
                      capture_output=True, text=True).returncode not in (0, 3, 4):
        subprocess.run([dem, "ensemble", str(scene), "--out", str(ens / "as_written"), "--members", "1",
                        "--perturb", "0", *common], capture_output=True, text=True)
    return proc


# The pictures of a configuration's median member, each drawn as a task of its own in a figure
# process (the three of the last configuration are drawn side by side).
PICTURES = (("frames", "plot_discharge_frames"), ("ratios", "plot_wall_ratios"), ("flow", "plot_flow"))


def draw(pictured_dir, out, tag, kind=None):
    """One picture (kind: frames, ratios or flow) of a configuration's median member, or all three;
    run in a figure process (the study's own process imports no matplotlib)."""
    from dem.compare.figures import runs as figures
    for name, plot in PICTURES:
        if kind in (None, name):
            getattr(figures, plot)(pictured_dir, out / f"{name}_{tag}.png")


def draw_in(pool, *args):
    """draw(*args) in a figure process of the pool, waited for: run as a task of the pool, a
    picture takes one of its --jobs places, so that no more processes run or draw at a time than
    there are places (processes beyond the cores cost CPU of their own: the discharge study 29.2
    -> 28.2 s CPU, 6 interleaved runs each, the same wall time)."""
    return pool.drawn(draw, *args)


def run_order(plan):
    """The configurations in the order their members are started: the longest runs first (the
    smaller time step, more steps a run), so that the configurations that end last are short ones
    and the last pictures start early; CONFIGS order within a time step."""
    return sorted(range(len(plan)), key=lambda k: plan[k][3])


def configuration_record(args, planned):
    """A configuration whose runs have all ended: its members merged (``dem ensemble``'s gather),
    its record, and the folder of the member its pictures show (None: no picture)."""
    tag, arr, scheme, dt, contact, scene, ens, common = planned
    proc = gather(args.dem, scene, ens, args.members, args.seed, common)
    rec = {"tag": tag, "arrangement": arr.replace("_", "/"), "scheme": scheme, "dt": dt,
           "contact": contact or "paper", "exit": proc.returncode}
    plain = ens / "as_written" / "ensemble.json"
    if plain.exists():
        one = (json.loads(plain.read_text()).get("runs") or [{}])[0]
        rec["as_written"] = one.get("discs_out_at_1s") \
            if one.get("status") in ("discharged", "jammed", "emptied") else one.get("status", "-")
    if not (ens / "ensemble.json").exists():
        rec["error"] = proc.stderr.strip()[-400:]
        return rec, None
    rec["ensemble"] = json.loads((ens / "ensemble.json").read_text())
    med = median_member(rec["ensemble"])
    pictured = RunDir(ens / f"member_{med['member']:02d}") if med else None
    if pictured and pictured.status != "unstable" and pictured.file("snapshots").exists():
        rec["pictured"] = med["member"]
        return rec, pictured.path
    return rec, None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/paper_silo/discharge")
    ap.add_argument("--dem", default=str(REPO / "build" / "dem"))
    ap.add_argument("--members", type=int, default=8)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                    help="engine runs and figure processes at once (default: all cores)")
    args = ap.parse_args(argv)
    out = Path(args.out).resolve()
    (out / "scenes").mkdir(parents=True, exist_ok=True)
    jobs = max(1, args.jobs)
    # Every member of every configuration is one task of one pool, so that no core waits for the
    # last member of an ensemble or for the scene as written; each configuration's pictures are
    # tasks of the same pool, drawn in figure processes (matplotlib imported once per process).
    plan = []
    for tag, arr, scheme, dt, contact in CONFIGS:
        scene = scene_with(arr, contact, out / "scenes")
        # --no-vtu: the study reads the members' CSV files and summaries only; their VTU files and
        # PVD indexes (32 of a member's 66 files, some 5 % of its CPU) would be written for nobody.
        common = ["--scheme", scheme, "--dt", repr(dt), "--force-dt", "--quiet", "--no-vtu"]
        plan.append((tag, arr, scheme, dt, contact, scene, out / tag, common))
    results, drawing = {}, []
    # Figure processes fork from a server that imported matplotlib once (compare/io/job_pool.py).
    with JobPool(jobs, figures="dem.compare.figures.runs") as pool:
        waiting = {}           # configuration index -> its runs not yet ended
        for k in run_order(plan):
            tag, arr, scheme, dt, contact, scene, ens, common = plan[k]
            for cmd in member_commands(args.dem, scene, ens, args.members, args.seed, common):
                waiting.setdefault(k, set()).add(pool.run(subprocess.run, cmd, capture_output=True, text=True))
        pending = set().union(*waiting.values())
        # Each configuration is merged and its pictures started as soon as its last run ends, while
        # the runs of the others go on.
        while waiting:
            done, pending = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
            for k in [k for k, futs in waiting.items() if not futs & pending]:
                del waiting[k]
                rec, pictured = configuration_record(args, plan[k])
                if pictured is not None:
                    drawing += [pool.run(draw_in, pool, pictured, out, rec["tag"], name) for name, _ in PICTURES]
                results[k] = rec
                e = rec.get("ensemble", {})
                print(f"{rec['tag']:34s} exit {rec['exit']}  out@1s {fmt(e.get('discs_out_at_1s'))}  "
                      f"jam {e.get('jam_fraction', {}).get('value', '-')}  pattern {e.get('pattern', '-')}",
                      flush=True)
        for f in drawing:
            f.result()  # a figure that failed stops the study with its error
    results = [results[k] for k in range(len(plan))]
    write_text_atomic(out / "discharge.json", json.dumps(results, indent=1) + "\n")

    lines = ["# The paper's silo, discharge (Kiyama & Fujimura, section 5(2))", "",
             f"Ensembles of {args.members} members (seed {args.seed}; every initial centre moved by a uniform",
             "amount in [-1e-4, 1e-4] cm), each: fill to rest, open the 8 cm slit, 1 s of discharge, outlet 4 cm",
             "below the floor, jam = 0.3 s without a removal. Mean ± standard error over members.", "",
             "| configuration | discs out at 1 s | as written | flow [discs/s] | jam fraction | peak/static bottom (raw / 50 ms) "
             "| peak/static side (raw / 50 ms) | funnel / piping / undetermined | blew up / failed |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        e = r.get("ensemble")
        if not e:
            lines.append(f"| {r['tag']} | error: {r.get('error', '')[:80]} | | | | | | | |")
            continue
        p = e["pattern"]
        lines.append(
            f"| {r['tag']} | {fmt(e['discs_out_at_1s'])} | {r.get('as_written', '-')} | {fmt(e['flow_rate_discs'])} | "
            f"{jam_text(e['jam_fraction'])} | {fmt(e['peak_ratio_bottom'])} / {fmt(e['peak_ratio_bottom_windowed'])} | "
            f"{fmt(e['peak_ratio_side'])} / {fmt(e['peak_ratio_side_windowed'])} | "
            f"{p['funnel']} / {p['piping']} / {p['undetermined']} | {e['unstable']} / {e.get('failed', 0)} |")
    lines += ["", "Definitions (docs/outputs.md): flow rate = slope of removed mass from the 5th removal on;",
              "peak/static = largest ratio over the wall bins carrying at least a quarter of the wall's largest",
              "static bin (raw: sampled every 5 ms; 50 ms: moving average); funnel = the top surface first sinks at",
              "a wall column, piping = first at the centre column. Members that blew up or failed count in no",
              "statistic (the jam fraction is of the members with a result).", "",
              "## The paper's statements against these ensembles", "",
              f"The paper's scheme (eq. 19, dt = 1e-4 s), {args.members} members each; peak ratios are "
              "ensemble means (`compare/papers/paper_claims.py` says how each is judged).", ""]
    paper = {r["arrangement"]: r["ensemble"] for r in results
             if r["scheme"] == "paper_eq19" and r["contact"] == "paper" and "ensemble" in r}
    lines += paper_claims.table(paper_claims.discharge(paper)) + ["",
              "## One run against the ensemble", "",
              "`as written` is the scene file run as it is (`dem run`, or an ensemble of one member with",
              "`--perturb 0`): the unperturbed, symmetric lattice. Discharge is chaotic: a perturbation of",
              "1e-4 cm grows into different arches, and the exact lattice is one special configuration, not a",
              "typical one, so that one run can fall outside the ensemble's range. The ensemble is the result",
              "to quote (the same seed gives the same members, bit for bit, with the same build); another",
              "`--seed` draws other members, and the standard errors say how far the means may move.", "",
              "## Pictures (the median member of each configuration, by discs out at 1 s)", ""]
    pictured = {r["tag"]: r["pictured"] for r in results if "pictured" in r}
    for f in sorted(out.glob("frames_*.png")) + sorted(out.glob("ratios_*.png")) + sorted(out.glob("flow_*.png")):
        tag = f.stem.split("_", 1)[1]
        if tag in pictured:
            lines.append(f"{f.stem} (member {pictured[tag]}):")
            lines.append("")
            lines.append(f"![{f.stem}]({f.name})")
            lines.append("")
    write_text_atomic(out / "report.md", "\n".join(lines) + "\n")
    print(f"report: {out / 'report.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""python3 -m dem.compare scene SCENE.toml|LIST.list ... --out DIR [options]   (what `dem compare` runs)
python3 -m dem.compare report --out DIR [--full]     the project's study: reference_inputs/agreement/{quick,full}.list
python3 -m dem.compare translate [--check | --out DIR]

Runs scenes in the native engine and the real reference codes with the shared law and writes
DIR/report.md, DIR/agreement.json and the PNGs. Every metric agrees, disagrees or is
inconclusive (compare/verdict/verdict.py); the exit code says which of the three the report is, 2 for bad
input refused before any run.
"""
import argparse
import json
import re
import shutil
import sys
from pathlib import Path

from dem.compare.cases import mutants, plan, common
from dem.compare.verdict import pipeline, report, sequential, verdict, translate, attribution
from dem.compare.io import scene_toml

CODES = ("native",) + plan.REFERENCE_CODES

EPILOG = """kinds (--kind, default from the scene): collision (one or two discs meet and part; measured
against analytic results and across codes), static (--start frozen: every code rests from the
native engine's rested packing, judged against tolerances matched to the codes' agreement;
--start scene: jittered members from the scene's own start, judged statistically), janssen (a
tall column's ensemble-averaged side-wall profile fitted with Janssen's law), discharge (--start
frozen, the default: every code's member k from the native engine's rested packing jittered with
seed k; --start scene: each code fills the jittered start itself; the gate opens; means, profiles
and the jam fraction against their margins), shear (paper 2's shear box, bonded clusters or free
discs: jittered members compressed to rest and sheared; sigma0, the peak tau/sigma, its mean in
strain bands and the dilation against the shear margin; native and YADE, LIGGGHTS and LAMMPS
refuse it). LAMMPS runs
when named (--codes lammps): collisions, static scenes and discharges; it refuses a hopper (no
inclined finite walls) and caps the total tangential force where the others cap the spring alone.

Every code runs the law all three share (overlap spring, total-force no-tension, Coulomb cap on
the total normal force) with velocity Verlet at the same dt; --native-law scene runs the native
side with the scene's own law instead and attributes a failing metric to the law option that
closes it. Each reference code's constants are read back from the code itself and compared with
`dem resolve` (the translation check). A list file names one scene a line (relative to the list)
with these same options; the project's CI and full studies are such lists
(reference_inputs/agreement/quick.list, full.list); a list line's --codes names the codes that line
runs (a scene one reference code cannot express).

A statistical metric agrees when the 90 % interval of the difference (code vs native, relative to
native's mean) lies inside its margin (--margin KIND=DELTA; defaults docs/compare.md), disagrees
when its interval lies entirely outside, and is inconclusive otherwise (with the members that
would decide it). A failed run, too few members or a native fill that did not rest is
inconclusive, never disagree.

exit codes: 0 agree (with --mutants: and every mutant caught, by a metric that disagrees), 1
disagree (or a mutant that agrees), 2 bad input or a scene a code cannot express, or a dt above
the engine's bound (refused before any run), 3 inconclusive (or a mutant left undecided)."""


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python3 -m dem.compare")
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("scene", prog="dem compare", help="compare scenes (or list files) across codes",
                       description="Runs scenes in the native engine and the reference codes (LIGGGHTS, YADE, "
                                   "LAMMPS) and judges whether they agree.", epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    s.add_argument("scenes", nargs="+", type=Path, help="scene TOML files and/or .list files")
    s.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="change one value of every scene given (and of the scenes of list files) before it is "
                        "translated, as `dem run --set` does: integrator.dt=5e-5, walls.0.material=steel "
                        "(repeatable; the changed scenes are written to OUT/scenes_set/ and validated by the engine)")
    _common(s)
    plan.add_arguments(s)
    r = sub.add_parser("report", help="the project's agreement study (quick.list, or full.list with --full)")
    _common(r)
    t = sub.add_parser("translate", help="write reference_inputs/liggghts/, yade/ and lammps/ for the paper's scenes")
    t.add_argument("--check", action="store_true", help="exit 1 when the committed inputs differ from the generator's")
    t.add_argument("--out", type=Path, help="write complete, runnable inputs here instead (YADE's script included)")
    return ap


def _common(p) -> None:
    p.add_argument("--out", required=True, type=Path, help="output folder (report.md, agreement.json, PNGs)")
    p.add_argument("--codes", default="native,liggghts,yade", help="native plus any of liggghts,yade,lammps (native, the reference, "
                   "runs whether named or not: --codes yade is native and YADE; LAMMPS runs only when named)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--quick", action="store_true", help="quick profile (default): 4 members, 0.3 s static rests")
    g.add_argument("--full", action="store_true", help="full profile: 8 members, 0.6 s static rests")
    p.add_argument("--mutants", action="store_true",
                   help="also run deliberately wrong translations of each reference code; passes only when "
                        "the unmutated run passes and every mutant fails (9 mutants for each reference code, on "
                        "the scenes given: reference_inputs/agreement/mutants.list is the project's set)")
    p.add_argument("--mutant", action="append", default=None, metavar="NAME",
                   help="run only this mutant (a name of the --mutants table, e.g. mu_disc_wall_x0.8 for every "
                        "reference code or liggghts_mu_disc_wall_x0.8 for one; repeatable; implies --mutants)")
    p.add_argument("--exhaustive", action="store_true",
                   help="with --mutants: run each mutant on every scene given, also after a physical metric has "
                        "caught it (by default a mutant stops at its first scene whose deterministic physical "
                        "metric disagrees: which scenes see which mutant)")
    p.add_argument("--timeout", type=float, default=900, help="seconds per reference run (default 900)")
    p.add_argument("--resume", action="store_true",
                   help="read back every run of OUT that finished (result.json ok) from byte-identical translated "
                        "inputs instead of running it again; failed, missing or changed runs run (a long study "
                        "stopped or timed out midway continues)")
    p.add_argument("--until-decided", action="store_true",
                   help="add members in batches (as many as the first) to every ensemble scene with an "
                        "inconclusive statistical metric until each agrees or disagrees, --max-members or --budget "
                        "(the level split over the planned looks; compare/verdict/sequential.py)")
    p.add_argument("--budget", type=float, default=60.0, metavar="MINUTES",
                   help="with --until-decided: no new look that would end after this many minutes (default 60)")
    p.add_argument("--max-members", type=int, default=0, metavar="N",
                   help=f"with --until-decided: members per code at most (default {sequential.DEFAULT_MAX_MEMBERS})")
    p.add_argument("--jobs", type=int, default=1,
                   help="ensemble members run at once (default 1; each member's codes run one after another, "
                        "every run single-threaded: up to one job a core)")


def main(argv=None) -> int:
    a = _parser().parse_args(argv)
    if a.cmd == "translate":
        return translate.main(a.check, a.out)
    codes = tuple(c.strip() for c in a.codes.split(",") if c.strip())
    bad = [c for c in codes if c not in CODES]
    if bad or not codes:
        print(f"--codes: unknown {bad}" if bad else "--codes: name native and any of liggghts,yade,lammps", file=sys.stderr)
        return 2
    codes = ("native",) + tuple(c for c in codes if c != "native")    # native, the reference, always runs
    if a.jobs < 1:
        print(f"--jobs: {a.jobs} is not a count of parallel members (give 1 or more)", file=sys.stderr)
        return 2
    if a.max_members < 0 or a.max_members == 1 or a.budget <= 0:
        print("--max-members: give 2 or more" if a.max_members < 0 or a.max_members == 1 else
              f"--budget: {a.budget:g} is not a number of minutes (give more than 0)", file=sys.stderr)
        return 2
    base = plan.Options(profile="full" if a.full else "quick", timeout=a.timeout, jobs=a.jobs,
                        resume=a.resume)
    if a.mutant:
        a.mutants = True
        try:
            mutants.mutations(codes, a.mutant)
        except ValueError as e:
            print(f"--mutant: {e}", file=sys.stderr)
            return 2
    try:
        if a.cmd == "report":
            entries = plan.read_list(plan.default_list(base.profile), base)
        else:
            base = plan.options_from(a, base)
            entries = []
            for s in a.scenes:
                if s.suffix == ".list":
                    entries += plan.read_list(s, base)
                elif not s.exists():
                    raise plan.PlanError(f"{s}: no such scene file")
                else:
                    entries.append(plan.Entry(s.resolve(), base, str(s)))
        if a.cmd == "scene" and a.set:
            fresh = not a.out.exists()
            try:
                entries = with_set(entries, a.set, a.out / "scenes_set")
            except plan.PlanError:
                if fresh:
                    shutil.rmtree(a.out, ignore_errors=True)
                raise
        plans = pipeline.plans_of(entries, codes)
    except plan.PlanError as e:
        print(f"dem compare: {e}", file=sys.stderr)
        return 2
    log = lambda m: print(m, flush=True)  # noqa: E731
    for old in a.out.glob("*.png") if a.out.is_dir() else ():   # no pictures of an earlier scene
        old.unlink()
    if a.until_decided:
        rep = sequential.run(plans, a.out, codes, log, a.budget, a.max_members or sequential.DEFAULT_MAX_MEMBERS)
    else:
        rep = pipeline.run(entries, a.out, codes, log=log, plans=plans)
    rep["profile"] = base.profile
    if any(p.options.native_law == "scene" for p in plans):
        rep["attribution"] = attribution.attribute(plans, rep, a.out, log)
    if a.mutants:
        rep["mutants"] = run_mutants(plans, rep, a.out, codes, log, a.mutant, a.exhaustive)
    report.write(rep, a.out)
    counts = {v: sum(m["verdict"] == v for m in rep["metrics"]) for v in verdict.ORDER}
    print(f"{a.out / 'report.md'}: {rep['verdict'].upper()} ({counts['agree']} agree, {counts['disagree']} disagree, "
          f"{counts['inconclusive']} inconclusive of {len(rep['metrics'])} metrics)"
          + (f"; mutants caught: {rep['mutants']['n_caught']} of {rep['mutants']['n_applicable']}" if a.mutants else ""))
    return exit_code(rep, a.mutants)


def exit_code(rep: dict, with_mutants: bool) -> int:
    """0 agree (with --mutants: and every mutant caught), 1 disagree (or a mutant that agrees: a
    blind spot), 3 inconclusive (or a mutant left undecided)."""
    if rep["verdict"] != verdict.AGREE or not with_mutants:
        return verdict.EXIT[rep["verdict"]]
    live = [r for r in rep["mutants"]["rows"] if r["applicable"] and not r["caught"]]
    if not live:
        return 0
    return 1 if any(r.get("verdict") == verdict.AGREE for r in live) else verdict.EXIT[verdict.INCONCLUSIVE]


def with_set(entries, assignments, folder: Path):
    """The entries with their scenes changed by ``--set`` (dem.compare.io.scene_toml), each written into
    folder/KK/ under its own name and validated by the engine (``dem resolve``); PlanError names
    the key or the field the engine refuses."""
    out = []
    for k, e in enumerate(entries):
        path = folder / f"{k:02d}" / e.scene.name
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            doc = scene_toml.rebase_paths(scene_toml.load(e.scene), e.scene.parent, path.parent)
            scene_toml.write(path, scene_toml.with_assignments(doc, assignments))
            common.resolve(path)
        except (KeyError, ValueError, common.CaseError) as err:
            shutil.rmtree(folder, ignore_errors=True)       # nothing half-written is left behind
            raise plan.PlanError(f"{e.label or e.scene}: --set: {_users_words(str(err), path)}") from None
        out.append(plan.Entry(path.resolve(), e.options, e.label))
    return out


def _users_words(msg: str, generated: Path) -> str:
    """The engine's message about the changed copy, said of the user's scene: without the copy's
    path and its line number (the user's file has neither)."""
    msg = msg.replace(f"dem: {generated}: ", "").replace(f"{generated}: ", "")
    return re.sub(r" \(line \d+\)", "", msg)


def run_mutants(plans, baseline: dict, out: Path, codes, log, names=None, exhaustive=False) -> dict:
    rows = []
    for mu in mutants.mutations(codes, names):
        on = mutant_plans(mu, plans)
        if not any(mu.applies(mu.code, plan.member_case(p, 0)) for p in on if mu.code in plan.codes_of(p, codes)):
            rows.append({"mutant": mu.name, "code": mu.code, "applicable": False, "caught": False,
                         "caught_physically": False, "metrics": []})
            log(f"mutant {mu.label}: changes nothing in these scenes (left out)")
            continue
        if len(on) < len(plans):
            log(f"mutant {mu.label}: a power check of {', '.join(mu.proves)}, run on the scenes that judge them: "
                + ", ".join(p.name for p in on))
        # A mutant caught by a deterministic physical metric needs no further scene (a power
        # check runs all of its scenes: it must disagree by each statistical kind it proves).
        stop = None if mu.proves or exhaustive else (lambda ms: mutants.physical_catch(baseline, ms))
        rep = pipeline.run([], out, codes, log=log, mutation=mu, plans=on,
                           looks=baseline.get("looks", {}).get("planned", 1), stop=stop)
        c = mutants.caught(baseline, rep, mu.proves)
        rows.append({"mutant": mu.name, "code": mu.code, "applicable": True, **c})
        log(f"mutant {mu.label}: {rep['verdict']}"
            + (f", caught by {', '.join(sorted({r['metric'] for r in c['metrics']}))}" if c["caught"] else ": NOT CAUGHT"))
    live = [r for r in rows if r["applicable"]]
    n = sum(r["caught"] for r in live)
    res = {"rows": rows, "n_caught": n, "n_applicable": len(live),
           "all_caught": bool(live) and n == len(live) and baseline["passed"]}
    (out / "mutants.json").write_text(json.dumps(res, indent=1, default=float))
    return res


def mutant_plans(mu, plans) -> list:
    """The plans a mutant runs on: a power-check mutant (one that must make statistical metrics
    of its kinds disagree) on the scenes that judge those kinds where there are any, since a
    deterministic scene catching it proves nothing about the statistics; any other on all."""
    power = [p for p in plans if mu.proves and plan.judges_any(p, mu.proves)]
    return power or list(plans)


if __name__ == "__main__":
    sys.exit(main())

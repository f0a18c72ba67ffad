"""The paper's job, timed: its parts for one or more checkouts, interleaved, with medians.

    /usr/bin/python3 benchmarks/paper_job.py --out out/paper_job [--repeats 3] \
        [--variant NAME REPO DEM ...] [--parts single,single_plots,single_pictures,static,discharge] \
        [--members 8]

Each variant is a checkout (REPO: its compare/ and scenes) and an engine binary (DEM); default:
this checkout and build/dem. Parts:

- ``single``:       `dem run reference_inputs/scenes/discharge_17_18.toml --out DIR --quiet`;
- ``single_plots``: that run, then `python3 -m dem.compare.figures run DIR` (its five pictures);
- ``single_pictures``: `dem run ... --quiet --pictures` (the run and the same pictures in one
  command: the picture process starts with the run);
- ``static``:       `python3 -m dem.compare.papers.paper_static --out DIR --dem DEM`;
- ``discharge``:    `python3 -m dem.compare.papers.paper_discharge --out DIR --dem DEM --members M`.

Repeat r runs every variant's part before repeat r + 1 (interleaved: a change of the machine's
load falls on all variants alike). Each run's wall time, CPU time (user + sys of the command and
every process it starts, figure processes whose parent has gone included: `perf stat -e
task-clock` when perf runs here, else the waited children's rusage) and the 1-minute load average
before it go to OUT/times.json; the table of medians is printed.
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PY = "/usr/bin/python3"


def has_perf():
    try:
        return subprocess.run(["perf", "stat", "-x,", "-e", "task-clock", "--", "true"],
                              capture_output=True).returncode == 0
    except OSError:
        return False


def timed(cmds, env, use_perf, cwd):
    """Runs the commands one after another in cwd (the variant's checkout: `python3 -m` puts the
    working folder first on sys.path); returns (wall s, cpu s) of them all."""
    wall = cpu = 0.0
    for cmd in cmds:
        before = os.times()
        t0 = time.perf_counter()
        if use_perf:
            p = subprocess.run(["perf", "stat", "-x,", "-e", "task-clock", "--", *cmd], env=env, cwd=cwd,
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        else:
            p = subprocess.run(cmd, env=env, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        wall += time.perf_counter() - t0
        if p.returncode != 0:
            sys.exit(f"paper_job: {' '.join(map(str, cmd))} exited {p.returncode}: {p.stderr[-400:]}")
        if use_perf:
            line = next(x for x in p.stderr.splitlines() if ",task-clock," in x)
            cpu += float(line.split(",")[0]) / 1000.0
        else:
            after = os.times()
            cpu += (after.children_user - before.children_user) + (after.children_system - before.children_system)
    return wall, cpu


def part_commands(part, repo, dem, out, members):
    scene = repo / "reference_inputs" / "scenes" / "discharge_17_18.toml"
    if part == "single":
        return [[dem, "run", scene, "--out", out, "--quiet"]]
    if part == "single_plots":
        return [[dem, "run", scene, "--out", out, "--quiet"], [PY, "-m", "dem.compare.figures", "run", out]]
    if part == "single_pictures":
        return [[dem, "run", scene, "--out", out, "--quiet", "--pictures"]]
    if part == "static":
        return [[PY, "-m", "dem.compare.papers.paper_static", "--out", out, "--dem", dem]]
    if part == "discharge":
        return [[PY, "-m", "dem.compare.papers.paper_discharge", "--out", out, "--dem", dem, "--members", str(members)]]
    raise SystemExit(f"paper_job: unknown part {part!r}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/paper_job")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--variant", nargs=3, action="append", metavar=("NAME", "REPO", "DEM"))
    ap.add_argument("--parts", default="single,single_plots,static,discharge")
    ap.add_argument("--members", type=int, default=8)
    args = ap.parse_args(argv)
    variants = args.variant or [["this", str(REPO), str(REPO / "build" / "dem")]]
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    use_perf = has_perf()
    rows = []
    for r in range(args.repeats):
        for part in args.parts.split(","):
            for name, repo, dem in variants:
                repo = Path(repo).resolve()
                run_out = out / "runs" / name / part
                shutil.rmtree(run_out, ignore_errors=True)
                env = dict(os.environ, PYTHONPATH=str(repo / "build" / "python"))
                load = os.getloadavg()[0]
                cmds = [[str(x) for x in c] for c in part_commands(part, repo, str(Path(dem).resolve()), run_out,
                                                                   args.members)]
                wall, cpu = timed(cmds, env, use_perf, repo)
                rows.append({"repeat": r, "part": part, "variant": name, "wall_s": wall, "cpu_s": cpu, "load1": load})
                print(f"[{r}] {part:13s} {name:8s} {wall:7.2f} s wall {cpu:7.2f} s cpu  load {load:.1f}", flush=True)
    (out / "times.json").write_text(json.dumps(rows, indent=1) + "\n")
    print(f"\nmedians over {args.repeats} interleaved repeats (cpu: {'perf task-clock' if use_perf else 'rusage'})")
    print("| part | variant | wall [s] | cpu [s] | wall range [s] | load (1 min) |\n|---|---|---|---|---|---|")
    for part in args.parts.split(","):
        for name, _, _ in variants:
            mine = [x for x in rows if x["part"] == part and x["variant"] == name]
            print(f"| {part} | {name} | {statistics.median(x['wall_s'] for x in mine):.2f} | "
                  f"{statistics.median(x['cpu_s'] for x in mine):.2f} | "
                  f"{min(x['wall_s'] for x in mine):.2f}-{max(x['wall_s'] for x in mine):.2f} | "
                  f"{min(x['load1'] for x in mine):.1f}-{max(x['load1'] for x in mine):.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())

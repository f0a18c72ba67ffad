"""Speed benchmark: particle-steps per second and peak memory of the native
engine, LIGGGHTS, LAMMPS and YADE on the same silo scenes, settling then discharging, in one run.

    /usr/bin/python3 benchmarks/speed.py --out out/speed            # all sizes (~30-40 min)
    /usr/bin/python3 benchmarks/speed.py --out out/speed --quick    # 350 and 10k discs (~5 min)

Method (benchmarks/README.md): every (scene, code, threads) run is a fresh process, repeated
--repeats times in an interleaved order (so slow drift of the machine hits all codes alike);
the table gives the median and the spread (min-max) of microseconds per particle-step, where a
particle-step is one disc advanced by one step and the time is the code's own stepping time
(native: summary.json wall_time_s, the step loop only; LIGGGHTS and LAMMPS: the "Loop time" of
each run (settling, discharge) minus its Output share; YADE: the time spent in O.run). Setup (reading the scene, building the lattice) and the
writing of final outputs are excluded for every code. Peak memory is the peak resident set size
of the run's process (for mpirun: the largest rank), measured by GNU time (/usr/bin/time, Debian
package `time`) around the run, reported as bytes per disc.

Scenes: the paper's 17/18 silo (350 discs, reference_inputs/scenes/discharge_17_18.toml) and the
scaled lattice silos bench_silo_{10k,100k,1m}.toml; each settles for S steps from its lattice and
then discharges through the opened slit for D steps (the same S and D for every code).
With --start settled the 10k, 100k and 1M scenes start instead from a packing at rest: before the
study (and untimed) the native engine runs the lattice scene with the paper's law and eq. (19) at
dt = 1e-4 s for SETTLE_TIME s (the lattice's gaps close and the column rests on the floor, some
two contacts a disc), and every code then starts from those positions, at rest, with no history.
The lattice start barely touches in the steps timed (a few thousand contacts at 1M discs); the
settled start is the dense packing a silo study spends its time in. --start shuffled is the
settled packing written as a file fill in a seeded random order (SHUFFLE_SEED): a user's file
in any order, the case of the engine's disc re-sort (benchmarks/README.md, "Disc order").

Physics: LIGGGHTS, LAMMPS (pair_style granular) and YADE run the law the codes share (compare/cases/common.py SHARED_VARIANT,
velocity Verlet) at dt = 5e-5 s (Verlet is unstable at the paper's 1e-4 s); the native engine runs
that same case (the comparison rows) and, as its own row, the paper's law with eq. (19) at 1e-4 s.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "build" / "python"))
sys.path.insert(0, str(ROOT / "benchmarks"))

import common_study  # noqa: E402
from dem.compare.io import scene_toml  # noqa: E402
from dem.compare.io.run_dir import RunDir  # noqa: E402

SCENES = ROOT / "reference_inputs" / "scenes"
DT_SHARED = 5e-5
DT_PAPER = 1e-4
# name: (scene file, settle steps, discharge steps at DT_SHARED, reference-code step scale)
SIZES = {
    "350": ("discharge_17_18.toml", 4000, 12000, 1.0),
    "10k": ("bench_silo_10k.toml", 1000, 2000, 1.0),
    "100k": ("bench_silo_100k.toml", 200, 400, 1.0),
    "1m": ("bench_silo_1m.toml", 40, 80, 0.5),
}


def without_tables(scene: Path, *names: str) -> list[str]:
    """Those of the tables ``names`` that the scene has (to remove before adding them anew)."""
    doc = scene_toml.load(scene)
    return [n for n in names if n in doc]


SETTLE_TIME = 0.25  # s: the lattice columns (up to 1667 rows) close their gaps and rest


def settled_scene(base: Path, dem: str, out: Path) -> Path:
    """The base lattice scene settled (untimed) by the native engine, as a scene that starts from the
    settled positions at rest (fill.type = "file"). Made once; kept under `out` for later studies."""
    scene = out / f"{base.stem}_settled.toml"
    packing = out / f"{base.stem}_settled" / "discs.csv"
    if scene.exists() and packing.exists():
        return scene
    settle = scene_toml.edit(base, None, out / f"{base.stem}_settle.toml", remove=without_tables(base, "discharge", "end"),
                             add={"end": {"time": SETTLE_TIME, "stop_at_rest": False}})
    t0 = time.monotonic()
    p = subprocess.run([dem, "run", str(settle), "--out", str(packing.parent), "--quiet", "--threads", str(os.cpu_count() or 1)], capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"settling {base.name} failed (dem exit {p.returncode}): {p.stderr.strip()[-300:]}")
    s = RunDir(packing.parent, strict=True).summary
    print(f"settled {base.name}: {s['n_discs']} discs, {SETTLE_TIME} s in {time.monotonic() - t0:.0f} s", flush=True)
    # The bottom of a tall column rests with overlaps of several per cent of a radius (its weight on kn).
    material = scene_toml.get(scene_toml.load(base), "fill.material")
    return scene_toml.edit(base, {"fill": {"type": "file", "file": f"{packing.parent.name}/discs.csv",
                                           "material": material, "max_initial_overlap": 0.3}}, scene)


SHUFFLE_SEED = 20240  # the shuffled start's order


def shuffled_scene(settled: Path, out: Path) -> Path:
    """The settled scene with its packing's rows in a seeded random order (the same discs)."""
    import random
    scene = out / f"{settled.stem}_shuffled.toml"
    packing = out / f"{settled.stem}_shuffled" / "discs.csv"
    if scene.exists() and packing.exists():
        return scene
    src = settled.parent / scene_toml.get(scene_toml.load(settled), "fill.file")
    lines = src.read_text().splitlines(keepends=True)
    rows = lines[1:]
    random.Random(SHUFFLE_SEED).shuffle(rows)
    packing.parent.mkdir(parents=True, exist_ok=True)
    packing.write_text(lines[0] + "".join(rows))
    fill = dict(scene_toml.get(scene_toml.load(settled), "fill"), file=f"{packing.parent.name}/discs.csv")
    return scene_toml.edit(settled, {"fill": fill}, scene)


def scene_with_phases(base: Path, settle_steps: int, discharge_steps: int, dt: float, out: Path) -> Path:
    """The base scene with [end] = settle for S steps and [discharge] = D steps (no snapshots)."""
    settle, dis = settle_steps * dt, discharge_steps * dt
    return scene_toml.edit(base, None, out, remove=without_tables(base, "discharge", "end"), add={
        "end": {"time": settle, "stop_at_rest": False},
        "discharge": {"time": dis, "gate": "gate", "outlet_depth": 4.0, "jam_time": dis + 1.0,
                      "series_interval": dis, "peak_window": dis, "snapshots": []}})


# ------------------------------------------------------------------ workers (one run each)

def _native(args) -> dict:
    scene = args.scene
    if args.scheme:  # the paper's law as the scene has it, at the paper's dt
        extra = ["--scheme", args.scheme, "--dt", repr(args.dt), "--force-dt"]
    else:  # the shared case, written exactly as the comparison layer writes it
        from dem.compare.codes import native_backend
        scene = str(native_backend.write_inputs(_case(args), Path(args.dir) / "case"))
        extra = []
    cmd = [args.dem, "run", scene, "--out", str(Path(args.dir) / "run"), "--quiet", "--threads", str(args.threads)] + extra
    p = subprocess.run(measured(args) + cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return {"error": f"dem exit {p.returncode}: {p.stderr.strip()[-300:]}"}
    s = RunDir(Path(args.dir) / "run", strict=True).summary
    return {"loop_s": s["wall_time_s"], "particle_steps": s["particle_steps"],
            "steps": s.get("steps"), "status": s["status"]}


def _case(args):
    from dem.compare.verdict import study
    c = study.discharge_case(Path(args.scene), DT_SHARED, args.settle * DT_SHARED, args.discharge * DT_SHARED, 0, 0.0)
    c.series_interval = args.discharge * DT_SHARED
    return c


def _reference(args, backend, log_name: str) -> dict:
    """A LIGGGHTS or LAMMPS run of the case (args.threads MPI ranks), timed by its own log."""
    case = _case(args)
    out = Path(args.dir)
    script = backend.write_inputs(case, out, args.threads)
    log = out / log_name
    with open(log, "w") as f:
        p = subprocess.run(measured(args) + backend.command(script, args.threads), cwd=out, stdout=f,
                           stderr=subprocess.STDOUT, env=dict(os.environ, OMP_NUM_THREADS="1"))
    text = log.read_text(errors="replace")
    t = common_study.loop_times(text, len(case.discs))
    if p.returncode != 0 or not t["runs"]:
        return {"error": f"{backend.__name__} exit {p.returncode}: " + " | ".join(text.strip().splitlines()[-3:])}
    return {"loop_s": t["loop_s"], "output_s": t["output_s"], "particle_steps": t["particle_steps"],
            "steps": t["steps"], "status": "ok"}


def _liggghts(args) -> dict:
    from dem.compare.codes import liggghts_backend
    return _reference(args, liggghts_backend, "liggghts.log")


def _lammps(args) -> dict:
    from dem.compare.codes import lammps_backend
    return _reference(args, lammps_backend, "lammps.log")


def _yade(args) -> dict:
    from dem.compare.codes import yade_backend as yb
    case = _case(args)
    res = yb.run(case, Path(args.dir), timeout=args.timeout, threads=args.threads, wrap=measured(args))
    if res.status != "ok":
        return {"error": res.reason}
    return {"loop_s": res.extra["loop_time_s"], "particle_steps": res.extra["particle_steps"],
            "steps": res.steps, "status": "ok"}


TIME = Path("/usr/bin/time")  # GNU time (Debian package `time`)


def measured(args) -> list[str]:
    """The prefix that measures the run's peak memory: GNU time, which waits for the run with
    wait4 and so reports the run's own peak (for mpirun, its largest rank). getrusage of this
    worker's children would not do: a child forked from this Python process counts the worker's
    own resident set (the case's discs, numpy) as its own until it execs the code."""
    return [str(TIME), "-f", "%M", "-o", str(Path(args.dir) / "peak_rss_kb")] if TIME.exists() else []


def worker(args) -> None:
    t0 = time.monotonic()
    fn = {"native": _native, "liggghts": _liggghts, "lammps": _lammps, "yade": _yade}[args.code]
    try:
        rec = fn(args)
    except Exception as e:  # noqa: BLE001 - reported as a failed point, never a crash of the study
        rec = {"error": repr(e)}
    rec["process_s"] = time.monotonic() - t0
    peak = Path(args.dir) / "peak_rss_kb"
    if peak.exists():  # time's last line (a failed command adds a line before it)
        rec["peak_rss_bytes"] = int(peak.read_text().split()[-1]) * 1024
        rec["peak_rss_source"] = "GNU time of the run"
    else:
        rec["peak_rss_bytes"] = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024
        rec["peak_rss_source"] = "getrusage of the worker's children (includes the worker's own size)"
    print(json.dumps(rec))


# ------------------------------------------------------------------ the study

# What a finished point keeps of its run directory: the records the study read and the inputs
# and logs that say how it ran. The rest (disc, contact and snapshot files, dumps, the case's copy
# of the packing) is some 0.5 GB a point at 1M discs, 17 GB for two studies; --keep-runs keeps it.
KEEP_SUFFIXES = {".json", ".log", ".toml", ".py", ".md"}
KEEP_NAMES = {"peak_rss_kb", "in.liggghts", "log.liggghts", "in.lammps"}


def prune_run(d: Path) -> int:
    """Deletes a finished point's bulky outputs under d (every file but those KEEP_* name, then the
    directories left empty); returns the bytes freed."""
    freed = 0
    for f in sorted(d.rglob("*"), reverse=True):  # files before their directories
        if f.is_file() and not f.is_symlink() and f.suffix not in KEEP_SUFFIXES and f.name not in KEEP_NAMES:
            freed += f.stat().st_size
            f.unlink()
        elif f.is_dir() and not any(f.iterdir()):
            f.rmdir()
    return freed


def run_point(code, scene, size, threads, rep, out, dem, scheme=None, dt=None, timeout=3600,
              keep_runs=False) -> dict:
    d = out / "runs" / f"{size}_{code}{'_' + scheme if scheme else ''}_t{threads}_r{rep}"
    d.mkdir(parents=True, exist_ok=True)
    file, settle, dis, scale = SIZES[size]
    if code != "native":
        settle, dis = max(1, int(settle * scale)), max(1, int(dis * scale))
    cmd = [sys.executable, __file__, "--worker", code, "--scene", str(scene), "--dir", str(d),
           "--threads", str(threads), "--dem", dem, "--settle", str(settle), "--discharge", str(dis),
           "--timeout", str(timeout)]
    if scheme:
        cmd += ["--scheme", scheme, "--dt", repr(dt)]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    try:
        rec = json.loads(p.stdout.strip().splitlines()[-1])
    except (IndexError, json.JSONDecodeError):
        rec = {"error": f"worker failed: {p.stderr.strip()[-400:]}"}
    rec.update(code=code, size=size, threads=threads, repeat=rep, scheme=scheme or "shared_verlet")
    if "loop_s" in rec and rec.get("particle_steps"):
        rec["us_per_ps"] = rec["loop_s"] / rec["particle_steps"] * 1e6
    if not keep_runs and "error" not in rec:  # a failed point keeps everything, to be looked at
        prune_run(d)
    return rec


def summarise(records, n_discs):
    rows = {}
    for r in records:
        key = (r["size"], r["code"], r["scheme"], r["threads"])
        rows.setdefault(key, []).append(r)
    table = []
    for (size, code, scheme, threads), rs in rows.items():
        ok = [r for r in rs if "us_per_ps" in r]
        us = [r["us_per_ps"] for r in ok]
        rss = [r["peak_rss_bytes"] for r in rs if "peak_rss_bytes" in r]
        table.append({"size": size, "code": code, "scheme": scheme, "threads": threads, "n": n_discs[size],
                      "runs": len(rs), "ok": len(ok),
                      "us_median": statistics.median(us) if us else None,
                      "us_min": min(us) if us else None, "us_max": max(us) if us else None,
                      "bytes_per_disc": max(rss) / n_discs[size] if rss else None,
                      "errors": sorted({r["error"][:200] for r in rs if "error" in r})})
    return table


def write_report(out, table, meta):
    def find(size, code, scheme, threads):
        for t in table:
            if (t["size"], t["code"], t["scheme"], t["threads"]) == (size, code, scheme, threads):
                return t
        return None

    L = ["# Speed benchmark: native engine, LIGGGHTS, LAMMPS, YADE", "",
         f"Machine: {meta['machine']}; {meta['cpus']} CPUs; LIGGGHTS {meta['liggghts']}, LAMMPS {meta.get('lammps', '-')}, "
         f"YADE {meta['yade']}, "
         f"dem {meta['dem_version']}. {meta['repeats']} repeats per point, interleaved; run "
         f"{meta['started']} ({meta['elapsed_s']:.0f} s).", "",
         ("Scenes start from packings settled before the study (--start settled): dense, about two contacts a disc."
          if meta.get("start") == "settled" else
          "Scenes start from packings settled before the study, listed in a seeded random order (--start shuffled)."
          if meta.get("start") == "shuffled" else
          "Scenes start from their lattices (--start lattice): in the steps timed they barely touch."), "",
         "Microseconds per particle-step (median, [min-max] over repeats) of the stepping alone; memory is the",
         "peak resident set of the process (the largest rank for mpirun) per disc. `shared` rows: the law all",
         f"codes share with velocity Verlet at dt = {DT_SHARED:g} s; `paper` row: native, the paper's law and eq. (19) at",
         f"dt = {DT_PAPER:g} s. Ratios are code / native (shared law, same thread count: 1 thread against serial",
         "LIGGGHTS / LAMMPS / YADE -j1, 2 threads against mpirun -np 2 / YADE -j2).", "",
         "| discs | code | law | threads | us / particle-step | spread | ratio to native | bytes / disc | runs ok |",
         "|---|---|---|---|---|---|---|---|---|"]
    for size in meta["sizes"]:
        for code, scheme in (("native", "paper_eq19"), ("native", "shared_verlet"), ("liggghts", "shared_verlet"),
                             ("lammps", "shared_verlet"), ("yade", "shared_verlet")):
            for th in (1, 2):
                t = find(size, code, scheme, th)
                if not t:
                    continue
                nat = find(size, "native", "shared_verlet", th)
                ratio = (t["us_median"] / nat["us_median"]) if (t["us_median"] and nat and nat["us_median"]) else None
                fmt = lambda v, f="{:.4g}": f.format(v) if v is not None else "-"
                L.append(f"| {t['n']} | {code} | {'paper' if scheme == 'paper_eq19' else 'shared'} | {th} | "
                         f"{fmt(t['us_median'])} | {fmt(t['us_min'])}-{fmt(t['us_max'])} | {fmt(ratio, '{:.1f}x')} | "
                         f"{fmt(t['bytes_per_disc'], '{:.0f}')} | {t['ok']}/{t['runs']} |")
    ceil = meta.get("ceiling")
    if ceil:
        L += ["", "## What 2 threads give on this machine", "",
              "The engine's 1 -> 2 thread speed-ups are to be read against what this machine gives for loops with no",
              "engine in them (benchmarks/ceiling.cpp, run before the study: 1 and 2 threads, each its own half,",
              f"{ceil['rounds']} interleaved rounds, ratio of the medians):", ""]
        for key, what in (("compute", "dependent square roots, no memory traffic"),
                          ("stream_10k", "the kick-drift loop on 10k discs' arrays (1.2 MB, in the caches)"),
                          ("stream_30k", "the same on 30k discs' arrays (3.6 MB)"),
                          ("stream_100k", "the same on 100k discs' arrays (12 MB)"),
                          ("stream_1m", "the same on 1M discs' arrays (120 MB, from memory)")):
            if key in ceil:
                c = ceil[key]
                L.append(f"- {what}: {c['speedup']:.2f}x (1 thread {c['t1_s'] * 1e6:.4g} us, 2 threads {c['t2_s'] * 1e6:.4g} us)")
    sources = sorted({r.get("peak_rss_source") for r in meta.get("records", []) if r.get("peak_rss_source")})
    if any("getrusage" in x for x in sources):
        L += ["", "Memory: /usr/bin/time was missing, so some rows come from getrusage of the worker's children,",
              "which includes the Python worker's own size (apt-get install time)."]
    L += ["", "## Targets", ""]
    for size in meta["sizes"]:
        n1, n2 = find(size, "native", "shared_verlet", 1), find(size, "native", "shared_verlet", 2)
        lg = find(size, "liggghts", "shared_verlet", 1)
        if n1 and lg and n1["us_median"] and lg["us_median"]:
            L.append(f"- {n1['n']} discs: native is {lg['us_median'] / n1['us_median']:.1f}x faster than serial LIGGGHTS "
                     f"per particle-step (target >= 10x).")
        if n1 and n2 and n1["us_median"] and n2["us_median"]:
            row = (ceil or {}).get({"10k": "stream_10k", "100k": "stream_100k", "1m": "stream_1m"}.get(size, ""))
            beside = f"; this machine, the kick-drift loop at that size: {row['speedup']:.2f}x" if row else ""
            L.append(f"- {n1['n']} discs: 1 -> 2 threads speed-up {n1['us_median'] / n2['us_median']:.2f}x "
                     f"(target >= 1.8x{beside}).")
    # Memory at 1M for both native rows: the comparison scene (shared law, Verlet) and the paper's
    # scheme, whose eq. (19) keeps the last increments (24 B a disc more).
    for scheme, what in (("shared_verlet", "shared law, velocity Verlet"), ("paper_eq19", "paper's law, eq. 19")):
        big = find("1m", "native", scheme, 1)
        if big and big["bytes_per_disc"]:
            L.append(f"- 1M discs, {what}: native peak memory {big['bytes_per_disc']:.0f} bytes per disc "
                     f"(target <= 200).")
    errs = [(t["size"], t["code"], t["threads"], e) for t in table for e in t["errors"]]
    if errs:
        L += ["", "## Failed runs", ""] + [f"- {s} {c} {th} threads: {e}" for s, c, th, e in errs]
    (out / "report.md").write_text("\n".join(L) + "\n")


def machine_ceiling(program: str) -> dict | None:
    """What 2 threads give on this machine with no engine in the loop (benchmarks/ceiling.cpp)."""
    try:
        p = subprocess.run([program], capture_output=True, text=True, timeout=600)
        return json.loads(p.stdout) if p.returncode == 0 else None
    except (OSError, json.JSONDecodeError, subprocess.TimeoutExpired):
        print(f"no ceiling measurement ({program}: build it with cmake --build build --target dem_ceiling)",
              file=sys.stderr)
        return None


def version_of(cmd) -> str:
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
        return (p.stdout + p.stderr).strip().splitlines()[0][:80]
    except (OSError, IndexError, subprocess.TimeoutExpired):
        return "unavailable"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/speed")
    ap.add_argument("--sizes", default="350,10k,100k,1m")
    ap.add_argument("--codes", default="native,liggghts,lammps,yade")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="350 and 10k discs only")
    ap.add_argument("--start", choices=("lattice", "settled", "shuffled"), default="lattice",
                    help="10k-1M scenes: from the lattice (default), from a packing settled before the study, "
                         "or from that packing listed in a seeded random order")
    ap.add_argument("--dem", default=os.environ.get("DEM_BINARY", str(ROOT / "build" / "dem")))
    ap.add_argument("--timeout", type=float, default=3600)
    ap.add_argument("--keep-runs", action="store_true",
                    help="keep each point's full outputs (by default only its records, inputs and logs)")
    ap.add_argument("--ceiling", default=str(ROOT / "build" / "benchmarks" / "dem_ceiling"),
                    help="the machine's 1 -> 2 thread ceiling program (benchmarks/ceiling.cpp)")
    # worker mode (internal)
    ap.add_argument("--worker")
    ap.add_argument("--scene")
    ap.add_argument("--dir")
    ap.add_argument("--scheme")
    ap.add_argument("--dt", type=float)
    ap.add_argument("--settle", type=int)
    ap.add_argument("--discharge", type=int)
    args = ap.parse_args()
    if args.worker:
        args.code = args.worker
        args.threads = int(args.threads)
        worker(args)
        return 0

    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    sizes = ["350", "10k"] if args.quick else args.sizes.split(",")
    codes = args.codes.split(",")
    threads = [int(t) for t in args.threads.split(",")]
    os.environ["DEM_BINARY"] = args.dem
    t0 = time.monotonic()
    ceiling = machine_ceiling(args.ceiling)
    scenes, n_discs, bases = {}, {}, {}
    for size in sizes:
        file, settle, dis, _ = SIZES[size]
        bases[size] = SCENES / file
        if args.start in ("settled", "shuffled") and size != "350":  # the 350-disc silo settles within its own run
            bases[size] = settled_scene(SCENES / file, args.dem, out)
            if args.start == "shuffled":
                bases[size] = shuffled_scene(bases[size], out)
        scenes[size] = scene_with_phases(bases[size], settle, dis, DT_SHARED, out / f"bench_{size}.toml")
        r = subprocess.run([args.dem, "resolve", str(scenes[size])], capture_output=True, text=True)
        if r.returncode != 0:
            print(r.stderr, file=sys.stderr)
            return 2
        n_discs[size] = len(json.loads(r.stdout)["discs"])
    points = []
    for size in sizes:
        _, settle, dis, _ = SIZES[size]
        for th in threads:
            if "native" in codes:
                points.append(("native", size, th, None, None))
                # the paper's law at its own dt: half the steps cover the same simulated time
                points.append(("native", size, th, "paper_eq19", DT_PAPER))
            for code in ("liggghts", "lammps", "yade"):
                if code in codes:
                    points.append((code, size, th, None, None))
    records = []
    for rep in range(args.repeats):
        for code, size, th, scheme, dt in points:
            scene = scenes[size]
            if scheme == "paper_eq19":  # same simulated times at the paper's dt (contact law: the scene's, the paper's)
                _, settle, dis, _ = SIZES[size]
                scene = out / f"bench_{size}_paper.toml"
                if not scene.exists():
                    scene_with_phases(bases[size], settle // 2, dis // 2, DT_PAPER, scene)
            rec = run_point(code, scene, size, th, rep, out, args.dem, scheme, dt, args.timeout, args.keep_runs)
            records.append(rec)
            print(f"[{time.monotonic() - t0:7.0f} s] {size:>5} {code:9} {rec['scheme']:14} t{th} r{rep}: "
                  f"{rec.get('us_per_ps', float('nan')):.4g} us/ps, {rec.get('peak_rss_bytes', 0) / 2**20:.0f} MiB"
                  f"{'  ERROR ' + rec['error'][:160] if 'error' in rec else ''}", flush=True)
            (out / "records.json").write_text(json.dumps(records, indent=1))
    table = summarise(records, n_discs)
    meta = {"machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
            "liggghts": version_of(["liggghts", "-h"]) if "liggghts" in codes else "-",
            "yade": version_of(["yade", "--version"]) if "yade" in codes else "-",
            "lammps": version_of(["lmp", "-h"]) if "lammps" in codes else "-",
            "dem_version": "git " + version_of(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"]), "repeats": args.repeats, "sizes": sizes,
            "started": time.strftime("%Y-%m-%d %H:%M"), "start": args.start, "elapsed_s": time.monotonic() - t0, "ceiling": ceiling}
    (out / "results.json").write_text(json.dumps({"meta": meta, "table": table, "records": records}, indent=1))
    write_report(out, table, dict(meta, records=records))
    print((out / "report.md").read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())

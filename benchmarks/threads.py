"""Threads on a quiet machine and beside a busy neighbour: the settled shared-law silos of the speed
study (benchmarks/speed.py --start settled) run with one thread and with two under several ways
of waiting at a barrier, alone and with a busy loop pinned to one core.

    /usr/bin/python3 benchmarks/threads.py --out out/threads                      # 10k and 100k, 3 repeats
    /usr/bin/python3 benchmarks/threads.py --out out/threads --sizes 10k --repeats 5 \
        --settings 1,2,2:spin=100,2:spin=300000,2:fixed

Settings: `1` one thread; `2` two threads as `dem run` runs them by default; `2:spin=N` two threads
with GOMP_SPINCOUNT=N (libgomp's own default is 300000, a few milliseconds); `2:passive`
OMP_WAIT_POLICY=passive; `2:fixed` two threads with the engine's thread choice off
(`--set integrator.thread_choice=off`). Conditions: `quiet` (whatever else the machine runs) and
`busy` (the same plus `taskset -c 0` busy loop, started before and stopped after each run).
Each point is a fresh `dem run --quiet`, the points interleaved (condition by condition, size by
size, setting by setting, then again); loop seconds are summary.json's wall_time_s; a run past
--limit seconds is stopped and counted at the limit (">"). The table gives the median [min-max]
and each setting's median against one thread's in the same condition.

--boost N (root) gives the study's processes, the busy loop included, autogroup niceness N: other
users' jobs then take little of the cores, and the busy loop still takes its core's half.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "build" / "python"))
sys.path.insert(0, str(ROOT / "benchmarks"))

import common_study  # noqa: E402
import speed  # noqa: E402

DEFAULT_SETTINGS = "1,2,2:spin=100,2:spin=300000,2:fixed"


def environment(setting: str) -> tuple[int, dict, list[str]]:
    """Threads, the environment and the extra dem arguments of a setting."""
    env = {k: v for k, v in os.environ.items() if k not in ("GOMP_SPINCOUNT", "OMP_WAIT_POLICY")}
    threads, _, how = setting.partition(":")
    extra: list[str] = []
    if how.startswith("spin="):
        env["GOMP_SPINCOUNT"] = how.split("=", 1)[1]
    elif how == "passive":
        env["OMP_WAIT_POLICY"] = "passive"
    elif how == "fixed":
        extra = ["--set", "integrator.thread_choice=off"]
    elif how:
        raise SystemExit(f"--settings: unknown way of waiting {how!r} in {setting!r}")
    return int(threads), env, extra


def run_point(dem: str, scene: Path, out: Path, setting: str, limit: float, boost: int | None) -> dict:
    threads, env, extra = environment(setting)
    cmd = [dem, "run", str(scene), "--out", str(out), "--quiet", "--threads", str(threads), *extra]
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if boost is not None:
        common_study.set_autogroup_nice(p.pid, boost)
    try:
        _, err = p.communicate(timeout=limit)
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        return {"loop_s": limit, "stopped": True}
    if p.returncode != 0:
        raise RuntimeError(f"dem exit {p.returncode}: {err.strip()[-300:]}")
    s = json.loads((out / "summary.json").read_text())
    return {"loop_s": s["wall_time_s"], "stopped": False, "threads_used": s.get("threads_used")}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/threads")
    ap.add_argument("--sizes", default="10k,100k")
    ap.add_argument("--settings", default=DEFAULT_SETTINGS)
    ap.add_argument("--conditions", default="quiet,busy")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--limit", type=float, default=60.0, help="seconds after which a run is stopped")
    ap.add_argument("--scale", type=int, default=1, help="runs K times the speed study's steps (longer runs)")
    ap.add_argument("--boost", type=int, help="autogroup niceness of the study's processes (root)")
    ap.add_argument("--dem", default=os.environ.get("DEM_BINARY", str(ROOT / "build" / "dem")))
    args = ap.parse_args()
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    if args.boost is not None:
        common_study.set_autogroup_nice(os.getpid(), args.boost)
    sizes, settings, conditions = args.sizes.split(","), args.settings.split(","), args.conditions.split(",")
    for s in settings:
        environment(s)  # bad settings fail before any run
    scenes = {}
    for size in sizes:  # the speed study's settled shared-law case, written as the comparison layer writes it
        _, settle, dis, _ = speed.SIZES[size]
        settle, dis = settle * args.scale, dis * args.scale
        settled = speed.settled_scene(speed.SCENES / speed.SIZES[size][0], args.dem, out)
        phases = speed.scene_with_phases(settled, settle, dis, speed.DT_SHARED, out / f"bench_{size}.toml")
        from dem.compare.codes import native_backend
        ns = argparse.Namespace(scene=str(phases), settle=settle, discharge=dis)
        scenes[size] = native_backend.write_inputs(speed._case(ns), out / f"case_{size}")
    records = []
    t0 = time.monotonic()
    for rep in range(args.repeats):
        for cond in conditions:
            for size in sizes:
                for setting in settings:
                    hog = None
                    if cond == "busy":
                        hog = subprocess.Popen(["taskset", "-c", "0", "sh", "-c", "while :; do :; done"])
                        if args.boost is not None:
                            common_study.set_autogroup_nice(hog.pid, args.boost)
                        time.sleep(0.2)
                    try:
                        rec = run_point(args.dem, scenes[size], out / "runs" / f"{cond}_{size}_{setting.replace(':', '_').replace('=', '')}_r{rep}",
                                        setting, args.limit, args.boost)
                    finally:
                        if hog:
                            hog.kill()
                            hog.wait()
                    load = os.getloadavg()[0]
                    rec.update(condition=cond, size=size, setting=setting, repeat=rep, load=load)
                    records.append(rec)
                    print(f"[{time.monotonic() - t0:6.0f} s] {cond:5} {size:>5} {setting:14} r{rep}: "
                          f"{'>' if rec['stopped'] else ''}{rec['loop_s']:.3f} s  (load {load:.1f})", flush=True)
                    (out / "records.json").write_text(json.dumps(records, indent=1))
    lines = [f"# Threads: loop seconds, median [min-max] of {args.repeats}; in brackets against 1 thread", "",
             "| discs | condition | " + " | ".join(settings) + " |", "|---|---|" + "---|" * len(settings)]
    for cond in conditions:
        for size in sizes:
            cells, base = [], None
            for setting in settings:
                v = [r["loop_s"] for r in records if (r["condition"], r["size"], r["setting"]) == (cond, size, setting)]
                stopped = any(r["stopped"] for r in records if (r["condition"], r["size"], r["setting"]) == (cond, size, setting))
                med = statistics.median(v)
                if setting == "1":
                    base = med
                rel = f" ({med / base:.2f}x)" if base else ""
                cells.append(f"{med:.3f} [{min(v):.3f}-{'>' if stopped else ''}{max(v):.3f}]{rel}")
            lines.append(f"| {size} | {cond} | " + " | ".join(cells) + " |")
    loads = [r["load"] for r in records]
    lines += ["", f"Load average (1 min) during the study: {min(loads):.1f}-{max(loads):.1f}."]
    (out / "report.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())

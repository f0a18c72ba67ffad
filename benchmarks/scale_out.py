#!/usr/bin/python3
"""Scale-out study: one settled silo of about 1M discs through ``dem run --engine liggghts`` and
``--engine lammps`` under ``mpirun -np N``, beside the native engine on the same case.

    /usr/bin/python3 benchmarks/scale_out.py --out out/scale_out [--size 1m] [--steps 500]
        [--configs native:1,native:2,liggghts:1,liggghts:2,liggghts:4,lammps:1,lammps:2,lammps:4]

Method (the report this writes, DIR/report.md, repeats it):

- The case: ``bench_silo_SIZE.toml`` settled by the native engine (benchmarks/speed.py's settled
  packing, made once under DIR), at rest, no contact history, run for ``--steps`` steps of the
  shared law (compare/cases/common.py SHARED_VARIANT) at dt = 5e-5 s. The reference codes get it from
  ``dem run SCENE --engine CODE --np N``: the user's command. The native engine runs the very case
  the translation runs, written by compare/codes/native_backend.py.
- Time: each code's own loop time (native: summary.json ``wall_time_s``; LIGGGHTS and LAMMPS: the
  sum of their "Loop time" lines less the Output row of the timing breakdown), divided by the
  particle-steps (steps x discs): microseconds per particle-step; x ranks: per rank. The whole
  command's wall time (translation, reading the data file, writing the outputs) is given beside.
- Memory: each rank's peak resident set (VmHWM of /proc/PID/status), sampled every 0.2 s for every
  process of the code while the run lasts; the largest rank. Divided by the discs a rank holds
  (n / ranks): bytes per disc per rank. Native: GNU time's peak of the one process.
- Outputs: each run's wall totals (summary.json: every wall group's normal and shear force) against
  the native 1-thread run of the same case, relative, with the comparison's static tolerances
  (compare/verdict/pipeline.py TOL_STATIC_TOTAL for normal totals, TOL_STATIC_SHEAR for side friction).
- The 10^7 estimate: time per step on R ranks = 10^7 x (per-rank microseconds per particle-step
  at the most ranks run without oversubscription) / R, assuming that per-rank throughput holds
  (the decomposition's halo grows as the strips thin: stated beside the estimate); memory per rank
  = the fixed part + b x 10^7 / R, b and the fixed part from the 1- and 2-rank peaks.

Each configuration runs ``--repeats`` times, interleaved (all configurations, then again).
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "build" / "python"))
sys.path.insert(0, str(ROOT / "benchmarks"))

import common_study  # noqa: E402
from dem.compare.io import scene_toml  # noqa: E402
from dem.compare.io.run_dir import RunDir  # noqa: E402

DT = 5e-5
PROCESS_NAMES = {"liggghts": ("liggghts",), "lammps": ("lmp",)}
TIME = Path("/usr/bin/time")


def study_scene(size: str, dem: str, out: Path, steps: int) -> Path:
    """The settled silo as a static scene of ``steps`` steps at DT (no discharge)."""
    import speed
    settled = speed.settled_scene(speed.SCENES / f"bench_silo_{size}.toml", dem, out)
    return scene_toml.edit(settled, {"integrator": {"scheme": "velocity_verlet", "dt": DT, "force_dt": False}},
                           out / f"scale_{size}.toml", remove=speed.without_tables(settled, "discharge", "end"),
                           add={"end": {"time": steps * DT, "stop_at_rest": False}})


def _descends_from(pid: str, root: int) -> bool:
    """Whether process pid has root among its ancestors (other users' runs of the code are not ours)."""
    for _ in range(16):
        try:
            ppid = int(re.search(r"^PPid:\s+(\d+)", Path(f"/proc/{pid}/status").read_text(), re.M).group(1))
        except (OSError, AttributeError):
            return False
        if ppid == root:
            return True
        if ppid <= 1:
            return False
        pid = str(ppid)
    return False


BOOST = None   # --boost: the autogroup niceness given to every process of a run


def boost(pid: str) -> None:
    """Gives process pid's autogroup the niceness BOOST (common_study.set_autogroup_nice)."""
    if BOOST is not None:
        common_study.set_autogroup_nice(pid, BOOST)


class PeakSampler(threading.Thread):
    """Largest VmHWM (kB) of the processes named ``names`` below process ``root``, sampled while
    running (and, with --boost, every process below root boosted)."""

    def __init__(self, names, root: int):
        super().__init__(daemon=True)
        self.names, self.root, self.peaks, self.stop = set(names), root, {}, threading.Event()

    def run(self):
        while not self.stop.is_set():
            for d in Path("/proc").iterdir():
                if not d.name.isdigit():
                    continue
                try:
                    text = (d / "status").read_text()
                except OSError:
                    continue
                name = text.split("\n", 1)[0].split(":", 1)[1].strip()
                mine = _descends_from(d.name, self.root)
                if mine:
                    boost(d.name)
                if name in self.names and mine:
                    m = re.search(r"^VmHWM:\s+(\d+) kB", text, re.M)
                    if m:
                        self.peaks[d.name] = max(self.peaks.get(d.name, 0), int(m.group(1)))
            time.sleep(0.2)


def loop_seconds(log: Path) -> tuple[float, float]:
    """(loop time less output, output) summed over a LIGGGHTS/LAMMPS log's runs."""
    t = common_study.loop_times(log.read_text(errors="replace"))
    return t["loop_s"], t["output_s"]


def run_reference(code: str, ranks: int, scene: Path, d: Path, dem: str) -> dict:
    t0 = time.monotonic()
    p = subprocess.Popen([dem, "run", str(scene), "--engine", code, "--np", str(ranks), "--out", str(d), "--quiet"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=dict(os.environ, OMP_NUM_THREADS="1"))
    sampler = PeakSampler(PROCESS_NAMES[code], p.pid)
    sampler.start()
    _, err = p.communicate()
    wall = time.monotonic() - t0
    sampler.stop.set()
    sampler.join()
    if p.returncode != 0:
        return {"error": f"exit {p.returncode}: {err.strip()[-400:]}"}
    s = json.loads((d / "summary.json").read_text())
    log = next(iter(sorted((d / code).glob("*.log"))), None)
    loop, output = loop_seconds(log) if log else (float("nan"), float("nan"))
    peaks = sorted(sampler.peaks.values())[-ranks:]   # the ranks (a short version query also runs the program)
    return {"loop_s": loop, "output_s": output, "command_s": wall, "steps": s["steps"], "n_discs": s["n_discs"],
            "ranks": ranks, "rank_peaks_kb": peaks, "peak_rank_bytes": (peaks[-1] * 1024) if peaks else None,
            "walls": wall_totals(s)}


def run_native(threads: int, scene: Path, d: Path, dem: str) -> dict:
    from dem.compare.codes import reference_run as engine_run, native_backend
    case = engine_run.make_case(scene, 0.0)
    nscene = native_backend.write_inputs(case, d / "case")
    t0 = time.monotonic()
    cmd = [dem, "run", str(nscene), "--out", str(d / "run"), "--quiet", "--threads", str(threads)]
    pre = [str(TIME), "-f", "%M", "-o", str(d / "peak_rss_kb")] if TIME.exists() else []
    p = subprocess.run(pre + cmd, capture_output=True, text=True)
    wall = time.monotonic() - t0
    if p.returncode != 0:
        return {"error": f"dem exit {p.returncode}: {p.stderr.strip()[-400:]}"}
    s = RunDir(d / "run", strict=True).summary
    peak = int((d / "peak_rss_kb").read_text().split()[-1]) * 1024 if (d / "peak_rss_kb").exists() else None
    return {"loop_s": s["wall_time_s"], "command_s": wall, "steps": s["steps"], "n_discs": s["n_discs"],
            "ranks": 1, "threads": threads, "peak_rank_bytes": peak, "walls": wall_totals(s)}


def wall_totals(summary: dict) -> dict:
    """group -> {"normal": sum, "shear": sum} over the walls of each group."""
    out = {}
    for w in summary["walls"]:
        g = out.setdefault(w["group"], {"normal": 0.0, "shear": 0.0})
        g["normal"] += float(w["normal_total"])
        g["shear"] += float(w["shear_total"])
    return out


def prune(d: Path) -> None:
    """Keep a finished point's summary, logs and scripts; the disc files and dumps go (GBs at 1M)."""
    for f in d.rglob("*"):
        if f.is_file() and f.suffix not in (".json", ".log", ".toml", ".py", ".md") and f.name not in (
                "peak_rss_kb", "in.liggghts", "in.lammps"):
            f.unlink()


def median(xs):
    xs = sorted(xs)
    n = len(xs)
    return xs[n // 2] if n % 2 else 0.5 * (xs[n // 2 - 1] + xs[n // 2])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--size", default="1m", choices=("10k", "100k", "1m"))
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--configs", default="native:1,native:2,liggghts:1,liggghts:2,liggghts:4,lammps:1,lammps:2,lammps:4")
    ap.add_argument("--boost", type=int, default=None, metavar="NICE",
                    help="root: set the autogroup niceness of the study and of every run's processes to NICE "
                         "(e.g. -19) so that other sessions' jobs on the machine take little of its cores")
    ap.add_argument("--dem", default=os.environ.get("DEM_BINARY") or str(ROOT / "build" / "dem"))
    a = ap.parse_args()
    global BOOST
    BOOST = a.boost
    boost(str(os.getpid()))
    dem = str(Path(a.dem).resolve())
    os.environ["DEM_BINARY"] = dem
    configs = [(c.split(":")[0], int(c.split(":")[1])) for c in a.configs.split(",")]
    a.out.mkdir(parents=True, exist_ok=True)
    scene = study_scene(a.size, dem, a.out, a.steps)
    records = []
    for rep in range(a.repeats):
        for code, n in configs:
            d = a.out / "runs" / f"{code}_{n}_r{rep}"
            if d.exists():
                shutil.rmtree(d)
            d.mkdir(parents=True)
            load = os.getloadavg()[0]
            rec = run_native(n, scene, d, dem) if code == "native" else run_reference(code, n, scene, d, dem)
            rec.update({"code": code, "n": n, "repeat": rep, "load_before": load, "load_after": os.getloadavg()[0]})
            if "error" not in rec:
                rec["us_per_particle_step"] = 1e6 * rec["loop_s"] / (rec["steps"] * rec["n_discs"])
                prune(d)
            print(json.dumps({k: v for k, v in rec.items() if k != "walls"}), flush=True)
            records.append(rec)
    (a.out / "results.json").write_text(json.dumps({"size": a.size, "steps": a.steps, "dt": DT, "scene": str(scene),
                                                    "records": records}, indent=1))
    write_report(a.out, records, a)
    return 0 if all("error" not in r for r in records) else 1


def write_report(out: Path, records: list, a) -> None:
    from dem.compare.verdict.pipeline import TOL_STATIC_SHEAR, TOL_STATIC_TOTAL
    ok = [r for r in records if "error" not in r]
    ref = [r for r in ok if r["code"] == "native" and r["n"] == 1]
    base = ref[0]["walls"] if ref else None
    rows = []
    by = {}
    for r in ok:
        by.setdefault((r["code"], r["n"]), []).append(r)
    lines = [f"# Scale-out study: {a.size} settled silo, {a.steps} steps of the shared law at dt {DT} s", "",
             "Command: `/usr/bin/python3 benchmarks/scale_out.py " + " ".join(sys.argv[1:]) + "`", "",
             "| code | ranks (threads) | us / particle-step, median [range] | per rank | command s | peak B / disc / rank | "
             "largest wall-total diff vs native (normal; shear) | within static tolerance | load |",
             "|---|---|---|---|---|---|---|---|---|"]
    for (code, n), rs in by.items():
        us = [r["us_per_particle_step"] for r in rs]
        ranks = rs[0]["ranks"]
        nd = rs[0]["n_discs"]
        peak = max((r["peak_rank_bytes"] or 0) for r in rs)
        bpd = peak / (nd / ranks) if peak else float("nan")
        dn = ds = float("nan")
        if base:
            dn = max(abs(rs[0]["walls"][g]["normal"] - base[g]["normal"]) / abs(base[g]["normal"])
                     for g in base if abs(base[g]["normal"]) > 0)
            sides = [g for g in base if g.startswith("side") and abs(base[g]["shear"]) > 0]
            ds = max((abs(rs[0]["walls"][g]["shear"] - base[g]["shear"]) / abs(base[g]["shear"]) for g in sides),
                     default=float("nan"))
        within = dn <= TOL_STATIC_TOTAL and (ds != ds or ds <= TOL_STATIC_SHEAR)
        rows.append({"code": code, "n": n, "us": median(us), "us_rank": median(us) * ranks, "bytes_per_disc_rank": bpd,
                     "diff_normal": dn, "diff_shear": ds, "within": within})
        lines.append(f"| {code} | {ranks if code != 'native' else f'1 ({n})'} | {median(us):.4g} [{min(us):.4g}-{max(us):.4g}] | "
                     f"{median(us) * ranks:.4g} | {median([r['command_s'] for r in rs]):.0f} | {bpd:.0f} | "
                     f"{dn:.2e}; {ds:.2e} | {'yes' if within else '**no**'} | "
                     f"{rs[0]['load_before']:.1f}-{rs[0]['load_after']:.1f} |")
    lines += ["", f"Tolerances: normal totals {TOL_STATIC_TOTAL:g}, side friction {TOL_STATIC_SHEAR:g} (relative).", ""]
    lines += estimate(by, rows)
    (out / "report.md").write_text("\n".join(lines) + "\n")
    (out / "table.json").write_text(json.dumps(rows, indent=1))
    print("\n".join(lines))


def estimate(by: dict, rows: list, cores: int | None = None) -> list:
    """The 10^7-disc estimate on 16 and 64 ranks from each MPI code's measured ranks."""
    out = ["## 10^7 discs on 16 and 64 ranks (estimate)", ""]
    for code in ("liggghts", "lammps"):
        pts = sorted((n, rs) for (c, n), rs in by.items() if c == code and n <= (cores or os.cpu_count() or 1))
        if not pts:
            continue
        n_top, rs_top = pts[-1]
        us_rank = median([r["us_per_particle_step"] for r in rs_top]) * n_top
        mem = [(n, max(r["peak_rank_bytes"] or 0 for r in rs), rs[0]["n_discs"]) for n, rs in pts]
        if len(mem) >= 2:
            (n1, p1, nd), (n2, p2, _) = mem[0], mem[-1]
            b = (p1 - p2) / (nd / n1 - nd / n2)
            fixed = p1 - b * nd / n1
        else:
            b, fixed = mem[0][1] / (mem[0][2] / mem[0][0]), 0.0
        out.append(f"- {code}: {us_rank:.3g} us per particle-step per rank at {n_top} ranks; memory per rank "
                   f"{fixed / 2**20:.0f} MiB + {b:.0f} B a disc.")
        for R in (16, 64):
            t = 1e7 * us_rank * 1e-6 / R
            m = fixed + b * 1e7 / R
            out.append(f"  - {R} ranks: {t:.3g} s a step ({3600 / t:.3g} steps an hour), {m / 2**30:.2f} GiB a rank")
    out += ["", "The estimate keeps the measured per-rank throughput: it holds while each rank's share stays "
            "large against its halo (10^7 / 64 = 156k discs a rank, strips of hundreds of disc diameters), and "
            "ignores the network (2 ranks here share one machine's memory)."]
    return out


if __name__ == "__main__":
    sys.exit(main())

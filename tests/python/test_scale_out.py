"""benchmarks/scale_out.py's readings: loop time from a LIGGGHTS/LAMMPS log, the processes of a
run (not other users' runs of the same program), the memory fit and the 10^7 estimate."""
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
import scale_out  # noqa: E402

LOG = """Setting up run ...
Loop time of 12.5 on 2 procs for 400 steps with 1000 atoms

Section |  min time  |  avg time  |  max time  |%varavg| %total
Pair    | 8.0        | 8.1        | 8.2        |   0.1 | 64.80
Output  | 0.40       | 0.50       | 0.60       |   0.0 |  4.00
Loop time of 7.5 on 2 procs for 100 steps with 998 atoms
Output  | 0.20       | 0.25       | 0.30       |   0.0 |  3.33
"""


def test_loop_time_sums_the_runs_less_their_average_output(tmp_path):
    f = tmp_path / "x.log"
    f.write_text(LOG)
    loop, out = scale_out.loop_seconds(f)
    assert abs(out - 0.75) < 1e-12 and abs(loop - (12.5 + 7.5 - 0.75)) < 1e-12


def test_only_the_runs_own_processes_are_sampled():
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(5)"])
    try:
        time.sleep(0.2)
        assert scale_out._descends_from(str(child.pid), scale_out.os.getpid())
        assert not scale_out._descends_from("1", scale_out.os.getpid())
        assert not scale_out._descends_from(str(scale_out.os.getpid()), child.pid)
    finally:
        child.kill()


def test_memory_fit_and_estimate_follow_the_stated_formulas():
    n = 1_000_000
    fixed, b = 200 * 2**20, 800.0
    rec = lambda ranks, us: {"us_per_particle_step": us, "peak_rank_bytes": fixed + b * n / ranks,  # noqa: E731
                             "n_discs": n}
    by = {("liggghts", 1): [rec(1, 0.14)], ("liggghts", 2): [rec(2, 0.10), rec(2, 0.12)]}
    text = "\n".join(scale_out.estimate(by, [], cores=2))
    us_rank = 0.11 * 2                                     # median of the 2-rank runs x ranks
    assert f"{us_rank:.3g} us per particle-step per rank at 2 ranks" in text
    assert "200 MiB + 800 B a disc" in text
    t16 = 1e7 * us_rank * 1e-6 / 16
    m16 = (fixed + b * 1e7 / 16) / 2**30
    assert f"16 ranks: {t16:.3g} s a step" in text and f"{m16:.2f} GiB a rank" in text

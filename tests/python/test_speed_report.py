"""The speed study's report (benchmarks/speed.py write_report): its targets section
states the ratio to serial LIGGGHTS, the 2-thread speed-up and the 1M memory of both native rows
(the comparison scene's and the paper's eq. 19), each computed from the runs' records."""
import sys
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO_ROOT / "benchmarks"))
import speed  # noqa: E402


def record(code, scheme, threads, us, rss, rep):
    return {"size": "1m", "code": code, "scheme": scheme, "threads": threads, "repeat": rep,
            "us_per_ps": us, "peak_rss_bytes": rss}


def test_targets_state_both_native_memory_rows(tmp_path):
    n = 1_000_000
    recs = []
    for rep, f in enumerate((1.0, 1.1, 0.9)):  # medians: the 1.0 runs
        recs += [record("native", "shared_verlet", 1, 0.02 * f, 190e6, rep),
                 record("native", "shared_verlet", 2, 0.0125 * f, 191e6, rep),
                 record("native", "paper_eq19", 1, 0.018 * f, 215e6, rep),
                 record("liggghts", "shared_verlet", 1, 0.15 * f, 1.0e9, rep)]
    table = speed.summarise(recs, {"1m": n})
    meta = {"machine": "x", "cpus": 2, "liggghts": "3.8.0", "yade": "-", "dem_version": "git 0", "repeats": 3,
            "sizes": ["1m"], "started": "now", "start": "settled", "elapsed_s": 1.0, "ceiling": None,
            "records": recs}
    speed.write_report(tmp_path, table, meta)
    text = (tmp_path / "report.md").read_text()
    targets = text[text.index("## Targets"):]
    assert "7.5x faster than serial LIGGGHTS" in targets  # 0.15 / 0.02
    assert "speed-up 1.60x" in targets                     # 0.02 / 0.0125
    # The 1-thread rows: the largest peak over their repeats, per disc.
    assert "shared law, velocity Verlet: native peak memory 190 bytes per disc" in targets
    assert "paper's law, eq. 19: native peak memory 215 bytes per disc" in targets


def test_finished_points_keep_their_records_inputs_and_logs_only(tmp_path):
    d = tmp_path / "runs" / "1m_native_t1_r0"
    keep = ["peak_rss_kb", "run/summary.json", "case/scene.toml", "liggghts.log", "in.liggghts", "yade_script.py"]
    drop = ["run/discs.csv", "run/contacts.vtu", "run/snapshots/discs_0001.vtu", "case/packing.csv", "discs_60.dump"]
    for name in keep + drop:
        (d / name).parent.mkdir(parents=True, exist_ok=True)
        (d / name).write_text("x" * 100)
    assert speed.prune_run(d) == 100 * len(drop)
    assert sorted(str(f.relative_to(d)) for f in d.rglob("*") if f.is_file()) == sorted(keep)
    assert not (d / "run" / "snapshots").exists()

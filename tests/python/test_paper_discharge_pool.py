"""The discharge study runs every member of every configuration as one task of one pool (`dem
ensemble --member K`, then `dem ensemble merge`) and draws the pictures in figure processes: its
ensemble files are those of each ensemble run in one process, byte for byte, and the pictures and
the report are all there."""
import json
import subprocess

import numpy as np
import pytest
from PIL import Image

from dem.compare.papers import paper_discharge
from dem.compare.io.run_dir import RunDir

# The pool is Python's; the engine runs it starts are the release build's (sanitizer: release only).
pytestmark = pytest.mark.release_only


def test_pooled_members_give_the_ensemble_of_one_process(tmp_path, dem_binary, monkeypatch):
    tag, arr, scheme, dt = "17_18_eq19_1e-4", "17_18", "paper_eq19", 1e-4
    monkeypatch.setattr(paper_discharge, "CONFIGS", [(tag, arr, scheme, dt, {})])
    out = tmp_path / "study"
    assert paper_discharge.main(["--out", str(out), "--dem", str(dem_binary), "--members", "2",
                                 "--seed", "3", "--jobs", "2"]) == 0
    # The same ensembles, each run whole by the engine in one process (the study's former way).
    scene = out / "scenes" / "discharge_17_18_paper.toml"
    whole = tmp_path / "whole"
    common = ["--scheme", scheme, "--dt", repr(dt), "--force-dt", "--quiet"]
    for args in (["--out", str(whole), "--members", "2", "--seed", "3"],
                 ["--out", str(whole / "as_written"), "--members", "1", "--perturb", "0"]):
        done = subprocess.run([str(dem_binary), "ensemble", str(scene), *args, *common], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
    assert (out / tag / "ensemble.json").read_bytes() == (whole / "ensemble.json").read_bytes()
    assert (out / tag / "as_written" / "ensemble.json").read_bytes() == \
        (whole / "as_written" / "ensemble.json").read_bytes()
    record = json.loads((out / "discharge.json").read_text())[0]
    assert record["exit"] == 0 and record["ensemble"]["members"] == 2
    report = (out / "report.md").read_text()
    for kind in ("frames", "ratios", "flow"):
        assert (out / f"{kind}_{tag}.png").stat().st_size > 0
        assert f"![{kind}_{tag}]({kind}_{tag}.png)" in report
    # The study's members write no VTU file and no PVD index (--no-vtu: nobody reads them), their
    # CSV files are those of the whole ensemble's members byte for byte, and the pictures drawn from
    # a member of the whole ensemble (snapshots found through its .pvd) have the same pixels.
    assert not [p for p in (out / tag).rglob("*") if p.suffix in (".vtu", ".pvd")]
    assert list(whole.rglob("*.vtu")) and list(whole.rglob("discharge_discs.pvd"))
    for member in sorted((out / tag).glob("member_*")):
        assert (member / "discharge_snapshots.csv").is_file()
        for f in member.rglob("*.csv"):
            if f.name != "discharge_snapshots.csv":
                assert f.read_bytes() == (whole / f.relative_to(out / tag)).read_bytes(), f
    pictured = whole / f"member_{record['pictured']:02d}"
    assert [s["t"] for s in RunDir(pictured).discharge_snapshots()] == \
        [s["t"] for s in RunDir(out / tag / pictured.name).discharge_snapshots()]
    paper_discharge.draw(pictured, tmp_path / "from_whole", tag)
    for kind in ("frames", "ratios", "flow"):
        ours, theirs = Image.open(out / f"{kind}_{tag}.png"), Image.open(tmp_path / "from_whole" / f"{kind}_{tag}.png")
        assert ours.mode == theirs.mode and ours.size == theirs.size
        assert np.array_equal(np.asarray(ours), np.asarray(theirs)), kind


def test_longest_runs_start_first():
    """The configurations at the smaller time step (twice the steps a run) start first, each step's
    configurations in CONFIGS order."""
    plan = [c for c in paper_discharge.CONFIGS]
    small = [k for k, c in enumerate(plan) if c[3] == 5e-5]
    large = [k for k, c in enumerate(plan) if c[3] == 1e-4]
    assert small and large and len(small) + len(large) == len(plan)
    assert paper_discharge.run_order(plan) == small + large


def test_configurations_ending_out_of_order_keep_their_place(tmp_path, dem_binary, monkeypatch):
    """The configuration listed second runs first (its step is smaller) and ends first: it is merged
    and pictured then, and the records and the report keep the order of CONFIGS."""
    configs = [("17_18_eq19_1e-4", "17_18", "paper_eq19", 1e-4, {}),
               ("17_18_verlet_5e-5", "17_18", "velocity_verlet", 5e-5, {})]
    monkeypatch.setattr(paper_discharge, "CONFIGS", configs)
    out = tmp_path / "study"
    assert paper_discharge.main(["--out", str(out), "--dem", str(dem_binary), "--members", "1",
                                 "--jobs", "2"]) == 0
    records = json.loads((out / "discharge.json").read_text())
    assert [r["tag"] for r in records] == [c[0] for c in configs]
    report = (out / "report.md").read_text()
    rows = [line.split(" | ")[0].lstrip("| ") for line in report.splitlines() if line.startswith("| 17_18_")]
    assert rows == [c[0] for c in configs]
    for tag, *_ in configs:
        for kind in ("frames", "ratios", "flow"):
            assert (out / f"{kind}_{tag}.png").stat().st_size > 0


def test_runs_and_pictures_share_the_jobs_places(tmp_path, dem_binary, monkeypatch):
    """Each picture is a task of the runs' pool (draw_in, waiting on its figure process): never more
    than --jobs engine runs and pictures at a time (a picture drawn beside --jobs runs, as when the
    figure processes had places of their own, fails this)."""
    import threading
    configs = [("17_18_eq19_1e-4", "17_18", "paper_eq19", 1e-4, {}),
               ("11_12_eq19_1e-4", "11_12", "paper_eq19", 1e-4, {})]
    monkeypatch.setattr(paper_discharge, "CONFIGS", configs)
    lock, busy, most, drawn = threading.Lock(), [0], [0], []

    def counted(kind, call):
        def wrapper(*args, **kwargs):
            with lock:
                busy[0] += 1
                most[0] = max(most[0], busy[0])
                if kind == "draw":
                    drawn.append(args[-1])
            try:
                return call(*args, **kwargs)
            finally:
                with lock:
                    busy[0] -= 1
        return wrapper

    run = subprocess.run
    monkeypatch.setattr(paper_discharge, "draw_in", counted("draw", paper_discharge.draw_in))
    monkeypatch.setattr(subprocess, "run", lambda cmd, *a, **k: (counted("run", run) if "--member" in cmd else run)(cmd, *a, **k))
    out = tmp_path / "study"
    assert paper_discharge.main(["--out", str(out), "--dem", str(dem_binary), "--members", "2", "--jobs", "2"]) == 0
    assert sorted(drawn) == sorted(["frames", "ratios", "flow"] * len(configs))
    assert 1 <= most[0] <= 2
    for tag, *_ in configs:
        for kind in ("frames", "ratios", "flow"):
            assert (out / f"{kind}_{tag}.png").stat().st_size > 0

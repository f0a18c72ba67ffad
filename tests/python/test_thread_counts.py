"""Every thread count gives the bits of one thread: a 10k-disc silo (three threads' worth of
discs) filled from its lattice and discharged, run with 1, 2 and 3 threads, every output file
compared byte for byte (scripts/output_digest.py drops the timings and the thread count)."""
import importlib.util
import subprocess
from pathlib import Path

import pytest

from dem.compare.io import scene_toml

REPO = Path(__file__).resolve().parents[2]
BASE = REPO / "reference_inputs" / "scenes" / "bench_silo_10k.toml"

_spec = importlib.util.spec_from_file_location("output_digest", REPO / "scripts" / "output_digest.py")
output_digest = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(output_digest)


def digests(run_dir: Path) -> dict:
    files = sorted(p for p in run_dir.rglob("*") if p.is_file()
                   and p.suffix not in output_digest.SKIP_SUFFIX and p.name not in output_digest.SKIP_NAMES)
    return {str(p.relative_to(run_dir)): output_digest.digest(p) for p in files}


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """The 10k silo: 0.05 s of fill from the lattice, then 0.1 s of discharge (discs leave at
    the outlet, samples and recorded contacts on the way)."""
    out = tmp_path_factory.mktemp("threads") / "silo_10k.toml"
    doc = scene_toml.load(BASE)
    remove = [t for t in ("discharge", "end") if t in doc]
    return scene_toml.edit(BASE, None, out, remove=remove, add={
        "end": {"time": 0.05, "stop_at_rest": False},
        "discharge": {"time": 0.1, "gate": "gate", "outlet_depth": 4.0, "jam_time": 1.0,
                      "series_interval": 0.02, "peak_window": 0.02, "snapshots": [0.05]}})


# velocity_verlet's threaded moves run in the unit tests too; its run here (twice the steps) is release only.
@pytest.mark.parametrize("scheme", [[], pytest.param(["--scheme", "velocity_verlet", "--dt", "2.5e-5", "--force-dt"],
                                                     marks=pytest.mark.release_only)],
                         ids=["paper_eq19", "velocity_verlet"])
def test_one_two_three_threads_same_bytes(scene, scheme, run_dem, tmp_path):
    runs = {}
    for threads in (1, 2, 3):
        out = tmp_path / f"t{threads}"
        p = run_dem("run", scene, "--out", out, "--quiet", "--threads", threads, *scheme)
        assert p.returncode == 0, p.stderr
        runs[threads] = digests(out)
    assert "contacts.csv" in runs[1] and "summary.json" in runs[1] and len(runs[1]) >= 5, sorted(runs[1])
    for threads in (2, 3):
        differ = sorted(f for f in runs[1].keys() | runs[threads].keys() if runs[1].get(f) != runs[threads].get(f))
        assert not differ, f"{threads} threads: {differ}"


@pytest.mark.parametrize("env, shown", [({}, "libgomp's default"),
                                        ({"OMP_WAIT_POLICY": "active"}, "OMP_WAIT_POLICY=active"),
                                        ({"GOMP_SPINCOUNT": "7"}, "GOMP_SPINCOUNT=7")],
                         ids=["unset", "policy", "spincount"])
def test_header_says_how_threads_wait(dem_binary, tmp_path, env, shown):
    """The header says how the threads wait at a barrier: libgomp's default, or what the user set."""
    import os
    clean = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
    p = subprocess.run([str(dem_binary), "run", str(BASE), "--out", str(tmp_path / "run"), "--threads", "2",
                        "--end-time", "0.001"], env={**clean, **env}, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert f"threads 2 (barriers: {shown}; or 1, whichever is faster now" in p.stdout, p.stdout[:600]


@pytest.mark.release_only  # a choice by measured speed, which a sanitizer skews
def test_thread_choice_in_summary(dem_binary, tmp_path):
    """A run with 2 threads on the 10k silo (enough discs for 2) says in summary.json how many
    steps each count ran; with integrator.thread_choice = "off" every step has the 2 threads."""
    import json
    for choice in ("auto", "off"):
        out = tmp_path / choice
        p = subprocess.run([str(dem_binary), "run", str(BASE), "--out", str(out), "--threads", "2", "--quiet",
                            "--end-time", "0.2", "--set", f"integrator.thread_choice={choice}"],
                           capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        s = json.loads((out / "summary.json").read_text())
        tc = s["thread_choice"]
        assert tc["mode"] == choice
        assert tc["steps_one_thread"] + tc["steps_threads"] == s["steps"], tc
        if choice == "off":
            assert tc["steps_threads"] == s["steps"] and tc["probes"] == 0, tc
        else:
            assert tc["probes"] >= 1 and tc["steps_threads"] >= 1, tc  # its first probe's threads

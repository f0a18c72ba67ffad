"""Discharge runs of the paper's 17/18 fill (section 5(2)): conservation, logs, jams, Beverloo,
determinism, and restarting from a saved state."""
import csv
import filecmp
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from dem.compare.io import scene_toml

REPO = Path(__file__).resolve().parents[2]
BASE = REPO / "reference_inputs" / "scenes" / "discharge_17_18.toml"


def scene(tmp_path, name, changes=None, **kwargs):
    """The 17/18 discharge scene with keys changed by dotted path (dem.compare.io.scene_toml: a key the
    scene does not have is an error)."""
    return scene_toml.edit(BASE, changes, tmp_path / f"{name}.toml", **kwargs)


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def run(run_dem, scene_path, out, *extra):
    proc = run_dem("run", scene_path, "--out", out, "--quiet", *extra)
    assert proc.returncode == 0, proc.stderr
    return json.loads((Path(out) / "summary.json").read_text())


@pytest.fixture(scope="module")
def every_step(tmp_path_factory, dem_binary):
    """A short discharge sampled at every step (series_interval = dt)."""
    import subprocess
    tmp = tmp_path_factory.mktemp("every")
    path = scene(tmp, "every", {"discharge.series_interval": 1e-4, "discharge.time": 0.4})
    out = tmp / "out"
    proc = subprocess.run([str(dem_binary), "run", str(path), "--out", str(out), "--quiet"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return out


def test_mass_conservation_every_step(every_step):
    s = json.loads((every_step / "summary.json").read_text())
    n0 = s["discharge"]["n_initial"]
    rows = read_csv(every_step / "flow_series.csv")
    assert len(rows) >= 4000  # one per step of 0.4 s at dt = 1e-4
    for r in rows:
        assert int(r["discs_in_silo"]) + int(r["discs_below"]) + int(r["removed"]) == n0, r["t"]
    assert s["n_discs"] + s["discharge"]["removed"] == n0


def test_removal_log_matches_flow_series_and_rate(every_step):
    s = json.loads((every_step / "summary.json").read_text())
    rem = read_csv(every_step / "removals.csv")
    rows = read_csv(every_step / "flow_series.csv")
    times = np.array([float(r["t"]) for r in rem])
    mass = np.array([float(r["mass"]) for r in rem])
    assert len(rem) == s["discharge"]["removed"] > 10
    for r in rows[::50]:
        t = float(r["t"])
        assert int(r["removed"]) == int(np.sum(times <= t + 1e-12)), t
        assert float(r["removed_mass"]) == pytest.approx(float(np.sum(mass[times <= t + 1e-12])), rel=1e-12, abs=1e-9)
    # Flow rate: least squares of cumulative mass from the 5th removal on (docs/outputs.md).
    slope = np.polyfit(times[4:], np.cumsum(mass)[4:], 1)[0]
    assert s["discharge"]["flow_rate_mass"] == pytest.approx(slope, rel=1e-9)
    assert s["discharge"]["flow_rate_discs"] == pytest.approx(slope / (2.65 * math.pi), rel=1e-9)


def test_slit_narrower_than_a_disc_jams(tmp_path, run_dem):
    s = run(run_dem, scene(tmp_path, "narrow", {"silo.slit_width": 1.5}), tmp_path / "out")
    assert s["status"] == "jammed"
    assert s["discharge"]["removed"] == 0
    assert s["discharge"]["jam_at"] == pytest.approx(0.3, abs=2e-4)


def test_slit_of_ten_diameters_flows(tmp_path, run_dem):
    s = run(run_dem, scene(tmp_path, "wide", {"silo.slit_width": 20.0}), tmp_path / "out")
    assert s["status"] in ("discharged", "emptied")
    assert not s["discharge"]["jammed"]
    assert s["discharge"]["removed"] > 200


def test_wide_slit_flow_rate_is_beverloo_plausible(tmp_path, run_dem):
    """Q = C rho_b sqrt(g) (D - k d)^1.5 with C in [0.5, 1], k in [1, 2], rho_b = phi rho_s,
    phi in [0.82, 0.907] (validation.md): the plausibility band, not a target."""
    D, d, rho, g = 12.0, 2.0, 2.65, 980.0
    s = run(run_dem, scene(tmp_path, "bev", {"silo.slit_width": float(D)}), tmp_path / "out")
    q = s["discharge"]["flow_rate_mass"]
    low = 0.5 * 0.82 * rho * math.sqrt(g) * (D - 2 * d) ** 1.5
    high = 1.0 * 0.907 * rho * math.sqrt(g) * (D - 1 * d) ** 1.5
    assert low <= q <= high, (low, q, high)


def test_same_scene_twice_is_bit_identical(tmp_path, run_dem):
    path = scene(tmp_path, "twice", {"discharge.time": 0.3})
    run(run_dem, path, tmp_path / "a")
    run(run_dem, path, tmp_path / "b")
    for name in ("wall_series.csv", "removals.csv", "flow_series.csv", "discs.csv", "contacts.csv"):
        assert filecmp.cmp(tmp_path / "a" / name, tmp_path / "b" / name, shallow=False), name


def test_fill_saved_then_discharged_from_state_equals_one_run(tmp_path, run_dem):
    """Two phases in one run == the fill saved to a state file + a run from that state."""
    whole = scene(tmp_path, "whole", {"discharge.time": 0.3})
    run(run_dem, whole, tmp_path / "one")
    fill = scene_toml.edit(whole, None, tmp_path / "fill.toml", remove=["discharge"])
    state = tmp_path / "rest.state"
    run(run_dem, fill, tmp_path / "fill", "--save-state", state)
    run(run_dem, whole, tmp_path / "two", "--from", state)
    for name in ("discs.csv", "removals.csv", "wall_series.csv"):
        assert filecmp.cmp(tmp_path / "one" / name, tmp_path / "two" / name, shallow=False), name


def test_keystone_removal_unjams(tmp_path, run_dem):
    s = run(run_dem, scene(tmp_path, "unjam", {"silo.slit_width": 3.0, "discharge.on_jam": "remove_keystone"}),
            tmp_path / "out")
    rem = read_csv(tmp_path / "out" / "removals.csv")
    hand = [r for r in rem if r["how"] == "keystone"]
    assert s["discharge"]["jams"] >= 1 and len(hand) == s["discharge"]["removed_by_hand"] >= 1
    assert s["status"] != "jammed" or s["discharge"]["jams"] > len(hand)


def test_snapshots_and_pvd(every_step):
    import meshio
    pvd = (every_step / "discharge_discs.pvd").read_text()
    files = re.findall(r'file="([^"]+)"', pvd)
    assert len(files) == 6  # snapshots at 0, 0.05, 0.1, 0.2, 0.3, 0.4 within 0.4 s
    for f in files:
        m = meshio.read(every_step / f)
        assert "displacement" in m.point_data


def test_a_series_file_that_cannot_be_written_stops_the_run_with_exit_4(tmp_path, run_dem):
    """The wall series is written as it is sampled: a file the run cannot write ends it with exit 4
    and a message naming the file (not an abort)."""
    out = tmp_path / "out"
    (out / "wall_series.csv.tmp").mkdir(parents=True)  # a directory where the file must go
    proc = run_dem("run", scene(tmp_path, "short", {"discharge.time": 0.05}), "--out", out, "--quiet")
    assert proc.returncode == 4, proc.stderr
    assert "cannot write" in proc.stderr and "wall_series.csv.tmp" in proc.stderr, proc.stderr
    assert "terminate" not in proc.stderr
    assert not (out / "summary.json").exists()

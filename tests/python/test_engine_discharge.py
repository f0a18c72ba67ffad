"""`dem run DISCHARGE.toml --engine liggghts|lammps|yade`: the native discharge outputs from a
reference code (compare/codes/reference_run.py, compare/codes/frame_measures.py).

The paper's 17/18 silo (350 discs), shortened with --set (settling 0.3 s, 0.2 s of flow, dt
5e-5 s), runs in each code; its folder must hold the files the native run of the same scene
writes, with the same CSV columns and the native summary's discharge keys, pass the strict reader,
be drawn by the figure tool, and keep every disc: each is in discs.csv or in removals.csv, once,
and at every sample of flow_series.csv and every snapshot the discs present plus the removals so
far are the start's. A removal log with one row dropped (a mutant) fails that check. YADE runs the
small silo of test_engine_run.py (14 discs): the 17/18 silo takes it minutes."""
from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from dem.compare.io.run_dir import RunDir, read_pvd
from test_engine_run import DISCHARGE, LATTICE, dem, needs_liggghts, needs_lmp, needs_yade, scene

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "reference_inputs" / "scenes" / "discharge_17_18.toml"
SNAPSHOTS = [0.0, 0.1, 0.2]
SHORT = ["--set", "discharge.time=0.2", "--set", "integrator.dt=5e-5",
         "--set", f"discharge.snapshots={SNAPSHOTS}"]
# the discharge files of docs/outputs.md but the contact snapshots (no contact list is read back)
FILES = ["removals.csv", "flow_series.csv", "wall_series.csv", "wall_totals_series.csv", "discharge_discs.pvd",
         "snapshots.pvd", "summary.json", "discs.csv", "discs.vtu", "wall_profiles.csv"]


def header(path: Path) -> str:
    return path.read_text().splitlines()[0]


@pytest.fixture(scope="module")
def native(tmp_path_factory, dem_binary) -> Path:
    """The engine's own run of the shortened scene (its fill cut at 0.3 s): the files and keys to match."""
    out = tmp_path_factory.mktemp("native") / "run"
    p = dem(dem_binary, "run", SCENE, "--out", out, "--quiet", "--set", "end.time=0.3", *SHORT, timeout=600)
    assert p.returncode == 0, p.stderr
    return out


def run_code(dem_binary, code: str, out: Path, scene_file: Path = SCENE, *extra) -> Path:
    p = dem(dem_binary, "run", scene_file, "--engine", code, "--out", out, *extra, timeout=900)
    assert p.returncode == 0, p.stdout + p.stderr
    return out


def conservation_problems(out: Path) -> list[str]:
    """Every way the folder loses or doubles a disc: the removal log against the summary, the discs
    left and the start; each flow_series.csv row and each snapshot against the removals so far."""
    run = RunDir(out, strict=True)
    d = run.summary["discharge"]
    n0, rem, discs, flow = d["n_initial"], run.removals(), run.discs(), run.flow_series()
    bad = []
    if d["removed"] != len(rem["t"]):
        bad.append(f"summary removed {d['removed']}, removals.csv {len(rem['t'])} rows")
    if len(discs["id"]) + len(rem["t"]) != n0:
        bad.append(f"{len(discs['id'])} discs left + {len(rem['t'])} removed != {n0}")
    if sorted(list(rem["id"]) + list(discs["id"])) != list(range(n0)):
        bad.append("the removed and the remaining ids are not the start's, once each")
    dt = run.summary["options"]["dt"]
    for t, a, b, r in zip(flow["t"], flow["discs_in_silo"], flow["discs_below"], flow["removed"]):
        logged = int(np.sum(rem["t"] <= t + 0.5 * dt))
        if r != logged or a + b + r != n0:
            bad.append(f"flow_series at t = {t}: {a} + {b} discs, {r} removed ({logged} in the log), start {n0}")
    for snap in run.discharge_snapshots():
        ids = run.snapshot_csv(snap["discs"], ("id",))["id"]
        logged = rem["id"][rem["t"] <= snap["t"] + 0.5 * dt]
        if len(ids) + len(logged) != n0 or set(ids) & set(logged):
            bad.append(f"snapshot at t = {snap['t']}: {len(ids)} discs and {len(logged)} removed of {n0}")
    return bad


def drop_a_removal(out: Path, to: Path) -> Path:
    """The mutant: the folder with the removal log's last row gone."""
    shutil.copytree(out, to)
    lines = (to / "removals.csv").read_text().splitlines()
    (to / "removals.csv").write_text("\n".join(lines[:-1]) + "\n")
    return to


def drop_a_column(out: Path, to: Path) -> Path:
    """The mutant: the folder with flow_series.csv's last column gone."""
    shutil.copytree(out, to)
    rows = (to / "flow_series.csv").read_text().splitlines()
    (to / "flow_series.csv").write_text("\n".join(r.rsplit(",", 1)[0] for r in rows) + "\n")
    return to


def check_native_layout(out: Path, native: Path) -> None:
    for name in FILES:
        assert (out / name).is_file(), name
        assert (native / name).is_file(), name
        if name.endswith(".csv"):
            assert header(out / name) == header(native / name), name
    mine, theirs = (json.loads((p / "summary.json").read_text())["discharge"] for p in (out, native))
    missing = set(theirs) - set(mine)
    assert not missing, missing
    # the snapshot files but the contacts': discs_NNNN.{csv,vtu}, walls_NNNN.vtu
    names = {p.name for p in (native / "snapshots").iterdir() if not p.name.startswith("contacts_")}
    assert {p.name for p in (out / "snapshots").iterdir()} == names
    snaps = read_pvd(out / "discharge_discs.pvd")
    assert [t for t, _f in snaps] == pytest.approx(SNAPSHOTS)
    for _t, f in snaps:
        stem = (out / f).with_suffix("")
        assert (out / f).is_file() and header(stem.with_suffix(".csv")) == header(native / "snapshots" / "discs_0000.csv")


@pytest.mark.reference_codes
@pytest.mark.parametrize("code", [pytest.param("liggghts", marks=needs_liggghts),
                                  pytest.param("lammps", marks=needs_lmp)])
def test_a_discharge_in_a_reference_code_writes_the_native_outputs(tmp_path, dem_binary, native, code):
    out = run_code(dem_binary, code, tmp_path / code, SCENE, "--settle", "0.3", *SHORT)
    check_native_layout(out, native)
    with pytest.raises(AssertionError, match="flow_series.csv"):
        check_native_layout(drop_a_column(out, tmp_path / "mutant_columns"), native)
    run = RunDir(out, strict=True)
    s, d = run.summary, run.summary["discharge"]
    assert s["status"] == "discharged" and d["duration"] == 0.2 and d["removed"] >= 1
    assert d["pattern"] in ("funnel", "piping", "undetermined") and isinstance(d["jammed"], bool)
    flow = run.flow_series()
    assert flow["t"][0] == 0 and np.allclose(np.diff(flow["t"]), 0.005)         # series_interval
    assert flow["removed"][-1] == d["removed"] and flow["moved_fraction"][0] == 0
    # the last frame and the final dump agree on where the discs are (floor at y = 0)
    discs = run.discs()
    assert flow["discs_in_silo"][-1] == np.sum(discs["y"] > 0)
    assert conservation_problems(out) == []
    assert conservation_problems(drop_a_removal(out, tmp_path / "mutant")) != []
    p = subprocess.run(["/usr/bin/python3", "-m", "dem.compare.figures", "run", str(out)], capture_output=True,
                       text=True, cwd=ROOT, timeout=300)
    assert p.returncode == 0, p.stderr
    for png in ("frames.png", "flow.png", "wall_ratios.png", "side_walls.png"):
        assert (out / png).stat().st_size > 0, png


@pytest.mark.reference_codes
@needs_yade
def test_a_discharge_in_yade_keeps_every_disc(tmp_path, dem_binary):
    text = scene("discharge", LATTICE, 0.1).replace("slit_width = 2.0", "slit_width = 4.0") + DISCHARGE
    (tmp_path / "d.toml").write_text(text.replace("series_interval = 0.01", "series_interval = 0.01\n"
                                                  "snapshots = [0.0, 0.1, 0.3]"))
    out = run_code(dem_binary, "yade", tmp_path / "yade", tmp_path / "d.toml", "--settle", "0.1")
    run = RunDir(out, strict=True)
    assert run.summary["discharge"]["removed"] >= 1 and len(run.discharge_snapshots()) == 3
    assert conservation_problems(out) == []
    assert conservation_problems(drop_a_removal(out, tmp_path / "mutant")) != []


def test_a_bad_set_exits_2_naming_the_key(tmp_path, dem_binary):
    out = tmp_path / "out"
    p = dem(dem_binary, "run", SCENE, "--engine", "lammps", "--set", "discharge.tme=0.2", "--out", out)
    assert p.returncode == 2, p.stderr
    assert "discharge.tme" in p.stderr and not out.exists()

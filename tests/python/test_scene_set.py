"""`--set KEY=VALUE` on dem run, dem ensemble, dem resolve and dem compare: the scene's parsed
table is changed before it is validated, so a set value runs exactly as the file's value and a
wrong key or value is refused (exit 2) naming the key."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from dem.compare.io import scene_toml

REPO = Path(__file__).resolve().parents[2]
SILO = REPO / "reference_inputs" / "scenes" / "silo_17_18.toml"
DISCHARGE = REPO / "reference_inputs" / "scenes" / "discharge_17_18.toml"
WALL_SCENE = REPO / "reference_inputs" / "agreement" / "calibration" / "head_on_disc_wall_steel.toml"
SHORT = "end.time=0.01"  # 100 steps: seconds on 2 cores


def same_run(a: Path, b: Path):
    """Every data file of two run folders equal byte for byte; summary.json equal but for the
    scene's file name, the command line and the wall-clock fields."""
    for name in ("discs.csv", "contacts.csv", "wall_profiles.csv", "discs.vtu", "contacts.vtu"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    sa, sb = (json.loads((d / "summary.json").read_text()) for d in (a, b))
    for s in (sa, sb):
        s["scene"].pop("file")
        for k in ("wall_time_s", "particle_steps_per_s", "command"):
            s.pop(k)
    assert sa == sb


def test_set_equals_the_file_with_that_value(tmp_path, run_dem):
    edited = scene_toml.edit(SILO, {"integrator.dt": 5e-5, "end.time": 0.01}, tmp_path / "silo_dt.toml")
    assert scene_toml.load(edited)["integrator"]["dt"] == 5e-5
    by_file = run_dem("run", edited, "--out", tmp_path / "file", "--quiet")
    by_set = run_dem("run", SILO, "--out", tmp_path / "set", "--quiet", "--set", "integrator.dt=5e-5",
                     "--set=" + SHORT)
    assert by_file.returncode == 0 and by_set.returncode == 0, by_file.stderr + by_set.stderr
    same_run(tmp_path / "file", tmp_path / "set")
    summary = json.loads((tmp_path / "set" / "summary.json").read_text())
    assert summary["options"]["dt"] == 5e-5 and 190 < summary["steps"] < 210


@pytest.mark.parametrize("assignment,expect", [
    ("integrator.dtt=1", ["integrator.dtt", "unknown key"]),
    ("integrator.dt=fast", ["integrator.dt", '"fast"', "expected a number"]),
    ("integrator.dt=-1e-5", ["integrator.dt", "> 0"]),
    ("integrator.scheme=rk4", ["integrator.scheme", "rk4", "one of"]),
    ("pairs.5.mu=0.3", ["pairs.5.mu", "pairs has 2 entries"]),
    ("silo.width.x=1", ["silo.width.x", "silo.width is not a table"]),
    ("integrator.dt", ["--set", "KEY=VALUE"]),
], ids=["unknown key", "wrong type", "negative", "bad choice", "index out of range", "through a value", "no value"])
def test_wrong_set_exits_2_naming_the_key(tmp_path, run_dem, assignment, expect):
    out = tmp_path / "out"
    proc = run_dem("run", SILO, "--out", out, "--quiet", "--set", assignment)
    assert proc.returncode == 2, proc.stderr
    for fragment in expect:
        assert fragment in proc.stderr, (fragment, proc.stderr)
    assert not out.exists()


def test_set_reaches_arrays_of_tables_and_new_keys(run_dem):
    proc = run_dem("resolve", WALL_SCENE, "--set", "walls.0.material=sand", "--set", "pairs[0].mu=0.25",
                   "--set", "integrator.force_dt=true", "--set", "contact.normal_spring=overlap")
    assert proc.returncode == 0, proc.stderr
    r = json.loads(proc.stdout)
    plain = json.loads(run_dem("resolve", WALL_SCENE).stdout)
    assert plain["walls"][0]["material"] == "steel" and r["walls"][0]["material"] == "sand"
    assert r["pairs"][0]["mu"] == 0.25 and plain["pairs"][0]["mu"] != 0.25
    assert r["contact"]["normal_spring"] == "overlap"


def test_ensemble_set(tmp_path, run_dem):
    proc = run_dem("ensemble", DISCHARGE, "--out", tmp_path / "e", "--members", "2", "--set", "discharge.tme=1")
    assert proc.returncode == 2 and "discharge.tme" in proc.stderr and "unknown key" in proc.stderr
    proc = run_dem("ensemble", DISCHARGE, "--out", tmp_path / "e", "--member", "0", "--quiet",
                   "--set", SHORT, "--set", "discharge.time=0.005")
    assert proc.returncode == 0, proc.stderr
    member = json.loads((tmp_path / "e" / "member_00" / "member.json").read_text())
    assert member["set"] == [SHORT, "discharge.time=0.005"]


def test_resume_refuses_other_set_values(tmp_path, run_dem):
    out = tmp_path / "run"
    first = run_dem("run", SILO, "--out", out, "--quiet", "--set", "end.time=0.005", "--checkpoint-every", "0.002")
    assert first.returncode == 0 and (out / "checkpoint.dem").exists(), first.stderr
    other = run_dem("run", SILO, "--out", out, "--quiet", "--set", "end.time=0.006", "--resume")
    assert other.returncode == 2 and "--resume" in other.stderr


def test_help_names_set(run_dem):
    for cmd in ("run", "ensemble"):
        assert "--set KEY=VALUE" in run_dem(cmd, "--help").stdout


def dem_compare(dem_binary, *args):
    env = {**os.environ, "DEM_BINARY": str(dem_binary)}
    return subprocess.run([sys.executable, "-m", "dem.compare", "scene", *map(str, args)], cwd=REPO, env=env,
                          capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize("assignment,expect", [
    ("integrator.dtt=1", ["integrator.dtt", "unknown key"]),
    ("integrator.dt=fast", ["integrator.dt", "fast"]),
    ("walls.3.material=sand", ["walls[3]", "1 entries"]),
], ids=["unknown key", "wrong type", "index out of range"])
@pytest.mark.release_only  # dem compare's Python; the engine's refusals are the tests above
def test_compare_set_refuses_like_the_engine(tmp_path, dem_binary, assignment, expect):
    proc = dem_compare(dem_binary, WALL_SCENE, "--codes", "native", "--out", tmp_path / "c", "--set", assignment)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    for fragment in expect:
        assert fragment in proc.stderr, (fragment, proc.stderr)
    # nothing is left behind, and the message speaks of the user's scene, not the changed copy
    assert not (tmp_path / "c").exists()
    assert "scenes_set" not in proc.stderr and "(line " not in proc.stderr, proc.stderr
    # an --out that existed keeps what it held, without the changed copies
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "keep.txt").write_text("x")
    proc = dem_compare(dem_binary, WALL_SCENE, "--codes", "native", "--out", tmp_path / "d", "--set", assignment)
    assert proc.returncode == 2 and sorted(p.name for p in (tmp_path / "d").iterdir()) == ["keep.txt"]


def test_compare_set_changes_the_scene_it_translates(tmp_path, dem_binary):
    doc = scene_toml.with_assignments(scene_toml.load(WALL_SCENE), ["walls.0.material=sand", "integrator.dt=5e-7"])
    assert doc["walls"][0]["material"] == "sand" and doc["integrator"]["dt"] == 5e-7
    assert scene_toml.parse_assignment("integrator.scheme=velocity_verlet") == ("integrator.scheme", "velocity_verlet")
    assert scene_toml.parse_assignment("walls.0.to=[1, 2]") == ("walls[0].to", [1, 2])
    from dem.compare import __main__ as cli
    from dem.compare.cases import plan
    entries = cli.with_set([plan.Entry(WALL_SCENE, plan.Options())], ["integrator.dt=5e-7"], tmp_path / "s")
    written = entries[0].scene
    assert written.name == WALL_SCENE.name and scene_toml.load(written)["integrator"]["dt"] == 5e-7
    # its disc file, read relative to the scene, is still found
    assert subprocess.run([str(dem_binary), "resolve", str(written)], capture_output=True).returncode == 0

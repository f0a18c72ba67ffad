"""What every output folder holds besides the physics' files (docs/outputs.md): run.log, the
periodic snapshots in snapshots.pvd with the walls, the progress lines of a log, the command
line and engine in summary.json, and a fresh folder on every run that is not a resume."""
import json
import signal
import subprocess
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest

from dem.compare.io import scene_toml
from dem.compare.io.run_dir import RunDir

REPO = Path(__file__).resolve().parents[2]
SCENES = REPO / "reference_inputs" / "scenes"


def dem(dem_binary, *args, timeout=300):
    return subprocess.run([str(dem_binary), *map(str, args)], capture_output=True, text=True, timeout=timeout)


def pvd(path):
    return [(float(d.get("timestep")), int(d.get("part")), d.get("file")) for d in ET.parse(path).getroot().iter("DataSet")]


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("scenes")
    return {
        # A short fill with periodic snapshots and progress lines every 1024 steps.
        # No rest checks (stop_at_rest off): the snapshots steps record their pair forces for the snapshots alone.
        "fill": scene_toml.edit(SCENES / "silo_17_18.toml", {"end.time": 0.25, "end.stop_at_rest": False}, tmp / "fill.toml",
                                add={"output.snapshot_interval": 0.1, "output.progress_interval": 0.0,
                                     "output.thermo_interval": 0.05}),
        "discharge": scene_toml.edit(SCENES / "discharge_17_18.toml",
                                     {"discharge.time": 0.06, "discharge.snapshots": [0.0, 0.05]},
                                     tmp / "discharge.toml"),
    }


@pytest.fixture(scope="module")
def fill_run(tmp_path_factory, dem_binary, scenes):
    out = tmp_path_factory.mktemp("fill") / "run"
    p = dem(dem_binary, "run", scenes["fill"], "--out", out, "--threads", "1")
    assert p.returncode == 0, p.stderr
    return out, p


def test_run_log_holds_the_header_and_the_status_line(fill_run):
    out, p = fill_run
    log = (out / "run.log").read_text()
    assert "stability bound of paper_eq19" in log and "zeta_n" in log and "units cgs" in log
    assert "end_time at t = 0.2500 s" in log
    assert log.startswith(p.stdout.splitlines()[0])  # what the run printed


def test_run_log_echoes_the_resolved_scene_and_times_the_loop(fill_run):
    """Like log.lammps, run.log echoes the input as the engine resolved it (never printed on
    screen) and ends with where the loop's time went, part by part, the shares adding to 100 %."""
    import json
    import re
    out, p = fill_run
    log = (out / "run.log").read_text()
    assert "resolved scene (dem resolve; its 350 discs not listed):" in log and "resolved scene" not in p.stdout
    echo = dict(re.findall(r"^    (\w+) = (.*)$", log, re.M))
    assert json.loads(echo["integrator"])["dt"] == 1e-4 and json.loads(echo["end"])["stop_at_rest"] is False
    total = float(re.search(r"loop time by part, this process \(([\d.]+) s\):", log).group(1))
    parts = re.findall(r"^    (.+?)\s+([\d.]+) s\s+([\d.]+) %$", log, re.M)
    names = [n for n, _, _ in parts]
    assert names[0].startswith("time step") and "checks" in names[1] and "checkpoints" in names
    assert sum(float(s) for _, s, _ in parts) == pytest.approx(total, abs=1e-3 + 1e-3 * total)
    assert sum(float(f) for _, _, f in parts) == pytest.approx(100.0, abs=0.5)
    wall = json.loads((out / "summary.json").read_text())["wall_time_s"]
    assert total == pytest.approx(wall, rel=0.05, abs=2e-3)


def test_run_log_of_a_quiet_and_of_an_unstable_run(tmp_path, dem_binary):
    """--quiet prints nothing but still writes run.log; an unstable run's log has its warning."""
    out = tmp_path / "unstable"
    p = dem(dem_binary, "run", SCENES / "silo_17_18.toml", "--out", out, "--quiet", "--scheme", "paper_eq18",
            "--dt", "1e-4", "--force-dt")
    assert p.returncode == 3 and p.stdout == ""
    log = (out / "run.log").read_text()
    assert "stability bound" in log and "dem: unstable run:" in log and "last good state" in log


def test_progress_in_a_log_is_one_line_each(fill_run):
    """stderr is a pipe here, not a terminal: whole lines, no carriage returns."""
    _, p = fill_run
    lines = [l for l in p.stderr.splitlines() if "steps/s" in l]
    assert len(lines) >= 2, p.stderr
    assert "\r" not in p.stderr and all("ETA" in l and l.startswith("  fill t = ") for l in lines)


def test_summary_records_command_engine_and_threads(fill_run, dem_binary, scenes):
    out, _ = fill_run
    s = json.loads((out / "summary.json").read_text())
    assert s["command"] == [str(dem_binary), "run", str(scenes["fill"]), "--out", str(out), "--threads", "1"]
    v = dem(dem_binary, "--version").stdout.split()
    assert s["engine_version"] == v[1] and s["build_id"] in " ".join(v)
    assert s["options"]["threads"] == 1 and s["options"]["units"] == "cgs"


def test_periodic_snapshots_with_walls_in_one_pvd(fill_run):
    """output.snapshot_interval = 0.1 s at dt = 1e-4: steps 0, 1000 and 2000, each the discs, the
    walls (VTK lines) and the contacts; thermo.csv every 0.05 s and at the fill's start and end."""
    out, _ = fill_run
    entries = pvd(out / "snapshots.pvd")
    assert [(round(t, 9), part) for t, part, _ in entries] == [(t, k) for t in (0.0, 0.1, 0.2) for k in (0, 1, 2)]
    for t, part, name in entries:
        if t == 0 and part == 2:  # no contact yet (the lattice's gaps): a grid meshio cannot read
            assert 'NumberOfCells="0"' in (out / name).read_text()
            continue
        mesh = meshio.read(out / name)
        if part == 0:
            assert len(mesh.points) == 350 and "radius" in mesh.point_data
        elif part == 1:
            assert mesh.cells[0].type == "line" and len(mesh.cells[0].data) == 5   # the silo's walls
            assert sorted(mesh.cell_data["wall"][0]) == [0, 1, 2, 3, 4]
        else:  # the step recorded its pair forces for the snapshot: no NaN totals
            assert mesh.cells[0].type == "line" and np.all(np.isfinite(mesh.cell_data["f_n"][0]))
    th = RunDir(out).thermo()
    assert list(th["step"]) == [0, 500, 1000, 1500, 2000, 2500]
    assert set(th["phase"]) == {"fill"} and th["kinetic_energy"][0] == 0 and th["kinetic_energy"][1] > 0


def test_discharge_snapshots_are_in_the_runs_pvd_with_the_gate_gone(tmp_path, dem_binary, scenes):
    out = tmp_path / "run"
    p = dem(dem_binary, "run", scenes["discharge"], "--out", out, "--quiet")
    assert p.returncode == 0, p.stderr
    entries = pvd(out / "snapshots.pvd")
    s = json.loads((out / "summary.json").read_text())
    t_open = s["discharge"]["t_open"]
    assert [part for _, part, _ in entries] == [0, 1, 2, 0, 1, 2]
    assert entries[0][0] == t_open and entries[3][0] == pytest.approx(t_open + 0.05)
    assert [name for _, _, name in entries][:3] == ["snapshots/discs_0000.vtu", "snapshots/walls_0000.vtu",
                                                    "snapshots/contacts_0000.vtu"]
    walls = meshio.read(out / "snapshots" / "walls_0000.vtu")
    names = [w["name"] for w in s["walls"]]
    assert "gate" not in [names[k] for k in walls.cell_data["wall"][0]] and len(walls.cells[0].data) == 4
    # The discharge's own collections stay as they are: the discs and the contacts.
    assert len(pvd_plain(out / "discharge_discs.pvd")) == 2


def pvd_plain(path):
    return [d.get("file") for d in ET.parse(path).getroot().iter("DataSet")]


def test_a_fresh_run_clears_an_earlier_runs_files(tmp_path, dem_binary, scenes):
    """A fill run into the folder of a discharge leaves none of the discharge's files; files the
    engine does not write stay."""
    out = tmp_path / "run"
    assert dem(dem_binary, "run", scenes["discharge"], "--out", out, "--quiet").returncode == 0
    assert (out / "removals.csv").exists() and (out / "snapshots" / "discs_0000.csv").exists()
    (out / "notes.txt").write_text("mine")
    (out / "snapshots" / "mine.txt").write_text("mine")
    fill = scene_toml.edit(SCENES / "silo_17_18.toml", {"end.time": 0.01}, tmp_path / "fill.toml")
    p = dem(dem_binary, "run", fill, "--out", out)
    assert p.returncode == 0, p.stderr
    assert "files of an earlier run from" in p.stdout
    left = sorted(str(f.relative_to(out)) for f in out.rglob("*") if f.is_file())
    assert left == sorted(["summary.json", "run.log", "thermo.csv", "discs.csv", "discs.vtu", "contacts.csv",
                           "contacts.vtu", "walls.vtu", "wall_profiles.csv", "notes.txt", "snapshots/mine.txt"])
    assert RunDir(out, strict=True).status == "end_time"


def test_a_resume_keeps_the_runs_files(tmp_path, dem_binary, scenes):
    """--resume goes on in the folder: the snapshots written before the stop stay, the run.log
    grows by the resumed part, and the run ends as one never stopped."""
    out = tmp_path / "run"
    proc = subprocess.Popen([str(dem_binary), "run", str(scenes["discharge"]), "--out", str(out), "--quiet",
                             "--checkpoint-every", "0.01"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 300
    while not (out / "snapshots" / "discs_0000.csv").exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    proc.send_signal(signal.SIGINT)
    assert proc.wait(timeout=300) in (130, 0)
    first = (out / "snapshots" / "discs_0000.csv").read_bytes()
    p = dem(dem_binary, "run", scenes["discharge"], "--out", out, "--quiet", "--resume", "--checkpoint-every", "0.01")
    assert p.returncode == 0, p.stderr
    assert (out / "snapshots" / "discs_0000.csv").read_bytes() == first
    log = (out / "run.log").read_text()
    assert log.count("stability bound") == 2 and "resumed from" in log and "discharged at t" in log
    full = tmp_path / "full"
    assert dem(dem_binary, "run", scenes["discharge"], "--out", full, "--quiet").returncode == 0
    for name in ("thermo.csv", "snapshots.pvd", "discharge_discs.pvd", "removals.csv", "snapshots/walls_0001.vtu"):
        assert (out / name).read_bytes() == (full / name).read_bytes(), name

"""Checkpoints and resume (docs/outputs.md, "Checkpoints"): a run killed with SIGKILL at random
points and resumed with --resume ends bit-identical to the run never stopped, for a fill to rest,
a discharge, a shear (paper 2's box with bonded clusters) and a discharge under
velocity_verlet_onset with the shared law (its pairs' kept f_n); SIGINT / SIGTERM stop after the current step with a checkpoint, all outputs
and status "interrupted" (exit 130 / 143); a checkpoint of another scene, engine version or
option set is refused with exit 2."""
import json
import os
import random
import signal
import struct
import subprocess
import time
from pathlib import Path

import pytest

from dem.compare.io import scene_toml

REPO = Path(__file__).resolve().parents[2]
SILO = REPO / "reference_inputs" / "scenes" / "silo_17_18.toml"
DISCHARGE = REPO / "reference_inputs" / "scenes" / "discharge_17_18.toml"
SHEAR = REPO / "reference_inputs" / "scenes" / "shear_a50_clusters.toml"
JANSSEN = REPO / "reference_inputs" / "scenes" / "janssen_column.toml"
# Files a run writes that must be equal bit for bit (summary.json: all but the wall-clock timing).
FILL_FILES = ["discs.csv", "contacts.csv", "wall_profiles.csv", "discs.vtu", "contacts.vtu", "thermo.csv"]
DISCHARGE_FILES = FILL_FILES + ["removals.csv", "flow_series.csv", "wall_series.csv", "wall_totals_series.csv",
                                "discharge_discs.pvd", "discharge_contacts.pvd", "snapshots.pvd"]
SHEAR_FILES = FILL_FILES + ["shear_series.csv", "shear_planes.csv", "snapshots/index.json", "snapshots.pvd"]
TIMING = ("wall_time_s", "particle_steps_per_s", "command", "thread_choice")  # the command line: --resume changes it;
# thread_choice: what this process measured and chose (timings)


def dem(dem_binary, *args, **kw):
    return subprocess.run([str(dem_binary), *map(str, args)], capture_output=True, text=True, timeout=600, **kw)


def summary(out):
    s = json.loads((Path(out) / "summary.json").read_text())
    for k in TIMING:
        s.pop(k)
    return s


def assert_same_run(a, b, files):
    for name in files:
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    snaps = sorted(p.name for p in (a / "snapshots").glob("*")) if (a / "snapshots").exists() else []
    assert snaps == sorted(p.name for p in (b / "snapshots").glob("*") if not p.name.endswith(".tmp"))
    for name in snaps:
        assert (a / "snapshots" / name).read_bytes() == (b / "snapshots" / name).read_bytes(), name
    assert summary(a) == summary(b)


def start(dem_binary, scene, out, every, extra=()):
    return subprocess.Popen([str(dem_binary), "run", str(scene), "--out", str(out), "--quiet",
                             "--checkpoint-every", str(every), *extra],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def wait_for(proc, path, timeout=300):
    """Waits until `path` exists (or the run ends); True when it exists."""
    deadline = time.monotonic() + timeout
    while not path.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.0002)
    return path.exists()


def stop(proc, sig):
    if proc.poll() is None:
        proc.send_signal(sig)
    proc.wait(timeout=300)
    return proc.returncode


def lowered_floor(folder):
    """The Janssen column with its floor lowered through the whole (short) run, so that every kill
    falls while the wall translates: its place must come back from the checkpoint."""
    return scene_toml.edit(JANSSEN, {"walls[2].move_from": 0.01, "walls[2].move_until": 0.5, "end.time": 0.08,
                                     "end.stop_at_rest": False}, Path(folder) / "floor.toml")


ONSET = {"integrator.scheme": "velocity_verlet_onset", "integrator.dt": 1e-5, "integrator.force_dt": True,
         "contact.normal_spring": "overlap", "contact.no_tension": "total", "contact.friction_cap": "total",
         "pairs[0].mu": 0.2}


def onset_discharge(folder, dem_binary):
    """A discharge under velocity_verlet_onset and the shared law (friction_cap "total", friction
    low enough that contacts slide), from the state of a 0.1 s fill (start.from): in the flow, slips
    start between discs at nearly every step, so the pairs' kept f_n (the cap at a step's start of
    the slip correction) must come back from the checkpoint, through the removals."""
    fill = scene_toml.edit(SILO, {**ONSET, "end.time": 0.1, "end.stop_at_rest": False}, Path(folder) / "onset_fill.toml")
    state = Path(folder) / "onset_fill.state"
    p = dem(dem_binary, "run", fill, "--out", Path(folder) / "onset_fill", "--quiet", "--save-state", state)
    assert p.returncode == 0, p.stderr
    return scene_toml.edit(DISCHARGE, {**ONSET, "discharge.time": 0.3, "discharge.snapshots": [0.0, 0.1, 0.2, 0.3]},
                           Path(folder) / "onset.toml", add={"start.from": str(state)})


@pytest.fixture(scope="module")
def full_runs(tmp_path_factory, dem_binary):
    """The uninterrupted runs (no checkpoints), their final states and wall times."""
    tmp = tmp_path_factory.mktemp("full")
    wall = {}
    for name, scene in (("silo", SILO), ("discharge", DISCHARGE), ("shear", SHEAR), ("floor", lowered_floor(tmp)),
                        ("onset", onset_discharge(tmp, dem_binary))):
        t0 = time.monotonic()
        p = dem(dem_binary, "run", scene, "--out", tmp / name, "--quiet", "--save-state", tmp / f"{name}.state")
        wall[name] = time.monotonic() - t0
        assert p.returncode == 0, p.stderr
    return tmp, wall


@pytest.mark.parametrize("case,scene,files,every", [
    ("silo", SILO, FILL_FILES, 0.002),
    ("discharge", DISCHARGE, DISCHARGE_FILES, 0.005),
    ("shear", SHEAR, SHEAR_FILES, 0.02),
    ("floor", None, FILL_FILES, 0.005),
    ("onset", None, DISCHARGE_FILES, 0.01),
])
def test_killed_and_resumed_run_is_bit_identical(tmp_path, dem_binary, full_runs, case, scene, files, every):
    """SIGKILL at random times (a fraction of the uninterrupted run's wall time), resume, compare."""
    full, wall = full_runs
    scene = scene or full / f"{case}.toml"
    rng = random.Random(7)
    killed = attempts = 0
    while killed < 3 and attempts < 12:
        attempts += 1
        out = tmp_path / f"run{attempts}"
        proc = start(dem_binary, scene, out, every)
        time.sleep(rng.uniform(0.1, 0.9) * wall[case])
        assert wait_for(proc, out / "checkpoint.dem")
        killed += stop(proc, signal.SIGKILL) == -signal.SIGKILL
        state = tmp_path / f"run{attempts}.state"
        p = dem(dem_binary, "run", scene, "--out", out, "--quiet", "--resume", "--save-state", state)
        assert p.returncode == 0, p.stderr
        assert_same_run(full / case, out, files)
        assert state.read_bytes() == (full / f"{case}.state").read_bytes()
    assert killed >= 3, f"only {killed} of {attempts} runs could be killed before they ended"


def test_kill_resume_kill_resume(tmp_path, dem_binary, full_runs):
    """Killed in the fill, resumed and killed again in the discharge, resumed to the end."""
    out = tmp_path / "run"
    proc = start(dem_binary, DISCHARGE, out, 0.005)
    assert wait_for(proc, out / "checkpoint.dem")
    assert stop(proc, signal.SIGKILL) == -signal.SIGKILL
    proc = start(dem_binary, DISCHARGE, out, 0.005, extra=("--resume",))
    assert wait_for(proc, out / "snapshots" / "discs_0001.csv")
    assert stop(proc, signal.SIGKILL) == -signal.SIGKILL
    p = dem(dem_binary, "run", DISCHARGE, "--out", out, "--quiet", "--resume", "--checkpoint-every", "0.005")
    assert p.returncode == 0, p.stderr
    assert_same_run(full_runs[0] / "discharge", out, DISCHARGE_FILES)


@pytest.mark.parametrize("sig,code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
@pytest.mark.parametrize("phase", ["fill", "discharge"])
def test_signal_stops_gracefully(tmp_path, dem_binary, full_runs, sig, code, phase):
    out = tmp_path / "run"
    proc = start(dem_binary, DISCHARGE, out, 0.01)
    # The first checkpoint comes early in the fill; the snapshots folder at the opening.
    assert wait_for(proc, out / ("checkpoint.dem" if phase == "fill" else "snapshots"))
    assert stop(proc, sig) == code, proc.stderr.read()
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "interrupted"
    phase_discharge = "discharge" in s
    assert phase_discharge == (phase == "discharge")
    for name in FILL_FILES + (DISCHARGE_FILES if phase_discharge else []):
        assert (out / name).stat().st_size > 0, name
    if phase_discharge:
        assert s["discharge"]["status"] == "interrupted"
    p = dem(dem_binary, "run", DISCHARGE, "--out", out, "--quiet", "--resume")
    assert p.returncode == 0, p.stderr
    assert_same_run(full_runs[0] / "discharge", out, DISCHARGE_FILES)


@pytest.mark.parametrize("sig,code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_signal_stops_a_shear_gracefully(tmp_path, dem_binary, full_runs, sig, code):
    """A stop request during the shear: exit 130 / 143, status "interrupted" with the shear's
    series so far, and the resumed run ends as the run never stopped."""
    out = tmp_path / "run"
    proc = start(dem_binary, SHEAR, out, 0.05)
    assert wait_for(proc, out / "snapshots")  # made when the shear begins
    assert stop(proc, sig) == code, proc.stderr.read()
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "interrupted" and "shear" in s
    assert s["shear"]["strain_final"] < s["shear"]["max_strain"]
    for name in SHEAR_FILES:
        assert (out / name).stat().st_size > 0, name
    p = dem(dem_binary, "run", SHEAR, "--out", out, "--quiet", "--resume")
    assert p.returncode == 0, p.stderr
    assert_same_run(full_runs[0] / "shear", out, SHEAR_FILES)


def test_the_printed_resume_command_goes_on(tmp_path, dem_binary, full_runs):
    """The command an interrupted run prints carries every option of the run (--end-time too)."""
    out = tmp_path / "run"
    proc = subprocess.Popen([str(dem_binary), "run", str(DISCHARGE), "--out", str(out), "--quiet",
                             "--end-time", "4.0"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert wait_for(proc, out / "snapshots")
    assert stop(proc, signal.SIGINT) == 130
    err = proc.stderr.read()
    cmd = err.split("written (", 1)[1].rsplit(" goes on)", 1)[0]
    assert "'--end-time' '4.0'" in cmd and cmd.endswith(" --resume"), err
    p = subprocess.run(cmd, shell=True, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert json.loads((out / "summary.json").read_text())["status"] == "discharged"


def test_checkpoint_every_from_the_scene(tmp_path, dem_binary, full_runs):
    scene = scene_toml.edit(SILO, None, tmp_path / "silo.toml", add={"output.checkpoint_every": 0.1})
    out = tmp_path / "run"
    p = dem(dem_binary, "run", scene, "--out", out, "--quiet")
    assert p.returncode == 0, p.stderr
    assert (out / "checkpoint.dem").exists()
    p = dem(dem_binary, "run", scene, "--out", out, "--quiet", "--resume")
    assert p.returncode == 0, p.stderr
    a, b = summary(full_runs[0] / "silo"), summary(out)
    for s in (a, b):
        s["scene"].pop("file")
    assert a == b
    for name in FILL_FILES:
        assert (full_runs[0] / "silo" / name).read_bytes() == (out / name).read_bytes(), name


@pytest.fixture
def checkpointed(tmp_path, dem_binary):
    out = tmp_path / "run"
    p = dem(dem_binary, "run", SILO, "--out", out, "--quiet", "--checkpoint-every", "0.1")
    assert p.returncode == 0, p.stderr
    return out


def fnv1a(data):
    h = 1469598103934665603
    for b in data:
        h = ((h ^ b) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h


def test_resume_refuses_another_engine_version(checkpointed, dem_binary):
    ckpt = checkpointed / "checkpoint.dem"
    body = ckpt.read_bytes()[:-8]
    version = json.loads((checkpointed / "summary.json").read_text())["engine"].encode()  # "dem 0.1.0"
    assert version in body
    other = b"dem 9.9.9"[:len(version)].ljust(len(version), b"9")
    body = body.replace(version, other, 1)
    ckpt.write_bytes(body + struct.pack("<Q", fnv1a(body)))
    p = dem(dem_binary, "run", SILO, "--out", checkpointed, "--quiet", "--resume")
    assert p.returncode == 2
    assert "--resume" in p.stderr and other.decode() in p.stderr and "same engine" in p.stderr


def test_resume_refuses_a_changed_scene(checkpointed, dem_binary, tmp_path):
    scene = scene_toml.edit(SILO, {"pairs[0].mu": 0.5}, tmp_path / "changed.toml")
    p = dem(dem_binary, "run", scene, "--out", checkpointed, "--quiet", "--resume")
    assert p.returncode == 2 and "the scene changed since the checkpoint" in p.stderr, p.stderr


def test_resume_refuses_other_options(checkpointed, dem_binary):
    p = dem(dem_binary, "run", SILO, "--out", checkpointed, "--quiet", "--resume", "--end-time", "3")
    assert p.returncode == 2 and "--end-time" in p.stderr and "must be as in the checkpointed run" in p.stderr, p.stderr


def test_resume_refuses_a_damaged_checkpoint(checkpointed, dem_binary):
    ckpt = checkpointed / "checkpoint.dem"
    data = bytearray(ckpt.read_bytes())
    data[len(data) // 2] ^= 0xFF
    ckpt.write_bytes(bytes(data))
    p = dem(dem_binary, "run", SILO, "--out", checkpointed, "--quiet", "--resume")
    assert p.returncode == 2 and "damaged checkpoint" in p.stderr, p.stderr
    ckpt.write_bytes(b"DEMCKPT1")
    p = dem(dem_binary, "run", SILO, "--out", checkpointed, "--quiet", "--resume")
    assert p.returncode == 2 and "checkpoint" in p.stderr, p.stderr


def test_resume_without_checkpoint(tmp_path, dem_binary):
    p = dem(dem_binary, "run", SILO, "--out", tmp_path / "none", "--quiet", "--resume")
    assert p.returncode == 2 and "no checkpoint" in p.stderr
    assert not (tmp_path / "none").exists()
    p = dem(dem_binary, "run", SILO, "--out", tmp_path / "x", "--checkpoint-every", "-1")
    assert p.returncode == 2 and "--checkpoint-every" in p.stderr


def test_resume_needs_the_wall_series_so_far(tmp_path, dem_binary, full_runs):
    """The wall series is written as it is sampled (wall_series.csv.tmp, renamed at the end); a
    checkpoint holds its length. A resumed discharge cuts the file back to that length and goes on;
    without it, or with less, it refuses, saying which file."""
    out = tmp_path / "run"
    proc = start(dem_binary, DISCHARGE, out, 0.01)
    assert wait_for(proc, out / "snapshots" / "discs_0001.csv")
    assert stop(proc, signal.SIGINT) == 130, proc.stderr.read()
    series = out / "wall_series.csv"
    text = series.read_bytes()
    assert text.startswith(b"t,wall,bin,") and text.endswith(b"\n")
    assert not (out / "wall_series.csv.tmp").exists()
    series.write_bytes(text[:-1])
    p = dem(dem_binary, "run", DISCHARGE, "--out", out, "--quiet", "--resume")
    assert p.returncode == 2 and "wall_series.csv" in p.stderr and "fewer than the checkpoint" in p.stderr, p.stderr
    series.unlink()
    p = dem(dem_binary, "run", DISCHARGE, "--out", out, "--quiet", "--resume")
    assert p.returncode == 2 and "wall_series.csv" in p.stderr and "missing" in p.stderr, p.stderr
    series.write_bytes(text + b"rows a killed run wrote after its checkpoint\n")  # cut off again
    p = dem(dem_binary, "run", DISCHARGE, "--out", out, "--quiet", "--resume")
    assert p.returncode == 0, p.stderr
    assert_same_run(full_runs[0] / "discharge", out, DISCHARGE_FILES)


def test_a_checkpoint_has_the_same_bytes_in_every_run_but_its_clock(tmp_path, dem_binary):
    """Two runs of one discharge write the same checkpoint but for the clock (the wall time so
    far, after the magic and the engine, scene, options and phase strings) and the checksum that
    covers it: no padding byte of a raw-written record left uninitialised."""
    import struct
    files = []
    for k in range(2):
        out = tmp_path / f"r{k}"
        p = dem(dem_binary, "run", DISCHARGE, "--out", out, "--quiet", "--checkpoint-every", "0.5")
        assert p.returncode == 0, p.stderr
        files.append((out / "checkpoint.dem").read_bytes())
    a, b = files
    at = 8
    for _ in range(4):                                    # engine, scene hash, options, phase
        if _ == 1:
            at += 8
            continue
        at += 8 + struct.unpack_from("<Q", a, at)[0]
    clock = slice(at, at + 8)
    assert len(a) == len(b) and a[:clock.start] == b[:clock.start] and a[clock.stop:-8] == b[clock.stop:-8]

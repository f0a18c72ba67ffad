"""Every output file is written to NAME.tmp and renamed when complete: a run killed (SIGKILL, the
whole process group, so the PNG drawing too) at random points leaves only files that parse
(json, CSV, VTU and PVD, PNG, the checkpoint by resuming from it); unfinished files can only be
NAME.tmp."""
import csv
import json
import os
import random
import shutil
import signal
import sys
import subprocess
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
import matplotlib.image  # noqa: E402
import meshio  # noqa: E402
import pytest  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
BASE = (REPO / "reference_inputs" / "scenes" / "discharge_17_18.toml").read_text()


def check_file(path):
    """Parses one output file by its kind; raises when it is incomplete."""
    name = path.name
    if name.endswith(".json"):
        json.loads(path.read_text())
    elif name.endswith(".csv"):
        text = path.read_text()
        assert text.endswith("\n"), f"{path}: no final line break"
        rows = list(csv.reader(text.splitlines()))
        assert rows and all(len(r) == len(rows[0]) for r in rows), f"{path}: ragged rows"
    elif name.endswith(".vtu"):
        meshio.read(path)
    elif name.endswith(".pvd"):
        ET.parse(path)
    elif name.endswith(".png"):
        assert matplotlib.image.imread(path).size > 0
    elif name == "run.log":
        assert path.read_text().endswith("\n"), f"{path}: no final line break"
    elif name == "checkpoint.dem":
        pass  # checked by resuming
    elif name == "last_good.bin":
        check_last_good(path)
    elif name == "opening_positions.bin":  # magic, count of ids, then x, y per id
        data = path.read_bytes()
        assert data[:8] == b"DEMOPEN1" and len(data) == 16 + 16 * int.from_bytes(data[8:16], "little"), path
    else:
        raise AssertionError(f"unexpected file {path}")


# The arrays of the last good state in their order (engine/src/io/state.cpp write_discs), by item
# size: per kind r, mass, 1/m, 1/I, material; per disc kind, id, x, y, phi (output.rotation_angle
# only: may be empty), vx, vy, omega, du, dv, dphi (eq. 19 only: may be empty), fx, fy, torque.
KIND_ITEMS = [8, 8, 8, 8, 4]
DISC_ITEMS = [4, 4] + [8] * 12


def check_last_good(path):
    """A kept last good state (engine/src/run/last_good.cpp): magic, time, the arrays, nothing more."""
    data = path.read_bytes()
    assert data[:8] == b"DEMGOOD1", path
    at = 16
    counts = []
    for size in KIND_ITEMS + DISC_ITEMS:
        counts.append(int.from_bytes(data[at:at + 8], "little"))
        at += 8 + counts[-1] * size
    assert at == len(data), (path, at, len(data))
    kinds, discs = counts[:len(KIND_ITEMS)], counts[len(KIND_ITEMS):]
    assert len(set(kinds)) == 1 and kinds[0] >= 1, (path, kinds)
    n = discs[0]
    assert 0 < n <= 350, (path, n)  # the discharge removes discs
    assert all(c == n or (c == 0 and k in (4, 8, 9, 10)) for k, c in enumerate(discs)), (path, discs)


def check_dir(out):
    checked = 0
    for path in sorted(out.rglob("*")):
        if path.is_dir():
            continue
        if path.name.endswith(".tmp"):  # an unfinished file keeps its temporary name
            assert (path.parent / path.name[:-4]).suffix in (".json", ".csv", ".vtu", ".pvd", ".png", ".dem", ".bin", ".log"), path
            continue
        check_file(path)
        checked += 1
    return checked


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """The 17/18 discharge with 26 snapshots (every 0.04 s) and checkpoints every 0.02 s."""
    path = tmp_path_factory.mktemp("scene") / "many_snapshots.toml"
    snaps = ", ".join(f"{0.04 * k:.2f}" for k in range(26))
    text = BASE.replace("snapshots = [0.0, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0]", f"snapshots = [{snaps}]")
    assert text != BASE
    path.write_text(text.replace("[output]\n", "[output]\ncheckpoint_every = 0.02\n", 1))
    return path


def test_killed_runs_leave_only_complete_files(tmp_path, dem_binary, scene):
    """dem run killed while it steps and writes, and the drawing of its pictures
    (dem.compare.figures run) killed while it draws: every file left is complete or a .tmp."""
    def timed(cmd):
        t0 = time.monotonic()
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600, cwd=REPO)
        assert proc.returncode == 0, proc.stderr
        return time.monotonic() - t0

    full = tmp_path / "full"
    engine = timed([str(dem_binary), "run", str(scene), "--out", str(full), "--quiet"])
    drawing = max(0.1, timed([sys.executable, "-m", "dem.compare.figures", "run", str(full)]))
    assert (full / "network.png").exists() and len(list((full / "snapshots").glob("*.vtu"))) == 78  # discs, contacts, walls
    assert check_dir(full) > 100
    rng = random.Random(11)
    seen_tmp = 0
    for k in range(6):
        out = tmp_path / f"killed{k}"
        if k % 2 == 0:  # while the engine steps and writes snapshots
            p = subprocess.Popen([str(dem_binary), "run", str(scene), "--out", str(out), "--quiet"],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
            time.sleep(rng.uniform(0.05, 1.0) * engine)
        else:  # while the PNGs are drawn
            shutil.copytree(full, out, ignore=shutil.ignore_patterns("*.png"))
            p = subprocess.Popen([sys.executable, "-m", "dem.compare.figures", "run", str(out)], cwd=REPO,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
            time.sleep(rng.uniform(0.0, 1.0) * drawing)
        os.killpg(p.pid, signal.SIGKILL)
        p.wait(timeout=60)
        if not out.exists():
            continue
        seen_tmp += any(path.name.endswith(".tmp") for path in out.rglob("*"))
        check_dir(out)
        if k % 2 == 0 and (out / "checkpoint.dem").exists():  # the checkpoint loads: resume it to the end
            resumed = tmp_path / f"resumed{k}"
            shutil.copytree(out, resumed)
            r = subprocess.run([str(dem_binary), "run", str(scene), "--out", str(resumed), "--quiet",
                                "--resume"], capture_output=True, text=True, timeout=600)
            assert r.returncode == 0, r.stderr
            assert (resumed / "discs.csv").read_bytes() == (full / "discs.csv").read_bytes()
        shutil.rmtree(out)
    print(f"engine {engine:.2f} s, drawing {drawing:.2f} s; {seen_tmp} of 6 killed runs left a .tmp file")

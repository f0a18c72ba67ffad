"""The examples (examples/*.py) run with the module from this build, from a folder outside the
repository, and print what they promise; and the .pth file the build installs makes
`import dem.compare` work from any folder."""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import package_dir

REPO = Path(__file__).resolve().parents[2]


def python(args, cwd, path_entries=None, timeout=120):
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    if path_entries:
        env["PYTHONPATH"] = os.pathsep.join(map(str, path_entries))
    return subprocess.run([sys.executable, *map(str, args)], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout)


def test_paper_silo_example(dem_module, tmp_path):
    proc = python([REPO / "examples" / "paper_silo.py", "--out", tmp_path / "out"], tmp_path, [package_dir()])
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert re.match(r"silo_17_18: rest at t = 0\.\d{4} s after \d+ steps, 350 discs$", lines[0]), lines[0]
    for wall in ("left", "right", "bottom_left", "gate", "bottom_right", "point L", "point R"):
        assert any(line.split()[0] == wall.split()[0] and wall in line for line in lines), wall
    weight, carried, ratio = re.match(r"weight of the discs (\S+) dyn/cm; walls and points carry (\S+) \((\S+)\)",
                                      lines[-2]).groups()
    assert abs(float(ratio) - 1) < 1e-3  # at rest the walls and points carry the weight
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "rest" and summary["weight"] == pytest.approx(float(weight), rel=1e-5)


def test_dt_sweep_example(dem_module, tmp_path):
    proc = python([REPO / "examples" / "dt_sweep.py"], tmp_path, [package_dir()])
    assert proc.returncode == 0, proc.stderr
    rows = [line.split() for line in proc.stdout.splitlines()[1:]]
    assert [(r[0], float(r[1])) for r in rows] == [(s, dt) for s in ("paper_eq19", "velocity_verlet")
                                                   for dt in (2.5e-5, 5e-5, 1e-4)]
    status = {(r[0], float(r[1])): r[2] for r in rows}
    # eq. (19) rests at every dt; Verlet blows up at the paper's 1e-4 s (above its bound, README)
    assert [status["paper_eq19", dt] for dt in (2.5e-5, 5e-5, 1e-4)] == ["rest"] * 3
    assert status["velocity_verlet", 5e-5] == "rest" and status["velocity_verlet", 1e-4] == "unstable"


def test_pth_file_imports_dem_and_its_compare_from_any_folder(dem_module, tmp_path):
    """build/dem.pth is what scripts/build.sh installs into the site folder: read as a site
    folder's .pth, it makes this build's package dem importable (the engine module, and
    dem.compare from the checkout), and no top-level `compare`."""
    pth = package_dir().parent / "dem.pth"
    assert pth.exists(), "the build writes dem.pth"
    # -S: no site folders at start-up, so a dem.pth installed there by another checkout's build
    # cannot come first; Debian's packages (numpy) after this build's folder.
    code = (f"import site; site.addsitedir({str(pth.parent)!r}); site.addsitedir('/usr/lib/python3/dist-packages'); "
            "import dem, dem.compare, importlib.util; print(dem.Simulation.__module__); print(dem.__file__); "
            "print(dem.compare.__file__); print(importlib.util.find_spec('compare'))")
    proc = python(["-S", "-c", code], tmp_path)
    assert proc.returncode == 0, proc.stderr
    engine, dem_file, compare_file, top_level = proc.stdout.split()
    assert engine == "dem._engine" and Path(dem_file).parent == package_dir() / "dem"
    assert Path(compare_file).resolve() == REPO / "compare" / "__init__.py"
    assert top_level == "None", "the .pth puts no package named compare on the path"

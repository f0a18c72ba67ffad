"""`cmake --install` gives a dem that runs with the source tree gone: the Python package dem goes
to PREFIX/lib/python3.X/dist-packages/dem (its __init__.py, the engine module, and compare as a
link to the layer installed beside the scenes, PREFIX/share/dem/compare), and the installed dem's
Python processes (`dem compare`, `dem run --pictures`) import that package, not the checkout's.
A copy of build/dem elsewhere, neither installed nor the build's own, has no package and says so."""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
MARK = 'import os; os.environ.get("DEM_MARK") and print("dem.compare imported from", __file__)\n'


def site_dir(prefix: Path) -> Path:
    return prefix / "lib" / f"python{sys.version_info[0]}.{sys.version_info[1]}" / "dist-packages"


@pytest.mark.release_only
def test_the_installed_dem_runs_its_own_package(tmp_path, dem_binary):
    prefix = tmp_path / "prefix"
    p = subprocess.run(["cmake", "--install", str(Path(dem_binary).parent), "--prefix", str(prefix)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    share, package = prefix / "share" / "dem", site_dir(prefix) / "dem"
    assert (share / "compare" / "__main__.py").is_file() and (share / "reference_inputs" / "scenes").is_dir()
    assert (package / "__init__.py").is_file() and any(package.glob("_engine.*.so"))
    assert (package / "compare").is_symlink() and (package / "compare").resolve() == (share / "compare").resolve()
    with open(share / "compare" / "__init__.py", "a") as f:
        f.write(MARK)          # the installed copy says when it is the one imported
    env = {**os.environ, "DEM_MARK": "1"}
    env.pop("PYTHONPATH", None)
    dem = prefix / "bin" / "dem"
    h = subprocess.run([str(dem), "compare", "--help"], capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120)
    assert h.returncode == 0 and f"dem.compare imported from {package / 'compare' / '__init__.py'}" in h.stdout, \
        h.stdout + h.stderr
    r = subprocess.run([str(dem), "run", str(REPO / "examples" / "flat_silo.toml"), "--out", str(tmp_path / "run"),
                        "--quiet", "--pictures", "--set", "discharge.time=0.1"],
                       capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
    assert r.returncode == 0, r.stderr
    assert str(package / "compare") in r.stdout + r.stderr and (tmp_path / "run" / "frames.png").is_file()
    # A script with the installed package on its path: the engine, and the layer reading the
    # installed scenes
    code = ("import dem; from dem.compare.cases import common; "
            "print(dem.__file__, dem.Simulation.__module__, common.ROOT); "
            "s = dem.Simulation(dem.Scene(str(common.ROOT / 'reference_inputs/scenes/silo_17_18.toml'))); s.step(2)")
    py = subprocess.run([sys.executable, "-S", "-c", f"import sys; sys.path[:0] = [{str(site_dir(prefix))!r}, "
                         "'/usr/lib/python3/dist-packages']; " + code],
                        capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120)
    assert py.returncode == 0, py.stderr
    assert py.stdout.splitlines()[-1].split() == [str(package / "__init__.py"), "dem._engine", str(share.resolve())], \
        py.stdout
    v = subprocess.run([str(dem), "--version"], capture_output=True, text=True, env=env, timeout=60)
    assert v.stdout.splitlines()[1] == f"python package: {package}", v.stdout
    # the checkout's build keeps its own checkout's layer
    b = subprocess.run([str(dem_binary), "compare", "--help"], capture_output=True, text=True, env=env, timeout=120)
    assert b.returncode == 0 and "imported from" not in b.stdout


def test_a_copy_of_build_dem_elsewhere_says_it_has_no_package(tmp_path, dem_binary):
    copy = tmp_path / "bin" / "dem"
    copy.parent.mkdir()
    shutil.copy2(dem_binary, copy)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    c = subprocess.run([str(copy), "compare", "--help"], capture_output=True, text=True, env=env, timeout=60)
    assert c.returncode == 4 and "dem compare: dem's Python package (dem.compare) is not found for " + str(copy) \
        in c.stderr and "cmake --install" in c.stderr, c.stderr
    v = subprocess.run([str(copy), "--version"], capture_output=True, text=True, env=env, timeout=60)
    assert v.returncode == 0 and v.stdout.splitlines()[1].startswith("python package: none (dem's Python package"), v.stdout
    out = tmp_path / "run"
    r = subprocess.run([str(copy), "run", str(REPO / "examples" / "flat_silo.toml"), "--out", str(out), "--pictures"],
                       capture_output=True, text=True, env=env, timeout=60)
    assert r.returncode == 2 and "--pictures: dem's Python package (dem.compare) is not found" in r.stderr, r.stderr
    assert not out.exists(), "refused before writing anything"
    # its engine runs anywhere
    q = subprocess.run([str(copy), "run", str(REPO / "examples" / "flat_silo.toml"), "--out", str(out), "--quiet",
                        "--set", "discharge.time=0.02"], capture_output=True, text=True, env=env, timeout=120)
    assert q.returncode == 0, q.stderr

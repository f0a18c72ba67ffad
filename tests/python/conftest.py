"""Put this build's Python package dem (build/python: the engine module and dem.compare, linked
to this checkout's compare/) first on the path, so that tests import `dem.compare` from the
checkout under test and never another through a .pth file."""
import os
import sys
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]


def package_dir() -> Path:
    """The folder holding this build's package dem (ctest passes DEM_PYTHON_DIR; otherwise build/python)."""
    return Path(os.environ.get("DEM_PYTHON_DIR", REPO_ROOT / "build" / "python")).absolute()


if str(package_dir()) not in sys.path:
    sys.path.insert(0, str(package_dir()))
# and first on the path of every Python process a test starts (`python3 -m dem.compare ...`)
if os.environ.get("PYTHONPATH", "").split(os.pathsep)[0] != str(package_dir()):
    os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(package_dir()), os.environ.get("PYTHONPATH")) if p)

import subprocess

import pytest


@pytest.fixture(scope="session")
def dem_binary():
    """The engine built by CMake (ctest passes DEM_BINARY; otherwise build/dem)."""
    path = Path(os.environ.get("DEM_BINARY", REPO_ROOT / "build" / "dem"))
    if not path.exists():
        pytest.fail(f"dem binary not found at {path}: build first (cmake --build build)")
    return path


@pytest.fixture(scope="session")
def dem_module():
    """This build's package dem with its engine module dem._engine, imported from its build
    folder; skipped on builds without the module (sanitizers: DEM_NO_MODULE)."""
    if os.environ.get("DEM_NO_MODULE") == "1":
        pytest.skip("this build has no engine module (DEM_PYTHON_MODULE=OFF, or a sanitizer build)")
    where = package_dir() / "dem"
    if not any(where.glob("_engine.*.so")):
        pytest.fail(f"the engine module dem._engine is not built in {where}: build first (cmake --build build)")
    import dem
    assert Path(dem.__file__).parent == where, dem.__file__
    return dem


@pytest.fixture
def run_dem(dem_binary):
    """Runs `dem ARGS...` and returns the CompletedProcess (text output)."""
    def run(*args, timeout=300):
        return subprocess.run([str(dem_binary), *map(str, args)], capture_output=True, text=True, timeout=timeout)
    return run


def pytest_configure(config):
    config.addinivalue_line("markers", "reference_codes: runs LIGGGHTS, YADE or LAMMPS; their runs are most of "
                            "its time, and the sanitizer build's run leaves it out")
    config.addinivalue_line("markers", "release_only: checks what the release build gives (a study's figures, an "
                            "installed copy, Python's pools and drawing, scenes of 100k discs and more) through "
                            "engine runs whose code paths shorter tests also step; the sanitizer build's run "
                            "leaves it out")


# The modules whose tests drive the engine's own code paths: its reader and --set, its command
# line, its phases, outputs, checkpoints, signals and threads. The other modules drive the
# comparison layer's Python through the engine (translations, verdicts, pictures, studies); the
# engine paths they step are these modules' too, so a sanitized engine adds nothing there.
SANITIZED_MODULES = {"test_atomic_outputs", "test_checkpoint", "test_cli", "test_corpus", "test_disc_order",
                     "test_discharge", "test_ensemble", "test_run_outputs", "test_run_records", "test_scene_set",
                     "test_scene_toml", "test_scene_validation", "test_shear", "test_speed_settled",
                     "test_thread_counts", "test_units", "test_vtu_binary"}


def pytest_collection_modifyitems(config, items):
    """DEM_ENGINE_TESTS_ONLY=1 (the sanitizer build's run): keep the tests of SANITIZED_MODULES
    that run the engine (those using the dem_binary fixture, directly or through another
    fixture), less those marked reference_codes (their time goes to the reference codes' runs,
    which a sanitized engine does not change) or release_only."""
    if os.environ.get("DEM_ENGINE_TESTS_ONLY") != "1":
        return
    keep = [item for item in items if "dem_binary" in getattr(item, "fixturenames", ())
            and Path(str(item.fspath)).stem in SANITIZED_MODULES
            and item.get_closest_marker("reference_codes") is None and item.get_closest_marker("release_only") is None]
    config.hook.pytest_deselected(items=[item for item in items if item not in keep])
    items[:] = keep

"""Make the repository root importable, so tests can `import compare.figures`."""
import sys
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
if str(REPO_ROOT) not in sys.path:
    sys.path.insert(0, str(REPO_ROOT))

import os
import subprocess

import pytest


@pytest.fixture(scope="session")
def dem_binary():
    """The engine built by CMake (ctest passes DEM_BINARY; otherwise build/dem)."""
    path = Path(os.environ.get("DEM_BINARY", REPO_ROOT / "build" / "dem"))
    if not path.exists():
        pytest.fail(f"dem binary not found at {path}: build first (cmake --build build)")
    return path


def module_dir() -> Path:
    """Where this build's module dem is (ctest passes DEM_MODULE_DIR; otherwise build/python)."""
    return Path(os.environ.get("DEM_MODULE_DIR", REPO_ROOT / "build" / "python"))


@pytest.fixture(scope="session")
def dem_module():
    """This build's Python module dem, imported from its build folder (never another checkout's
    through a .pth file); skipped on builds without it (sanitizers: DEM_NO_MODULE)."""
    if os.environ.get("DEM_NO_MODULE") == "1":
        pytest.skip("this build has no Python module (DEM_PYTHON_MODULE=OFF, or a sanitizer build)")
    where = module_dir()
    if not any(where.glob("dem.*.so")):
        pytest.fail(f"the module dem is not built in {where}: build first (cmake --build build)")
    sys.path.insert(0, str(where))
    import dem
    assert Path(dem.__file__).parent.resolve() == where.resolve(), dem.__file__
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

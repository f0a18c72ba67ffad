"""dem: the 2D discrete-element engine of Kiyama & Fujimura's silo (docs/python.md) and its
comparison layer with LIGGGHTS, YADE and LAMMPS, ``dem.compare`` (docs/compare.md).

The engine's names (Scene, Simulation, load, SceneError, __version__, ...) are those of the
extension ``dem._engine`` (pybind11, engine/python), loaded on first use: ``dem.compare`` does not
load it, and works in a build without it (``-DDEM_PYTHON_MODULE=OFF``, sanitizer builds), where
the engine's names say why they are missing.
"""
import importlib


def _load_engine():
    try:
        return importlib.import_module("dem._engine")
    except ModuleNotFoundError as e:
        if e.name != "dem._engine":
            raise
        return None


def __getattr__(name):
    if name.startswith("__") and name != "__version__":
        raise AttributeError(name)
    engine = _load_engine()
    if engine is None:
        raise AttributeError(f"dem.{name}: this build of dem has no engine module (dem._engine): it was configured "
                             "with DEM_PYTHON_MODULE=OFF or with sanitizers; dem.compare works without it")
    try:
        value = getattr(engine, name)
    except AttributeError:
        raise AttributeError(f"module 'dem' has no attribute {name!r}") from None
    globals()[name] = value
    return value


def __dir__():
    engine = _load_engine()
    return sorted(set(globals()) | set(dir(engine) if engine else ()))

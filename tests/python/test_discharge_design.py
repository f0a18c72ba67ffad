"""A discharge compared from the native engine's rested packing (--start frozen) and its flow rate
over the steady window (study.steady_flow_rate)."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

from dem.compare.verdict import pipeline, study
from dem.compare.cases import plan as plan_mod
from dem.compare.cases.common import Case, Result, failed

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(autouse=True)
def _engine(dem_binary, monkeypatch):
    monkeypatch.setenv("DEM_BINARY", str(dem_binary))


def _small_silo(tmp_path) -> Path:
    """A 40-disc silo written by the design silos' own generator (scripts/make_design_silos.py)."""
    spec = importlib.util.spec_from_file_location("make_design_silos", ROOT / "scripts" / "make_design_silos.py")
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    d = dict(n=40, width=12.0, slit=4.0, flow=0.2, fill_time=1.5)
    xyr = gen.fill(d["n"], d["width"], seed=1)
    (tmp_path / "small_fill.csv").write_text("x,y,r\n" + "".join(f"{x:.4f},{y:.4f},{r:.4f}\n" for x, y, r in xyr))
    scene = tmp_path / "small.toml"
    scene.write_text(gen.scene_text("small", d, "small_fill.csv", float(np.ceil(xyr[:, 1].max() + 4))))
    return scene


def _plan(scene, start="frozen", settle=0.0):
    o = plan_mod.Options(members=3, start=start, settle=settle, perturb=1e-3)
    return plan_mod.make_plan(plan_mod.Entry(scene, o))


def test_frozen_discharge_members_start_alike_in_every_code_from_the_rested_packing(tmp_path, monkeypatch):
    scene = _small_silo(tmp_path)
    plan = _plan(scene)
    assert plan.settle == plan_mod.FROZEN_DISCHARGE_SETTLE          # a short settle after the jitter
    assert _plan(scene, start="scene").settle == 1.0                 # the scene's start fills itself
    assert _plan(scene, settle=0.2).settle == 0.2
    pack = pipeline.discharge_start(plan, tmp_path / "out")
    assert (tmp_path / "out" / "frozen.npy").exists()
    scene_start = plan_mod.start_discs(plan.shared)
    # the fill fell and rested: every disc moved down from its grid site, the velocities are zeroed
    assert np.all(pack[:, 1] < scene_start[:, 1] - 0.05) and np.all(pack[:, 3:] == 0.0)
    np.testing.assert_array_equal(pack[:, 2], scene_start[:, 2])    # the scene's disc order
    seen = {}

    def record(code, case, plan, out, mutation=None):
        seen[(code, case.seed)] = (np.array(case.discs), case.settle)
        return failed(code, case.name, "not run")
    monkeypatch.setattr(pipeline, "run_one", record)
    pipeline.ensemble_runs(plan, ("native", "liggghts", "yade"), tmp_path / "out", start=pack)
    for k in range(3):
        a, settle = seen[("native", k)]
        for c in ("liggghts", "yade"):
            np.testing.assert_array_equal(seen[(c, k)][0], a)       # member k alike in every code
        assert settle == plan_mod.FROZEN_DISCHARGE_SETTLE
        off = a[:, :2] - pack[:, :2]
        assert 0 < np.abs(off).max() <= 1e-3 and np.all(a[:, 2:] == pack[:, 2:])
    assert np.abs(seen[("native", 0)][0] - seen[("native", 1)][0]).max() > 0   # members differ by the jitter


def test_the_frozen_packing_is_at_rest(tmp_path):
    """The packing, unjittered, run for a member's settle in the native engine: the discs stay
    where they are, to within the jitter of a member."""
    from dem.compare.codes import native_backend
    scene = _small_silo(tmp_path)
    plan = _plan(scene)
    pack = pipeline.frozen_packing(plan, tmp_path / "out")
    case = Case(name="rest", resolved=plan.shared, discs=pack, dt=plan.dt, duration=plan.settle,
                materials=plan_mod.scene_material_index(plan.shared))
    res = native_backend.run(case, tmp_path / "rest", 120)
    assert res.ok, res.reason
    moved = np.abs(np.array(res.discs_end, float)[:, :2] - pack[:, :2]).max()
    assert moved < plan.perturb, moved


def _removals(rate, t0, t1, transient, seed=0):
    """Removal times: a burst of ``transient`` removals in the first 0.06 s after the opening (the
    discs over the slit falling at once), then a steady flow of ``rate`` discs/s from 0.06 s on,
    each removal jittered by a tenth of its interval."""
    rng = np.random.default_rng(seed)
    burst = np.sort(rng.uniform(0.03, 0.06, transient))
    steady = np.arange(0.06, t1, 1.0 / rate)
    steady = steady + rng.uniform(-0.1, 0.1, len(steady)) / rate
    return np.concatenate([burst, steady])


def test_steady_flow_rate_recovers_a_known_rate_and_leaves_the_transient_out():
    t = _removals(200.0, 0.1, 1.0, transient=60)
    got = study.steady_flow_rate(t, 0.1, 1.0)
    assert got == pytest.approx(200.0, rel=0.01)
    # the transient counts when the window starts before it: the slope over all removals is off
    assert abs(study.steady_flow_rate(t, 0.0, 1.0) - 200.0) > 0.05 * 200.0
    # the window's end: removals after it do not count
    late = np.concatenate([t, np.linspace(1.01, 1.2, 200)])
    assert study.steady_flow_rate(late, 0.1, 1.0) == pytest.approx(got, rel=1e-12)
    # too few removals in the window: no rate (a jam, judged by the jam fraction)
    assert np.isnan(study.steady_flow_rate(t[t < 0.13], 0.1, 1.0))


def test_discharge_measures_take_the_flow_rate_over_the_flow_window():
    scene = ROOT / "reference_inputs" / "scenes" / "discharge_11_12.toml"
    case = study.discharge_case(scene, 2.5e-5, 1.0, 0.8, 0, 0.0)
    t = _removals(150.0, study.FLOW_START, 0.8, transient=25, seed=3)
    res = Result(code="x", case=case.name, removals=list(t), n_final=100)
    m = study.discharge_measures(res, case)
    assert m["discs_out"] == len(t)
    assert m["flow_rate"] == pytest.approx(study.steady_flow_rate(t, *study.flow_window(case)), rel=1e-12)
    assert m["flow_rate"] == pytest.approx(150.0, rel=0.02)


def test_the_committed_design_silos_are_the_generator_s():
    import subprocess
    import sys
    p = subprocess.run([sys.executable, str(ROOT / "scripts" / "make_design_silos.py"), "--check"],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr

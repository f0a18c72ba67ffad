"""velocity_verlet_onset through the work-precision study's own path (benchmarks/work_precision.py):
a 3-point dt sweep of the shared-law head-on collision against the closed form measures order 2
(velocity Verlet: 1), and targets() reads the dt of an error goal off a code's error curve
(checked on curves made from formulas)."""
import math
import sys
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO_ROOT / "benchmarks"))
import common_study as cs  # noqa: E402
import work_precision as wp  # noqa: E402

# A study's sweep of many runs, judged in Python; the engine paths it steps are the shorter tests'
# (sanitizer: release only).
pytestmark = pytest.mark.release_only

DTS = [2e-6, 4e-6, 8e-6]     # dt / t_c = 0.003 ... 0.012


@pytest.fixture(scope="module")
def sweep(dem_binary, tmp_path_factory):
    cs.setup_binary(str(dem_binary))
    setup = wp.collision_setup()["disc_disc_head_on"]
    out = tmp_path_factory.mktemp("onset")
    return {s: [wp.collision_point("native", s, "shared", "disc_disc_head_on", setup, dt, 4, 2e-3, out) for dt in DTS]
            for s in ("velocity_verlet", wp.ONSET)}


def test_onset_is_second_order_verlet_first(sweep):
    want = {"velocity_verlet": (0.7, 1.4), wp.ONSET: (1.7, 2.3)}
    for scheme, ps in sweep.items():
        assert all(p["ok"] for p in ps), [p["failure"] for p in ps]
        order, n, _ = cs.fit_order(DTS, [p["error"] for p in ps])
        assert n == 3 and want[scheme][0] < order < want[scheme][1], (scheme, order)
    for pv, po in zip(sweep["velocity_verlet"], sweep[wp.ONSET]):
        assert po["error"] < pv["error"] / 5


def test_targets_reads_the_goal_off_each_curve():
    # error = c (dt / t)^p exactly, so the dt of a goal is t (goal / c)^(1/p)
    dur, t = 2e-3, 7e-4
    curves = {("native", wp.ONSET): (30.0, 2.0, 1e-7), ("native", "velocity_verlet"): (1.0, 1.0, 1e-7),
              ("liggghts", "velocity_verlet"): (1.0, 1.0, 1e-5)}
    pts = [{"case": "disc_disc_head_on", "law": "shared", "ok": True, "code": code, "scheme": scheme, "dt": dt,
            "error": c * (dt / t) ** p, "loop_s": step * dur / dt}
           for (code, scheme), (c, p, step) in curves.items() for dt in (1e-6, 2e-6, 5e-6, 1e-5, 2e-5, 5e-5)]
    # below a curve's finest point (Verlet at 0.1 %: 7e-7 s) targets() extrapolates at its measured order
    orders = [{"problem": "collision disc_disc_head_on (shared law)", "measure": "e", "code": code, "scheme": scheme,
               "order": p} for (code, scheme), (c, p, step) in curves.items()]
    res = {"config": {"collision_duration": dur}, "collision": {"points": pts}, "orders": orders}
    rows = {(r["who"], r["goal"]): r for r in wp.targets(res)}
    for who, (c, p, step) in ((wp.ONSET, curves[("native", wp.ONSET)]),
                              ("velocity_verlet", curves[("native", "velocity_verlet")]),
                              ("liggghts", curves[("liggghts", "velocity_verlet")])):
        for goal in (0.01, 0.001):
            r = rows[(who, goal)]
            assert r["dt"] == pytest.approx(t * (goal / c) ** (1 / p), rel=1e-9)
            assert r["loop_s"] == pytest.approx(step * dur / r["dt"], rel=1e-9)
    lig, on = rows[("liggghts", 0.001)], rows[(wp.ONSET, 0.001)]
    assert on["liggghts_over_this"] == pytest.approx(lig["loop_s"] / on["loop_s"], rel=1e-12)

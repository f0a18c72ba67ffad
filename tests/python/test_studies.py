"""Smoke test of the work-precision and stability studies (benchmarks/): a 3-point dt
sweep of the head-on collision measures the convergence order of each scheme against the
closed-form damped oscillator, and the closed form agrees with compare/'s RK4 ODE. A few
seconds; the full studies are run by hand (benchmarks/README.md)."""
import math
import sys
from pathlib import Path

import numpy as np
import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO_ROOT / "benchmarks"))
import common_study as cs  # noqa: E402
import work_precision as wp  # noqa: E402

# A study's sweep of many runs, judged in Python; the engine paths it steps are the shorter tests'
# (sanitizer: release only).
pytestmark = pytest.mark.release_only

DTS = [2e-6, 4e-6, 8e-6]     # dt / t_c = 0.003 ... 0.012: the asymptotic range
PHASES = 4


@pytest.fixture(scope="module")
def sweep(dem_binary, tmp_path_factory):
    cs.setup_binary(str(dem_binary))
    setup = wp.collision_setup()["disc_disc_head_on"]
    out = tmp_path_factory.mktemp("studies")
    pts = {}
    for scheme in cs.SCHEMES:
        pts[scheme] = [wp.collision_point("native", scheme, "paper", "disc_disc_head_on", setup, dt, PHASES, 2e-3, out)
                       for dt in DTS]
    return setup, pts


def test_closed_form_matches_compare_ode(sweep):
    setup, _ = sweep
    ref, rk4 = setup["refs"]["shared"], setup["rk4_shared"]
    assert abs(ref["e"] - rk4["e"]) < 1e-4
    assert abs(ref["t_c"] - rk4["t_c"]) < 2e-8      # RK4 steps of dt/1000 = 1e-8 s
    paper = setup["refs"]["paper"]
    z = paper["zeta"]
    assert z == pytest.approx(0.3, rel=1e-9)        # calibration.ZETA
    # The clamped (shared) law ends the contact earlier and rebounds more elastically.
    assert ref["e"] > paper["e"] and ref["t_c"] < paper["t_c"]


def test_every_scheme_is_first_order_on_the_collision(sweep):
    _, pts = sweep
    for scheme, ps in pts.items():
        assert all(p["ok"] for p in ps), [p["failure"] for p in ps]
        order, n, _ = cs.fit_order(DTS, [p["error"] for p in ps])
        assert n == 3
        assert 0.7 < order < 1.3, (scheme, order, [p["error"] for p in ps])
        # error about 1-4 dt/t_c in e: first order with an O(1) constant
        t_c = 6.91e-4
        for p in ps:
            assert 0.2 * p["dt"] / t_c < p["error"] < 10 * p["dt"] / t_c, (scheme, p["dt"], p["error"])


def test_eq19_costs_accuracy_and_verlet_moves_like_eq18(sweep):
    _, pts = sweep
    for p18, p19, pvv in zip(pts["paper_eq18"], pts["paper_eq19"], pts["velocity_verlet"]):
        assert p19["error"] > 1.5 * p18["error"]
        # Same increments du = v dt: identical collisions up to round-off.
        assert np.allclose(pvv["e"], p18["e"], rtol=1e-9, atol=0)
        assert np.allclose(pvv["t_c"], p18["t_c"], rtol=1e-9, atol=0)
    assert not math.isnan(pts["paper_eq18"][0]["loop_s"])

"""The ensemble Janssen analysis (compare/janssen.py): the weighted fit recovers known parameters
from synthetic noisy Janssen profiles within its 95 % intervals, at about the nominal rate; K and
mu_w,eff follow validation.md's formulas; the r^2 gate; wrong profiles (hydrostatic, mu_w
changed) fail the comparison; the member checks catch a broken force balance. Every expected
value is computed here from the Janssen formulas, none comes from a simulation."""
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from compare import janssen

ROOT = Path(__file__).resolve().parents[2]

# A 2D slab like the column scene: W = 20 cm, rho_b = phi rho_s, g; K and mu_w give p_inf, lambda.
W, RHO_S, PHI, G = 20.0, 2.65, 0.80, 980.0
RHO_B = PHI * RHO_S


def janssen_truth(K=0.9, mu=0.25, z0=0.5):
    return {"p_inf": RHO_B * G * W / (2 * mu), "lambda": W / (2 * K * mu), "z0": z0, "K": K, "mu_w_eff": mu}


def synthetic_members(truth, n=8, noise=0.25, seed=1, surface=129.4, top=240.0, bin_=2.0, floor=0.0,
                      profile=None):
    """Members in the form compare.janssen_column writes: side-wall pressure per 2 cm bin against
    height, each bin with independent multiplicative noise of relative size ``noise``."""
    rng = np.random.default_rng(seed)
    s_lo = np.arange(0.0, top, bin_)
    y_hi, y_lo = top - s_lo, top - s_lo - bin_
    out = []
    for _ in range(n):
        surf = surface + rng.normal(0, 0.2)
        z = surf - 0.5 * (y_lo + y_hi)
        p = (profile(z) if profile else janssen.model(z, truth["p_inf"], truth["lambda"], truth["z0"]))
        p = np.where(z > 0, p * (1 + noise * rng.standard_normal(len(z))), 0.0)
        out.append({"y_lo": y_lo.tolist(), "y_hi": y_hi.tolist(), "p": p.tolist(), "surface": surf,
                    "floor": floor, "width": W, "phi": PHI + rng.normal(0, 0.002), "rho_s": RHO_S, "g": G,
                    "mu_w": 0.5, "balance": 0.0, "mobilised_upper": truth["mu_w_eff"],
                    "mobilised_all": truth["mu_w_eff"], "max_overlap_ratio": 0.0})
    return out


def test_fit_recovers_known_parameters_within_its_intervals():
    truth = janssen_truth()
    rng = np.random.default_rng(3)
    z = np.arange(3.0, 120.0, 6.0)
    sigma = 0.03 * truth["p_inf"] * np.ones_like(z)
    p = janssen.model(z, truth["p_inf"], truth["lambda"], truth["z0"]) + sigma * rng.standard_normal(len(z))
    f = janssen.derived_ci(janssen.fit_ci(z, p, sigma), RHO_B, 0.0, G, W)
    assert f["r2"] >= janssen.R2_MIN
    for k in janssen.FIT_KEYS:
        assert abs(f[k] - truth[k]) <= f["ci"][k], (k, f[k], truth[k], f["ci"][k])
        # the intervals say something: within half the value (z0: within one 6 cm fit bin)
        assert f["ci"][k] < (6.0 if k == "z0" else 0.5 * truth[k]), (k, f["ci"][k])


def test_intervals_cover_the_truth_at_about_the_nominal_rate():
    truth = janssen_truth()
    rng = np.random.default_rng(11)
    z = np.arange(3.0, 120.0, 6.0)
    sigma = 0.04 * truth["p_inf"] * (0.3 + z / z.max())        # unequal errors, as in the column
    exact = janssen.model(z, truth["p_inf"], truth["lambda"], truth["z0"])
    trials, hits = 300, {k: 0 for k in ("p_inf", "lambda", "z0", "K", "mu_w_eff")}
    for _ in range(trials):
        f = janssen.derived_ci(janssen.fit_ci(z, exact + sigma * rng.standard_normal(len(z)), sigma),
                               RHO_B, 0.0, G, W)
        for k in hits:
            hits[k] += abs(f[k] - truth[k]) <= f["ci"][k]
    for k, h in hits.items():
        # nominal 0.95; 300 trials give a binomial spread of about 0.013; the reduced-chi^2
        # widening makes the intervals slightly conservative
        assert 0.90 <= h / trials <= 0.995, (k, h / trials)


@pytest.mark.parametrize("mu", [0.25, 0.12])   # lambda 44 cm (saturates) and 93 cm (as the column)
def test_ensemble_fit_recovers_K_and_mu_w_from_noisy_members(mu):
    truth = janssen_truth(K=0.9, mu=mu)
    f = janssen.ensemble_fit(synthetic_members(truth, noise=0.3, seed=5), merge=3)
    assert f["profile"]["members"] == 8
    assert min(f["profile"]["z"]) > 0 and max(f["profile"]["z"]) < 129.4 - W / 2
    assert f["r2"] >= janssen.R2_MIN
    for k in janssen.FIT_KEYS:
        assert abs(f[k] - truth[k]) <= f["ci"][k], (k, f[k], truth[k], f["ci"][k])


def test_same_physics_agrees_and_r2_gate_refuses_a_noise_fit():
    truth = janssen_truth()
    fits = [janssen.ensemble_fit(synthetic_members(truth, noise=0.2, seed=s), merge=3) for s in range(40)]
    agree = [janssen.compare_fits(fits[i], fits[i + 1])["agree"] for i in range(0, 40, 2)]
    # five 95 % tests on correlated parameters: the whole comparison passes in most pairs
    assert np.mean(agree) >= 0.75, agree
    a = fits[0]
    noisy = janssen.ensemble_fit(synthetic_members(truth, noise=3.0, seed=3), merge=3)
    assert noisy["r2"] < janssen.R2_MIN
    c = janssen.compare_fits(a, noisy)
    assert not c["r2_ok"] and not c["agree"]


def test_mu_w_changed_fails_the_comparison():
    ref = janssen.ensemble_fit(synthetic_members(janssen_truth(mu=0.25), noise=0.2, seed=1), merge=3)
    wrong = janssen.ensemble_fit(synthetic_members(janssen_truth(mu=0.30), noise=0.2, seed=2), merge=3)
    assert ref["r2"] >= janssen.R2_MIN and wrong["r2"] >= janssen.R2_MIN
    c = janssen.compare_fits(ref, wrong)
    assert not c["agree"]
    assert not c["params"]["mu_w_eff"]["agree"] and not c["params"]["p_inf"]["agree"]


def test_hydrostatic_profile_fails_the_comparison():
    truth = janssen_truth()
    ref = janssen.ensemble_fit(synthetic_members(truth, noise=0.2, seed=1), merge=3)
    # no wall friction: p = K rho_b g z, no saturation
    hydro = synthetic_members(truth, noise=0.2, seed=2, profile=lambda z: truth["K"] * RHO_B * G * z)
    try:
        f = janssen.ensemble_fit(hydro, merge=3)
    except RuntimeError:          # curve_fit may find no saturation at all: that is a failure too
        return
    assert not janssen.compare_fits(ref, f)["agree"]


def test_member_checks_catch_a_broken_balance():
    truth = janssen_truth()
    ms = synthetic_members(truth, seed=1)
    assert janssen.member_checks(ms)["balance_ok"]
    ms[3]["balance"] = 0.05           # floor force + wall friction 5 % off the weight
    assert not janssen.member_checks(ms)["balance_ok"]


def test_confidence_band_contains_the_fit_and_widens_without_data():
    truth = janssen_truth()
    f = janssen.ensemble_fit(synthetic_members(truth, noise=0.2, seed=1), merge=3)
    z = np.linspace(5, 300, 50)
    m, lo, hi = janssen.band(f, z)
    assert np.all(lo <= m) and np.all(m <= hi)
    assert (hi - lo)[-1] > (hi - lo)[10]      # extrapolation beyond the profile is less certain


def test_scene_generator_is_up_to_date():
    p = subprocess.run([sys.executable if sys.executable else "/usr/bin/python3",
                        str(ROOT / "scripts" / "make_janssen_scene.py"), "--check"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    text = (ROOT / "reference_inputs" / "scenes" / "janssen_column_loose.csv").read_text().splitlines()[1:]
    d = np.array([[float(v) for v in line.split(",")] for line in text])
    r = d[:, 2]
    assert r.min() >= 0.4 and r.max() <= 0.6                   # 0.8-1.2 x the mean radius 0.5 cm
    assert abs(r.mean() - 0.5) < 0.01 and W >= 20 * 2 * 0.5       # W >= 20 mean diameters
    # the packed fill (about 0.8 of the area) is at least 6 W deep
    assert np.sum(math.pi * r ** 2) / (0.84 * W) >= 6 * W


def test_small_ensembles_use_the_pooled_scatter_and_still_cover_the_truth():
    truth = janssen_truth()
    hits, trials = 0, 40
    for s in range(trials):
        f = janssen.ensemble_fit(synthetic_members(truth, n=2, noise=0.1, seed=100 + s), merge=3)
        assert f["profile"]["sigma"] == "pooled"
        hits += all(abs(f[k] - truth[k]) <= f["ci"][k] for k in ("p_inf", "lambda"))
    assert hits / trials >= 0.8, hits / trials
    assert janssen.ensemble_profile(synthetic_members(truth, n=8), sigma="auto")["sigma"] == "bin"
    with pytest.raises(ValueError):
        janssen.ensemble_profile(synthetic_members(truth, n=2), sigma="median")


# ------------------------------------------------------------------ the column's members

@pytest.fixture
def column(dem_binary, monkeypatch):
    monkeypatch.setenv("DEM_BINARY", str(dem_binary))
    from compare import janssen_column
    return janssen_column, janssen_column.resolved_scene()


def test_member_starts_are_seeded_jittered_and_apart(column):
    jc, r = column
    base = np.array(r["discs"], float)
    a, a2, b = jc.member_start(r, 0), jc.member_start(r, 0), jc.member_start(r, 1)
    assert np.array_equal(a, a2) and not np.array_equal(a, b)
    assert np.max(np.abs(a[:, :2] - base[:, :2])) <= jc.JITTER
    assert np.max(np.abs(a[:, :2] - base[:, :2])) > 0.9 * jc.JITTER
    geo = jc.geometry(r)
    assert jc.max_overlap_ratio(a, geo["width"], geo["floor"]) == 0.0   # every disc apart


def test_max_overlap_ratio_and_floor_cut(column):
    jc, _ = column
    d = np.array([[5.0, 5.0, 0.5, 0, 0, 0], [5.99, 5.0, 0.5, 0, 0, 0], [10.0, 0.395, 0.4, 0, 0, 0]])
    # pair: overlap 0.01 cm over r 0.5 = 0.02; floor: 0.005 cm over r 0.4 = 0.0125
    assert jc.max_overlap_ratio(d, 20.0, 0.0) == pytest.approx(0.02, abs=1e-12)
    assert jc.max_overlap_ratio(d[2:], 20.0, 0.0) == pytest.approx(0.0125, abs=1e-12)
    cut = jc.cut_floor_layer(np.vstack([d, [[3.0, 1.2, 0.5, 1, 1, 1]]]), 0.0)
    assert len(cut) == 3 and np.all(cut[:, 3:] == 0)        # the disc touching the floor is taken away
    assert 0.395 not in cut[:, 1] and 1.2 in cut[:, 1]      # one resting 0.2 cm above it is kept


def test_member_record_balance_and_mobilised_friction(column):
    from compare.common import Result
    jc, r = column
    geo = jc.geometry(r)
    discs = np.array([[10.0, 50.0 + k, 0.5, 0, 0, 0] for k in range(40)])
    weight = float(np.sum(geo["rho_s"] * math.pi * discs[:, 2] ** 2) * geo["g"])
    n_bins = 120
    prof = lambda normal, shear: {"s_lo": list(np.arange(n_bins) * 2.0), "s_hi": list(np.arange(1, n_bins + 1) * 2.0),
                                  "normal": list(normal), "shear": list(shear)}
    normal = np.full(n_bins, 1000.0)
    shear = 0.3 * normal                                   # every bin at 0.3 of its normal force
    friction = 2 * shear.sum()
    good = Result(code="x", case="c", discs_end=discs.tolist(),
                  profiles={"left": prof(normal, shear), "right": prof(normal, shear),
                            "bottom": {"s_lo": [0.0], "s_hi": [20.0], "normal": [weight - friction], "shear": [0.0]}})
    rec = jc.member_record(r, good, "x", 0, 1.0)
    assert rec["balance"] == pytest.approx(0.0, abs=1e-12)
    assert rec["mobilised_upper"] == pytest.approx(0.3) and rec["mobilised_all"] == pytest.approx(0.3)
    assert rec["p"][0] == pytest.approx(500.0)            # mean of both walls per cm of wall
    good.profiles["bottom"]["normal"] = [weight - 0.5 * friction]   # half the friction missing
    assert jc.member_record(r, good, "x", 0, 1.0)["balance"] == pytest.approx(0.5 * friction / weight)

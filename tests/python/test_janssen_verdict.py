"""The Janssen column's judged statistics (compare/verdict/pipeline.py janssen_metrics, compare/cases/janssen.py
saturated_mu, deep_top and jackknife_fits), on synthetic members (no simulation, seconds): two
codes of the same physics agree on K, lambda, mu_w,eff and the deep half's mu_w,eff with paired
intervals inside the 10 % margin; a disc-wall friction x 0.8 in one code (p_inf x 1.25, lambda x
1.25) disagrees by mu_w,eff; every judged metric carries its verdict, margin and intervals; a
profile Janssen's law does not fit (janssen.goodness_of_fit) leaves the fitted parameters
inconclusive, with why, and the deep half still judged."""
import types

import numpy as np
import pytest

from dem.compare.cases import janssen
from dem.compare.verdict import pipeline, verdict
from dem.compare.cases.plan import Options

# A column like scripts/make_janssen_scene.py's (W = 8 cm, a fill 3 lambda deep), mu_w,eff = 0.1.
W, RHO_S, PHI, G = 8.0, 2.65, 0.78, 980.0
RHO_B = PHI * RHO_S


def members(mu=0.1, K=0.7, n=16, noise=0.1, seed=1, surface=178.0, common=None):
    """Member records as compare.janssen.member_record writes them: side-wall pressure per 1 cm
    bin of a 190 cm wall, Janssen's profile times independent bin noise and a member-wide factor
    (the member-to-member spread of a real column's force chains); ``common``: the member-wide
    factors (shared by member k of two codes: paired starts)."""
    rng = np.random.default_rng(seed)
    p_inf, lam = RHO_B * G * W / (2 * mu), W / (2 * K * mu)
    top, bin_ = 190.0, 1.0
    s_lo = np.arange(0.0, top, bin_)
    y_hi, y_lo = top - s_lo, top - s_lo - bin_
    fac = common if common is not None else 1 + 0.05 * rng.standard_normal(n)
    out = []
    for k in range(n):
        surf = surface + rng.normal(0, 0.2)
        z = surf - 0.5 * (y_lo + y_hi)
        p = janssen.model(z, p_inf, lam, 0.5) * fac[k] * (1 + noise * rng.standard_normal(len(z)))
        out.append({"status": "ok", "y_lo": y_lo.tolist(), "y_hi": y_hi.tolist(),
                    "p": np.where(z > 0, p, 0.0).tolist(), "surface": surf, "floor": 0.0, "width": W,
                    "phi": PHI + rng.normal(0, 0.002), "rho_s": RHO_S, "g": G, "mu_w": 0.5, "balance": 0.0,
                    "mobilised_upper": mu, "mobilised_all": mu, "max_overlap_ratio": 0.0})
    return out


def judged(ra, rb, profile="quick", unfit=False):
    plan = types.SimpleNamespace(name="janssen_column", options=Options(kind="janssen", profile=profile))
    fa, fb = janssen.ensemble_fit(ra), janssen.ensemble_fit(rb)
    for f in (fa, fb):                  # as pipeline.janssen_column gates each code's fit
        f["gof"] = janssen.goodness_of_fit(f)
        assert f["gof"]["ok"], f["gof"]
    if unfit:                           # a profile the law does not fit, as the gate sees it
        fa["gof"] = dict(fa["gof"], p=0.001, ok=False)
    ms = pipeline.janssen_metrics(plan, fa, fb, "liggghts", ra, rb)
    verdict.finalize(ms)
    return {m["metric"].split(" (")[0]: m for m in ms}


def test_the_same_physics_agrees_with_paired_intervals_inside_the_margin():
    common = 1 + 0.05 * np.random.default_rng(7).standard_normal(16)
    ms = judged(members(seed=1, common=common), members(seed=2, common=common))
    assert set(ms) == {"Janssen K", "Janssen lambda", "Janssen mu_w_eff",
                       "Janssen mu_w_eff of the deep half, member by member"}
    for name, m in ms.items():
        assert m["kind"] == "statistical" and m["margin_kind"] == "janssen" and m["margin"] == 0.10, name
        assert m["stat"]["design"] == "paired" and m["stat"]["df"] == 15, name
        assert m["verdict"] == "agree", (name, m["ci"])
        assert -0.10 <= m["ci"][0] < m["ci"][1] <= 0.10
        lo, hi = m["ci_disagree"]
        assert lo < m["ci"][0] and m["ci"][1] < hi                 # the split interval is the wider
    sat = ms["Janssen mu_w_eff of the deep half, member by member"]
    assert sat["values"]["bins"] >= 8 and sat["values"]["y_top"] == pytest.approx((178.0 + W / 2) / 2, abs=0.5)


def test_disc_wall_friction_x08_disagrees_by_mu_w_eff():
    """mu_w,eff x 0.8: p_inf and lambda x 1.25; the saturated pressure's mu_w,eff is 20 % lower."""
    common = 1 + 0.05 * np.random.default_rng(7).standard_normal(16)
    ms = judged(members(seed=1, common=common), members(mu=0.8 * 0.1, seed=2, common=common))
    sat = ms["Janssen mu_w_eff of the deep half, member by member"]
    assert sat["verdict"] == "disagree", sat["ci_disagree"]
    # Janssen's profile over the lower half (1.5-3 lambda deep): p_deep x 1.16, mu_w,eff -14 %
    assert sat["ci_disagree"][1] < -0.10 and -0.2 < sat["stat"]["estimate"] < -0.1
    assert ms["Janssen mu_w_eff"]["verdict"] == "disagree"
    assert ms["Janssen lambda"]["stat"]["estimate"] > 0.1             # lambda x 1.25


def test_a_profile_the_law_does_not_fit_leaves_the_fits_inconclusive_and_the_deep_half_judged():
    common = 1 + 0.05 * np.random.default_rng(7).standard_normal(16)
    ms = judged(members(seed=1, common=common), members(mu=0.08, seed=2, common=common), unfit=True)
    for k in ("K", "lambda", "mu_w_eff"):
        assert ms[f"Janssen {k}"]["verdict"] == "inconclusive" and "goodness of fit" in ms[f"Janssen {k}"]["note"]
    sat = ms["Janssen mu_w_eff of the deep half, member by member"]
    assert sat["verdict"] == "disagree" and sat["margin"] == 0.10


def test_the_jackknife_pairs_members_and_drops_failed_ones():
    ra, rb = members(n=6, seed=1), members(n=6, seed=2)
    rb[2] = {"status": "failed", "reason": "x"}
    jack = janssen.jackknife_fits(ra, rb, ("mu_w_eff",))
    se, n = jack["mu_w_eff"]
    assert n == 5 and 0 < se < 0.2
    vals, bins = janssen.saturated_mu(rb, 60.0, 5)
    assert vals[2] is None and all(v > 0 for i, v in enumerate(vals) if i != 2) and bins >= 2
    with pytest.raises(RuntimeError, match="3 members"):
        janssen.jackknife_fits(ra[:2], rb[:2])


def test_a_sliding_column_checks_the_members_mean_balance():
    """Each member of a column that ends sliding carries its stick-slip inertia (+-2 %); the mean
    of the members must still carry the weight within 1 %."""
    ms = members(n=4)
    for m, b in zip(ms, (0.02, -0.02, 0.015, -0.012)):
        m["balance"] = b
    chk = janssen.member_checks(ms)
    assert not chk["balance_ok"] and chk["balance_mean_ok"] and chk["balance_mean"] == pytest.approx(0.00075)
    for m in ms:
        m["balance"] = 0.03                     # a force missing in every member
    assert not janssen.member_checks(ms)["balance_mean_ok"]

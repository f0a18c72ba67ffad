"""The ensemble Janssen analysis (compare/cases/janssen.py): the weighted fit recovers known parameters
from synthetic noisy Janssen profiles within its 95 % intervals, at about the nominal rate; K and
mu_w,eff follow validation.md's formulas; the r^2 gate of a single fit and the goodness-of-fit
gate of an ensemble's; wrong profiles (hydrostatic, mu_w
changed) fail the comparison; the member checks catch a broken force balance. Every expected
value is computed here from the Janssen formulas, none comes from a simulation."""
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from dem.compare.cases import janssen

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


# A column like the Janssen scene's: 21 bins 8 cm tall over 4 lambda, 8 members, each bin's
# pressure scattered by 20 % from member to member (the column measures 10-40 %).
GOF_Z = 4.0 + 8.0 * np.arange(21)
GOF_TRUTH = janssen.model(GOF_Z, 3.0e4, 40.0, 0.5)


def _gof_p(shape, seed, members=8, cv=0.2):
    rng = np.random.default_rng(seed)
    mean, sd, se = janssen._mean_sd_se(shape * (1 + cv * rng.standard_normal((members, len(GOF_Z)))), "bin")
    f = janssen.fit_ci(GOF_Z, mean, se)
    f["profile"] = {"z": GOF_Z, "p": mean, "se": se, "sd": sd, "members": members, "sigma": "bin"}
    return janssen.goodness_of_fit(f, replicates=200, seed=seed)["p"], f["r2"]


def test_goodness_of_fit_accepts_janssen_profiles_that_r2_refuses():
    """Profiles drawn from Janssen's law: the bootstrap p-value falls below GOF_ALPHA (0.01) in
    at most 2 of 40 (expected 0.4), while r^2 >= 0.95, the gate it replaces, refuses several: r^2
    measures the scatter against the profile's range, not the misfit. An uncalibrated p (the
    chi^2 table, whose bins' standard errors are taken as exact) would refuse more than the level."""
    from scipy import stats as sps
    res = [_gof_p(GOF_TRUTH, seed) for seed in range(40)]
    assert sum(p < janssen.GOF_ALPHA for p, _ in res) <= 2, res
    assert sum(r2 < 0.95 for _, r2 in res) >= 5, res
    # the same profiles' chi^2 against the table: the standard errors' own scatter inflates it
    table = []
    for seed in range(40):
        rng = np.random.default_rng(seed)
        mean, sd, se = janssen._mean_sd_se(GOF_TRUTH * (1 + 0.2 * rng.standard_normal((8, len(GOF_Z)))), "bin")
        f = janssen.fit_ci(GOF_Z, mean, se)
        table.append(sps.chi2.sf(f["chi2_red"] * (len(GOF_Z) - 3), len(GOF_Z) - 3))
    assert np.mean(np.array(table) < 0.05) > np.mean(np.array([p for p, _ in res]) < 0.05)


def test_goodness_of_fit_refuses_a_profile_that_falls_at_depth():
    """Below mid-depth the pressure falls by 30 % to the floor (no saturation at p_inf: not
    Janssen's law): refused (p < 0.01) in at least 30 of 40 ensembles."""
    zm = np.median(GOF_Z)
    falls = np.where(GOF_Z < zm, GOF_TRUTH,
                     np.interp(zm, GOF_Z, GOF_TRUTH) * (1 - 0.3 * (GOF_Z - zm) / (GOF_Z.max() - zm)))
    res = [_gof_p(falls, 100 + seed) for seed in range(40)]
    assert sum(p < janssen.GOF_ALPHA for p, _ in res) >= 30, res


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
    assert abs(r.mean() - 0.5) < 0.01
    # the column: 8 mean diameters wide, its packed fill (about 0.78 of the area) at least 20 W
    # deep: 3 Janssen lengths at mu_w,eff = 0.1 and K = 0.7
    assert np.sum(math.pi * r ** 2) / (0.8 * C_W) >= 20 * C_W


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

SCENE = ROOT / "reference_inputs" / "scenes" / "janssen_column.toml"
C_W, C_MU_W = 8.0, 0.1       # the column's width [cm] and its smooth walls' friction


@pytest.fixture
def column(dem_binary, monkeypatch):
    monkeypatch.setenv("DEM_BINARY", str(dem_binary))
    from dem.compare.cases.common import SHARED_VARIANT, resolve
    r = resolve(SCENE)
    r["contact"] = dict(SHARED_VARIANT)
    return r


def test_the_column_lowers_its_floor_slowly_by_a_fraction_of_a_diameter(column):
    """The scene mobilises the wall friction by lowering the floor after the fill has settled:
    by a fraction of the mean diameter, slowly against a free fall over a diameter, until the run
    ends (the profile while the column slides along its smooth walls)."""
    floor = next(w for w in column["walls"] if w["group"] == "bottom")
    m = floor["motion"]
    d_mean = 2 * np.mean(np.array(column["discs"])[:, 2])
    depth = -m["velocity"][1] * (m["until"] - m["from"])
    assert m["velocity"][0] == 0 and 0.1 * d_mean <= depth <= 0.5 * d_mean
    assert -m["velocity"][1] < 0.02 * math.sqrt(2 * G * d_mean)
    assert m["from"] >= 1.0 and m["until"] == column["end"]["time"]
    # the side walls reach below the lowered floor: its ends stay on them
    assert all(min(w["from"][1], w["to"][1]) < -depth for w in column["walls"] if w["group"].startswith("side"))
    geo = janssen.geometry(column, column["end"]["time"])
    assert geo["floor"] == pytest.approx(-depth, abs=1e-12) and geo["width"] == C_W and geo["mu_w"] == C_MU_W
    assert next(p["mu"] for p in column["pairs"] if p["materials"] == ["sand", "sand"]) == 0.5
    assert janssen.geometry(column, 0.0)["floor"] == 0.0


def test_max_overlap_ratio():
    d = np.array([[5.0, 5.0, 0.5, 0, 0, 0], [5.99, 5.0, 0.5, 0, 0, 0], [10.0, 0.395, 0.4, 0, 0, 0]])
    # pair: overlap 0.01 cm over r 0.5 = 0.02; floor: 0.005 cm over r 0.4 = 0.0125
    assert janssen.max_overlap_ratio(d, 20.0, 0.0) == pytest.approx(0.02, abs=1e-12)
    assert janssen.max_overlap_ratio(d[2:], 20.0, 0.0) == pytest.approx(0.0125, abs=1e-12)
    assert janssen.max_overlap_ratio(d[2:], 20.0, -0.25) == 0.0     # the lowered floor


def test_member_record_balance_and_mobilised_friction(column):
    from dem.compare.cases.common import Result
    r = column
    t_end = r["end"]["time"]
    geo = janssen.geometry(r, t_end)
    discs = np.array([[4.0, 50.0 + k, 0.5, 0, 0, 0] for k in range(40)])
    weight = float(np.sum(geo["rho_s"] * math.pi * discs[:, 2] ** 2) * geo["g"])
    n_bins = 121                                           # 241 cm of profile in 2 cm bins, the last 1 cm
    edges = np.minimum(np.arange(n_bins + 1) * 2.0, 241.0)
    prof = lambda normal, shear: {"s_lo": list(edges[:-1]), "s_hi": list(edges[1:]),  # noqa: E731
                                  "normal": list(normal), "shear": list(shear)}
    normal = np.full(n_bins, 1000.0)
    shear = 0.3 * normal                                   # every bin at 0.3 of its normal force
    friction = 2 * shear.sum()
    t0 = r["walls"][2]["motion"]["from"]
    series = {"t": [0.0, t0, t0 + 0.05],                   # before the lowering: 0.1 of the normal force
              "walls": {w: {"normal": [list(normal)] * 3, "shear": [list(0.1 * normal), list(0.1 * normal),
                                                                    list(shear)]} for w in ("left", "right")}}
    good = Result(code="x", case="c", discs_end=discs.tolist(), series=series,
                  profiles={"left": prof(normal, shear), "right": prof(normal, shear),
                            "bottom": {"s_lo": [0.0], "s_hi": [C_W], "normal": [weight - friction], "shear": [0.0]}})
    rec = janssen.member_record(r, good, "x", 0, t_end)
    assert rec["balance"] == pytest.approx(0.0, abs=1e-12)
    assert rec["mobilised_upper"] == pytest.approx(0.3) and rec["mobilised_all"] == pytest.approx(0.3)
    assert rec["mobilised_before"] == pytest.approx(0.1)
    assert rec["floor"] == pytest.approx(-0.4) and rec["p"][0] == pytest.approx(500.0)    # per cm of wall
    assert rec["p"][-1] == pytest.approx(1000.0)           # the last bin is 1 cm long
    good.profiles["bottom"]["normal"] = [weight - 0.5 * friction]   # half the friction missing
    assert janssen.member_record(r, good, "x", 0, t_end)["balance"] == pytest.approx(0.5 * friction / weight)
    good.series = {}                                        # a code without a series (the engine's static runs)
    assert math.isnan(janssen.member_record(r, good, "x", 0, t_end)["mobilised_before"])


def test_fitted_bins_are_the_width_tall_and_enough_over_the_depth():
    """The fit's bins: W tall (8 cm in the column), at least 8 of them between W/2 above the floor
    and the surface of a fill 22 W deep (the column's: 21 bins)."""
    ms = synthetic_members(janssen_truth(), surface=22 * W, top=22 * W + 20)
    assert janssen.merge_for(ms) == 10
    f = janssen.ensemble_fit(ms)
    assert f["bin_width"] == pytest.approx(W) and f["n_points"] >= 8
    assert np.all(np.diff(f["profile"]["z"]) == pytest.approx(W))


def test_the_plan_refuses_a_run_that_ends_while_the_floor_moves(dem_binary, monkeypatch):
    monkeypatch.setenv("DEM_BINARY", str(dem_binary))
    from dem.compare.cases.plan import Entry, Options, PlanError, make_plan
    p = make_plan(Entry(SCENE, Options(kind="janssen", members=8)))
    from dem.compare.io import scene_toml
    assert p.duration == scene_toml.load(SCENE)["end"]["time"] and p.members == 8    # the scene's end.time
    with pytest.raises(PlanError, match="bottom still move at the run's end"):
        make_plan(Entry(SCENE, Options(kind="janssen", duration=1.5)))


def test_the_power_check_mutant_is_run_by_name():
    from dem.compare.cases import mutants
    default = mutants.mutations(("native", "liggghts", "yade"))               # the default set, per code
    assert len(default) == 2 * len(mutants.SPECS)
    assert "liggghts_mu_disc_wall_x0.8" not in [m.name for m in default]      # named only
    sel = mutants.mutations(("native", "liggghts", "yade"), ["liggghts_mu_disc_wall_x0.8"])
    assert [m.name for m in sel] == ["liggghts_mu_disc_wall_x0.8"] and sel[0].factor == 0.8
    assert len(mutants.mutations(("native", "liggghts", "yade"), ["mu_disc_wall_x0.8"])) == 2
    with pytest.raises(ValueError, match="unknown mutant"):
        mutants.mutations(("native", "liggghts"), ["mu_x0.8"])


LOWERED = """[scene]
name = "lowered_floor"
[physics]
gravity = [0.0, -980.0]
[integrator]
scheme = "velocity_verlet"
dt = 2e-5
[materials.sand]
density = 2.65
[materials.wall]
[[pairs]]
materials = ["sand", "sand"]
kn_rho_g = 3.64e4
ks_rho_g = 0.91e4
eta_n_rho_g = 7.65
eta_s_rho_g = 3.825
mu = 0.5
[[pairs]]
materials = ["sand", "wall"]
kn_rho_g = 7.28e4
ks_rho_g = 1.82e4
eta_n_rho_g = 15.3
eta_s_rho_g = 7.65
mu = 0.5
[[walls]]
name = "left"
group = "side_left"
from = [0.0, 30.0]
to = [0.0, -1.0]
material = "wall"
[[walls]]
name = "right"
group = "side_right"
from = [3.0, 30.0]
to = [3.0, -1.0]
material = "wall"
[[walls]]
name = "bottom"
group = "bottom"
from = [0.0, 0.0]
to = [3.0, 0.0]
material = "wall"
velocity = [0.0, -1.0]
move_from = 0.3
move_until = 0.5
[fill]
type = "list"
material = "sand"
count = 12
discs = [[0.75, 0.6, 0.5], [2.25, 0.6, 0.5], [0.75, 1.8, 0.5], [2.25, 1.8, 0.5], [0.75, 3.0, 0.5],
         [2.25, 3.0, 0.5], [0.75, 4.2, 0.5], [2.25, 4.2, 0.5], [0.75, 5.4, 0.5], [2.25, 5.4, 0.5],
         [1.5, 6.6, 0.5], [1.5, 7.8, 0.5]]
[end]
time = 0.7
[output]
profile_bin = 1.0
"""


def _codes_here():
    import shutil
    return ["native"] + [c for c in ("liggghts", "yade") if shutil.which(c)]


@pytest.mark.parametrize("code", _codes_here())
def test_a_lowered_floor_in_every_code(dem_binary, monkeypatch, tmp_path, code):
    """Twelve discs settle in a narrow box whose floor is then lowered 0.2 cm at 1 cm/s (the
    scene's walls[].velocity, translated by each code's backend): the bottom discs end 0.2 cm
    lower, the walls carry the weight, and the side walls' friction holds the discs up."""
    monkeypatch.setenv("DEM_BINARY", str(dem_binary))
    from importlib import import_module
    from dem.compare.cases.common import SHARED_VARIANT, Case, resolve
    from dem.compare.cases.plan import start_discs
    (tmp_path / "s.toml").write_text(LOWERED)
    r = resolve(tmp_path / "s.toml")
    r["contact"] = dict(SHARED_VARIANT)
    assert r["walls"][2]["motion"] == {"velocity": [0.0, -1.0], "from": 0.3, "until": 0.5}
    case = Case(name="lowered", resolved=r, discs=start_discs(r), dt=2e-5, duration=0.7, series_interval=0.05)
    res = import_module(f"dem.compare.codes.{code}_backend").run(case, tmp_path / code, 600)
    assert res.ok, res.reason
    d = np.array(res.discs_end)
    weight = float(np.sum(2.65 * math.pi * d[:, 2] ** 2) * 980)
    # the two bottom discs (r = 0.5) rest on the floor at -0.2 with overlaps of about 1e-4 cm
    assert np.all((d[:2, 1] < 0.3) & (d[:2, 1] > 0.3 - 1e-3)), d[:2, 1]
    tot = {w: (sum(p["normal"]), sum(p["shear"])) for w, p in res.profiles.items()}
    friction = tot["left"][1] + tot["right"][1]
    assert tot["bottom"][0] + friction == pytest.approx(weight, rel=1e-3)
    assert 0.03 * weight < friction < 0.2 * weight
    rec = janssen.member_record(r, res, code, 0, 0.7)
    assert rec["floor"] == pytest.approx(-0.2) and rec["mobilised_all"] > 0
    if code != "native":                                   # a series: the mobilisation before the lowering
        assert math.isfinite(rec["mobilised_before"])

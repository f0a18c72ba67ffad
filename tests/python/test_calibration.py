"""Calibration scenes (Chung & Ooi restated for 2D discs): the generator's --check, the
references against hand formulas, measure() on end states built by hand, native runs within
the tolerances, and a wrong constant caught. LIGGGHTS/YADE runs are skipped when the code is
missing or DEM_SKIP_SLOW=1."""
import copy
import math
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from dem.compare.cases.common import SHARED_VARIANT

from dem.compare.verdict import calibration as cal
from dem.compare.codes import native_backend
from dem.compare.cases.common import Case, pair

ROOT = cal.ROOT
sys.path.insert(0, str(ROOT / "scripts"))
import make_calibration_scenes as gen  # noqa: E402

RHO, G = 2.65, 980.0
MASS = RHO * math.pi
slow = pytest.mark.skipif(os.environ.get("DEM_SKIP_SLOW") == "1", reason="DEM_SKIP_SLOW=1")


def needs(code):
    return pytest.mark.skipif(shutil.which(code) is None and os.environ.get("CI") != "true",
                              reason=f"{code} not installed")


@pytest.fixture(scope="module")
def cases(dem_binary):
    os.environ.setdefault("DEM_BINARY", str(dem_binary))
    return {n: cal.case(n) for n in cal.scene_names()}


# ------------------------------------------------------------------------------- the generator

def test_committed_scenes_are_what_the_generator_writes(tmp_path, monkeypatch):
    p = subprocess.run([sys.executable, str(ROOT / "scripts" / "make_calibration_scenes.py"), "--check"],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    stale = tmp_path / "calibration"
    shutil.copytree(gen.OUT, stale)
    monkeypatch.setattr(gen, "OUT", stale)
    assert gen.main(["--check"]) == 0
    f = stale / "floor_launch.toml"
    f.write_text(f.read_text().replace("mu = 0.176", "mu = 0.2"))
    assert gen.main(["--check"]) == 1


def test_scenes_cover_the_tests_and_resolve(cases):
    assert len(cases) >= 20
    for name, c in cases.items():
        assert c.resolved["contact"] == SHARED_VARIANT
        assert c.resolved["integrator"]["scheme"] == "velocity_verlet" and c.dt == 1e-5
        assert c.resolved["end"]["stop_at_rest"] is False
    steel = cases["head_on_disc_wall_steel"].resolved
    assert pair(steel, "sand", "steel")["kn"] != 2 * pair(steel, "sand", "sand")["kn"]
    assert cases["unequal_discs"].discs[0, 2] != cases["unequal_discs"].discs[1, 2]
    assert {round(cal.geometry(c.resolved, c.discs)["n"] @ [0, 1], 12) for n, c in cases.items()
            if n.startswith("oblique_wall")} == {1.0}


# ------------------------------------------------------------------------------- references

def test_head_on_closed_form_against_hand_formulas_and_the_integration(cases):
    k, m = 1.890616e8, MASS
    undamped = cal.head_on(k, 0.0, m, 50.0)
    assert undamped["e"] == pytest.approx(1.0, abs=1e-12)
    assert undamped["t_c"] == pytest.approx(math.pi * math.sqrt(m / k), rel=1e-12)
    assert cal.head_on(1.1 * k, 0.0, m, 50.0)["t_c"] != pytest.approx(math.pi * math.sqrt(m / k), rel=1e-3)
    # weak damping: e -> exp(-zeta pi) to first order in zeta (clamp and geometric end: O(zeta^2))
    z = 0.01
    e = cal.head_on(k, 2 * z * math.sqrt(k * m), m, 50.0)["e"]
    assert e == pytest.approx(math.exp(-z * math.pi), abs=3 * z * z)
    # the closed form against the RK4 integration of the same law (independent of each other)
    for name in ("restitution_zeta_030", "restitution_zeta_090", "head_on_disc_disc"):
        c = cases[name]
        closed = cal.reference(c.resolved, c.discs, c.dt)
        end = cal.integrate(c.resolved, c.discs, c.duration, c.dt / 100)
        rk4 = cal.measure(c.resolved, c.discs, end, c.duration)
        assert rk4["e"] == pytest.approx(closed["e"], abs=1e-6), name
        assert rk4["t_c"] == pytest.approx(closed["t_c"], abs=2 * c.dt / 100), name
    wrong = copy.deepcopy(cases["restitution_zeta_090"].resolved)
    pair(wrong, "sand", "wall")["eta_n"] *= 1.1
    c = cases["restitution_zeta_090"]
    assert cal.reference(wrong, c.discs, c.dt)["e"] != pytest.approx(cal.reference(c.resolved, c.discs, c.dt)["e"],
                                                                        abs=1e-3)


def test_integration_of_a_dashpot_free_sliding_impact_gives_coulomb_impulse_limits(cases):
    """Without dashpots the spring is at the cap from the first touch (slip > mu k_n v_n / k_s):
    the integration must give the impulse limits: J_n = 2 m v_n, J_t = mu J_n."""
    c = cases["oblique_wall_75deg"]
    r = copy.deepcopy(c.resolved)
    for p in r["pairs"]:
        p["eta_n"] = p["eta_s"] = 0.0
    vt, vn = c.discs[0, 3], -c.discs[0, 4]
    mu = pair(r, "sand", "wall")["mu"]
    end = cal.integrate(r, c.discs, c.duration, c.dt / 100)
    got = cal.measure(r, c.discs, end, c.duration)
    assert got["e"] == pytest.approx(1.0, abs=1e-6)
    assert got["v_t_end"] == pytest.approx(vt - 2 * mu * vn, abs=1e-3 * vn)
    assert got["omega_end_0"] == pytest.approx(-2 * (2 * mu * vn) / 1.0, abs=2e-3 * vn)
    assert got["v_t_end"] != pytest.approx(vt - 2 * 1.1 * mu * vn, abs=1e-3 * vn)
    rigid = cal.reference(r, c.discs, c.dt)["coulomb_limit"]
    assert rigid["slides_throughout"]
    assert rigid["v_t_end"] == pytest.approx(got["v_t_end"], abs=1e-3 * vn)
    assert rigid["omega_end_0"] == pytest.approx(got["omega_end_0"], abs=2e-3 * vn)


def test_floor_references_are_the_hand_formulas(cases):
    c = cases["floor_launch"]
    ref = cal.reference(c.resolved, c.discs, c.dt)
    assert ref["t_roll"] == pytest.approx(100.0 / (3 * 0.176 * G), rel=1e-12)
    assert ref["v_end"] == pytest.approx(200.0 / 3, rel=1e-12)
    assert ref["omega_end_0"] == pytest.approx(-200.0 / 3, rel=1e-12)
    rest = cases["rest_on_floor"]
    assert cal.reference(rest.resolved, rest.discs, rest.dt)["floor_force"] == pytest.approx(RHO * math.pi * G, rel=1e-14)


def test_incline_reference_is_the_sliding_disc_and_refuses_a_disc_that_would_roll(cases):
    """Down a 45 degree incline (tan 45 > 3 mu) the contact point slides throughout: the friction
    mu m g cos 45 opposes it, dv/dt = g (sin - mu cos), r domega/dt = 2 mu g cos."""
    c = cases["incline_slide_45deg"]
    geo = cal.geometry(c.resolved, c.discs)
    assert geo["kind"] == "incline"
    ref = cal.reference(c.resolved, c.discs, c.dt)
    s, mu, T = math.sqrt(0.5), 0.176, c.duration
    assert ref["v_end"] == pytest.approx(20.0 + G * (s - mu * s) * T, rel=1e-12)
    assert ref["omega_end_0"] == pytest.approx(-2 * mu * G * s * T / 1.0, rel=1e-12)
    assert cal.tolerances(ref, c.dt)["v_end"] == pytest.approx(c.dt * G * (s - mu * s), rel=1e-12)
    # on a 10 degree incline the slip stops within T: the disc rolls, not this closed form
    th = math.radians(10.0)
    with pytest.raises(ValueError, match="slip stops"):
        cal.incline(np.array([0.0, 1.0, 1.0, 20.0, 0.0, 0.0]), np.array([math.sin(th), math.cos(th)]),
                    np.array([math.cos(th), -math.sin(th)]), np.array([0.0, -G]), mu, T)


def test_an_open_slit_has_no_reference_and_a_joined_floor_keeps_its_own(cases):
    """A point that ends one wall only (an open slit end) makes the scene cross-code only; points
    where two walls meet (slit_end_launch) never act and leave the floor launch's closed form."""
    c = cases["slit_roll_over"]
    assert cal.geometry(c.resolved, c.discs)["kind"] == "slit"
    ref = cal.reference(c.resolved, c.discs, c.dt)
    assert ref["cross_code_only"] and cal.tolerances(ref, c.dt) == {}
    assert cal.code_tolerances(ref)["v_end"] == pytest.approx(cal.CODE_REL * 15.0)
    end = np.array([[4.0, 1.0, 1.0, 8.6, 0.0, -8.6]])
    assert cal.measure(c.resolved, c.discs, end, c.duration) == pytest.approx(
        {"v_end": 8.6, "vn_end": 0.0, "omega_end_0": -8.6, "s_end": 1.2})
    joined = cases["slit_end_launch"]
    assert cal.geometry(joined.resolved, joined.discs)["kind"] == "floor_launch"


# ------------------------------------------------------------------------------- measure()

def _free(d, dt_):
    d = np.array(d, float)
    d[:, :2] += d[:, 3:5] * dt_
    return d


def test_measure_inverts_end_states_built_by_hand(cases):
    # disc-wall: contact from t0 (gap / v) for t_c, then rebound at e v with a tangential speed
    c = cases["oblique_wall_30deg"]
    d0 = c.discs
    vn, T = -d0[0, 4], c.duration
    e, t_c, vt1, w1 = 0.41, 7.1e-4, 11.0, -17.0
    t0 = (d0[0, 1] - 1.0) / vn
    flight = T - t0 - t_c
    end = np.array([[5.0, 1.0 + e * vn * flight, 1.0, vt1, e * vn, w1]])
    m = cal.measure(c.resolved, d0, end, T)
    assert m == pytest.approx({"e": e, "t_c": t_c, "v_t_end": vt1, "omega_end_0": w1}, rel=1e-9)
    end[0, 1] += 1e-4                       # a wrong end state reads as a wrong t_c
    assert cal.measure(c.resolved, d0, end, T)["t_c"] != pytest.approx(t_c, rel=1e-3)
    # two discs, oblique: relative motion along the start's line of centres, then apart
    c = cases["oblique_disc_disc"]
    d0 = c.discs
    p0, u0 = d0[1, :2] - d0[0, :2], d0[1, 3:5] - d0[0, 3:5]
    a, b, cc = u0 @ u0, 2 * p0 @ u0, p0 @ p0 - 4.0
    t0 = (-b - math.sqrt(b * b - 4 * a * cc)) / (2 * a)
    touch = p0 + u0 * t0                     # relative position at the first touch
    n = touch / np.linalg.norm(touch)
    u1 = 0.3 * 50.0 * n + 7.0 * np.array([-n[1], n[0]])   # leaving the contact point
    flight = T - t0 - 6.5e-4
    p1 = touch + u1 * flight
    end = np.array([[0.0, 0.0, 1.0, 1.0, 2.0, -3.0], [p1[0], p1[1], 1.0, 1.0 + u1[0], 2.0 + u1[1], -4.0]])
    m = cal.measure(c.resolved, d0, end, T)
    assert m["t_c"] == pytest.approx(6.5e-4, rel=1e-9)
    assert m["omega_end_0"] == -3.0 and m["omega_end_1"] == -4.0
    assert m["v_t_end"] == pytest.approx(u1[1], rel=1e-12)   # start frame: n = x, t = y
    # floor launch: slide at mu g until t_r, then roll: t_r from the distance
    c = cases["floor_launch"]
    v0, t_r, T = 100.0, 0.15, c.duration
    v1 = 2 * v0 / 3
    x = v0 * t_r - (v0 - v1) / t_r * t_r ** 2 / 2 + v1 * (T - t_r)
    end = np.array([[x, 1.0, 1.0, v1, 0.0, -v1]])
    got = cal.measure(c.resolved, c.discs, end, T)
    assert got["t_roll"] == pytest.approx(t_r, rel=1e-9) and got["v_end"] == v1
    # rest: the floor force is the sum of the profiles' normal force
    c = cases["rest_on_floor"]
    prof = {"floor": {"normal": [0.0, 8000.0, 158.72], "shear": [0.0, 0.0, 0.0]}}
    assert cal.measure(c.resolved, c.discs, c.discs, c.duration, prof)["floor_force"] == pytest.approx(8158.72)


# ------------------------------------------------------------------------------- runs

NATIVE_SCENES = ["head_on_disc_wall_steel", "restitution_zeta_090", "oblique_wall_20deg", "floor_launch",
                 "slit_end_launch", "rest_on_floor", "incline_slide_45deg", "sliding_disc_disc_undamped"]


@pytest.mark.parametrize("name", NATIVE_SCENES)
def test_native_within_the_reference(cases, tmp_path, name):
    c = cases[name]
    res = native_backend.run(c, tmp_path)
    assert res.ok, res.reason
    ref = cal.reference(c.resolved, c.discs, c.dt)
    got = cal.measure(c.resolved, c.discs, res.discs_end, c.duration, res.profiles)
    ok = cal.within(got, ref, c.dt)
    assert ok and all(ok.values()), (got, ref, cal.tolerances(ref, c.dt))


@pytest.mark.parametrize("name,key,scale,quantity", [("floor_launch", "mu", 1.1, "t_roll"),
                                                     ("head_on_disc_disc", "kn", 1.1, "t_c"),
                                                     ("incline_slide_45deg", "mu", 0.9, "v_end"),
                                                     ("restitution_zeta_060", "eta_n", 1.1, "e")])
def test_a_wrong_constant_given_to_a_code_fails_the_check(cases, tmp_path, name, key, scale, quantity):
    c = cases[name]
    wrong = copy.deepcopy(c.resolved)
    for p in wrong["pairs"]:
        p[key] *= scale
    res = native_backend.run(Case(name=name, resolved=wrong, discs=c.discs, dt=c.dt, duration=c.duration), tmp_path)
    assert res.ok, res.reason
    ref = cal.reference(c.resolved, c.discs, c.dt)          # what the scene says
    got = cal.measure(c.resolved, c.discs, res.discs_end, c.duration, res.profiles)
    assert cal.within(got, ref, c.dt)[quantity] is False, (got[quantity], ref[quantity])


@pytest.mark.reference_codes
@slow
@pytest.mark.parametrize("code", [pytest.param("liggghts", marks=needs("liggghts")),
                                  pytest.param("yade", marks=needs("yade"))])
def test_reference_code_within_the_reference_and_agrees_with_the_other(cases, tmp_path, code):
    rows = [cal.run_scene(n, ["native", code], tmp_path, timeout=120) for n in ("head_on_disc_disc", "oblique_wall_45deg")]
    for row in rows:
        m = row["codes"][code]
        assert "failed" not in m, m
        assert all(row["pass"][code].values()), row
    head = rows[0]["agree"][f"native vs {code}"]
    assert all(head.values()), rows[0]

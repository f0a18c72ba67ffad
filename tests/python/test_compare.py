"""The comparison layer: translators, the LIGGGHTS runner and reader on files the real program
wrote, the Janssen fit and the rule that a failed reference run never
counts as agreement."""
import copy
import json
import math
import os
import shutil
import subprocess
from pathlib import Path

import meshio
import numpy as np
import pytest

from dem.compare.cases import janssen, plan
from dem.compare.codes import liggghts_backend, native_backend, yade_backend
from dem.compare.verdict import study, verdict
from dem.compare.cases.common import SHARED_VARIANT, Case, CaseError, Result, failed, resolve

ROOT = Path(__file__).resolve().parents[2]
SILO = ROOT / "reference_inputs" / "scenes" / "silo_17_18.toml"
needs_liggghts = pytest.mark.skipif(shutil.which("liggghts") is None and os.environ.get("CI") != "true",
                                    reason="liggghts not installed (CI installs it)")


@pytest.fixture(autouse=True)
def _engine(dem_binary, monkeypatch):
    monkeypatch.setenv("DEM_BINARY", str(dem_binary))


def floor_case(x=5.5, v=(0.0, 0.0, 0.0), duration=0.1):
    r = resolve(SILO)
    r["contact"] = dict(SHARED_VARIANT)
    r["walls"] = [w for w in r["walls"] if w["group"] == "bottom"]
    r["points"] = []
    discs = np.array([[x, 1.0 - 1e-3, 1.0, *v]])
    return Case(name="floor", resolved=r, discs=discs, dt=5e-5, duration=duration)


# ------------------------------------------------------------------ Janssen fit

def test_janssen_fit_recovers_known_parameters_from_noisy_profiles():
    rng = np.random.default_rng(7)
    z = np.linspace(1, 200, 100)
    truth = {"p_inf": 1.5e5, "lambda": 45.0, "z0": 2.5}
    p = janssen.model(z, truth["p_inf"], truth["lambda"], truth["z0"])
    noisy = p * (1 + 0.03 * rng.standard_normal(len(z)))
    f = janssen.fit(z, noisy)
    assert f["p_inf"] == pytest.approx(truth["p_inf"], rel=0.03)
    assert f["lambda"] == pytest.approx(truth["lambda"], rel=0.06)
    assert f["z0"] == pytest.approx(truth["z0"], abs=1.0)
    exact = janssen.fit(z, p)
    assert exact["lambda"] == pytest.approx(truth["lambda"], rel=1e-6)
    # mu_w,eff and K from the definitions: p_inf = rho_b g W / (2 mu_w), lambda = W / (2 K mu_w)
    d = janssen.derived({"p_inf": 2.65 * 0.8 * 980 * 20 / (2 * 0.4), "lambda": 20 / (2 * 0.7 * 0.4)}, 2.65 * 0.8, 980, 20)
    assert d["mu_w_eff"] == pytest.approx(0.4) and d["K"] == pytest.approx(0.7)


def test_janssen_fit_refuses_too_few_points():
    with pytest.raises(ValueError, match="at least 4"):
        janssen.fit([1, 2, 3], [1, 2, 3])


# ------------------------------------------------------------------ translators

def test_native_translation_round_trips_through_dem_resolve(tmp_path):
    r = resolve(SILO)
    r["contact"] = dict(SHARED_VARIANT)
    d = np.array(r["discs"], float)
    case = Case(name="rt", resolved=r, discs=np.column_stack([d[:, :3], np.zeros((len(d), 3))]), dt=5e-5, duration=0.1)
    scene = native_backend.write_inputs(case, tmp_path)
    back = resolve(scene)
    assert back["pairs"] == r["pairs"]          # absolute constants survive bit for bit
    assert [(w["name"], w["from"], w["to"]) for w in back["walls"]] == [(w["name"], w["from"], w["to"]) for w in r["walls"]]
    assert back["points"] == r["points"]
    assert back["contact"] == SHARED_VARIANT
    assert np.array_equal(np.array(back["discs"])[:, :3], d[:, :3])


def test_liggghts_translation_units_and_wall_strips(tmp_path):
    case = floor_case()
    script = liggghts_backend.write_inputs(case, tmp_path)
    text = script.read_text()
    r = case.resolved
    dd, dw = r["pairs"][0], r["pairs"][1]
    assert f"kn peratomtypepair 2 {dd['kn']!r} {dw['kn']!r} {dw['kn']!r}" in text
    assert f"gammat_abs peratomtypepair 2 {dd['eta_s']!r} {dw['eta_s']!r}" in text
    assert "absolute_damping on limitForce on" in text and "dimension 2" in text
    # data file: diameter 2r, density rho (LIGGGHTS 2D: mass = density pi r^2)
    atoms = (tmp_path / "discs.data").read_text().split("Atoms")[1].split("Velocities")[0].split()
    assert float(atoms[2]) == 2.0 and float(atoms[3]) == 2.65
    # strips: every profile bin edge is a strip edge, strips <= 1 cm, z = +-2
    for w in r["walls"]:
        m = meshio.read(tmp_path / f"w_{w['name']}.stl")
        xs = np.unique(np.round(m.points[:, 0], 9))
        assert set(np.arange(w["from"][0], w["to"][0] + 1e-9, 2.0)).issubset(set(xs))
        assert np.max(np.diff(xs)) <= 1.0 + 1e-9
        assert set(np.round(m.points[:, 2], 9)) == {-2.0, 2.0}


def test_translators_refuse_a_law_the_codes_cannot_express(tmp_path):
    case = floor_case()
    case.resolved["contact"] = {"normal_spring": "incremental", "no_tension": "elastic", "friction_cap": "elastic"}
    with pytest.raises(CaseError, match="contact"):
        liggghts_backend.write_inputs(case, tmp_path)
    res = liggghts_backend.run(case, tmp_path)
    assert not res.ok and "translation" in res.reason


# ------------------------------------------------------------------ real runs

@needs_liggghts
def test_liggghts_reader_on_a_real_run_floor_carries_the_disc_weight(tmp_path):
    case = floor_case()
    res = liggghts_backend.run(case, tmp_path, timeout=120)
    assert res.ok, res.reason
    mg = 2.65 * math.pi * 980.0
    total = sum(sum(p["normal"]) for p in res.profiles.values())
    assert total == pytest.approx(mg, rel=1e-6)
    assert sum(sum(p["shear"]) for p in res.profiles.values()) == pytest.approx(0.0, abs=1e-6 * mg)
    # the bin holding the contact point (x = 5.5 -> bottom_left bin 2) carries it all
    assert res.profiles["bottom_left"]["normal"][2] == pytest.approx(mg, rel=1e-6)
    assert res.n_final == 1 and len(res.series["t"]) > 1


@needs_liggghts
def test_liggghts_rolling_disc_has_the_disc_inertia(tmp_path):
    """A disc sliding on the floor ends rolling at v0 / (1 + I / (m r^2)) = 2/3 v0 for a disc."""
    res = liggghts_backend.run(floor_case(x=5.0, v=(100.0, 0.0, 0.0), duration=0.3), tmp_path, timeout=120)
    assert res.ok, res.reason
    vx, omega = res.discs_end[0][3], res.discs_end[0][5]
    assert vx == pytest.approx(200.0 / 3.0, rel=1e-3)
    assert omega == pytest.approx(-vx / 1.0, rel=1e-3)


@needs_liggghts
def test_liggghts_runner_reports_a_broken_input_clearly(tmp_path, monkeypatch):
    case = floor_case()
    real = liggghts_backend._script
    monkeypatch.setattr(liggghts_backend, "_script",
                        lambda *a, **k: real(*a, **k).replace("fix e2d all enforce2d", "fix e2d all no_such_fix"))
    res = liggghts_backend.run(case, tmp_path, timeout=120)
    assert not res.ok
    assert "liggghts failed" in res.reason and "ERROR" in res.reason


@needs_liggghts
def test_liggghts_runner_reports_a_timeout(tmp_path):
    res = liggghts_backend.run(floor_case(duration=50.0), tmp_path, timeout=2)
    assert not res.ok and "timed out" in res.reason


@needs_liggghts
def test_liggghts_blow_up_is_a_failure(tmp_path):
    """dt 40x above the bound: discs leave the closed silo or energy explodes -> failed."""
    r = resolve(SILO)
    r["contact"] = dict(SHARED_VARIANT)
    d = np.array(r["discs"], float)[:60]
    case = Case(name="blow", resolved=r, discs=np.column_stack([d[:, :3], np.zeros((len(d), 3))]), dt=4e-3,
                duration=0.4)
    res = liggghts_backend.run(case, tmp_path, timeout=120)
    assert not res.ok, "a blown-up LIGGGHTS run must not read as a result"


# ------------------------------------------------------------------ agreement rules

def test_a_failed_reference_run_never_counts_as_agreement():
    case = floor_case()
    good = Result(code="native", case="floor", profiles={"bottom_left": {"s_lo": [0], "s_hi": [2], "normal": [1.0], "shear": [0.0]}})
    bad = failed("liggghts", "floor", "lost discs: 350 at the start, 349 at the end")
    metrics, detail = study.static_compare(case, {"native": good, "liggghts": bad})
    assert metrics and all(m["verdict"] == "inconclusive" for m in metrics)      # never agree, never disagree
    assert all("lost discs" in m["note"] for m in metrics)
    runs = {"native": [(good, {"discs_out": 3, "flow_rate": 50.0, "jammed": False, "peak_ratio_side": 2.0,
                               "peak_ratio_bottom": 3.0})], "yade": [(failed("yade", "x", "timed out after 900 s"), {})]}
    m, _ = study.discharge_compare("d", runs, plan.Options())
    assert m and all(x["verdict"] == "inconclusive" for x in verdict.finalize(m)) and "timed out" in m[0]["note"]


def test_profile_comparison_tells_an_edge_contact_from_a_real_difference():
    a = {"gate": {"normal": [0.0, 5.0, 0.0, 1.0]}, "left": {"normal": [1.0, 2.0, 3.0]}}
    moved = {"gate": {"normal": [0.0, 0.0, 5.0, 1.0]}, "left": {"normal": [1.0, 2.0, 3.0]}}
    worst, flips = study.cumulative_diff(a, moved)
    assert flips == 1 and worst == 0.0
    wrong = {"gate": {"normal": [0.0, 5.0, 0.0, 1.0]}, "left": {"normal": [3.0, 2.0, 1.0]}}
    worst, flips = study.cumulative_diff(a, wrong)
    assert flips == 0 and worst == pytest.approx(2.0 / 6.0)


# ------------------------------------------------------------------ particle snapshots

needs_yade = pytest.mark.skipif(shutil.which("yade") is None and os.environ.get("CI") != "true",
                                reason="yade not installed (CI installs it)")
BACKENDS = {"native": native_backend, "liggghts": liggghts_backend, "yade": yade_backend}
CODES = [pytest.param("native"), pytest.param("liggghts", marks=needs_liggghts), pytest.param("yade", marks=needs_yade)]
G = 980.0


def slit_case(mode: str) -> Case:
    """A 10 cm box with a 4 cm slit (gate 3..7 cm, slit ends L and R as points), disc 0 over the
    slit and disc 1 on the floor beside it; snapshots every 0.02 s for 0.2 s. Discharge: disc 0
    rests on the gate for 0.05 s, then falls freely through the slit and is removed 4 cm below.
    Static: disc 0 starts at y = 5 cm at rest and falls onto the closed gate."""
    r = resolve(SILO)
    r["contact"] = dict(SHARED_VARIANT)

    def wall(name, a, b, group):
        return {"name": name, "group": group, "material": "wall", "active": True, "from": list(a), "to": list(b)}
    r["walls"] = [wall("left", (0, 12), (0, 0), "side_left"), wall("right", (10, 12), (10, 0), "side_right"),
                  wall("bottom_left", (0, 0), (3, 0), "bottom"), wall("gate", (3, 0), (7, 0), "bottom"),
                  wall("bottom_right", (7, 0), (10, 0), "bottom")]
    r["points"] = [{"name": "L", "group": "slit_ends", "material": "wall", "at": [3.0, 0.0]},
                   {"name": "R", "group": "slit_ends", "material": "wall", "at": [7.0, 0.0]}]
    r["discharge"] = {"gate": "gate", "outlet_depth": 4.0, "jam_time": 0.3}
    y0 = 0.999 if mode == "discharge" else 5.0
    discs = np.array([[5.0, y0, 1.0, 0.0, 0.0, 0.0], [1.5, 0.999, 1.0, 0.0, 0.0, 0.0]])
    return Case(name=f"snap_{mode}", resolved=r, discs=discs, dt=5e-5, mode=mode,
                settle=0.05 if mode == "discharge" else 0.0, duration=0.2, series_interval=0.01,
                snapshot_interval=0.02)


def _free_fall(snaps, case, t_end):
    """Disc 0 from the first snapshot to t_end: y = y0 - g t^2 / 2, vy = -g t. Each code defines the
    instant of release to within half a step (the engine keeps the gate's force in the first
    half-kick, LIGGGHTS moves the gate in the step before the first dump, YADE's leapfrog starts
    from v(-dt/2)), an offset of at most g t dt / 2 in y and g dt / 2 in vy; YADE's VTU points
    are Float32 (1e-7 relative)."""
    s0 = snaps[0]
    k0 = list(s0.id).index(0)
    x0, y0 = s0.x[k0], s0.y[k0]
    checked = 0
    for s in snaps:
        if s.t > t_end + 1e-9:
            break
        k = list(s.id).index(0)
        t = s.t - s0.t
        assert s.x[k] == pytest.approx(x0, abs=1e-5)
        assert abs(s.y[k] - (y0 - 0.5 * G * t * t)) <= 0.5 * G * t * case.dt * (1 + 1e-9) + 1e-5, (s.t, s.y[k])
        assert abs(s.vy[k] + G * t) <= 0.5 * G * case.dt * (1 + 1e-9) + 1e-6, (s.t, s.vy[k])
        checked += 1
    return checked


@pytest.mark.parametrize("code", CODES)
def test_snapshots_of_a_discharge_follow_free_fall_and_end_as_the_final_state(code, tmp_path):
    case = slit_case("discharge")
    be = BACKENDS[code]
    res = be.run(case, tmp_path, timeout=120)
    assert res.ok, res.reason
    snaps = be.read_snapshots(case, tmp_path)
    # one snapshot every 0.02 s from the opening to the end, ids = rows of the packing
    assert [s.t for s in snaps] == pytest.approx(case.snapshot_times(), abs=1e-9)
    assert len(snaps) == 11
    t_out = res.removals[0]          # disc 0 leaves 4 cm below the floor: after sqrt(2 x 5 cm / g)
    assert t_out == pytest.approx(math.sqrt(2 * 5.0 / G), abs=2e-3)
    for s in snaps:
        assert list(s.id) == ([0, 1] if s.t < t_out else [1]), s.t
        assert np.all(s.r == 1.0)
        k1 = list(s.id).index(1)     # disc 1 rests on the floor beside the slit throughout
        assert s.x[k1] == pytest.approx(1.5, abs=1e-6) and s.y[k1] == pytest.approx(snaps[0].y[k1], abs=1e-6)
    assert _free_fall(snaps, case, t_out) == 6
    # the last snapshot is the final state (YADE: Float32 points; velocities a half step apart)
    assert snaps[-1].t == pytest.approx(case.duration)
    np.testing.assert_allclose(snaps[-1].rows()[:, :3], np.array(res.discs_end)[:, :3], rtol=0, atol=1e-5)
    np.testing.assert_allclose(snaps[-1].rows()[:, 3:], np.array(res.discs_end)[:, 3:], rtol=0, atol=1e-3)


@pytest.mark.parametrize("code", CODES)
def test_snapshots_of_a_static_run(code, tmp_path):
    """A disc dropped from 5 cm onto the closed gate: free fall until it lands at t = 0.09 s, at rest
    at the end. The engine writes snapshots only during a discharge: its static run gives the final
    discs.vtu alone."""
    case = slit_case("static")
    be = BACKENDS[code]
    res = be.run(case, tmp_path, timeout=120)
    assert res.ok, res.reason
    snaps = be.read_snapshots(case, tmp_path)
    if code == "native":
        assert len(snaps) == 1
    else:
        assert [s.t for s in snaps] == pytest.approx(case.snapshot_times(), abs=1e-9)
        assert snaps[0].y[0] == 5.0 and list(snaps[0].id) == [0, 1]
        assert _free_fall(snaps, case, math.sqrt(2 * 4.0 / G)) == 5
    last = snaps[-1]
    assert last.t == pytest.approx(case.duration) and list(last.id) == [0, 1]
    np.testing.assert_allclose(last.rows()[:, :3], np.array(res.discs_end)[:, :3], rtol=0, atol=1e-5)
    assert last.y[0] == pytest.approx(1.0, abs=1e-3) and abs(last.vy[0]) < 1e-3     # at rest on the gate


# ------------------------------------------------------------------ wall forces during flow

def _flow_member(case, scale, seed, extra_side=0.0):
    """A synthetic discharge Result: side walls carry scale x (1 + depth/20) per bin plus noise,
    the bottom walls 2 x scale per bin, the gate nothing; a large transient before FLOW_START."""
    rng = np.random.default_rng(seed)
    t = np.round(np.arange(0, case.duration + 1e-9, case.series_interval), 9)
    walls, profiles = {}, {}
    for w in case.resolved["walls"]:
        nb = len(np.arange(0, np.linalg.norm(np.subtract(w["to"], w["from"])) - 1e-9, case.profile_bin))
        base = np.zeros(nb)
        if w["group"].startswith("side"):
            base = scale * (1 + np.arange(nb) / 20.0) * (1 + extra_side)
        elif w["name"] != "gate":
            base = 2 * scale * np.ones(nb)
        rows = base[None, :] * (1 + 0.05 * rng.standard_normal((len(t), nb)))
        rows[t < study.FLOW_START - 1e-9] *= 5.0           # the opening transient: left out
        walls[w["name"]] = {"normal": rows.tolist(), "shear": (0.1 * rows).tolist()}
        profiles[w["name"]] = {"s_lo": list(np.arange(nb) * 2.0), "s_hi": list(np.arange(1, nb + 1) * 2.0),
                               "normal": rows[-1].tolist(), "shear": (0.1 * rows[-1]).tolist()}
    return Result(code="x", case=case.name, series={"t": t.tolist(), "walls": walls}, profiles=profiles,
                  removals=list(np.linspace(0.01, case.duration, 30)), n_final=100)


def test_time_averaged_wall_profiles_during_flow_are_judged_statistically():
    scene = ROOT / "reference_inputs" / "scenes" / "discharge_11_12.toml"
    case = study.discharge_case(scene, 2.5e-5, 1.0, 0.6, 0, 0.0)
    m = study.discharge_measures(_flow_member(case, 1e4, 1), case)
    # the window mean leaves the transient out: side bins are 1e4 (1 + k/20) within the noise
    left = np.array(m["flow_profile"]["left"]["normal"])
    assert left == pytest.approx(1e4 * (1 + np.arange(len(left)) / 20), rel=0.03)
    assert "gate" not in m["flow_profile"] and m["flow_window"] == [study.FLOW_START, 0.6]
    assert m["flow_bottom_normal"] == pytest.approx(2e4 * 16, rel=0.02)
    assert m["flow_samples"] == round((0.6 - study.FLOW_START) / case.series_interval) + 1

    def ensemble(extra, seed0):
        return [(r, study.discharge_measures(r, case))
                for r in (_flow_member(case, 1e4, seed0 + k, extra) for k in range(4))]
    same = {"native": ensemble(0.0, 10), "liggghts": ensemble(0.0, 20)}
    metrics, summary = study.discharge_compare("d", same, plan.Options())
    flow = [x for x in verdict.finalize(metrics) if "flow" in x["metric"] and "rate" not in x["metric"]]
    assert len(flow) == 5 and all(x["verdict"] == "agree" for x in flow), [(x["metric"], x["ci"]) for x in flow]
    assert summary["native"]["flow_profile"]["left"]["members"] == 4
    # side walls 30 % stronger in one code: the totals and the cumulative side profile disagree, the bottom agrees
    off = {"native": ensemble(0.0, 10), "liggghts": ensemble(0.3, 20)}
    metrics, _ = study.discharge_compare("d", off, plan.Options())
    res = {x["metric"].split(" (")[0]: x["verdict"] for x in verdict.finalize(metrics)}
    assert res["discharge flow_side_normal"] == res["discharge flow_side_shear"] == "disagree"
    assert res["discharge flow_bottom_normal"] == "agree"
    assert res["discharge time-averaged side-wall normal profile during flow, cumulative"] == "disagree"
    assert res["discharge time-averaged bottom-wall normal profile during flow, cumulative"] == "agree"
    # --metrics keeps only the kinds named
    kept, _ = study.discharge_compare("d", same, plan.Options(metrics=("wall_load",)))
    assert [x["margin_kind"] for x in kept] == ["wall_load"] * 2     # side and bottom normal; friction is its own kind

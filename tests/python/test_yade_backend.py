"""The YADE backend against exact results, the engine, and its own failure reporting.

Every test runs the real `yade` (2023.02a); they are skipped when it is not installed.
Scenes are small edits of the resolved 17/18 silo (its materials), so `build/dem` is needed for
`dem resolve`. Variant checked everywhere: the comparison layer's SHARED_VARIANT (e_n = K_n x
overlap, total normal force clamped >= 0, Coulomb cap on the total normal force, shear dashpot
off while sliding), which is YADE's ViscEl law.
"""
from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest

from dem.compare.io import scene_toml
from dem.compare.codes import yade_backend as yb
from dem.compare.io.run_dir import RunDir
from dem.compare.cases.common import SHARED_VARIANT, Case, CaseError, dem_binary, resolve

pytestmark = pytest.mark.skipif(not yb.available(), reason="yade is not on PATH (Debian: apt-get install yade)")

ROOT = Path(__file__).resolve().parents[2]
RHO = 2.65
M1 = RHO * math.pi          # mass of a disc of radius 1 per 1 cm of thickness [g]


def _wall(name, a, b, material="wall"):
    return {"name": name, "group": name, "material": material, "active": True, "from": list(a), "to": list(b)}


@pytest.fixture(scope="module")
def base() -> dict:
    try:
        dem_binary()
    except FileNotFoundError as e:
        pytest.skip(f"needs the engine for `dem resolve`: {e}")
    r = resolve(ROOT / "reference_inputs" / "scenes" / "silo_17_18.toml")
    r["contact"] = dict(SHARED_VARIANT)
    return r


def scene(base, walls, points=(), gravity=(0.0, -980.0), dd=None, dw=None) -> dict:
    r = json.loads(json.dumps(base))
    r["walls"], r["points"], r["gravity"] = list(walls), list(points), list(gravity)
    for p in r["pairs"]:
        new = dd if p["materials"] == ["sand", "sand"] else dw
        if new:
            p.update(new)
    return r


def clamped_restitution(k: float, eta: float, m_eff: float) -> tuple[float, float, float]:
    """Linear spring-dashpot with the total force clamped >= 0 (Schwager & Poeschel 2007): the
    contact ends when k x + eta x' = 0, i.e. x'' = 0. Returns (e_clamped, e_free, t_c)."""
    w0 = math.sqrt(k / m_eff)
    zeta = eta / (2 * math.sqrt(k * m_eff))
    a, wd = zeta * w0, w0 * math.sqrt(1 - zeta ** 2)
    tf = (math.pi - math.atan(2 * a * wd / (wd * wd - a * a))) / wd
    e_clamped = math.exp(-a * tf) * abs(wd * math.cos(wd * tf) - a * math.sin(wd * tf)) / wd
    e_free = math.exp(-math.pi * zeta / math.sqrt(1 - zeta ** 2))
    return e_clamped, e_free, math.pi / wd


# ------------------------------------------------------------------------------------------
# A disc resting on a floor, with disc-wall constants that are NOT 2 x disc-disc: the wall
# material is then solved from YADE's series rule.
@pytest.fixture(scope="module")
def rest(base, tmp_path_factory):
    dd = {"kn": 9.0e7, "ks": 3.0e7, "eta_n": 3.0e4, "eta_s": 1.0e4, "mu": 0.5}
    dw = {"kn": 1.35e8, "ks": 4.0e7, "eta_n": 5.0e4, "eta_s": 1.5e4, "mu": 0.2}   # 0.75, 0.67, 0.83, 0.75 x 2dd
    r = scene(base, [_wall("floor", (-5.0, 0.0), (5.0, 0.0))], dd=dd, dw=dw)
    case = Case(name="rest", resolved=r, discs=np.array([[0.3, 0.999, 1.0, 0.0, 0.0, 0.0]]), dt=5e-5,
                duration=0.1, series_interval=0.01)
    out = tmp_path_factory.mktemp("yade_rest")
    return case, out, yb.run(case, out), dd, dw


def test_disc_resting_on_floor_loads_it_with_mg(rest):
    case, _out, res, _dd, dw = rest
    assert res.ok, res.reason
    mg = M1 * 980.0
    prof = res.profiles["floor"]
    assert sum(prof["contacts"]) == 1
    assert prof["contacts"][2] == 1                       # contact point x = 0.3: s = 5.3, bin [4, 6)
    assert sum(prof["normal"]) == pytest.approx(mg, rel=1e-6)   # by the disc on the wall, pushing: +
    assert abs(sum(prof["shear"])) < 1e-9 * mg
    x, y, r, vx, vy, om = res.discs_end[0]
    assert y == pytest.approx(1.0 - mg / dw["kn"], abs=1e-3 * mg / dw["kn"])
    assert abs(vx) + abs(vy) < 1e-6 and abs(om) < 1e-6
    # the series ends with the same static load; YADE's own wall total agrees with our sum
    assert res.series["t"][0] == 0.0 and res.series["t"][-1] == pytest.approx(0.1)
    assert sum(res.series["walls"]["floor"]["normal"][-1]) == pytest.approx(mg, rel=1e-6)
    assert res.extra["wall_force_mismatch_rel"] < 1e-12
    assert res.n_initial == res.n_final == 1 and res.steps == 2000
    assert res.version.startswith("yade ")


def test_series_materials_give_the_resolved_pair_constants(rest):
    _case, _out, res, _dd, dw = rest
    seen = res.extra["pairs_seen"]["floor"]
    for yade_key, key in (("kn", "kn"), ("ks", "ks"), ("cn", "eta_n"), ("cs", "eta_s"), ("mu", "mu")):
        assert seen[yade_key] == pytest.approx(dw[key], rel=1e-12), yade_key


def test_reader_rereads_what_yade_wrote(rest):
    case, out, res, _dd, _dw = rest
    again = yb.read(case, out)
    assert again.ok
    assert again.profiles == res.profiles
    assert again.series == res.series
    assert again.discs_end == res.discs_end
    assert again.wall_time_s == res.wall_time_s      # the process time saved by run()
    assert (out / yb.LOG_FILE).exists() and (out / yb.SCRIPT).exists()


def test_material_translation_rules():
    assert yb.series(2.0, 0.0) == 2.0 and yb.series(0.0, 0.0) == 0.0
    w = yb._series_partner("kn", 2.0e8, 1.5e8)
    assert yb.series(2.0e8, w) == pytest.approx(1.5e8, rel=1e-14)
    assert yb._series_partner("kn", 2.0e8, 2.0e8) == 0.0       # the paper: disc-wall = 2 x disc-disc
    with pytest.raises(CaseError, match="kn"):
        yb._series_partner("pairs[sand,wall].kn", 2.0e8, 2.5e8)


def test_case_errors(base, tmp_path):
    discs = np.array([[0.0, 1.0, 1.0, 0.0, 0.0, 0.0]])
    r = scene(base, [_wall("floor", (-5.0, 0.0), (5.0, 0.0))])
    r["contact"] = {"normal_spring": "incremental", "no_tension": "elastic", "friction_cap": "elastic"}
    with pytest.raises(CaseError, match="contact"):
        yb.write_inputs(Case(name="v", resolved=r, discs=discs, dt=1e-4, duration=0.01), tmp_path)
    r = scene(base, [_wall("floor", (-5.0, 0.0), (5.0, 0.0))], dw={"kn": 3.0 * 9.45308e7})
    case = Case(name="k", resolved=r, discs=discs, dt=1e-4, duration=0.01)
    with pytest.raises(CaseError, match=r"pairs\[sand,wall\]\.kn"):
        yb.write_inputs(case, tmp_path)
    res = yb.run(case, tmp_path)                     # run() never raises: a failed Result
    assert not res.ok and res.reason.startswith("translation: pairs[sand,wall].kn")


# ------------------------------------------------------------------------------------------
def test_head_on_collision_restitution(base, tmp_path):
    """Two equal discs, gravity 0: e of the clamped linear spring-dashpot, m_eff = m/2.
    Tolerance 2 dt/t_c (first order in dt/t_c; here dt/t_c = 3e-3)."""
    k, zeta = 1.0e6, 0.3
    m_eff = M1 / 2
    eta = 2 * zeta * math.sqrt(k * m_eff)
    e_clamped, e_free, t_c = clamped_restitution(k, eta, m_eff)
    r = scene(base, [], gravity=(0.0, 0.0), dd={"kn": k, "eta_n": eta, "ks": k / 3, "eta_s": eta / 3})
    dt, v0 = 2e-5, 50.0
    discs = np.array([[-1.2, 0.0, 1.0, v0, 0.0, 0.0], [1.2, 0.0, 1.0, -v0, 0.0, 0.0]])
    res = yb.run(Case(name="head_on", resolved=r, discs=discs, dt=dt, duration=0.02, series_interval=0.01), tmp_path)
    assert res.ok, res.reason
    d = np.array(res.discs_end)
    e = (d[1, 3] - d[0, 3]) / (2 * v0)
    assert e == pytest.approx(e_clamped, rel=2 * dt / t_c)
    assert abs(e - e_free) > 0.1 * e_free               # the clamp matters: not the unclamped formula
    assert d[0, 3] + d[1, 3] == pytest.approx(0.0, abs=1e-9 * v0)   # momentum
    assert np.all(np.abs(d[:, 4:]) < 1e-9)               # head-on: no lateral motion, no spin


def test_oblique_gross_sliding_spin(base, tmp_path):
    """Disc onto a wall, gravity 0, tangential speed 30 mu (1+e) v_n (slides throughout), no shear
    dashpot: dv_t = mu (1+e) v_n and R d(omega) = 2 mu (1+e) v_n (validation.md). Spin tolerance
    1%: YADE's lever arm is r - overlap/2 (overlap/r < 1% here)."""
    k, zeta, mu = 1.0e7, 0.3, 0.176
    eta = 2 * zeta * math.sqrt(k * M1)
    e, _e_free, _t_c = clamped_restitution(k, eta, M1)
    r = scene(base, [_wall("floor", (-20.0, 0.0), (20.0, 0.0))], gravity=(0.0, 0.0),
              dd={"kn": k, "eta_n": eta, "ks": k / 3, "eta_s": 0.0},
              dw={"kn": k, "eta_n": eta, "ks": k / 3, "eta_s": 0.0, "mu": mu})
    vn = 10.0
    vt = 30 * mu * (1 + e) * vn
    discs = np.array([[0.0, 1.05, 1.0, vt, -vn, 0.0]])
    res = yb.run(Case(name="oblique", resolved=r, discs=discs, dt=1e-5, duration=0.01, series_interval=0.005),
                 tmp_path)
    assert res.ok, res.reason
    _x, _y, _r, vx, vy, om = res.discs_end[0]
    jt = mu * (1 + e) * vn
    assert vy == pytest.approx(e * vn, rel=0.01)
    assert vt - vx == pytest.approx(jt, rel=0.01)
    assert om == pytest.approx(-2 * jt / 1.0, rel=0.01)   # moving +x over the floor: clockwise


def _engine_disc_end(tmp: Path, case: Case) -> list[float]:
    """The same scene run by build/dem (velocity Verlet, same contact variant)."""
    r = case.resolved
    scene_toml.write(tmp / "scene.toml", {
        "scene": {"name": "oblique_engine"},
        "physics": {"gravity": list(r["gravity"])},
        "integrator": {"scheme": "velocity_verlet", "dt": case.dt},
        "contact": dict(r["contact"]),
        "materials": {"sand": {"density": 2.65}, "wall": {}},
        "pairs": [{"materials": p["materials"], **{k: float(p[k]) for k in ("kn", "ks", "eta_n", "eta_s", "mu")}}
                  for p in r["pairs"]],
        "walls": [{"name": w["name"], "from": list(map(float, w["from"])), "to": list(map(float, w["to"])),
                   "material": "wall"} for w in r["walls"]],
        "fill": {"type": "file", "file": "packing.csv", "material": "sand", "velocities": True},
        "end": {"time": case.duration, "stop_at_rest": False},
        "output": {"progress": False}})
    (tmp / "packing.csv").write_text("x,y,r,vx,vy,omega\n" +
                                     "\n".join(",".join(repr(float(v)) for v in row) for row in case.discs) + "\n")
    p = subprocess.run([str(dem_binary()), "run", str(tmp / "scene.toml"), "--out", str(tmp / "run"), "--quiet"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    discs = RunDir(tmp / "run").discs()
    return [float(discs[k][0]) for k in ("x", "y", "r", "vx", "vy", "omega")]


def test_oblique_sticking_spin_matches_the_engine(base, tmp_path):
    """Low tangential speed (0.5 mu (1+e) v_n): the tangential spring and dashpot act (the
    contact sticks part of the time), no simple closed form: YADE against the engine on the same
    scene. The same law (lever arm r - overlap/2 in both: SHARED_VARIANT's lever_arm) and the
    same positions (YADE's leapfrog and velocity Verlet move the discs alike): agreement to
    rounding, tolerance 1e-9 (with the engine's lever arm r, v_t differs by 3e-3)."""
    k, zeta, mu = 1.0e7, 0.3, 0.176
    eta = 2 * zeta * math.sqrt(k * M1)
    e, _e_free, _t_c = clamped_restitution(k, eta, M1)
    r = scene(base, [_wall("floor", (-20.0, 0.0), (20.0, 0.0))], gravity=(0.0, 0.0),
              dd={"kn": k, "eta_n": 2 * zeta * math.sqrt(k * M1 / 2), "ks": k / 3,
                  "eta_s": 2 * zeta * math.sqrt(k * M1 / 2) / 3},
              dw={"kn": k, "eta_n": eta, "ks": k / 3, "eta_s": eta / 3, "mu": mu})
    vn = 10.0
    discs = np.array([[0.0, 1.05, 1.0, 0.5 * mu * (1 + e) * vn, -vn, 0.0]])
    case = Case(name="oblique_stick", resolved=r, discs=discs, dt=1e-5, duration=0.01, series_interval=0.005)
    res = yb.run(case, tmp_path / "yade")
    assert res.ok, res.reason
    (tmp_path / "dem").mkdir()
    ref = _engine_disc_end(tmp_path / "dem", case)
    _x, _y, _r, vx, vy, om = res.discs_end[0]
    assert vy == pytest.approx(ref[4], rel=1e-9)
    assert vx == pytest.approx(ref[3], rel=1e-9)
    assert om == pytest.approx(ref[5], rel=1e-9)
    assert om < 0


# ------------------------------------------------------------------------------------------
def test_disc_on_the_two_slit_ends(base, tmp_path):
    """Open slit narrower than the disc: it rests on the ends L and R (facet vertices), each
    carrying m g / 2 vertically (frictionless, so the split is determinate); reported under the walls ending there, in their end bins, with
    shear along from -> to: -(m g / 2) tan(theta) on bottom_left, + on bottom_right."""
    walls = [_wall("bottom_left", (0.0, 0.0), (4.5, 0.0)), _wall("bottom_right", (5.5, 0.0), (10.0, 0.0))]
    gate = _wall("gate", (4.5, 0.0), (5.5, 0.0))
    gate["active"] = False
    pts = [{"name": "L", "group": "slit_ends", "material": "wall", "at": [4.5, 0.0]},
           {"name": "R", "group": "slit_ends", "material": "wall", "at": [5.5, 0.0]}]
    r = scene(base, walls + [gate], pts, dw={"mu": 0.0})   # frictionless: forces along the normals
    res = yb.run(Case(name="slit_ends", resolved=r, discs=np.array([[5.0, 0.87, 1.0, 0.0, 0.0, 0.0]]), dt=5e-5,
                      duration=0.1, series_interval=0.05), tmp_path)
    assert res.ok, res.reason
    mg = M1 * 980.0
    x, y, *_ = res.discs_end[0]
    tan = 0.5 / y
    bl, br = res.profiles["bottom_left"], res.profiles["bottom_right"]
    assert bl["contacts"][-1] == 1 and sum(bl["contacts"]) == 1
    assert br["contacts"][0] == 1 and sum(br["contacts"]) == 1
    assert bl["normal"][-1] == pytest.approx(mg / 2, rel=1e-6)
    assert br["normal"][0] == pytest.approx(mg / 2, rel=1e-6)
    assert bl["shear"][-1] == pytest.approx(-mg / 2 * tan, rel=1e-6)
    assert br["shear"][0] == pytest.approx(mg / 2 * tan, rel=1e-6)
    assert sum(res.profiles["gate"]["contacts"]) == 0


def test_closed_junction_has_one_contact_like_the_engine(base, tmp_path):
    """A disc resting just past the junction of two collinear walls (bottom_left | gate, closed):
    the engine has one plane contact (the gate owns the end point L); YADE's facet vertex of
    bottom_left would add a second one. The guard switches it off: one contact, overlap m g / k."""
    walls = [_wall("bottom_left", (0.0, 0.0), (4.5, 0.0)), _wall("gate", (4.5, 0.0), (5.5, 0.0)),
             _wall("bottom_right", (5.5, 0.0), (10.0, 0.0))]
    pts = [{"name": "L", "group": "slit_ends", "material": "wall", "at": [4.5, 0.0]}]
    r = scene(base, walls, pts)
    kn = next(p for p in r["pairs"] if p["materials"] != ["sand", "sand"])["kn"]
    res = yb.run(Case(name="junction", resolved=r, discs=np.array([[4.505, 0.9999, 1.0, 0.0, 0.0, 0.0]]),
                      dt=5e-5, duration=0.05, series_interval=0.05), tmp_path)
    assert res.ok, res.reason
    mg = M1 * 980.0
    assert sum(res.profiles["bottom_left"]["contacts"]) == 0
    assert sum(res.profiles["gate"]["contacts"]) == 1
    assert sum(res.profiles["gate"]["normal"]) == pytest.approx(mg, rel=1e-6)
    assert res.discs_end[0][1] == pytest.approx(1.0 - mg / kn, abs=1e-3 * mg / kn)
    assert res.extra["guard_flips"] >= 1


def test_small_discharge_removes_discs_in_free_fall_time(base, tmp_path):
    """Two discs stacked over a 4 cm slit and one beside it; the gate is erased after 0.05 s: the
    stacked discs fall out, the first crossing y = -4 after sqrt(2 x 5 / g) (from rest at y = 1)."""
    walls = [_wall("left", (0.0, 12.0), (0.0, 0.0)), _wall("right", (10.0, 12.0), (10.0, 0.0)),
             _wall("bottom_left", (0.0, 0.0), (3.0, 0.0)), _wall("gate", (3.0, 0.0), (7.0, 0.0)),
             _wall("bottom_right", (7.0, 0.0), (10.0, 0.0))]
    pts = [{"name": "L", "group": "slit_ends", "material": "wall", "at": [3.0, 0.0]},
           {"name": "R", "group": "slit_ends", "material": "wall", "at": [7.0, 0.0]}]
    r = scene(base, walls, pts)
    r["discharge"] = {"gate": "gate", "outlet_depth": 4.0}
    discs = np.array([[5.0, 1.0, 1.0, 0.0, 0.0, 0.0], [5.0, 3.01, 1.0, 0.0, 0.0, 0.0], [1.5, 1.0, 1.0, 0.0, 0.0, 0.0]])
    res = yb.run(Case(name="small_discharge", resolved=r, discs=discs, dt=5e-5, mode="discharge", settle=0.05,
                      duration=0.25, series_interval=0.01), tmp_path)
    assert res.ok, res.reason
    assert len(res.removals) == 2 and res.n_final == 1 and res.extra["removal_index"] == [0, 1]
    assert res.removals[0] == pytest.approx(math.sqrt(2 * 5.0 / 980.0), abs=5e-4)
    assert res.extra["kept_index"] == [2]
    assert res.discs_end[0][0] == pytest.approx(1.5, abs=1e-6)
    assert res.series["t"][0] == 0.0 and len(res.series["t"]) == 26
    assert all(sum(row) == 0.0 for row in res.series["walls"]["gate"]["normal"])     # erased at t = 0
    assert res.steps == 6000


# ------------------------------------------------------------------------------------------
# Failures are failed Results with a reason, never exceptions.
def _floor_case(base, **kw) -> Case:
    r = scene(base, [_wall("floor", (-5.0, 0.0), (5.0, 0.0))])
    args = dict(name="broken", resolved=r, discs=np.array([[0.0, 0.999, 1.0, 0.0, 0.0, 0.0]]), dt=5e-5,
                duration=0.01, series_interval=0.005)
    args.update(kw)
    return Case(**args)


def test_python_error_in_the_script_is_a_failed_result(base, tmp_path):
    case = _floor_case(base)
    script = yb.write_inputs(case, tmp_path)
    script.write_text(script.read_text().replace("def main():", "raise RuntimeError('injected failure')\n\n\ndef main():"))
    res = yb.run_written(case, tmp_path)
    assert not res.ok
    assert "exited with code 1" in res.reason and "injected failure" in res.reason


def test_nan_radius_slipped_past_validation_is_a_failed_result(base, tmp_path):
    case = _floor_case(base, discs=np.array([[0.0, 0.999, float("nan"), 0.0, 0.0, 0.0]]))
    with pytest.raises(CaseError):
        yb.write_inputs(case, tmp_path)             # validation catches it ...
    yb._write(yb.case_data(case), tmp_path, 1)      # ... slipped past: the script must refuse it
    res = yb.run_written(case, tmp_path)
    assert not res.ok and "non-finite" in res.reason


def test_yade_abort_is_a_failed_result(base, tmp_path):
    """An inconsistent ViscElMat set makes YADE abort (SIGABRT, exit 134 in a shell)."""
    case = _floor_case(base)
    script = yb.write_inputs(case, tmp_path)
    text = script.read_text()
    assert 'ks=m["ks"], cs=m["cs"],' in text
    script.write_text(text.replace('ks=m["ks"], cs=m["cs"],', 'ks=float("nan"), cs=m["cs"],'))
    res = yb.run_written(case, tmp_path)
    assert not res.ok and "abort" in res.reason and "same defined set" in res.reason


def test_blow_up_is_a_failed_result(base, tmp_path):
    """dt far above the stability limit in a closed box: discs are flung out of the container."""
    walls = [_wall("left", (0.0, 12.0), (0.0, 0.0)), _wall("right", (10.0, 12.0), (10.0, 0.0)),
             _wall("bottom", (0.0, 0.0), (10.0, 0.0))]
    discs = np.array([[5.0, 1.0, 1.0, 0.0, 0.0, 0.0], [5.0, 3.01, 1.0, 0.0, 0.0, 0.0]])
    res = yb.run(Case(name="blow_up", resolved=scene(base, walls), discs=discs, dt=2e-3, duration=0.5), tmp_path)
    assert not res.ok
    assert "left the container" in res.reason or "blow-up" in res.reason or "non-finite" in res.reason


def test_timeout_is_a_failed_result(base, tmp_path):
    res = yb.run(_floor_case(base, duration=100.0), tmp_path, timeout=1.0)
    assert not res.ok and res.reason.startswith("timeout")

"""The LAMMPS backend: its translation (deck text, constants, refusals) and real runs of `lmp`.

The translation tests need only `dem resolve`; the runs need Debian's `lammps` (`lmp`, GRANULAR
package) and are skipped without it, except in CI (which installs it: a missing binary fails).
Expected values come from closed forms (restitution of the clamped spring-dashpot, the rolling
disc's 2/3, the weight rho pi r^2 g) or from the resolved scene, never from the engine's output.
"""
from __future__ import annotations

import copy
import dataclasses
import math
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from dem.compare.verdict import calibration, probe
from dem.compare.codes import lammps_backend as lb
from dem.compare.cases import mutants
from dem.compare.cases.common import SHARED_VARIANT, Case, CaseError, dem_binary, resolve

ROOT = Path(__file__).resolve().parents[2]
CAL = ROOT / "reference_inputs" / "agreement" / "calibration"
needs_lmp = pytest.mark.skipif(shutil.which("lmp") is None and os.environ.get("CI") != "true",
                               reason="lmp not installed (Debian: apt-get install lammps; CI installs it)")


@pytest.fixture(scope="module")
def silo() -> dict:
    try:
        dem_binary()
    except FileNotFoundError as e:
        pytest.skip(f"needs the engine for `dem resolve`: {e}")
    r = resolve(ROOT / "reference_inputs" / "scenes" / "silo_17_18.toml")
    r["contact"] = dict(SHARED_VARIANT)
    return r


def silo_case(r: dict, **kw) -> Case:
    d = np.array(r["discs"], float)
    return Case(name="silo", resolved=r, discs=np.column_stack([d[:, :3], np.zeros((len(d), 3))]), dt=5e-5,
                duration=kw.pop("duration", 0.01), **kw)


def _pair(r, a, b):
    return next(p for p in r["pairs"] if sorted(p["materials"]) == sorted([a, b]))


def test_deck_states_the_shared_law_the_disc_mass_and_the_scene_constants(silo, tmp_path):
    script = lb.write_inputs(silo_case(silo), tmp_path).read_text()
    for line in ("dimension 2", "atom_style sphere", "fix e2d all enforce2d", "fix integr all nve/sphere disc",
                 "pair_style granular", "set type 1 density/disc 2.65"):
        assert line in script.splitlines(), line
    dd, dw = _pair(silo, "sand", "sand"), _pair(silo, "sand", "wall")
    words = (f"hooke {dd['kn']!r} {dd['eta_n']!r} tangential linear_history {dd['ks']!r} "
             f"{dd['eta_s'] / dd['eta_n']!r} {dd['mu']!r} damping velocity limit_damping")
    assert f"pair_coeff 1 1 {words}" in script
    wall_words = (f"hooke {dw['kn']!r} {dw['eta_n']!r} tangential linear_history {dw['ks']!r} "
                  f"{dw['eta_s'] / dw['eta_n']!r} {dw['mu']!r} damping velocity limit_damping")
    fixes = [l for l in script.splitlines() if "wall/gran/region" in l]
    # left, right and ONE floor plane (bottom_left, gate and bottom_right lie on one line)
    assert len(fixes) == 3 and all(wall_words in l for l in fixes)
    regions = sorted(l.split()[1:] for l in script.splitlines() if l.startswith("region "))
    normals = sorted(tuple(float(v) for v in reg[5:7]) for reg in regions)
    assert normals == [(-1.0, 0.0), (0.0, 1.0), (1.0, 0.0)]
    data = (tmp_path / "discs.data").read_text()
    assert f"{len(silo['discs'])} atoms" in data and "Atoms # sphere" in data


def test_planes_merge_collinear_walls_and_refuse_a_gap(silo):
    pls = lb.planes(silo_case(silo))
    floor = next(p for p in pls if p["n"][1] > 0.5)
    assert sorted(w["name"] for w, _lo, _hi in floor["walls"]) == ["bottom_left", "bottom_right", "gate"]
    r = copy.deepcopy(silo)
    for w in r["walls"]:
        if w["name"] == "gate":
            w["active"] = False        # the opened slit
    with pytest.raises(CaseError, match=r"walls: .*gap of 8 cm.*infinite planes"):
        lb.planes(silo_case(r))


@pytest.mark.parametrize("edit, match", [
    (lambda r: r.update(discharge={"gate": "nosuch", "outlet_depth": 2.0}), r"discharge\.gate: 'nosuch' is not"),
    (lambda r: (r.update(discharge={"gate": "gate", "outlet_depth": 2.0}),
                r["walls"][0].update({"from": [0.0, 40.0], "to": [1.0, 0.0]})),
     r"walls: 'left' .* neither horizontal nor vertical"),
    (lambda r: (r.update(discharge={"gate": "gate", "outlet_depth": 2.0}), r["points"][0].update(at=[17.0, 0.0])),
     r"points: L .* not the end of walls"),
    (lambda r: r["points"].append({"name": "P", "at": [10.0, 20.0], "material": "wall", "group": "P"}),
     r"points: P .*can act"),
    (lambda r: _pair(r, "sand", "sand").update(eta_n=0.0), r"pairs\[sand,sand\]\.eta_s: .*x eta_n"),
    (lambda r: r.update(contact=dict(SHARED_VARIANT, lever_arm="radius")), r"contact: "),
])
def test_what_lammps_cannot_express_is_refused_naming_the_field(silo, tmp_path, edit, match):
    r = copy.deepcopy(silo)
    edit(r)
    case = silo_case(r, mode="discharge", settle=0.1) if "discharge" in r else silo_case(r)
    with pytest.raises(CaseError, match=match):
        lb.write_inputs(case, tmp_path)


def test_a_disc_beyond_a_walls_end_is_refused(silo, tmp_path):
    case = silo_case(silo)
    case.discs = np.vstack([case.discs, [[-5.0, 2.0, 1.0, 0.0, 0.0, 0.0]]])   # left of the silo, over the floor line
    case.materials = np.zeros(len(case.discs), int)
    with pytest.raises(CaseError, match=r"walls: disc .* beyond the end of"):
        lb.write_inputs(case, tmp_path)


def test_dem_compare_refuses_the_hopper_for_lammps_before_any_run(tmp_path):
    """The hopper's slit needs finite walls (blocks), and its walls are inclined."""
    try:
        dem = dem_binary()
    except FileNotFoundError as e:
        pytest.skip(str(e))
    p = subprocess.run([str(dem), "compare", str(ROOT / "reference_inputs" / "agreement" / "user" / "hopper.toml"),
                        "--codes", "lammps", "--out", str(tmp_path / "out")], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 2, p.stderr
    assert "lammps cannot express it: walls: 'hopper_left'" in p.stderr
    assert not (tmp_path / "out" / "report.md").exists()


def test_discharge_deck_has_block_walls_a_dropping_gate_and_the_outlet(silo, tmp_path):
    r = copy.deepcopy(silo)
    r["discharge"] = {"gate": "gate", "outlet_depth": 4.0, "jam_time": 0.3}
    case = silo_case(r, mode="discharge", settle=0.05, duration=0.01)
    script = lb.write_inputs(case, tmp_path).read_text().splitlines()
    regions = {l.split()[1]: l.split()[2:] for l in script if l.startswith("region ")}
    blocks = [v for v in regions.values() if v[0] == "block" and "side" in v]
    assert len(blocks) == 5 and all(v[-1] == "out" or v[-4:] == ["move", "v_zero", "v_gate_dy", "NULL"] for v in blocks)
    gate = next(v for v in blocks if "move" in v)
    assert [float(x) for x in gate[1:5]] == [16.0, 24.0, -lb.BLOCK, 0.0]       # the slit, BLOCK thick below
    assert f"variable gate_dy equal (step>{round(0.05 / 5e-5)})*{-lb.GATE_DROP!r}" in script
    assert regions["outlet"][:5] == ["block", "INF", "INF", "INF", repr(-4.0)]
    assert any(l.startswith("fix outlet all evaporate 1 ") for l in script)


# --------------------------------------------------------------------------- real runs of lmp

def _cal_run(name: str, tmp_path: Path):
    c = calibration.case(name)
    res = lb.run(c, tmp_path / name, timeout=120)
    assert res.ok, res.reason
    return c, calibration.measure(c.resolved, c.discs, res.discs_end, c.duration, res.profiles)


@needs_lmp
def test_head_on_restitution_is_the_clamped_spring_dashpot(tmp_path):
    """e and t_c within the first-order scheme error of Schwager & Poeschel's closed form."""
    c, m = _cal_run("head_on_disc_disc", tmp_path)
    p = _pair(c.resolved, "sand", "sand")
    mass = c.resolved["materials"][0]["density"] * math.pi * c.discs[0, 2] ** 2
    ho = calibration.head_on(p["kn"], p["eta_n"], mass / 2, float(np.linalg.norm(c.discs[1, 3:5] - c.discs[0, 3:5])))
    # first order in dt / t_c (calibration.tolerances, K = 1); t_c one step more (it starts inside a step)
    assert abs(m["e"] - ho["e"]) <= c.dt / ho["t_c"]
    assert abs(m["t_c"] - ho["t_c"]) <= 2 * c.dt
    assert m["v_t_end"] == 0.0


@needs_lmp
def test_rolling_disc_has_the_disc_inertia_and_the_floor_carries_the_weight(tmp_path):
    """floor_launch: slides at mu g, rolls at 2/3 v0 (I = m r^2 / 2: a sphere's 2/5 would give 5/7);
    rest_on_floor: the floor carries rho pi r^2 g (the 2D mass, not 4/3 pi r^3 rho)."""
    c, m = _cal_run("floor_launch", tmp_path)
    v0 = float(c.discs[0, 3])
    assert abs(m["v_end"] - 2 / 3 * v0) <= 1e-6 * v0
    c, m = _cal_run("rest_on_floor", tmp_path)
    rho = c.resolved["materials"][0]["density"]
    weight = rho * math.pi * c.discs[0, 2] ** 2 * abs(c.resolved["gravity"][1])
    assert abs(m["floor_force"] - weight) <= 1e-9 * weight


@needs_lmp
def test_probe_reads_the_scene_constants_back_and_catches_a_mutant(tmp_path):
    c = calibration.case("oblique_wall_20deg")
    ok = probe.check_case(c, tmp_path / "ok", codes=("lammps",))["lammps"]
    assert ok["pass"] and ok["max_rel_diff"] <= 1e-12, ok
    names = {r["quantity"] for r in ok["rows"]}
    assert {"pairs[sand|wall].kn", "pairs[sand|wall].eta_s", "mass[sand@r=1.0]", "inertia[sand@r=1.0]"} <= names
    mu = next(m for m in mutants.mutations(["lammps"]) if m.name == "lammps_mu_disc_wall_x0.9")
    bad = probe.probe("lammps", dataclasses.replace(c, resolved=mu.apply(c.resolved)), tmp_path / "mu")
    rows = probe.compare_constants(probe.expected_constants(c.resolved, c.discs, c.dt), bad)
    wrong = [r["quantity"] for r in rows if not r["pass"]]
    assert wrong == ["pairs[sand|wall].mu"], wrong


@needs_lmp
def test_runner_reports_a_broken_input_clearly(silo, tmp_path, monkeypatch):
    real = lb._script
    monkeypatch.setattr(lb, "_script", lambda *a, **k: real(*a, **k).replace("pair_style granular", "pair_style nosuch"))
    res = lb.run(silo_case(silo), tmp_path, timeout=120)
    assert not res.ok and "lammps failed" in res.reason and "ERROR" in res.reason


@needs_lmp
def test_version_names_lammps():
    assert re.match(r"LAMMPS \d+ \w+ \d{4}", lb.version()), lb.version()


@needs_lmp
def test_discharge_block_walls_carry_what_the_planes_carry_and_discs_leave(silo, tmp_path):
    """Before the opening the five block walls of a discharge give the forces of the three planes of
    the static translation (the same contacts: round-off apart); after it discs fall out, every disc
    is either removed or still in, and the dropped gate carries nothing."""
    settle = 0.05
    static = lb.run(silo_case(silo, duration=settle, series_interval=settle), tmp_path / "static", timeout=300)
    r = copy.deepcopy(silo)
    r["discharge"] = {"gate": "gate", "outlet_depth": 4.0, "jam_time": 0.3}
    dis = lb.run(silo_case(r, mode="discharge", settle=settle, duration=0.2), tmp_path / "discharge", timeout=300)
    assert static.ok and dis.ok, (static.reason, dis.reason)
    for w, prof in static.profiles.items():
        at_opening = np.array(dis.series["walls"][w]["normal"][0])
        assert np.allclose(at_opening, prof["normal"], rtol=1e-9, atol=1e-9 * max(prof["normal"])), w
    assert dis.series["t"][0] == 0.0
    assert len(dis.removals) >= 1 and min(dis.removals) > 0
    assert dis.n_final + len(dis.removals) == len(silo["discs"])
    assert all(sum(row) == 0.0 for row in dis.series["walls"]["gate"]["normal"][1:])

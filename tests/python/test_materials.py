"""Scenes with several disc materials (glass and steel) and several wall materials (a steel box,
a rubber ledge) through the LIGGGHTS, YADE and native translations.

Expected values come from the scene written here (its pairs and densities) and from YADE's
series rule k = k1 k2 / (k1 + k2), never from a run of our engine; the probes run the real
`liggghts` and `yade` (skipped when not installed).
"""
from __future__ import annotations

import csv
import dataclasses
import json
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from dem.compare.codes import liggghts_backend, native_backend, yade_backend
from dem.compare.verdict import probe as P
from dem.compare.io import scene_toml
from dem.compare.cases.common import PYTHON, ROOT, SHARED_VARIANT, Case, CaseError, dem_binary, kinetic_energy, resolve

needs_liggghts = pytest.mark.skipif(not liggghts_backend.available(), reason="liggghts is not on PATH")
needs_yade = pytest.mark.skipif(not yade_backend.available(), reason="yade is not on PATH")

DENSITY = {"glass": 2.5, "steel": 7.8}
FIELDS = ("kn", "ks", "eta_n", "eta_s", "mu")
# Disc-disc pairs of each disc material, and the disc-wall pairs of glass (YADE solves its wall
# materials from these).
OWN = {("glass", "glass"): (1.0e7, 4.0e6, 2.0e3, 8.0e2, 0.5), ("steel", "steel"): (3.0e7, 1.0e7, 5.0e3, 2.0e3, 0.3),
       ("glass", "steelwall"): (1.2e7, 4.5e6, 2.5e3, 9.0e2, 0.35), ("glass", "rubber"): (6.0e6, 2.0e6, 1.5e3, 6.0e2, 0.8)}
# The cross pairs as a user writes them (not YADE's series values).
FREE = {("glass", "steel"): (1.5e7, 5.0e6, 3.0e3, 1.0e3, 0.4), ("steel", "steelwall"): (3.5e7, 1.2e7, 6.0e3, 2.2e3, 0.25),
        ("steel", "rubber"): (8.0e6, 2.5e6, 1.8e3, 7.0e2, 0.7)}
WALLS = [("floor", (0.0, 0.0), (24.0, 0.0), "steelwall"), ("left", (0.0, 20.0), (0.0, 0.0), "steelwall"),
         ("right", (24.0, 0.0), (24.0, 20.0), "steelwall"), ("ledge", (0.0, 1.5), (13.0, 1.5), "rubber"),
         ("stop", (13.0, 1.5), (13.0, 4.0), "steelwall")]


def series(a: float, b: float) -> float:
    return a * b / (a + b)


def series_pairs() -> dict:
    """The cross pairs YADE's series combination gives: disc material = 2 x its own pair; a wall
    material w solved from glass, series(2 x glass-glass, w) = glass-wall, so
    w = k_gw k_g / (k_g - k_gw); steel-wall = series(2 x steel-steel, w). Friction is free."""
    out = {}
    g, s = OWN[("glass", "glass")], OWN[("steel", "steel")]
    out[("glass", "steel")] = tuple(series(2 * a, 2 * b) for a, b in zip(g[:4], s[:4])) + (0.4,)
    for wm, mu in (("steelwall", 0.25), ("rubber", 0.7)):
        gw = OWN[("glass", wm)]
        w = [k * 2 * kg / (2 * kg - k) for k, kg in zip(gw[:4], g[:4])]
        out[("steel", wm)] = tuple(series(2 * a, b) for a, b in zip(s[:4], w)) + (mu,)
    return out


def discs() -> list[tuple]:
    """x, y, r, material: a row of glass and steel jammed on the ledge between the left wall and
    the stop (overlapping by 1e-3 cm), four discs in its grooves, four apart on the floor beside
    it (the discs' centroid stays above the ledge: the comparison judges a wall on the discs'
    side)."""
    rows = [(0.5005 + 0.999 * i, 2.1, 0.5, "glass" if i % 2 == 0 else "steel") for i in range(13)]
    rows += [(0.5005 + 0.999 * (i + 0.5), 2.9, 0.4, "glass" if i % 4 == 0 else "steel") for i in (0, 2, 4, 6)]
    rows += [(17.0 + 1.5 * i, 0.6, 0.5 if i in (0, 3) else 0.4, "steel" if i % 2 == 0 else "glass") for i in range(4)]
    return rows


def write_scene(folder: Path, cross: dict, name: str = "two_materials") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / f"{name}.csv", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["x", "y", "r", "material"])
        w.writerows([[x, y, r, m] for x, y, r, m in discs()])
    return scene_toml.write(folder / f"{name}.toml", {
        "scene": {"name": name},
        "physics": {"gravity": [0.0, -980.0]},
        "integrator": {"scheme": "velocity_verlet", "dt": 5e-5},
        "materials": {**{m: {"density": rho} for m, rho in DENSITY.items()}, "steelwall": {}, "rubber": {}},
        "pairs": [{"materials": [a, b], **dict(zip(FIELDS, vals))} for (a, b), vals in (OWN | cross).items()],
        "walls": [{"name": wname, "from": list(a), "to": list(b), "material": m} for wname, a, b, m in WALLS],
        "fill": {"type": "file", "file": f"{name}.csv", "material": "glass", "count": len(discs()),
                 "max_initial_overlap": 0.01},
        "end": {"time": 1.0},
        "output": {"profile_bin": 2.0}})


def pair_of(cross: dict, a: str, b: str) -> dict:
    table = OWN | cross
    vals = table.get((a, b), table.get((b, a)))
    return dict(zip(FIELDS, vals))


def make_case(tmp_path: Path, cross: dict) -> Case:
    try:
        dem_binary()
    except FileNotFoundError as e:
        pytest.skip(f"needs the engine for `dem resolve`: {e}")
    r = resolve(write_scene(tmp_path / "scene", cross))
    r["contact"] = dict(SHARED_VARIANT)
    d = np.array(r["discs"], float)
    return Case(name="two_materials", resolved=r, discs=np.column_stack([d[:, :3], np.zeros((len(d), 3))]),
                dt=5e-5, duration=0.01, materials=d[:, 3].astype(int))


@pytest.fixture
def free_case(tmp_path) -> Case:
    return make_case(tmp_path, FREE)


@pytest.fixture
def series_case(tmp_path) -> Case:
    return make_case(tmp_path, series_pairs())


def _failing(rows) -> set[str]:
    return {r["quantity"] for r in rows if not r["pass"]}


ALL_PAIRS = {"glass|glass", "glass|steel", "steel|steel", "glass|rubber", "glass|steelwall", "steel|rubber",
             "steel|steelwall"}


# ------------------------------------------------------------------------------------------
def test_case_materials_and_kinetic_energy(free_case):
    assert free_case.material_names() == [m for *_x, m in discs()]
    assert free_case.disc_materials() == ["glass", "steel"]
    d = np.array(free_case.discs, float)
    d[:, 3], d[:, 5] = 2.0, 3.0
    want = sum(DENSITY[m] * math.pi * r * r * (0.5 * 4.0 + 0.25 * r * r * 9.0) for *_xy, r, m in discs())
    assert kinetic_energy(free_case.resolved, d, free_case.material_index()) == pytest.approx(want, rel=1e-14)
    wrong = np.zeros(len(d), int) + free_case.material_index()[0]       # every disc glass
    assert kinetic_energy(free_case.resolved, d, wrong) != pytest.approx(want, rel=1e-3)
    with pytest.raises(CaseError, match="materials"):                    # a packing of other discs
        dataclasses.replace(free_case, discs=d[:3], materials=None).material_index()


def test_expected_constants_list_every_pair_and_material(free_case):
    e = P.expected_constants(free_case.resolved, free_case.discs, free_case.dt, free_case.material_index())
    assert set(e["pairs"]) == ALL_PAIRS
    for key, vals in e["pairs"].items():
        assert vals == pair_of(FREE, *key.split("|"))
    assert e["mass"] == {f"{m}@r={r!r}": pytest.approx(DENSITY[m] * math.pi * r * r, rel=1e-15)
                         for m in DENSITY for r in (0.4, 0.5)}


def test_native_packing_carries_each_discs_material(free_case, tmp_path):
    scene = native_backend.write_inputs(free_case, tmp_path)
    rows = list(csv.DictReader(open(tmp_path / "packing.csv")))
    assert [row["material"] for row in rows] == [m for *_x, m in discs()]
    names = [m["name"] for m in free_case.resolved["materials"]]
    assert [names[int(d[3])] for d in resolve(scene)["discs"]] == [m for *_x, m in discs()]
    res = P.probe("native", free_case, tmp_path / "probe")
    e = P.expected_constants(free_case.resolved, free_case.discs, free_case.dt, free_case.material_index())
    assert res["status"] == "ok" and not _failing(P.compare_constants(e, res))


def test_native_probe_sees_a_packing_without_materials(free_case, tmp_path, monkeypatch):
    """A packing written without the material column: the engine makes every disc fill.material
    (glass); the steel pairs and masses are missing from what the probe reads back."""
    orig = native_backend.write_inputs

    def no_column(case, out_dir, threads=1):
        glass = dataclasses.replace(case, materials=np.zeros(len(case.discs), int))   # index 0: glass
        return orig(glass, out_dir, threads)

    monkeypatch.setattr(native_backend, "write_inputs", no_column)
    res = P.probe("native", free_case, tmp_path)
    e = P.expected_constants(free_case.resolved, free_case.discs, free_case.dt, free_case.material_index())
    assert {"pairs[glass|steel].kn", "pairs[steel|rubber].mu", "mass[steel@r=0.5]"} <= _failing(
        P.compare_constants(e, res))


def test_liggghts_types_densities_and_matrices(free_case, tmp_path):
    liggghts_backend.write_inputs(free_case, tmp_path)
    types = {"glass": 1, "steel": 2, "rubber": 3, "steelwall": 4}      # discs, then walls, by material order
    data = (tmp_path / "discs.data").read_text().splitlines()
    assert "4 atom types" in data
    k = data.index("Atoms") + 2
    for line, (x, y, r, m) in zip(data[k:k + len(discs())], discs()):
        f = line.split()
        assert int(f[1]) == types[m] and float(f[3]) == DENSITY[m] and float(f[4]) == x
    script = (tmp_path / "in.liggghts").read_text()
    for wname, _a, _b, m in WALLS:
        assert f"fix w_{wname} all mesh/surface/stress file w_{wname}.stl type {types[m]}" in script
    names = sorted(types, key=types.get)
    for key, field in (("kn", "kn"), ("kt", "ks"), ("gamman_abs", "eta_n"), ("gammat_abs", "eta_s"),
                       ("coefficientFriction", "mu")):
        line = next(l for l in script.splitlines() if f"property/global {key} peratomtypepair 4 " in l)
        m = np.array(line.split()[7:], float).reshape(4, 4)
        assert np.array_equal(m, m.T)
        for i, a in enumerate(names):
            for j, b in enumerate(names):
                if a in DENSITY or b in DENSITY:
                    assert m[i, j] == pair_of(FREE, a, b)[field], (key, a, b)


def test_liggghts_refuses_a_missing_disc_wall_pair(free_case, tmp_path):
    r = json.loads(json.dumps(free_case.resolved))
    r["pairs"] = [p for p in r["pairs"] if sorted(p["materials"]) != ["rubber", "steel"]]
    with pytest.raises(CaseError, match=r"pairs: no constants for materials 'steel' and 'rubber'"):
        liggghts_backend.write_inputs(dataclasses.replace(free_case, resolved=r), tmp_path)


def test_liggghts_refuses_a_point_of_another_material_than_its_walls(free_case, tmp_path):
    """A point is the mesh edge of the walls ending at it: the ledge's free end (13, 1.5) is also
    the stop's lower end, so a point there must be of rubber and steelwall at once."""
    r = json.loads(json.dumps(free_case.resolved))
    r["points"] = [{"name": "tip", "group": "tip", "at": [13.0, 1.5], "material": "rubber"}]
    with pytest.raises(CaseError, match=r"points: tip has material 'rubber' but wall 'stop'"):
        liggghts_backend.write_inputs(dataclasses.replace(free_case, resolved=r), tmp_path)


def test_yade_refuses_a_cross_pair_that_is_not_the_series_value(free_case, series_case):
    want = series(2 * OWN[("glass", "glass")][2], 2 * OWN[("steel", "steel")][2])
    with pytest.raises(CaseError, match=r"pairs\[glass,steel\]\.eta_n: YADE") as e:
        yade_backend.case_data(free_case)
    assert repr(want) in str(e.value)
    r = json.loads(json.dumps(series_case.resolved))       # disc pairs in series, one wall pair not
    for p in r["pairs"]:
        if sorted(p["materials"]) == ["steel", "steelwall"]:
            p["ks"] *= 1.01
    with pytest.raises(CaseError, match=r"pairs\[steel,steelwall\]\.ks: YADE has one 'steelwall' wall material"):
        yade_backend.case_data(dataclasses.replace(series_case, resolved=r))
    data = yade_backend.case_data(series_case)               # the series scene is expressed
    assert data["disc_material_of"] == [m for *_x, m in discs()]
    assert data["disc_materials"]["steel"]["density"] == DENSITY["steel"]


# ------------------------------------------------------------------------------------------
def _probe_rows(code: str, case: Case, out: Path):
    res = P.probe(code, case, out)
    assert res["status"] == "ok", res["reason"]
    e = P.expected_constants(case.resolved, case.discs, case.dt, case.material_index())
    return P.compare_constants(e, res)


@needs_liggghts
def test_liggghts_probe_reads_every_pair(free_case, tmp_path):
    rows = _probe_rows("liggghts", free_case, tmp_path)
    assert not _failing(rows), [r for r in rows if not r["pass"]]
    assert {q.split("]")[0][6:] for q in (r["quantity"] for r in rows) if q.startswith("pairs[")} == ALL_PAIRS
    assert max(r["rel_diff"] for r in rows) < 1e-9


@needs_liggghts
def test_liggghts_probe_sees_swapped_disc_wall_entries(free_case, tmp_path, monkeypatch):
    """The kn matrix with glass-rubber and steel-rubber swapped (types 1-3 and 2-3, both halves)."""
    orig = liggghts_backend._matrix

    def swapped(c, key):
        m = np.array(orig(c, key).split(), float).reshape(4, 4)
        if key == "kn":
            m[0, 2], m[1, 2] = m[1, 2], m[0, 2]
            m[2, 0], m[2, 1] = m[2, 1], m[2, 0]
        return " ".join(repr(float(v)) for v in m.ravel())

    monkeypatch.setattr(liggghts_backend, "_matrix", swapped)
    assert _failing(_probe_rows("liggghts", free_case, tmp_path)) == {"pairs[glass|rubber].kn",
                                                                      "pairs[steel|rubber].kn"}


@needs_yade
def test_yade_probe_reads_every_pair_of_the_series_scene(series_case, tmp_path):
    rows = _probe_rows("yade", series_case, tmp_path)
    assert not _failing(rows), [r for r in rows if not r["pass"]]
    assert {q.split("]")[0][6:] for q in (r["quantity"] for r in rows) if q.startswith("pairs[")} == ALL_PAIRS
    assert max(r["rel_diff"] for r in rows) < 1e-9


@needs_yade
def test_yade_probe_sees_a_wrong_disc_material(series_case, tmp_path, monkeypatch):
    """Steel's density x 1.05 in the YADE translation: its masses and inertias fail, nothing else."""
    orig = yade_backend.materials

    def heavy(resolved, names=None):
        d, w, f = orig(resolved, names)
        d["steel"]["density"] *= 1.05
        return d, w, f

    monkeypatch.setattr(yade_backend, "materials", heavy)
    failing = _failing(_probe_rows("yade", series_case, tmp_path))
    assert failing == {f"{q}[steel@r={r!r}]" for q in ("mass", "inertia") for r in (0.4, 0.5)}


# ------------------------------------------------------------------------------------------
def _compare(*args, timeout):
    """`dem compare ARGS` as the binary runs it: this tree's comparison layer (python3 -m dem.compare
    scene) with the engine as the native code."""
    env = dict(os.environ, DEM_BINARY=str(dem_binary()))
    return subprocess.run([PYTHON, "-m", "dem.compare", "scene", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, env=env, cwd=ROOT)


@needs_liggghts
def test_two_materials_static_frozen_through_dem_compare(tmp_path):
    """native and LIGGGHTS agree on the scene with its own cross pairs, and every mutant of the
    LIGGGHTS translation (one constant of every pair, or density, or gravity, wrong) is caught."""
    scene = write_scene(tmp_path / "scene", FREE)
    out = tmp_path / "out"
    p = _compare(scene, "--codes", "native,liggghts", "--settle", "1.0", "--duration", "0.1", "--mutants",
                 "--out", out, timeout=900)
    rep = json.loads((out / "agreement.json").read_text())
    assert p.returncode == 0, [m for m in rep["metrics"] if not m["pass"]] or p.stdout[-2000:] + p.stderr[-2000:]
    names = {m["metric"] for m in rep["metrics"]}
    assert "translation constants read back (liggghts)" in names
    assert any(n.startswith("weight carried by the walls") for n in names)
    mutants = json.loads((out / "mutants.json").read_text())
    from dem.compare.cases.mutants import SPECS
    assert mutants["all_caught"] and len(mutants["rows"]) == len(SPECS)
    # no bonds, no side-wall group, no points: those mutants change nothing here
    assert [r["mutant"] for r in mutants["rows"] if not r["applicable"]] == [
        "liggghts_bonds_touching_only", "liggghts_wall_right_shift_0.01r", "liggghts_slit_ends_0.2r"]
    density = next(r for r in mutants["rows"] if r["mutant"] == "liggghts_density_x1.01")
    assert density["caught_physically"]          # the weight and the wall totals see a wrong density
    refused = _compare(scene, "--codes", "native,yade", "--out", tmp_path / "refused", timeout=300)
    assert refused.returncode == 2 and "yade cannot express it: pairs[glass,steel].eta_n" in refused.stderr


def test_collision_and_janssen_kinds_refuse_several_disc_materials(tmp_path):
    from dem.compare.cases.plan import Entry, Options, PlanError, make_plan
    scene = write_scene(tmp_path / "scene", FREE)
    for kind in ("collision", "janssen"):
        with pytest.raises(PlanError, match=f"fill: --kind {kind} judges discs of one material"):
            make_plan(Entry(scene, Options(kind=kind)))
    assert make_plan(Entry(scene, Options())).kind == "static"


@needs_liggghts
@needs_yade
def test_series_scene_static_frozen_in_all_three_codes(tmp_path):
    """With the cross pairs at YADE's series values every code runs the scene, and they agree."""
    scene = write_scene(tmp_path / "scene", series_pairs())
    out = tmp_path / "out"
    p = _compare(scene, "--codes", "native,liggghts,yade", "--settle", "1.0", "--duration", "0.1", "--out", out,
                 timeout=900)
    rep = json.loads((out / "agreement.json").read_text())
    assert p.returncode == 0, [m for m in rep["metrics"] if not m["pass"]] or p.stderr[-2000:]
    assert {"translation constants read back (yade)", "static wall normal totals (yade vs native)",
            "weight carried by the walls at rest (yade vs rho pi r^2 g)"} <= {m["metric"] for m in rep["metrics"]}

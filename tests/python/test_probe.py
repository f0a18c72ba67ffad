"""dem.compare.verdict.probe: each code's effective constants, read back from the code, equal the resolved
scene's to 1e-9, and a wrong translation (a backend that scales one constant, or a case whose
resolved constants were changed for the code) fails compare_constants naming the quantity.

The expected values come from the resolved scene (the engine's `dem resolve`), never from a
probe; the probes run the real `liggghts` and `yade` (skipped when not installed).
"""
from __future__ import annotations

import copy
import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from dem.compare.codes import liggghts_backend, native_backend, yade_backend
from dem.compare.verdict import probe as P
from dem.compare.cases.common import SHARED_VARIANT, Case, dem_binary, resolve

ROOT = Path(__file__).resolve().parents[2]
DD = {"kn": 9.0e7, "ks": 3.0e7, "eta_n": 3.0e4, "eta_s": 1.0e4, "mu": 0.5}
DW = {"kn": 1.35e8, "ks": 4.0e7, "eta_n": 5.0e4, "eta_s": 1.5e4, "mu": 0.2}   # not 2 x DD: YADE solves its series
PROBE_SECONDS = 10.0    # each probe must stay a few seconds: it runs once per case in every report

needs_liggghts = pytest.mark.skipif(not liggghts_backend.available(), reason="liggghts is not on PATH")
needs_yade = pytest.mark.skipif(not yade_backend.available(), reason="yade is not on PATH")


@pytest.fixture(scope="module")
def case() -> Case:
    """The 17/18 silo (walls, slit points, 350 discs) with two materials whose disc-disc and
    disc-wall constants all differ."""
    try:
        dem_binary()
    except FileNotFoundError as e:
        pytest.skip(f"needs the engine for `dem resolve`: {e}")
    r = resolve(ROOT / "reference_inputs" / "scenes" / "silo_17_18.toml")
    r["contact"] = dict(SHARED_VARIANT)
    for p in r["pairs"]:
        p.update(DD if p["materials"] == ["sand", "sand"] else DW)
    d = np.array(r["discs"], float)
    return Case(name="probe_small", resolved=r, discs=np.column_stack([d[:, :3], np.zeros((len(d), 3))]),
                dt=5e-5, duration=0.01)


def _expected(case: Case) -> dict:
    return P.expected_constants(case.resolved, case.discs, case.dt)


def _failing(rows) -> set[str]:
    return {r["quantity"] for r in rows if not r["pass"]}


def _mutated(case: Case, pair: str, field: str, factor: float) -> Case:
    r = copy.deepcopy(case.resolved)
    for p in r["pairs"]:
        if "|".join(p["materials"]) == pair:
            p[field] *= factor
    return dataclasses.replace(case, resolved=r)


# ------------------------------------------------------------------------------------------
def test_expected_constants_from_formulas(case):
    e = _expected(case)
    m = 2.65 * math.pi * 1.0 ** 2
    assert e["pairs"] == {"sand|sand": DD, "sand|wall": DW}
    assert e["mass"] == {"sand@r=1.0": pytest.approx(m, rel=1e-15)}
    assert e["inertia"] == {"sand@r=1.0": pytest.approx(m / 2, rel=1e-15)}
    assert e["gravity"] == [0.0, -980.0] and e["dt"] == 5e-5


def test_compare_constants_flags_a_wrong_or_missing_quantity(case):
    e = _expected(case)
    good = {"constants": json.loads(json.dumps(e))}
    assert not _failing(P.compare_constants(e, good))
    bad = json.loads(json.dumps(good))
    bad["constants"]["pairs"]["sand|wall"]["ks"] *= 1 + 2e-9
    bad["constants"]["gravity"][0] = 1e-6 * 980        # expected 0: judged against |g|
    del bad["constants"]["inertia"]["sand@r=1.0"]
    bad["checks"] = {"mass[sand@r=1.0]": 1.1 * e["mass"]["sand@r=1.0"]}
    rows = P.compare_constants(e, bad)
    assert _failing(rows) == {"pairs[sand|wall].ks", "gravity[x]", "inertia[sand@r=1.0]", "mass[sand@r=1.0] (check)"}
    assert next(r for r in rows if r["quantity"] == "gravity[x]")["rel_diff"] == pytest.approx(1e-6)


def test_layout_places_every_probe_disc_in_one_contact_only(case):
    lay = P.layout(case)
    d = lay.discs
    touching = set()
    for i in range(len(d)):
        for j in range(i + 1, len(d)):
            if np.hypot(*(d[i, :2] - d[j, :2])) < d[i, 2] + d[j, 2]:
                touching.add((i, j))
    assert touching == {lay.pairs[k] for k in ("rest", "closing", "sliding")}
    on_wall = {row: name for roles in lay.walls.values() for row, name in roles.values()}
    for i in range(len(d)):
        near = {w["name"]: P._seg_dist(d[i, :2], w["from"], w["to"]) for w in case.resolved["walls"]}
        near = {k: v for k, v in near.items() if v < d[i, 2]}
        assert list(near) == ([on_wall[i]] if i in on_wall else [])
        for dist in near.values():
            assert dist == pytest.approx(d[i, 2] * (1 - P.OVERLAP), rel=1e-12)


# ------------------------------------------------------------------------------------------
def test_native_probe_reads_the_resolved_constants(case, tmp_path):
    res = P.probe("native", case, tmp_path)
    assert res["status"] == "ok", res["reason"]
    assert not _failing(P.compare_constants(_expected(case), res))


def test_native_probe_sees_a_wrong_scene_translation(case, tmp_path, monkeypatch):
    orig = native_backend.scene_toml
    monkeypatch.setattr(native_backend, "scene_toml",
                        lambda c, f: orig(_mutated(c, "sand|wall", "eta_s", 1.05), f))
    res = P.probe("native", case, tmp_path)
    assert _failing(P.compare_constants(_expected(case), res)) == {"pairs[sand|wall].eta_s"}


@pytest.mark.parametrize("code", ["liggghts", "yade"])
def test_probe_reads_the_resolved_constants(code, case, tmp_path):
    if not {"liggghts": liggghts_backend, "yade": yade_backend}[code].available():
        pytest.skip(f"{code} is not on PATH")
    res = P.probe(code, case, tmp_path)
    assert res["status"] == "ok", res["reason"]
    rows = P.compare_constants(_expected(case), res)
    assert not _failing(rows), [r for r in rows if not r["pass"]]
    assert max(r["rel_diff"] for r in rows) < 1e-12
    assert len(rows) > 15                         # 2 pairs x 5, mass, inertia, gravity x 2, dt, checks
    assert res["wall_time_s"] < PROBE_SECONDS


@needs_liggghts
@pytest.mark.parametrize("key,field", [("kn", "kn"), ("kt", "ks"), ("gamman_abs", "eta_n"), ("gammat_abs", "eta_s"),
                                       ("coefficientFriction", "mu")])
def test_liggghts_probe_sees_a_scaled_matrix(key, field, case, tmp_path, monkeypatch):
    orig = liggghts_backend._matrix

    def scaled(c, k):
        m = orig(c, k)
        return " ".join(repr(float(v) * 1.05) for v in m.split()) if k == field else m

    monkeypatch.setattr(liggghts_backend, "_matrix", scaled)
    res = P.probe("liggghts", case, tmp_path)
    assert res["status"] == "ok", res["reason"]
    text = (tmp_path / "in.probe").read_text()
    assert f"property/global {key} peratomtypepair 2 {DD[field] * 1.05!r}" in text
    assert _failing(P.compare_constants(_expected(case), res)) == {f"pairs[sand|sand].{field}", f"pairs[sand|wall].{field}"}


@needs_yade
@pytest.mark.parametrize("field,name", [("kn", "kn"), ("cs", "eta_s")])
def test_yade_probe_sees_a_scaled_material(field, name, case, tmp_path, monkeypatch):
    orig = yade_backend.materials

    def scaled(resolved, names=None):
        discs, walls, friction = orig(resolved, names)
        return {m: dict(d, **{field: d[field] * 1.05}) for m, d in discs.items()}, walls, friction

    monkeypatch.setattr(yade_backend, "materials", scaled)
    res = P.probe("yade", case, tmp_path)
    assert res["status"] == "ok", res["reason"]
    failing = _failing(P.compare_constants(_expected(case), res))
    want = {f"pairs[sand|sand].{name}", f"pairs[sand|wall].{name}"}
    assert failing == (want | {f"{q} (check)" for q in want} if name == "kn" else want)


@pytest.mark.parametrize("code", ["liggghts", "yade"])
def test_probe_sees_a_mutated_case(code, case, tmp_path):
    """The case the code runs carries mu x 0.9 (disc-disc), density x 1.1, gravity x 0.99 and dt x 2;
    compared with the unmutated expectation, exactly those quantities fail."""
    if not {"liggghts": liggghts_backend, "yade": yade_backend}[code].available():
        pytest.skip(f"{code} is not on PATH")
    bad = _mutated(case, "sand|sand", "mu", 0.9)
    for m in bad.resolved["materials"]:
        if m["name"] == "sand":
            m["density"] *= 1.1
    bad.resolved["gravity"] = [0.0, -980.0 * 0.99]
    bad = dataclasses.replace(bad, dt=2 * case.dt)
    res = P.probe(code, bad, tmp_path)
    assert res["status"] == "ok", res["reason"]
    failing = _failing(P.compare_constants(_expected(case), res))
    assert failing - {"mass[sand@r=1.0] (check)"} == {"pairs[sand|sand].mu", "mass[sand@r=1.0]",
                                                      "inertia[sand@r=1.0]", "gravity[y]", "dt"}

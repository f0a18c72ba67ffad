"""dem.compare.verdict.geometry_probe: each code's walls, points, radii and start positions, read back from the
code after its setup, equal the case's to 1e-9 of the scene's length scale; a moved wall, point,
radius or position fails naming the item. And the probes' cache key (pipeline.probe_key) is the
bytes of the translated inputs: a translation that differs gets its own probe.

Expected values come from the case (its resolved walls and points, its discs) and the tolerance
from geometry_probe.REL; the real-code tests run `liggghts`, `yade` and `lmp` (skipped when absent).
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import types
from pathlib import Path

import numpy as np
import pytest

from dem.compare.verdict import geometry_probe as G
from dem.compare.codes import lammps_backend, liggghts_backend, yade_backend
from dem.compare.verdict import pipeline, probe as P
from dem.compare.cases.common import SHARED_VARIANT, Case, dem_binary, resolve
from dem.compare.cases.mutants import Mutation

ROOT = Path(__file__).resolve().parents[2]
RUN_SECONDS = 20.0      # a zero-step run of a tiny case in each code


def _box_case() -> Case:
    """A box with a slit in its floor (points L and R at the joints) and three discs; no engine."""
    walls = [{"name": "left", "from": [0.0, 10.0], "to": [0.0, 0.0]},
             {"name": "right", "from": [12.0, 10.0], "to": [12.0, 0.0]},
             {"name": "bottom_left", "from": [0.0, 0.0], "to": [5.0, 0.0]},
             {"name": "gate", "from": [5.0, 0.0], "to": [7.0, 0.0]},
             {"name": "bottom_right", "from": [7.0, 0.0], "to": [12.0, 0.0]}]
    points = [{"name": "L", "at": [5.0, 0.0]}, {"name": "R", "at": [7.0, 0.0]}]
    discs = np.array([[2.0, 1.0, 1.0, 0, 0, 0], [4.5, 1.0, 0.75, 0, 0, 0], [8.0, 3.0, 1.25, 0, 0, 0]], float)
    return Case(name="box", resolved={"walls": walls, "points": points}, discs=discs, dt=1e-5, duration=1e-5)


def _as_read(e: dict) -> dict:
    """The expected geometry in the form a code's read-back has (ends, z = 0 discs)."""
    return {"walls": {k: {"from": list(w["from"]), "to": list(w["to"])} for k, w in e["walls"].items()},
            "points": {k: list(v) for k, v in e["points"].items()},
            "discs": [[x, y, 0.0, r] for x, y, r in e["discs"]]}


def _failing(rows) -> set[str]:
    return {r["item"] for r in rows if not r["pass"]}


# ------------------------------------------------------------------------------------------
def test_length_scale_is_the_diagonal_of_walls_points_and_discs():
    c = _box_case()
    d = c.discs
    xs = [0.0, 12.0] + list(d[:, 0] - d[:, 2]) + list(d[:, 0] + d[:, 2])
    ys = [0.0, 10.0] + list(d[:, 1] - d[:, 2]) + list(d[:, 1] + d[:, 2])
    assert G.expected_geometry(c)["length"] == math.hypot(max(xs) - min(xs), max(ys) - min(ys))


def test_the_case_itself_passes():
    e = G.expected_geometry(_box_case())
    rows = G.compare_geometry(e, _as_read(e))
    assert rows and not _failing(rows) and max(r["rel"] for r in rows) == 0.0


@pytest.mark.parametrize("factor, fails", [(0.5, False), (2.0, True)])
def test_a_moved_item_fails_beyond_the_tolerance_only(factor, fails):
    """Each kind of item moved by factor x REL x L: a wall end, a face point off the wall, a point,
    a disc's position (in z too) and a radius."""
    e = G.expected_geometry(_box_case())
    eps = factor * G.REL * e["length"]
    moves = {
        "walls[right].to": lambda r: r["walls"]["right"]["to"].__setitem__(0, 12.0 + eps),
        "walls[gate].face": lambda r: r["walls"]["gate"].__setitem__("face", [[6.0, -eps, 0.0]]),
        "points[L]": lambda r: r["points"].__setitem__("L", [5.0 + eps, 0.0]),
        "discs[1].position": lambda r: r["discs"][1].__setitem__(2, eps),
        "discs[2].radius": lambda r: r["discs"][2].__setitem__(3, 1.25 + eps),
    }
    for item, move in moves.items():
        read = _as_read(e)
        move(read)
        rows = G.compare_geometry(e, read)
        assert _failing(rows) == ({item} if fails else set()), item
        row = next(r for r in rows if r["item"] == item)
        assert row["deviation"] == pytest.approx(eps, rel=1e-6), item


def test_a_reversed_wall_is_the_same_wall_and_a_missing_or_extra_one_fails():
    e = G.expected_geometry(_box_case())
    read = _as_read(e)
    w = read["walls"]["gate"]
    w["from"], w["to"] = w["to"], w["from"]
    assert not _failing(G.compare_geometry(e, read))
    del read["walls"]["left"]
    read["walls"]["lid"] = {"from": [0.0, 10.0], "to": [12.0, 10.0]}
    read["discs"].pop()
    assert _failing(G.compare_geometry(e, read)) == {"walls[left]", "walls[lid]", "discs"}


def test_a_plane_is_judged_by_the_distance_of_the_wall_ends_from_it():
    """LAMMPS's read: two points of its plane; a plane tilted so that one end is off by 2 REL L fails."""
    e = G.expected_geometry(_box_case())
    read = _as_read(e)
    read["points"] = None
    eps = 2 * G.REL * e["length"]
    read["walls"] = {k: {"line": [w["from"], w["to"]]} for k, w in e["walls"].items()}
    assert not _failing(G.compare_geometry(e, read))
    # right wall: x = 12 at y = 10, x = 12 + eps at y = 0 (the points lie beyond the ends)
    read["walls"]["right"] = {"line": [[12.0 - eps, 20.0], [12.0 + 2 * eps, -10.0]]}
    rows = G.compare_geometry(e, read)
    assert _failing(rows) == {"walls[right].to (plane)"}
    assert next(r for r in rows if r["item"] == "walls[right].to (plane)")["deviation"] == pytest.approx(eps, rel=1e-6)


# ------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def silo() -> Case:
    """The 17/18 silo's walls and slit points with its first six discs (the shared law)."""
    try:
        dem_binary()
    except FileNotFoundError as e:
        pytest.skip(f"needs the engine for `dem resolve`: {e}")
    r = resolve(ROOT / "reference_inputs" / "scenes" / "silo_17_18.toml")
    r["contact"] = dict(SHARED_VARIANT)
    d = np.array(r["discs"], float)[:6]
    return Case(name="geometry_small", resolved=r, discs=np.column_stack([d[:, :3], np.zeros((len(d), 3))]),
                dt=5e-5, duration=5e-5)


def _mutated(case: Case, code: str, what: str, factor: float) -> Case:
    m = Mutation("m", code, "geometry", what, factor, "all")
    return dataclasses.replace(case, resolved=m.apply(case.resolved))


BACKENDS = {"liggghts": liggghts_backend, "yade": yade_backend, "lammps": lammps_backend}


@pytest.mark.parametrize("code", list(BACKENDS))
def test_the_real_code_builds_the_case_and_a_moved_wall_is_seen(silo, code, tmp_path):
    if not BACKENDS[code].available():
        pytest.skip(f"{code} is not on PATH")
    e = G.expected_geometry(silo)
    res = G.probe(code, silo, tmp_path / "clean")
    assert res["status"] == "ok", res["reason"]
    assert res["wall_time_s"] < RUN_SECONDS
    rows = G.compare_geometry(e, res["geometry"])
    assert not _failing(rows), [r for r in rows if not r["pass"]]
    assert len(res["geometry"]["discs"]) == len(silo.discs)
    # the right wall moved outwards by 1 % of the radius in the case the code translates
    shift = 0.01 * float(np.min(np.array(silo.resolved["discs"])[:, 2]))
    res = G.probe(code, _mutated(silo, code, "wall_right", 0.01), tmp_path / "moved")
    assert res["status"] == "ok", res["reason"]
    rows = G.compare_geometry(e, res["geometry"])
    want = {"walls[right].from (plane)", "walls[right].to (plane)"} if code == "lammps" else \
        {"walls[right].from", "walls[right].to"} | ({"walls[right].face"} if code == "liggghts" else set())
    assert _failing(rows) == want
    assert all(r["deviation"] == pytest.approx(shift, rel=1e-6) for r in rows if not r["pass"])


@pytest.mark.parametrize("code", ["liggghts", "yade"])
def test_the_real_code_sees_moved_slit_ends(silo, code, tmp_path):
    if not BACKENDS[code].available():
        pytest.skip(f"{code} is not on PATH")
    e = G.expected_geometry(silo)
    res = G.probe(code, _mutated(silo, code, "points", 0.2), tmp_path)
    assert res["status"] == "ok", res["reason"]
    bad = _failing(G.compare_geometry(e, res["geometry"]))
    assert {"points[L]", "points[R]", "walls[bottom_left].to", "walls[bottom_right].from"} <= bad
    assert {i for i in bad if i.startswith("walls[gate]")} == {"walls[gate].from", "walls[gate].to"}


def test_a_backend_mistake_is_read_from_the_code_not_from_the_case(silo, tmp_path, monkeypatch):
    """The case stays right; LIGGGHTS' STL writer moves the right wall and YADE's translation grows
    a radius, each by 10 REL L: the read-back, from the codes' own state, fails on that item."""
    e = G.expected_geometry(silo)
    eps = 10 * G.REL * e["length"]
    if liggghts_backend.available():
        orig = liggghts_backend.write_wall_stl

        def stl(wall, profile_bin, path):
            if wall["name"] == "right":
                wall = dict(wall, **{k: [wall[k][0] + eps, wall[k][1]] for k in ("from", "to")})
            return orig(wall, profile_bin, path)
        monkeypatch.setattr(liggghts_backend, "write_wall_stl", stl)
        res = G.probe("liggghts", silo, tmp_path / "liggghts")
        rows = G.compare_geometry(e, res["geometry"])
        assert _failing(rows) == {"walls[right].from", "walls[right].to", "walls[right].face"}
        assert all(r["deviation"] == pytest.approx(eps, rel=1e-6) for r in rows if not r["pass"])
    if yade_backend.available():
        orig_data = yade_backend.case_data

        def data(case):
            d = orig_data(case)
            d["discs"][2][2] += eps
            return d
        monkeypatch.setattr(yade_backend, "case_data", data)
        res = G.probe("yade", silo, tmp_path / "yade")
        rows = G.compare_geometry(e, res["geometry"])
        assert _failing(rows) == {"discs[2].radius"}
        assert next(r for r in rows if not r["pass"])["deviation"] == pytest.approx(eps, rel=1e-6)


# ------------------------------------------------------------------------------------------
# The cache key: the bytes of what the probe runs
def _old_key(code: str, case: Case) -> str:
    """The key before: a JSON of selected resolved constants (blind to a backend's own mistake)."""
    r = case.resolved
    key = json.dumps({"code": code, "pairs": r["pairs"], "materials": r["materials"], "gravity": r["gravity"],
                      "contact": r["contact"], "dt": case.dt,
                      "radii": sorted({(float(x), int(m)) for x, m in zip(np.asarray(case.discs)[:, 2],
                                                                          case.material_index())})}, sort_keys=True)
    return hashlib.sha1(key.encode()).hexdigest()[:16]


def _lammps_mu_disc_disc_bug(monkeypatch, factor=0.9):
    """A LAMMPS translation that writes disc-disc friction x factor (the resolved case unchanged)."""
    orig = lammps_backend._coeffs

    def coeffs(p, where):
        a, b = where[len("pairs["):-1].split(",")
        dd = a == b == "sand"
        return orig(dict(p, mu=p["mu"] * factor) if dd else p, where)
    monkeypatch.setattr(lammps_backend, "_coeffs", coeffs)


@pytest.mark.parametrize("module", [P, G], ids=["constants", "geometry"])
def test_the_key_is_the_translation_bytes(silo, module, monkeypatch):
    key = lambda c: pipeline.probe_key(module, "lammps", c)       # noqa: E731
    clean, old_clean = key(silo), _old_key("lammps", silo)
    assert key(dataclasses.replace(silo, name="another")) == clean      # the name translates to nothing
    resolved = Mutation("lammps_mu_disc_disc_x0.9", "lammps", "mu", "disc-disc", 0.9, "all").apply(silo.resolved)
    assert key(dataclasses.replace(silo, resolved=resolved)) != clean
    _lammps_mu_disc_disc_bug(monkeypatch)
    assert key(silo) != clean
    assert _old_key("lammps", silo) == old_clean       # the hole: the old key sees no backend mistake


def test_resume_into_probes_of_the_clean_translation_probes_a_mutant_anew(silo, tmp_path, monkeypatch):
    """A run folder holding probes/ of the unmutated LAMMPS translation, then a LAMMPS translation with
    disc-disc friction x 0.9: the cached probe is not reused (a new probe runs); the clean one is."""
    calls = []

    def fake_probe(code, case, out_dir, timeout):
        calls.append(Path(out_dir))
        return {"status": "ok", "n": len(calls)}
    module = types.SimpleNamespace(write_probe_inputs=P.write_probe_inputs, probe=fake_probe)
    first = pipeline._probe_cached(module, "lammps", silo, tmp_path, 1)
    assert pipeline._probe_cached(module, "lammps", silo, tmp_path, 1) == first and len(calls) == 1
    mutant = Mutation("lammps_mu_disc_disc_x0.9", "lammps", "mu", "disc-disc", 0.9, "all")
    mutated = pipeline._probe_cached(module, "lammps", dataclasses.replace(silo, resolved=mutant.apply(silo.resolved)),
                                     tmp_path, 1)
    assert len(calls) == 2 and mutated["n"] == 2 and calls[1] != calls[0]
    _lammps_mu_disc_disc_bug(monkeypatch)              # the same mistake made by the backend itself
    again = pipeline._probe_cached(module, "lammps", silo, tmp_path, 1)
    assert len(calls) == 3 and again["n"] == 3 and calls[2] not in calls[:2]

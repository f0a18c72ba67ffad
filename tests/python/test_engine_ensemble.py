"""`dem ensemble SCENE --member K --engine CODE` and `dem ensemble merge` of such members
(docs/ensembles.md): member K's perturbed start runs in the reference code, and merge gathers the
members' summaries into ensemble.json, refusing a member of another code. LAMMPS runs the small
silo of test_engine_run.py (14 discs, a second each)."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from test_engine_run import DISCHARGE, LATTICE, dem, needs_liggghts, needs_lmp, scene

PERTURB = 1e-3


@pytest.fixture(scope="module")
def silo(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("engine_ensemble")
    text = scene("discharge", LATTICE, 0.1).replace("slit_width = 2.0", "slit_width = 4.0") + DISCHARGE
    (d / "d.toml").write_text(text)
    return d


def member(dem_binary, silo: Path, out: Path, k: int, code: str = "lammps", *extra):
    return dem(dem_binary, "ensemble", silo / "d.toml", "--out", out, "--member", k, "--engine", code,
               "--settle", "0.1", "--seed", 3, "--perturb", PERTURB, "--quiet", *extra, timeout=300)


def lattice(dem_binary, silo: Path) -> np.ndarray:
    p = dem(dem_binary, "resolve", silo / "d.toml")
    assert p.returncode == 0, p.stderr
    return np.array(json.loads(p.stdout)["discs"], float)[:, :2]


def data_positions(path: Path) -> np.ndarray:
    """x, y of LAMMPS's read_data file (atom id, type, diameter, density, x, y, z), by atom id."""
    lines = path.read_text().splitlines()
    k = next(i for i, l in enumerate(lines) if l.strip().startswith("Atoms"))
    end = next((i for i, l in enumerate(lines) if i > k and l.strip() and l.strip()[0].isalpha()), len(lines))
    rows = [l.split() for l in lines[k + 1:end] if l.strip()]
    rows = [r for r in rows if len(r) >= 7 and r[0].isdigit()]
    rows.sort(key=lambda r: int(r[0]))
    return np.array([[float(r[4]), float(r[5])] for r in rows])


@pytest.mark.reference_codes
@needs_lmp
def test_members_in_lammps_start_perturbed_and_merge(silo, dem_binary):
    out = silo / "ens"
    for k in (0, 1):
        p = member(dem_binary, silo, out, k)
        assert p.returncode == 0, p.stderr
    start = lattice(dem_binary, silo)
    starts = []
    for k in (0, 1):
        d = out / f"member_{k:02d}"
        ident = json.loads((d / "member.json").read_text())
        assert ident["member"] == k and ident["engine"] == "lammps" and ident["settle"] == 0.1
        assert ident["seed"] == 3 and ident["perturb"] == PERTURB
        xy = np.loadtxt(d / "member_start.csv", delimiter=",", skiprows=1)
        shift = np.abs(xy - start)
        assert shift.shape == start.shape and 0 < shift.max() <= PERTURB
        # the code was given that start (its data file), not the lattice
        assert np.allclose(data_positions(d / "lammps" / "discs.data"), xy, rtol=0, atol=1e-12)
        s = json.loads((d / "summary.json").read_text())
        assert s["engine_name"] == "lammps" and s["status"] == "discharged"
        starts.append(xy)
    assert not np.array_equal(starts[0], starts[1])
    # member 0 again: the same start (a generator seeded by seed and K alone)
    assert member(dem_binary, silo, silo / "again", 0).returncode == 0
    assert np.array_equal(np.loadtxt(silo / "again" / "member_00" / "member_start.csv", delimiter=",", skiprows=1),
                          starts[0])
    p = dem(dem_binary, "ensemble", "merge", out, "--members", 2, "--quiet")
    assert p.returncode == 0, p.stderr
    ens = json.loads((out / "ensemble.json").read_text())
    assert ens["members"] == 2 and ens["failed"] == 0 and len(ens["runs"]) == 2
    for run in ens["runs"]:
        d = out / f"member_{run['member']:02d}"
        removed = len((d / "removals.csv").read_text().splitlines()) - 1
        assert run["status"] == "discharged" and run["discs_out_at_1s"] == removed    # 0.3 s of flow
    assert sum(ens["pattern"].values()) == 2


@pytest.mark.reference_codes
@needs_lmp
@needs_liggghts
def test_merge_refuses_a_member_of_another_code(silo, dem_binary):
    out = silo / "mixed"
    assert member(dem_binary, silo, out, 0).returncode == 0
    assert member(dem_binary, silo, out, 1, "liggghts").returncode == 0
    p = dem(dem_binary, "ensemble", "merge", out, "--members", 2)
    assert p.returncode == 2 and "another ensemble" in p.stderr and "liggghts" in p.stderr
    assert not (out / "ensemble.json").exists()


def test_engine_needs_a_member_and_a_known_code(silo, dem_binary):
    p = dem(dem_binary, "ensemble", silo / "d.toml", "--out", silo / "x", "--engine", "lammps")
    assert p.returncode == 2 and "--member K" in p.stderr
    p = dem(dem_binary, "ensemble", silo / "d.toml", "--out", silo / "x", "--member", 0, "--engine", "abaqus")
    assert p.returncode == 2 and "abaqus" in p.stderr
    p = dem(dem_binary, "ensemble", silo / "d.toml", "--out", silo / "x", "--member", 0, "--np", 2)
    assert p.returncode == 2 and "--engine" in p.stderr
    p = dem(dem_binary, "ensemble", silo / "d.toml", "--out", silo / "x", "--member", 0, "--engine", "lammps", "--no-vtu")
    assert p.returncode == 2 and "--no-vtu does not go with --engine" in p.stderr
    assert not (silo / "x").exists()


@needs_lmp
def test_a_member_the_code_refuses_leaves_nothing(silo, dem_binary, tmp_path):
    text = (silo / "d.toml").read_text().replace("eta_n_rho_g = 15.3", "eta_n_rho_g = 0.0")   # LAMMPS: no
    (tmp_path / "no_dashpot.toml").write_text(text)
    out = tmp_path / "ens"
    p = dem(dem_binary, "ensemble", tmp_path / "no_dashpot.toml", "--out", out, "--member", 0, "--engine", "lammps")
    assert p.returncode == 2 and "lammps cannot express it" in p.stderr
    assert not (out / "member_00").exists()

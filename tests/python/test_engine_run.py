"""`dem run SCENE --engine liggghts|lammps`: a scene run in the real reference code, written as the
engine's run folder (compare/codes/reference_run.py).

A small silo (14 discs) rests in the engine; the rested packing is a file scene that every code
runs for 0.05 s. The reference codes' wall totals must lie within the comparison's static
tolerances (compare/verdict/pipeline.py) of the engine's run of the same scene, the folder must pass the
strict reader and the figure tool, a scene the code cannot express exits 2 naming the field, and a
blow-up and a timeout exit 3 and 4 with the program's message. Runs need the programs (skipped
without them, except in CI, which installs them)."""
from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import meshio
import numpy as np
import pytest

from dem.compare.verdict.pipeline import TOL_STATIC_SHEAR, TOL_STATIC_TOTAL
from dem.compare.io.run_dir import RunDir

ROOT = Path(__file__).resolve().parents[2]


def _needs(program: str):
    return pytest.mark.skipif(shutil.which(program) is None and os.environ.get("CI") != "true",
                              reason=f"{program} not installed (scripts/install_deps.sh; CI installs it)")


needs_liggghts, needs_lmp, needs_yade = _needs("liggghts"), _needs("lmp"), _needs("yade")
# (code, MPI ranks): LIGGGHTS also under mpirun -np 2
CODES = [pytest.param("liggghts", 1, marks=needs_liggghts), pytest.param("lammps", 1, marks=needs_lmp),
         pytest.param("liggghts", 2, marks=needs_liggghts), pytest.param("yade", 1, marks=needs_yade)]

DT, REST_TIME = 5e-5, 0.05
LAW = """
[physics]
gravity = [0.0, -980.0]
[integrator]
scheme = "velocity_verlet"
dt = {dt}
[contact]
normal_spring = "overlap"
no_tension = "total"
friction_cap = "total"
lever_arm = "contact_point"
[materials.sand]
density = 2.65
[materials.wall]
[[pairs]]
materials = ["sand", "sand"]
kn_rho_g = 36400.0
ks_rho_g = 9100.0
eta_n_rho_g = {eta_n}
eta_s_rho_g = 7.65
mu = 0.577
[[pairs]]
materials = ["sand", "wall"]
kn_rho_g = 72800.0
ks_rho_g = 18200.0
eta_n_rho_g = 30.6
eta_s_rho_g = 15.3
mu = 0.176
[silo]
width = 10.0
height = 12.0
slit_width = 2.0
slit = "closed"
wall_material = "wall"
[output]
profile_bin = 2.0
"""


def scene(name: str, fill: str, time: float, dt: float = DT, eta_n: float = 15.3) -> str:
    return (f'[scene]\nname = "{name}"\ndescription = "a small silo for dem run --engine"\n'
            + LAW.format(dt=dt, eta_n=eta_n) + fill + f"[end]\ntime = {time}\nstop_at_rest = false\n")


DISCHARGE = """
[discharge]
time = 0.3
gate = "gate"
outlet_depth = 4.0
jam_time = 0.3
series_interval = 0.01
peak_window = 0.05
"""
LATTICE = '[fill]\ntype = "lattice"\ns = 4\nradius = 1.0\ngap = 0.004\ncount = 14\nmaterial = "sand"\n'
RESTED = '[fill]\ntype = "file"\nfile = "fill/discs.csv"\nmaterial = "sand"\nmax_initial_overlap = 0.05\n'


def dem(binary, *args, timeout=120):
    return subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def rested(tmp_path_factory, dem_binary) -> Path:
    """The lattice filled to rest in the engine, that packing as a scene, and the engine's run of it."""
    d = tmp_path_factory.mktemp("engine_run")
    (d / "lattice.toml").write_text(scene("lattice", LATTICE, 0.1))
    p = dem(dem_binary, "run", d / "lattice.toml", "--out", d / "fill", "--quiet")
    assert p.returncode == 0, p.stderr
    (d / "rested.toml").write_text(scene("rested", RESTED, REST_TIME))
    p = dem(dem_binary, "run", d / "rested.toml", "--out", d / "native", "--quiet")
    assert p.returncode == 0, p.stderr
    return d


def _rel(a: float, b: float) -> float:
    return abs(a - b) / abs(b)


def wall_load_problems(s: dict, nat: dict) -> list[str]:
    """The walls the native run loads whose totals in the code's run lie outside the comparison's
    static tolerances: normal totals on every loaded wall, friction on the side walls."""
    mine = {w["name"]: w for w in s["walls"]}
    bad = []
    for w in (w for w in nat["walls"] if w["normal_total"] > 0):
        if _rel(mine[w["name"]]["normal_total"], w["normal_total"]) > TOL_STATIC_TOTAL:
            bad.append(f"{w['name']} normal_total")
        if w["group"].startswith("side") and _rel(mine[w["name"]]["shear_total"], w["shear_total"]) > TOL_STATIC_SHEAR:
            bad.append(f"{w['name']} shear_total")
    return bad


@pytest.mark.reference_codes
@pytest.mark.parametrize("code,ranks", CODES)
def test_a_rested_scene_in_a_reference_code_carries_the_native_wall_loads(rested, dem_binary, code, ranks):
    out = rested / f"{code}_np{ranks}"
    p = dem(dem_binary, "run", rested / "rested.toml", "--engine", code, "--np", ranks, "--out", out)
    assert p.returncode == 0, p.stdout + p.stderr
    run = RunDir(out, strict=True)
    s, nat = run.summary, RunDir(rested / "native", strict=True).summary
    assert s["engine_name"] == code and s["engine"].startswith(code) and s["np"] == s["ranks"] == ranks
    if code != "yade":
        assert f"on {ranks} procs" in (out / code / f"{code}.log").read_text()     # the program's own count
    assert s["status"] == "end_time" and s["steps"] == round(REST_TIME / DT)
    assert s["rest"]["reached"] is None and "not checked" in s["rest"]["criterion"]
    assert s["n_discs"] == nat["n_discs"] == 14
    mine = {w["name"]: w for w in s["walls"]}
    loaded = [w for w in nat["walls"] if w["normal_total"] > 0]
    assert len(loaded) >= 4          # both side walls and the floor on both sides of the gate
    for w in loaded:
        if w["group"].startswith("side"):
            assert abs(w["shear_total"]) >= 1e-3 * w["normal_total"]     # friction to compare
    assert wall_load_problems(s, nat) == []
    # the load along gravity is the discs' weight (rho pi r^2 g each), whatever the code
    weight = 14 * 2.65 * np.pi * 980.0
    assert abs(s["weight"] - weight) <= 1e-9 * weight
    assert abs(s["balance"]["walls_vertical"] - weight) <= 1e-4 * weight
    # the files agree with the summary, and the discs are the scene's, one material
    prof = run.profiles()
    for name, w in mine.items():
        assert np.isclose(prof["normal"][prof["wall"] == name].sum(), w["normal_total"], rtol=1e-12, atol=1e-9)
    discs = run.discs()
    assert list(discs["id"]) == list(range(14)) and set(discs["material"]) == {"sand"}
    assert np.allclose(discs["r"], 1.0)
    vtu = meshio.read(out / "discs.vtu")
    assert len(vtu.points) == 14 and np.allclose(vtu.point_data["radius"], 1.0)


@pytest.mark.parametrize("code", [pytest.param("lammps", marks=needs_lmp),
                                  pytest.param("liggghts", marks=needs_liggghts)])
def test_the_wall_load_check_fails_on_a_translation_with_the_density_x1_02(rested, dem_binary, code):
    """The mutant (DEM_ENGINE_MUTANT, compare/codes/reference_run.py): the code is given discs 2 % heavier,
    the folder still measures against the scene; the floor carries 2 % more than the native run's,
    beyond TOL_STATIC_TOTAL, and the check above says which walls."""
    out = rested / f"{code}_mutant"
    p = subprocess.run([str(dem_binary), "run", str(rested / "rested.toml"), "--engine", code, "--out", str(out)],
                       capture_output=True, text=True, timeout=120,
                       env={**os.environ, "DEM_ENGINE_MUTANT": "density:1.02"})
    assert p.returncode == 0, p.stderr
    assert "DEM_ENGINE_MUTANT=density:1.02" in p.stderr
    s, nat = RunDir(out, strict=True).summary, RunDir(rested / "native", strict=True).summary
    assert s["mutant"] == "density:1.02" and abs(s["weight"] - nat["weight"]) <= 1e-9 * nat["weight"]
    bad = wall_load_problems(s, nat)
    assert any(b.startswith("bottom") and b.endswith("normal_total") for b in bad), bad
    # the vertical load is the mutant's weight: 1.02 x the scene's
    assert s["balance"]["walls_vertical"] == pytest.approx(1.02 * s["weight"], rel=1e-4)


def test_a_malformed_mutant_exits_2_naming_it(rested, dem_binary):
    p = subprocess.run([str(dem_binary), "run", str(rested / "rested.toml"), "--engine", "lammps", "--out",
                        str(rested / "bad_mutant")], capture_output=True, text=True, timeout=120,
                       env={**os.environ, "DEM_ENGINE_MUTANT": "density"})
    assert p.returncode == 2 and "DEM_ENGINE_MUTANT='density'" in p.stderr
    assert not (rested / "bad_mutant").exists()


@needs_liggghts
def test_the_figure_tool_draws_a_reference_run_without_its_contact_network(rested, dem_binary):
    """`--pictures` draws the reference run's pictures (no network: the code gives no
    contact list), and dem.compare.figures (matplotlib) draws them again."""
    out = rested / "figures"
    p = dem(dem_binary, "run", rested / "rested.toml", "--engine", "liggghts", "--out", out, "--pictures")
    assert p.returncode == 0, p.stderr
    assert "contact network is skipped" in p.stderr and str(out / "side_walls.png") in p.stdout
    assert (out / "side_walls.png").stat().st_size > 0 and not (out / "network.png").exists()
    (out / "side_walls.png").unlink()
    p = subprocess.run(["/usr/bin/python3", "-m", "dem.compare.figures", "run", str(out)], capture_output=True,
                       text=True, cwd=ROOT, timeout=120)
    assert p.returncode == 0, p.stderr
    assert "contact network is skipped" in p.stderr
    assert (out / "side_walls.png").stat().st_size > 0 and not (out / "network.png").exists()


@needs_lmp
def test_a_scene_lammps_cannot_express_exits_2_naming_the_field(tmp_path, dem_binary):
    (tmp_path / "s.toml").write_text(scene("no_normal_dashpot", LATTICE, 0.01, eta_n=0.0))
    out = tmp_path / "out"
    p = dem(dem_binary, "run", tmp_path / "s.toml", "--engine", "lammps", "--out", out)
    assert p.returncode == 2, p.stderr
    assert "lammps cannot express it" in p.stderr and "pairs[sand,sand].eta_s" in p.stderr
    assert not out.exists()


@needs_lmp
def test_a_blow_up_exits_3_and_a_timeout_4_with_the_programs_message(rested, dem_binary):
    (rested / "blow.toml").write_text(scene("blow", RESTED, 0.5, dt=2e-3))   # 40x the stable dt
    p = dem(dem_binary, "run", rested / "blow.toml", "--engine", "lammps", "--out", rested / "blow")
    assert p.returncode == 3, p.stderr
    assert "Lost atoms" in p.stderr          # LAMMPS's own ERROR line
    assert RunDir(rested / "blow").status == "unstable"
    (rested / "long.toml").write_text(scene("long", RESTED, 100.0))
    p = dem(dem_binary, "run", rested / "long.toml", "--engine", "lammps", "--timeout", "1", "--out",
            rested / "long")
    assert p.returncode == 4, p.stderr
    assert "timed out after 1 s" in p.stderr


def test_dem_run_help_documents_engine_and_np(dem_binary):
    text = dem(dem_binary, "run", "--help").stdout
    assert "--engine CODE" in text and "--np N" in text and "liggghts|lammps|yade" in text


@needs_liggghts
def test_a_discharge_in_liggghts_writes_the_removal_log_and_the_wall_series(tmp_path, dem_binary):
    """The slit (4 cm) opens after 0.1 s of settling; every disc is in discs.csv or removals.csv,
    once, and the wall series start at the opening with the walls' static loads."""
    text = scene("discharge", LATTICE, 0.1).replace("slit_width = 2.0", "slit_width = 4.0") + DISCHARGE
    (tmp_path / "d.toml").write_text(text)
    out = tmp_path / "out"
    p = dem(dem_binary, "run", tmp_path / "d.toml", "--engine", "liggghts", "--settle", "0.1", "--out", out)
    assert p.returncode == 0, p.stderr
    run = RunDir(out, strict=True)
    s, d = run.summary, run.summary["discharge"]
    assert s["status"] == "discharged" and d["t_open"] == pytest.approx(0.1) and d["duration"] == 0.3
    rem, discs = run.removals(), run.discs()
    assert d["removed"] == len(rem["t"]) >= 1 and s["n_discs"] == len(discs["id"]) == 14 - d["removed"]
    assert sorted(list(rem["id"]) + list(discs["id"])) == list(range(14))
    assert np.all((rem["t"] > 0) & (rem["t"] <= 0.3)) and np.all(rem["vy"] < 0)   # out through the slit
    assert np.allclose(rem["mass"], 2.65 * np.pi)
    assert isinstance(d["jammed"], bool) and d["pattern"] in ("funnel", "piping", "undetermined")
    series, totals = run.wall_series(), run.wall_totals_series()
    t = np.unique(series["t"])
    assert t[0] == pytest.approx(0.0) and np.allclose(np.diff(t), 0.01)
    first = totals["t"] == t[0]
    # at the opening the gate has just gone: the remaining walls carry at most the discs' weight
    load = totals["normal"][first & np.isin(totals["name"], ["bottom_left", "bottom_right"])].sum()
    assert 0 < load <= 14 * 2.65 * np.pi * 980.0 * (1 + 1e-6)


@pytest.mark.reference_codes
def test_the_law_a_reference_code_runs_is_said_on_screen_and_in_run_log(rested, dem_binary):
    """The scene's own law (here the paper's incremental spring, set by --set) is not what LIGGGHTS
    runs: the screen and run.log name each option that differs, with both values; a scene already
    on the shared law is said to run its own law."""
    out = rested / "law"
    p = dem(dem_binary, "run", rested / "rested.toml", "--engine", "liggghts", "--out", out,
            "--set", "contact.normal_spring=incremental")
    assert p.returncode == 0, p.stderr
    line = next(x for x in p.stdout.splitlines() if x.startswith("law:"))
    assert "normal_spring = 'incremental' -> 'overlap'" in line and "no_tension" not in line
    assert line in (out / "run.log").read_text()
    p = dem(dem_binary, "run", rested / "rested.toml", "--engine", "liggghts", "--out", rested / "law_same")
    assert "runs the scene's own contact law" in p.stdout and (rested / "law_same" / "run.log").exists()

"""The Python module dem (engine/python): scenes from files and dicts validated as the engine
validates files, values set by key, runs and steps, and the arrays read back; a run through the
module gives the bits of `dem run` (compared with its output files)."""
import csv
import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
SILO = REPO / "reference_inputs" / "scenes" / "silo_17_18.toml"
DISCHARGE = REPO / "reference_inputs" / "scenes" / "discharge_17_18.toml"
FLAT = ("x", "y", "vx", "vy", "omega", "fx", "fy", "torque")


def short_silo(dem, end_time=0.01):
    scene = dem.Scene(SILO)
    scene.set("end.time", end_time)
    return scene


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_scene_from_file(dem_module):
    scene = dem_module.Scene(SILO)
    assert scene.name == "silo_17_18" and scene.dt == 1e-4 and scene.n_discs > 300
    assert dem_module.load(str(SILO)).resolved() == scene.resolved()
    with pytest.raises(dem_module.SceneError, match="cannot open"):
        dem_module.Scene(REPO / "no_such_scene.toml")


def test_scene_from_dict_is_the_file(dem_module):
    tables = tomllib.loads(SILO.read_text())
    from_dict, from_file = dem_module.Scene.from_dict(tables), dem_module.Scene(SILO)
    a, b = from_dict.resolved(), from_file.resolved()
    assert a.pop("file") == "<dict>" and b.pop("file") == str(SILO)
    assert a == b
    assert dem_module.load(tables).to_dict() == tables == from_file.to_dict()


def without(tables, table, key):
    out = json.loads(json.dumps(tables))
    del out[table][key]
    return out


@pytest.mark.parametrize("change,expect", [
    (lambda t: without(t, "integrator", "dt"), ["<dict>: integrator.dt", "required value is missing"]),
    (lambda t: {**t, "integrator": {**t["integrator"], "dt": "fast"}}, ["integrator.dt", '"fast"', "expected a number"]),
    (lambda t: {**t, "integrator": {**t["integrator"], "sheme": 1}}, ["integrator.sheme", "unknown key"]),
    (lambda t: {**t, "fill": {**t["fill"], "count": 10**12}}, ["fill.count", "5e7"]),
    (lambda t: {**t, "integrator": {**t["integrator"], "dt": None}}, ["integrator.dt", "None", "not a scene value"]),
], ids=["missing", "wrong type", "unknown key", "limit", "not a value"])
def test_bad_dict_names_the_field(dem_module, change, expect):
    tables = change(tomllib.loads(SILO.read_text()))
    with pytest.raises(dem_module.SceneError) as e:
        dem_module.Scene.from_dict(tables)
    assert isinstance(e.value, ValueError)
    for fragment in expect:
        assert fragment in str(e.value), (fragment, str(e.value))


def test_set_validates_and_leaves_a_refused_scene_unchanged(dem_module):
    scene = dem_module.Scene(SILO)
    scene.set("integrator.dt", 5e-5)
    scene.set("pairs.1.mu", 0.2)
    scene.set("contact.lever_arm", "contact_point")  # a key the file does not have
    assert scene.dt == 5e-5 and scene.resolved()["pairs"][1]["mu"] == 0.2
    for key, value, fragment in [("integrator.dt", "fast", "expected a number"), ("integrator.dtt", 1, "unknown key"),
                                 ("pairs.7.mu", 0.3, "pairs has 2 entries")]:
        with pytest.raises(dem_module.SceneError, match=fragment) as e:
            scene.set(key, value)
        assert key.split(".")[0] in str(e.value)
    assert scene.dt == 5e-5 and "dtt" not in scene.to_dict()["integrator"]
    scene.set("integrator.dt", 1e-3)  # the bound is the world's: checked when it is built, as dem run does
    with pytest.raises(dem_module.SceneError, match="integrator.dt = 0.001: above the stability bound"):
        dem_module.Simulation(scene)


def test_arrays_views_and_copies(dem_module):
    sim = dem_module.Simulation(short_silo(dem_module))
    n = sim.n_discs
    sim.step(200)  # 0.02 s: the discs have fallen onto each other and the floor
    assert sim.steps == 200 and sim.time == pytest.approx(0.02)
    for name in FLAT:
        a = getattr(sim, name)
        assert a.shape == (n,) and a.dtype == np.float64, name
        assert not a.flags.writeable and not a.flags.owndata, name  # a view of the engine's array
        assert np.shares_memory(a, getattr(sim, name)), name
    for name in ("positions", "velocities", "forces"):
        a = getattr(sim, name)
        assert a.shape == (n, 2) and a.dtype == np.float64 and a.flags.owndata, name
    assert np.array_equal(sim.positions[:, 0], sim.x) and np.array_equal(sim.forces[:, 1], sim.fy)
    assert sim.radii.shape == (n,) and np.all(sim.radii == 1.0)
    assert sim.ids.dtype == np.int32 and np.array_equal(sim.ids, np.arange(n))
    y_view, y_copy = sim.y, sim.positions[:, 1].copy()
    sim.step(1)
    assert np.array_equal(y_view, sim.y) and not np.array_equal(y_view, y_copy)  # the view follows the engine
    with pytest.raises(ValueError):
        y_view[0] = 0.0
    walls = sim.walls()
    assert "gate" in walls["name"] and len(walls["group"]) == len(walls["name"])
    assert walls["normal"].shape == (len(walls["name"]),) and walls["contacts"].dtype == np.int32
    c = sim.contacts()
    assert set(c) == {"kind", "i", "j", "e_n", "e_s", "f_n", "f_s"} and len(c["i"]) > 0


def assert_same_discs(sim, run_dir):
    rows = read_csv(run_dir / "discs.csv")
    assert len(rows) == sim.n_discs
    for name in ("x", "y", "vx", "vy", "omega"):
        assert np.array_equal(getattr(sim, name), np.array([float(r[name]) for r in rows])), name
    assert np.array_equal(sim.radii, np.array([float(r["r"]) for r in rows]))


def cli_run(run_dem, tmp_path, name, *sets):
    out = tmp_path / name
    args = [a for s in sets for a in ("--set", s)]
    proc = run_dem("run", SILO, "--out", out, "--quiet", *args)
    assert proc.returncode == 0, proc.stderr
    return out


def test_run_gives_the_bits_of_dem_run(dem_module, run_dem, tmp_path):
    cli = cli_run(run_dem, tmp_path, "cli", "end.time=0.01")
    sim = dem_module.Simulation(short_silo(dem_module))
    assert sim.run(tmp_path / "py") == "end_time"
    for name in ("discs.csv", "contacts.csv", "wall_profiles.csv"):
        assert (cli / name).read_bytes() == (tmp_path / "py" / name).read_bytes(), name
    assert_same_discs(sim, cli)
    summary = json.loads((cli / "summary.json").read_text())
    assert sim.steps == summary["steps"] and sim.time == summary["time"]
    walls = sim.walls()
    for k, w in enumerate(summary["walls"]):
        assert walls["name"][k] == w["name"]
        assert walls["normal"][k] == w["normal_total"] and walls["shear"][k] == w["shear_total"], w["name"]
        assert [walls["fx"][k], walls["fy"][k]] == w["force"] and walls["contacts"][k] == w["contacts"], w["name"]
    c = sim.contacts()
    contact_rows = read_csv(cli / "contacts.csv")
    assert len(contact_rows) == len(c["i"])
    for field in ("e_n", "e_s", "f_n", "f_s"):
        assert np.array_equal(c[field], np.array([float(r[field]) for r in contact_rows])), field
    rows = read_csv(cli / "discs.csv")
    kinetic = 0.5 * sum(np.pi * 2.65 * float(r["r"]) ** 2 * (float(r["vx"]) ** 2 + float(r["vy"]) ** 2
                                                                + 0.5 * float(r["r"]) ** 2 * float(r["omega"]) ** 2)
                        for r in rows)
    assert sim.kinetic_energy() == pytest.approx(kinetic, rel=1e-12)


def test_steps_and_fill_give_the_bits_of_dem_run(dem_module, run_dem, tmp_path):
    cli = cli_run(run_dem, tmp_path, "cli", "end.time=0.006", "integrator.scheme=velocity_verlet",
                  "integrator.dt=5e-5")
    scene = short_silo(dem_module, 0.006)
    scene.set("integrator.scheme", "velocity_verlet")
    scene.set("integrator.dt", 5e-5)
    filled = dem_module.Simulation(scene)
    assert filled.fill() == "end_time"
    assert_same_discs(filled, cli)
    stepped = dem_module.Simulation(scene)
    stepped.step(filled.steps)
    assert_same_discs(stepped, cli)
    stepped.write(tmp_path / "written")
    assert (tmp_path / "written" / "contacts.csv").read_bytes() == (cli / "contacts.csv").read_bytes()


def test_discharge_run_removes_discs(dem_module, tmp_path):
    scene = dem_module.Scene(DISCHARGE)
    scene.set("end.time", 0.3)
    scene.set("discharge.time", 0.25)
    scene.set("integrator.scheme", "paper_eq19")
    sim = dem_module.Simulation(scene)
    n0 = sim.n_discs
    status = sim.run(tmp_path / "d")
    summary = json.loads((tmp_path / "d" / "summary.json").read_text())
    assert status == summary["status"] and sim.n_discs == summary["n_discs"]
    assert sim.n_discs < n0 and sim.x.shape == (sim.n_discs,)
    with pytest.raises(RuntimeError, match="from its start"):
        sim.run(tmp_path / "again")


def test_start_set_from_python_is_the_scene_that_says_it(dem_module, run_dem, tmp_path):
    """Positions, velocities and spins set before the first step run bit for bit as a scene whose
    fill file holds them; refused values (an overlap, a wrong length, after a step) leave the
    simulation as it was, named as a scene's fill is."""
    scene = dem_module.Scene(REPO / "examples" / "flat_silo.toml")
    scene.set("end.time", 0.05)
    scene.set("discharge.time", 0.05)
    sim = dem_module.Simulation(scene)
    p = sim.positions + [0.003, 0.0]
    v = np.column_stack([np.linspace(-5, 5, sim.n_discs), np.full(sim.n_discs, -10.0)])
    w = np.linspace(0, 3, sim.n_discs)
    sim.set_positions(p)
    sim.set_velocities(v)
    sim.set_spins(w)
    assert np.array_equal(sim.positions, p) and np.array_equal(sim.velocities, v) and np.array_equal(sim.omega, w)
    bad = p.copy()
    bad[1] = bad[0]
    with pytest.raises(dem_module.SceneError, match=r"fill: disc 0 .* overlaps disc 1"):
        sim.set_positions(bad)
    with pytest.raises(ValueError, match="5 values for 102 discs"):
        sim.set_spins(w[:5])
    assert np.array_equal(sim.positions, p)            # unchanged by the refusals
    assert sim.run(tmp_path / "py") in ("discharged", "jammed")
    log = (tmp_path / "py" / "run.log").read_text()
    assert log.startswith("dem ") and "set from Python" in log and "steps; fill rest" in log
    with pytest.raises(ValueError, match="only before the first step"):
        sim.set_spins(w)

    radii = dem_module.Simulation(scene).radii
    fill = tmp_path / "fill.csv"
    fill.write_text("x,y,r,vx,vy,omega\n" + "".join(f"{a!r},{b!r},{r!r},{c!r},{d!r},{e!r}\n" for (a, b), r, (c, d), e
                                                     in zip(p, radii, v, w)))
    text = (REPO / "examples" / "flat_silo.toml").read_text()
    text = text[:text.index("[fill]")] + (f'[fill]\ntype = "file"\nmaterial = "glass"\nfile = "{fill}"\nvelocities = true\n\n'
                                          + text[text.index("[end]"):])
    (tmp_path / "same.toml").write_text(text)
    proc = run_dem("run", tmp_path / "same.toml", "--out", tmp_path / "cli", "--quiet", "--set", "end.time=0.05",
                   "--set", "discharge.time=0.05")
    assert proc.returncode == 0, proc.stderr
    for name in ("discs.csv", "removals.csv", "wall_profiles.csv"):
        assert (tmp_path / "cli" / name).read_bytes() == (tmp_path / "py" / name).read_bytes(), name

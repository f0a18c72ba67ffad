"""physics.units (docs/scene.md): an SI scene gets SI defaults (gravity -9.81 m/s^2, the silo,
lattice and discharge lengths in m) and prints SI units; the paper's cgs scenes print cgs."""
import json
import math
import subprocess
from pathlib import Path

import pytest

from dem.compare.io import scene_toml

REPO = Path(__file__).resolve().parents[2]
SCENES = REPO / "reference_inputs" / "scenes"


def si_scene(path):
    """The paper's 17/18 discharge in SI: every length x 0.01 (the kn_rho_g family are lengths),
    density in kg/m^3; gravity, the silo's size, the lattice's radius and gap, and the discharge's
    outlet depth and surface columns left to their defaults."""
    doc = scene_toml.load(SCENES / "discharge_17_18.toml")
    changes = {"materials.sand.density": 2650.0, "end.time": 0.01, "output.profile_bin": 0.02,
               "discharge.time": 0.01, "discharge.snapshots": [0.0]}
    for k in (0, 1):
        for key in ("kn_rho_g", "ks_rho_g", "eta_n_rho_g", "eta_s_rho_g"):
            changes[f"pairs[{k}].{key}"] = doc["pairs"][k][key] * 0.01
    remove = ["physics.gravity", "silo.width", "silo.height", "silo.slit_width", "fill.radius", "fill.gap",
              "discharge.outlet_depth"]
    return scene_toml.edit(SCENES / "discharge_17_18.toml", changes, path, remove=remove,
                           add={"physics.units": "si"})


def run(dem_binary, scene, out, *extra):
    p = subprocess.run([str(dem_binary), "run", str(scene), "--out", str(out), *extra], capture_output=True,
                       text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return p, json.loads((out / "summary.json").read_text())


def test_an_si_scene_without_gravity_gets_9_81_and_says_m_per_s2(tmp_path, dem_binary):
    p, s = run(dem_binary, si_scene(tmp_path / "si.toml"), tmp_path / "run")
    assert s["options"]["gravity"] == [0, -9.81] and s["options"]["units"] == "si"
    assert s["width"] == pytest.approx(0.4) and s["height"] == pytest.approx(0.4)
    assert s["discharge"]["outlet_y"] == pytest.approx(-0.04) and s["discharge"]["slit"] == pytest.approx([0.16, 0.24])
    assert s["disc_weight"] == pytest.approx(2650 * math.pi * 0.01 ** 2 * 9.81)
    header = p.stdout[:p.stdout.index("stability bound")]
    assert "gravity (0, -9.81) m/s^2" in header and "units si" in header and "kg/m^3" in header and "N/m" in header
    assert "cm" not in header.replace(str(tmp_path), "")
    assert "units si" in (tmp_path / "run" / "run.log").read_text()


def test_the_papers_scenes_say_cgs(tmp_path, dem_binary):
    scene = scene_toml.edit(SCENES / "silo_17_18.toml", {"end.time": 0.01}, tmp_path / "cgs.toml")
    p, s = run(dem_binary, scene, tmp_path / "run")
    assert "gravity (0, -980) cm/s^2" in p.stdout and "units cgs" in p.stdout and "dyn/cm" in p.stdout
    assert s["options"]["units"] == "cgs"


def test_a_cgs_scene_without_gravity_gets_980(tmp_path, dem_binary):
    scene = scene_toml.edit(SCENES / "silo_17_18.toml", {"end.time": 0.01}, tmp_path / "cgs.toml",
                            remove=["physics.gravity"])
    _, s = run(dem_binary, scene, tmp_path / "run", "--quiet")
    assert s["options"]["gravity"] == [0, -980]


def _table(text):
    """The rows of dem params' table: E -> (K_n/(rho g), eta_n/(rho g), dt, K_s/(rho g), b)."""
    rows = {}
    for line in text.splitlines():
        cells = line.split()
        try:
            vals = [float(c) for c in cells]
        except ValueError:
            continue
        if len(vals) == 6:
            rows[vals[0]] = vals[1:]
    return rows


def params(dem_binary, *args):
    p = subprocess.run([str(dem_binary), "params", *args], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
    return p.stdout


def test_params_in_si_are_the_cgs_table_in_metres(tmp_path, dem_binary):
    """The same material in SI (r 0.01 m, rho 2650 kg/m^3, q 30 gf/cm, g 9.8 m/s^2): every
    X/(rho g) is a length, so the SI column is the cgs one x 0.01; dt (seconds) and the ratios
    stay. An SI scene's physics.units gives the same table as --units si."""
    cgs, si = _table(params(dem_binary)), _table(params(dem_binary, "--units", "si"))
    assert set(cgs) == set(si) == {7.5e2, 1e3, 1e4, 1e5, 1e6}
    for e in cgs:
        kn, eta, dt, ks, b = cgs[e]
        assert si[e] == pytest.approx([kn * 0.01, eta * 0.01, dt, ks * 0.01, b * 0.01], rel=2e-3)  # %.4g printing
    out = params(dem_binary, str(si_scene(tmp_path / "si.toml")))
    assert _table(out) == si
    header = out.splitlines()[:3]
    assert "[m]" in header[2] and "[m s]" in header[2] and "kg/m^3" in header[0] and "cm" not in header[2]
    cgs_out = params(dem_binary, str(SCENES / "discharge_17_18.toml"))
    assert _table(cgs_out) == cgs and "[cm]" in cgs_out.splitlines()[2]


def test_params_refuses_an_unknown_unit_system(dem_binary):
    p = subprocess.run([str(dem_binary), "params", "--units", "imperial"], capture_output=True, text=True,
                       timeout=60)
    assert p.returncode == 2 and "--units" in p.stderr and "imperial" in p.stderr


def test_resolve_names_the_units_of_its_numbers(tmp_path, dem_binary):
    def resolve(scene):
        p = subprocess.run([str(dem_binary), "resolve", str(scene)], capture_output=True, text=True, timeout=60)
        assert p.returncode == 0, p.stderr
        return json.loads(p.stdout)
    si = resolve(si_scene(tmp_path / "si.toml"))["units"]
    cgs = resolve(SCENES / "discharge_17_18.toml")["units"]
    assert si["system"] == "si" and si["length"] == "m" and si["force"] == "N/m" and si["density"] == "kg/m^3"
    assert cgs["system"] == "cgs" and cgs["length"] == "cm" and cgs["force"] == "dyn/cm"
    assert cgs["acceleration"] == "cm/s^2" and si["time"] == cgs["time"] == "s"


@pytest.mark.release_only  # Python's side: the sanitized engine's runs are the other tests'
def test_pictures_and_jitter_carry_the_scenes_units(tmp_path, dem_binary, monkeypatch):
    """An SI scene's pictures label lengths in m and masses in kg, and dem compare's default
    jitter is the cgs scenes' 1e-3 cm expressed in m (1e-5); a given --perturb is taken as it is."""
    from dem.compare.cases import plan
    from dem.compare.figures import runs
    scene = si_scene(tmp_path / "si.toml")
    _, s = run(dem_binary, scene, tmp_path / "run")
    fig_labels = []
    save = runs._save

    def keep(fig, out_png):
        fig_labels.extend(t.get_text() for ax in fig.axes for t in (ax.xaxis.label, ax.yaxis.label))
        return save(fig, out_png)
    monkeypatch.setattr(runs, "_save", keep)
    runs.plot_network(tmp_path / "run", tmp_path / "n.png")
    runs.plot_flow(tmp_path / "run", tmp_path / "f.png")
    runs.plot_side_profiles([tmp_path / "run"], tmp_path / "s.png")
    text = " ".join(fig_labels)
    assert "[m]" in text and "[kg per m]" in text and "cm" not in text, fig_labels
    si = plan.make_plan(plan.Entry(scene, plan.Options()))
    cgs = plan.make_plan(plan.Entry(SCENES / "discharge_17_18.toml", plan.Options()))
    assert si.perturb == 1e-5 and cgs.perturb == 1e-3
    assert plan.make_plan(plan.Entry(scene, plan.Options(perturb=2e-4))).perturb == 2e-4

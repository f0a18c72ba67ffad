"""dem compare end to end on small scenes with the real LIGGGHTS: a scene in, report.md and
agreement.json out; the exit codes; mutants caught; a law difference attributed to its option."""
import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CAL = ROOT / "reference_inputs" / "agreement" / "calibration"
needs_liggghts = pytest.mark.skipif(shutil.which("liggghts") is None and os.environ.get("CI") != "true",
                                    reason="liggghts not installed (CI installs it)")


def compare(dem_binary, *args, timeout=900):
    return subprocess.run([str(dem_binary), "compare", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout)


@pytest.mark.reference_codes
@needs_liggghts
def test_a_collision_scene_through_dem_compare(dem_binary, tmp_path):
    out = tmp_path / "out"
    p = compare(dem_binary, CAL / "head_on_disc_disc.toml", "--kind", "collision", "--codes", "native,liggghts",
                "--out", out)
    assert p.returncode == 0, p.stdout + p.stderr
    rep = json.loads((out / "agreement.json").read_text())
    names = [m["metric"] for m in rep["metrics"]]
    assert names == ["translation constants read back (liggghts)", "translation geometry read back (liggghts)",
                     "collision against the reference (native)",
                     "collision against the reference (liggghts)", "collision (liggghts vs native)"]
    assert rep["passed"] and (out / "report.md").read_text().startswith("# Agreement report")
    assert (out / "calibration.png").exists()


@pytest.mark.reference_codes
@needs_liggghts
def test_mutants_are_caught_and_a_mutant_with_nothing_to_change_is_not_counted(dem_binary, tmp_path):
    """On a gravity-free collision every constant mutant of LIGGGHTS' translation fails a metric;
    the disc-wall friction mutant of the gravity scenes changes nothing there and is left out."""
    out = tmp_path / "out"
    p = compare(dem_binary, CAL / "head_on_disc_disc.toml", "--kind", "collision", "--codes", "native,liggghts",
                "--mutants", "--out", out)
    mu = json.loads((out / "mutants.json").read_text())
    rows = {r["mutant"]: r for r in mu["rows"]}
    assert rows["liggghts_mu_disc_wall_x0.9_gravity_cases"]["applicable"] is False
    assert rows["liggghts_gravity_x1.01"]["applicable"] is False            # no gravity to scale
    for name in ("kn_x1.05", "eta_n_x1.2", "density_x1.01"):
        r = rows[f"liggghts_{name}"]
        assert r["caught"] and r["caught_physically"], r        # t_c and e of the head-on collision
    # a head-on collision has no friction and no gravity: those mutants only the translation check sees
    assert rows["liggghts_mu_disc_disc_x0.9"]["caught"] and not rows["liggghts_mu_disc_disc_x0.9"]["caught_physically"]
    assert p.returncode == 0 and mu["all_caught"], p.stdout[-2000:]


@pytest.mark.reference_codes
@needs_liggghts
def test_a_mutant_stops_at_its_first_physical_catch_unless_exhaustive(dem_binary, tmp_path):
    """k_n x 1.05 changes the head-on collision's contact time: caught there, the second scene is
    not run for it; friction x 0.9 is seen by the translation check only on the head-on collision,
    so it goes on to the grazing one, which catches it physically. --exhaustive (resumed: only the
    runs not yet made) runs k_n x 1.05 on the second scene too."""
    out = tmp_path / "out"
    def mutant_scenes(*extra):
        p = compare(dem_binary, CAL / "head_on_disc_disc.toml", CAL / "grazing_disc_disc.toml", "--kind", "collision",
                    "--codes", "native,liggghts", "--mutant", "liggghts_kn_x1.05", "--mutant",
                    "liggghts_mu_disc_disc_x0.9", *extra, "--out", out)
        assert p.returncode == 0, p.stdout[-3000:] + p.stderr
        runs = {}
        for line in p.stdout.splitlines():
            if "[mutant " in line:
                runs.setdefault(line.split("[mutant ")[1].rstrip("]"), []).append(line.split(":")[0])
        rows = {r["mutant"]: r for r in json.loads((out / "mutants.json").read_text())["rows"]}
        assert all(rows[n]["caught_physically"] for n in runs), rows
        return runs
    both = ["head_on_disc_disc", "grazing_disc_disc"]
    assert mutant_scenes() == {"liggghts_kn_x1.05": ["head_on_disc_disc"], "liggghts_mu_disc_disc_x0.9": both}
    assert mutant_scenes("--exhaustive", "--resume") == {"liggghts_kn_x1.05": both, "liggghts_mu_disc_disc_x0.9": both}


@pytest.mark.reference_codes
@needs_liggghts
def test_a_law_difference_is_attributed_to_the_option_that_closes_it(dem_binary, tmp_path):
    """The native side runs the scene's own law (no-tension on the elastic force, so the dashpot
    pulls the discs together as they part, and they part slower; the cap on the elastic force)
    against LIGGGHTS' shared law; the collision fails, and setting no_tension to the shared value
    alone closes it."""
    scene = tmp_path / "pull.toml"
    shutil.copy(CAL / "head_on_disc_disc.csv", tmp_path / "head_on_disc_disc.csv")
    scene.write_text((CAL / "head_on_disc_disc.toml").read_text()
                     .replace('no_tension = "total"', 'no_tension = "elastic"')
                     .replace('friction_cap = "total"', 'friction_cap = "elastic"'))
    out = tmp_path / "out"
    p = compare(dem_binary, scene, "--kind", "collision", "--codes", "native,liggghts", "--native-law", "scene",
                "--out", out)
    assert p.returncode == 1
    rep = json.loads((out / "agreement.json").read_text())
    att = rep["attribution"][0]
    assert att["failing"] >= 1
    rows = {r["option"]: r["failing"] for r in att["rows"]}
    # a head-on collision has no shear: the friction cap's variant alone changes nothing
    assert rows == {"no_tension = total": 0, "friction_cap = total": att["failing"]}
    assert att["verdict"] == "no_tension = total alone closes every failing metric"
    assert "## Attribution" in (out / "report.md").read_text()

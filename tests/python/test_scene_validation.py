"""Bad scenes are refused before any step: exit code 2, a message naming the file, the field,
the value and the reason, and no output directory left behind."""
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
BASE = (REPO / "reference_inputs" / "scenes" / "silo_17_18.toml").read_text()


def edit(text, old, new):
    assert old in text, f"test setup: {old!r} not in the base scene"
    return text.replace(old, new, 1)


LIST_FILL = """[fill]
type = "list"
material = "sand"
discs = [[10.0, 5.0, 1.0], [12.5, 5.0, 1.0]]
"""


def with_fill(fill):
    return re.sub(r"\[fill\].*?(?=\n\[end\])", fill.strip() + "\n", BASE, flags=re.S)


# (case id, scene text, fragments the message must contain)
CASES = [
    ("unknown key", edit(BASE, "[integrator]\n", "[integrator]\nsheme = 1\n"), ["integrator.sheme", "unknown key"]),
    ("unknown table", BASE + "\n[extra]\nx = 1\n", ["extra", "unknown key"]),
    ("missing dt", edit(BASE, "dt = 0.0001", ""), ["integrator.dt", "missing"]),
    ("missing table", re.sub(r"\[end\].*?(?=\n\[output\])", "", BASE, flags=re.S), ["end", "missing"]),
    ("wrong type", edit(BASE, "dt = 0.0001", 'dt = "small"'), ["integrator.dt", '"small"', "expected a number"]),
    ("negative dt", edit(BASE, "dt = 0.0001", "dt = -1e-5"), ["integrator.dt", "-1e-05", "> 0"]),
    ("zero density", edit(BASE, "density = 2.65", "density = 0"), ["materials.sand.density", "> 0"]),
    ("zero radius", edit(BASE, "radius = 1.0 ", "radius = 0.0 "), ["fill.radius", "> 0"]),
    ("list radius", with_fill(LIST_FILL.replace("[12.5, 5.0, 1.0]", "[12.5, 5.0, -1.0]")), ["disc 1", "radius", "> 0"]),
    ("bad scheme", edit(BASE, '"paper_eq19"', '"rk4"'), ["integrator.scheme", "rk4", "one of"]),
    ("bad lever arm", edit(BASE, 'friction_cap = "elastic"\n', 'friction_cap = "elastic"\nlever_arm = "centre"\n'),
     ["contact.lever_arm", "centre", "one of"]),
    ("overlap", with_fill(LIST_FILL.replace("[12.5, 5.0, 1.0]", "[11.5, 5.0, 1.0]")), ["overlaps", "disc 0", "disc 1"]),
    ("outside", with_fill(LIST_FILL.replace("[12.5, 5.0, 1.0]", "[55.0, 5.0, 1.0]")), ["disc 1", "outside the walls"]),
    ("through wall", with_fill(LIST_FILL.replace("[12.5, 5.0, 1.0]", "[0.5, 5.0, 1.0]")), ["disc 1", "overlaps wall", "left"]),
    ("count mismatch", with_fill(LIST_FILL + "count = 3\n"), ["fill.count", "3", "does not match"]),
    ("dt above bound", edit(BASE, "dt = 0.0001", "dt = 4e-4"), ["integrator.dt", "0.0004", "stability bound", "force_dt"]),
    ("nan", edit(BASE, "dt = 0.0001", "dt = nan"), ["integrator.dt", "finite"]),
    ("lattice too wide", edit(BASE, "s = 18 ", "s = 25 "), ["fill.s", "25", "do not fit"]),
    ("huge lattice", edit(BASE, "count = 350 ", "count = 1000000000000 "), ["fill.count", "5e7"]),
    ("missing pair", re.sub(r'\[\[pairs\]\]\s*# Table 2, particle to wall.*?(?=\n\[silo\])', "", BASE, flags=re.S),
     ["pairs", "sand", "wall"]),
    ("toml syntax", edit(BASE, "[integrator]", "[integrator"), ["TOML syntax error", "line"]),
]


@pytest.mark.parametrize("case,text,expect", CASES, ids=[c[0] for c in CASES])
def test_bad_scene_is_refused(tmp_path, run_dem, case, text, expect):
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    out = tmp_path / "out"
    proc = run_dem("run", scene, "--out", out)
    assert proc.returncode == 2, f"{case}: exit {proc.returncode}\n{proc.stdout}\n{proc.stderr}"
    assert str(scene) in proc.stderr, proc.stderr
    for frag in expect:
        assert frag in proc.stderr, f"{case}: {frag!r} not in: {proc.stderr}"
    assert not out.exists(), f"{case}: output directory left behind"


# A misspelt key is named as itself with the key it was meant to be, before any value is read:
# never as the required key it left missing, in whichever table it is.
MISSPELT = [
    ("required key", edit(BASE, "scheme = ", "schem = "), "integrator.schem: unknown key; did you mean `scheme`? (line 11)"),
    ("table", edit(BASE, "[integrator]", "[integrater]"), "integrater: unknown key; did you mean `integrator`?"),
    ("in a later table", edit(edit(BASE, "dt = 0.0001", ""), "time = 5.0 ", "tme = 5.0 "),
     "end.tme: unknown key; did you mean `time`?"),
    ("array of tables", edit(BASE, "[[pairs]]", "[[pairs]]\nmuu = 0.1"), "pairs[0].muu: unknown key; did you mean `mu`?"),
    ("far from any", edit(BASE, "[integrator]\n", "[integrator]\ncolour = 1\n"),
     "integrator.colour: unknown key (known: scheme, dt, force_dt, threads, disc_order, thread_choice)"),
]


@pytest.mark.parametrize("case,text,expect", MISSPELT, ids=[c[0] for c in MISSPELT])
def test_a_misspelt_key_is_named_before_a_missing_one(tmp_path, run_dem, case, text, expect):
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    proc = run_dem("run", scene, "--out", tmp_path / "out")
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert proc.stderr.startswith(f"dem: {scene}: {expect}") and proc.stderr.count("\n") == 1, proc.stderr
    assert "missing" not in proc.stderr
    assert not (tmp_path / "out").exists()


def test_dt_above_bound_runs_when_forced(tmp_path, run_dem):
    scene = tmp_path / "forced.toml"
    scene.write_text(edit(edit(BASE, "dt = 0.0001", "dt = 4e-4"), "time = 5.0 ", "time = 0.004 "))
    proc = run_dem("run", scene, "--out", tmp_path / "out", "--force-dt")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "out" / "summary.json").exists()


def test_blow_up_stops_with_exit_3(tmp_path, run_dem):
    """Verlet at dt = 1e-4 (forced) blows up on the paper's 17/18 fill, as in LIGGGHTS."""
    scene = tmp_path / "blow.toml"
    scene.write_text(edit(BASE, '"paper_eq19"', '"velocity_verlet"'))
    proc = run_dem("run", scene, "--out", tmp_path / "out", "--force-dt", "--quiet")
    assert proc.returncode == 3, proc.stdout + proc.stderr
    # Caught by the energy budget (blowup.hpp) before any overlap reaches half a radius: the
    # discs start at rest, so every erg above the start energy was made by the integrator.
    assert "unstable run" in proc.stderr and "energy created without a source" in proc.stderr, proc.stderr
    assert "fastest disc id" in proc.stderr
    import json
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "unstable" and "energy" in summary["reason"]
    step = int(re.search(r"\(step (\d+)\)", summary["reason"]).group(1))
    assert step <= 200, summary["reason"]  # 0.02 s of a fill that takes 0.4 s to rest
    # The state written is the last good one: kept every 1000 steps, so here the start (the
    # lattice at rest), not the blown-up discs.
    assert "last good state at t = 0 s" in proc.stderr, proc.stderr
    import numpy as np
    discs = np.genfromtxt(tmp_path / "out" / "discs.csv", delimiter=",", names=True, dtype=None, encoding=None)
    assert len(discs) == 350
    assert np.all(discs["vx"] == 0) and np.all(discs["vy"] == 0) and np.all(discs["omega"] == 0)
    assert np.all(np.isfinite(discs["x"])) and discs["y"].min() > 0


def test_blow_up_by_overlap_when_energy_check_is_loose(tmp_path, run_dem):
    """The overlap criterion alone still stops the same blow-up (end.max_energy_gain huge)."""
    scene = tmp_path / "blow.toml"
    scene.write_text(edit(edit(BASE, '"paper_eq19"', '"velocity_verlet"'), "[end]", "[end]\nmax_energy_gain = 1e12"))
    proc = run_dem("run", scene, "--out", tmp_path / "out", "--force-dt", "--quiet")
    assert proc.returncode == 3, proc.stdout + proc.stderr
    assert "unstable run" in proc.stderr and "overlap" in proc.stderr, proc.stderr


def test_cli_errors(run_dem, tmp_path):
    assert run_dem("run").returncode == 2
    assert run_dem("run", tmp_path / "missing.toml", "--out", tmp_path / "o").returncode == 2
    assert run_dem("frobnicate").returncode == 2
    assert run_dem("params", "--E", "abc").returncode == 2
    for args in (("--help",), ("run", "--help"), ("params", "--help")):
        proc = run_dem(*args)
        assert proc.returncode == 0 and "usage" in proc.stdout

"""benchmarks/rattle_study.py on one disc squeezed between a floor and a ceiling through
overdamped normal contacts: past the scheme's bound for its vertical mode (the closed form of
validation.md: mass m, stiffness and damping of the two contacts) the walls' load along gravity
flips from step to step and the study counts the member as rattling; inside the bound the walls
carry the disc's weight and the study counts none."""
import json
import math
import sys
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO_ROOT / "benchmarks"))
import rattle_study  # noqa: E402

R, RHO, KN, ZETA, SQUEEZE = 0.5, 2.65, 1e7, 3.0, 5e-4
M = RHO * math.pi * R * R
ETA = ZETA * 2 * math.sqrt(M * 2 * KN) / 2     # each contact's: zeta of m v'' = -2 k v - 2 eta v'
# velocity Verlet on m x'' = -k x - c x': dt < (2 / w0) (sqrt(1 + zeta^2) - zeta)
BOUND = 2 / math.sqrt(2 * KN / M) * (math.sqrt(1 + ZETA * ZETA) - ZETA)

# both pairs (disc-disc, disc-wall) alike: the one disc touches only the walls
PAIRS = "".join(f"""[[pairs]]
materials = ["sand", "{other}"]
kn = {KN!r}
ks = 0.0
eta_n = {ETA!r}
eta_s = 0.0
mu = 0.5
""" for other in ("sand", "wall"))

SCENE = f"""
[scene]
name = "squeezed_disc"
[physics]
gravity = [0.0, -980.0]
[integrator]
scheme = "velocity_verlet"
dt = {0.5 * BOUND!r}
[contact]
normal_spring = "overlap"
[materials.sand]
density = {RHO}
[materials.wall]
{PAIRS}[[walls]]
name = "floor"
from = [-5.0, 0.0]
to = [5.0, 0.0]
material = "wall"
[[walls]]
name = "ceiling"
from = [-5.0, {2 * (R - SQUEEZE)!r}]
to = [5.0, {2 * (R - SQUEEZE)!r}]
material = "wall"
[fill]
type = "list"
material = "sand"
discs = [[0.0, {R - SQUEEZE!r}, {R}]]
max_initial_overlap = 0.01
[end]
time = 0.1
stop_at_rest = false
"""


@pytest.fixture
def members(tmp_path, dem_module):
    scene = tmp_path / "case" / "m0" / "native" / "scene.toml"
    scene.parent.mkdir(parents=True)
    scene.write_text(SCENE)
    return tmp_path


def test_past_the_bound_the_floor_load_flips_inside_it_carries_the_weight(members, capsys):
    assert rattle_study.main([str(members), "--dt", f"{1.25 * BOUND!r},{0.8 * BOUND!r}", "--jobs", "1"]) == 0
    past, inside = json.loads((members / "rattle.json").read_text())
    assert past["dt"] > BOUND > inside["dt"]
    assert past["alternation"] > 1e-2, past["balance"]
    # step by step, not every other step: the load flips sign at each of them
    assert all(a * b < 0 for a, b in zip(past["balance"], past["balance"][1:])), past["balance"]
    assert inside["alternation"] < 1e-9 and abs(inside["mean"]) < 1e-6, inside["balance"]
    assert past["rattler"]["r"] == R and past["rattler"]["force_over_weight"] > 1e-2
    table = capsys.readouterr().out
    assert "1 of 1" in table and "0 of 1" in table, table


def test_a_folder_without_member_scenes_is_refused(tmp_path, capsys):
    assert rattle_study.main([str(tmp_path)]) == 2
    assert "no member scenes" in capsys.readouterr().err

"""The verdict's own machinery: the statistics whose power the report states, the plan of a scene
(kinds, list files, refusals before any run), mutants and attribution switches."""
import json
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest

from dem.compare.cases import mutants, plan, stats
from dem.compare.verdict import study
from dem.compare.cases.common import SHARED_VARIANT, Case, Result

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "reference_inputs" / "scenes"


@pytest.fixture(autouse=True)
def _engine(dem_binary, monkeypatch):
    monkeypatch.setenv("DEM_BINARY", str(dem_binary))


# ------------------------------------------------------------------ statistics

def test_the_stated_detectable_difference_is_detected_with_the_stated_power():
    """Monte Carlo: members drawn from normal distributions; a true difference equal to the
    stated detectable difference is rejected about POWER of the time, no difference about alpha."""
    rng = np.random.default_rng(3)
    n, sd, alpha, trials = 8, 1.0, 0.01, 3000
    se = sd / math.sqrt(n)
    mde = stats.detectable(math.hypot(se, se), 2 * n - 2, alpha)
    hits = {0.0: 0, mde: 0}
    for shift in hits:
        for _ in range(trials):
            a, b = rng.normal(10, sd, n), rng.normal(10 + shift, sd, n)
            t = stats.compare_means(stats.mean_se(a), stats.mean_se(b), alpha)
            hits[shift] += not t["pass"]
    assert hits[0.0] / trials < 2 * alpha
    # the t-quantile approximation of the power is within a few percent of the exact power
    assert 0.74 <= hits[mde] / trials <= 0.86, hits[mde] / trials


def test_wilson_interval_and_fisher_test_against_hand_values():
    z2 = 1.959963984540054 ** 2
    lo, hi = stats.wilson(0, 8)
    assert lo == 0.0 and hi == pytest.approx(z2 / (8 + z2), rel=1e-12)      # k = 0: upper = z^2/(n + z^2)
    lo, hi = stats.wilson(4, 8)
    half = 1.959963984540054 * math.sqrt(0.25 / 8 + z2 / 256) / (1 + z2 / 8)
    assert (lo, hi) == pytest.approx((0.5 - half, 0.5 + half), rel=1e-12)  # symmetric about 1/2
    # all jam against none: Fisher's p = 2 / C(16, 8) for 8 and 8 members
    t = stats.compare_proportions(0, 8, 8, 8, 0.05)
    assert t["p"] == pytest.approx(2 / math.comb(16, 8), rel=1e-9) and not t["pass"]
    assert stats.compare_proportions(2, 4, 1, 4, 0.05)["pass"]


def test_bootstrap_median_is_seeded_and_brackets_the_median():
    v = [1.0, 2.0, 3.0, 4.0, 100.0]
    m, lo, hi = stats.bootstrap_median(v)
    assert m == 3.0 and lo <= 3.0 <= hi and stats.bootstrap_median(v) == (m, lo, hi)


def test_members_for_a_five_percent_difference():
    # 2.8 s.e. rule of validation.md at many members: n = 2 (2.8 cv / d)^2
    n = stats.members_for(0.05, 0.05, 0.05)
    assert abs(n - 2 * (2.8 * 0.05 / 0.05) ** 2) <= 3


# ------------------------------------------------------------------ plans

def _entry(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_list_files_name_the_line_of_a_bad_option(tmp_path):
    lst = tmp_path / "x.list"
    lst.write_text(f"# comment\n{SCENES / 'silo_17_18.toml'} --dt 5e-5\n{SCENES / 'silo_17_18.toml'} --members one\n")
    with pytest.raises(plan.PlanError, match=r"x.list:3"):
        plan.read_list(lst, plan.Options())
    lst.write_text("missing.toml\n")
    with pytest.raises(plan.PlanError, match="not found"):
        plan.read_list(lst, plan.Options())


def test_kinds_come_from_the_scene():
    o = plan.Options()
    assert plan.make_plan(plan.Entry(SCENES / "discharge_11_12.toml", o)).kind == "discharge"
    p = plan.make_plan(plan.Entry(SCENES / "silo_17_18.toml", o))
    assert p.kind == "static" and p.members == 1 and p.shared["contact"] == SHARED_VARIANT
    assert p.resolved["contact"]["normal_spring"] == "incremental"      # the scene's own law kept apart
    with pytest.raises(plan.PlanError, match=r"\[discharge\]"):
        plan.make_plan(plan.Entry(SCENES / "discharge_11_12.toml", plan.Options(kind="static")))
    assert plan.make_plan(plan.Entry(SCENES / "shear_a58_clusters.toml", o)).kind == "shear"
    with pytest.raises(plan.PlanError, match=r"\[shear_box\]"):
        plan.make_plan(plan.Entry(SCENES / "shear_a58_clusters.toml", plan.Options(kind="static")))


def test_members_are_seeded_jitters_of_the_scene_start():
    d = np.array([[0.0, 0.0, 1.0, 0, 0, 0], [3.0, 0.0, 1.0, 0, 0, 0]])
    a, b = plan.jittered(d, 2, 1e-3), plan.jittered(d, 2, 1e-3)
    assert np.array_equal(a, b) and 0 < np.abs(a - d).max() <= 1e-3 and np.array_equal(a[:, 2:], d[:, 2:])
    z = plan.jittered(d, 0, 1e-3)                   # member 0 is a draw like the others
    assert 0 < np.abs(z - d).max() <= 1e-3 and not np.array_equal(z, a)


def test_a_scene_a_reference_code_cannot_express_is_refused_before_any_run(tmp_path, dem_binary):
    """A disc-wall spring stiffer than twice the disc-disc one: YADE combines the two materials of a
    contact in series and cannot reach it; the refusal names the field, the code and why, and
    nothing is written (exit 2)."""
    from dem.compare.io import scene_toml
    scene = scene_toml.edit(SCENES / "silo_17_18.toml", {"pairs[1].kn_rho_g": 1.5e5}, tmp_path / "s.toml")
    out = tmp_path / "out"
    p = subprocess.run([str(dem_binary), "compare", str(scene), "--out", str(out), "--codes", "native,yade"],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2, p.stderr
    assert "yade cannot express it" in p.stderr and "kn" in p.stderr and "series" in p.stderr
    assert not out.exists()


def test_dem_compare_documents_itself(dem_binary):
    p = subprocess.run([str(dem_binary), "compare", "--help"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0
    for word in ("--members", "--quick", "--full", "--mutants", "--native-law", "collision", "janssen",
                 "--margin", "--until-decided", "inconclusive", "exit codes"):
        assert word in p.stdout


# ------------------------------------------------------------------ mutants

def test_a_mutant_changes_one_constant_of_one_code():
    r = plan.make_plan(plan.Entry(SCENES / "silo_17_18.toml", plan.Options())).shared
    case = Case(name="x", resolved=r, discs=np.zeros((1, 6)), dt=5e-5, duration=0.1)
    m = mutants.Mutation("m", "yade", "mu", "disc-wall", 0.9, "gravity")
    assert m.applies("yade", case) and not m.applies("liggghts", case)
    r2 = m.apply(r)
    dd = [p for p in r2["pairs"] if p["materials"] == ["sand", "sand"]][0]
    dw = [p for p in r2["pairs"] if p["materials"] != ["sand", "sand"]][0]
    assert dd == [p for p in r["pairs"] if p["materials"] == ["sand", "sand"]][0]
    assert dw["mu"] == pytest.approx(0.9 * 0.176) and r["pairs"][1]["mu"] == 0.176   # the original untouched
    free = Case(name="x", resolved=dict(r, gravity=[0.0, 0.0]), discs=np.zeros((1, 6)), dt=5e-5, duration=0.1)
    assert not m.applies("yade", free)                 # the gravity-only mutant leaves collisions alone
    g = mutants.Mutation("g", "yade", "gravity", "", 1.01, "all").apply(r)
    assert g["gravity"][1] == pytest.approx(-980 * 1.01)


def test_caught_lists_only_metrics_that_disagree_under_the_mutant_alone():
    def m(name, v):
        return {"scene": "s", "metric": name, "verdict": v, "values": {}}
    tc = "translation constants read back (yade)"
    base = {"metrics": [m("a", "agree"), m("b", "disagree"), m("c", "agree"), m(tc, "agree")]}
    mut = {"metrics": [m("a", "agree"), m("b", "disagree"), m("c", "inconclusive"), m(tc, "disagree")]}
    c = mutants.caught(base, mut)
    assert c["caught"] and not c["caught_physically"] and [r["metric"] for r in c["metrics"]] == [tc]
    mut["metrics"][0]["verdict"] = "disagree"          # a physical metric disagrees: caught physically
    assert mutants.caught(base, mut)["caught_physically"]
    mut["metrics"][0]["verdict"] = "inconclusive"      # inconclusive is never a catch
    mut["metrics"][3]["verdict"] = "agree"
    assert not mutants.caught(base, mut)["caught"]


def test_a_power_check_mutant_must_disagree_by_its_statistical_kinds():
    """density_x1.25 caught by the translation check alone proves nothing of the wall loads."""
    def m(name, v, kind=None):
        return {"scene": "s", "metric": name, "verdict": v, "values": {},
                **({"kind": "statistical", "margin_kind": kind, "stat": {"estimate": 0.25}, "margin": 0.1,
                    "ci": [0.2, 0.3]} if kind else {"kind": "deterministic"})}
    tc = "translation constants read back (liggghts)"
    base = {"metrics": [m(tc, "agree"), m("load", "agree", "wall_load"), m("rate", "agree", "flow_rate")]}
    only_read_back = {"metrics": [m(tc, "disagree"), m("load", "inconclusive", "wall_load"),
                                  m("rate", "agree", "flow_rate")]}
    c = mutants.caught(base, only_read_back, ("wall_load",))
    assert not c["caught"] and c["proves"] == ["wall_load"] and c["proved"] == []
    by_load = {"metrics": [m(tc, "disagree"), m("load", "disagree", "wall_load"), m("rate", "agree", "flow_rate")]}
    c = mutants.caught(base, by_load, ("wall_load",))
    assert c["caught"] and c["proved"] == ["wall_load"] and c["effects"][0]["estimate"] == 0.25
    # a kind the run does not have is not required (the Janssen check on a list without the column)
    assert mutants.caught(base, by_load, ("wall_load", "janssen"))["caught"]
    assert [x.proves for x in mutants.mutations(("native", "liggghts"), ["density_x1.25"])] == [("wall_load",)]


# ------------------------------------------------------------------ discharge measures

def test_windowed_peak_is_the_largest_moving_average_over_the_opening_value():
    r = plan.make_plan(plan.Entry(SCENES / "discharge_11_12.toml", plan.Options())).shared
    case = Case(name="d", resolved=r, discs=np.zeros((1, 6)), dt=2.5e-5, duration=0.6, mode="discharge", settle=1.0)
    t = np.arange(0, 0.6 + 1e-9, case.series_interval)
    walls = {}
    for w in r["walls"]:
        nb = 20
        rows = np.ones((len(t), nb))
        if w["name"] == "left":
            rows[40:50] *= 4.0           # a 0.05 s surge to 4x on one side wall
            rows[60, 3] *= 100.0         # one wild sample of one bin: a raw peak ratio of 100
        walls[w["name"]] = {"normal": rows.tolist(), "shear": (0 * rows).tolist()}
    res = Result(code="x", case="d", series={"t": t.tolist(), "walls": walls})
    pk = study.windowed_peaks(res, case)
    # side total at the opening: 2 walls x 20 bins = 40; the surge: (4 x 20 + 20) / 40 = 2.5 over
    # its whole window; the spike's window: (40 + 99 / 10) / 40 = 1.2475, below it
    assert pk["peak_window_side"] == pytest.approx(2.5)
    assert pk["peak_window_bottom"] == pytest.approx(1.0)


def test_every_code_removes_discs_at_the_engines_outlet_height(tmp_path, dem_binary):
    """outlet_depth is measured from the gate (the slit's floor), not from y = 0: a hopper whose
    gate is at y = 6 removes discs below y = 2 in the engine, the LIGGGHTS outlet mesh and the
    YADE remover alike (measured from y = 0 the references counted discs some 0.05 s later)."""
    import meshio
    from dem.compare.codes import liggghts_backend, yade_backend
    from dem.compare.cases.common import outlet_y
    scene = ROOT / "reference_inputs" / "agreement" / "user" / "hopper.toml"
    p = plan.make_plan(plan.Entry(scene, plan.Options()))
    gate = next(w for w in p.shared["walls"] if w["name"] == "gate")
    expected = gate["from"][1] - p.shared["discharge"]["outlet_depth"]
    assert expected == 2.0 and outlet_y(p.shared) == expected
    case = plan.member_case(p, 0)
    liggghts_backend.write_inputs(case, tmp_path / "l")
    assert np.allclose(meshio.read(str(tmp_path / "l" / "outlet.stl")).points[:, 1], expected)
    assert yade_backend.case_data(case)["outlet_y"] == expected
    r = subprocess.run([str(dem_binary), "run", str(scene), "--out", str(tmp_path / "n"), "--quiet",
                        "--end-time", "0.01"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert json.loads((tmp_path / "n" / "summary.json").read_text())["discharge"]["outlet_y"] == expected


def test_a_power_check_mutant_runs_on_the_scenes_that_judge_its_metrics():
    """A power-check mutant runs only where the statistical metric kinds it must make disagree are
    judged (in CI the quick list: the slit ends on the designed discharge alone, the density on
    the static members and the discharge); another mutant, or one with no such scene, on all."""
    from dem.compare.__main__ import mutant_plans
    plans = [plan.make_plan(e) for e in plan.read_list(plan.default_list("quick"), plan.Options())]
    by = {m.name: m for m in mutants.mutations(("native", "liggghts", "yade"),
                                               ["liggghts_slit_ends_1r", "liggghts_density_x1.25", "liggghts_ks_x0.5"])}
    names = lambda mu: [p.name for p in mutant_plans(mu, plans)]
    assert names(by["liggghts_slit_ends_1r"]) == ["silo_1000"]
    assert names(by["liggghts_density_x1.25"]) == ["silo_17_18_members", "silo_1000"]
    assert len(names(by["liggghts_ks_x0.5"])) == len(plans) > 15
    collisions = [p for p in plans if p.kind == "collision"]
    assert mutant_plans(by["liggghts_slit_ends_1r"], collisions) == collisions

"""The shear kind of `dem compare` (compare/cases/shear.py): paper 2's shear box planned from its scene,
LIGGGHTS' refusal before any run, the one translation of each code (native scene, YADE case) for
a jittered member, the bond-set mutant, the judge, and (with YADE) a small box end to end."""
import dataclasses
import json
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from dem.compare.cases import margins, mutants, plan, shear, stats
from dem.compare.codes import backends, native_backend, yade_backend
from dem.compare.verdict import shear_judge, verdict
from dem.compare.cases.common import SHARED_VARIANT, Result, resolve

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "reference_inputs" / "scenes"
CODES = ("native", "liggghts", "yade")


@pytest.fixture(autouse=True)
def _engine(dem_binary, monkeypatch):
    monkeypatch.setenv("DEM_BINARY", str(dem_binary))


def _plan(name, **kw):
    return plan.make_plan(plan.Entry(SCENES / f"{name}.toml", plan.Options(**kw)))


# ------------------------------------------------------------------ plans and refusals

def test_a_shear_box_scene_is_planned_as_the_shear_kind():
    p = _plan("shear_a50_clusters")
    assert p.kind == "shear" and p.members == 4 and p.name == "shear_a50_clusters"
    assert p.shared["contact"] == SHARED_VARIANT and p.shared["integrator"]["scheme"] == "velocity_verlet"
    assert p.resolved["contact"]["normal_spring"] == "incremental"      # the scene's own law kept apart
    # the shared scheme (velocity Verlet) with the bonded clusters: 1e-4 halved to 2.5e-5 s
    # (bound 4.59e-5 s: dem resolve --stability with the shared scheme and law)
    assert p.dt == 2.5e-5
    assert p.settle == 4.0 and p.duration == pytest.approx(math.atan(0.15) / 0.05, rel=1e-15)
    case = plan.member_case(p, 1)
    assert case.mode == "shear" and case.name == "shear_a50_clusters_m1" and case.settle == 4.0
    # a shorter shear and compression: the walls turn for --duration s, compression at most --settle s
    q = _plan("shear_a50_free", duration=1.0, settle=2.0, dt=5e-5, members=2)
    assert q.shared["shear"]["max_strain"] == pytest.approx(math.tan(0.05), rel=1e-15)
    assert q.shared["end"]["time"] == 2.0 == q.settle and q.dt == 5e-5 and q.members == 2
    assert q.resolved["shear"]["max_strain"] == q.shared["shear"]["max_strain"]   # --native-law scene alike


def test_shear_and_clusters_are_refused_by_the_other_kinds(tmp_path):
    with pytest.raises(plan.PlanError, match=r"\[shear_box\].*--kind static"):
        _plan("shear_a58_clusters", kind="static")
    with pytest.raises(plan.PlanError, match=r"--kind shear: the scene has no \[shear_box\]"):
        _plan("silo_17_18", kind="shear")
    text = (SCENES / "silo_17_18.toml").read_text() + "\n[clusters]\nmembers = [[0, 1]]\n"
    (tmp_path / "c.toml").write_text(text)
    with pytest.raises(plan.PlanError, match=r"\[clusters\]: bonded clusters are compared in the shear box only"):
        plan.make_plan(plan.Entry(tmp_path / "c.toml", plan.Options()))


@pytest.mark.reference_codes
def test_liggghts_refuses_the_shear_box_before_any_run(tmp_path, dem_binary):
    """Bonds: LIGGGHTS-PUBLIC 3.8.0's only bond style is a central harmonic spring; the plate: a
    wall moved by gravity and the discs' forces, which LIGGGHTS' meshes cannot be. A free-disc box
    is refused for the plate alone. Exit 2, nothing written; YADE alone plans."""
    for name, has_bonds in (("shear_a50_clusters", True), ("shear_a50_free", False)):
        out = tmp_path / name
        p = subprocess.run([str(dem_binary), "compare", str(SCENES / f"{name}.toml"), "--out", str(out)],
                           capture_output=True, text=True, timeout=120)
        assert p.returncode == 2, p.stderr
        assert "liggghts cannot express it" in p.stderr and "shear_box.plate_mass" in p.stderr
        assert ("clusters.bonds" in p.stderr and "bond_style harmonic" in p.stderr) == has_bonds
        assert "yade cannot" not in p.stderr and not out.exists()
    p = _plan("shear_a50_clusters")
    assert backends.refusals(p, ("native", "yade")) == []


def test_a_list_line_names_the_codes_it_runs(tmp_path):
    lst = tmp_path / "x.list"
    lst.write_text(f"{SCENES / 'shear_a50_clusters.toml'} --codes native,yade --members 2\n"
                   f"{SCENES / 'silo_17_18.toml'} --duration 0.1\n")
    a, b = [plan.make_plan(e) for e in plan.read_list(lst, plan.Options())]
    assert plan.codes_of(a, CODES) == ("native", "yade") and plan.codes_of(b, CODES) == CODES
    assert plan.codes_of(a, ("native", "liggghts")) == ("native",)
    lst.write_text(f"{SCENES / 'silo_17_18.toml'} --codes yade\n")     # native, the reference, always runs
    assert plan.read_list(lst, plan.Options())[0].options.codes == ("native", "yade")
    lst.write_text(f"{SCENES / 'silo_17_18.toml'} --codes lammps\n")       # the third reference code
    assert plan.read_list(lst, plan.Options())[0].options.codes == ("native", "lammps")
    lst.write_text(f"{SCENES / 'silo_17_18.toml'} --codes native,nosuch\n")
    with pytest.raises(plan.PlanError, match="unknown"):
        plan.read_list(lst, plan.Options())


def test_the_shear_entry_of_the_full_study_runs_native_and_yade():
    entries = [e for e in plan.read_list(plan.default_list("full"), plan.Options(profile="full"))
               if e.scene.name.startswith("shear_")]
    assert entries and all(e.options.codes == ("native", "yade") for e in entries)


# ------------------------------------------------------------------ the translations

def test_both_codes_translate_the_same_member(tmp_path):
    """One jittered member: the engine's scene resolves to the case's discs, constants, clusters
    and box (plate placed by the engine itself plate_gap above the jittered discs); YADE's case has
    the same discs, the plate at the same height, the series materials and every bond of the
    engine's list with its pair's springs."""
    p = _plan("shear_a50_clusters")
    case = plan.member_case(p, 2)
    assert 0 < np.abs(case.discs[:, :2] - plan.start_discs(p.shared)[:, :2]).max() <= 1e-3
    scene = native_backend.write_inputs(case, tmp_path / "native")
    r = resolve(scene)
    assert r["contact"] == SHARED_VARIANT and r["integrator"]["scheme"] == "velocity_verlet"
    assert r["integrator"]["dt"] == 2.5e-5 and r["end"]["time"] == 4.0 and r["end"]["stop_at_rest"]
    assert np.array_equal(np.array(r["discs"])[:, :3], case.discs[:, :3])
    assert r["clusters"] == p.shared["clusters"] and r["shear"] == p.shared["shear"]
    assert r["pairs"] == p.shared["pairs"] and r["gravity"] == p.shared["gravity"]
    for k in ("width", "wall_length", "plate_mass", "plate_horizontal"):
        assert r["shear_box"][k] == p.shared["shear_box"][k]
    assert {w["name"]: (w["from"], w["to"]) for w in r["walls"] if w["name"] != "plate"} == \
        {w["name"]: (w["from"], w["to"]) for w in p.shared["walls"] if w["name"] != "plate"}
    y = yade_backend.case_data(case)
    assert y["mode"] == "shear" and y["dt"] == 2.5e-5 and y["compress"]["max_time"] == 4.0
    assert y["box"]["plate_y"] == pytest.approx(r["shear_box"]["plate_y"], abs=1e-12)
    assert y["box"]["plate_y"] == pytest.approx(float(np.max(case.discs[:, 1] + 1.0)) + 0.004, abs=1e-12)
    assert np.array_equal(np.array(y["discs"]), case.discs)
    dd = p.shared["pairs"][0]
    assert y["disc_materials"]["sand"]["kn"] == 2 * dd["kn"] and y["wall_materials"]["wall"]["kn"] == 0.0
    assert [a for a in y["friction"]] == [["sand", "sand", 0.577], ["sand", "wall", 0.176]]
    bonds = y["clusters"]["bonds"]
    assert len(bonds) == 3 * 60 and all([kn, ks] == [dd["kn"], dd["ks"]] for _, _, kn, ks in bonds)
    assert [b[:2] for b in bonds] == shear.bonds_of(case.discs, p.shared["clusters"])
    yade_backend.write_inputs(case, tmp_path / "yade")
    assert (tmp_path / "yade" / "yade_script.py").read_text() == yade_backend.SHEAR_TEMPLATE.read_text()


def test_the_touching_clusters_bond_the_apex_base_pairs_only():
    case = plan.member_case(_plan("shear_a50_touching"), 0)
    assert len(yade_backend.case_data(case)["clusters"]["bonds"]) == 2 * 60
    free = plan.member_case(_plan("shear_a50_free"), 0)
    assert yade_backend.case_data(free)["clusters"] == {"mode": "none"}


def test_the_engine_has_no_clumps(tmp_path):
    case = dataclasses.replace(plan.member_case(_plan("shear_a50_clusters"), 0), clusters="clumps")
    with pytest.raises(Exception, match="YADE's alone"):
        native_backend.write_inputs(case, tmp_path)
    assert yade_backend.case_data(case)["clusters"]["mode"] == "clumps"


@pytest.mark.reference_codes
def test_the_bond_set_mutant_drops_the_gap_bonds_of_yade_only():
    p = _plan("shear_a50_clusters")
    case = plan.member_case(p, 0)
    m = next(x for x in mutants.mutations(("native", "yade")) if x.name == "yade_bonds_touching_only")
    assert m.applies("yade", case) and not m.applies("native", case)
    mutated = dataclasses.replace(case, resolved=m.apply(case.resolved))
    assert len(yade_backend.case_data(mutated)["clusters"]["bonds"]) == 2 * 60
    assert mutated.resolved["pairs"] == case.resolved["pairs"]        # the constants the probe reads: unchanged
    for other in ("shear_a50_touching", "shear_a50_free", "silo_17_18"):
        assert not m.applies("yade", plan.member_case(_plan(other), 0))


# ------------------------------------------------------------------ the judge

def _result(code, ratio_scale=1.0, rise=0.5, seed=0, rest=True):
    rng = np.random.default_rng(seed)
    strain = np.round(np.arange(0, 0.1505, 0.001), 12)
    ratio = ratio_scale * (0.8 * (1 - np.exp(-strain / 0.02)) + rng.normal(0, 0.004, len(strain)))
    plate_y = -0.08 + rise * strain / 0.15 + rng.normal(0, 0.004)
    series = {"strain": strain.tolist(), "ratio": ratio.tolist(), "sigma": (1.2e5 + rng.normal(0, 50) + 0 * strain).tolist(),
              "tau": (ratio * 1.2e5).tolist(), "plate_y": plate_y.tolist(), "t": (strain / 0.05).tolist()}
    return Result(code=code, case="x", extra={"shear": {"series": series, "rest_reached": rest, "status": "sheared"}})


def _judged(metrics):
    """The metrics judged as a report judges them (compare/verdict/verdict.py)."""
    return verdict.finalize(metrics)


def test_the_judge_agrees_on_one_distribution_and_disagrees_on_a_shifted_one():
    opts = plan.Options()
    same = {"native": [_result("native", seed=k) for k in range(6)],
            "yade": [_result("yade", seed=100 + k) for k in range(6)]}
    metrics, detail = shear_judge.judge("x", same, 0.15, 0.001, opts)
    metrics = _judged(metrics)
    names = [m["metric"] for m in metrics]
    assert len([n for n in names if n.startswith("shear ") and "(yade vs native)" in n]) == 2 + 4 + 1
    stat = [m for m in metrics if m["kind"] == "statistical"]
    assert all(m["margin"] == margins.margin("shear", "quick") for m in stat)
    peak = next(m for m in stat if "peak" in m["metric"])
    assert peak["verdict"] == "agree" and -0.1 < peak["ci"][0] < peak["ci"][1] < 0.1
    # the peak's 10 % shift lies on the margin: never agree; 30 % disagrees
    for scale, want in ((1.1, ("inconclusive", "disagree")), (1.3, ("disagree",))):
        shifted = dict(same, yade=[_result("yade", ratio_scale=scale, seed=100 + k) for k in range(6)])
        metrics, _ = shear_judge.judge("x", shifted, 0.15, 0.001, opts)
        assert next(m for m in _judged(metrics) if "peak" in m["metric"])["verdict"] in want, scale
    unrested = dict(same, yade=[_result("yade", seed=100 + k, rest=k > 0) for k in range(6)])
    metrics, _ = shear_judge.judge("x", unrested, 0.15, 0.001, opts)
    assert not next(m for m in _judged(metrics) if "at rest before the shear (yade)" in m["metric"])["pass"]
    failed = dict(same, yade=same["yade"][:5] + [Result(code="yade", case="x", status="failed", reason="boom")])
    metrics, _ = shear_judge.judge("x", failed, 0.15, 0.001, opts)
    judged = [m for m in _judged(metrics) if "vs native" in m["metric"]]
    assert judged and all(m["verdict"] == "inconclusive" and "boom" in m["note"] for m in judged)
    assert len(detail["curves"]["native"]["ratio"]["mean"]) == len(detail["strain"]) == 151


def test_bands_follow_a_shorter_shear():
    assert shear.bands(0.15) == list(shear.BANDS)
    assert shear.bands(0.05) == [(0.0, 0.02), (0.02, 0.05)]
    assert shear.bands(0.022) == [(0.0, 0.02)]


# ------------------------------------------------------------------ end to end (YADE)

def small_box(tmp_path, max_strain=0.01):
    import importlib.util
    spec = importlib.util.spec_from_file_location("make_shear_scenes", ROOT / "scripts" / "make_shear_scenes.py")
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    gen.WIDTH, gen.HEIGHT = 12.0, 6.0
    text = gen.scene_text(50, "clusters").replace("max_strain = 0.15", f"max_strain = {max_strain}")
    text = text.replace("snapshots = [0.0, 0.05, 0.15]", f"snapshots = [0.0, {max_strain}]")
    scene = tmp_path / "box.toml"
    scene.write_text(text.replace("progress = true", "progress = false"))
    return scene


@pytest.mark.reference_codes
@pytest.mark.skipif(shutil.which("yade") is None, reason="yade is not installed")
def test_a_small_clustered_box_agrees_in_native_and_yade(tmp_path, dem_binary):
    """12 cm x 6 cm box of bonded triangles, 2 members, sheared to 1 %: every member rests, no
    metric disagrees (two members decide little: inconclusive is the honest verdict, exit 3), every
    statistical metric carries its margin and interval, the report shows the box."""
    out = tmp_path / "out"
    p = subprocess.run([str(dem_binary), "compare", str(small_box(tmp_path)), "--codes", "native,yade",
                        "--members", "2", "--out", str(out)], capture_output=True, text=True, timeout=600)
    rep = json.loads((out / "agreement.json").read_text())
    assert p.returncode in (0, 3) and rep["verdict"] in ("agree", "inconclusive"), \
        [m for m in rep["metrics"] if m["verdict"] == "disagree"] or p.stdout[-2000:] + p.stderr[-2000:]
    assert all(m["verdict"] == "agree" for m in rep["metrics"] if m["kind"] == "deterministic")
    assert all("margin" in m and len(m["ci"]) == 2 for m in rep["metrics"] if m["kind"] == "statistical")
    names = [m["metric"] for m in rep["metrics"]]
    assert "translation constants read back (yade)" in names
    assert any(n.startswith("shear peak tau/sigma") for n in names)
    assert any(n.startswith("shear dilation") for n in names)
    text = (out / "report.md").read_text()
    assert "## Shear box box" in text and (out / "shear_box.png").exists()
    yade = json.loads((out / "shear" / "box" / "m0" / "yade" / "result.json").read_text())
    assert yade["status"] == "ok" and yade["extra"]["shear"]["bonds"] == len(
        json.loads((out / "shear" / "box" / "m0" / "yade" / "yade_case.json").read_text())["clusters"]["bonds"])

"""What the verdict refuses or leaves undecided before any reference code runs: a dt above the
engine's bound (exit 2, with the largest dt that passes), a bad --margin, a native fill that did
not rest (inconclusive, with the --settle that reaches rest); and the exit code of an undecided
report (3)."""
import json
import subprocess
import time
from pathlib import Path

import pytest

from dem.compare.cases import margins, plan
from dem.compare.verdict import verdict

ROOT = Path(__file__).resolve().parents[2]
SILO = ROOT / "reference_inputs" / "scenes" / "silo_17_18.toml"


def compare(dem_binary, *args, timeout=600):
    return subprocess.run([str(dem_binary), "compare", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout)


def test_a_dt_above_the_engines_bound_is_refused_before_any_run(dem_binary, tmp_path):
    out = tmp_path / "out"
    t0 = time.monotonic()
    p = compare(dem_binary, SILO, "--dt", "2e-4", "--out", out)
    assert p.returncode == 2 and time.monotonic() - t0 < 10, p.stderr
    assert "stability bound" in p.stderr and not out.exists()
    largest = float(p.stderr.split("(--dt ")[1].split(")")[0])
    bound = float(p.stderr.split("stability bound ")[1].split(" s")[0])
    assert largest <= bound and largest > 0.99 * bound
    # the dt it names passes the pre-flight
    q = subprocess.run([str(dem_binary), "resolve", str(SILO)], capture_output=True, text=True)
    assert q.returncode == 0
    from dem.compare.verdict import preflight
    pl = plan.make_plan(plan.Entry(SILO, plan.Options(dt=largest)))
    assert preflight.refusal(pl, plan.member_case(pl, 0)) is None
    pl = plan.make_plan(plan.Entry(SILO, plan.Options(dt=bound * 1.01)))
    assert "stability bound" in preflight.refusal(pl, plan.member_case(pl, 0))


@pytest.mark.parametrize("item, why", [("flow=0.1", "KIND one of"), ("flow_rate=x", "not a number"),
                                       ("flow_rate=0", "fraction in (0, 1]"), ("flow_rate", "KIND=DELTA")])
def test_a_bad_margin_is_refused_naming_it(item, why, dem_binary, tmp_path):
    with pytest.raises(ValueError, match=why.replace("(", r"\(").replace(")", r"\)")):
        margins.parse([item])
    p = compare(dem_binary, SILO, "--margin", item, "--out", tmp_path / "o")
    assert p.returncode == 2 and "--margin" in p.stderr and not (tmp_path / "o").exists()


def test_margins_by_profile_and_override():
    assert margins.margin("flow_rate", "quick") == 0.10 and margins.margin("flow_rate", "full") == 0.05
    assert margins.margin("flow_rate", "full", {"flow_rate": 0.2}) == 0.2
    assert not margins.MARGINS["jam_fraction"].relative


def test_a_fill_that_does_not_rest_is_inconclusive_and_names_the_settle(dem_binary, tmp_path):
    """0.02 s of fill: the lattice is still falling; no reference code runs, the report says
    inconclusive (exit 3) and gives the --settle it tried."""
    out = tmp_path / "out"
    p = compare(dem_binary, SILO, "--codes", "native", "--dt", "5e-5", "--settle", "0.02", "--duration", "0.01",
                "--out", out)
    rep = json.loads((out / "agreement.json").read_text())
    assert p.returncode == 3 and rep["verdict"] == "inconclusive", p.stdout + p.stderr
    m = rep["metrics"][0]
    assert m["verdict"] == "inconclusive" and "did not reach rest in 0.02 s (--settle 0.02;" in m["note"]
    assert "--settle 0.04" in m["note"] or "--settle 0.08" in m["note"]
    assert not list((out / "static").rglob("native/result.json"))     # the codes never started


@pytest.mark.release_only  # Python's side: the sanitized engine's runs are the other tests'
def test_a_discharge_whose_members_open_before_rest_is_inconclusive(dem_binary, tmp_path):
    """--start scene with 0.05 s of settling: each member would open the gate on a falling lattice.
    The native fill of that --settle is tried first; no member runs, the verdict is inconclusive
    (exit 3), naming the --settle that reaches rest."""
    out = tmp_path / "out"
    scene = SILO.parent / "discharge_17_18.toml"
    p = compare(dem_binary, scene, "--codes", "native", "--start", "scene", "--dt", "5e-5", "--settle", "0.05",
                "--duration", "0.05", "--out", out)
    rep = json.loads((out / "agreement.json").read_text())
    assert p.returncode == 3 and rep["verdict"] == "inconclusive", p.stdout + p.stderr
    m = rep["metrics"][0]
    assert "did not reach rest in 0.05 s (--settle 0.05;" in m["note"] and "--settle 0.2 reaches it" in m["note"], m
    assert not list(out.rglob("m0"))                                   # no member ran


def test_verdicts_combine_and_map_to_exit_codes():
    assert verdict.combine(["agree", "inconclusive", "agree"]) == "inconclusive"
    assert verdict.combine(["agree", "inconclusive", "disagree"]) == "disagree"
    assert verdict.combine(["agree"]) == "agree" and verdict.combine([]) == "inconclusive"
    assert verdict.EXIT == {"agree": 0, "disagree": 1, "inconclusive": 3}


def test_the_forest_plot_draws_every_statistical_metric_of_a_scene(tmp_path):
    from dem.compare.verdict import report
    from dem.compare.cases import stats
    a, b = [100.0, 101.0, 99.0, 100.5], [101.0, 102.0, 100.0, 101.0]
    ms = [verdict.statistical("flow_rate (liggghts vs native)", "s", stats.difference(a, b, paired=True), "flow_rate",
                              plan.Options()),
          verdict.statistical("jam fraction (liggghts vs native)", "s", stats.proportions(0, 4, 0, 4), "jam_fraction",
                              plan.Options()),
          {"metric": "collision", "scene": "s", "values": {}, "tolerance": 1, "pass": True, "note": ""}]
    verdict.finalize(ms)
    assert [m["verdict"] for m in ms] == ["agree", "inconclusive", "agree"]
    assert report.plot_forest(ms, tmp_path / "v.png", "s") and (tmp_path / "v.png").stat().st_size > 10_000
    assert not report.plot_forest(ms[2:], tmp_path / "w.png", "s") and not (tmp_path / "w.png").exists()

"""`dem ensemble`: members differ by a seeded perturbation; statistics are those of the members."""
import json
import math
from pathlib import Path

import numpy as np

from dem.compare.io import scene_toml

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "reference_inputs" / "scenes" / "discharge_17_18.toml"


def short_scene(tmp_path):
    return scene_toml.edit(SCENE, {"discharge.time": 0.4}, tmp_path / "short.toml")


def test_ensemble_statistics_and_seeds(tmp_path, run_dem):
    scene = short_scene(tmp_path)
    runs = {}
    for tag, seed in (("a", 7), ("b", 7), ("c", 8)):
        out = tmp_path / tag
        proc = run_dem("ensemble", scene, "--out", out, "--members", 3, "--seed", seed, "--jobs", 2, "--quiet")
        assert proc.returncode == 0, proc.stderr
        runs[tag] = json.loads((out / "ensemble.json").read_text())
    a, b, c = runs["a"], runs["b"], runs["c"]
    assert a["flow_rate_discs"] == b["flow_rate_discs"]          # same seed: identical
    assert [r["flow_rate_discs"] for r in a["runs"]] != [r["flow_rate_discs"] for r in c["runs"]]
    members = [json.loads((tmp_path / "a" / f"member_{k:02d}" / "summary.json").read_text())["discharge"]
               for k in range(3)]
    out1 = np.array([m["discs_out_at_1s"] for m in members], dtype=float)
    assert a["discs_out_at_1s"]["mean"] == np.mean(out1)
    expect_se = np.std(out1, ddof=1) / math.sqrt(3)
    assert abs(a["discs_out_at_1s"]["stderr"] - expect_se) <= 1e-12 * max(1.0, expect_se)
    jams = sum(1 for m in members if m["jams"] > 0)
    assert a["jam_fraction"]["value"] == jams / 3
    # Each member's folder has its run.log (header and outcome), thermo.csv and the command line.
    member = tmp_path / "a" / "member_01"
    log = (member / "run.log").read_text()
    assert "stability bound" in log and "ensemble member 1" in log and " steps; fill rest " in log
    assert (member / "thermo.csv").read_text().count(",discharge,") > 0
    s = json.loads((member / "summary.json").read_text())
    assert s["command"][1:3] == ["ensemble", str(scene)] and "--seed" in s["command"]


def test_ensemble_refuses_a_perturbation_that_overlaps(tmp_path, run_dem):
    proc = run_dem("ensemble", SCENE, "--out", tmp_path / "o", "--members", 2, "--perturb", 0.01)
    assert proc.returncode == 2
    assert "perturb" in proc.stderr and "overlap" in proc.stderr
    assert not (tmp_path / "o").exists()


def test_ensemble_fails_when_every_member_failed(tmp_path, run_dem):
    """No member to read: exit 4 when members could not run (here: their folders cannot be
    made), 3 when every member was unstable (a step far above the stability bound, forced)."""
    out = tmp_path / "blocked"
    out.mkdir()
    for k in range(2):
        (out / f"member_{k:02d}").write_text("a file where the member's folder goes")
    proc = run_dem("ensemble", short_scene(tmp_path), "--out", out, "--members", 2, "--quiet")
    assert proc.returncode == 4, proc.stderr
    assert "every member failed" in proc.stderr
    runs = json.loads((out / "ensemble.json").read_text())["runs"]
    assert all(r["status"].startswith("error") for r in runs)
    proc = run_dem("ensemble", short_scene(tmp_path), "--out", tmp_path / "unstable", "--members", 2, "--quiet",
                   "--dt", 2e-3, "--force-dt")
    assert proc.returncode == 3, proc.stderr
    assert json.loads((tmp_path / "unstable" / "ensemble.json").read_text())["unstable"] == 2


def test_one_member_that_could_not_run_fails_the_ensemble_even_quiet(tmp_path, run_dem):
    """The help promises exit 4 when a member could not run: one blocked member of two gives 4
    and a message on stderr with --quiet; the other member's statistics are still written."""
    out = tmp_path / "e"
    out.mkdir()
    (out / "member_00").write_text("a file where the member's folder goes")
    proc = run_dem("ensemble", short_scene(tmp_path), "--out", out, "--members", 2, "--quiet",
                   "--set", "discharge.time=0.05")
    assert proc.returncode == 4 and "1 of 2 members could not run" in proc.stderr, proc.stderr
    e = json.loads((out / "ensemble.json").read_text())
    assert e["failed"] == 1 and e["discs_out_at_1s"]["n"] == 1


def test_members_run_alone_and_merged_equal_the_ensemble(tmp_path, run_dem):
    """--member K runs member K alone (a job of a job array); merge gathers the members into the
    same ensemble.json, bit for bit, as the ensemble run in one process."""
    scene = short_scene(tmp_path)
    whole, parts = tmp_path / "whole", tmp_path / "parts"
    proc = run_dem("ensemble", scene, "--out", whole, "--members", 3, "--seed", 5, "--jobs", 2, "--quiet")
    assert proc.returncode == 0, proc.stderr
    for k in (2, 0, 1):  # any order, any machine
        proc = run_dem("ensemble", scene, "--out", parts, "--member", k, "--seed", 5, "--quiet")
        assert proc.returncode == 0, proc.stderr
    proc = run_dem("ensemble", "merge", parts, "--members", 3, "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert (parts / "ensemble.json").read_bytes() == (whole / "ensemble.json").read_bytes()
    for k in range(3):
        for name in ("discs.csv", "removals.csv", "wall_series.csv"):
            a, b = whole / f"member_{k:02d}" / name, parts / f"member_{k:02d}" / name
            assert a.read_bytes() == b.read_bytes(), (k, name)


def test_merge_refuses_missing_members_and_other_ensembles(tmp_path, run_dem):
    scene = short_scene(tmp_path)
    out = tmp_path / "parts"
    for k, seed in ((0, 5), (1, 6)):
        proc = run_dem("ensemble", scene, "--out", out, "--member", k, "--seed", seed, "--quiet")
        assert proc.returncode == 0, proc.stderr
    proc = run_dem("ensemble", "merge", out, "--quiet")
    assert proc.returncode == 2 and "another ensemble" in proc.stderr, proc.stderr
    assert not (out / "ensemble.json").exists()
    (out / "member_01" / "member.json").unlink()
    proc = run_dem("ensemble", "merge", out, "--members", 2, "--quiet")
    assert proc.returncode == 2 and "member_01" in proc.stderr and "missing" in proc.stderr, proc.stderr
    proc = run_dem("ensemble", "merge", out, "--members", 3, "--quiet")
    assert proc.returncode == 2, proc.stderr


def test_members_without_a_result_count_in_no_statistic(tmp_path, run_dem):
    """An unstable member (here: one member's summary marked so before the merge) is left out of
    the means, the jam fraction and the pattern counts, and counted as failed."""
    scene = short_scene(tmp_path)
    out = tmp_path / "parts"
    for k in range(3):
        proc = run_dem("ensemble", scene, "--out", out, "--member", k, "--seed", 5, "--quiet")
        assert proc.returncode == 0, proc.stderr
    path = out / "member_02" / "summary.json"
    s = json.loads(path.read_text())
    s["status"] = "unstable"
    path.write_text(json.dumps(s))
    proc = run_dem("ensemble", "merge", out, "--members", 3, "--quiet")
    assert proc.returncode == 0, proc.stderr
    e = json.loads((out / "ensemble.json").read_text())
    members = [json.loads((out / f"member_{k:02d}" / "summary.json").read_text())["discharge"] for k in range(2)]
    assert e["unstable"] == 1 and e["failed"] == 1
    assert e["discs_out_at_1s"]["n"] == 2
    assert e["discs_out_at_1s"]["mean"] == np.mean([m["discs_out_at_1s"] for m in members])
    assert e["jam_fraction"]["of"] == 2
    assert e["jam_fraction"]["value"] == sum(1 for m in members if m["jams"] > 0) / 2
    assert sum(e["pattern"].values()) == 2

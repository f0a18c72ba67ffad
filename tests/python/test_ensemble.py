"""`dem ensemble`: members differ by a seeded perturbation; statistics are those of the members."""
import json
import math
import re
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "reference_inputs" / "scenes" / "discharge_17_18.toml"


def short_scene(tmp_path):
    head, tail = SCENE.read_text().split("[discharge]")
    tail = re.sub(r"(?m)^time = .*$", "time = 0.4", tail, count=1)
    path = tmp_path / "short.toml"
    path.write_text(head + "[discharge]" + tail)
    return path


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


def test_ensemble_refuses_a_perturbation_that_overlaps(tmp_path, run_dem):
    proc = run_dem("ensemble", SCENE, "--out", tmp_path / "o", "--members", 2, "--perturb", 0.01)
    assert proc.returncode == 2
    assert "perturb" in proc.stderr and "overlap" in proc.stderr
    assert not (tmp_path / "o").exists()

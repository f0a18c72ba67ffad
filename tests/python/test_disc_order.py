"""A fill listed in a random order (a user's file in any order): the engine puts the discs in
cell order (integrator.disc_order = "auto"), yet every output lists them in the user's order (by
id), every thread count gives the same bytes, and the run is the one of the order as given to
round-off. The 10k silo's lattice, written as a file fill in a seeded random order, filled for
0.05 s and discharged for 0.1 s."""
import csv
import importlib.util
import json
import random
import subprocess
from pathlib import Path

import numpy as np
import pytest

from dem.compare.io import scene_toml

REPO = Path(__file__).resolve().parents[2]
BASE = REPO / "reference_inputs" / "scenes" / "bench_silo_10k.toml"

_spec = importlib.util.spec_from_file_location("output_digest", REPO / "scripts" / "output_digest.py")
output_digest = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(output_digest)


def digests(run_dir: Path) -> dict:
    files = sorted(p for p in run_dir.rglob("*") if p.is_file()
                   and p.suffix not in output_digest.SKIP_SUFFIX and p.name not in output_digest.SKIP_NAMES)
    return {str(p.relative_to(run_dir)): output_digest.digest(p) for p in files}


@pytest.fixture(scope="module")
def scene(tmp_path_factory, dem_binary):
    tmp = tmp_path_factory.mktemp("disc_order")
    r = subprocess.run([str(dem_binary), "resolve", str(BASE)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    discs = json.loads(r.stdout)["discs"]  # [x, y, r, material index], the lattice's order
    rows = [(x, y, rad) for x, y, rad, _ in discs]
    random.Random(5).shuffle(rows)
    with open(tmp / "shuffled.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["x", "y", "r"])
        w.writerows([repr(v) for v in row] for row in rows)
    doc = scene_toml.load(BASE)
    remove = [t for t in ("fill", "discharge", "end") if t in doc]
    out = scene_toml.edit(BASE, None, tmp / "silo_10k_shuffled.toml", remove=remove, add={
        "fill": {"type": "file", "file": "shuffled.csv", "material": "sand"},
        "end": {"time": 0.05, "stop_at_rest": False},
        "discharge": {"time": 0.1, "gate": "gate", "outlet_depth": 4.0, "jam_time": 1.0,
                      "series_interval": 0.02, "peak_window": 0.02, "snapshots": [0.05]}})
    fill = scene_toml.edit(out, None, tmp / "silo_10k_shuffled_fill.toml", remove=["discharge"])
    return out, rows, fill


def read_csv(path: Path) -> list[dict]:
    with open(path) as f:
        return list(csv.DictReader(f))


def test_outputs_in_user_order_same_bytes_at_any_thread_count(scene, run_dem, tmp_path):
    path, rows, _ = scene
    runs = {}
    for threads in (1, 2):
        out = tmp_path / f"t{threads}"
        p = run_dem("run", path, "--out", out, "--quiet", "--threads", threads, timeout=900)
        assert p.returncode == 0, p.stderr
        runs[threads] = digests(out)
        s = json.loads((out / "summary.json").read_text())
        assert s["disc_resorts"] >= 1 and s["options"]["disc_order"] == "auto"
    differ = sorted(f for f in runs[1].keys() | runs[2].keys() if runs[1].get(f) != runs[2].get(f))
    assert not differ, differ
    out = tmp_path / "t1"
    discs = read_csv(out / "discs.csv")
    ids = [int(d["id"]) for d in discs]
    assert ids == sorted(ids) and len(set(ids)) == len(ids), "discs.csv in increasing id order"
    assert len(ids) < len(rows), "the discharge removed discs"
    assert all(float(d["r"]) == rows[int(d["id"])][2] for d in discs), "id k is the file's row k"
    removals = read_csv(out / "removals.csv")
    by_t = {}
    for r in removals:
        by_t.setdefault(r["t"], []).append(int(r["id"]))
    assert removals and all(v == sorted(v) for v in by_t.values()), "a step's removals in id order"
    contacts = read_csv(out / "contacts.csv")
    dd = [(int(c["i"]), int(c["j"])) for c in contacts if c["kind"] == "dd"]
    assert dd and all(i < j for i, j in dd) and dd == sorted(dd), "pairs by (id_i, id_j), id_i < id_j"
    walls = [int(c["i"]) for c in contacts if c["kind"] in ("dw", "dp")]
    assert walls == sorted(walls)


def test_off_keeps_the_order_and_agrees_to_round_off(scene, run_dem, tmp_path):
    """The fill alone (0.05 s: the lattice closes its gaps, contacts form): the re-sorted run and
    the run in the given order agree to round-off (only the order of each disc's force terms
    differs). 1e-9 cm on discs of 1 cm: far below any effect of a lost or misplaced history."""
    _, _, path = scene
    res = {}
    for mode in ("auto", "off"):
        out = tmp_path / mode
        p = run_dem("run", path, "--out", out, "--quiet", "--set", f"integrator.disc_order={mode}", timeout=900)
        assert p.returncode == 0, p.stderr
        res[mode] = read_csv(out / "discs.csv")
        s = json.loads((out / "summary.json").read_text())
        assert (s["disc_resorts"] >= 1) == (mode == "auto")
    a, b = res["auto"], res["off"]
    assert [d["id"] for d in a] == [d["id"] for d in b]
    worst = max(max(abs(float(p["x"]) - float(q["x"])), abs(float(p["y"]) - float(q["y"]))) for p, q in zip(a, b))
    assert worst < 1e-9, worst


def test_module_arrays_in_user_order(scene, dem_module):
    """The Python module lists the discs by id once the engine has re-sorted them: the arrays
    are the file's rows (radii in the file's order), ids 0..N-1 in order."""
    _, rows, fill = scene
    sim = dem_module.Simulation(dem_module.Scene(str(fill)))
    sim.step(300)  # the lattice's gaps close: contacts, and the check at step 256 re-sorts
    ids = np.asarray(sim.ids)
    assert list(ids) == list(range(len(rows)))
    assert np.array_equal(np.asarray(sim.radii), np.array([r[2] for r in rows]))
    assert np.array_equal(np.asarray(sim.positions)[:, 0], np.asarray(sim.x))

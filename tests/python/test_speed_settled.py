"""The speed study's settled start (benchmarks/speed.py --start settled): the 10k lattice
silo settled by the engine becomes a scene that starts every code from the packing at rest. The
scene keeps the silo and the disc count, the packing touches (about two contacts a disc, against
none in the lattice), and the native comparison case accepts its overlaps. A few seconds."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

REPO_ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO_ROOT / "benchmarks"))
import speed  # noqa: E402


def resolved(dem, scene):
    p = subprocess.run([str(dem), "resolve", str(scene)], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


def contacts_per_disc(discs):
    """Touching disc pairs per disc, by brute force over a coarse grid (independent of the engine)."""
    xy, r = discs[:, :2], discs[:, 2]
    cell = 2 * r.max()
    keys = np.floor(xy / cell).astype(int)
    grid = {}
    for n, k in enumerate(map(tuple, keys)):
        grid.setdefault(k, []).append(n)
    touching = 0
    for n, (kx, ky) in enumerate(map(tuple, keys)):
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for m in grid.get((kx + dx, ky + dy), ()):
                    if m > n and np.hypot(*(xy[m] - xy[n])) <= r[m] + r[n]:
                        touching += 1
    return touching / len(discs)


def test_settled_scene_starts_from_a_resting_packing(dem_binary, tmp_path):
    base = REPO_ROOT / "reference_inputs" / "scenes" / "bench_silo_10k.toml"
    scene = speed.settled_scene(base, str(dem_binary), tmp_path)
    lattice, settled = resolved(dem_binary, base), resolved(dem_binary, scene)
    assert settled["walls"] == lattice["walls"]
    assert len(settled["discs"]) == len(lattice["discs"])
    assert settled["fill"]["max_initial_overlap"] == 0.3
    d0, d1 = np.array(lattice["discs"], float), np.array(settled["discs"], float)
    assert contacts_per_disc(d0) == 0.0          # the lattice's gaps
    assert 1.5 < contacts_per_disc(d1) < 3.0     # a resting packing: two supports a disc, some neighbours
    # It rested: every disc has sunk (the gaps closed), none by more than the lattice's height.
    drop = d0[:, 1] - d1[:, 1]
    assert drop.min() > -0.01 and drop.max() < 5.0
    # Made once: a second call reuses the packing.
    stamp = (tmp_path / "bench_silo_10k_settled" / "discs.csv").stat().st_mtime_ns
    assert speed.settled_scene(base, str(dem_binary), tmp_path) == scene
    assert (tmp_path / "bench_silo_10k_settled" / "discs.csv").stat().st_mtime_ns == stamp
    # The native comparison case keeps the scene's allowance (the frozen default is 0.05 r).
    from dem.compare.codes import native_backend
    from dem.compare.verdict import study
    phased = speed.scene_with_phases(scene, 20, 20, 5e-5, tmp_path / "phased.toml")  # as the study times it
    case = study.discharge_case(phased, 5e-5, 1e-3, 1e-3, 0, 0.0)
    text = native_backend.write_inputs(case, tmp_path / "case").read_text()
    assert "max_initial_overlap = 0.3" in text


def test_shuffled_scene_lists_the_settled_packing_in_a_random_order(dem_binary, tmp_path):
    """--start shuffled: the same discs and walls as the settled scene, in another order."""
    base = REPO_ROOT / "reference_inputs" / "scenes" / "bench_silo_10k.toml"
    settled = speed.settled_scene(base, str(dem_binary), tmp_path)
    shuffled = speed.shuffled_scene(settled, tmp_path)
    a, b = resolved(dem_binary, settled), resolved(dem_binary, shuffled)
    assert a["walls"] == b["walls"]
    assert a["discs"] != b["discs"]
    assert sorted(map(tuple, a["discs"])) == sorted(map(tuple, b["discs"]))
    # Most discs moved: a random order, not a rotation of a few.
    moved = sum(p != q for p, q in zip(a["discs"], b["discs"]))
    assert moved > 0.99 * len(a["discs"])

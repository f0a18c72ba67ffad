"""Paper 2's simple shear test through the CLI: a small box (12 cm x 6 cm) with and without
clusters, sheared a little; outputs, the plane stresses against the plate and walls, the
validation of the new scene tables, and the figures. The full study is scripts/shear_study.sh."""
import csv
import importlib.util
import json
import math
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from dem.compare.io import scene_toml

REPO = Path(__file__).resolve().parents[2]


def generator():
    spec = importlib.util.spec_from_file_location("make_shear_scenes", REPO / "scripts" / "make_shear_scenes.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def small_scene(variant, alpha=50, max_strain=0.02):
    gen = generator()
    gen.WIDTH, gen.HEIGHT = 12.0, 6.0
    doc = scene_toml.loads(gen.scene_text(alpha, variant))
    return scene_toml.dumps(scene_toml.with_changes(doc, {"shear.max_strain": max_strain,
                                                          "shear.snapshots": [0.0, max_strain],
                                                          "output.progress": False}))


def test_committed_scenes_are_up_to_date():
    assert generator().main(["--check"]) == 0


def test_generated_arrangement_has_the_papers_angles():
    gen = generator()
    for alpha in gen.ALPHAS:
        pattern, s, p, h, built, rows, xy, row_of = gen.discs(alpha)
        assert abs(built - alpha) < 1.0
        # diagonal neighbours one gap apart, row neighbours apart, all inside the box
        d = 2 * gen.RADIUS + gen.GAP
        assert math.isclose(math.hypot(p / 2, h), d, rel_tol=1e-12)
        assert p > 2 * gen.RADIUS
        xs = [x for x, _ in xy]
        assert min(xs) >= gen.RADIUS and max(xs) <= gen.WIDTH - gen.RADIUS + 1e-9
    # alpha = 58: 12 rows, hence 11 inter-row planes, as the paper's Fig. 5
    assert gen.discs(58)[5] == 12
    members = gen.clusters(gen.discs(58)[7])
    assert all(len(m) == 3 for m in members)
    assert len({i for m in members for i in m}) == 3 * len(members)


@pytest.fixture(scope="module")
def small_runs(tmp_path_factory, dem_binary):
    base = tmp_path_factory.mktemp("shear")
    runs = {}
    for variant in ("free", "clusters"):
        scene = base / f"{variant}.toml"
        scene.write_text(small_scene(variant))
        out = base / variant
        proc = subprocess.run([str(dem_binary), "run", str(scene), "--out", str(out), "--quiet"],
                              capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0, proc.stderr
        runs[variant] = out
    return runs


def read_rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_shear_outputs(small_runs):
    for variant, out in small_runs.items():
        summary = json.loads((out / "summary.json").read_text())
        assert summary["status"] == "sheared"
        sh = summary["shear"]
        assert sh["planes"] == sh["rows"] - 1 >= 2
        assert sh["strain_final"] >= 0.02 - 1e-9
        assert sh["samples"] == len(read_rows(out / "shear_series.csv"))
        assert (sh["bonds"] > 0) == (variant == "clusters")
        index = json.loads((out / "snapshots" / "index.json").read_text())["snapshots"]
        assert [round(s["strain_wanted"], 6) for s in index] == [0.0, 0.02]
        for s in index:
            assert (out / "snapshots" / s["contacts"]).is_file()
            assert any(w["name"] == "plate" for w in s["walls"])
        kinds = {r["kind"] for r in read_rows(out / "contacts.csv")}
        assert ("db" in kinds) == (variant == "clusters")


def test_engine_cluster_bound_is_the_python_one(small_runs, dem_binary):
    """The engine's time-step bound of the clusters (C++, Eigen) against dem.compare.cases.shear_stability
    (numpy), two codes written apart from the same model: each distinct cluster with its bonds
    and its neighbours within 0.01 cm held, every contact sticking."""
    from dem.compare.cases import shear_stability
    for variant, out in small_runs.items():
        stab = json.loads((out / "summary.json").read_text())["stability"]
        if variant != "clusters":
            assert stab["dt_clusters"] is None and stab["cluster_shapes"] == 0
            continue
        scene = out.parent / f"{variant}.toml"
        python = shear_stability.scene_bounds(shear_stability.resolve(scene, dem_binary))
        assert stab["dt_clusters"] == pytest.approx(python["paper_eq19"], rel=1e-5)
        assert stab["dt_bound"] <= stab["dt_clusters"]


def test_dem_resolve_gives_the_bounds_a_run_enforces_for_every_scheme(small_runs, dem_binary):
    """`dem resolve --stability`: the bounds of the run's summary.json (the comparison layer reads
    them there, never derives them again), and the clusters' bound for each scheme, which the
    numpy version (dem.compare.cases.shear_stability) gives too."""
    from dem.compare.cases import common, shear, shear_stability
    for variant, out in small_runs.items():
        scene = out.parent / f"{variant}.toml"
        stab = common.stability(scene, dem=dem_binary)
        run = json.loads((out / "summary.json").read_text())["stability"]
        assert {k: v for k, v in stab.items() if k != "dt_clusters_by_scheme"} == run
        by = stab["dt_clusters_by_scheme"]
        if variant != "clusters":
            assert by == {"paper_eq18": None, "paper_eq19": None, "velocity_verlet": None}
            continue
        python = shear_stability.scene_bounds(shear_stability.resolve(scene, dem_binary))
        for scheme in ("paper_eq18", "paper_eq19", "velocity_verlet"):
            assert by[scheme] == pytest.approx(python[scheme], rel=1e-5), scheme
        # the shared scheme's bound, with the shared law, is the one a velocity Verlet run enforces
        vv = common.stability(scene, {"integrator.scheme": "velocity_verlet"}, dem_binary)
        assert vv["dt_clusters"] == by["velocity_verlet"] and shear.shared_bound(scene) <= vv["dt_clusters"]
    bad = subprocess.run([str(dem_binary), "resolve", str(small_runs["free"].parent / "free.toml"), "--stability",
                          "--set", "integrator.dt=1e-3"], capture_output=True, text=True)
    assert bad.returncode == 0 and json.loads(bad.stdout)["stability"]["dt_bound"] < 1e-3   # reported, not refused


def without_shear(scene, out):
    """The same box, compressed only: the scene less its [shear] table, written to out."""
    return scene_toml.edit(scene, None, out, remove=["shear"])


def dem(binary, *args):
    import subprocess
    proc = subprocess.run([str(binary), *map(str, args), "--quiet"], capture_output=True, text=True,
                          timeout=120)
    return proc


def test_shear_from_a_saved_compression_is_the_run_in_one_piece(small_runs, dem_binary, tmp_path):
    """Compress once and save (bonds, plate, walls in the state file), then shear from the state:
    the same bits as compressing and shearing in one run. Split again inside the shear (walls
    turned, plate moving): the second part's samples are the one-piece run's from there on."""
    one = small_runs["clusters"]
    scene = one.parent / "clusters.toml"
    comp = without_shear(scene, tmp_path / "compress.toml")
    proc = dem(dem_binary, "run", comp, "--out", tmp_path / "comp", "--save-state", tmp_path / "sample.bin")
    assert proc.returncode == 0, proc.stderr
    proc = dem(dem_binary, "run", scene, "--out", tmp_path / "two", "--from", tmp_path / "sample.bin")
    assert proc.returncode == 0, proc.stderr
    for name in ("shear_series.csv", "shear_planes.csv", "snapshots/contacts_01.csv", "snapshots/discs_01.csv",
                 "contacts.csv"):
        assert (tmp_path / "two" / name).read_bytes() == (one / name).read_bytes(), name

    half = scene_toml.edit(scene, {"shear.max_strain": 0.01}, tmp_path / "half.toml")
    proc = dem(dem_binary, "run", half, "--out", tmp_path / "half", "--save-state", tmp_path / "half.bin")
    assert proc.returncode == 0, proc.stderr
    proc = dem(dem_binary, "run", scene, "--out", tmp_path / "rest", "--from", tmp_path / "half.bin")
    assert proc.returncode == 0, proc.stderr
    whole = read_rows(one / "shear_series.csv")
    first = read_rows(tmp_path / "half" / "shear_series.csv")
    rest = read_rows(tmp_path / "rest" / "shear_series.csv")
    assert len(first) == 11 and len(rest) == 10  # samples every 0.001 to 0.01, then on to 0.02
    no_t = [{k: v for k, v in r.items() if k != "t"} for r in first + rest]  # t counts from each part's start
    assert no_t == [{k: v for k, v in r.items() if k != "t"} for r in whole]
    assert (tmp_path / "rest" / "snapshots" / "contacts_01.csv").read_bytes() == \
        (one / "snapshots" / "contacts_01.csv").read_bytes()
    assert not (tmp_path / "rest" / "snapshots" / "contacts_00.csv").exists()  # strain 0 lies behind


def test_a_state_fits_only_its_own_box_and_clusters(small_runs, dem_binary, tmp_path):
    free = small_runs["free"].parent / "free.toml"
    clusters = small_runs["clusters"].parent / "clusters.toml"
    comp = without_shear(free, tmp_path / "free_compress.toml")
    proc = dem(dem_binary, "run", comp, "--out", tmp_path / "comp", "--save-state", tmp_path / "free.bin")
    assert proc.returncode == 0, proc.stderr
    cases = [
        (clusters, "another number of cluster bonds"),
        (free.parent / "wider.toml", "another plate"),
        (free.parent / "follow.toml", "shear_box.plate_horizontal"),
    ]
    scene_toml.edit(free, {"shear_box.plate_volume": 1400.0}, free.parent / "wider.toml")
    scene_toml.edit(free, {"shear_box.plate_horizontal": "with_walls"}, free.parent / "follow.toml")
    for k, (scene, fragment) in enumerate(cases):
        proc = dem(dem_binary, "run", scene, "--out", tmp_path / f"o{k}", "--from", tmp_path / "free.bin")
        assert proc.returncode == 2, proc.stderr
        assert "free.bin" in proc.stderr and fragment in proc.stderr, proc.stderr
        assert not (tmp_path / f"o{k}").exists()
    import subprocess
    proc = subprocess.run([str(dem_binary), "ensemble", str(clusters), "--out", str(tmp_path / "ens"), "--members", "2",
                           "--quiet"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "a [shear] scene runs with dem run" in proc.stderr, proc.stderr
    assert not (tmp_path / "ens").exists()


def test_a_contact_inside_a_cluster_counts_once():
    """Three discs bonded 0-1 and 1-2 (as bonds = "touching" with a tolerance under 0.005 cm
    makes them), 0 and 2 first apart, then 0.005 cm apart below disc 1: the 0-2 block of the
    cluster's stiffness is zero, then that one contact's, -(kn n n^T + ks t t^T)."""
    from dem.compare.cases import shear_stability
    r, kn, ks = 1.0, 3.0e4, 1.0e4
    x2 = 2 * r * math.cos(math.radians(30))
    resolved = {
        "discs": [(0.0, 0.0, r, 0), (x2, r, r, 0), (2 * x2, 0.0, r, 0)],  # 0 and 2 apart: no contact
        "materials": [{"name": "sand", "density": 2.65}],
        "pairs": [{"materials": ["sand", "sand"], "kn": kn, "ks": ks, "eta_n": 0.0, "eta_s": 0.0}],
        "walls": [],
    }
    K, C, minv = shear_stability.cluster_system(resolved, [0, 1, 2], [(0, 1), (1, 2)])
    assert np.all(K[0:3, 6:9] == 0)
    gap = 0.005
    resolved["discs"][1:] = [((2 * r + gap) / 2, math.sqrt(4 * r * r - ((2 * r + gap) / 2) ** 2), r, 0),
                             (2 * r + gap, 0.0, r, 0)]
    K, C, minv = shear_stability.cluster_system(resolved, [0, 1, 2], [(0, 1), (1, 2)])
    n, t = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    assert np.allclose(K[0:2, 6:8], -(kn * np.outer(n, n) + ks * np.outer(t, t)), rtol=1e-12)
    assert K[2, 8] == pytest.approx(ks * r * r)  # both lever arms r: one shear spring


def test_plane_stresses_match_plate_and_walls(small_runs):
    """Each plane's sigma and tau equal the load of the part above (weight, plate, walls) up to
    its inertia; exactly (to roundoff) with the inertia. At the start sigma exceeds the plate
    load/b by at most the discs' weight/b."""
    for out in small_runs.values():
        summary = json.loads((out / "summary.json").read_text())
        sh = summary["shear"]
        for r in read_rows(out / "shear_planes.csv"):
            s, t = float(r["sigma"]), float(r["tau"])
            sc, tc = float(r["sigma_check"]), float(r["tau_check"])
            si, ti = float(r["sigma_inertia"]), float(r["tau_inertia"])
            assert s == pytest.approx(sc + si, rel=1e-9)
            assert t == pytest.approx(tc + ti, abs=1e-9 * abs(s))
        series = read_rows(out / "shear_series.csv")
        first = series[0]
        plate_load = sh["plate_weight"] / sh["width"]
        assert float(first["sigma_plate"]) == pytest.approx(plate_load, rel=1e-3)  # compressed at rest
        assert plate_load < float(first["sigma"]) < plate_load + sh["discs_weight"] / sh["width"]
        assert abs(float(first["tau"])) < 1e-2 * float(first["sigma"])
        assert sh["check_static_max_relative"] < 0.1


def test_bad_tables_are_refused(tmp_path, run_dem):
    base = small_scene("clusters")
    cases = [
        (base.replace("plate_volume = 1500.0", "plate_volume = 1500.0\nplate_colour = 1"), ["shear_box.plate_colour", "unknown key"]),
        (base.replace("rate = 0.05", "rate = -0.05"), ["shear.rate", "> 0"]),
        (base.replace('bonds = "all"', 'bonds = "some"'), ["clusters.bonds", "one of"]),
        (base.replace("members = [\n", "members = [\n  [0, 9999],\n"), ["clusters.members[0]", "9999", "out of range"]),
        (base.replace("members = [\n", "members = [\n  [0, 1],\n"), ["disc 0", "already in"]),
        (base.replace("members = [\n", "members = [\n  [3],\n"), ["members[0]", "2 to 1000"]),
        (re.sub(r"\[shear_box\]\n.*?(?=\n\[)", "", base, flags=re.S), ["[shear] needs a [shear_box]"]),
        (base.replace("[shear_box]", "[shear_boxx]"), ["shear_boxx: unknown key; did you mean `shear_box`?"]),
        (base + "\n[shear_boxx]\n", ["shear_boxx", "unknown key"]),
    ]
    for k, (text, fragments) in enumerate(cases):
        scene = tmp_path / f"bad{k}.toml"
        scene.write_text(text)
        proc = run_dem("run", scene, "--out", tmp_path / f"o{k}")
        assert proc.returncode == 2, proc.stderr
        for f in fragments:
            assert f in proc.stderr, (f, proc.stderr)
        assert not (tmp_path / f"o{k}").exists()


def test_touching_clusters_must_hold_together(tmp_path, run_dem):
    # discs 0 and 1 are row neighbours with a gap: not connected by touching pairs
    text = re.sub(r"members = \[\n.*?\n\]\n", "members = [[0, 1]]\n", small_scene("touching"), flags=re.S)
    scene = tmp_path / "t.toml"
    scene.write_text(text)
    proc = run_dem("run", scene, "--out", tmp_path / "o")
    assert proc.returncode == 2, proc.stderr
    assert "cluster 0" in proc.stderr and "not connected" in proc.stderr, proc.stderr


def test_shear_figures(small_runs, tmp_path):
    from dem.compare.figures import shear_figures as sf
    series = sf.read_series(str(small_runs["clusters"] / "shear_series.csv"))
    raw, at, windowed = sf.peak(series)
    assert np.isfinite(raw) and raw >= windowed
    png = sf.plot_ratio([("50", "free", sf.read_series(str(small_runs["free"] / "shear_series.csv"))),
                         ("50", "clusters", series)], str(tmp_path / "fig7.png"))
    assert Path(png).stat().st_size > 10000
    png = sf.plot_networks([(str(small_runs["clusters"]), 0, "compressed"), (str(small_runs["clusters"]), 1, "sheared")],
                           str(tmp_path / "net.png"))
    assert Path(png).stat().st_size > 10000


@pytest.mark.reference_codes
def test_yade_runs_the_same_small_box_with_unbreakable_bonds(tmp_path, dem_binary):
    """YADE (real binary) on the small clustered box: its bonds never break, the compressed
    state carries the same plate load as the engine's, and the files have the engine's columns."""
    import shutil
    if shutil.which("yade") is None:
        pytest.skip("yade is not installed")
    from dem.compare.codes import shear_yade
    scene = tmp_path / "clusters.toml"
    scene.write_text(small_scene("clusters", max_strain=0.005))
    summary = shear_yade.run(scene, tmp_path / "yade", "bonds", 5e-5, dem_binary, timeout=300)
    assert summary["status"] == "sheared" and summary["rest"]["reached"]
    sh = summary["shear"]
    case = json.loads((tmp_path / "yade" / "yade_case.json").read_text())
    assert sh["bonds"] == len(case["clusters"]["bonds"]) > 0
    rows = read_rows(tmp_path / "yade" / "shear_series.csv")
    first = rows[0]
    plate_load = sh["plate_weight"] / sh["width"]
    assert float(first["sigma_plate"]) == pytest.approx(plate_load, rel=2e-2)
    assert plate_load < float(first["sigma"]) < plate_load + sh["discs_weight"] / sh["width"]
    kinds = [r["kind"] for r in read_rows(tmp_path / "yade" / "snapshots" / "contacts_01.csv")]
    assert kinds.count("db") == sh["bonds"]  # every bond still there after the shear

"""dem.compare.io.run_dir, the one reader of a `dem run` directory: real runs (a fill, a discharge, a
shear) read with every key docs/outputs.md promises checked, the files agree with the summary,
and a missing or malformed file is an error that names it."""
import importlib.util
import json
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from dem.compare.io import scene_toml
from dem.compare.io.run_dir import (DISCHARGE_KEYS, FILES, SHEAR_KEYS, SUMMARY_KEYS, WALL_KEYS, RunDir, RunDirError,
                             read_csv)

REPO = Path(__file__).resolve().parents[2]
SCENES = REPO / "reference_inputs" / "scenes"
DOC = (REPO / "docs" / "outputs.md").read_text()


def dem_run(dem_binary, scene, out):
    p = subprocess.run([str(dem_binary), "run", str(scene), "--out", str(out), "--quiet"], capture_output=True,
                       text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return RunDir(out, strict=True)


@pytest.fixture(scope="module")
def runs(tmp_path_factory, dem_binary):
    """A fill (with the rotation angle), a short discharge and a small shear."""
    tmp = tmp_path_factory.mktemp("run_dir")
    fill = scene_toml.edit(SCENES / "silo_17_18.toml", {"end.time": 0.2}, tmp / "fill.toml",
                           add={"output.rotation_angle": True})
    discharge = scene_toml.edit(SCENES / "discharge_17_18.toml", {"discharge.time": 0.1,
                                                                   "discharge.snapshots": [0.0, 0.05]},
                                tmp / "discharge.toml")
    spec = importlib.util.spec_from_file_location("make_shear_scenes", REPO / "scripts" / "make_shear_scenes.py")
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    gen.WIDTH, gen.HEIGHT = 12.0, 6.0
    shear = tmp / "shear.toml"
    scene_toml.write(shear, scene_toml.with_changes(scene_toml.loads(gen.scene_text(50, "clusters")), {
        "shear.max_strain": 0.004, "shear.snapshots": [0.0, 0.004], "output.progress": False}))
    return {name: dem_run(dem_binary, scene, tmp / name)
            for name, scene in (("fill", fill), ("discharge", discharge), ("shear", shear))}


# --------------------------------------------------------------------------- the documented keys

def test_the_checked_keys_are_those_docs_outputs_md_promises():
    block = DOC[DOC.index("## summary.json\n```"):]
    block = block[:block.index("```\n", len("## summary.json\n```"))]
    documented = set(re.findall(r'"(\w+)":', block))
    for keys in (SUMMARY_KEYS, WALL_KEYS):
        assert set(keys) <= documented, set(keys) - documented
    discharge = DOC[DOC.index("## Discharge outputs"):DOC.index("Files:")]
    shear = DOC[DOC.index("- summary.json: `\"status\"`: `sheared`"):DOC.index("`compare/figures/shear_figures.py` draws")]
    for keys, text in ((DISCHARGE_KEYS, discharge), (SHEAR_KEYS, shear)):
        named = set(re.findall(r"`(\w+)`", text)) | set(re.findall(r"`(\w+)` \(and `_windowed`\)", text))
        named |= {k + "_windowed" for k in named}
        assert set(keys) <= named, set(keys) - named
    for name in FILES:
        assert f"`{name}`" in DOC or f"## {name}" in DOC, name


# --------------------------------------------------------------------------- real runs

def test_a_fill(runs):
    rd = runs["fill"]
    s = rd.summary
    assert set(SUMMARY_KEYS) <= set(s) and s["status"] in ("rest", "end_time")
    discs, contacts, profiles = rd.discs(), rd.contacts(), rd.profiles()
    assert len(discs["id"]) == s["n_discs"] == 350 and discs["id"].dtype.kind == "i"
    assert "phi" in discs and np.all(np.isfinite(discs["phi"]))        # output.rotation_angle's column
    assert set(contacts["kind"]) <= {"dd", "dw", "dp", "db"} and contacts["j"].dtype.kind == "U"
    for wall in s["walls"]:
        dw = (contacts["kind"] == "dw") & (contacts["j"] == wall["name"])
        assert contacts["f_n"][dw].sum() == pytest.approx(wall["normal_total"], rel=1e-12, abs=1e-9)
        rows = profiles["wall"] == wall["name"]
        assert profiles["contacts"][rows].sum() == wall["contacts"]
        assert profiles["normal"][rows].tolist() == wall["profile"]["normal"]
    assert not rd.is_discharge() and not rd.is_shear()


def test_a_discharge(runs):
    rd = runs["discharge"]
    s = rd.summary
    assert rd.is_discharge() and set(DISCHARGE_KEYS) <= set(s["discharge"])
    removals, flow = rd.removals(), rd.flow_series()
    assert len(removals["t"]) == s["discharge"]["removed"]
    assert set(removals["how"]) <= {"outlet", "keystone"}
    assert flow["removed"][-1] == s["discharge"]["removed"]
    assert np.isnan(flow["arch_crown_y"]).any() or np.isfinite(flow["arch_crown_y"]).all()
    wall, totals = rd.series("wall"), rd.series("wall_totals")
    assert set(wall["wall"]) <= {w["name"] for w in s["walls"]}
    assert set(np.unique(wall["t"])) == set(np.unique(totals["t"]))
    snaps = rd.discharge_snapshots()
    assert [round(x["t"], 9) for x in snaps] == [0.0, 0.05]
    first = rd.snapshot_csv(Path(snaps[0]["discs"]).relative_to(rd.path), ("id", "x", "y", "r", "dx", "dy"))
    assert np.all(first["dx"] == 0) and np.all(first["dy"] == 0)


def test_a_shear(runs):
    rd = runs["shear"]
    s = rd.summary
    assert rd.is_shear() and set(SHEAR_KEYS) <= set(s["shear"]) and s["status"] == "sheared"
    series, planes = rd.shear_series(), rd.shear_planes()
    assert len(series["strain"]) == s["shear"]["samples"]
    assert np.allclose(series["ratio"], series["tau"] / series["sigma"], rtol=1e-12, equal_nan=True)
    assert set(planes["plane"].astype(int)) == set(range(s["shear"]["planes"]))
    index = rd.shear_snapshots()
    assert len(index) == 2 and {"strain", "t", "discs", "contacts"} <= set(index[0])
    contacts = rd.snapshot_csv(Path("snapshots") / index[-1]["contacts"], ("kind", "i", "j", "f_n"))
    assert "db" in set(contacts["kind"])                                 # the clusters' bonds


@pytest.mark.parametrize("name,phases", [("fill", ["fill"]), ("discharge", ["fill", "discharge"]),
                                         ("shear", ["fill", "shear"])])
def test_thermo_in_every_phase(runs, name, phases):
    """thermo.csv: rows of every phase in order, the last one the run's end; the wall groups'
    normal totals of the last row are the summary's."""
    rd = runs[name]
    th, s = rd.thermo(), rd.summary
    assert list(dict.fromkeys(th["phase"])) == phases
    assert th["step"][-1] == s["steps"] and th["t"][-1] == s["time"] and th["discs"][-1] == s["n_discs"]
    assert np.all(np.diff(th["step"]) >= 0) and np.all(th["kinetic_energy"] >= 0)
    for group, g in s["groups"].items():
        if f"{group}_normal" in th:
            assert th[f"{group}_normal"][-1] == pytest.approx(g["normal_total"], rel=1e-9, abs=1e-9)


# --------------------------------------------------------------------------- errors

def copy_run(rd, to):
    to.mkdir()
    for f in rd.path.iterdir():
        if f.is_file():
            (to / f.name).write_bytes(f.read_bytes())
    return to


def test_missing_files_and_keys_are_named(runs, tmp_path):
    run = copy_run(runs["fill"], tmp_path / "run")
    (run / "contacts.csv").unlink()
    with pytest.raises(RunDirError, match=r"contacts.csv: file is missing") as e:
        RunDir(run).contacts()
    assert e.value.path == str(run / "contacts.csv")
    s = json.loads((run / "summary.json").read_text())
    del s["balance"]
    del s["walls"][0]["profile"]
    (run / "summary.json").write_text(json.dumps(s))
    assert RunDir(run).summary["n_discs"] == 350                      # not strict: what the figures need
    with pytest.raises(RunDirError, match=r"summary.json: the summary has no 'balance'"):
        RunDir(run, strict=True).summary
    s["balance"] = {}
    (run / "summary.json").write_text(json.dumps(s))
    with pytest.raises(RunDirError, match=r"'balance' has no 'weight', 'walls_vertical', 'residual_relative'"):
        RunDir(run, strict=True).summary
    (run / "summary.json").write_text("{broken")
    with pytest.raises(RunDirError, match=r"summary.json: not valid JSON"):
        RunDir(run).summary
    (run / "summary.json").write_text(json.dumps({"disc_weight": -1, "walls": []}))
    with pytest.raises(RunDirError, match=r"'disc_weight' must be a number >= 0, found -1"):
        RunDir(run).summary
    (run / "summary.json").unlink()
    with pytest.raises(RunDirError, match=r"summary.json: file is missing"):
        RunDir(run).summary


def test_malformed_csv_lines_are_named(runs, tmp_path):
    run = copy_run(runs["fill"], tmp_path / "run")
    text = (run / "wall_profiles.csv").read_text().splitlines()
    (run / "wall_profiles.csv").write_text("\n".join(text + [text[1].replace(",", ",x,", 1)]) + "\n")
    with pytest.raises(RunDirError, match=rf"wall_profiles.csv: line {len(text) + 1}: expected 11 fields"):
        RunDir(run).profiles()
    (run / "discs.csv").write_text("id,x,y\n0,1,2\n")
    with pytest.raises(RunDirError, match=r"discs.csv: line 1: the header id,x,y has no column 'r', 'vx'"):
        RunDir(run).discs()
    (run / "flow_series.csv").write_text(",".join(FILES["flow_series.csv"]) + "\n0,1,2,3,4,5,6,7,8,,\n")
    assert np.isnan(RunDir(run).flow_series()["arch_discs"][0])      # no arch: empty cells
    with pytest.raises(RunDirError, match=r"column 'arch_discs' is not a number"):
        read_csv(run / "flow_series.csv", FILES["flow_series.csv"])


def test_columns_are_read_by_their_header(tmp_path):
    (tmp_path / "a.csv").write_text("y,x,extra\n2,1,9\n")
    got = read_csv(tmp_path / "a.csv", ("x", "y"))
    assert {k: v.tolist() for k, v in got.items()} == {"x": [1.0], "y": [2.0]}
    assert read_csv(tmp_path / "a.csv", ("x", "y"), extra=True)["extra"].tolist() == [9.0]
    (tmp_path / "b.csv").write_text("1,2\n")                           # no header: the columns in order
    assert read_csv(tmp_path / "b.csv", ("x", "y"))["y"].tolist() == [2.0]


def test_plain_files_read_as_csv_reader_reads_them(tmp_path, monkeypatch):
    """A plain file (no quotes, no whitespace but line feeds) is split on commas without csv.reader:
    the same arrays, dtypes and messages as the file with spaces (read by csv.reader and strip)."""
    columns = ("t", "wall", "bin", "normal")
    plain = "t,wall,bin,normal\n0,left,0,1.5\n\n0.005,right,3,-2e-3\n0.01,bottom_a,12,\n"
    spaced = plain.replace(",", ", ")
    for name, text in (("plain.csv", plain), ("spaced.csv", spaced)):
        (tmp_path / name).write_text(text)
    a = read_csv(tmp_path / "plain.csv", columns, empty=float("nan"))
    b = read_csv(tmp_path / "spaced.csv", columns, empty=float("nan"))
    assert a["wall"].tolist() == ["left", "right", "bottom_a"] and a["bin"].tolist() == [0, 3, 12]
    import dem.compare.io.run_dir
    monkeypatch.setattr(dem.compare.io.run_dir, "PLAIN_MAX_BYTES", 10)          # the plain file by csv.reader
    c = read_csv(tmp_path / "plain.csv", columns, empty=float("nan"))
    for k in columns:
        assert a[k].dtype == b[k].dtype == c[k].dtype, k
        np.testing.assert_array_equal(a[k], b[k])
        np.testing.assert_array_equal(a[k], c[k])
    monkeypatch.undo()
    # A short row: the same line number (the empty line counted) both ways.
    for name, text in (("plain.csv", plain), ("spaced.csv", spaced)):
        (tmp_path / name).write_text(text + ("1,left,2\n" if name == "plain.csv" else "1, left, 2\n"))
        with pytest.raises(RunDirError, match=rf"{name}: line 6: expected 4 fields"):
            read_csv(tmp_path / name, columns, empty=float("nan"))


def test_numbers_read_by_numpy_are_those_of_float_and_int(tmp_path, monkeypatch):
    """A plain file's numbers go through np.loadtxt: the same doubles as Python's float() (random
    bit patterns written as repr and as %.17g, subnormals, infinities and NaN among them), the same
    ints as int(), and an integer column holding 1.0 still refused with read_csv's message."""
    rng = np.random.default_rng(7)
    bits = rng.integers(0, 2**63, size=4000, dtype=np.uint64) | (rng.integers(0, 2, 4000, dtype=np.uint64) << 63)
    values = [float(v) for v in bits.view(np.float64)] + [5e-324, -0.0, 1e308, float("inf")]
    lines = ["t,wall,bin,normal"]
    for k, v in enumerate(values):
        lines.append(f"{v!r},w{k % 7},{k - 2000},{'%.17g' % v}")
    (tmp_path / "a.csv").write_text("\n".join(lines) + "\n")
    columns = ("t", "wall", "bin", "normal")
    import dem.compare.io.run_dir
    fast = read_csv(tmp_path / "a.csv", columns)
    monkeypatch.setattr(dem.compare.io.run_dir, "PLAIN_MAX_BYTES", 10)        # csv.reader, float(), int()
    slow = read_csv(tmp_path / "a.csv", columns)
    monkeypatch.undo()
    for k in columns:
        assert fast[k].dtype == slow[k].dtype, k
        np.testing.assert_array_equal(fast[k], slow[k])
    assert fast["t"].view(np.uint64).tolist() == slow["t"].view(np.uint64).tolist()     # the bits, NaNs too
    assert fast["normal"].view(np.uint64).tolist() == fast["t"].view(np.uint64).tolist()
    (tmp_path / "b.csv").write_text("t,wall,bin,normal\n0,left,1.0,2\n")
    with pytest.raises(RunDirError, match=r"line 2: column 'bin' is not a number: '1.0'"):
        read_csv(tmp_path / "b.csv", columns)

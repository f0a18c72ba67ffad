"""A real run of the paper's 17/18 fill: output files parse (json, csv, meshio) and agree."""
import csv
import json
import math
from pathlib import Path

import meshio
import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "reference_inputs" / "scenes" / "silo_17_18.toml"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory, dem_binary):
    import subprocess
    out = tmp_path_factory.mktemp("silo") / "run"
    proc = subprocess.run([str(dem_binary), "run", str(SCENE), "--out", str(out)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "zeta_n" in proc.stdout and "stability bound" in proc.stdout  # the run header
    return out


def test_summary(run_dir):
    s = json.loads((run_dir / "summary.json").read_text())
    assert s["status"] == "rest" and s["rest"]["reached"]
    assert s["n_discs"] == 350
    # Paper's note 3: the threshold is 1e-4 g dt^2.
    assert s["rest"]["threshold"] == pytest.approx(1e-4 * 980 * 1e-4 ** 2)
    assert s["particle_steps_per_s"] > 0 and s["steps"] > 0
    m = 2.65 * math.pi
    assert s["disc_weight"] == pytest.approx(m * 980)
    assert s["weight"] == pytest.approx(350 * m * 980)
    assert s["balance"]["residual_relative"] < 1e-3
    names = {w["name"] for w in s["walls"]}
    assert names == {"left", "right", "bottom_left", "gate", "bottom_right"}
    dd = next(p for p in s["derived"] if p["kind"] == "disc-disc")
    # Table 2: eta_n = 15.3 rho g against m* = m/2 gives zeta = 1.0015 (reference-codes.md).
    assert dd["zeta_n"] == pytest.approx(15.3 * 2.65 * 980 / (2 * math.sqrt(m / 2 * 3.64e4 * 2.65 * 980)))
    assert dd["dt_bound_eq26"] == pytest.approx(15.3 / 3.64e4)


def test_summary_derived_is_as_documented(run_dir):
    """docs/outputs.md's "derived" entry names exactly the keys each material pair's entry has."""
    import re
    doc = (REPO / "docs" / "outputs.md").read_text()
    block = doc[doc.index('"derived": ['):doc.index('"stability": {')]
    documented = set(re.findall(r'"(\w+)":', block)) - {"derived"}
    s = json.loads((run_dir / "summary.json").read_text())
    assert isinstance(s["derived"], list) and s["derived"]
    for entry in s["derived"]:
        assert set(entry) == documented, set(entry) ^ documented


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_csv_files_agree_with_summary(run_dir):
    s = json.loads((run_dir / "summary.json").read_text())
    discs = read_csv(run_dir / "discs.csv")
    assert len(discs) == s["n_discs"]
    contacts = read_csv(run_dir / "contacts.csv")
    for wall in s["walls"]:
        fn = sum(float(c["f_n"]) for c in contacts if c["kind"] == "dw" and c["j"] == wall["name"])
        assert fn == pytest.approx(wall["normal_total"], rel=1e-12, abs=1e-9)
    prof = read_csv(run_dir / "wall_profiles.csv")
    for wall in s["walls"]:
        rows = [r for r in prof if r["wall"] == wall["name"]]
        assert sum(float(r["normal"]) for r in rows) == pytest.approx(wall["normal_total"], rel=1e-12, abs=1e-9)
        assert sum(int(r["contacts"]) for r in rows) == wall["contacts"]


def test_vtu_files_read_with_meshio(run_dir):
    s = json.loads((run_dir / "summary.json").read_text())
    discs = meshio.read(run_dir / "discs.vtu")
    assert discs.points.shape == (s["n_discs"], 3)
    assert np.allclose(discs.point_data["radius"], 1.0)
    assert discs.point_data["velocity"].shape == (s["n_discs"], 3)
    contacts = meshio.read(run_dir / "contacts.vtu")
    lines = contacts.cells_dict["line"]
    n_csv = len(read_csv(run_dir / "contacts.csv"))
    assert lines.shape == (n_csv, 2)
    assert contacts.cell_data["f_n"][0].shape == (n_csv,)


def test_final_vtu_files_carry_forces_materials_contacts_and_walls(run_dir):
    """discs.vtu holds each disc's force (eq. 15's resultant, gravity in it), torque, material and
    contact count: at rest the forces are near zero beside the weight, every contact of
    contacts.csv counts for both its discs (one for a wall's); walls.vtu holds the scene's walls."""
    s = json.loads((run_dir / "summary.json").read_text())
    discs = meshio.read(run_dir / "discs.vtu")
    pd = discs.point_data
    weight = s["disc_weight"]
    assert pd["force"].shape == (s["n_discs"], 3) and np.abs(pd["force"][:, :2]).max() < 1e-2 * weight
    assert pd["torque"].shape == (s["n_discs"],) and set(np.unique(pd["material"])) == {0}
    rows = read_csv(run_dir / "contacts.csv")
    count = np.zeros(s["n_discs"], int)
    for r in rows:
        count[int(r["i"])] += 1
        if r["kind"] in ("dd", "db"):
            count[int(r["j"])] += 1
    ids = pd["id"].astype(int)
    assert np.array_equal(pd["contacts"][np.argsort(ids)], count)
    walls = meshio.read(run_dir / "walls.vtu")
    assert len(walls.cells_dict["line"]) == sum(1 for w in s["walls"] if w.get("active", True))


def test_rotation_angle_only_when_asked(run_dir, tmp_path, dem_binary):
    """output.rotation_angle adds a phi column (CSV and VTU) and changes nothing else."""
    import subprocess
    assert "phi" not in read_csv(run_dir / "discs.csv")[0]
    assert "phi" not in meshio.read(run_dir / "discs.vtu").point_data
    from dem.compare.io import scene_toml
    scene = scene_toml.edit(SCENE, None, tmp_path / "angle.toml", add={"output.rotation_angle": True})
    out = tmp_path / "run"
    proc = subprocess.run([str(dem_binary), "run", str(scene), "--out", str(out), "--quiet"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    plain, angle = read_csv(run_dir / "discs.csv"), read_csv(out / "discs.csv")
    assert len(plain) == len(angle)
    for a, b in zip(plain, angle):
        assert {k: v for k, v in b.items() if k != "phi"} == a  # same bits everywhere else
    phi = np.array([float(r["phi"]) for r in angle])
    assert np.all(np.isfinite(phi)) and np.abs(phi).max() > 1e-3  # the fill turns its discs
    assert np.allclose(meshio.read(out / "discs.vtu").point_data["phi"], phi)


def test_run_writes_data_and_python_draws_its_pictures(run_dir):
    """The engine draws nothing; dem.compare.figures run draws a run's pictures into its folder."""
    import subprocess
    import sys
    assert not list(run_dir.glob("*.png"))
    proc = subprocess.run([sys.executable, "-m", "dem.compare.figures", "run", str(run_dir)], cwd=REPO,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    for name in ("network.png", "side_walls.png"):
        assert (run_dir / name).stat().st_size > 10000


def test_no_temporary_files_left(run_dir):
    assert not list(run_dir.glob("*.tmp"))


def test_figures_from_a_real_run(run_dir, tmp_path):
    from dem.compare.figures import runs as figures
    net = tmp_path / "network.png"
    prof = tmp_path / "profiles.png"
    figures.plot_network(run_dir, net)
    figures.plot_side_profiles([run_dir], prof)
    for png in (net, prof):
        assert png.stat().st_size > 10000


@pytest.mark.parametrize("scheme", ["paper_eq18", "paper_eq19", "velocity_verlet"])
def test_contacts_are_written_where_their_forces_were_computed(tmp_path, dem_binary, scheme):
    """Mid-collision, every scheme: the disc-disc row's contact point and e_n are those of the
    positions its forces came from. Eqs. (18) and (19) compute the forces of a step and then move
    the discs: the positions at the end of the step before (a run one step shorter). Verlet
    computes them after its move: the positions of the run's own discs.csv."""
    import subprocess
    scene = REPO / "reference_inputs" / "agreement" / "calibration" / "head_on_disc_disc.toml"
    kn, dt, end = 94530800.0, 1e-5, 3e-4  # the scene's overlap spring and step; mid-contact

    def run(tag, t_end):
        out = tmp_path / tag
        proc = subprocess.run([str(dem_binary), "run", str(scene), "--out", str(out), "--quiet", "--scheme", scheme, "--end-time", repr(t_end)], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
        return out

    out = run("full", end)
    at = out if scheme == "velocity_verlet" else run("before", end - dt)
    x = [float(d["x"]) for d in read_csv(at / "discs.csv")]
    rows = [r for r in read_csv(out / "contacts.csv") if r["kind"] == "dd"]
    assert len(rows) == 1, "mid-collision: one touching pair"
    overlap = 2.0 - abs(x[1] - x[0])
    assert float(rows[0]["e_n"]) == pytest.approx(kn * overlap, rel=1e-9)
    assert float(rows[0]["x"]) == pytest.approx(0.5 * (x[0] + x[1]), abs=1e-12)


def test_no_vtu_writes_the_csv_files_alone(tmp_path, dem_binary):
    """`dem run --no-vtu` (output.vtu = "none"): no VTU file and no PVD index, every other file the
    same bytes as the run with them (summary.json but its timings and command), and the discharge
    snapshots listed with the .pvd's times in discharge_snapshots.csv. A run that still wrote a VTU
    file, or whose index had other times or names, fails this."""
    import subprocess
    from dem.compare.io.run_dir import RunDir
    scene = REPO / "reference_inputs" / "scenes" / "discharge_17_18.toml"
    runs = {}
    for name, extra in (("vtu", []), ("none", ["--no-vtu"])):
        runs[name] = tmp_path / name
        proc = subprocess.run([str(dem_binary), "run", str(scene), "--out", str(runs[name]), "--quiet", *extra],
                              capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
    files = {k: {p.relative_to(d) for p in d.rglob("*") if p.is_file()} for k, d in runs.items()}
    vtu_only = {p for p in files["vtu"] if p.suffix in (".vtu", ".pvd")}
    assert vtu_only and not {p for p in files["none"] if p.suffix in (".vtu", ".pvd")}
    assert files["none"] == files["vtu"] - vtu_only | {Path("discharge_snapshots.csv")}
    for p in files["vtu"] - vtu_only - {Path("summary.json"), Path("run.log")}:
        assert (runs["vtu"] / p).read_bytes() == (runs["none"] / p).read_bytes(), p
    with_pvd, with_csv = RunDir(runs["vtu"]).discharge_snapshots(), RunDir(runs["none"]).discharge_snapshots()
    assert len(with_pvd) == 10
    assert [s["t"] for s in with_csv] == [s["t"] for s in with_pvd]
    for a, b in zip(with_csv, with_pvd):
        assert Path(a["discs"]).relative_to(runs["none"]) == Path(b["discs"]).relative_to(runs["vtu"])
        assert Path(a["contacts"]).relative_to(runs["none"]) == Path(b["contacts"]).relative_to(runs["vtu"])

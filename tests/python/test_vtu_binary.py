"""Binary VTU files (output.vtu, docs/outputs.md): the same grid and data as the ASCII files, read
back by meshio and by ParaView's own reader (pvpython's XMLUnstructuredGridReader)."""
import shutil
import subprocess
from pathlib import Path

import meshio
import numpy as np
import pytest

from dem.compare.io import scene_toml

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "reference_inputs" / "scenes" / "silo_17_18.toml"
FILES = ("discs.vtu", "contacts.vtu", "snapshots/step_000000000_walls.vtu", "snapshots/step_000000400_contacts.vtu")


@pytest.fixture(scope="module")
def runs(tmp_path_factory, dem_binary):
    tmp = tmp_path_factory.mktemp("vtu")
    out = {}
    for fmt in ("ascii", "binary", "auto"):
        scene = scene_toml.edit(SCENE, {"end.time": 0.05}, tmp / f"{fmt}.toml",
                                add={"output.vtu": fmt, "output.snapshot_interval": 0.04})
        p = subprocess.run([str(dem_binary), "run", str(scene), "--out", str(tmp / fmt), "--quiet"],
                           capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        out[fmt] = tmp / fmt
    return out


def test_binary_files_are_binary_and_auto_is_ascii_below_10k_discs(runs):
    for name in FILES:
        head = (runs["binary"] / name).read_bytes()[:400]
        assert b'format="appended"' in head and b'header_type="UInt64"' in head, name
        assert b'compressor="vtkZLibDataCompressor"' in head  # the build links zlib (find_package)
        assert (runs["auto"] / name).read_bytes() == (runs["ascii"] / name).read_bytes(), name


@pytest.mark.parametrize("name", FILES)
def test_meshio_reads_the_same_grid_and_data(runs, name):
    a, b = meshio.read(runs["ascii"] / name), meshio.read(runs["binary"] / name)
    assert np.array_equal(a.points, b.points)
    assert [(c.type, c.data.tolist()) for c in a.cells] == [(c.type, c.data.tolist()) for c in b.cells]
    for data_a, data_b in ((a.point_data, b.point_data), (a.cell_data, b.cell_data)):
        assert set(data_a) == set(data_b)
        for key in data_a:
            assert np.array_equal(np.asarray(data_a[key]), np.asarray(data_b[key])), key


PVPYTHON = shutil.which("pvpython")


@pytest.mark.skipif(PVPYTHON is None, reason="ParaView's pvpython is not installed")
def test_paraview_reads_the_binary_files(runs, tmp_path):
    script = tmp_path / "read.py"
    script.write_text(
        "import sys\n"
        "from paraview.simple import XMLUnstructuredGridReader, servermanager\n"
        "for path in sys.argv[1:]:\n"
        "    r = XMLUnstructuredGridReader(FileName=[path])\n"
        "    r.UpdatePipeline()\n"
        "    d = servermanager.Fetch(r)\n"
        "    print(path, d.GetNumberOfPoints(), d.GetNumberOfCells())\n")
    names = [str(runs["binary"] / n) for n in FILES]
    p = subprocess.run([PVPYTHON, str(script), *names], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    counts = {line.split()[0]: (int(line.split()[1]), int(line.split()[2]))
              for line in p.stdout.splitlines() if line.startswith("/")}
    for n in names:
        mesh = meshio.read(n)
        assert counts[n] == (len(mesh.points), sum(len(c.data) for c in mesh.cells)), n
    assert counts[names[0]] == (350, 350)


@pytest.mark.skipif(PVPYTHON is None, reason="ParaView's pvpython is not installed")
def test_paraview_reads_the_runs_collection(runs, tmp_path):
    """snapshots.pvd: at each time a multiblock of the discs, the walls and the contacts."""
    script = tmp_path / "pvd.py"
    script.write_text(
        "import sys\n"
        "from paraview.simple import PVDReader, servermanager\n"
        "r = PVDReader(FileName=sys.argv[1])\n"
        "for t in r.TimestepValues:\n"
        "    r.UpdatePipeline(t)\n"
        "    d = servermanager.Fetch(r)\n"
        "    print('at', t, *[d.GetBlock(k).GetNumberOfCells() for k in range(d.GetNumberOfBlocks())])\n")
    p = subprocess.run([PVPYTHON, str(script), str(runs["binary"] / "snapshots.pvd")], capture_output=True,
                       text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    rows = [line.split()[1:] for line in p.stdout.splitlines() if line.startswith("at ")]
    contacts = len(meshio.read(runs["binary"] / "snapshots" / "step_000000400_contacts.vtu").cells[0].data)
    assert [(round(float(t), 9), int(d), int(w), int(c)) for t, d, w, c in rows] == [(0.0, 350, 5, 0),
                                                                                     (0.04, 350, 5, contacts)]

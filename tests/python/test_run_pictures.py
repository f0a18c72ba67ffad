"""A run's pictures: `python3 -m dem.compare.figures run DIR [--wait] [--quiet]` and `dem run --pictures`,
which starts that process with the run, on an engine run of the paper's 17/18 discharge."""
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image


REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "reference_inputs" / "scenes" / "discharge_17_18.toml"
PICTURES = ("network.png", "side_walls.png", "frames.png", "wall_ratios.png", "flow.png")


def draw(*args, cwd=REPO):
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, cwd=cwd, timeout=300)


@pytest.fixture(scope="module")
def run(tmp_path_factory, dem_binary):
    """The engine's run of the 17/18 fill and discharge (350 discs, 10 snapshots)."""
    out = tmp_path_factory.mktemp("pictures") / "run"
    p = subprocess.run([str(dem_binary), "run", str(SCENE), "--out", str(out), "--quiet"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return out


def copy_run(run, where):
    """A copy of the run's data, without pictures."""
    shutil.copytree(run, where, ignore=shutil.ignore_patterns("*.png", "*.tmp"))
    return where


# --------------------------------------------------------------------------- the five files


def test_five_pictures_written_and_decoded(run, tmp_path):
    """`python3 -m dem.compare.figures run DIR` writes the five files, listed on stdout, PNGs that PIL
    decodes and that are not blank (4 % of the pixels or more other than white, several colours)."""
    out = copy_run(run, tmp_path / "run")
    p = draw("-m", "dem.compare.figures", "run", str(out))
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == [str(out / name) for name in PICTURES]
    for name in PICTURES:
        image = Image.open(out / name)
        image.load()
        assert image.format == "PNG", name
        pixels = np.asarray(image.convert("RGB"))
        assert np.mean(np.any(pixels != 255, axis=-1)) > 0.04, name
        assert len(np.unique(pixels.reshape(-1, 3)[::97], axis=0)) > 20, name
    assert not list(out.glob("*.tmp"))


@pytest.mark.release_only  # Python's drawing, the engine's run shared with the tests below
def test_wait_draws_on_draw_and_nothing_otherwise(run, tmp_path):
    """--wait: the process reads one line on stdin; "draw" draws (--quiet: nothing listed), any
    other line or the end of stdin draws nothing and exits 0."""
    for line, drawn in (("draw\n", True), ("stop\n", False), ("", False)):
        out = copy_run(run, tmp_path / f"run_{line.strip() or 'eof'}")
        p = subprocess.run([sys.executable, "-m", "dem.compare.figures", "run", str(out), "--wait", "--quiet"],
                           input=line, capture_output=True, text=True, cwd=REPO, timeout=300)
        assert p.returncode == 0 and p.stdout == "", p.stderr
        assert sorted(x.name for x in out.glob("*.png")) == (sorted(PICTURES) if drawn else []), line


@pytest.mark.release_only  # the picture process also runs in the unstable run's test below
def test_dem_run_pictures_draws_the_same_files_after_the_run(run, tmp_path, dem_binary):
    """`dem run SCENE --out DIR --pictures`: the run's outputs, then the five pictures of
    `python3 -m dem.compare.figures run DIR`, byte for byte (the run is deterministic), the files named on
    stdout unless --quiet."""
    out = tmp_path / "both"
    p = subprocess.run([str(dem_binary), "run", str(SCENE), "--out", str(out), "--pictures", "--quiet"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert p.stdout == "", p.stdout
    reference = copy_run(run, tmp_path / "reference")
    p = draw("-m", "dem.compare.figures", "run", str(reference))
    assert p.returncode == 0, p.stderr
    for name in PICTURES:
        assert (out / name).read_bytes() == (reference / name).read_bytes(), name
    p = subprocess.run([str(dem_binary), "run", str(SCENE), "--out", str(out), "--pictures"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert [line for line in p.stdout.splitlines() if line.endswith(".png")] == [str(out / n) for n in PICTURES]
    assert "--pictures draws them next" in p.stdout


def test_dem_run_pictures_draws_nothing_for_an_unstable_run_and_says_when_they_fail(tmp_path, dem_binary):
    """An unstable run (eq. 18 on the discharge: exit 3) gets no pictures, and its picture process
    ends with it; a picture that cannot be written (a folder in its place) exits 4 naming the
    pictures, the run's outputs written; a bad scene exits 2 before anything starts."""
    out = tmp_path / "unstable"
    p = subprocess.run([str(dem_binary), "run", str(SCENE), "--out", str(out), "--pictures", "--quiet",
                        "--scheme", "paper_eq18", "--force-dt"], capture_output=True, text=True, timeout=300)
    assert p.returncode == 3, p.stderr
    assert (out / "discs.csv").exists() and not list(out.glob("*.png"))
    out = tmp_path / "blocked"
    (out / "flow.png").mkdir(parents=True)
    p = subprocess.run([str(dem_binary), "run", str(SCENE), "--out", str(out), "--pictures", "--quiet"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 4, p.stderr
    assert "dem run --pictures: the pictures were not drawn" in p.stderr and "flow.png" in p.stderr
    assert (out / "summary.json").exists()
    p = subprocess.run([str(dem_binary), "run", str(SCENE), "--out", str(tmp_path / "bad"), "--pictures",
                        "--set", "integrator.dt=-1"], capture_output=True, text=True, timeout=300)
    assert p.returncode == 2 and not (tmp_path / "bad").exists(), p.stderr


def test_a_missing_run_directory_is_named(tmp_path):
    p = draw("-m", "dem.compare.figures", "run", str(tmp_path / "nowhere"))
    assert p.returncode != 0
    assert str(tmp_path / "nowhere") in p.stderr
    assert "Traceback" not in p.stderr


@pytest.mark.parametrize("broken", ["summary.json missing", "wall_series.csv short line",
                                    "flow_series.csv column gone"])
def test_a_broken_run_names_the_file(run, tmp_path, broken):
    """A missing or malformed file stops the pictures with a message that names it (no
    traceback), exit status non-zero."""
    out = copy_run(run, tmp_path / "run")
    name = broken.split()[0]
    if broken == "summary.json missing":
        (out / name).unlink()
    elif broken == "wall_series.csv short line":
        lines = (out / name).read_text().splitlines()
        lines[5] = lines[5].rsplit(",", 1)[0]
        (out / name).write_text("\n".join(lines) + "\n")
    else:
        lines = (out / name).read_text().splitlines()
        (out / name).write_text("\n".join(",".join(line.split(",")[:-1]) for line in lines) + "\n")
    p = draw("-m", "dem.compare.figures", "run", str(out))
    assert p.returncode != 0
    assert f"{out / name}:" in p.stderr, p.stderr
    assert "Traceback" not in p.stderr, p.stderr
    assert not list(out.glob("*.tmp"))

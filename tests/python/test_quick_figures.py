"""Tests of compare.figures.quick_figures and compare.raster_plot: a run's five pictures drawn with PIL,
without matplotlib, on an engine run of the paper's 17/18 discharge."""
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from compare.figures import quick_figures, raster_plot as rp
from compare.figures.figure_data import DEAD_RADII, displacement_radii

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "reference_inputs" / "scenes" / "discharge_17_18.toml"
PICTURES = ("network.png", "side_walls.png", "frames.png", "wall_ratios.png", "flow.png")
# The pictures' sizes at 150 dpi, from compare.figures' layouts: network 7 in wide; side walls
# 11 x 7 in; frames 5 panels of 3.2 in + 1.3 in; wall ratios 11 in x (2.7 per strip (3) + 2.9);
# flow 12 x 8 in.
WIDTHS = {"network.png": 1050, "side_walls.png": 1650, "frames.png": 2595, "wall_ratios.png": 1650,
          "flow.png": 1800}
HEIGHTS = {"side_walls.png": 1050, "wall_ratios.png": 1650, "flow.png": 1200}


def draw(*args, cwd=REPO):
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, cwd=cwd, timeout=300)


@pytest.fixture(scope="module")
def run(tmp_path_factory, dem_binary):
    """The engine's run of the 17/18 fill and discharge (350 discs, 10 snapshots)."""
    out = tmp_path_factory.mktemp("quick") / "run"
    p = subprocess.run([str(dem_binary), "run", str(SCENE), "--out", str(out), "--quiet"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return out


def copy_run(run, where):
    """A copy of the run's data, without pictures."""
    shutil.copytree(run, where, ignore=shutil.ignore_patterns("*.png", "*.tmp"))
    return where


# --------------------------------------------------------------------------- the five files


def test_five_pictures_written_decoded_and_sized(run, tmp_path):
    """`python3 -m compare.figures.quick_figures run DIR` writes the five files of `compare.figures run`,
    PNGs that PIL decodes, of compare.figures' sizes, and not blank: each has 4 % of its pixels or
    more other than white and shows several colours."""
    out = copy_run(run, tmp_path / "run")
    p = draw("-m", "compare.figures.quick_figures", "run", str(out))
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == [str(out / name) for name in PICTURES]
    for name in PICTURES:
        image = Image.open(out / name)
        image.load()
        assert image.format == "PNG" and image.mode == "RGB", name
        assert image.size[0] == WIDTHS[name], (name, image.size)
        assert abs(image.size[1] - HEIGHTS.get(name, image.size[1])) <= 1, (name, image.size)
        assert 600 <= image.size[1] <= 2200, (name, image.size)
        pixels = np.asarray(image)
        assert np.mean(np.any(pixels != 255, axis=-1)) > 0.04, name
        assert len(np.unique(pixels.reshape(-1, 3)[::97], axis=0)) > 20, name
    assert not list(out.glob("*.tmp"))


def test_every_panel_shows_its_data(run, tmp_path):
    """Inside every axes box of the five pictures (their Figures' all_axes) at least 2 % of the
    pixels are neither white nor the grid's grey: no panel is left blank or painted over."""
    for name, fig in quick_figures.draw_run(str(run)).items():
        pixels = np.asarray(Image.open(fig.save(str(tmp_path / name)))).astype(int)
        for k, ax in enumerate(fig.all_axes):
            x0, y0, x1, y1 = ax.box
            inside = pixels[y0 + 3:y1 - 2, x0 + 3:x1 - 2]
            plain = np.all(inside == 255, axis=-1) | np.all(np.abs(inside - 223) <= 2, axis=-1)
            assert np.mean(~plain) > 0.02, (name, k, np.mean(~plain))


def test_compare_figures_renderer_pil_imports_no_matplotlib(run, tmp_path):
    """`compare.figures run DIR --renderer pil` writes the five files and never imports matplotlib
    (python -X importtime lists every module imported); the same check run on the default
    renderer sees matplotlib, so it can fail."""
    out = copy_run(run, tmp_path / "run")
    p = draw("-X", "importtime", "-m", "compare.figures", "run", str(out), "--renderer", "pil")
    assert p.returncode == 0, p.stderr[-2000:]
    imported = [line.rsplit("|", 1)[-1].strip() for line in p.stderr.splitlines() if "|" in line]
    assert "PIL.ImageDraw" in imported and "numpy" in imported
    assert not [m for m in imported if m.startswith("matplotlib")]
    for name in PICTURES:
        assert (out / name).stat().st_size > 0, name
    # the check itself: the default renderer imports matplotlib
    p = draw("-X", "importtime", "-m", "compare.figures", "run", str(out))
    assert p.returncode == 0, p.stderr[-2000:]
    assert [line for line in p.stderr.splitlines() if "| matplotlib" in line]


def test_a_run_without_contact_lists_gets_four_pictures(run, tmp_path):
    """A reference code's run (no contacts.csv, no contact snapshots): no network.png, a note on
    stderr naming contacts.csv, side_walls.png per wall_profiles.csv bin, the discharge's three."""
    out = copy_run(run, tmp_path / "run")
    for f in [out / "contacts.csv", out / "contacts.vtu", out / "discharge_contacts.pvd",
              *(out / "snapshots").glob("contacts_*")]:
        f.unlink()
    p = draw("-m", "compare.figures", "run", str(out), "--renderer", "pil")
    assert p.returncode == 0, p.stderr
    assert f"{out / 'contacts.csv'}: absent" in p.stderr
    assert sorted(x.name for x in out.glob("*.png")) == sorted(PICTURES[1:])


def test_pil_requested():
    from compare.figures.runs import pil_requested
    assert pil_requested(["run", "D", "--renderer", "pil"])
    assert pil_requested(["run", "--renderer=pil", "D"])
    assert not pil_requested(["run", "D", "--renderer", "matplotlib"])
    assert not pil_requested(["run", "D"])
    assert not pil_requested(["run", "D", "--renderer"])


# --------------------------------------------------------------------------- bad input


def test_plot_run_holds_one_picture_at_a_time_and_writes_what_save_writes(run, tmp_path, monkeypatch):
    """plot_run lets each picture go once it is encoded (at most one Figure alive while the next is
    drawn: five pictures' pixels at once cost this process more than drawing them), and its files
    are the bytes Figure.save writes for draw_run's pictures. A plot_run that keeps its Figures,
    or encodes them otherwise, fails this."""
    import gc
    import weakref
    out = copy_run(run, tmp_path / "run")
    alive, most = [], []
    real_init = rp.Figure.__init__

    def counting_init(self, *args, **kwargs):
        gc.collect()
        most.append(sum(ref() is not None for ref in alive))   # Figures alive as this one starts
        alive.append(weakref.ref(self))
        real_init(self, *args, **kwargs)

    monkeypatch.setattr(rp.Figure, "__init__", counting_init)
    written = quick_figures.plot_run(str(out))
    assert tuple(os.path.basename(p) for p in written) == PICTURES
    assert len(most) == len(PICTURES) and max(most) == 0, most
    monkeypatch.setattr(rp.Figure, "__init__", real_init)
    for name, fig in quick_figures.draw_run(str(out)).items():
        assert (out / name).read_bytes() == open(fig.save(str(tmp_path / name)), "rb").read(), name


def test_two_processes_share_the_pictures_and_write_the_same_bytes(run, tmp_path, monkeypatch):
    """plot_run(jobs=2) draws in this process and a forked one (each draws some pictures: the
    calls are logged by pid) and writes the bytes of plot_run(jobs=1); the share-out gives every
    picture to one process, the costliest first to the least loaded."""
    one, two = copy_run(run, tmp_path / "one"), copy_run(run, tmp_path / "two")
    quick_figures.plot_run(str(one), jobs=1)
    log = tmp_path / "pids.txt"
    real = quick_figures._encoded

    def logged(run_dir, pictures):
        with open(log, "a") as f:
            f.write(f"{os.getpid()} {' '.join(name for name, _ in pictures)}\n")
        return real(run_dir, pictures)

    monkeypatch.setattr(quick_figures, "_encoded", logged)
    written = quick_figures.plot_run(str(two), jobs=2)
    assert tuple(os.path.basename(p) for p in written) == PICTURES
    calls = [line.split() for line in log.read_text().splitlines()]
    assert len(calls) == 2 and calls[0][0] != calls[1][0], calls           # two processes
    assert sorted(name for call in calls for name in call[1:]) == sorted(PICTURES)
    for name in PICTURES:
        assert (two / name).read_bytes() == (one / name).read_bytes(), name
    pictures = [(name, None) for name in PICTURES]
    assert quick_figures._shares(pictures, 2) == [[0, 2], [1, 3, 4]]        # 3.5 + 1.2 against 2.5 + 1.3 + 1.0
    assert sorted(k for share in quick_figures._shares(pictures, 9) for k in share) == list(range(5))


def test_a_picture_process_that_dies_stops_the_pictures_and_writes_none(run, tmp_path, monkeypatch):
    """A forked picture process killed before its reply (SIGKILL): plot_run stops with a message
    and writes no picture, its own pictures included."""
    import signal
    out = copy_run(run, tmp_path / "run")
    parent, real = os.getpid(), quick_figures._encoded

    def dying(run_dir, pictures):
        if os.getpid() != parent:
            os.kill(os.getpid(), signal.SIGKILL)
        return real(run_dir, pictures)

    monkeypatch.setattr(quick_figures, "_encoded", dying)
    with pytest.raises(SystemExit, match="a picture process ended without its pictures"):
        quick_figures.plot_run(str(out), jobs=2)
    assert not list(out.glob("*.png")) and not list(out.glob("*.tmp"))


def test_dem_run_pictures_draws_the_same_files_after_the_run(run, tmp_path, dem_binary):
    """`dem run SCENE --out DIR --pictures`: the run's outputs, then the five pictures of
    `compare.quick_figures run DIR`, byte for byte (the run is deterministic), the files named on
    stdout unless --quiet."""
    out = tmp_path / "both"
    p = subprocess.run([str(dem_binary), "run", str(SCENE), "--out", str(out), "--pictures", "--quiet"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert p.stdout == "", p.stdout
    reference = copy_run(run, tmp_path / "reference")
    quick_figures.plot_run(str(reference), jobs=1)
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
    p = draw("-m", "compare.figures.quick_figures", "run", str(tmp_path / "nowhere"))
    assert p.returncode != 0
    assert f"{tmp_path / 'nowhere'}: not a directory" in p.stderr
    assert "Traceback" not in p.stderr


@pytest.mark.parametrize("broken", ["summary.json missing", "wall_series.csv short line",
                                    "flow_series.csv column gone"])
def test_a_broken_run_names_the_file_and_writes_nothing(run, tmp_path, broken):
    """A missing or malformed file stops both entries with a message that names it (no
    traceback), exit status non-zero, and no picture written: all five are drawn before the
    first is written."""
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
    for entry in (["-m", "compare.figures.quick_figures", "run", str(out), "--jobs", "1"],
                  ["-m", "compare.figures.quick_figures", "run", str(out), "--jobs", "2"],
                  ["-m", "compare.figures", "run", str(out), "--renderer", "pil"]):
        p = draw(*entry)
        assert p.returncode != 0, entry
        assert f"{out / name}:" in p.stderr, p.stderr
        assert "Traceback" not in p.stderr, p.stderr
        assert not list(out.glob("*.png")) and not list(out.glob("*.tmp")), entry


# --------------------------------------------------------------------------- ticks


@pytest.mark.parametrize("lo, hi, n, expected", [
    (0.0, 7.3, 6, [0, 2, 4, 6]),                 # 7.3 / 6 = 1.22 -> step 2
    (0.0, 1.0, 5, [0, 0.2, 0.4, 0.6, 0.8, 1.0]),  # 0.2 exactly
    (-3.0, 47.0, 6, [0, 10, 20, 30, 40]),        # 8.33 -> 10
    (0.013, 0.087, 4, [0.02, 0.04, 0.06, 0.08]),  # 0.0185 -> 0.02
    (12.0, 39.5, 9, [15, 20, 25, 30, 35]),       # 3.06 -> 5
    (0.0, 5.0, 2, [0, 2.5, 5]),                  # 2.5 -> 2.5
])
def test_nice_ticks_by_hand(lo, hi, n, expected):
    np.testing.assert_allclose(rp.nice_ticks(lo, hi, n), expected, atol=1e-12)


def test_nice_ticks_rule():
    """For any range: the step is 1, 2, 2.5 or 5 x 10^k, the smallest such with at most n
    intervals over the range; the ticks are the step's multiples inside it, and none is left out."""
    rng = np.random.default_rng(3)
    for _ in range(300):
        lo = float(rng.uniform(-100, 100)) * 10.0 ** rng.integers(-3, 3)
        hi = lo + float(rng.uniform(0.01, 50)) * 10.0 ** rng.integers(-3, 3)
        n = int(rng.integers(2, 10))
        ticks = rp.nice_ticks(lo, hi, n)
        step = ticks[1] - ticks[0] if len(ticks) > 1 else None
        if step is None:
            continue
        k = math.floor(math.log10(step) + 1e-9)
        mantissa = step / 10.0 ** k
        assert min(abs(mantissa - m) for m in (1, 2, 2.5, 5)) < 1e-6, (lo, hi, n, step)
        assert (hi - lo) / step <= n * (1 + 1e-9), (lo, hi, n, step)
        candidates = [m * 10.0 ** j for j in (k - 1, k) for m in (1, 2, 2.5, 5)]
        smaller = max(c for c in candidates if c < step * (1 - 1e-9))
        assert (hi - lo) / smaller > n * (1 - 1e-9), (lo, hi, n, step, smaller)
        assert ticks[0] >= lo - 1e-9 * abs(step) and ticks[-1] <= hi + 1e-9 * abs(step)
        assert ticks[0] - step < lo and ticks[-1] + step > hi
        np.testing.assert_allclose(np.diff(ticks), step, rtol=1e-9)


def test_tick_labels():
    assert rp.tick_labels([0, 2, 4, 6]) == ["0", "2", "4", "6"]
    assert rp.tick_labels([-1.0, -0.5, 0.0, 0.5]) == ["\u22121.0", "\u22120.5", "0.0", "0.5"]
    assert rp.tick_labels([0.02, 0.04, 0.06]) == ["0.02", "0.04", "0.06"]
    assert rp.tick_labels([0, 2.5, 5]) == ["0.0", "2.5", "5.0"]


# --------------------------------------------------------------------------- data -> pixel

# A figure of 4 x 3 inches; axes from 1 in at the left, 0.5 in from the top, 2.5 x 2 in, showing
# X 0..10, Y 0..8 (the same layout as tests/python/test_figures.py's disc test).
LAYOUT = {"size": (4.0, 3.0), "left": 1.0, "top": 0.5, "width": 2.5, "height": 2.0,
          "xlim": (0.0, 10.0), "ylim": (0.0, 8.0)}
RED = (204, 51, 26)
MARKER_PT = 8.0


def pixel_of(x, y, dpi=150):
    """(row, column) of data point (x, y) from LAYOUT alone: x from the box's left edge, y up
    from the box's bottom edge."""
    (x0, x1), (y0, y1) = LAYOUT["xlim"], LAYOUT["ylim"]
    col = (LAYOUT["left"] + (x - x0) / (x1 - x0) * LAYOUT["width"]) * dpi
    row = (LAYOUT["top"] + LAYOUT["height"] - (y - y0) / (y1 - y0) * LAYOUT["height"]) * dpi
    return int(row), int(col)


def marker_png(path, x, y, invert_y=False):
    fig = rp.Figure(*LAYOUT["size"])
    ax = fig.axes(LAYOUT["left"], LAYOUT["top"], LAYOUT["width"], LAYOUT["height"],
                  xlim=LAYOUT["xlim"], ylim=LAYOUT["ylim"], invert_y=invert_y)
    ax.markers([x], [y], "o", MARKER_PT, RED)
    ax.finish(xlabel="X [cm]", ylabel="Y [cm]", title="one marker")
    return fig.save(str(path))


def check_marker(png, x, y):
    """RED at the marker's centre and a third of its radius away (4 ways); white one and a half
    radii away (4 ways)."""
    pixels = np.asarray(Image.open(png).convert("RGB")).astype(int)
    r_px = (MARKER_PT + 1) / 72 * 150 / 2                      # the radius with its 1 pt edge
    for dx, dy in ((0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)):
        row, col = pixel_of(x, y)
        row, col = int(row + dy * r_px / 3), int(col + dx * r_px / 3)
        assert np.abs(pixels[row, col] - RED).max() <= 3, (dx, dy, pixels[row, col])
    for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        row, col = pixel_of(x, y)
        row, col = int(row + dy * 1.5 * r_px), int(col + dx * 1.5 * r_px)
        assert (pixels[row, col] == 255).all(), (dx, dy, pixels[row, col])


def test_a_marker_lands_at_the_pixel_of_its_data_point(tmp_path):
    for x, y in ((2.0, 6.0), (7.5, 2.5), (5.0, 4.0)):
        check_marker(marker_png(tmp_path / "m.png", x, y), x, y)


@pytest.mark.parametrize("wrong", ["y flipped", "x a tenth off"])
def test_the_marker_check_fails_a_wrong_mapping(tmp_path, wrong):
    """The check above fails a picture whose axes map y downward (invert_y where it should not)
    or whose marker is a tenth of the X range off."""
    x, y = 2.0, 6.0
    png = marker_png(tmp_path / "m.png", x, y, invert_y=True) if wrong == "y flipped" \
        else marker_png(tmp_path / "m.png", x + 1.0, y)
    with pytest.raises(AssertionError):
        check_marker(png, x, y)


def test_colormaps_at_their_stops():
    """A map's ends and middle are its table's (viridis 0 and 1; RdBu_r's white middle)."""
    assert tuple(rp.colormap("viridis", [0.0])[0]) == (68, 1, 84)
    assert tuple(rp.colormap("viridis", [1.0])[0]) == (253, 231, 37)
    assert tuple(rp.colormap("RdBu_r", [0.5])[0]) == (247, 246, 246)
    assert tuple(rp.colormap("YlOrRd", [2.0])[0]) == (128, 0, 38)          # clipped to 1


# --------------------------------------------------------------------------- frames' discs

GREY_DEAD = np.array([224, 224, 224])


def disc_classes(png, fig, frames, wrong=None):
    """For each panel's discs (wholly inside the panel): whether the picture shows the class of
    its displacement: dead (< 1 radius) light grey 224, moved a warm YlOrRd colour (red above
    blue by 60 or more). A disc is judged at its centre and half a radius from it (4 ways): the
    class that most of the five pixels show, pixels of neither class (a contact segment, a wall,
    a text across it) left out. Returns (agreeing,
    judged) over all panels. ``wrong`` draws the check on a wrong premise: 'y flipped' (the
    disc looked for at its Y mirrored in the panel) or 'classes swapped'."""
    pixels = np.asarray(Image.open(png).convert("RGB")).astype(int)
    agree = judged = 0
    for ax, (t, discs, _) in zip(fig.all_axes, frames):
        moved = displacement_radii(discs)
        y_range = ax.ylim
        for x, y, r, m in zip(discs["x"], discs["y"], discs["r"], moved):
            if wrong == "y flipped":
                y = y_range[0] + y_range[1] - y
            votes = []
            for dx, dy in ((0, 0), (0.5, 0), (-0.5, 0), (0, 0.5), (0, -0.5)):
                fx, fy = ax.figure_px(x + dx * r, y + dy * r)
                p = pixels[int(fy), int(fx)]
                if np.abs(p - GREY_DEAD).max() <= 4:
                    votes.append("dead")
                elif p[0] - p[2] >= 60:
                    votes.append("moved")
                else:
                    votes.append("other")
            classes = [v for v in votes if v != "other"] or ["other"]
            shown = max(sorted(set(classes)), key=classes.count)
            expected = "dead" if m < DEAD_RADII else "moved"
            if wrong == "classes swapped":
                expected = {"dead": "moved", "moved": "dead"}[expected]
            agree += shown == expected
            judged += 1
    return agree, judged


@pytest.fixture(scope="module")
def frames_picture(run, tmp_path_factory):
    from compare.figures.figure_data import discharge_frames
    fig = quick_figures.frames(str(run))
    png = fig.save(str(tmp_path_factory.mktemp("frames") / "frames.png"))
    return png, fig, discharge_frames(str(run))["frames"]


def test_frames_discs_have_the_colour_of_their_displacement_class(frames_picture):
    """Nearly every disc of the ten panels (a disc under a wall or dot aside) shows its class;
    the run has both (dead discs beside the walls, moved ones above the slit)."""
    png, fig, frames = frames_picture
    moved = np.concatenate([displacement_radii(d) for _, d, _ in frames])
    assert (moved < DEAD_RADII).sum() > 500 and (moved >= DEAD_RADII).sum() > 500
    agree, judged = disc_classes(png, fig, frames)
    assert judged > 3000 and agree >= 0.97 * judged, (agree, judged)


@pytest.mark.parametrize("wrong", ["y flipped", "classes swapped"])
def test_the_disc_class_check_fails_a_wrong_premise(frames_picture, wrong):
    png, fig, frames = frames_picture
    agree, judged = disc_classes(png, fig, frames, wrong)
    assert agree < 0.97 * judged, (wrong, agree, judged)

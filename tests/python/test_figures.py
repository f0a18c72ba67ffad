"""Tests of dem.compare.figures on synthetic run directories written as docs/outputs.md describes."""
import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import matplotlib.image

from dem.compare.figures import runs as figures

REPO_ROOT = Path(__file__).resolve().parents[2]

DISC_WEIGHT = 8159.9           # m g of a disc of r = 1 cm, rho = 2.65 g/cm^3
UNIT = 50 / math.pi * DISC_WEIGHT   # force drawn as one disc diameter
BIN = 2.0                      # profile bin, cm


def write_csv(path, columns, rows):
    """Write a CSV file with a header row, like the engine."""
    with open(path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(columns)
        out.writerows(rows)


def wall_bins(wall, contacts):
    """Profile of one wall from its dw contacts (columns of wall_profiles.csv except wall/group)."""
    a, b = np.array(wall["from"], float), np.array(wall["to"], float)
    length = np.linalg.norm(b - a)
    u = (b - a) / length
    nbins = int(math.ceil(length / BIN - 1e-9))
    normal, shear, count = np.zeros(nbins), np.zeros(nbins), np.zeros(nbins, int)
    for c in contacts:
        if c[0] == "dw" and c[2] == wall["name"]:
            k = min(int(np.dot(np.array(c[3:5]) - a, u) // BIN), nbins - 1)
            normal[k] += c[7]
            shear[k] += c[8]
            count[k] += 1
    rows = []
    for k in range(nbins):
        s_lo, s_hi = k * BIN, min((k + 1) * BIN, length)
        mid = a + u * (s_lo + s_hi) / 2
        rows.append([k, s_lo, s_hi, float(mid[0]), float(mid[1]), None,
                     float(normal[k]), float(shear[k]), int(count[k])])
    return rows


def make_run(run_dir, s=6, nrows=5, name="synthetic 5/6", right_factor=1.0):
    """Write a synthetic run: an (s-1)/s arrangement of discs (r = 1 cm) in a silo with two side
    walls, a bottom split by a slit whose ends L, R are point contacts, and made-up forces that
    grow with depth. right_factor scales the right wall's forces (to make the sides differ)."""
    run_dir.mkdir(parents=True, exist_ok=True)
    a = 2.4                                  # horizontal spacing: discs touch 4 neighbours
    dy = math.sqrt(4 - (a / 2) ** 2)
    width = 2 + (s - 1) * a
    height = 2 + (nrows - 1) * dy + 2
    xl, xr = 1 + (s // 2 - 1) * a, 1 + (s // 2) * a   # slit ends under two bottom discs
    discs = []
    for row in range(nrows):
        n = s if row % 2 == 0 else s - 1
        for k in range(n):
            x = 1 + k * a + (0 if row % 2 == 0 else a / 2)
            discs.append((len(discs), x, 1 + row * dy, 1.0))
    walls = [{"name": "left", "group": "side_left", "from": [0, height], "to": [0, 0]},
             {"name": "right", "group": "side_right", "from": [width, height], "to": [width, 0]},
             {"name": "bottom_a", "group": "bottom", "from": [0, 0], "to": [xl, 0]},
             {"name": "bottom_b", "group": "bottom", "from": [xr, 0], "to": [width, 0]}]
    contacts = []
    for i, xi, yi, ri in discs:
        depth = height - yi
        for j, xj, yj, rj in discs:
            d = math.hypot(xj - xi, yj - yi)
            if j > i and d < ri + rj + 1e-9:
                nx, ny = (xj - xi) / d, (yj - yi) / d
                en = DISC_WEIGHT * (0.5 + 0.6 * depth)
                es = 0.15 * en * (1 if nx > 0 else -1)
                contacts.append(["dd", i, str(j), xi + ri * nx, yi + ri * ny, nx, ny, en, es, en, es])
        if xi - ri < 1e-9:
            en = DISC_WEIGHT * 0.4 * depth
            contacts.append(["dw", i, "left", 0.0, yi, -1.0, 0.0, en, 0.1 * en, en, 0.1 * en])
        if xi + ri > width - 1e-9:
            en = DISC_WEIGHT * 0.4 * depth * right_factor
            contacts.append(["dw", i, "right", width, yi, 1.0, 0.0, en, 0.1 * en, en, 0.1 * en])
        if yi - ri < 1e-9:
            en = DISC_WEIGHT * 0.8 * depth
            where = "L" if abs(xi - xl) < 1e-9 else "R" if abs(xi - xr) < 1e-9 else \
                "bottom_a" if xi < xl else "bottom_b"
            contacts.append(["dp" if where in "LR" else "dw", i, where, xi, 0.0, 0.0, -1.0,
                             en, 0.0, en, 0.0])

    profile_rows = []
    for w in walls:
        bins = wall_bins(w, contacts)
        for r in bins:
            r[5] = height - r[4]                      # depth_mid = H - y_mid
        w.update({"normal_total": sum(r[6] for r in bins), "shear_total": sum(r[7] for r in bins),
                  "contacts": int(sum(r[8] for r in bins)),
                  "profile": {k: [r[m] for r in bins] for m, k in enumerate(
                      ("bin", "s_lo", "s_hi", "x_mid", "y_mid", "depth_mid", "normal", "shear",
                       "contacts")) if k != "bin"}})
        profile_rows += [[w["name"], w["group"]] + r for r in bins]
    summary = {
        "engine": "dem 0.1.0",
        "scene": {"name": name, "file": "synthetic.toml", "description": "test fixture"},
        "status": "rest", "options": {"scheme": "paper_eq19", "dt": 1e-4},
        "n_discs": len(discs), "steps": 12000, "time": 1.2, "wall_time_s": 0.1,
        "weight": DISC_WEIGHT * len(discs), "disc_weight": DISC_WEIGHT,
        "height": height, "width": width, "walls": walls,
        "points": [{"name": "L", "force": [0, 0], "contacts": 1},
                   {"name": "R", "force": [0, 0], "contacts": 1}],
    }
    (run_dir / "summary.json").write_text(json.dumps(summary, indent=1))
    write_csv(run_dir / "contacts.csv", figures.CONTACT_COLUMNS, contacts)
    write_csv(run_dir / "discs.csv", figures.DISC_COLUMNS,
              [[i, x, y, r, 0, 0, 0, "glass"] for i, x, y, r in discs])
    write_csv(run_dir / "wall_profiles.csv", figures.PROFILE_COLUMNS, profile_rows)
    return run_dir


def assert_png(path):
    """The file is a PNG that matplotlib reads back as a non-empty image."""
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    image = matplotlib.image.imread(str(path))
    assert image.ndim == 3 and image.shape[0] > 100 and image.shape[1] > 100
    assert image.std() > 0                                   # not a blank canvas


def one_contact(x, y, nx, ny, en, es):
    """contacts.csv arrays holding a single contact."""
    return {"x": [x], "y": [y], "nx": [nx], "ny": [ny], "e_n": [en], "e_s": [es]}


# --------------------------------------------------------------------------- segment geometry

def test_normal_contact_segment_is_one_diameter_long():
    # e_n = 50/pi disc weights is drawn as one disc diameter (2 r_ref = 2 cm), along n = (1, 0),
    # centred on (3, 4): from (2, 4) to (4, 4).
    seg = figures.network_segments(one_contact(3, 4, 1, 0, UNIT, 0), 1.0, DISC_WEIGHT)
    assert seg.shape == (1, 2, 2)
    ends = sorted(map(tuple, seg[0]))
    np.testing.assert_allclose(ends, [(2, 4), (4, 4)], atol=1e-12)


def test_pure_shear_segment_lies_along_t():
    # n = (0, 1) so t = (-ny, nx) = (-1, 0); e_s = half the unit, r_ref = 2: length 2 * 2 * 0.5 = 2.
    seg = figures.network_segments(one_contact(0, 0, 0, 1, 0, UNIT / 2), 2.0, DISC_WEIGHT)[0]
    np.testing.assert_allclose(seg.mean(axis=0), [0, 0], atol=1e-12)
    direction = seg[1] - seg[0]
    np.testing.assert_allclose(np.linalg.norm(direction), 2.0)
    np.testing.assert_allclose(direction[1], 0.0, atol=1e-12)       # parallel to t = (-1, 0)


def test_oblique_resultant_direction_and_length():
    # n = (0.6, 0.8), t = (-0.8, 0.6); e_n = 3k, e_s = 4k with k = UNIT/5, so |e| = UNIT and the
    # segment is 2 r_ref = 2 long along 0.6 n + 0.8 t = (0.36 - 0.64, 0.48 + 0.48) = (-0.28, 0.96).
    k = UNIT / 5
    seg = figures.network_segments(one_contact(1, 1, 0.6, 0.8, 3 * k, 4 * k), 1.0, DISC_WEIGHT)[0]
    direction = seg[1] - seg[0]
    direction *= np.sign(direction[1])
    np.testing.assert_allclose(direction, [-0.56, 1.92], atol=1e-12)
    np.testing.assert_allclose(seg.mean(axis=0), [1, 1], atol=1e-12)


def test_zero_contacts_give_empty_array():
    empty = {k: np.zeros(0) for k in ("x", "y", "nx", "ny", "e_n", "e_s")}
    assert figures.network_segments(empty, 1.0, DISC_WEIGHT).shape == (0, 2, 2)


# --------------------------------------------------------------------------- reading

def test_load_run_parses_every_file(tmp_path):
    run = figures.load_run(make_run(tmp_path / "run"))
    assert run["summary"]["disc_weight"] == DISC_WEIGHT
    c, d, p = run["contacts"], run["discs"], run["profiles"]
    assert set(c["kind"]) == {"dd", "dw", "dp"}
    assert c["i"].dtype.kind == "i" and c["e_n"].dtype.kind == "f"
    assert {"left", "right", "L", "R"} <= set(c["j"])
    assert len(d["id"]) == run["summary"]["n_discs"] and d["r"][0] == 1.0
    assert set(p["group"]) == {"side_left", "side_right", "bottom"}
    assert figures.reference_radius(d) == 1.0


def test_point_positions_come_from_point_contacts(tmp_path):
    run = figures.load_run(make_run(tmp_path / "run", s=6), parts=("contacts",))
    pts = figures.point_positions(run["summary"], run["contacts"])
    assert set(pts) == {"L", "R"}
    assert pts["L"][1] == 0.0 and pts["L"][0] < pts["R"][0]


def test_headerless_csv_is_read(tmp_path):
    path = tmp_path / "discs.csv"
    path.write_text("0,1,2,1,0,0,0,glass\n1,3,2,1,0,0,0,glass\n")
    discs = figures.read_csv(str(path), figures.DISC_COLUMNS)
    np.testing.assert_array_equal(discs["x"], [1, 3])


# --------------------------------------------------------------------------- side profile

def test_side_profile_averages_left_and_right_at_the_same_depth(tmp_path):
    path = tmp_path / "wall_profiles.csv"
    rows = [["left", "side_left", k, 2 * k, 2 * k + 2, 0, 7 - 2 * k, 2 * k + 1, n, s, 3]
            for k, (n, s) in enumerate([(1, 0.1), (2, 0.2), (3, 0.3), (4, -0.4)])]
    # Right wall rows in reverse order: matching is by depth, not by file order.
    rows += [["right", "side_right", k, 2 * k, 2 * k + 2, 8, 7 - 2 * k, 2 * k + 1, n, s, 3]
             for k, (n, s) in reversed(list(enumerate([(3, 0.3), (4, 0.4), (5, 0.5), (6, -0.2)])))]
    rows += [["floor", "bottom", 0, 0, 2, 1, 0, 8, 99, 0, 4]]
    write_csv(path, figures.PROFILE_COLUMNS, rows)
    prof = figures.side_profile(figures.read_csv(str(path), figures.PROFILE_COLUMNS))
    np.testing.assert_allclose(prof["depth"], [1, 3, 5, 7])
    np.testing.assert_allclose(prof["normal"], [2, 3, 4, 5])
    np.testing.assert_allclose(prof["shear"], [0.2, 0.3, 0.4, -0.3])
    np.testing.assert_allclose(prof["groups"]["side_left"]["normal"], [1, 2, 3, 4])
    np.testing.assert_allclose(prof["groups"]["side_right"]["normal"], [3, 4, 5, 6])
    assert prof["bin_width"] == 2.0


def test_side_profile_without_side_walls_is_none(tmp_path):
    path = tmp_path / "wall_profiles.csv"
    write_csv(path, figures.PROFILE_COLUMNS, [["floor", "bottom", 0, 0, 2, 1, 0, 8, 99, 0, 4]])
    assert figures.side_profile(figures.read_csv(str(path), figures.PROFILE_COLUMNS)) is None


# --------------------------------------------------------------------------- figures

def test_network_png(tmp_path):
    run = make_run(tmp_path / "run")
    out = tmp_path / "network.png"
    assert figures.plot_network(str(run), str(out)) == str(out)
    assert_png(out)


def test_profiles_png_of_several_runs(tmp_path):
    runs = [str(make_run(tmp_path / f"run{s}", s=s, nrows=9, name=f"{s - 1}/{s}",
                         right_factor=1.0 if s % 2 else 1.3)) for s in (5, 6, 7)]
    out = tmp_path / "side.png"
    figures.plot_side_profiles(runs, str(out))
    assert_png(out)
    figures.plot_side_profiles(runs, str(out), labels=["a", "b", "c"])
    assert_png(out)


def test_bottom_png(tmp_path):
    out = tmp_path / "sub" / "bottom.png"
    figures.plot_bottom_profile(str(make_run(tmp_path / "run")), str(out))
    assert_png(out)


def test_cli_subcommands(tmp_path):
    run = str(make_run(tmp_path / "run"))
    for n, args in enumerate((["network", run], ["profiles", run, run, "--labels", "x", "y"],
                              ["profiles", run, "--per", "bin"], ["bottom", run],
                              ["grid", run, run, run, "--labels", "a", "b", "c", "--ncols", "2"])):
        out = tmp_path / f"{n}_{args[0]}.png"
        done = subprocess.run([sys.executable, "-m", "dem.compare.figures", *args, "--out", str(out)],
                              cwd=REPO_ROOT, capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        assert_png(out)


def capture_figures(monkeypatch):
    """Make figures._save keep the figure (still writing the PNG); returns the list of figures."""
    kept = []

    def save(fig, out_png):
        kept.append(fig)
        fig.savefig(out_png, dpi=50)
        return out_png
    monkeypatch.setattr(figures, "_save", save)
    return kept


def set_rest(run_dir, reached, status):
    """Add summary.json's rest block and status to a synthetic run."""
    path = run_dir / "summary.json"
    summary = json.loads(path.read_text())
    summary["rest"] = {"reached": reached}
    summary["status"] = status
    path.write_text(json.dumps(summary))


def test_network_is_drawn_by_draw_network_with_the_paper_scale(tmp_path, monkeypatch):
    kept = capture_figures(monkeypatch)
    run_dir = make_run(tmp_path / "run")
    figures.plot_network(str(run_dir), str(tmp_path / "n.png"))
    run = figures.load_run(str(run_dir), parts=("contacts", "discs"))
    expected = figures.network_segments(run["contacts"], 1.0, DISC_WEIGHT)
    lines = [c for c in kept[0].axes[0].collections if isinstance(c, figures.LineCollection)]
    assert len(lines) == 1
    np.testing.assert_allclose(np.array(lines[0].get_segments()), expected)


def test_network_grid_panels_titles_and_scale(tmp_path, monkeypatch):
    kept = capture_figures(monkeypatch)
    runs = [make_run(tmp_path / f"run{s}", s=s, name=f"{s - 1}/{s}") for s in (5, 6, 7)]
    set_rest(runs[0], True, "rest")
    set_rest(runs[1], False, "end_time")            # runs[2] has no rest block at all
    out = tmp_path / "grid.png"
    assert figures.plot_network_grid([str(r) for r in runs], str(out), ncols=2) == str(out)
    assert_png(out)
    fig = kept[0]
    assert len(fig.axes) == 4                        # 2 x 2, the last one switched off
    titles = [ax.get_title() for ax in fig.axes[:3]]
    assert titles == ["4/5: at rest", "5/6: NOT at rest (end_time)", "6/7: rest unknown"]
    assert not fig.axes[3].axison
    assert "50/\u03c0" in fig._suptitle.get_text() and "disc weights" in fig._suptitle.get_text()
    # Each panel's segments follow the same rule as plot_network (r_ref = 1 cm here) ...
    for ax, run_dir in zip(fig.axes, runs):
        run = figures.load_run(str(run_dir), parts=("contacts", "discs"))
        lines = [c for c in ax.collections if isinstance(c, figures.LineCollection)]
        np.testing.assert_allclose(np.array(lines[0].get_segments()),
                                   figures.network_segments(run["contacts"], 1.0, DISC_WEIGHT))
    # ... and all panels show the same length of silo per panel (one length scale).
    spans = {(round(np.diff(ax.get_xlim())[0], 9), round(np.diff(ax.get_ylim())[0], 9))
             for ax in fig.axes[:3]}
    assert len(spans) == 1
    figures.plot_network_grid([str(r) for r in runs], str(out), labels=["a", "b", "c"])
    assert [ax.get_title().split(":")[0] for ax in kept[1].axes] == ["a", "b", "c"]
    with pytest.raises(SystemExit, match="2 labels for 3 runs"):
        figures.plot_network_grid([str(r) for r in runs], str(out), labels=["a", "b"])


# --------------------------------------------------------------------------- per-contact profile

SIDE_WALLS = [{"name": "left", "group": "side_left", "from": [0, 10], "to": [0, 0]},
              {"name": "right", "group": "side_right", "from": [8, 10], "to": [8, 0]},
              {"name": "floor", "group": "bottom", "from": [0, 0], "to": [8, 0]}]


def contact_arrays(rows):
    """contacts.csv arrays from rows (kind, i, j, x, y, nx, ny, f_n, f_s); e = f here."""
    cols = {k: [] for k in figures.CONTACT_COLUMNS}
    for kind, i, j, x, y, nx, ny, fn, fs in rows:
        for k, v in zip(figures.CONTACT_COLUMNS, (kind, i, j, x, y, nx, ny, fn, fs, fn, fs)):
            cols[k].append(v)
    return {k: np.array(v, dtype=str if k in ("kind", "j") else float) for k, v in cols.items()}


def test_side_wall_contacts_by_hand():
    rows = [
        # Left wall, y = 7: n = (-1, 0), t = (-ny, nx) = (0, -1). Force on the wall
        # 5 n + 2 t = (-5, -2); along from -> to = (0, -1): friction +2 (downward). Depth 10 - 7 = 3.
        ("dw", 0, "left", 0, 7, -1, 0, 5, 2),
        # Right wall, y = 7 + 4e-7 (same row): n = (1, 0), t = (0, 1). Force 7 n - 1 t = (7, -1),
        # friction +1. Depth 3 - 4e-7, within 1e-6 of the left one: mean normal 6, friction 1.5.
        ("dw", 1, "right", 8, 7 + 4e-7, 1, 0, 7, -1),
        # Left, y = 4 (depth 6), n = (-0.8, 0.6), t = (-0.6, -0.8): force 10 n + 5 t
        # = (-8 - 3, 6 - 4) = (-11, 2), friction -2 (upward).
        ("dw", 2, "left", 0, 4, -0.8, 0.6, 10, 5),
        # Right, y = 4: n = (1, 0), t = (0, 1): force 10 n - 3 t = (10, -3), friction +3.
        # Mean at depth 6: normal 10, friction 0.5.
        ("dw", 3, "right", 8, 4, 1, 0, 10, -3),
        # Ignored: a disc-disc contact and a bottom contact.
        ("dd", 0, "2", 0.5, 5.5, 0, -1, 99, 9),
        ("dw", 4, "floor", 4, 0, 0, -1, 50, 1),
    ]
    prof = figures.side_wall_contacts({"walls": SIDE_WALLS}, contact_arrays(rows))
    assert prof["paired"]
    np.testing.assert_allclose(prof["depth"], [3 - 2e-7, 6], atol=1e-12)
    np.testing.assert_allclose(prof["normal"], [6, 10])
    np.testing.assert_allclose(prof["friction"], [1.5, 0.5], atol=1e-12)
    np.testing.assert_allclose(prof["groups"]["side_left"]["normal"], [5, 10])
    np.testing.assert_allclose(prof["groups"]["side_left"]["friction"], [2, -2], atol=1e-12)
    np.testing.assert_allclose(prof["groups"]["side_right"]["friction"], [1, 3], atol=1e-12)
    assert set(prof["groups"]) == {"side_left", "side_right"}
    np.testing.assert_allclose(prof["contacts"]["side_right"]["depth"], [3 - 4e-7, 6], atol=1e-12)


def test_side_wall_contacts_unpaired_and_wall_direction():
    # The right wall now runs bottom to top, so its friction flips sign: contact at y = 7 with
    # force (7, -1) on the wall, along (0, 1): -1. The left contact at y = 4 has no partner
    # (right contact at y = 4.5, depth 5.5): the rows are not paired.
    walls = [dict(SIDE_WALLS[0]), {"name": "right", "group": "side_right", "from": [8, 0], "to": [8, 10]}]
    rows = [("dw", 0, "left", 0, 7, -1, 0, 5, 2),
            ("dw", 1, "right", 8, 7, 1, 0, 7, -1),
            ("dw", 2, "left", 0, 4, -1, 0, 4, 0),
            ("dw", 3, "right", 8, 4.5, 1, 0, 8, 0)]
    prof = figures.side_wall_contacts({"walls": walls}, contact_arrays(rows))
    assert not prof["paired"]
    np.testing.assert_allclose(prof["depth"], [3, 5.5, 6])
    np.testing.assert_allclose(prof["normal"], [6, 8, 4])          # one side only at 5.5 and 6
    np.testing.assert_allclose(prof["friction"], [0.5, 0, 0], atol=1e-12)   # (2 + -1) / 2
    assert np.isnan(prof["groups"]["side_left"]["normal"][1])
    assert figures.side_wall_contacts({"walls": walls}, contact_arrays(rows[:0])) is None


def test_side_wall_contacts_of_a_synthetic_run_match_the_wall_totals(tmp_path):
    run = figures.load_run(str(make_run(tmp_path / "run", nrows=9)), parts=("contacts",))
    prof = figures.side_wall_contacts(run["summary"], run["contacts"])
    assert prof["paired"]
    for w in run["summary"]["walls"]:
        if w["group"].startswith("side"):
            raw = prof["contacts"][w["group"]]
            assert len(raw["depth"]) == w["contacts"]
            np.testing.assert_allclose(raw["normal"].sum(), w["normal_total"])
            # left wall: n = (-1, 0), force on it (-e_n, -0.1 e_n), friction +0.1 e_n = 0.04 depth W
            if w["name"] == "left":
                np.testing.assert_allclose(raw["friction"], 0.04 * raw["depth"] * DISC_WEIGHT)


def test_profiles_plot_one_point_per_contact_row(tmp_path, monkeypatch):
    kept = capture_figures(monkeypatch)
    runs = [make_run(tmp_path / "same", nrows=9, name="same"),
            make_run(tmp_path / "differ", nrows=9, name="differ", right_factor=1.3)]
    out = tmp_path / "side.png"
    figures.plot_side_profiles([str(r) for r in runs], str(out))
    assert_png(out)
    axn, axs = kept[0].axes
    assert "per contact" in axn.get_xlabel() and "per contact" in axs.get_xlabel()
    assert "P_y per contact" in kept[0]._suptitle.get_text()
    run = figures.load_run(str(runs[0]), parts=("contacts",))
    prof = figures.side_wall_contacts(run["summary"], run["contacts"])
    # First run: sides equal, one line per panel holding the per-row means in disc weights.
    first = axn.get_lines()[0]
    np.testing.assert_allclose(first.get_xdata(), prof["normal"] / DISC_WEIGHT)
    np.testing.assert_allclose(first.get_ydata(), prof["depth"])
    # Second run: the right wall pushes 1.3 times the left, so each side is drawn too; in the
    # normal panel: first run 1 line, second run mean + 2 sides. In the friction panel the
    # synthetic data's friction is +0.1 e_n on the left and -0.1 e_n on the right: sides drawn.
    assert len(axn.get_lines()) == 1 + 3
    assert [h for h in axn.get_legend().get_texts()][-1].get_text() == "side_right alone"
    # per="bin" keeps the former figure.
    figures.plot_side_profiles([str(r) for r in runs], str(out), per="bin")
    assert "per 2 cm bin" in kept[1].axes[0].get_xlabel()
    with pytest.raises(SystemExit, match="per must be"):
        figures.plot_side_profiles([str(r) for r in runs], str(out), per="row")


def test_profiles_of_a_run_with_unlevel_rows_draw_the_sides_apart(tmp_path, monkeypatch):
    kept = capture_figures(monkeypatch)
    run_dir = make_run(tmp_path / "run", nrows=5, name="tilted")
    path = run_dir / "contacts.csv"
    lines = path.read_text().splitlines()
    shifted = []
    for line in lines:                                # move every right-wall contact up 0.01
        cells = line.split(",")
        if cells[0] == "dw" and cells[2] == "right":
            cells[4] = repr(float(cells[4]) + 0.01)
        shifted.append(",".join(cells))
    path.write_text("\n".join(shifted) + "\n")
    figures.plot_side_profiles([str(run_dir)], str(tmp_path / "side.png"))
    axn = kept[0].axes[0]
    assert len(axn.get_lines()) == 2                  # left and right, no mean line
    assert {l.get_marker() for l in axn.get_lines()} == {"<", ">"}
    assert "not level in tilted" in kept[0]._suptitle.get_text()


# --------------------------------------------------------------------------- errors

def test_missing_summary_names_the_file(tmp_path):
    run = make_run(tmp_path / "run")
    (run / "summary.json").unlink()
    with pytest.raises(SystemExit, match="summary.json"):
        figures.plot_network(str(run), str(tmp_path / "x.png"))


def test_malformed_summary_names_the_file(tmp_path):
    run = make_run(tmp_path / "run")
    (run / "summary.json").write_text("{not json")
    with pytest.raises(SystemExit, match="summary.json.*JSON"):
        figures.load_run(str(run))


def test_missing_or_malformed_csv_names_the_file(tmp_path):
    run = make_run(tmp_path / "run")
    (run / "wall_profiles.csv").unlink()
    with pytest.raises(SystemExit, match="wall_profiles.csv.*missing"):
        figures.plot_side_profiles([str(run)], str(tmp_path / "x.png"), per="bin")
    figures.plot_side_profiles([str(run)], str(tmp_path / "x.png"))   # per contact: not needed
    with open(run / "contacts.csv", "a") as f:
        f.write("dd,0,1,oops,0,1,0,1,0,1,0\n")
    with pytest.raises(SystemExit, match="contacts.csv.*'x'"):
        figures.plot_network(str(run), str(tmp_path / "x.png"))
    with pytest.raises(SystemExit, match="contacts.csv.*'x'"):
        figures.plot_side_profiles([str(run)], str(tmp_path / "x.png"))


def test_profiles_without_side_wall_contacts_name_the_file(tmp_path):
    run = make_run(tmp_path / "run")
    rows = [line for line in (run / "contacts.csv").read_text().splitlines()
            if ",left," not in line and ",right," not in line]
    (run / "contacts.csv").write_text("\n".join(rows) + "\n")
    with pytest.raises(SystemExit, match="contacts.csv.*side"):
        figures.plot_side_profiles([str(run)], str(tmp_path / "x.png"))


# --------------------------------------------------------------------------- discharge

DISCHARGE_WALLS = [
    {"name": "left", "group": "side_left", "from": [0, 10], "to": [0, 0]},
    {"name": "right", "group": "side_right", "from": [8, 10], "to": [8, 0]},
    {"name": "bottom_left", "group": "bottom", "from": [0, 0], "to": [3, 0]},
    {"name": "gate", "group": "bottom", "from": [3, 0], "to": [5, 0]},
    {"name": "bottom_right", "group": "bottom", "from": [5, 0], "to": [8, 0]},
]
SNAPSHOT_TIMES = (0.0, 0.05, 0.1)
# Discs of each snapshot: (id, x, y, dx, dy); r = 1. Disc 1 falls through the slit and is gone
# at 0.1 s; disc 3 sinks 1.4 then 3.9 radii; disc 2 creeps 0.5 (dead); disc 0 stays (dead).
SNAPSHOT_DISCS = (
    [(0, 1, 1, 0, 0), (1, 4, 1, 0, 0), (2, 7, 1, 0, 0), (3, 4, 2.9, 0, 0)],
    [(0, 1, 1, 0, 0), (1, 4, -1, 0, -2), (2, 7, 1, 0, 0), (3, 4, 1.5, 0, -1.4)],
    [(0, 1, 1, 0, 0), (2, 7.5, 1, 0.5, 0), (3, 4, -1.0, 0, -3.9)],
)
SNAPSHOT_CONTACTS = (
    [["dw", 0, "left", 0, 1, -1, 0, 2 * DISC_WEIGHT, 0, 2 * DISC_WEIGHT, 0],
     ["dw", 1, "gate", 4, 0, 0, -1, 5 * DISC_WEIGHT, 0, 5 * DISC_WEIGHT, 0],
     ["dd", 1, "3", 4, 1.95, 0, 1, 3 * DISC_WEIGHT, 0.5 * DISC_WEIGHT, 3 * DISC_WEIGHT, 0]],
    [["dw", 0, "bottom_left", 1, 0, 0, -1, 9 * DISC_WEIGHT, 1, 9 * DISC_WEIGHT, 1],
     ["dp", 3, "L", 3, 0, -0.6, -0.8, 4 * DISC_WEIGHT, 0, 4 * DISC_WEIGHT, 0]],
    [],
)
# Static (t = 0) normal force per bin of each wall in wall_series.csv, then two later samples
# as multiples of a fixed pattern; the side walls have 5 bins of 2 cm from the top.
SERIES = {
    "left": [[0, 8, 2, 1.9, 10], [0, 16, 1, 5, 30], [0, 4, 6, 0, 0]],
    "right": [[0, 8, 8, 8, 8], [0, 8, 16, 8, 8], [0, 8, 8, 8, 0]],
    "bottom_left": [[4, 4], [12, 2], [4, 0]],
    "gate": [[6], [0], [0]],
    "bottom_right": [[4, 1], [4, 1], [4, 1]],
}
SERIES_TIMES = (0.0, 0.05, 0.1)
# Removals: five outlet discs (mass 2), then a keystone removed by hand at 0.08 s, then two more.
REMOVALS = [(0.01, 10, 2.0, "outlet"), (0.02, 11, 2.0, "outlet"), (0.03, 12, 2.0, "outlet"),
            (0.04, 13, 2.0, "outlet"), (0.05, 14, 2.0, "outlet"), (0.08, 15, 2.0, "keystone"),
            (0.09, 16, 2.0, "outlet"), (0.095, 17, 2.0, "outlet")]


def bin_geometry(wall, k):
    """(s_mid, x_mid, y_mid, depth_mid) of 2 cm bin k of one of DISCHARGE_WALLS (top = 10)."""
    a, b = np.array(wall["from"], float), np.array(wall["to"], float)
    length = np.linalg.norm(b - a)
    s = (k * BIN + min((k + 1) * BIN, length)) / 2
    x, y = a + (b - a) / length * s
    return s, float(x), float(y), 10 - float(y)


def make_discharge_run(run_dir, contacts_pvd=True, name="tiny discharge"):
    """Write a synthetic discharge run as docs/outputs.md ("Discharge outputs") describes."""
    run_dir.mkdir(parents=True, exist_ok=True)
    (run_dir / "snapshots").mkdir(exist_ok=True)
    walls = [dict(w, normal_total=0.0, shear_total=0.0, contacts=0) for w in DISCHARGE_WALLS]
    summary = {
        "engine": "dem 0.1.0",
        "scene": {"name": name, "file": "tiny.toml", "description": "test fixture"},
        "status": "jammed", "n_discs": 3, "time": 0.5, "disc_weight": DISC_WEIGHT,
        "weight": 4 * DISC_WEIGHT, "height": 10, "width": 8, "walls": walls,
        "points": [{"name": "L", "group": "slit_ends", "at": [3, 0], "force": [0, 0], "contacts": 0},
                   {"name": "R", "group": "slit_ends", "at": [5, 0], "force": [0, 0], "contacts": 0}],
        "rest": {"reached": True, "time": 0.4},
        "discharge": {"status": "jammed", "t_open": 0.4, "duration": 0.1, "n_initial": 4,
                      "removed": 8, "removed_by_hand": 1, "discs_out_at_1s": 8,
                      "flow_rate_mass": 40.0, "flow_rate_discs": 20.0, "jammed": True,
                      "jam_at": 0.07, "jams": 1, "peak_ratio_bottom": 3.0,
                      "peak_ratio_bottom_windowed": 2.25, "peak_ratio_side": 2.0,
                      "peak_ratio_side_windowed": 1.5, "pattern": "funnel",
                      "surface_sink_time": {"left_wall": 0.05, "centre": None, "right_wall": 0.05},
                      "moved_fraction_end": 0.75, "dead_fraction_end": 0.25,
                      "slit": [3, 5], "outlet_y": -2.0},
    }
    (run_dir / "summary.json").write_text(json.dumps(summary, indent=1))
    entries = {"discs": [], "contacts": []}
    for n, (t, discs, contacts) in enumerate(zip(SNAPSHOT_TIMES, SNAPSHOT_DISCS, SNAPSHOT_CONTACTS)):
        write_csv(run_dir / "snapshots" / f"discs_{n:04d}.csv", figures.SNAPSHOT_DISC_COLUMNS,
                  [[i, x, y, 1.0, 0, 0, 0, "glass", dx, dy] for i, x, y, dx, dy in discs])
        write_csv(run_dir / "snapshots" / f"contacts_{n:04d}.csv", figures.CONTACT_COLUMNS, contacts)
        for kind in entries:
            entries[kind].append(f'    <DataSet timestep="{t!r}" file="snapshots/{kind}_{n:04d}.vtu"/>')
    for kind, lines in entries.items():
        if kind == "contacts" and not contacts_pvd:
            continue
        (run_dir / f"discharge_{kind}.pvd").write_text(
            '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n'
            + "\n".join(lines) + "\n  </Collection>\n</VTKFile>\n")
    write_csv(run_dir / "removals.csv", figures.REMOVAL_COLUMNS,
              [[t, i, m, 0.0, -90.0, how] for t, i, m, how in REMOVALS])
    write_csv(run_dir / "flow_series.csv", figures.FLOW_COLUMNS,
              [[0.0, 4, 0, 0, 0, 0.0, 9.0, 9.0, 9.0, 3, 2.5],
               [0.05, 3, 1, 5, 10, 0.5, 7.9, 8.8, 7.9, "", ""],
               [0.1, 2, 1, 8, 16, 0.75, 7.0, 8.0, 7.0, 4, 3.0]])
    geometry = {w["name"]: w for w in DISCHARGE_WALLS}
    rows = []
    for t, k in zip(SERIES_TIMES, range(3)):
        for wall, samples in SERIES.items():
            for b, normal in enumerate(samples[k]):
                rows.append([t, wall, b, *bin_geometry(geometry[wall], b), normal * DISC_WEIGHT, 0.0])
    write_csv(run_dir / "wall_series.csv", figures.WALL_SERIES_COLUMNS, rows)
    totals = []
    for t, k in zip(SERIES_TIMES, range(3)):
        for wall, samples in SERIES.items():
            totals.append([t, wall, sum(samples[k]) * DISC_WEIGHT, 0.0, 0.0, 0.0])
        totals += [[t, "L", 0, 0, 0, 0], [t, "R", 0, 0, 0, 0]]
    write_csv(run_dir / "wall_totals_series.csv", figures.WALL_TOTALS_COLUMNS, totals)
    return run_dir


def test_read_pvd_sorts_by_timestep(tmp_path):
    path = tmp_path / "a.pvd"
    path.write_text('<VTKFile><Collection><DataSet timestep="0.1" file="b.vtu"/>'
                    '<DataSet timestep="0" file="a.vtu"/>'
                    '<DataSet timestep="0.049999999999994493" file="c.vtu"/></Collection></VTKFile>')
    assert figures.read_pvd(str(path)) == [(0.0, "a.vtu"), (0.049999999999994493, "c.vtu"),
                                           (0.1, "b.vtu")]
    path.write_text('<VTKFile><Collection><DataSet file="b.vtu"/></Collection></VTKFile>')
    with pytest.raises(SystemExit, match="a.pvd.*timestep"):
        figures.read_pvd(str(path))
    path.write_text("<VTKFile><Collection>")
    with pytest.raises(SystemExit, match="a.pvd.*XML"):
        figures.read_pvd(str(path))


@pytest.mark.parametrize("contacts_pvd", [True, False])
def test_snapshot_index_pairs_csv_twins(tmp_path, contacts_pvd):
    run = make_discharge_run(tmp_path / "run", contacts_pvd=contacts_pvd)
    snaps = figures.snapshot_index(str(run))
    assert [s["t"] for s in snaps] == list(SNAPSHOT_TIMES)
    assert snaps[2]["discs"] == str(run / "snapshots" / "discs_0002.csv")
    assert snaps[2]["contacts"] == str(run / "snapshots" / "contacts_0002.csv")


def test_select_snapshots_takes_the_nearest_once(tmp_path):
    snaps = figures.snapshot_index(str(make_discharge_run(tmp_path / "run")))
    # 0.04 and 0.06 are both nearest to 0.05; 0.2 is nearest to 0.1; -1 to 0.
    picked = figures.select_snapshots(snaps, [0.2, 0.04, 0.06])
    assert [s["t"] for s in picked] == [0.05, 0.1]
    assert [s["t"] for s in figures.select_snapshots(snaps, [-1])] == [0.0]
    assert figures.select_snapshots(snaps) == snaps
    with pytest.raises(SystemExit, match="no discharge snapshots"):
        figures.select_snapshots([], None)


def test_displacement_in_radii():
    discs = {"dx": np.array([3.0, 0.0]), "dy": np.array([4.0, -0.5]), "r": np.array([2.0, 1.0])}
    np.testing.assert_allclose(figures.displacement_radii(discs), [2.5, 0.5])


def test_wall_series_matrix_by_hand():
    # Rows out of order, and the t = 0.2 sample lacks bin 1.
    series = {"t": np.array([0.1, 0.0, 0.0, 0.1, 0.2, 0.0]),
              "wall": np.array(["w", "w", "w", "w", "w", "v"]),
              "bin": np.array([1, 1, 0, 0, 0, 0]),
              "s_mid": np.array([3.0, 3.0, 1.0, 1.0, 1.0, 9.0]),
              "x_mid": np.zeros(6), "y_mid": np.array([7.0, 7.0, 9.0, 9.0, 9.0, 0.0]),
              "depth_mid": np.array([3.0, 3.0, 1.0, 1.0, 1.0, 10.0]),
              "normal": np.array([5.0, 2.0, 4.0, 8.0, 1.0, 99.0]),
              "shear": np.array([0.5, 0.2, 0.4, 0.8, 0.1, 9.9])}
    m = figures.wall_series_matrix(series, "w")
    np.testing.assert_allclose(m["t"], [0.0, 0.1, 0.2])
    np.testing.assert_array_equal(m["bin"], [0, 1])
    np.testing.assert_allclose(m["depth_mid"], [1.0, 3.0])
    np.testing.assert_allclose(m["normal"], [[4, 2], [8, 5], [1, np.nan]])
    np.testing.assert_allclose(m["shear"][1], [0.8, 0.5])
    assert figures.wall_series_matrix(series, "nope") is None


def test_static_ratio_masks_weak_bins():
    normal = [[8.0, 2.0, 1.9, 0.0], [16.0, 1.0, 5.0, 3.0]]
    # Largest static bin 8: a quarter is 2, so bins 0 (8) and 1 (2) are kept, 1.9 and 0 are not.
    ratio, static, keep = figures.static_ratio(normal)
    np.testing.assert_array_equal(keep, [True, True, False, False])
    np.testing.assert_allclose(static, [8, 2, 1.9, 0])
    np.testing.assert_allclose(ratio, [[1, 1, np.nan, np.nan], [2, 0.5, np.nan, np.nan]])
    # With a fifth (1.6) the 1.9 bin is kept too: 5 / 1.9.
    ratio, _, keep = figures.static_ratio(normal, fraction=0.2)
    np.testing.assert_array_equal(keep, [True, True, True, False])
    np.testing.assert_allclose(ratio[1, 2], 5 / 1.9)
    # A wall with no static load has no kept bin.
    ratio, _, keep = figures.static_ratio([[0.0, 0.0], [1.0, 2.0]])
    assert not keep.any() and np.isnan(ratio).all()


def test_cell_edges():
    np.testing.assert_allclose(figures.cell_edges([0.0, 1.0, 3.0]), [-0.5, 0.5, 2.0, 4.0])
    np.testing.assert_allclose(figures.cell_edges([2.0]), [1.5, 2.5])


def test_flow_fit_line_intercept():
    # From the 5th point on M = 3 + 10 t exactly; the first four are off the line.
    t = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7])
    m = np.array([0.0, 9.0, 1.0, 2.0, 8.0, 9.0, 10.0])
    assert figures.flow_fit_line(t, m, 10.0) == pytest.approx((0.5, 0.7, 3.0))
    assert figures.flow_fit_line(t[:4], m[:4], 10.0) is None
    assert figures.flow_fit_line(t, m, None) is None


def test_flow_series_empty_cells(tmp_path):
    run = make_discharge_run(tmp_path / "run")
    flow = figures.read_csv(str(run / "flow_series.csv"), figures.FLOW_COLUMNS, empty=float("nan"))
    assert np.isnan(flow["arch_crown_y"][1]) and flow["arch_crown_y"][2] == 3.0
    with pytest.raises(SystemExit, match="flow_series.csv.*arch_discs"):
        figures.read_csv(str(run / "flow_series.csv"), figures.FLOW_COLUMNS)


def test_discharge_frames(tmp_path, monkeypatch):
    kept = capture_figures(monkeypatch)
    run = make_discharge_run(tmp_path / "run")
    out = tmp_path / "frames.png"
    assert figures.plot_discharge_frames(str(run), str(out), ncols=2) == str(out)
    assert_png(out)
    fig = kept[0]
    panels = [ax for ax in fig.axes if ax.get_title().startswith("t = ")]
    assert [ax.get_title() for ax in panels] == ["t = 0.00 s", "t = 0.05 s", "t = 0.10 s"]
    assert "tiny discharge" in fig._suptitle.get_text() and "funnel" in fig._suptitle.get_text()
    assert "jammed" in fig._suptitle.get_text()
    for ax, contacts in zip(panels, SNAPSHOT_CONTACTS):
        # Forces at plot_network's scale (r_ref = radius of disc 0 = 1).
        lines = [c for c in ax.collections if isinstance(c, figures.LineCollection)]
        expected = figures.network_segments(
            {k: np.array([row[n] for row in contacts], dtype=float)
             for n, k in enumerate(figures.CONTACT_COLUMNS) if k in ("x", "y", "nx", "ny", "e_n", "e_s")},
            1.0, DISC_WEIGHT)
        np.testing.assert_allclose(np.array(lines[0].get_segments()).reshape(-1, 2, 2), expected)
        # The gate (3,0)-(5,0) is open: no solid line along it (the slit-end dots are markers).
        for line in ax.get_lines():
            if line.get_linestyle() == "-":
                assert not (list(line.get_xdata()) == [3, 5] and list(line.get_ydata()) == [0, 0])
        assert ax.get_ylim()[0] <= -2.0                 # down to the outlet
    # Dead discs (moved < 1 radius) grey; at 0.05 s discs 1 (2 radii) and 3 (1.4) are coloured.
    faces = [c for c in panels[1].collections if isinstance(c, figures.EllipseCollection)][0]
    grey = matplotlib.colors.to_rgba("0.88")
    is_grey = [tuple(f) == grey for f in faces.get_facecolors()]
    assert is_grey == [True, False, True, False]
    # Only the snapshots nearest the asked times.
    figures.plot_discharge_frames(str(run), str(out), times=[0.09])
    assert [ax.get_title() for ax in kept[1].axes if ax.get_title().startswith("t = ")] == ["t = 0.10 s"]


def test_wall_ratio_heat_maps(tmp_path, monkeypatch):
    kept = capture_figures(monkeypatch)
    run = make_discharge_run(tmp_path / "run")
    out = tmp_path / "ratios.png"
    figures.plot_wall_ratios(str(run), str(out))
    assert_png(out)
    fig = kept[0]
    strips = [ax for ax in fig.axes if ax.collections and "per bin" in ax.get_title(loc="left")]
    assert len(strips) == 3                                   # left, right, bottom walls
    # Left wall: static [0, 8, 2, 1.9, 10]; a quarter of 10 is 2.5, so bins 1 (8) and 4 (10)
    # are kept: ratios over time [1, 2, 0.5] and [1, 3, 0]; 0 is clipped to 0.1.
    mesh = strips[0].collections[0]
    values = np.ma.masked_invalid(mesh.get_array()).reshape(5, 3)    # (bin, time)
    expected = np.ma.masked_invalid(np.log10(np.array(
        [[np.nan] * 3, [1, 2, 0.5], [np.nan] * 3, [np.nan] * 3, [1, 3, 0.1]])))
    np.testing.assert_array_equal(np.ma.getmaskarray(values), np.ma.getmaskarray(expected))
    np.testing.assert_allclose(values.compressed(), expected.compressed())
    assert "max 3\u00d7 at t = 0.050 s" in strips[0].get_title(loc="left")
    # Bottom walls: the gate is left out, bottom_left and bottom_right are drawn.
    assert len(strips[2].collections) == 2
    assert "gate" not in strips[2].get_title(loc="left").replace("gate left out", "")
    assert "bottom_left: max 3\u00d7" in strips[2].get_title(loc="left")
    # Totals: one line per wall (gate left out), ratio to the first sample.
    totals = fig.axes[3]
    labels = [line.get_label() for line in totals.get_lines() if not line.get_label().startswith("_")]
    assert labels == ["left (max 2.37)", "right (max 1.25)", "bottom_left (max 1.75)",
                      "bottom_right (max 1)"]
    left = totals.get_lines()[0]
    # static 0 + 8 + 2 + 1.9 + 10 = 21.9; later 52 and 10
    np.testing.assert_allclose(left.get_ydata(), [1, 52 / 21.9, 10 / 21.9])
    title = fig._suptitle.get_text()
    assert "bottom 3 (windowed 2.25), side 2 (windowed 1.5)" in title


def test_flow_figure(tmp_path, monkeypatch):
    kept = capture_figures(monkeypatch)
    run = make_discharge_run(tmp_path / "run")
    out = tmp_path / "flow.png"
    figures.plot_flow(str(run), str(out))
    assert_png(out)
    ax = kept[0].axes[0]
    lines = {line.get_label(): line for line in ax.get_lines()}
    keystone = lines["keystone removed by hand (1)"]
    np.testing.assert_allclose(keystone.get_xdata(), [0.08])
    np.testing.assert_allclose(keystone.get_ydata(), [12.0])          # 6th removal, 6 x 2 g
    # Fit: slope 40 through the 5th removal on: t = .05,.08,.09,.095, M = 10,12,14,16.
    fit = [line for label, line in lines.items() if label.startswith("fit: 40 g/s")][0]
    b = np.mean([10, 12, 14, 16]) - 40 * np.mean([0.05, 0.08, 0.09, 0.095])
    np.testing.assert_allclose(fit.get_xdata(), [0.05, 0.095])
    np.testing.assert_allclose(fit.get_ydata(), [b + 40 * 0.05, b + 40 * 0.095])
    surfaces = kept[0].axes[2]
    labels = [line.get_label() for line in surfaces.get_lines() if not line.get_label().startswith("_")]
    assert labels == ["left: sinks at 0.05 s", "centre: does not sink", "right: sinks at 0.05 s"]
    assert "8 of 4 discs out (1 by hand), 1 jams" in kept[0]._suptitle.get_text()


def test_discharge_cli(tmp_path):
    run = str(make_discharge_run(tmp_path / "run"))
    for args in (["frames", run, "--times", "0", "0.1", "--ncols", "1"], ["ratios", run],
                 ["flow", run]):
        out = tmp_path / f"{args[0]}.png"
        done = subprocess.run([sys.executable, "-m", "dem.compare.figures", *args, "--out", str(out)],
                              cwd=REPO_ROOT, capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        assert_png(out)
    outdir = tmp_path / "all"
    done = subprocess.run([sys.executable, "-m", "dem.compare.figures", "discharge", run,
                           "--outdir", str(outdir)], cwd=REPO_ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    for name in ("frames.png", "wall_ratios.png", "flow.png"):
        assert_png(outdir / name)


def test_discharge_figures_need_a_discharge_run(tmp_path):
    run = str(make_run(tmp_path / "static"))
    for plot in (figures.plot_discharge_frames, figures.plot_wall_ratios, figures.plot_flow):
        with pytest.raises(SystemExit, match="summary.json.*not a discharge run"):
            plot(run, str(tmp_path / "x.png"))


def test_figures_are_written_in_the_format_their_suffix_names(tmp_path):
    run = make_run(tmp_path / "run")
    figures.plot_network(str(run), str(tmp_path / "network.pdf"))
    assert (tmp_path / "network.pdf").read_bytes()[:5] == b"%PDF-"
    figures.plot_network(str(run), str(tmp_path / "network.svg"))
    assert b"<svg" in (tmp_path / "network.svg").read_bytes()[:400]
    with pytest.raises(ValueError, match="png, .pdf or .svg"):
        figures.plot_network(str(run), str(tmp_path / "network.jpeg"))
    assert not list(tmp_path.glob("network.jpeg*"))


def _figure(transparent):
    """A small figure with lines, a filled area, text and a colour map (drawn the same each call)."""
    fig, ax = figures.plt.subplots(figsize=(3, 2))
    x = np.linspace(0, 1, 50)
    ax.plot(x, np.sin(6 * x), color="tab:blue")
    ax.fill_between(x, 0, x, color="tab:orange", alpha=0.5)
    ax.imshow(np.outer(x, x), extent=(0, 0.3, 0, 0.3), cmap="viridis")
    ax.set_title("t = 0.10 s")
    if transparent:
        fig.patch.set_alpha(0.0)
        ax.patch.set_alpha(0.0)
    return fig


@pytest.mark.parametrize("transparent", [False, True])
def test_png_has_the_pixels_of_savefig(tmp_path, transparent):
    """_save writes the pixels matplotlib's own savefig writes at 150 dpi (its alpha kept), and
    leaves no temporary file."""
    from PIL import Image
    ours = figures._save(_figure(transparent), str(tmp_path / "ours.png"))
    fig = _figure(transparent)
    fig.savefig(tmp_path / "theirs.png", dpi=150)
    figures.plt.close(fig)
    a, b = Image.open(ours), Image.open(tmp_path / "theirs.png")
    assert a.size == b.size == (3 * 150, 2 * 150)
    np.testing.assert_array_equal(np.asarray(a.convert("RGBA")), np.asarray(b.convert("RGBA")))
    assert (np.asarray(a.convert("RGBA"))[..., 3] < 255).any() == transparent
    assert not list(tmp_path.glob("*.tmp"))


def _text_boxes(fig):
    """Window extents of the figure's title and its axes' titles, tick labels and axis labels."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    texts = [fig._suptitle] if fig._suptitle is not None else []
    for ax in fig.axes:
        if not ax.axison:
            continue
        texts += [ax.title, ax._left_title, ax.xaxis.label, ax.yaxis.label]
        for axis in (ax.xaxis, ax.yaxis):           # the ticks drawn: those inside the view limits
            texts += [tick.label1 for tick in axis._update_ticks()] + [tick.label2 for tick in axis._update_ticks()]
    return [(t.get_text(), t.get_window_extent(renderer)) for t in texts if t.get_visible() and t.get_text()]


@pytest.mark.parametrize("plot", ["frames", "ratios", "flow"])
def test_fixed_layouts_keep_the_titles_inside_and_apart(tmp_path, monkeypatch, plot):
    """The discharge figures' fixed layouts: every title and label lies inside the figure, and the
    figure's title overlaps no axes title, also when it is long enough to be wrapped."""
    kept = capture_figures(monkeypatch)
    run = make_discharge_run(tmp_path / "run", name="a discharge scene with a name long enough " * 3)
    {"frames": figures.plot_discharge_frames, "ratios": figures.plot_wall_ratios,
     "flow": figures.plot_flow}[plot](str(run), str(tmp_path / "x.png"))
    fig = kept[0]
    width, height = fig.canvas.get_width_height()
    boxes = _text_boxes(fig)
    for text, box in boxes:
        assert box.x0 >= -1 and box.x1 <= width + 1 and box.y0 >= -1 and box.y1 <= height + 1, text
    head = fig._suptitle.get_window_extent(fig.canvas.get_renderer())
    assert "\n" in fig._suptitle.get_text()             # the long name wrapped the title
    for ax in fig.axes:
        for title in (ax.title, ax._left_title):
            if title.get_text():
                assert not head.overlaps(title.get_window_extent(fig.canvas.get_renderer())), title.get_text()


# --------------------------------------------------------------------------- discs at their pixels

# A figure of 4 x 3 inches laid out by _fixed_layout: the axes span 1..3.5 inches across and
# 0.5..2.5 inches up, and show X 0..10, Y 0..8 (no equal aspect: the box is the layout's).
LAYOUT = {"size": (4.0, 3.0), "left": 1.0, "right": 0.5, "bottom": 0.5, "top": 0.5, "xlim": (0.0, 10.0),
          "ylim": (0.0, 8.0)}
FACE = (0.8, 0.2, 0.1, 1.0)


def _disc_png(path, x, y, r):
    """One disc (face FACE, edge grey) drawn by _draw_discs in the LAYOUT figure, saved by _save."""
    fig, ax = figures.plt.subplots(figsize=LAYOUT["size"])
    figures._fixed_layout(fig, LAYOUT["left"], LAYOUT["right"], LAYOUT["bottom"], LAYOUT["top"])
    ax.set_xlim(*LAYOUT["xlim"])
    ax.set_ylim(*LAYOUT["ylim"])
    figures._draw_discs(ax, {"x": np.array([x]), "y": np.array([y]), "r": np.array([r])}, [FACE], "0.5", 0.3)
    return figures._save(fig, str(path))


def _pixel_of(x, y):
    """The PNG's (row, column) of data point (x, y) from LAYOUT alone, at the saved 150 dpi."""
    dpi, (w, h) = figures.SAVE_DPI, LAYOUT["size"]
    (x0, x1), (y0, y1) = LAYOUT["xlim"], LAYOUT["ylim"]
    box_w, box_h = w - LAYOUT["left"] - LAYOUT["right"], h - LAYOUT["bottom"] - LAYOUT["top"]
    px = (LAYOUT["left"] + (x - x0) / (x1 - x0) * box_w) * dpi
    py = (LAYOUT["bottom"] + (y - y0) / (y1 - y0) * box_h) * dpi      # up from the bottom edge
    return int(h * dpi - py), int(px)


def _check_disc_pixels(png, x, y, r):
    """The disc's face colour at its centre and half a radius from it (4 ways); the white axes
    background one radius and a half away (4 ways)."""
    from PIL import Image
    pixels = np.asarray(Image.open(png).convert("RGB")).astype(int)
    face = np.round(np.array(FACE[:3]) * 255)
    for dx, dy in ((0, 0), (0.5, 0), (-0.5, 0), (0, 0.5), (0, -0.5)):
        row, col = _pixel_of(x + dx * r, y + dy * r)
        assert np.abs(pixels[row, col] - face).max() <= 2, (dx, dy, pixels[row, col])
    for dx, dy in ((1.5, 0), (-1.5, 0), (0, 1.5), (0, -1.5)):
        row, col = _pixel_of(x + dx * r, y + dy * r)
        assert (pixels[row, col] == 255).all(), (dx, dy, pixels[row, col])


def test_a_disc_lies_at_the_pixels_the_layout_gives(tmp_path):
    """A disc drawn by _draw_discs and written by _save covers the pixels that the fixed layout
    (margins in inches, the axes' limits, 150 dpi) maps it to, and no others nearby."""
    for x, y, r in ((2.0, 6.0, 0.8), (7.5, 2.5, 1.0)):
        _check_disc_pixels(_disc_png(tmp_path / "disc.png", x, y, r), x, y, r)


@pytest.mark.parametrize("wrong", ["y flipped", "one radius off in x"])
def test_the_disc_pixel_check_fails_a_misplaced_disc(tmp_path, wrong):
    """The check above fails a picture whose disc is drawn mirrored in Y (an image row order
    turned over) or one radius off in X (an extent off by one radius)."""
    x, y, r = 2.0, 6.0, 0.8
    drawn = (x, LAYOUT["ylim"][1] - y, r) if wrong == "y flipped" else (x + r, y, r)
    png = _disc_png(tmp_path / "disc.png", *drawn)
    with pytest.raises(AssertionError):
        _check_disc_pixels(png, x, y, r)


def test_an_unknown_figure_suffix_is_refused_with_the_known_ones(tmp_path):
    """No traceback: exit 2 naming the suffix and the known ones, nothing written."""
    p = subprocess.run([sys.executable, "-m", "dem.compare.figures", "network", str(tmp_path / "no_run"), "--out",
                        str(tmp_path / "x.xyz")], capture_output=True, text=True, cwd=Path(__file__).resolve().parents[2])
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert "'.xyz'" in p.stderr and ".png, .pdf, .svg" in p.stderr and not list(tmp_path.iterdir())

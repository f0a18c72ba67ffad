"""Tests of compare.figures on synthetic run directories written as docs/outputs.md describes."""
import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import matplotlib.image

from compare import figures

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
        done = subprocess.run([sys.executable, "-m", "compare.figures", *args, "--out", str(out)],
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

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
    for args in (["network", run], ["profiles", run, run, "--labels", "x", "y"], ["bottom", run]):
        out = tmp_path / f"{args[0]}.png"
        done = subprocess.run([sys.executable, "-m", "compare.figures", *args, "--out", str(out)],
                              cwd=REPO_ROOT, capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        assert_png(out)


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
        figures.plot_side_profiles([str(run)], str(tmp_path / "x.png"))
    with open(run / "contacts.csv", "a") as f:
        f.write("dd,0,1,oops,0,1,0,1,0,1,0\n")
    with pytest.raises(SystemExit, match="contacts.csv.*'x'"):
        figures.plot_network(str(run), str(tmp_path / "x.png"))

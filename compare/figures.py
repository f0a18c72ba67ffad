"""Figures of dem run directories, after Kiyama & Fujimura (1982).

The file formats read here are those of docs/outputs.md:

- ``network``:  the contact-force network of one run (the paper's Fig. 6): every contact is one
  segment centred on the contact point, along the elastic resultant e_n n + e_s t, whose length
  is the resultant's size at the paper's scale (one disc diameter = 50/pi disc weights);
- ``profiles``: side-wall normal force and wall friction per depth bin for several runs (Fig. 7);
- ``bottom``:   bottom-wall normal force per bin against X for one run.

Usage, from the repository root::

    /usr/bin/python3 -m compare.figures network RUN_DIR --out network.png
    /usr/bin/python3 -m compare.figures profiles RUN_DIR [RUN_DIR ...] --out side.png
    /usr/bin/python3 -m compare.figures bottom RUN_DIR --out bottom.png
"""

import argparse
import csv
import json
import math
import os

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)
from matplotlib.collections import EllipseCollection, LineCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

# The paper's plot scale: one disc diameter stands for 50/pi (about 16) disc weights.
DIAMETER_IN_DISC_WEIGHTS = 50.0 / math.pi

CONTACT_COLUMNS = ("kind", "i", "j", "x", "y", "nx", "ny", "e_n", "e_s", "f_n", "f_s")
DISC_COLUMNS = ("id", "x", "y", "r", "vx", "vy", "omega", "material")
PROFILE_COLUMNS = ("wall", "group", "bin", "s_lo", "s_hi", "x_mid", "y_mid", "depth_mid",
                   "normal", "shear", "contacts")
TEXT_COLUMNS = {"kind", "j", "wall", "group", "material"}   # kept as str
INT_COLUMNS = {"i", "id", "bin", "contacts"}                 # converted to int

# Line styles of the separate side walls in the profile figure.
SIDE_STYLES = {"side_left": "--", "side_right": ":"}


def _fail(path, message):
    """Stop with a message that names the offending file."""
    raise SystemExit(f"compare.figures: {path}: {message}")


# --------------------------------------------------------------------------- reading


def read_csv(path, columns):
    """Read a CSV file with the given columns into a dict of numpy arrays.

    A header row naming exactly ``columns`` is skipped if present. Columns in TEXT_COLUMNS
    stay strings, INT_COLUMNS become int, the others float. An empty file (or a header
    alone) gives arrays of length 0.
    """
    if not os.path.isfile(path):
        _fail(path, "file is missing")
    with open(path, newline="") as f:
        rows = [(n, [c.strip() for c in row]) for n, row in enumerate(csv.reader(f), 1) if row]
    if rows and rows[0][1] == list(columns):
        rows = rows[1:]
    data = {}
    for k, name in enumerate(columns):
        values = []
        for line, row in rows:
            if len(row) != len(columns):
                _fail(path, f"line {line}: expected {len(columns)} fields "
                            f"({','.join(columns)}), found {len(row)}")
            cell = row[k]
            if name not in TEXT_COLUMNS:
                try:
                    cell = int(cell) if name in INT_COLUMNS else float(cell)
                except ValueError:
                    _fail(path, f"line {line}: column '{name}' is not a number: {cell!r} "
                                f"(expected header {','.join(columns)})")
            values.append(cell)
        dtype = str if name in TEXT_COLUMNS else int if name in INT_COLUMNS else float
        data[name] = np.array(values, dtype=dtype)
    return data


def read_summary(path):
    """Read summary.json and check the few keys the figures need."""
    if not os.path.isfile(path):
        _fail(path, "file is missing")
    try:
        with open(path) as f:
            summary = json.load(f)
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        _fail(path, f"not valid JSON: {err}")
    if not isinstance(summary, dict):
        _fail(path, "expected a JSON object")
    weight = summary.get("disc_weight")
    if not isinstance(weight, (int, float)) or not weight > 0:
        _fail(path, f"'disc_weight' must be a positive number, found {weight!r}")
    walls = summary.get("walls")
    if not isinstance(walls, list):
        _fail(path, "'walls' must be a list")
    for w in walls:
        if not (isinstance(w, dict) and len(w.get("from", ())) == 2 and len(w.get("to", ())) == 2):
            _fail(path, f"wall without 'from'/'to' points: {w!r}")
    return summary


def load_run(run_dir, parts=("contacts", "discs", "profiles")):
    """Load one run directory.

    Returns a dict with ``dir``, ``summary`` (summary.json) and, for each name in ``parts``,
    ``contacts`` (contacts.csv), ``discs`` (discs.csv), ``profiles`` (wall_profiles.csv)
    as dicts of numpy arrays keyed by column name; parts not asked for are None.
    A missing or malformed file stops with SystemExit naming it.
    """
    files = {"contacts": ("contacts.csv", CONTACT_COLUMNS),
             "discs": ("discs.csv", DISC_COLUMNS),
             "profiles": ("wall_profiles.csv", PROFILE_COLUMNS)}
    run = {"dir": run_dir, "summary": read_summary(os.path.join(run_dir, "summary.json"))}
    for part, (name, columns) in files.items():
        run[part] = read_csv(os.path.join(run_dir, name), columns) if part in parts else None
    return run


def scene_name(summary):
    """The scene's name from summary.json, or '?'."""
    scene = summary.get("scene")
    return str(scene.get("name", "?")) if isinstance(scene, dict) else "?"


# --------------------------------------------------------------------------- pure maths


def network_segments(contacts, r_ref, disc_weight):
    """Segments of the contact-force plot, an (n, 2, 2) array [contact, end, xy].

    Each segment is centred on the contact point (x, y) and lies along the elastic resultant
    e_n n + e_s t with t = (-ny, nx); its length is 2 r_ref |(e_n, e_s)| / ((50/pi) disc_weight),
    i.e. one disc diameter (2 r_ref) stands for 50/pi disc weights.
    """
    x, y, nx, ny, en, es = (np.asarray(contacts[k], dtype=float)
                            for k in ("x", "y", "nx", "ny", "e_n", "e_s"))
    half = r_ref / (DIAMETER_IN_DISC_WEIGHTS * disc_weight)   # half length per unit force
    fx = en * nx - es * ny
    fy = en * ny + es * nx
    centre = np.stack([x, y], axis=-1)
    d = half * np.stack([fx, fy], axis=-1)
    return np.stack([centre - d, centre + d], axis=1)


def reference_radius(discs):
    """Radius of disc 0 (the disc whose weight is summary.json's disc_weight).

    If disc 0 is no longer in discs.csv (removed below the slit), the first row is used.
    """
    ids, r = discs["id"], discs["r"]
    if len(r) == 0:
        return None
    zero = np.nonzero(ids == 0)[0]
    return float(r[zero[0]] if len(zero) else r[0])


def point_positions(summary, contacts):
    """Positions of the point contacts (slit ends) as {name: (x, y)}.

    summary.json's points carry no position in docs/outputs.md, so a position key
    ('at', 'pos', 'position' or 'xy') is used if present, else the contact point of a
    'dp' contact with that point (which is the point itself). Points without either are left out.
    """
    found = {}
    for p in summary.get("points") or []:
        for key in ("at", "pos", "position", "xy"):
            if isinstance(p, dict) and len(p.get(key) or ()) == 2:
                found[p.get("name")] = tuple(map(float, p[key]))
                break
    if contacts is not None:
        for kind, j, x, y in zip(contacts["kind"], contacts["j"], contacts["x"], contacts["y"]):
            if kind == "dp" and j not in found:
                found[j] = (float(x), float(y))
    return found


def side_profile(profiles):
    """Side-wall profile against depth from wall_profiles.csv arrays.

    Uses the walls whose group starts with 'side'. Bins of walls of the same group at the same
    depth are summed; the groups (left, right) are then averaged at each depth.
    Returns a dict: ``depth`` (sorted bin mid-depths), ``normal`` and ``shear`` (group means,
    force per bin), ``groups`` = {group: {"normal": .., "shear": ..}} aligned on ``depth``
    (nan where a group has no bin at that depth), and ``bin_width`` (median s_hi - s_lo).
    Returns None if there is no side wall.
    """
    side = np.char.startswith(profiles["group"].astype(str), "side")
    if not side.any():
        return None
    key = np.round(profiles["depth_mid"][side], 9)
    depth = np.unique(key)
    where = np.searchsorted(depth, key)
    groups = {}
    for g in sorted(set(profiles["group"][side])):
        sel = profiles["group"][side] == g
        sums = {}
        for q in ("normal", "shear"):
            acc = np.zeros(len(depth))
            np.add.at(acc, where[sel], profiles[q][side][sel])
            seen = np.zeros(len(depth), dtype=bool)
            seen[where[sel]] = True
            sums[q] = np.where(seen, acc, np.nan)
        groups[g] = sums
    mean = {q: np.nanmean(np.array([groups[g][q] for g in groups]), axis=0)
            for q in ("normal", "shear")}
    width = float(np.median(np.abs(profiles["s_hi"][side] - profiles["s_lo"][side])))
    return {"depth": depth, "normal": mean["normal"], "shear": mean["shear"],
            "groups": groups, "bin_width": width}


# --------------------------------------------------------------------------- figures


def _save(fig, out_png):
    """Save a figure as PNG at 150 dpi, creating the folder, and close it."""
    folder = os.path.dirname(out_png)
    if folder:
        os.makedirs(folder, exist_ok=True)
    fig.savefig(out_png, dpi=150)
    plt.close(fig)
    return out_png


def plot_network(run_dir, out_png, title=None):
    """Contact-force network of one run in the style of the paper's Fig. 6.

    Walls are thick black lines, point contacts black dots, discs thin grey circles of their
    true radius, contacts dark red segments from network_segments().
    """
    run = load_run(run_dir, parts=("contacts", "discs"))
    summary, discs, contacts = run["summary"], run["discs"], run["contacts"]
    weight = summary["disc_weight"]
    r_ref = reference_radius(discs)
    if r_ref is None:
        _fail(os.path.join(run_dir, "discs.csv"), "no discs: the plot scale needs disc 0")
    segments = network_segments(contacts, r_ref, weight)
    points = point_positions(summary, contacts)

    # Drawing bounds: walls, points and discs.
    xs = [c[0] for w in summary["walls"] for c in (w["from"], w["to"])] + [p[0] for p in points.values()]
    ys = [c[1] for w in summary["walls"] for c in (w["from"], w["to"])] + [p[1] for p in points.values()]
    if len(discs["r"]):
        xs += [np.min(discs["x"] - discs["r"]), np.max(discs["x"] + discs["r"])]
        ys += [np.min(discs["y"] - discs["r"]), np.max(discs["y"] + discs["r"])]
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    pad = 0.04 * max(x1 - x0, y1 - y0, 1e-9)
    x0, x1, y0, y1 = x0 - pad, x1 + pad, y0 - pad, y1 + pad
    aspect = (y1 - y0) / (x1 - x0)
    fig, ax = plt.subplots(figsize=(7.0, min(max(7.0 * aspect, 3.0), 14.0) + 0.9))

    if len(discs["r"]):
        ax.add_collection(EllipseCollection(
            2 * discs["r"], 2 * discs["r"], np.zeros(len(discs["r"])), units="xy",
            offsets=np.column_stack([discs["x"], discs["y"]]), offset_transform=ax.transData,
            facecolors="none", edgecolors="0.6", linewidths=0.5))
    ax.add_collection(LineCollection(segments, colors="darkred", linewidths=1.2))
    for w in summary["walls"]:
        ax.plot([w["from"][0], w["to"][0]], [w["from"][1], w["to"][1]],
                color="black", linewidth=3, solid_capstyle="round")
    if points:
        px, py = zip(*points.values())
        ax.plot(px, py, "o", color="black", markersize=3)

    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("X [cm]")
    ax.set_ylabel("Y [cm]")
    head = title or (f"{scene_name(summary)}: {len(discs['r'])} discs, "
                     f"t = {float(summary.get('time', float('nan'))):.4g} s")
    ax.set_title(f"{head}\ncontact forces e_n n + e_s t: "
                 f"disc diameter = 50/\u03c0 \u2248 {DIAMETER_IN_DISC_WEIGHTS:.1f} disc weights",
                 fontsize=10)
    fig.tight_layout()
    return _save(fig, out_png)


def plot_side_profiles(run_dirs, out_png, labels=None):
    """Side-wall normal force and wall friction per depth bin for several runs (Fig. 7).

    Left panel: normal force per bin (mean of left and right side walls) in disc weights;
    right panel: shear (wall friction, positive = discs drag the wall down) per bin. Depth
    increases downward. Where left and right differ by more than 5 % of the largest mean
    normal force, each side is also drawn thin (left dashed, right dotted).
    """
    if labels is not None and len(labels) != len(run_dirs):
        raise SystemExit(f"compare.figures: {len(labels)} labels for {len(run_dirs)} runs")
    fig, (axn, axs) = plt.subplots(1, 2, sharey=True, figsize=(11, 7))
    colours = plt.cm.viridis(np.linspace(0.0, 0.9, max(len(run_dirs), 1)))
    widths, split_drawn = set(), set()
    for k, run_dir in enumerate(run_dirs):
        run = load_run(run_dir, parts=("profiles",))
        weight = run["summary"]["disc_weight"]
        prof = side_profile(run["profiles"])
        if prof is None:
            _fail(os.path.join(run_dir, "wall_profiles.csv"),
                  "no wall whose group starts with 'side'")
        widths.add(round(prof["bin_width"], 6))
        label = labels[k] if labels else scene_name(run["summary"])
        scale = np.nanmax(np.abs(prof["normal"])) if len(prof["depth"]) else 0.0
        for ax, q in ((axn, "normal"), (axs, "shear")):
            ax.plot(prof[q] / weight, prof["depth"], "-o", color=colours[k], markersize=3,
                    linewidth=1.6, label=label if q == "normal" else None)
            sides = [prof["groups"][g][q] for g in prof["groups"]]
            differ = len(sides) > 1 and np.nanmax(np.abs(sides[0] - sides[-1]),
                                                  initial=0.0) > 0.05 * scale
            if differ:
                for g, values in prof["groups"].items():
                    style = SIDE_STYLES.get(g, "-.")
                    split_drawn.add((g, style))
                    ax.plot(values[q] / weight, prof["depth"], style, color=colours[k], linewidth=0.8)

    width = "/".join(f"{w:g}" for w in sorted(widths))
    axn.set_xlabel(f"side-wall normal force per {width} cm bin [disc weights]")
    axs.set_xlabel(f"wall friction (shear) per {width} cm bin [disc weights], + = downward")
    axn.set_ylabel("depth below the top of the silo [cm]")
    axs.axvline(0.0, color="black", linewidth=0.8)
    axn.invert_yaxis()
    for ax in (axn, axs):
        ax.grid(True, alpha=0.4)
    handles, names = axn.get_legend_handles_labels()
    for g, style in sorted(split_drawn):
        handles.append(Line2D([], [], color="0.3", linestyle=style, linewidth=0.8))
        names.append(f"{g} alone")
    axn.legend(handles, names, fontsize=8, loc="upper right")
    fig.suptitle("Side walls against depth (cf. Kiyama & Fujimura 1982, Fig. 7)")
    fig.tight_layout()
    return _save(fig, out_png)


def plot_bottom_profile(run_dir, out_png):
    """Normal force per bin on the bottom walls (group 'bottom...') against X, in disc weights."""
    run = load_run(run_dir, parts=("profiles",))
    summary, prof = run["summary"], run["profiles"]
    weight = summary["disc_weight"]
    bottom = np.char.startswith(prof["group"].astype(str), "bottom")
    if not bottom.any():
        _fail(os.path.join(run_dir, "wall_profiles.csv"), "no wall whose group is 'bottom'")
    width = np.abs(prof["s_hi"][bottom] - prof["s_lo"][bottom])
    normal = prof["normal"][bottom] / weight
    fig, ax = plt.subplots(figsize=(9, 4.5))
    ax.bar(prof["x_mid"][bottom], normal, width=0.95 * width, color="steelblue", edgecolor="black",
           linewidth=0.5)
    ax.axhline(0.0, color="black", linewidth=0.8)
    for w in summary["walls"]:       # the bottom walls themselves, so that the slit shows
        if str(w.get("group", "")).startswith("bottom"):
            ax.plot([w["from"][0], w["to"][0]], [0, 0], color="black", linewidth=4,
                    solid_capstyle="butt")
    ax.set_xlabel("X [cm]")
    ax.set_ylabel(f"bottom normal force per {np.median(width):g} cm bin [disc weights]")
    ax.grid(True, axis="y", alpha=0.4)
    total = f"total {normal.sum():.4g} disc weights"
    if isinstance(summary.get("weight"), (int, float)):
        total += f" (fill weighs {summary['weight'] / weight:.4g})"
    ax.set_title(f"{scene_name(summary)}: bottom-wall normal force, {total}", fontsize=10)
    fig.tight_layout()
    return _save(fig, out_png)


# --------------------------------------------------------------------------- command line


def main(argv=None):
    """Command line: network, profiles and bottom subcommands (see the module docstring)."""
    parser = argparse.ArgumentParser(prog="python3 -m compare.figures", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("network", help="contact-force network of one run (Fig. 6)")
    p.add_argument("run_dir")
    p.add_argument("--out", required=True, help="PNG file to write")
    p.add_argument("--title", help="first title line (default: scene, discs, time)")
    p = sub.add_parser("profiles", help="side-wall forces against depth of several runs (Fig. 7)")
    p.add_argument("run_dirs", nargs="+")
    p.add_argument("--out", required=True, help="PNG file to write")
    p.add_argument("--labels", nargs="+", help="one legend label per run (default: scene names)")
    p = sub.add_parser("bottom", help="bottom-wall normal force against X of one run")
    p.add_argument("run_dir")
    p.add_argument("--out", required=True, help="PNG file to write")
    args = parser.parse_args(argv)

    if args.command == "network":
        out = plot_network(args.run_dir, args.out, title=args.title)
    elif args.command == "profiles":
        out = plot_side_profiles(args.run_dirs, args.out, labels=args.labels)
    else:
        out = plot_bottom_profile(args.run_dir, args.out)
    print(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

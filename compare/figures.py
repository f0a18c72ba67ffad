"""Figures of dem run directories, after Kiyama & Fujimura (1982).

The file formats read here are those of docs/outputs.md:

- ``network``:  the contact-force network of one run (the paper's Fig. 6): every contact is one
  segment centred on the contact point, along the elastic resultant e_n n + e_s t, whose length
  is the resultant's size at the paper's scale (one disc diameter = 50/pi disc weights);
- ``grid``:     the networks of several runs side by side in one figure, same scale rule;
- ``profiles``: side-wall normal force and wall friction against depth for several runs
  (Fig. 7): by default one point per side-wall contact (from contacts.csv, as the paper
  plots P_y per contact), or with ``--per bin`` per depth bin of wall_profiles.csv;
- ``bottom``:   bottom-wall normal force per bin against X for one run.

Usage, from the repository root::

    /usr/bin/python3 -m compare.figures network RUN_DIR --out network.png
    /usr/bin/python3 -m compare.figures grid RUN_DIR [RUN_DIR ...] --out grid.png [--labels ...]
    /usr/bin/python3 -m compare.figures profiles RUN_DIR [RUN_DIR ...] --out side.png [--per bin]
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
# Discharge outputs (docs/outputs.md, "Discharge outputs").
SNAPSHOT_DISC_COLUMNS = DISC_COLUMNS + ("dx", "dy")
REMOVAL_COLUMNS = ("t", "id", "mass", "vx", "vy", "how")
FLOW_COLUMNS = ("t", "discs_in_silo", "discs_below", "removed", "removed_mass", "moved_fraction",
                "surface_left", "surface_centre", "surface_right", "arch_discs", "arch_crown_y")
WALL_SERIES_COLUMNS = ("t", "wall", "bin", "s_mid", "x_mid", "y_mid", "depth_mid", "normal",
                       "shear")
WALL_TOTALS_COLUMNS = ("t", "name", "normal", "shear", "fx", "fy")
TEXT_COLUMNS = {"kind", "j", "wall", "group", "material", "how", "name"}   # kept as str
INT_COLUMNS = {"i", "id", "bin", "contacts"}                 # converted to int

# Line styles of the separate side walls in the profile figure.
SIDE_STYLES = {"side_left": "--", "side_right": ":"}
SIDE_MARKERS = {"side_left": "<", "side_right": ">"}

# Side-wall contacts whose depths differ by at most this much [scene length unit] are taken
# to be at the same depth (left and right contacts of one lattice row).
SAME_DEPTH = 1e-6


def _fail(path, message):
    """Stop with a message that names the offending file."""
    raise SystemExit(f"compare.figures: {path}: {message}")


# --------------------------------------------------------------------------- reading


def read_csv(path, columns, empty=None):
    """Read a CSV file with the given columns into a dict of numpy arrays.

    A header row naming exactly ``columns`` is skipped if present. Columns in TEXT_COLUMNS
    stay strings, INT_COLUMNS become int, the others float. An empty file (or a header
    alone) gives arrays of length 0. With ``empty`` given (e.g. nan), an empty cell of a float
    column reads as that value (flow_series.csv leaves the arch columns empty when there is
    no arch); otherwise it is an error.
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
            if name not in TEXT_COLUMNS and empty is not None and cell == "" \
                    and name not in INT_COLUMNS:
                cell = empty
            elif name not in TEXT_COLUMNS:
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


def _cluster(values, tol):
    """Cluster sorted-able values: returns (centres, index of each value's cluster).

    Values are sorted and a new cluster starts where the gap to the previous value exceeds tol;
    a cluster's centre is the mean of its values.
    """
    values = np.asarray(values, dtype=float)
    order = np.argsort(values, kind="stable")
    start = np.ones(len(values), dtype=bool)
    start[1:] = np.diff(values[order]) > tol
    label_sorted = np.cumsum(start) - 1
    where = np.empty(len(values), dtype=int)
    where[order] = label_sorted
    n = int(label_sorted[-1]) + 1 if len(values) else 0
    centres = np.zeros(n)
    np.add.at(centres, where, values)
    return centres / np.maximum(np.bincount(where, minlength=n), 1), where


def side_wall_contacts(summary, contacts, tol=SAME_DEPTH):
    """Side-wall forces per contact against depth, from contacts.csv arrays (Fig. 7 as drawn).

    Uses the ``dw`` contacts whose wall (j) is in a group starting with 'side'. For each:
    depth = top - y, top = the largest Y of the walls' from/to points; normal = f_n (the push
    of the disc on the wall); friction = the component of the force on the wall,
    f_n n + f_s t with t = (-ny, nx), along the wall's unit from -> to direction (side walls run
    top to bottom, so + = the discs drag the wall down).

    Contacts within ``tol`` in depth are at one depth: within one group they are summed, and
    the groups (left, right) are averaged. Returns None if there is no side-wall contact, else
    a dict: ``depth`` (ascending), ``normal`` and ``friction`` (group means, nan-free),
    ``groups`` = {group: {"normal": .., "friction": ..}} aligned on ``depth`` (nan where the
    group has no contact at that depth), ``paired`` (every depth has a contact of every group),
    and ``contacts`` = {group: {"depth", "normal", "friction"}} the raw contacts by depth.
    """
    walls = summary["walls"]
    top = max(float(c[1]) for w in walls for c in (w["from"], w["to"]))
    group_of, direction = {}, {}
    for w in walls:
        g = str(w.get("group", ""))
        if g.startswith("side"):
            a, b = np.asarray(w["from"], float), np.asarray(w["to"], float)
            length = float(np.hypot(*(b - a)))
            if length > 0:
                group_of[str(w.get("name"))] = g
                direction[str(w.get("name"))] = (b - a) / length
    sel = np.array([k == "dw" and j in group_of for k, j in zip(contacts["kind"], contacts["j"])],
                   dtype=bool)
    if not sel.any():
        return None
    names = contacts["j"][sel]
    nx, ny, fn, fs = (np.asarray(contacts[q], float)[sel] for q in ("nx", "ny", "f_n", "f_s"))
    fx, fy = fn * nx - fs * ny, fn * ny + fs * nx          # force on the wall
    ux = np.array([direction[n][0] for n in names])
    uy = np.array([direction[n][1] for n in names])
    friction = fx * ux + fy * uy
    depth_each = top - np.asarray(contacts["y"], float)[sel]
    groups_each = np.array([group_of[n] for n in names])

    depth, where = _cluster(depth_each, tol)
    groups, raw = {}, {}
    for g in sorted(set(groups_each)):
        in_g = groups_each == g
        order = np.argsort(depth_each[in_g], kind="stable")
        raw[g] = {"depth": depth_each[in_g][order], "normal": fn[in_g][order],
                  "friction": friction[in_g][order]}
        seen = np.zeros(len(depth), dtype=bool)
        seen[where[in_g]] = True
        groups[g] = {}
        for q, values in (("normal", fn), ("friction", friction)):
            acc = np.zeros(len(depth))
            np.add.at(acc, where[in_g], values[in_g])
            groups[g][q] = np.where(seen, acc, np.nan)
    stack = {q: np.array([groups[g][q] for g in groups]) for q in ("normal", "friction")}
    paired = bool(np.isfinite(stack["normal"]).all())
    mean = {q: np.nanmean(stack[q], axis=0) for q in stack}   # every depth has >= 1 group
    return {"depth": depth, "normal": mean["normal"], "friction": mean["friction"],
            "groups": groups, "paired": paired, "contacts": raw}


# --------------------------------------------------------------------------- figures


def _save(fig, out_png):
    """Save a figure as PNG at 150 dpi, creating the folder, and close it."""
    folder = os.path.dirname(out_png)
    if folder:
        os.makedirs(folder, exist_ok=True)
    fig.savefig(out_png, dpi=150)
    plt.close(fig)
    return out_png


def network_bounds(run, pad_fraction=0.04):
    """Drawing bounds (x0, x1, y0, y1) of a run's network: walls, point contacts and discs,
    padded by pad_fraction of the larger extent."""
    summary, discs = run["summary"], run["discs"]
    points = point_positions(summary, run["contacts"])
    xs = [c[0] for w in summary["walls"] for c in (w["from"], w["to"])] + [p[0] for p in points.values()]
    ys = [c[1] for w in summary["walls"] for c in (w["from"], w["to"])] + [p[1] for p in points.values()]
    if len(discs["r"]):
        xs += [np.min(discs["x"] - discs["r"]), np.max(discs["x"] + discs["r"])]
        ys += [np.min(discs["y"] - discs["r"]), np.max(discs["y"] + discs["r"])]
    if not xs:
        _fail(run["dir"], "nothing to draw: no walls, points or discs")
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    pad = pad_fraction * max(x1 - x0, y1 - y0, 1e-9)
    return x0 - pad, x1 + pad, y0 - pad, y1 + pad


def _draw_discs(ax, discs, facecolors, edgecolors, linewidth, zorder=1):
    """Discs of their true radius (an EllipseCollection in data units)."""
    ax.add_collection(EllipseCollection(
        2 * discs["r"], 2 * discs["r"], np.zeros(len(discs["r"])), units="xy",
        offsets=np.column_stack([discs["x"], discs["y"]]), offset_transform=ax.transData,
        facecolors=facecolors, edgecolors=edgecolors, linewidths=linewidth, zorder=zorder))


def _draw_walls(ax, walls, linewidth, skip=()):
    """Walls as thick black lines, leaving out those whose name is in ``skip``."""
    for w in walls:
        if w.get("name") in skip:
            continue
        ax.plot([w["from"][0], w["to"][0]], [w["from"][1], w["to"][1]],
                color="black", linewidth=3 * linewidth, solid_capstyle="round")


def _draw_points(ax, points, linewidth):
    """Point contacts ({name: (x, y)}) as black dots."""
    if points:
        px, py = zip(*points.values())
        ax.plot(px, py, "o", color="black", markersize=3 * linewidth)


def draw_network(ax, run, linewidth=1.0):
    """Draw one run's contact-force network (the paper's Fig. 6) on a matplotlib Axes.

    ``run`` is load_run()'s dict with contacts and discs. Walls are thick black lines, point
    contacts black dots, discs thin grey circles of their true radius, contacts dark red
    segments from network_segments() (one disc diameter = 50/pi disc weights, the diameter
    being that of disc 0). ``linewidth`` scales every line width (smaller for small panels).
    Sets equal aspect and the limits of network_bounds(); returns those bounds.
    """
    summary, discs, contacts = run["summary"], run["discs"], run["contacts"]
    r_ref = reference_radius(discs)
    if r_ref is None:
        _fail(os.path.join(run["dir"], "discs.csv"), "no discs: the plot scale needs disc 0")
    segments = network_segments(contacts, r_ref, summary["disc_weight"])
    points = point_positions(summary, contacts)
    x0, x1, y0, y1 = network_bounds(run)

    _draw_discs(ax, discs, "none", "0.6", 0.5 * linewidth)
    ax.add_collection(LineCollection(segments, colors="darkred", linewidths=1.2 * linewidth))
    _draw_walls(ax, summary["walls"], linewidth)
    _draw_points(ax, points, linewidth)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    return x0, x1, y0, y1


def _rest_text(summary):
    """'at rest', 'NOT at rest (status)' or 'rest unknown' from summary.json."""
    rest = summary.get("rest")
    if isinstance(rest, dict) and "reached" in rest:
        if rest["reached"]:
            return "at rest"
        return f"NOT at rest ({summary.get('status', '?')})"
    return "rest unknown"


def plot_network(run_dir, out_png, title=None):
    """Contact-force network of one run in the style of the paper's Fig. 6 (see draw_network)."""
    run = load_run(run_dir, parts=("contacts", "discs"))
    summary, discs = run["summary"], run["discs"]
    x0, x1, y0, y1 = network_bounds(run)
    aspect = (y1 - y0) / (x1 - x0)
    fig, ax = plt.subplots(figsize=(7.0, min(max(7.0 * aspect, 3.0), 14.0) + 0.9))
    draw_network(ax, run)
    ax.set_xlabel("X [cm]")
    ax.set_ylabel("Y [cm]")
    head = title or (f"{scene_name(summary)}: {len(discs['r'])} discs, "
                     f"t = {float(summary.get('time', float('nan'))):.4g} s")
    ax.set_title(f"{head}\ncontact forces e_n n + e_s t: "
                 f"disc diameter = 50/\u03c0 \u2248 {DIAMETER_IN_DISC_WEIGHTS:.1f} disc weights",
                 fontsize=10)
    fig.tight_layout()
    return _save(fig, out_png)


def plot_network_grid(run_dirs, out_png, labels=None, ncols=4):
    """The networks of several runs in one figure, as small multiples (e.g. the eight
    arrangements). Every panel is drawn by draw_network() with the same scale rule (one disc
    diameter = 50/pi disc weights) and titled with its label (default: the scene name) and
    whether summary.json's rest.reached is true; all panels share one length scale.
    """
    if not run_dirs:
        raise SystemExit("compare.figures: grid needs at least one run directory")
    if labels is not None and len(labels) != len(run_dirs):
        raise SystemExit(f"compare.figures: {len(labels)} labels for {len(run_dirs)} runs")
    if ncols < 1:
        raise SystemExit(f"compare.figures: ncols must be >= 1, found {ncols}")
    runs = [load_run(d, parts=("contacts", "discs")) for d in run_dirs]
    bounds = np.array([network_bounds(r) for r in runs])
    span_x = float(np.max(bounds[:, 1] - bounds[:, 0]))
    span_y = float(np.max(bounds[:, 3] - bounds[:, 2]))
    ncols = min(ncols, len(runs))
    nrows = -(-len(runs) // ncols)
    panel = 4.2                                              # inches per panel width
    fig, axes = plt.subplots(nrows, ncols, squeeze=False,
                             figsize=(panel * ncols, panel * min(max(span_y / span_x, 0.4), 2.5)
                                      * nrows + 0.9))
    for k, ax in enumerate(axes.flat):
        if k >= len(runs):
            ax.axis("off")
            continue
        run = runs[k]
        x0, x1, y0, y1 = draw_network(ax, run, linewidth=0.6)
        # Same cm per inch in every panel: centre each run's bounds in the largest span.
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        ax.set_xlim(cx - span_x / 2, cx + span_x / 2)
        ax.set_ylim(cy - span_y / 2, cy + span_y / 2)
        ax.tick_params(labelsize=7)
        label = labels[k] if labels else scene_name(run["summary"])
        rest = _rest_text(run["summary"])
        ax.set_title(f"{label}: {rest}", fontsize=9,
                     color="black" if rest == "at rest" else "firebrick")
    fig.suptitle("Contact forces e_n n + e_s t (cf. Kiyama & Fujimura 1982, Fig. 6): "
                 f"disc diameter = 50/\u03c0 \u2248 {DIAMETER_IN_DISC_WEIGHTS:.1f} disc weights; "
                 "X, Y in cm", fontsize=11)
    fig.tight_layout()
    return _save(fig, out_png)


def plot_side_profiles(run_dirs, out_png, labels=None, per="contact"):
    """Side-wall normal force and wall friction against depth for several runs (Fig. 7).

    per="contact" (default, as the paper plots P_y): one point per side-wall contact, from
    contacts.csv via side_wall_contacts(). Left panel: normal force f_n; right panel: wall
    friction (+ = the discs drag the wall down); both in disc weights, depth increasing
    downward. Left and right contacts at the same depth are averaged and the mean drawn as a
    line with markers; each side is also drawn thin (left dashed, right dotted) where the
    two differ by more than 1 % of the run's largest |mean| of that quantity. If some depth has
    a contact on one side only (left and right rows not level, e.g. a run not at rest), no mean
    is drawn: each side is drawn as its own line with markers (< left, > right).

    per="bin": the former figure, force per depth bin of wall_profiles.csv (mean of the sides).
    """
    if labels is not None and len(labels) != len(run_dirs):
        raise SystemExit(f"compare.figures: {len(labels)} labels for {len(run_dirs)} runs")
    if per == "bin":
        return _plot_side_bins(run_dirs, out_png, labels)
    if per != "contact":
        raise SystemExit(f"compare.figures: per must be 'contact' or 'bin', found {per!r}")
    fig, (axn, axs) = plt.subplots(1, 2, sharey=True, figsize=(11, 7))
    colours = plt.cm.viridis(np.linspace(0.0, 0.9, max(len(run_dirs), 1)))
    split_drawn, unpaired = set(), []
    for k, run_dir in enumerate(run_dirs):
        run = load_run(run_dir, parts=("contacts",))
        weight = run["summary"]["disc_weight"]
        prof = side_wall_contacts(run["summary"], run["contacts"])
        if prof is None:
            _fail(os.path.join(run_dir, "contacts.csv"),
                  "no dw contact with a wall whose group starts with 'side'")
        label = labels[k] if labels else scene_name(run["summary"])
        if not prof["paired"]:
            unpaired.append(label)
        for ax, q in ((axn, "normal"), (axs, "friction")):
            name = label if q == "normal" else None
            if not prof["paired"]:
                for g, raw in prof["contacts"].items():
                    style, marker = SIDE_STYLES.get(g, "-."), SIDE_MARKERS.get(g, "o")
                    split_drawn.add((g, style, marker))
                    ax.plot(raw[q] / weight, raw["depth"], style, marker=marker, color=colours[k], markersize=4,
                            linewidth=1.2, label=name)
                    name = None
                continue
            ax.plot(prof[q] / weight, prof["depth"], "-o", color=colours[k], markersize=3.5,
                    linewidth=1.6, label=name)
            scale = float(np.max(np.abs(prof[q]))) if len(prof[q]) else 0.0
            sides = np.array([prof["groups"][g][q] for g in prof["groups"]])
            differ = len(sides) > 1 and float(np.max(sides.max(axis=0) - sides.min(axis=0))) \
                > 0.01 * scale
            if differ:
                for g, values in prof["groups"].items():
                    style = SIDE_STYLES.get(g, "-.")
                    split_drawn.add((g, style, ""))
                    ax.plot(values[q] / weight, prof["depth"], style, color=colours[k],
                            linewidth=0.8)

    axn.set_xlabel("side-wall normal force per contact [disc weights]")
    axs.set_xlabel("wall friction per contact [disc weights], + = downward")
    axn.set_ylabel("depth below the top of the silo [cm]")
    axs.axvline(0.0, color="black", linewidth=0.8)
    axn.invert_yaxis()
    for ax in (axn, axs):
        ax.grid(True, alpha=0.4)
    handles, names = axn.get_legend_handles_labels()
    for g, style, marker in sorted(split_drawn):
        handles.append(Line2D([], [], color="0.3", linestyle=style, linewidth=0.8,
                              marker=marker or None, markersize=4))
        names.append(f"{g} alone")
    axn.legend(handles, names, fontsize=8, loc="upper right")
    note = ("mean of left and right per contact row; "
            "the paper's Fig. 7 shows P_y per contact")
    if unpaired:
        note += f"\nleft and right rows not level in {', '.join(unpaired)}: sides drawn apart"
    fig.suptitle("Side walls against depth (cf. Kiyama & Fujimura 1982, Fig. 7)\n" + note,
                 fontsize=11)
    fig.tight_layout()
    return _save(fig, out_png)


def _plot_side_bins(run_dirs, out_png, labels):
    """plot_side_profiles(per="bin"): forces per depth bin of wall_profiles.csv.

    Left panel: normal force per bin (mean of left and right side walls) in disc weights;
    right panel: shear (wall friction, positive = discs drag the wall down) per bin. Depth
    increases downward. Where left and right differ by more than 5 % of the largest mean
    normal force, each side is also drawn thin (left dashed, right dotted).
    """
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
    """Command line: network, grid, profiles and bottom subcommands (see the module docstring)."""
    parser = argparse.ArgumentParser(prog="python3 -m compare.figures", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("network", help="contact-force network of one run (Fig. 6)")
    p.add_argument("run_dir")
    p.add_argument("--out", required=True, help="PNG file to write")
    p.add_argument("--title", help="first title line (default: scene, discs, time)")
    p = sub.add_parser("grid", help="contact-force networks of several runs in one figure")
    p.add_argument("run_dirs", nargs="+")
    p.add_argument("--out", required=True, help="PNG file to write")
    p.add_argument("--labels", nargs="+", help="one panel title per run (default: scene names)")
    p.add_argument("--ncols", type=int, default=4, help="panels per row (default 4)")
    p = sub.add_parser("profiles", help="side-wall forces against depth of several runs (Fig. 7)")
    p.add_argument("run_dirs", nargs="+")
    p.add_argument("--out", required=True, help="PNG file to write")
    p.add_argument("--labels", nargs="+", help="one legend label per run (default: scene names)")
    p.add_argument("--per", choices=("contact", "bin"), default="contact",
                   help="one point per side-wall contact (default) or per wall_profiles.csv bin")
    p = sub.add_parser("bottom", help="bottom-wall normal force against X of one run")
    p.add_argument("run_dir")
    p.add_argument("--out", required=True, help="PNG file to write")
    args = parser.parse_args(argv)

    if args.command == "network":
        out = plot_network(args.run_dir, args.out, title=args.title)
    elif args.command == "grid":
        out = plot_network_grid(args.run_dirs, args.out, labels=args.labels, ncols=args.ncols)
    elif args.command == "profiles":
        out = plot_side_profiles(args.run_dirs, args.out, labels=args.labels, per=args.per)
    else:
        out = plot_bottom_profile(args.run_dir, args.out)
    print(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Figures of dem run directories, after Kiyama & Fujimura (1983).

The file formats read here are those of docs/outputs.md:

- ``network``:  the contact-force network of one run (the paper's Fig. 6): every contact is one
  segment centred on the contact point, along the elastic resultant e_n n + e_s t, whose length
  is the resultant's size at the paper's scale (one disc diameter = 50/pi disc weights);
- ``grid``:     the networks of several runs side by side in one figure, same scale rule;
- ``profiles``: side-wall normal force and wall friction against depth for several runs
  (Fig. 7): by default one point per side-wall contact (from contacts.csv, as the paper
  plots P_y per contact), or with ``--per bin`` per depth bin of wall_profiles.csv;
- ``bottom``:   bottom-wall normal force per bin against X for one run;
- ``frames``:   discs (coloured by displacement since opening) and contact forces at the
  discharge snapshots, one panel each (the paper's Figs. 8 and 9);
- ``ratios``:   wall normal force per bin relative to static against time during discharge,
  as heat maps, and the wall totals (the paper's Fig. 10);
- ``flow``:     removed discs, discs in the silo, moved fraction, surface heights and the arch
  against time during discharge;
- ``discharge``: the three discharge figures of one run into one folder;
- ``run``:      the pictures of one run directory, into it: network.png and side_walls.png, and
  for a discharge frames.png, wall_ratios.png and flow.png (the engine writes data only).

Usage, from the repository root::

    /usr/bin/python3 -m dem.compare.figures network RUN_DIR --out network.png
    /usr/bin/python3 -m dem.compare.figures grid RUN_DIR [RUN_DIR ...] --out grid.png [--labels ...]
    /usr/bin/python3 -m dem.compare.figures profiles RUN_DIR [RUN_DIR ...] --out side.png [--per bin]
    /usr/bin/python3 -m dem.compare.figures bottom RUN_DIR --out bottom.png
    /usr/bin/python3 -m dem.compare.figures frames RUN_DIR --out frames.png [--times 0 0.1 ...]
    /usr/bin/python3 -m dem.compare.figures ratios RUN_DIR --out wall_ratios.png
    /usr/bin/python3 -m dem.compare.figures flow RUN_DIR --out flow.png
    /usr/bin/python3 -m dem.compare.figures discharge RUN_DIR --outdir DIR
    /usr/bin/python3 -m dem.compare.figures run RUN_DIR [--wait] [--quiet]

``run --wait``: `dem run --pictures` starts this process with the run, so that Python and
matplotlib are imported while the engine steps; it reads one line on stdin when the run has
ended and draws when the line is ``draw`` (anything else, or the end of stdin: the run did not
end well, nothing is drawn, exit 0). ``--quiet``: the files written are not listed.
"""

import argparse
import math
import os
import sys
import textwrap

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)
from matplotlib.collections import EllipseCollection, LineCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

# Reading and the pure maths (compare/figures/figure_data.py, no matplotlib), re-exported here.
from dem.compare.io import atomic_file  # noqa: E402
from dem.compare.io import run_dir as _run_dir  # noqa: E402,F401
from dem.compare.figures.figure_data import (DIAMETER_IN_DISC_WEIGHTS, PAPER_LAW, SAME_DEPTH, SHARED_LAW,  # noqa: E402,F401
                                 _cluster, _fail, _reading, common_caption, law_name, load_run,
                                 network_segments, point_positions, read_csv, read_summary,
                                 reference_radius, run_caption, scene_name, side_profile,
                                 side_wall_contacts)
# The discharge pictures' data (compare/figures/figure_data.py), re-exported here.
from dem.compare.figures.figure_data import (DEAD_RADII, GATE_NAME, RATIO_LIMITS, STATIC_FRACTION,  # noqa: E402,F401
                                 SURFACE_COLOURS, _discharge_head, _fmt, _rest_text, cell_edges,
                                 discharge_info, displacement_radii, flow_fit_line, gate_name,
                                 network_bounds, read_pvd, select_snapshots, snapshot_index,
                                 static_ratio, wall_series_matrix, discharge_frames, flow_data,
                                 wall_ratio_data, network_title, side_title, frames_title,
                                 ratios_title, flow_title, side_bins_title)
# The columns of the run's files (docs/outputs.md), as compare/io/run_dir.py reads them.
from dem.compare.io.run_dir import (CONTACT_COLUMNS, DISC_COLUMNS, FLOW_COLUMNS, INT_COLUMNS,  # noqa: E402,F401
                             PROFILE_COLUMNS, REMOVAL_COLUMNS, SNAPSHOT_DISC_COLUMNS, TEXT_COLUMNS,
                             WALL_SERIES_COLUMNS, WALL_TOTALS_COLUMNS, RunDir, RunDirError)

# Line styles and markers of the separate side walls in the profile figure (figure_data's).
from dem.compare.figures.figure_data import SIDE_MARKERS, SIDE_STYLES, units_of  # noqa: E402,F401

# --------------------------------------------------------------------------- figures


# The pictures' resolution [dots per inch].
SAVE_DPI = 150
# The formats a figure is written in, by the file's suffix (matplotlib's Agg and vector backends).
FORMATS = {".png": "png", ".pdf": "pdf", ".svg": "svg"}


def _save(fig, out_png):
    """Save a figure at SAVE_DPI in the format its suffix names (.png, .pdf or .svg), creating
    the folder, and close it. The file is written to NAME.tmp in the same folder and renamed when
    complete (a killed run leaves no half file)."""
    fmt = FORMATS.get(os.path.splitext(out_png)[1].lower())
    if fmt is None:
        plt.close(fig)
        raise ValueError(f"{out_png}: a figure is written as .png, .pdf or .svg")
    try:
        with atomic_file.replacing(out_png) as tmp:
            fig.savefig(tmp, dpi=SAVE_DPI, format=fmt)
    finally:
        plt.close(fig)
    return out_png


def _fixed_layout(fig, left, right, bottom, top, wspace=0.0, hspace=0.0):
    """subplots_adjust with the margins and gaps in inches (a layout computed once, in place of
    constrained or tight layout, which measure every text of the figure at each draw). The figures
    laid out so give their axes titles y=1.0: a title whose height is left to matplotlib is moved
    above whatever the axes draw at their top, which measures every tick label at each draw."""
    w, h = fig.get_size_inches()
    gs = fig.axes[0].get_subplotspec().get_gridspec() if fig.axes else None
    ncols, nrows = (gs.ncols, gs.nrows) if gs is not None else (1, 1)
    cell_w = (w - left - right - wspace * (ncols - 1)) / ncols
    cell_h = (h - top - bottom - hspace * (nrows - 1)) / nrows
    fig.subplots_adjust(left=left / w, right=1 - right / w, bottom=bottom / h, top=1 - top / h,
                        wspace=wspace / cell_w if ncols > 1 else 0.0,
                        hspace=hspace / cell_h if nrows > 1 else 0.0)


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


def plot_network(run_dir, out_png, title=None):
    """Contact-force network of one run in the style of the paper's Fig. 6 (see draw_network)."""
    run = load_run(run_dir, parts=("contacts", "discs"))
    summary, discs = run["summary"], run["discs"]
    x0, x1, y0, y1 = network_bounds(run)
    aspect = (y1 - y0) / (x1 - x0)
    fig, ax = plt.subplots(figsize=(7.0, min(max(7.0 * aspect, 3.0), 14.0) + 0.9))
    draw_network(ax, run)
    length = units_of(summary)["length"]
    ax.set_xlabel(f"X [{length}]")
    ax.set_ylabel(f"Y [{length}]")
    title = network_title(summary, discs, title)
    ax.set_title(title, fontsize=10, y=1.0)
    # A fixed layout (inches): the title's lines above, the tick and axis labels.
    _fixed_layout(fig, left=0.65, right=0.2, bottom=0.55, top=0.2 + 0.19 * (title.count("\n") + 1))
    return _save(fig, out_png)


def plot_network_grid(run_dirs, out_png, labels=None, ncols=4):
    """The networks of several runs in one figure, as small multiples (e.g. the eight
    arrangements). Every panel is drawn by draw_network() with the same scale rule (one disc
    diameter = 50/pi disc weights) and titled with its label (default: the scene name) and
    whether summary.json's rest.reached is true; all panels share one length scale.
    """
    if not run_dirs:
        raise SystemExit("dem.compare.figures: grid needs at least one run directory")
    if labels is not None and len(labels) != len(run_dirs):
        raise SystemExit(f"dem.compare.figures: {len(labels)} labels for {len(run_dirs)} runs")
    if ncols < 1:
        raise SystemExit(f"dem.compare.figures: ncols must be >= 1, found {ncols}")
    runs = [load_run(d, parts=("contacts", "discs")) for d in run_dirs]
    bounds = np.array([network_bounds(r) for r in runs])
    span_x = float(np.max(bounds[:, 1] - bounds[:, 0]))
    span_y = float(np.max(bounds[:, 3] - bounds[:, 2]))
    ncols = min(ncols, len(runs))
    nrows = -(-len(runs) // ncols)
    panel = 4.2                                              # inches per panel width
    title = (textwrap.fill(f"Contact forces e_n n + e_s t (cf. Kiyama & Fujimura 1983, Fig. 6), "
                           f"{common_caption([r['summary'] for r in runs])}", int(panel * ncols * 11))
             + f"\ndisc diameter = 50/\u03c0 \u2248 {DIAMETER_IN_DISC_WEIGHTS:.1f} disc weights; X, Y in {units_of(runs[0]['summary'])['length']}")
    top, bottom, hspace = 0.45 + 0.2 * (title.count("\n") + 1), 0.3, 0.45
    fig, axes = plt.subplots(nrows, ncols, squeeze=False,
                             figsize=(panel * ncols, (panel - 0.5) * min(max(span_y / span_x, 0.4), 2.5)
                                      * nrows + top + bottom + hspace * (nrows - 1)))
    # A fixed layout (inches): the title's lines, each panel's title and tick labels.
    _fixed_layout(fig, left=0.4, right=0.15, bottom=bottom, top=top, wspace=0.35, hspace=hspace)
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
                     color="black" if rest == "at rest" else "firebrick", y=1.0)
    fig.suptitle(title, fontsize=11, y=1 - 0.08 / fig.get_size_inches()[1], va="top")
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
        raise SystemExit(f"dem.compare.figures: {len(labels)} labels for {len(run_dirs)} runs")
    if per == "bin":
        return _plot_side_bins(run_dirs, out_png, labels)
    if per != "contact":
        raise SystemExit(f"dem.compare.figures: per must be 'contact' or 'bin', found {per!r}")
    fig, (axn, axs) = plt.subplots(1, 2, sharey=True, figsize=(11, 7))
    colours = plt.cm.viridis(np.linspace(0.0, 0.9, max(len(run_dirs), 1)))
    split_drawn, unpaired, summaries = set(), [], []
    for k, run_dir in enumerate(run_dirs):
        run = load_run(run_dir, parts=("contacts",))
        summaries.append(run["summary"])
        weight = run["summary"]["disc_weight"]
        prof = side_wall_contacts(run["summary"], run["contacts"])
        if prof is None:
            _fail(os.path.join(run_dir, "contacts.csv"),
                  "no dw contact with a wall whose group starts with 'side'")
        label = labels[k] if labels else scene_name(run["summary"])
        if _rest_text(run["summary"]) != "at rest":      # drawn, but never silently
            label += f" ({_rest_text(run['summary'])})"
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
    _finish_side_axes(axn, axs, summaries)
    handles, names = axn.get_legend_handles_labels()
    for g, style, marker in sorted(split_drawn):
        handles.append(Line2D([], [], color="0.3", linestyle=style, linewidth=0.8,
                              marker=marker or None, markersize=4))
        names.append(f"{g} alone")
    axn.legend(handles, names, fontsize=8, loc="upper right")
    title = side_title(summaries, unpaired)
    fig.suptitle(title, fontsize=11, y=1 - 0.1 / fig.get_size_inches()[1], va="top")
    # A fixed layout (inches): the title's lines, the tick and axis labels.
    _fixed_layout(fig, left=0.75, right=0.25, bottom=0.6, top=0.25 + 0.2 * (title.count("\n") + 1),
                  wspace=0.3)
    return _save(fig, out_png)


def _finish_side_axes(axn, axs, summaries):
    """Shared look of the two side-wall panels: depth down, zero line for the friction."""
    axn.set_ylabel(f"depth below the top of the silo [{units_of(summaries[0])['length'] if summaries else 'cm'}]")
    axs.axvline(0.0, color="black", linewidth=0.8)
    axn.invert_yaxis()
    for ax in (axn, axs):
        ax.grid(True, alpha=0.4)


def _plot_side_bins(run_dirs, out_png, labels):
    """plot_side_profiles(per="bin"): forces per depth bin of wall_profiles.csv.

    Left panel: normal force per bin (mean of left and right side walls) in disc weights;
    right panel: shear (wall friction, positive = discs drag the wall down) per bin. Depth
    increases downward. Where left and right differ by more than 5 % of the largest mean
    normal force, each side is also drawn thin (left dashed, right dotted).
    """
    fig, (axn, axs) = plt.subplots(1, 2, sharey=True, figsize=(11, 7))
    colours = plt.cm.viridis(np.linspace(0.0, 0.9, max(len(run_dirs), 1)))
    widths, split_drawn, summaries = set(), set(), []
    for k, run_dir in enumerate(run_dirs):
        run = load_run(run_dir, parts=("profiles",))
        summaries.append(run["summary"])
        weight = run["summary"]["disc_weight"]
        prof = side_profile(run["profiles"])
        if prof is None:
            _fail(os.path.join(run_dir, "wall_profiles.csv"),
                  "no wall whose group starts with 'side'")
        widths.add(round(prof["bin_width"], 6))
        label = labels[k] if labels else scene_name(run["summary"])
        if _rest_text(run["summary"]) != "at rest":
            label += f" ({_rest_text(run['summary'])})"
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
    length = units_of(summaries[0])["length"] if summaries else "cm"
    axn.set_xlabel(f"side-wall normal force per {width} {length} bin [disc weights]")
    axs.set_xlabel(f"wall friction (shear) per {width} {length} bin [disc weights], + = downward")
    _finish_side_axes(axn, axs, summaries)
    handles, names = axn.get_legend_handles_labels()
    for g, style in sorted(split_drawn):
        handles.append(Line2D([], [], color="0.3", linestyle=style, linewidth=0.8))
        names.append(f"{g} alone")
    axn.legend(handles, names, fontsize=8, loc="upper right")
    fig.suptitle(side_bins_title(summaries))
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
    length = units_of(summary)["length"]
    ax.set_xlabel(f"X [{length}]")
    ax.set_ylabel(f"bottom normal force per {np.median(width):g} {length} bin [disc weights]")
    ax.grid(True, axis="y", alpha=0.4)
    total = f"total {normal.sum():.4g} disc weights"
    if isinstance(summary.get("weight"), (int, float)):
        total += f" (fill weighs {summary['weight'] / weight:.4g})"
    ax.set_title(f"{run_caption(summary)}\nbottom-wall normal force, {total}", fontsize=10)
    fig.tight_layout()
    return _save(fig, out_png)


# --------------------------------------------------------------------------- discharge


def plot_discharge_frames(run_dir, out_png, times=None, ncols=5):
    """Disc positions and contact forces at the discharge snapshots (the paper's Figs. 8, 9).

    One panel per snapshot (all, or the nearest to each of ``times``, seconds since opening):
    walls without the gate (open), slit ends, discs coloured by their displacement since
    opening (light grey: less than one radius, 'dead'; log colour scale above), and the
    contact-force segments e_n n + e_s t with plot_network's scale (one diameter of disc 0 =
    50/pi disc weights). All panels share the same limits, which reach down to the outlet
    (summary["discharge"]["outlet_y"], where discs are removed).
    """
    if ncols < 1:
        raise SystemExit(f"dem.compare.figures: ncols must be >= 1, found {ncols}")
    d = discharge_frames(run_dir, times)
    summary, info, frames, r_ref, walls, points = (d[k] for k in ("summary", "info", "frames", "r_ref",
                                                                  "walls", "points"))
    n_initial, outlet_y, pad, top = d["n_initial"], d["outlet_y"], d["pad"], d["top"]
    x0, x1, y0, y1 = d["bounds"]
    weight = summary["disc_weight"]
    norm = matplotlib.colors.LogNorm(DEAD_RADII, max(2.0 * DEAD_RADII, top))
    cmap = matplotlib.colors.LinearSegmentedColormap.from_list(
        "moved", plt.get_cmap("YlOrRd")(np.linspace(0.15, 0.85, 256)))
    dead_colour = matplotlib.colors.to_rgba("0.88")

    ncols = min(ncols, len(frames))
    nrows = -(-len(frames) // ncols)
    panel = 3.2
    aspect = (y1 - y0) / (x1 - x0)
    width = panel * ncols + 1.3
    chars = int(width * 12)                    # characters per title line at 10 pt
    title = frames_title(summary, n_initial, chars)
    # A fixed layout (inches): the title's lines, each panel's title, the tick labels of the
    # outer panels only (all panels share their limits), the colour bar at the right.
    top = 0.15 + 0.19 * (title.count("\n") + 1) + 0.25
    left, bottom, right, gap_w, gap_h = 0.35, 0.3, 1.0, 0.12, 0.34
    fig, axes = plt.subplots(nrows, ncols, squeeze=False, sharex=True, sharey=True,
                             figsize=(width, panel * aspect * nrows + top + bottom + gap_h * (nrows - 1)))
    _fixed_layout(fig, left, right, bottom, top, gap_w, gap_h)
    for axis in (axes[0, 0].xaxis, axes[0, 0].yaxis):     # a few round ticks, shared by all panels
        axis.set_major_locator(matplotlib.ticker.MaxNLocator(nbins=6, steps=[1, 2, 5, 10]))
    lw = 0.55
    for k, ax in enumerate(axes.flat):
        if k >= len(frames):
            ax.axis("off")
            continue
        t, discs, contacts = frames[k]
        moved = displacement_radii(discs)
        dead = moved < DEAD_RADII
        face = np.empty((len(moved), 4))
        face[dead] = dead_colour
        face[~dead] = cmap(norm(moved[~dead]))
        _draw_discs(ax, discs, face, "0.5", 0.4 * lw)
        if contacts is not None:
            ax.add_collection(LineCollection(network_segments(contacts, r_ref, weight),
                                             colors="black", linewidths=1.6 * lw, zorder=3))
        _draw_walls(ax, walls, lw)
        _draw_points(ax, points, lw * 1.5)
        slit = info.get("slit")
        if isinstance(outlet_y, (int, float)) and isinstance(slit, list) and len(slit) == 2:
            ax.plot(slit, [outlet_y, outlet_y], ":", color="0.3", linewidth=1.0)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=6, labelbottom=k // ncols == nrows - 1 or k + ncols >= len(frames),
                       labelleft=k % ncols == 0)
        ax.set_title(f"t = {t:.2f} s", fontsize=10, pad=3, y=1.0)
        ax.text(x0 + pad, y0 + pad, f"{len(moved)} discs, dead {np.sum(dead) / n_initial:.0%}",
                fontsize=6.5, va="bottom", ha="left")
    w, h = fig.get_size_inches()
    cax = fig.add_axes([1 - (right - 0.12) / w, bottom / h + 0.1 * (1 - (top + bottom) / h),
                        0.14 / w, 0.8 * (1 - (top + bottom) / h)])
    bar = fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), cax=cax)
    ticks = [v for v in (1, 2, 3, 5, 10, 20, 30, 50, 100) if norm.vmin <= v <= norm.vmax]
    bar.set_ticks(ticks)
    bar.set_ticklabels([f"{v:g}" for v in ticks])
    bar.ax.minorticks_off()
    bar.set_label("displacement since opening [radii]; grey: < 1 (dead)", fontsize=8)
    bar.ax.tick_params(labelsize=7)
    fig.suptitle(title, fontsize=10, y=1 - 0.12 / h, va="top")
    return _save(fig, out_png)


def _ratio_image(ax, m, ratio, position, log_norm, cmap):
    """Draw one wall's ratio matrix as cells (time x position); returns the QuadMesh."""
    order = np.argsort(position, kind="stable")
    lo, hi = RATIO_LIMITS
    value = np.log10(np.clip(ratio[:, order], lo, hi))
    return ax.pcolormesh(cell_edges(m["t"]), cell_edges(position[order]), value.T,
                         norm=log_norm, cmap=cmap, shading="flat")


def _mark_peak(ax, t, position, ratio):
    """Circle the largest ratio of a matrix; returns a text 'max R at t, position' or ''."""
    if not np.isfinite(ratio).any():
        return "no bin with a static load"
    it, ib = np.unravel_index(np.nanargmax(ratio), ratio.shape)
    ax.plot(t[it], position[ib], "o", markersize=9, markerfacecolor="none",
            markeredgecolor="black", markeredgewidth=1.2)
    return f"max {ratio[it, ib]:.3g}\u00d7 at t = {t[it]:.3f} s"


def plot_wall_ratios(run_dir, out_png, fraction=STATIC_FRACTION):
    """Wall normal force relative to static during discharge (the paper's Fig. 10 analogue).

    Heat maps (time since opening on x) of normal force per bin / its static value (first
    sample, t = 0) from wall_series.csv: one strip per side wall (depth on y, top up) and one
    for the bottom walls without the gate (X on y); log colour scale RATIO_LIMITS, ratio 1
    white; bins whose static value is below ``fraction`` of that wall's largest static bin
    are masked (grey). The largest shown ratio of each strip is circled. Last panel: each
    wall's total normal force (wall_totals_series.csv) / its static total.
    The title quotes summary.json's peak ratios (raw and windowed).
    """
    d = wall_ratio_data(run_dir)
    summary, info, series, totals, sides, bottoms, strips = (
        d[k] for k in ("summary", "info", "series", "totals", "sides", "bottoms", "strips"))

    lo, hi = RATIO_LIMITS
    log_norm = matplotlib.colors.TwoSlopeNorm(vmin=math.log10(lo), vcenter=0.0,
                                              vmax=math.log10(hi))
    cmap = plt.get_cmap("RdBu_r").copy()
    cmap.set_bad("0.72")
    head = ratios_title(summary, info)
    fig, axes = plt.subplots(len(strips) + 1, 1, sharex=True,
                             figsize=(11, 2.7 * len(strips) + 2.9),
                             gridspec_kw={"height_ratios": [3] * len(strips) + [2.3]})
    # A fixed layout (inches): the title's lines, a title above each panel, the colour bar at the
    # right of the heat maps.
    fig_w, fig_h = fig.get_size_inches()
    _fixed_layout(fig, left=0.65, right=1.15, bottom=0.45, top=0.3 + 0.19 * (head.count("\n") + 1), hspace=0.3)
    t_end = 0.0
    for ax, (title, group, coord) in zip(axes, strips):
        notes = []
        for w in group:
            m = wall_series_matrix(series, w["name"])
            if m is None:
                notes.append(f"'{w['name']}' not in wall_series.csv")
                continue
            ratio, _, _ = static_ratio(m["normal"], fraction)
            _ratio_image(ax, m, ratio, m[coord], log_norm, cmap)
            note = _mark_peak(ax, m["t"], m[coord], ratio)
            notes.append(note if len(group) == 1 else f"{w['name']}: {note}")
            t_end = max(t_end, float(m["t"][-1]))
        if coord == "depth_mid":
            ax.invert_yaxis()
            ax.set_ylabel(f"depth [{units_of(summary)['length']}]")
        else:
            ax.set_ylabel(f"X [{units_of(summary)['length']}]")
            slit = info.get("slit")
            if isinstance(slit, list) and len(slit) == 2:
                ax.axhspan(slit[0], slit[1], color="white", zorder=0)
                ax.text(0.005, (slit[0] + slit[1]) / 2, " slit", va="center", fontsize=8,
                        transform=ax.get_yaxis_transform())
        ax.set_title(f"{title}, normal force / static per bin: " + "; ".join(notes),
                     fontsize=9, loc="left", y=1.0)
    y_lo, y_hi = axes[-2].get_position().y0, axes[0].get_position().y1
    cax = fig.add_axes([1 - 1.0 / fig_w, y_lo + 0.05 * (y_hi - y_lo), 0.16 / fig_w, 0.9 * (y_hi - y_lo)])
    bar = fig.colorbar(matplotlib.cm.ScalarMappable(norm=log_norm, cmap=cmap), cax=cax)
    ticks = [r for r in (0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 30) if lo <= r <= hi]
    bar.set_ticks([math.log10(r) for r in ticks])
    bar.set_ticklabels([f"{r:g}" for r in ticks])
    bar.set_label(f"normal / static (clipped to {lo:g}..{hi:g}); grey: static < "
                  f"{fraction:.0%} of the wall's largest bin", fontsize=8)

    ax = axes[-1]
    styles = {"side": "-", "bottom": "--"}
    colours = plt.cm.tab10(np.arange(10))
    for k, w in enumerate(sides + bottoms):
        sel = totals["name"] == w["name"]
        if not sel.any():
            continue
        t, normal = totals["t"][sel], totals["normal"][sel]
        order = np.argsort(t, kind="stable")
        t, normal = t[order], normal[order]
        if not normal[0] > 0:
            continue
        kind = "side" if w in sides else "bottom"
        ax.plot(t, normal / normal[0], styles[kind], color=colours[k % 10], linewidth=1.0,
                label=f"{w['name']} (max {np.max(normal) / normal[0]:.3g})")
        t_end = max(t_end, float(t[-1]))
    ax.axhline(1.0, color="black", linewidth=0.8)
    ax.set_ylabel("wall total / static")
    ax.set_xlabel("time since opening [s]")
    ax.grid(True, alpha=0.4)
    ax.legend(fontsize=8, ncol=4, loc="lower right", bbox_to_anchor=(1.0, 1.0), frameon=False,
              borderaxespad=0.1, handlelength=1.5, columnspacing=1.0, handletextpad=0.4)
    ax.set_title("total normal force on each wall / its static value", fontsize=9, loc="left", y=1.0)
    ax.set_xlim(0.0, t_end if t_end > 0 else 1.0)
    fig.suptitle(head, fontsize=10, y=1 - 0.1 / fig_h, va="top")
    return _save(fig, out_png)


def _removed_panel(ax_out, removals, info, t_end, summary):
    """plot_flow's (a): cumulative removed mass, keystones, the fitted flow line, the first jam."""
    cumulative = np.cumsum(removals["mass"])
    ax_out.step(np.concatenate([[0.0], removals["t"], [t_end]]),
                np.concatenate([[0.0], cumulative, cumulative[-1:] if len(cumulative) else [0]]),
                where="post", color="tab:blue", linewidth=1.4,
                label=f"removed ({len(cumulative)} discs)")
    hand = removals["how"] == "keystone"
    if hand.any():
        ax_out.plot(removals["t"][hand], cumulative[hand], "v", color="firebrick",
                    markersize=8, label=f"keystone removed by hand ({int(hand.sum())})")
    rate = info.get("flow_rate_mass")
    fit = flow_fit_line(removals["t"], cumulative, rate)
    if fit is not None:
        t0, t1, b = fit
        ax_out.plot([t0, t1], [b + rate * t0, b + rate * t1], "--", color="black",
                    linewidth=1.0, label=f"fit: {rate:.4g} {units_of(summary)['mass']}/s per {units_of(summary)['length']} "
                                         f"({_fmt(info.get('flow_rate_discs'))} discs/s)")
    jam = info.get("jam_at")
    if isinstance(jam, (int, float)):
        ax_out.axvline(jam, color="firebrick", linestyle=":", label=f"first jam {jam:.3g} s")
    mass = removals["mass"]
    if len(mass) and np.ptp(mass) <= 1e-9 * abs(mass[0]) and mass[0] > 0:
        unit = float(mass[0])
        sec = ax_out.secondary_yaxis("right", functions=(lambda m: m / unit, lambda n: n * unit))
        sec.set_ylabel("removed discs")
    ax_out.set_ylabel(f"removed mass [{units_of(summary)['mass']} per {units_of(summary)['length']}]")
    ax_out.set_title("(a) discs through the outlet", fontsize=10, loc="left", y=1.0)
    ax_out.legend(fontsize=8, loc="upper left")


def _arch_panel(ax_a, flow, summary):
    """plot_flow's (d): the arch's crown height and its discs against time."""
    ax_a.plot(flow["t"], flow["arch_crown_y"], ".", color="tab:brown", markersize=3,
              label="crown height (left)")
    ax_a.set_ylabel(f"arch crown Y [{units_of(summary)['length']}]")
    ax_a.set_ylim(bottom=0)
    twin = ax_a.twinx()
    twin.plot(flow["t"], flow["arch_discs"], color="0.5", linewidth=0.8,
              drawstyle="steps-post", label="discs in the arch (right)")
    twin.set_ylabel("discs in the arch")
    twin.set_ylim(bottom=0)
    h1, l1 = ax_a.get_legend_handles_labels()
    h2, l2 = twin.get_legend_handles_labels()
    ax_a.legend(h1 + h2, l1 + l2, fontsize=8, loc="upper left")
    ax_a.set_xlabel("time since opening [s]")
    no_arch = float(np.mean(np.isnan(flow["arch_crown_y"]))) if len(flow["t"]) else 0.0
    ax_a.set_title(f"(d) arch from slit end to slit end (none in {no_arch:.0%} of samples)",
                   fontsize=10, loc="left", y=1.0)


def plot_flow(run_dir, out_png):
    """Flow during discharge in four panels against time since opening.

    (a) cumulative removed mass (removals.csv; keystones removed by hand marked) with the
    fitted flow line (slope summary flow_rate_mass, intercept fitted as in flow_fit_line) and,
    when all removed discs weigh the same, a removed-disc count axis; (b) discs in the silo and
    below the floor, and the moved fraction; (c) the three surface heights with the sink times
    (summary surface_sink_time) marked; (d) the arch over the outlet: crown height and discs.
    """
    d = flow_data(run_dir)
    summary, info, removals, flow, t_end = (d[k] for k in ("summary", "info", "removals", "flow", "t_end"))

    title = flow_title(summary, info)
    fig, axes = plt.subplots(2, 2, sharex=True, figsize=(12, 8))
    # A fixed layout (inches): the title's lines, a title above each panel, a right-hand axis on
    # each.
    _fixed_layout(fig, left=0.75, right=0.75, bottom=0.5, top=0.42 + 0.2 * (title.count("\n") + 1),
                  wspace=1.45, hspace=0.45)
    (ax_out, ax_n), (ax_s, ax_a) = axes

    _removed_panel(ax_out, removals, info, t_end, summary)

    present = flow["discs_in_silo"] + flow["discs_below"]
    ax_n.plot(flow["t"], flow["discs_in_silo"], color="tab:blue", label="discs in the silo")
    ax_n.fill_between(flow["t"], flow["discs_in_silo"], present, color="tab:orange",
                      alpha=0.6, linewidth=0, label="+ discs below the floor")
    ax_n.set_ylabel("discs")
    twin = ax_n.twinx()
    twin.plot(flow["t"], flow["moved_fraction"], color="tab:purple", linestyle="--",
              label="moved fraction (right)")
    twin.set_ylim(0, 1.02)
    twin.set_ylabel("moved fraction (moved > 1 radius or removed)")
    h1, l1 = ax_n.get_legend_handles_labels()
    h2, l2 = twin.get_legend_handles_labels()
    ax_n.legend(h1 + h2, l1 + l2, fontsize=8, loc="center left")
    ax_n.set_title(f"(b) discs; dead fraction at the end "
                   f"{_fmt(info.get('dead_fraction_end'), '.2f')}", fontsize=10, loc="left", y=1.0)

    sink = info.get("surface_sink_time") or {}
    for column, key in (("left", "left_wall"), ("centre", "centre"), ("right", "right_wall")):
        when = sink.get(key)
        colour = SURFACE_COLOURS[column]
        label = f"{column}: " + (f"sinks at {when:.3g} s" if isinstance(when, (int, float))
                                 else "does not sink")
        ax_s.plot(flow["t"], flow[f"surface_{column}"], color=colour, linewidth=1.3,
                  label=label, linestyle={"left": "-", "centre": "-", "right": "--"}[column])
        if isinstance(when, (int, float)):
            ax_s.axvline(when, color=colour, linestyle=":", linewidth=1.2)
    ax_s.set_ylabel(f"top surface height Y [{units_of(summary)['length']}]")
    ax_s.set_xlabel("time since opening [s]")
    ax_s.legend(fontsize=8, loc="lower left")
    ax_s.set_title(f"(c) top surface in the wall and centre columns: "
                   f"{info.get('pattern', '?')}", fontsize=10, loc="left", y=1.0)

    _arch_panel(ax_a, flow, summary)
    for ax in axes.flat:
        ax.grid(True, alpha=0.4)
        ax.set_xlim(0.0, t_end)
    fig.suptitle(title, fontsize=11, y=1 - 0.1 / fig.get_size_inches()[1], va="top")
    return _save(fig, out_png)


def plot_discharge(run_dir, outdir):
    """All discharge figures of one run: frames.png, wall_ratios.png and flow.png in outdir."""
    return [plot_discharge_frames(run_dir, os.path.join(outdir, "frames.png")),
            plot_wall_ratios(run_dir, os.path.join(outdir, "wall_ratios.png")),
            plot_flow(run_dir, os.path.join(outdir, "flow.png"))]


def plot_run(run_dir):
    """The pictures of one `dem run` directory, written into it (one process: matplotlib is
    imported once): network.png and side_walls.png; a discharge run adds its three figures.

    A run without contacts.csv (a reference code's, `dem run --engine`: no contact list is read
    back) has no network to draw: it is skipped with a note on stderr, and side_walls.png is
    drawn per bin of wall_profiles.csv; a discharge's frames.png has its discs without forces."""
    if not os.path.exists(os.path.join(run_dir, "contacts.csv")):
        sys.stderr.write(f"dem.compare.figures: {os.path.join(run_dir, 'contacts.csv')}: absent (the run gives no "
                         "contact list): the contact network is skipped; side_walls.png is drawn per "
                         "wall_profiles.csv bin\n")
        out = [plot_side_profiles([run_dir], os.path.join(run_dir, "side_walls.png"), per="bin")]
        if os.path.exists(os.path.join(run_dir, "flow_series.csv")):
            out += plot_discharge(run_dir, run_dir)
        return out
    out = [plot_network(run_dir, os.path.join(run_dir, "network.png"))]
    run = load_run(run_dir, parts=("contacts",))
    if side_wall_contacts(run["summary"], run["contacts"]) is not None:
        out.append(plot_side_profiles([run_dir], os.path.join(run_dir, "side_walls.png")))
    else:  # a discharge that ended with no disc on a side wall: its (empty) profile bins, said so
        sys.stderr.write(f"dem.compare.figures: {run_dir}: no disc touches a side wall at the run's end: "
                         "side_walls.png is drawn per wall_profiles.csv bin\n")
        out.append(plot_side_profiles([run_dir], os.path.join(run_dir, "side_walls.png"), per="bin"))
    if os.path.exists(os.path.join(run_dir, "flow_series.csv")):
        out += plot_discharge(run_dir, run_dir)
    return out


# --------------------------------------------------------------------------- command line


def main(argv=None):
    """Command line: the subcommands of the module docstring."""
    parser = argparse.ArgumentParser(prog="python3 -m dem.compare.figures", description=__doc__,
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
    p = sub.add_parser("frames", help="discs and contact forces at the discharge snapshots "
                                      "(Figs. 8, 9)")
    p.add_argument("run_dir")
    p.add_argument("--out", required=True, help="PNG file to write")
    p.add_argument("--times", type=float, nargs="+",
                   help="seconds since opening: the nearest snapshots (default: all)")
    p.add_argument("--ncols", type=int, default=5, help="panels per row (default 5)")
    p = sub.add_parser("ratios", help="wall normal force / static during discharge (Fig. 10)")
    p.add_argument("run_dir")
    p.add_argument("--out", required=True, help="PNG file to write")
    p = sub.add_parser("flow", help="removals, discs, surfaces and arch during discharge")
    p.add_argument("run_dir")
    p.add_argument("--out", required=True, help="PNG file to write")
    p = sub.add_parser("discharge", help="frames.png, wall_ratios.png and flow.png of one run")
    p.add_argument("run_dir")
    p.add_argument("--outdir", required=True, help="folder to write the three PNGs to")
    p = sub.add_parser("run", help="the pictures of one run directory, into it")
    p.add_argument("run_dir")
    p.add_argument("--wait", action="store_true",
                   help="draw only once a line 'draw' is read on stdin (dem run --pictures)")
    p.add_argument("--quiet", action="store_true", help="do not list the files written")
    args = parser.parse_args(argv)
    suffix = os.path.splitext(args.out)[1].lower() if getattr(args, "out", None) else ".png"
    if suffix not in FORMATS:      # refused before any data is read, like any bad argument (exit 2)
        parser.error(f"--out {args.out}: unknown suffix {suffix or '(none)'!r}; known: {', '.join(FORMATS)}")

    if args.command == "network":
        out = plot_network(args.run_dir, args.out, title=args.title)
    elif args.command == "grid":
        out = plot_network_grid(args.run_dirs, args.out, labels=args.labels, ncols=args.ncols)
    elif args.command == "profiles":
        out = plot_side_profiles(args.run_dirs, args.out, labels=args.labels, per=args.per)
    elif args.command == "bottom":
        out = plot_bottom_profile(args.run_dir, args.out)
    elif args.command == "frames":
        out = plot_discharge_frames(args.run_dir, args.out, times=args.times, ncols=args.ncols)
    elif args.command == "ratios":
        out = plot_wall_ratios(args.run_dir, args.out)
    elif args.command == "flow":
        out = plot_flow(args.run_dir, args.out)
    elif args.command == "discharge":
        out = "\n".join(plot_discharge(args.run_dir, args.outdir))
    else:
        if args.wait and sys.stdin.readline().strip() != "draw":
            return 0
        try:
            out = "\n".join(plot_run(args.run_dir))
        except OSError as e:
            sys.stderr.write(f"dem.compare.figures: {e}\n")
            return 1
        if args.quiet:
            return 0
    print(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

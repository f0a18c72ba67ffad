"""The pictures of one `dem run` directory drawn with PIL (compare/raster_plot.py), no matplotlib.

    /usr/bin/python3 -m compare.figures.quick_figures run RUN_DIR [--jobs N]
    /usr/bin/python3 -m compare.figures run RUN_DIR --renderer pil      (the same)
    build/dem run SCENE --out RUN_DIR --pictures                        (the run, then the same)

Writes into RUN_DIR the files of `compare.figures run`: network.png and side_walls.png and, for
a discharge, frames.png, wall_ratios.png and flow.png, with the same titles, panels, axes,
legends and colour bars, from the same data (compare/figure_data.py). Importing matplotlib
costs more than drawing all five pictures so (benchmarks/README.md). Every picture is drawn
before the first is written, so a run directory with a missing or malformed file gets none (the
error names the file) rather than some. On two cores or more the pictures are shared out to two
processes (--jobs N; the same bytes).
"""

import ctypes
import math
import os
import pickle
import sys
import traceback

if __name__ == "__main__":
    # no linear algebra here: one OpenBLAS thread, not one a core started at numpy's import
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from compare.figures.figure_data import (DEAD_RADII, RATIO_LIMITS, SIDE_MARKERS, SIDE_STYLES,  # noqa: E402
                                 STATIC_FRACTION, SURFACE_COLOURS, _fail, _fmt, _rest_text,
                                 cell_edges, discharge_frames, displacement_radii, flow_data,
                                 flow_fit_line, flow_title, frames_title, load_run,
                                 network_bounds, network_segments, network_title, point_positions,
                                 ratios_title, reference_radius, scene_name, side_bins_title,
                                 side_profile, side_title, side_wall_contacts, static_ratio,
                                 wall_ratio_data, wall_series_matrix)
from compare.io import atomic_file  # noqa: E402
from compare.figures import raster_plot as rp  # noqa: E402

GREY_DEAD = (224, 224, 224)            # matplotlib's '0.88': discs that moved < 1 radius
GREY_BAD = (184, 184, 184)             # '0.72': heat-map bins without a static load


# --------------------------------------------------------------------------- layout helpers


def _limits(arrays, margin=0.05, include=()):
    """Autoscaled limits (matplotlib's 5 % margins) of the finite values of arrays and include."""
    values = [np.asarray(a, float).ravel() for a in arrays] + [np.asarray(include, float)]
    values = np.concatenate(values) if values else np.zeros(0)
    values = values[np.isfinite(values)]
    if not len(values):
        return (0.0, 1.0)
    lo, hi = float(values.min()), float(values.max())
    if hi - lo <= 1e-12 * max(abs(lo), abs(hi), 1.0):
        lo, hi = lo - max(abs(lo) * 0.05, 0.5), hi + max(abs(hi) * 0.05, 0.5)
    pad = margin * (hi - lo)
    return lo - pad, hi + pad


def _equal_box(left, top, width, height, xlim, ylim):
    """The box (inches) of equal-aspect axes in a cell: shrunk in one direction, centred."""
    aspect = (ylim[1] - ylim[0]) / (xlim[1] - xlim[0])
    if height / width > aspect:
        h = width * aspect
        return left, top + (height - h) / 2, width, h
    w = height / aspect
    return left + (width - w) / 2, top, w, height


def _intervals(length_in, tick_size, per_label):
    """How many tick intervals an axis gets: matplotlib's auto locator allows one label per
    per_label x the tick label size (3 along x, 2 along y), at most 9."""
    return int(min(max(length_in * 72 // (tick_size * per_label), 1), 9))


def _ticks(ax, tick_size=10, steps=(1, 2, 2.5, 5, 10), nbins=None):
    """nice_ticks of the axes' limits, as many as their size allows (or nbins intervals)."""
    w_in, h_in = ax.w / ax.fig.scale, ax.h / ax.fig.scale
    ax.xticks = rp.nice_ticks(*ax.xlim, nbins or _intervals(w_in, tick_size, 3), steps)
    ax.yticks = rp.nice_ticks(*ax.ylim, nbins or _intervals(h_in, tick_size, 2), steps)


def _draw_walls(ax, walls, width):
    """Walls as thick black lines with round ends."""
    for w in walls:
        ax.line([w["from"][0], w["to"][0]], [w["from"][1], w["to"][1]], "black", width)
        ax.markers([w["from"][0], w["to"][0]], [w["from"][1], w["to"][1]], "o", width, "black")


def _draw_points(ax, points, size):
    """Point contacts ({name: (x, y)}) as black dots."""
    if points:
        px, py = zip(*points.values())
        ax.markers(px, py, "o", size, "black")


# --------------------------------------------------------------------------- network


def network(run_dir):
    """The contact-force network (compare.figures.plot_network): discs, forces, walls, points."""
    run = load_run(run_dir, parts=("contacts", "discs"))
    summary, discs, contacts = run["summary"], run["discs"], run["contacts"]
    r_ref = reference_radius(discs)
    if r_ref is None:
        _fail(os.path.join(run_dir, "discs.csv"), "no discs: the plot scale needs disc 0")
    segments = network_segments(contacts, r_ref, summary["disc_weight"])
    points = point_positions(summary, contacts)
    x0, x1, y0, y1 = network_bounds(run)
    title = network_title(summary, discs)
    top = 0.2 + 0.19 * (title.count("\n") + 1)
    width, height = 7.0, min(max(7.0 * (y1 - y0) / (x1 - x0), 3.0), 14.0) + 0.9
    fig = rp.Figure(width, height)
    box = _equal_box(0.65, top, width - 0.65 - 0.2, height - top - 0.55, (x0, x1), (y0, y1))
    ax = fig.axes(*box, xlim=(x0, x1), ylim=(y0, y1))
    _ticks(ax)
    ax.discs(discs["x"], discs["y"], discs["r"], None, "0.6", 0.5)
    ax.segments(segments, "darkred", 1.2)
    _draw_walls(ax, summary["walls"], 3.0)
    _draw_points(ax, points, 3.0)
    ax.finish(xlabel="X [cm]", ylabel="Y [cm]", tick_size=10)
    fig.text(fig.px(box[0] + box[2] / 2), fig.px(box[1]) - fig.pt(6), title, size=10, ha="center",
             va="bottom", align="center")
    return fig


# --------------------------------------------------------------------------- side walls


def side_walls(run_dir, per="contact"):
    """Side-wall normal force and friction against depth (compare.figures.plot_side_profiles of
    one run): per side-wall contact, or per="bin" per wall_profiles.csv bin."""
    run = load_run(run_dir, parts=("contacts",) if per == "contact" else ("profiles",))
    summary = run["summary"]
    weight = summary["disc_weight"]
    colour = tuple(int(v) for v in rp.colormap("viridis", [0.0])[0])     # viridis(0): one run
    label = scene_name(summary)
    if _rest_text(summary) != "at rest":
        label += f" ({_rest_text(summary)})"
    curves, split_drawn, unpaired = {"normal": [], "friction": []}, set(), []
    if per == "contact":
        prof = side_wall_contacts(summary, run["contacts"])
        if prof is None:
            _fail(os.path.join(run_dir, "contacts.csv"),
                  "no dw contact with a wall whose group starts with 'side'")
        keys = (("normal", "normal"), ("friction", "friction"))
        if not prof["paired"]:
            unpaired.append(label)
    else:
        prof = side_profile(run["profiles"])
        if prof is None:
            _fail(os.path.join(run_dir, "wall_profiles.csv"), "no wall whose group starts with 'side'")
        keys = (("normal", "normal"), ("friction", "shear"))
    # (x, depth, style, width, marker, marker size) of each curve of each panel
    for panel, q in keys:
        if per == "contact" and not prof["paired"]:
            for g, raw in prof["contacts"].items():
                split_drawn.add((g, SIDE_STYLES.get(g, "-."), SIDE_MARKERS.get(g, "o")))
                curves[panel].append((raw[q] / weight, raw["depth"], SIDE_STYLES.get(g, "-."), 1.2,
                                      SIDE_MARKERS.get(g, "o"), 4))
            continue
        curves[panel].append((prof[q] / weight, prof["depth"], "-", 1.6, "o", 3.5 if per == "contact" else 3))
        sides = np.array([prof["groups"][g][q] for g in prof["groups"]])
        if per == "contact":
            scale = float(np.max(np.abs(prof[q]))) if len(prof[q]) else 0.0
            differ = len(sides) > 1 and float(np.max(sides.max(axis=0) - sides.min(axis=0))) > 0.01 * scale
        else:
            scale = np.nanmax(np.abs(prof["normal"])) if len(prof["depth"]) else 0.0
            differ = len(sides) > 1 and np.nanmax(np.abs(sides[0] - sides[-1]), initial=0.0) > 0.05 * scale
        if differ:
            for g, values in prof["groups"].items():
                split_drawn.add((g, SIDE_STYLES.get(g, "-."), ""))
                curves[panel].append((values[q] / weight, prof["depth"], SIDE_STYLES.get(g, "-."), 0.8, None, 0))

    title = side_title([summary], unpaired) if per == "contact" else side_bins_title([summary])
    top = 0.25 + 0.2 * (title.count("\n") + 1)
    fig = rp.Figure(11.0, 7.0)
    panel_w = (11.0 - 0.75 - 0.25 - 0.3) / 2
    depth_lim = _limits([c[1] for cs in curves.values() for c in cs])
    if per == "contact":
        width = ""
        xlabels = ("side-wall normal force per contact [disc weights]",
                   "wall friction per contact [disc weights], + = downward")
    else:
        width = f"{prof['bin_width']:g}"
        xlabels = (f"side-wall normal force per {width} cm bin [disc weights]",
                   f"wall friction (shear) per {width} cm bin [disc weights], + = downward")
    axes = []
    for k, panel in enumerate(("normal", "friction")):
        xlim = _limits([c[0] for c in curves[panel]])
        ax = fig.axes(0.75 + k * (panel_w + 0.3), top, panel_w, 7.0 - top - 0.6, xlim=xlim, ylim=depth_lim,
                      invert_y=True)
        _ticks(ax)
        ax.grid()
        if panel == "friction":
            ax.vline(0.0, "black", 0.8)
        for x, depth, style, lw, marker, ms in curves[panel]:
            ax.line(x, depth, colour, lw, style)
            if marker:
                ax.markers(x, depth, marker, ms, colour)
        axes.append(ax)
    axn, axs = axes
    first = curves["normal"][0]
    items = [(label, colour, first[2], first[3], first[4], False)]
    items += [(f"{g} alone", rp.rgb("0.3"), style, 0.8, marker or None, False) for g, style, marker in sorted(split_drawn)]
    axn.legend(items, loc="upper right", size=8)
    axn.finish(xlabel=xlabels[0], ylabel="depth below the top of the silo [cm]", tick_size=10)
    axs.finish(xlabel=xlabels[1], ytick_labels=False, tick_size=10)
    fig.text(fig.size[0] / 2, fig.px(0.1), title, size=11, ha="center", va="top", align="center")
    return fig


# --------------------------------------------------------------------------- frames


def frames(run_dir, ncols=5):
    """Discs coloured by displacement and contact forces at the discharge snapshots, one panel
    each, with the colour bar (compare.figures.plot_discharge_frames)."""
    d = discharge_frames(run_dir)
    summary, info, snaps, r_ref = d["summary"], d["info"], d["frames"], d["r_ref"]
    x0, x1, y0, y1 = d["bounds"]
    weight = summary["disc_weight"]
    vmax = max(2.0 * DEAD_RADII, d["top"])

    def face(moved):
        """Light grey for dead discs, else YlOrRd (its 0.15..0.85 part) on a log scale 1..vmax."""
        out = np.empty((len(moved), 3), np.uint8)
        dead = moved < DEAD_RADII
        out[dead] = GREY_DEAD
        f = np.log(np.maximum(moved[~dead], DEAD_RADII) / DEAD_RADII) / math.log(vmax / DEAD_RADII)
        out[~dead] = rp.colormap("YlOrRd", f, 0.15, 0.85)
        return out

    ncols = min(ncols, len(snaps))
    nrows = -(-len(snaps) // ncols)
    panel, aspect = 3.2, (y1 - y0) / (x1 - x0)
    width = panel * ncols + 1.3
    title = frames_title(summary, d["n_initial"], int(width * 12))
    top = 0.15 + 0.19 * (title.count("\n") + 1) + 0.25
    left, bottom, right, gap_w, gap_h = 0.35, 0.3, 1.0, 0.12, 0.34
    height = panel * aspect * nrows + top + bottom + gap_h * (nrows - 1)
    fig = rp.Figure(width, height)
    cell_w = (width - left - right - gap_w * (ncols - 1)) / ncols
    cell_h = (height - top - bottom - gap_h * (nrows - 1)) / nrows
    lw = 0.55
    slit = info.get("slit")
    outlet_y = d["outlet_y"]
    xt = yt = None
    for k, (t, discs, contacts) in enumerate(snaps):
        row, col = divmod(k, ncols)
        box = _equal_box(left + col * (cell_w + gap_w), top + row * (cell_h + gap_h), cell_w, cell_h,
                         (x0, x1), (y0, y1))
        ax = fig.axes(*box, xlim=(x0, x1), ylim=(y0, y1))
        if xt is None:                       # a few round ticks, shared by all panels
            _ticks(ax, steps=(1, 2, 5, 10), nbins=6)
            xt, yt = ax.xticks, ax.yticks
        ax.xticks, ax.yticks = xt, yt
        moved = displacement_radii(discs)
        ax.discs(discs["x"], discs["y"], discs["r"], face(moved), "0.5", 0.4 * lw)
        if contacts is not None:
            ax.segments(network_segments(contacts, r_ref, weight), "black", 1.6 * lw)
        _draw_walls(ax, d["walls"], 3 * lw)
        _draw_points(ax, d["points"], 3 * lw * 1.5)
        if isinstance(outlet_y, (int, float)) and isinstance(slit, list) and len(slit) == 2:
            ax.line(slit, [outlet_y, outlet_y], "0.3", 1.0, ":")
        ax.finish(tick_size=6, xtick_labels=row == nrows - 1 or k + ncols >= len(snaps),
                  ytick_labels=col == 0, title=f"t = {t:.2f} s", title_size=10)
        ax.text(x0 + d["pad"], y0 + d["pad"], f"{len(moved)} discs, dead "
                f"{np.sum(moved < DEAD_RADII) / d['n_initial']:.0%}", size=6.5)
    inner = height - top - bottom
    ticks = [v for v in (1, 2, 3, 5, 10, 20, 30, 50, 100) if DEAD_RADII <= v <= vmax]
    fig.colorbar(width - (right - 0.12), top + 0.1 * inner, 0.14, 0.8 * inner,
                 rp.colormap("YlOrRd", np.linspace(0, 1, 256), 0.15, 0.85),
                 [(math.log(v / DEAD_RADII) / math.log(vmax / DEAD_RADII), f"{v:g}") for v in ticks],
                 "displacement since opening [radii]; grey: < 1 (dead)")
    fig.text(fig.size[0] / 2, fig.px(0.12), title, size=10, ha="center", va="top", align="center")
    return fig


# --------------------------------------------------------------------------- wall ratios


def _ratio_fraction(ratio):
    """Colour-map fraction of force / static: log10, clipped to RATIO_LIMITS, 1 at the middle
    (matplotlib's TwoSlopeNorm of compare.figures)."""
    lo, hi = (math.log10(v) for v in RATIO_LIMITS)
    v = np.log10(np.clip(ratio, *RATIO_LIMITS))
    return np.where(v < 0, 0.5 * (v - lo) / (0 - lo), 0.5 + 0.5 * v / hi)


def wall_ratios(run_dir, fraction=STATIC_FRACTION):
    """Heat maps of wall normal force / static per bin against time, and the wall totals / static
    (compare.figures.plot_wall_ratios)."""
    d = wall_ratio_data(run_dir)
    summary, info, series, totals = d["summary"], d["info"], d["series"], d["totals"]
    strips, sides, bottoms = d["strips"], d["sides"], d["bottoms"]
    head = ratios_title(summary, info)
    fig_w, fig_h = 11.0, 2.7 * len(strips) + 2.9
    top, bottom, hspace = 0.3 + 0.19 * (head.count("\n") + 1), 0.45, 0.3
    left, right = 0.65, 1.15
    unit = (fig_h - top - bottom - hspace * len(strips)) / (3 * len(strips) + 2.3)
    fig = rp.Figure(fig_w, fig_h)
    # the matrices first: the strips' time range sets the shared x
    mats, t_end = [], 0.0
    for title, group, coord in strips:
        ms = [(w, wall_series_matrix(series, w["name"])) for w in group]
        mats.append(ms)
        t_end = max([t_end] + [float(m["t"][-1]) for _, m in ms if m is not None])
    curves = []
    for k, w in enumerate(sides + bottoms):
        sel = totals["name"] == w["name"]
        if not sel.any():
            continue
        order = np.argsort(totals["t"][sel], kind="stable")
        t, normal = totals["t"][sel][order], totals["normal"][sel][order]
        if not normal[0] > 0:
            continue
        curves.append((w, k, t, normal / normal[0], "-" if w in sides else "--"))
        t_end = max(t_end, float(t[-1]))
    xlim = (0.0, t_end if t_end > 0 else 1.0)
    y = top
    for (title, group, coord), ms in zip(strips, mats):
        notes, cells, edges = [], [], []
        for w, m in ms:
            if m is None:
                notes.append(f"'{w['name']}' not in wall_series.csv")
                continue
            ratio, _, _ = static_ratio(m["normal"], fraction)
            order = np.argsort(m[coord], kind="stable")
            cells.append((m, ratio, order))
            edges.append(cell_edges(m[coord][order]))
        ylim = (min(e[0] for e in edges), max(e[-1] for e in edges)) if edges else (0.0, 1.0)
        # cells are sharp-edged: drawn at the figure's pixels (supersampling them cost a third
        # of the picture's drawing); only the peak's circle is left unsmoothed
        ax = fig.axes(left, y, fig_w - left - right, 3 * unit, xlim=xlim, ylim=ylim,
                      invert_y=coord == "depth_mid", supersample=1)
        _ticks(ax)
        slit = info.get("slit")
        if coord == "x_mid" and isinstance(slit, list) and len(slit) == 2:
            ax.hspan(slit[0], slit[1], "white")
        for (m, ratio, order), e in zip(cells, edges):
            f = _ratio_fraction(ratio[:, order])
            colours = rp.colormap("RdBu_r", np.nan_to_num(f)).reshape(f.shape + (3,))
            colours[~np.isfinite(f)] = GREY_BAD
            ax.cells(cell_edges(m["t"]), e, colours.transpose(1, 0, 2))
        for (m, ratio, order), (w, _) in zip(cells, [x for x in ms if x[1] is not None]):
            if not np.isfinite(ratio).any():
                note = "no bin with a static load"
            else:
                it, ib = np.unravel_index(np.nanargmax(ratio), ratio.shape)
                ax.markers([m["t"][it]], [m[coord][ib]], "o", 9, None, "black", 1.2)
                note = f"max {ratio[it, ib]:.3g}\u00d7 at t = {m['t'][it]:.3f} s"
            notes.append(note if len(group) == 1 else f"{w['name']}: {note}")
        ax.finish(ylabel="depth [cm]" if coord == "depth_mid" else "X [cm]", xtick_labels=False,
                  title=f"{title}, normal force / static per bin: " + "; ".join(notes), title_size=9,
                  title_loc="left")
        if coord == "x_mid" and isinstance(slit, list) and len(slit) == 2:
            fig.text(ax.box[0] + 0.005 * ax.w, float(ax.figure_px(0, (slit[0] + slit[1]) / 2)[1]), " slit",
                     size=8, va="center")
        y += 3 * unit + hspace
    strips_h = y - hspace - top
    lo, hi = RATIO_LIMITS
    ticks = [r for r in (0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 30) if lo <= r <= hi]
    fig.colorbar(fig_w - 1.0, top + 0.05 * strips_h, 0.16, 0.9 * strips_h,
                 rp.colormap("RdBu_r", np.linspace(0, 1, 256)),
                 [(float(_ratio_fraction(r)), f"{r:g}") for r in ticks],
                 f"normal / static (clipped to {lo:g}..{hi:g}); grey: static < {fraction:.0%} of the "
                 "wall's largest bin", label_size=8, size=10)

    ylim = _limits([c[3] for c in curves], include=[1.0])
    ax = fig.axes(left, y, fig_w - left - right, 2.3 * unit, xlim=xlim, ylim=ylim)
    _ticks(ax)
    ax.grid()
    ax.hline(1.0, "black", 0.8)
    items = []
    for w, k, t, r, style in curves:
        c = rp.TAB10[k % 10]
        ax.line(t, r, c, 1.0, style)
        items.append((f"{w['name']} (max {np.max(r):.3g})", c, style, 1.0, None, False))
    ax.finish(xlabel="time since opening [s]", ylabel="wall total / static",
              title="total normal force on each wall / its static value", title_size=9, title_loc="left")
    ax.legend(items, loc="above right", size=8, ncol=4)
    fig.text(fig.size[0] / 2, fig.px(0.1), head, size=10, ha="center", va="top", align="center")
    return fig


# --------------------------------------------------------------------------- flow


def flow(run_dir):
    """Removals, discs, surfaces and the arch against time in four panels (compare.figures.plot_flow)."""
    d = flow_data(run_dir)
    summary, info, removals, series, t_end = (d[k] for k in ("summary", "info", "removals", "flow", "t_end"))
    title = flow_title(summary, info)
    top = 0.42 + 0.2 * (title.count("\n") + 1)
    left, right, bottom, wspace, hspace = 0.75, 0.75, 0.5, 1.45, 0.45
    pw, ph = (12 - left - right - wspace) / 2, (8 - top - bottom - hspace) / 2
    fig = rp.Figure(12.0, 8.0)
    xlim = (0.0, t_end)

    def box(row, col):
        return left + col * (pw + wspace), top + row * (ph + hspace), pw, ph

    # (a) cumulative removed mass, keystones, fitted line, first jam, discs on the right
    cumulative = np.cumsum(removals["mass"])
    st = np.concatenate([[0.0], removals["t"], [t_end]])
    sm = np.concatenate([[0.0], cumulative, cumulative[-1:] if len(cumulative) else [0]])
    rate = info.get("flow_rate_mass")
    fit = flow_fit_line(removals["t"], cumulative, rate)
    fit_y = [] if fit is None else [fit[2] + rate * fit[0], fit[2] + rate * fit[1]]
    ax = fig.axes(*box(0, 0), xlim=xlim, ylim=_limits([sm, fit_y]))
    _ticks(ax)
    ax.grid()
    items = []
    ax.step(st, sm, colour="tab:blue", width=1.4)
    items.append((f"removed ({len(cumulative)} discs)", rp.rgb("tab:blue"), "-", 1.4, None, False))
    hand = removals["how"] == "keystone"
    if hand.any():
        ax.markers(removals["t"][hand], cumulative[hand], "v", 8, "firebrick")
        items.append((f"keystone removed by hand ({int(hand.sum())})", rp.rgb("firebrick"), None, 0, "v", False))
    if fit is not None:
        t0, t1, b = fit
        ax.line([t0, t1], [b + rate * t0, b + rate * t1], "black", 1.0, "--")
        items.append((f"fit: {rate:.4g} g/s per cm ({_fmt(info.get('flow_rate_discs'))} discs/s)",
                      (0, 0, 0), "--", 1.0, None, False))
    jam = info.get("jam_at")
    if isinstance(jam, (int, float)):
        ax.vline(jam, "firebrick", 1.5, ":")
        items.append((f"first jam {jam:.3g} s", rp.rgb("firebrick"), ":", 1.5, None, False))
    ax.legend(items, loc="upper left", size=8)
    mass = removals["mass"]
    sec = None                          # a removed-disc count axis when all discs weigh the same
    if len(mass) and np.ptp(mass) <= 1e-9 * abs(mass[0]) and mass[0] > 0:
        unit = float(mass[0])
        sec = ax.twin((ax.ylim[0] / unit, ax.ylim[1] / unit))
        _ticks(sec)
    ax.finish(ylabel="removed mass [g per cm]", xtick_labels=False, title="(a) discs through the outlet",
              title_loc="left")
    if sec is not None:
        sec.finish(ylabel="removed discs", right=True)

    # (b) discs in the silo, below the floor, moved fraction on the right
    present = series["discs_in_silo"] + series["discs_below"]
    ax = fig.axes(*box(0, 1), xlim=xlim, ylim=_limits([series["discs_in_silo"], present]))
    _ticks(ax)
    ax.grid()
    ax.fill_between(series["t"], series["discs_in_silo"], present, rp.blend("tab:orange", 0.6))
    ax.line(series["t"], series["discs_in_silo"], "tab:blue", 1.5)
    twin = ax.twin((0.0, 1.02))
    _ticks(twin)
    twin.line(series["t"], series["moved_fraction"], "tab:purple", 1.5, "--")
    ax.legend([("discs in the silo", rp.rgb("tab:blue"), "-", 1.5, None, False),
               ("+ discs below the floor", rp.blend("tab:orange", 0.6), None, 0, None, True),
               ("moved fraction (right)", rp.rgb("tab:purple"), "--", 1.5, None, False)],
              loc="center left", size=8)
    ax.finish(ylabel="discs", xtick_labels=False, title_loc="left",
              title=f"(b) discs; dead fraction at the end {_fmt(info.get('dead_fraction_end'), '.2f')}")
    twin.finish(ylabel="moved fraction (moved > 1 radius or removed)", right=True)

    # (c) the three surface heights and their sink times
    sink = info.get("surface_sink_time") or {}
    ax = fig.axes(*box(1, 0), xlim=xlim,
                  ylim=_limits([series[f"surface_{c}"] for c in ("left", "centre", "right")]))
    _ticks(ax)
    ax.grid()
    items = []
    for column, key in (("left", "left_wall"), ("centre", "centre"), ("right", "right_wall")):
        when = sink.get(key)
        colour = SURFACE_COLOURS[column]
        style = "--" if column == "right" else "-"
        ax.line(series["t"], series[f"surface_{column}"], colour, 1.3, style)
        if isinstance(when, (int, float)):
            ax.vline(when, colour, 1.2, ":")
        items.append((f"{column}: " + (f"sinks at {when:.3g} s" if isinstance(when, (int, float))
                                       else "does not sink"), rp.rgb(colour), style, 1.3, None, False))
    ax.legend(items, loc="lower left", size=8)
    ax.finish(xlabel="time since opening [s]", ylabel="top surface height Y [cm]", title_loc="left",
              title=f"(c) top surface in the wall and centre columns: {info.get('pattern', '?')}")

    # (d) the arch: crown height, and its discs on the right
    crown = series["arch_crown_y"]
    ax = fig.axes(*box(1, 1), xlim=xlim, ylim=(0.0, _limits([crown], include=[0.0])[1]))
    _ticks(ax)
    ax.grid()
    ax.markers(series["t"], crown, "o", 3 * 0.45, "tab:brown")
    twin = ax.twin((0.0, _limits([series["arch_discs"]], include=[0.0])[1]))
    _ticks(twin)
    twin.step(series["t"], series["arch_discs"], colour="0.5", width=0.8)
    ax.legend([("crown height (left)", rp.rgb("tab:brown"), None, 0, "o", False),
               ("discs in the arch (right)", rp.rgb("0.5"), "-", 0.8, None, False)], loc="upper left", size=8)
    no_arch = float(np.mean(np.isnan(crown))) if len(series["t"]) else 0.0
    ax.finish(xlabel="time since opening [s]", ylabel="arch crown Y [cm]", title_loc="left",
              title=f"(d) arch from slit end to slit end (none in {no_arch:.0%} of samples)")
    twin.finish(ylabel="discs in the arch", right=True)
    fig.text(fig.size[0] / 2, fig.px(0.1), title, size=11, ha="center", va="top", align="center")
    return fig


# --------------------------------------------------------------------------- one run


def _pictures(run_dir):
    """The run's pictures as [(file name, function drawing its Figure)].

    A run without contacts.csv (a reference code's) has no network: it is left out with a note on
    stderr and side_walls.png is drawn per wall_profiles.csv bin, as compare.figures does."""
    if not os.path.isdir(run_dir):
        _fail(run_dir, "not a directory (a `dem run` output folder)")
    pictures = []
    if os.path.exists(os.path.join(run_dir, "contacts.csv")):
        pictures += [("network.png", network), ("side_walls.png", side_walls)]
    else:
        sys.stderr.write(f"compare.figures.quick_figures: {os.path.join(run_dir, 'contacts.csv')}: absent (the run "
                         "gives no contact list): the contact network is skipped; side_walls.png is drawn "
                         "per wall_profiles.csv bin\n")
        pictures.append(("side_walls.png", lambda d: side_walls(d, per="bin")))
    if os.path.exists(os.path.join(run_dir, "flow_series.csv")):
        pictures += [("frames.png", frames), ("wall_ratios.png", wall_ratios), ("flow.png", flow)]
    return pictures


def draw_run(run_dir):
    """The pictures of one run as {file name: Figure}, all drawn before any is written."""
    return {name: draw(run_dir) for name, draw in _pictures(run_dir)}


# What each picture costs to read, draw and encode, relative to flow.png (CPU seconds of the 17/18
# discharge run, benchmarks/quick_figure_times.py): the share-out of plot_run's processes.
PICTURE_COST = {"frames.png": 3.5, "wall_ratios.png": 2.5, "side_walls.png": 1.3, "network.png": 1.2,
                "flow.png": 1.0}


def _encoded(run_dir, pictures):
    """[(name, PNG bytes)] of the pictures, each encoded as soon as it is drawn and its image let
    go (one picture's pixels in memory at a time, not five: fresh pages cost this process more
    than drawing on them)."""
    encoded = []
    for name, draw in pictures:
        fig = draw(run_dir)
        encoded.append((name, fig.png()))
        del fig
    return encoded


def _shares(pictures, jobs):
    """The pictures dealt to `jobs` processes, the costliest first, each to the least loaded."""
    shares, loads = [[] for _ in range(jobs)], [0.0] * jobs
    for k in sorted(range(len(pictures)), key=lambda k: -PICTURE_COST.get(pictures[k][0], 1.0)):
        least = loads.index(min(loads))
        shares[least].append(k)
        loads[least] += PICTURE_COST.get(pictures[k][0], 1.0)
    return [sorted(share) for share in shares if share]


def _encoded_in_processes(run_dir, pictures, jobs):
    """_encoded over `jobs` processes: this one and jobs - 1 forked children, each with its share
    (_shares), the children's PNG bytes sent back through a pipe. A child's error (a missing or
    malformed file) stops this process with the child's message. In the pictures' order."""
    shares = _shares(pictures, jobs)
    children = []
    for share in shares[1:]:
        read_end, write_end = os.pipe()
        pid = os.fork()
        if pid == 0:                                   # the child: its share, then out at once
            os.close(read_end)
            try:
                reply = ("ok", _encoded(run_dir, [pictures[k] for k in share]))
            except SystemExit as stop:
                reply = ("error", str(stop.code))
            except BaseException:                      # noqa: B902 - told to the parent, whatever it is
                reply = ("error", traceback.format_exc())
            with os.fdopen(write_end, "wb") as pipe:
                pickle.dump(reply, pipe, protocol=pickle.HIGHEST_PROTOCOL)
            os._exit(0)
        os.close(write_end)
        children.append((pid, read_end, share))
    try:
        encoded = dict(zip(shares[0], _encoded(run_dir, [pictures[k] for k in shares[0]])))
    finally:
        replies = []
        for pid, read_end, share in children:          # read the whole reply, then reap
            with os.fdopen(read_end, "rb") as pipe:
                try:
                    replies.append((share, pickle.load(pipe)))
                except (EOFError, pickle.UnpicklingError):   # it ended (a signal) before its reply was whole
                    replies.append((share, ("error", "a picture process ended without its pictures")))
            os.waitpid(pid, 0)
    for share, (status, value) in replies:
        if status != "ok":
            raise SystemExit(value)
        encoded.update(zip(share, value))
    return [encoded[k] for k in range(len(pictures))]


def plot_run(run_dir, jobs=1):
    """Draw the run's pictures and write them into run_dir; returns their paths. ``jobs`` > 1
    shares the pictures out to that many processes (forked: Linux and macOS; one process
    elsewhere), the same bytes. The files are written once all are encoded, so that an error
    leaves none written."""
    pictures = _pictures(run_dir)
    jobs = min(jobs, len(pictures)) if hasattr(os, "fork") else 1
    encoded = _encoded_in_processes(run_dir, pictures, jobs) if jobs > 1 else _encoded(run_dir, pictures)
    return [atomic_file.write_bytes(os.path.join(run_dir, name), data) for name, data in encoded]


def default_jobs():
    """Processes for the pictures: two where this process may run on two cores or more (the five
    pictures share out to two about evenly: _shares), else one."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:
        cores = os.cpu_count() or 1
    return 2 if cores >= 2 else 1


def _keep_freed_memory():
    """glibc only (else nothing): memory the process frees stays in its heap for the next picture
    instead of going back to the system (large blocks are mapped and unmapped by default, and
    every page mapped afresh is a page fault: some 0.05 s of the five pictures here)."""
    try:
        libc = ctypes.CDLL("libc.so.6")
        m_trim_threshold, m_mmap_threshold = -1, -3
        libc.mallopt(m_mmap_threshold, 1 << 30)
        libc.mallopt(m_trim_threshold, 1 << 30)
    except (OSError, AttributeError):
        pass


def _options(argv):
    """(run_dir, jobs, wait, quiet) of the command line, or None: `run RUN_DIR [--jobs N]
    [--wait] [--quiet]`, compare.figures' `--renderer pil` taken out."""
    rest = [a for k, a in enumerate(argv) if a not in ("--renderer=pil", "--renderer")
            and not (a == "pil" and k > 0 and argv[k - 1] == "--renderer")]
    wait, quiet = "--wait" in rest, "--quiet" in rest
    rest = [a for a in rest if a not in ("--wait", "--quiet")]
    jobs = default_jobs()
    if len(rest) == 4 and rest[2] == "--jobs":
        if not rest[3].isdigit() or int(rest[3]) < 1:
            return None
        jobs, rest = int(rest[3]), rest[:2]
    if len(rest) != 2 or rest[0] != "run":
        return None
    return rest[1], jobs, wait, quiet


def main(argv=None):
    """Command line: `run RUN_DIR [--jobs N] [--wait] [--quiet]` (also as compare.figures' `run
    RUN_DIR --renderer pil`). --wait: `dem run --pictures` starts this process with the run, so
    that the imports are done while the engine runs; it reads a line on stdin when the run has
    ended, and draws when the line is "draw" (anything else, or the end of stdin: the run did not
    end well, nothing is drawn, exit 0). --quiet: the files written are not listed."""
    options = _options(sys.argv[1:] if argv is None else list(argv))
    if options is None:
        sys.stderr.write("usage: python3 -m compare.figures.quick_figures run RUN_DIR [--jobs N] [--wait] [--quiet]\n"
                         "       python3 -m compare.figures run RUN_DIR --renderer pil [--jobs N]\n")
        return 2
    run_dir, jobs, wait, quiet = options
    _keep_freed_memory()
    if wait and sys.stdin.readline().strip() != "draw":
        return 0
    written = plot_run(run_dir, jobs)
    if not quiet:
        print("\n".join(written))
    return 0


if __name__ == "__main__":
    status = main()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)

"""The data of dem.compare.figures' pictures, without matplotlib: reading a run directory (with a
message that names the offending file), captions, and the pure maths of the pictures (contact-force
segments, side-wall profiles, the discharge pictures' matrices and fits). dem.compare.figures re-exports every name; the studies' main processes
(dem.compare.papers.paper_claims in them) import this module alone, so that matplotlib is imported only in
the processes that draw.
"""

import math
import os
import sys
import textwrap

import numpy as np

from dem.compare.io import run_dir as _run_dir
from dem.compare.io.run_dir import CONTACT_COLUMNS, SNAPSHOT_DISC_COLUMNS, RunDir, RunDirError

# The paper's plot scale: one disc diameter stands for 50/pi (about 16) disc weights.
DIAMETER_IN_DISC_WEIGHTS = 50.0 / math.pi


# Side-wall contacts whose depths differ by at most this much [scene length unit] are taken
# to be at the same depth (left and right contacts of one lattice row).
SAME_DEPTH = 1e-6


def _fail(path, message):
    """Stop with a message that names the offending file."""
    raise SystemExit(f"dem.compare.figures: {path}: {message}")


# --------------------------------------------------------------------------- reading


def _reading(fn, *args, **kwargs):
    """fn(...) of dem.compare.io.run_dir, its RunDirError a stop that names the file."""
    try:
        return fn(*args, **kwargs)
    except RunDirError as err:
        _fail(err.path, err.message)


def read_csv(path, columns, empty=None):
    """A CSV file of a run as a dict of numpy arrays (dem.compare.io.run_dir.read_csv); a missing or
    malformed file stops with SystemExit naming it."""
    return _reading(_run_dir.read_csv, path, columns, empty=empty)


def read_summary(path):
    """summary.json (dem.compare.io.run_dir.read_summary) with a positive ``disc_weight``: the unit of
    the figures' force scale."""
    summary = _reading(_run_dir.read_summary, path)
    if not summary["disc_weight"] > 0:
        _fail(path, f"'disc_weight' must be a positive number, found {summary['disc_weight']!r}")
    return summary


def load_run(run_dir, parts=("contacts", "discs", "profiles")):
    """Load one run directory.

    Returns a dict with ``dir``, ``summary`` (summary.json) and, for each name in ``parts``,
    ``contacts`` (contacts.csv), ``discs`` (discs.csv), ``profiles`` (wall_profiles.csv)
    as dicts of numpy arrays keyed by column name; parts not asked for are None.
    A missing or malformed file stops with SystemExit naming it.
    """
    rd = RunDir(run_dir)
    run = {"dir": run_dir, "summary": read_summary(rd.file("summary.json"))}
    for part in ("contacts", "discs", "profiles"):
        run[part] = _reading(getattr(rd, part)) if part in parts else None
    return run


def scene_name(summary):
    """The scene's name from summary.json, or '?'."""
    scene = summary.get("scene")
    return str(scene.get("name", "?")) if isinstance(scene, dict) else "?"


# The contact law's options (docs/scene.md) at the paper's values, and LIGGGHTS' and YADE's.
PAPER_LAW = {"normal_spring": "incremental", "no_tension": "elastic", "friction_cap": "elastic",
             "lever_arm": "radius"}
SHARED_LAW = {"normal_spring": "overlap", "no_tension": "total", "friction_cap": "total",
              "lever_arm": "contact_point"}


def law_name(options):
    """'the paper's law', 'the shared law (LIGGGHTS, YADE)' or the options that differ from the
    paper's, from summary.json's options."""
    law = {k: options.get(k) for k in PAPER_LAW if k in options}
    if not law:
        return "law ?"
    if all(law[k] == v for k, v in PAPER_LAW.items() if k in law):
        return "the paper's law"
    if all(law[k] == v for k, v in SHARED_LAW.items() if k in law):
        return "the shared law (LIGGGHTS, YADE)"
    return "law: " + ", ".join(f"{k} {v}" for k, v in law.items() if PAPER_LAW[k] != v)


def run_caption(summary, with_scene=True):
    """'scene, scheme, dt = .. s, law' of a run, for figure titles (every figure says what ran)."""
    o = summary.get("options") or {}
    dt = o.get("dt")
    parts = [scene_name(summary)] if with_scene else []
    parts += [str(o.get("scheme", "scheme ?")), f"dt = {dt:g} s" if isinstance(dt, (int, float)) else "dt ?",
              law_name(o)]
    return ", ".join(parts)


def common_caption(summaries):
    """The caption of several runs when scheme, dt and law agree (else each differing part is
    named as 'mixed')."""
    caps = [run_caption(s, with_scene=False).split(", ", 2) for s in summaries]
    return ", ".join(c[0] if all(x[i] == c[0] for x in caps) else "mixed " + ("scheme", "dt", "law")[i]
                     for i, c in enumerate(zip(*caps))) if caps else ""


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


# --------------------------------------------------------------------------- pictures' common data


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


def _rest_text(summary):
    """'at rest', 'NOT at rest (status)' or 'rest unknown' from summary.json."""
    rest = summary.get("rest")
    if isinstance(rest, dict) and "reached" in rest:
        if rest["reached"]:
            return "at rest"
        return f"NOT at rest ({summary.get('status', '?')})"
    return "rest unknown"


# The gate wall is removed at opening; summary.json does not name it (docs/outputs.md), so the
# wall of this name is the gate unless summary["discharge"]["gate"] says otherwise.
GATE_NAME = "gate"
# Discs that moved less than this many radii since opening are "dead" (docs/outputs.md).
DEAD_RADII = 1.0
# Bins whose static (t = 0) normal force is below this fraction of the wall's largest static bin
# are masked in the ratio heat maps (docs/outputs.md: peak_ratio_*).
STATIC_FRACTION = 0.25
# Colour range of the force / static ratio (log scale, ratio 1 = white).
RATIO_LIMITS = (0.1, 30.0)
# Colours of the three surface columns and of the wall groups.
SURFACE_COLOURS = {"left": "tab:blue", "centre": "tab:red", "right": "tab:green"}


def discharge_info(summary, path):
    """summary["discharge"], or stop: the run has no [discharge] table."""
    info = summary.get("discharge")
    if not isinstance(info, dict):
        _fail(path, "no 'discharge' object: not a discharge run (scene without [discharge])")
    return info


def gate_name(summary):
    """Name of the gate wall: summary["discharge"]["gate"] if given, else 'gate'."""
    gate = (summary.get("discharge") or {}).get("gate")
    return gate if isinstance(gate, str) and gate else GATE_NAME


def read_pvd(path):
    """The DataSets of a ParaView collection (.pvd) as (timestep, file) pairs sorted by time
    (dem.compare.io.run_dir.read_pvd); a missing or malformed file stops with SystemExit naming it."""
    return _reading(_run_dir.read_pvd, path)


def snapshot_index(run_dir):
    """The discharge snapshots of a run: a list of {"t", "discs", "contacts"} sorted by t
    (dem.compare.io.run_dir.RunDir.discharge_snapshots)."""
    return _reading(RunDir(run_dir).discharge_snapshots)


def select_snapshots(snaps, times=None):
    """All snapshots (times None), or for each requested time the snapshot nearest to it
    (each snapshot once, in time order)."""
    if not snaps:
        raise SystemExit("dem.compare.figures: the run has no discharge snapshots")
    if times is None:
        return list(snaps)
    at = np.array([s["t"] for s in snaps])
    picked = sorted({int(np.argmin(np.abs(at - float(t)))) for t in times})
    return [snaps[k] for k in picked]


def displacement_radii(discs):
    """Displacement since opening, |(dx, dy)| / r, of each disc of a snapshot."""
    return np.hypot(discs["dx"], discs["dy"]) / discs["r"]


def wall_series_matrix(series, wall):
    """One wall's bins over time from wall_series.csv arrays, or None if the wall is absent.

    Returns a dict: ``t`` (sorted sample times), ``bin`` (sorted bin numbers), ``s_mid``,
    ``x_mid``, ``y_mid``, ``depth_mid`` (per bin, from its first row), and ``normal``,
    ``shear`` as (len(t), len(bin)) arrays (nan where a sample lacks a bin).
    """
    sel = series["wall"] == wall
    if not np.any(sel):
        return None
    times, it = np.unique(series["t"][sel], return_inverse=True)
    bins, first, ib = np.unique(series["bin"][sel], return_index=True, return_inverse=True)
    out = {"t": times, "bin": bins}
    for q in ("s_mid", "x_mid", "y_mid", "depth_mid"):
        out[q] = np.asarray(series[q], float)[sel][first]
    for q in ("normal", "shear"):
        m = np.full((len(times), len(bins)), np.nan)
        m[it, ib] = np.asarray(series[q], float)[sel]
        out[q] = m
    return out


def static_ratio(normal, fraction=STATIC_FRACTION):
    """Force over static force per bin: returns (ratio, static, keep).

    ``normal`` is a (time, bin) array whose first row is the static state (t = 0, at opening).
    A bin is kept if its static value is positive and at least ``fraction`` of the largest
    static bin; ratio = normal / static in kept bins, nan in the others.
    """
    normal = np.asarray(normal, float)
    static = normal[0] if len(normal) else np.zeros(normal.shape[1:])
    positive = np.isfinite(static) & (static > 0)
    largest = float(static[positive].max()) if positive.any() else 0.0
    keep = positive & (static >= fraction * largest)
    ratio = np.full(normal.shape, np.nan)
    ratio[:, keep] = normal[:, keep] / static[keep]
    return ratio, static, keep


def cell_edges(centres):
    """Edges of cells around sorted centres (midpoints; the ends mirror the nearest gap)."""
    c = np.asarray(centres, float)
    if len(c) == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = (c[1:] + c[:-1]) / 2
    return np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])


def flow_fit_line(t, cumulative, slope, first=5):
    """The fitted flow line through cumulative removals: returns (t0, t1, intercept) or None.

    summary.json gives only the least-squares slope, from the ``first``-th removal on; the
    least-squares intercept for that slope over the same points is mean(M) - slope mean(t).
    The line is drawn from the first to the last of those points.
    """
    if slope is None or len(t) < first:
        return None
    t, m = np.asarray(t, float)[first - 1:], np.asarray(cumulative, float)[first - 1:]
    return float(t[0]), float(t[-1]), float(np.mean(m) - slope * np.mean(t))


def _fmt(value, spec=".3g"):
    """A number formatted, or 'n/a' for None / non-numbers."""
    return format(value, spec) if isinstance(value, (int, float)) else "n/a"


def _discharge_head(summary):
    """'scene, scheme, dt, law: pattern flow, status S' for discharge figure titles."""
    info = summary.get("discharge") or {}
    return (f"{run_caption(summary)}: {info.get('pattern', '?')} flow, "
            f"status {summary.get('status', '?')}")


def discharge_frames(run_dir, times=None):
    """The data of the frames picture (the paper's Figs. 8, 9): the snapshots nearest to ``times``
    (all if None) and what every panel shares.

    Returns a dict: ``summary``, ``info`` (summary["discharge"]), ``frames`` = [(t, discs,
    contacts or None)], ``r_ref`` (the plot scale's radius), ``walls`` (without the gate),
    ``points`` ({name: (x, y)}), ``n_initial``, ``outlet_y``, ``bounds`` (x0, x1, y0, y1: walls,
    points, outlet and every snapshot's discs, padded by ``pad``), ``pad`` and ``top`` (the
    largest displacement in radii). A reference code's run (no contact files) has contacts None,
    with a note on stderr.
    """
    summary, info = discharge_summary(run_dir)
    snaps = select_snapshots(snapshot_index(run_dir), times)
    # a reference code's run (dem run --engine) has no contact files: its discs without forces
    frames = [(s["t"], read_csv(s["discs"], SNAPSHOT_DISC_COLUMNS),
               read_csv(s["contacts"], CONTACT_COLUMNS) if os.path.exists(s["contacts"]) else None)
              for s in snaps]
    if any(c is None for _, _, c in frames):
        sys.stderr.write(f"dem.compare.figures: {run_dir}: snapshots without contact files (the run gives no "
                         "contact list): frames.png draws the discs only\n")
    r_ref = next((reference_radius(d) for _, d, _ in frames if len(d["r"])), None)
    if r_ref is None:
        _fail(snaps[0]["discs"], "no discs in any snapshot: the plot scale needs disc 0")
    gate = gate_name(summary)
    walls = [w for w in summary["walls"] if w.get("name") != gate]
    points = point_positions(summary, None)
    for _, _, c in frames:
        if c is not None:
            points.update({k: v for k, v in point_positions({}, c).items() if k not in points})
    n_initial = info.get("n_initial") or len(frames[0][1]["r"])
    outlet_y = info.get("outlet_y")

    xs = [c[0] for w in walls for c in (w["from"], w["to"])] + [p[0] for p in points.values()]
    ys = [c[1] for w in walls for c in (w["from"], w["to"])] + [p[1] for p in points.values()]
    if isinstance(outlet_y, (int, float)):
        ys.append(outlet_y)
    for _, d, _ in frames:
        if len(d["r"]):
            xs += [np.min(d["x"] - d["r"]), np.max(d["x"] + d["r"])]
            ys += [np.min(d["y"] - d["r"]), np.max(d["y"] + d["r"])]
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    pad = 0.03 * max(x1 - x0, y1 - y0, 1e-9)
    x0, x1, y0, y1 = x0 - pad, x1 + pad, y0 - pad, y1 + pad

    top = max([float(np.max(displacement_radii(d))) for _, d, _ in frames if len(d["r"])] + [0])
    return {"summary": summary, "info": info, "frames": frames, "r_ref": r_ref, "walls": walls,
            "points": points, "n_initial": n_initial, "outlet_y": outlet_y,
            "bounds": (x0, x1, y0, y1), "pad": pad, "top": top}


def discharge_summary(run_dir):
    """A discharge run's summary.json and its discharge block (discharge_info: refused, naming the
    file, when the run is not a discharge)."""
    spath = os.path.join(run_dir, "summary.json")
    summary = read_summary(spath)
    return summary, discharge_info(summary, spath)


def flow_data(run_dir):
    """The data of the flow picture: ``summary``, ``info`` (summary["discharge"]), ``removals``
    (removals.csv) and ``flow`` (flow_series.csv), each sorted by t, and ``t_end`` (the
    discharge's duration or the last sample, 1 if neither is positive)."""
    summary, info = discharge_summary(run_dir)
    rd = RunDir(run_dir)
    removals = _reading(rd.removals)
    flow = _reading(rd.flow_series)
    order = np.argsort(flow["t"], kind="stable")
    flow = {k: v[order] for k, v in flow.items()}
    order = np.argsort(removals["t"], kind="stable")
    removals = {k: v[order] for k, v in removals.items()}
    duration = info.get("duration")
    t_end = max([float(duration) if isinstance(duration, (int, float)) else 0.0]
                + list(flow["t"][-1:]) + list(removals["t"][-1:])) or 1.0
    return {"summary": summary, "info": info, "removals": removals, "flow": flow, "t_end": t_end}


def wall_ratio_data(run_dir):
    """The data of the wall-ratio picture (the paper's Fig. 10): ``summary``, ``info``,
    ``series`` (wall_series.csv), ``totals`` (wall_totals_series.csv), ``sides`` and ``bottoms``
    (the walls of those groups, the gate left out) and ``strips`` = [(title, walls, coordinate
    column)]: one per side wall (against depth_mid), one for the bottom walls (against x_mid)."""
    summary, info = discharge_summary(run_dir)
    rd = RunDir(run_dir)
    series = _reading(rd.wall_series)
    totals = _reading(rd.wall_totals_series)
    gate = gate_name(summary)
    sides = [w for w in summary["walls"] if str(w.get("group", "")).startswith("side")]
    bottoms = [w for w in summary["walls"]
               if str(w.get("group", "")).startswith("bottom") and w.get("name") != gate]
    strips = [(f"side wall {w['name']}", [w], "depth_mid") for w in sides]
    if bottoms:
        strips.append(("bottom walls (gate left out)", bottoms, "x_mid"))
    if not strips:
        _fail(os.path.join(run_dir, "summary.json"), "no side or bottom wall in 'walls'")
    return {"summary": summary, "info": info, "series": series, "totals": totals, "sides": sides,
            "bottoms": bottoms, "strips": strips}


# --------------------------------------------------------------------------- titles

# Line styles and markers of the separate side walls in the side-wall picture.
SIDE_STYLES = {"side_left": "--", "side_right": ":"}
SIDE_MARKERS = {"side_left": "<", "side_right": ">"}


def network_title(summary, discs, title=None):
    """The network picture's title: ``title`` or 'caption: N discs, t = ..', wrapped, and the scale."""
    head = title or (f"{run_caption(summary)}: {len(discs['r'])} discs, "
                     f"t = {float(summary.get('time', float('nan'))):.4g} s")
    return (textwrap.fill(head, 7 * 12) + "\ncontact forces e_n n + e_s t: "
            f"disc diameter = 50/\u03c0 \u2248 {DIAMETER_IN_DISC_WEIGHTS:.1f} disc weights")


def side_title(summaries, unpaired):
    """The side-wall picture's title (per contact), naming the runs whose rows are not level."""
    note = ("mean of left and right per contact row; "
            "the paper's Fig. 7 shows P_y per contact")
    if unpaired:
        note += f"\nleft and right rows not level in {', '.join(unpaired)}: sides drawn apart"
    return textwrap.fill("Side walls against depth (cf. Kiyama & Fujimura 1983, Fig. 7), "
                         f"{common_caption(summaries)}", 11 * 11) + "\n" + note


def side_bins_title(summaries):
    """The side-wall picture's title per wall_profiles.csv bin."""
    return f"Side walls against depth (cf. Kiyama & Fujimura 1983, Fig. 7), {common_caption(summaries)}"


def frames_title(summary, n_initial, chars):
    """The frames picture's title, wrapped at ``chars`` characters a line."""
    head = (f"{_discharge_head(summary)}: discs and contact forces e_n n + e_s t during "
            f"discharge (cf. Kiyama & Fujimura 1983, Figs. 8, 9)")
    note = (f"t since opening; segment of one disc diameter = 50/\u03c0 \u2248 "
            f"{DIAMETER_IN_DISC_WEIGHTS:.1f} disc weights; gate open; dotted: outlet "
            f"(discs removed); dead = share of the {n_initial} discs at opening")
    return textwrap.fill(head, chars) + "\n" + textwrap.fill(note, chars)


def ratios_title(summary, info):
    """The wall-ratio picture's title with summary.json's peak ratios."""
    head = textwrap.fill(f"{_discharge_head(summary)}: wall forces relative to static "
                         f"(cf. Kiyama & Fujimura 1983, Fig. 10)", 11 * 12)
    return head + (f"\nsummary peak ratios: bottom {_fmt(info.get('peak_ratio_bottom'))} (windowed "
                   f"{_fmt(info.get('peak_ratio_bottom_windowed'))}), side {_fmt(info.get('peak_ratio_side'))} "
                   f"(windowed {_fmt(info.get('peak_ratio_side_windowed'))})")


def flow_title(summary, info):
    """The flow picture's title: discs out, by hand, jams."""
    return textwrap.fill(f"{_discharge_head(summary)}: {_fmt(info.get('removed'), 'd')} of "
                         f"{_fmt(info.get('n_initial'), 'd')} discs out "
                         f"({_fmt(info.get('removed_by_hand'), 'd')} by hand), "
                         f"{_fmt(info.get('jams'), 'd')} jams", 12 * 11)


UNITS = {"cgs": {"length": "cm", "mass": "g"}, "si": {"length": "m", "mass": "kg"}}


def units_of(summary: dict) -> dict:
    """The words of a run's unit system (summary.json options.units: cgs or si), for its labels."""
    return UNITS.get((summary.get("options") or {}).get("units", "cgs"), UNITS["cgs"])

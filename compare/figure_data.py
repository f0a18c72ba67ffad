"""The data of compare.figures' pictures, without matplotlib: reading a run directory (with a
message that names the offending file), captions, and the pure maths of the pictures (contact-force
segments, side-wall profiles). compare.figures re-exports every name; the studies' main processes
(compare.paper_claims in them) import this module alone, so that matplotlib is imported only in
the processes that draw.
"""

import math

import numpy as np

from compare import run_dir as _run_dir
from compare.run_dir import RunDir, RunDirError

# The paper's plot scale: one disc diameter stands for 50/pi (about 16) disc weights.
DIAMETER_IN_DISC_WEIGHTS = 50.0 / math.pi


# Side-wall contacts whose depths differ by at most this much [scene length unit] are taken
# to be at the same depth (left and right contacts of one lattice row).
SAME_DEPTH = 1e-6


def _fail(path, message):
    """Stop with a message that names the offending file."""
    raise SystemExit(f"compare.figures: {path}: {message}")


# --------------------------------------------------------------------------- reading


def _reading(fn, *args, **kwargs):
    """fn(...) of compare.run_dir, its RunDirError a stop that names the file."""
    try:
        return fn(*args, **kwargs)
    except RunDirError as err:
        _fail(err.path, err.message)


def read_csv(path, columns, empty=None):
    """A CSV file of a run as a dict of numpy arrays (compare.run_dir.read_csv); a missing or
    malformed file stops with SystemExit naming it."""
    return _reading(_run_dir.read_csv, path, columns, empty=empty)


def read_summary(path):
    """summary.json (compare.run_dir.read_summary) with a positive ``disc_weight``: the unit of
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

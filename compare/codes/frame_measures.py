"""A discharge's flow measures from a reference code's disc frames, as the engine takes them from
its own discs (engine/src/run/discharge.cpp, docs/outputs.md): flow_series.csv's rows, the top
surface's sink times and the flow pattern, the moved fraction, the jams and the arch.

The frames are the code's particle dumps every ``series_interval`` from the opening on (the
backends' ``read_snapshots``, Snapshot: ids are rows of the case's start). Two measures differ
in what they can read:

- the arch is the shortest chain of OVERLAPPING discs from a disc touching one slit end to one
  touching the other (the engine's chain runs over the pairs with a compressive force: the codes'
  pair forces are not read back, an overlap is their sign);
- a jam is read off the removal log afterwards: ``jam_time`` seconds without a removal while discs
  remain above the floor. The code runs on to the end (it neither stops at a jam nor removes a
  keystone), so every later gap is counted too.
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from dem.compare.cases.common import Snapshot

FLOW_HEADER = ("t,discs_in_silo,discs_below,removed,removed_mass,moved_fraction,surface_left,"
               "surface_centre,surface_right,arch_discs,arch_crown_y")


@dataclass
class Frame:
    """The silo's landmarks as the engine takes them (make_frame in discharge.cpp): the floor and
    the slit are the gate's, the columns at the walls' extreme x."""
    floor: float
    slit_left: float
    slit_right: float
    x_left: float
    x_right: float
    column: float

    @property
    def xc(self) -> float:
        return 0.5 * (self.slit_left + self.slit_right)


def silo_frame(resolved: dict) -> Frame:
    walls = [w for w in resolved["walls"] if w.get("active", True)]
    gate = next(w for w in resolved["walls"] if w["name"] == resolved["discharge"]["gate"])
    xs = [c[0] for w in walls for c in (w["from"], w["to"])]
    gx = (gate["from"][0], gate["to"][0])
    # the engine's default column: 4 cm, or 0.04 m in an SI scene
    default = 0.04 if resolved.get("units", {}).get("system") == "si" else 4.0
    return Frame(floor=min(gate["from"][1], gate["to"][1]), slit_left=min(gx), slit_right=max(gx),
                 x_left=min(xs), x_right=max(xs),
                 column=float(resolved["discharge"].get("surface_column", default)))


def surfaces(s: Snapshot, f: Frame) -> list[float]:
    """Top of the fill (highest disc top above the floor) in the left wall, centre and right wall
    columns; -inf in a column without discs."""
    out = []
    for lo, hi in ((f.x_left, f.x_left + f.column), (f.xc - 0.5 * f.column, f.xc + 0.5 * f.column),
                   (f.x_right - f.column, f.x_right + 1e-12)):
        sel = (s.x >= lo) & (s.x < hi) & (s.y > f.floor)
        out.append(float(np.max(s.y[sel] + s.r[sel])) if np.any(sel) else -math.inf)
    return out


def _feet(s: Snapshot, f: Frame, resolved: dict) -> dict[int, int]:
    """Disc place -> bits (1 left, 2 right): discs touching a point, or a wall at the floor's
    height, with the contact point within 2 r_max of a slit end (find_arch's feet)."""
    rmax = float(np.max(s.r)) if len(s.r) else 0.0
    feet: dict[int, int] = {}
    xy = np.column_stack([s.x, s.y])
    contacts = []    # (disc places, contact x)
    for p in resolved.get("points", []):
        d = np.hypot(s.x - p["at"][0], s.y - p["at"][1])
        contacts += [(i, float(p["at"][0])) for i in np.nonzero(d < s.r)[0]]
    for w in resolved["walls"]:
        if not w.get("active", True) or w["name"] == resolved["discharge"]["gate"]:
            continue
        a, b = np.array(w["from"], float), np.array(w["to"], float)
        ab = b - a
        u = np.clip(((xy - a) @ ab) / float(ab @ ab), 0.0, 1.0)
        c = a + u[:, None] * ab
        d = np.hypot(*(xy - c).T)
        for i in np.nonzero(d < s.r)[0]:
            if abs(c[i, 1] - f.floor) < 1e-9 * (1 + abs(f.floor)):
                contacts.append((i, float(c[i, 0])))
    for i, px in contacts:
        bits = (1 if abs(px - f.slit_left) <= 2 * rmax else 0) | (2 if abs(px - f.slit_right) <= 2 * rmax else 0)
        if bits:
            feet[int(i)] = feet.get(int(i), 0) | bits
    return feet


def arch(s: Snapshot, f: Frame, resolved: dict) -> list[int]:
    """Places (in the snapshot) of the shortest chain of overlapping discs from a left foot to a
    right foot, every disc after the first above the floor; [] when none (or one disc on both)."""
    if len(s.x) == 0:
        return []
    feet = _feet(s, f, resolved)
    if not any(b & 1 for b in feet.values()):
        return []
    xy = np.column_stack([s.x, s.y])
    pairs = cKDTree(xy).query_pairs(2 * float(np.max(s.r)), output_type="ndarray")
    if len(pairs):
        d = np.hypot(*(xy[pairs[:, 0]] - xy[pairs[:, 1]]).T)
        pairs = pairs[d < s.r[pairs[:, 0]] + s.r[pairs[:, 1]]]
    nbr: dict[int, list[int]] = {}
    for i, j in pairs.tolist():
        nbr.setdefault(i, []).append(j)
        nbr.setdefault(j, []).append(i)
    prev = {i: -1 for i, b in sorted(feet.items()) if b & 1}
    q = deque(prev)
    while q:
        i = q.popleft()
        if feet.get(i, 0) & 2:
            path = []
            while i >= 0:
                path.append(i)
                i = prev[i]
            return path if len(path) >= 2 else []
        for j in sorted(nbr.get(i, [])):
            if j not in prev and s.y[j] > f.floor:
                prev[j] = i
                q.append(j)
    return []


def jams(removal_times, frames: list[Snapshot], f: Frame, jam_time: float, duration: float,
         dt: float) -> tuple[float | None, int]:
    """(first jam time, number of jams): a gap of more than jam_time after a removal (or the
    opening) while discs remain above the floor, the jam at the first step past it."""
    times = sorted(float(t) for t in removal_times)
    starts, ends = [0.0] + times, times + [None]
    first, count = None, 0
    for a, b in zip(starts, ends):
        # the first step whose time exceeds a + jam_time; a removal at that step ends the gap
        t_jam = (math.floor((a + jam_time) / dt + 1e-9) + 1) * dt
        if (b is not None and t_jam > b - 0.5 * dt) or t_jam > duration + 0.5 * dt:
            continue
        before = [s for s in frames if s.t <= t_jam + 0.5 * dt]
        if before and np.any(before[-1].y > f.floor):
            count += 1
            first = t_jam if first is None else first
    return first, count


def pattern(sink: list[float | None]) -> str:
    """funnel: the top surface first sinks at a wall column; piping: first at the centre."""
    walls = [t for t in (sink[0], sink[2]) if t is not None]
    t_walls = min(walls) if walls else None
    if t_walls is not None and (sink[1] is None or t_walls < sink[1]):
        return "funnel"
    if sink[1] is not None and (t_walls is None or sink[1] <= t_walls):
        return "piping"
    return "undetermined"


def _f(v: float) -> str:
    return "%.17g" % v if math.isfinite(v) else ("-inf" if v < 0 else "inf" if v > 0 else "nan")


def flow(frames: list[Snapshot], removals: list[tuple[float, int]], mass: np.ndarray, n_initial: int,
         f: Frame, resolved: dict, dt: float) -> dict:
    """flow_series.csv's rows and the summary's measures. ``removals``: (t since opening, id) of
    every disc out, in time order; ``mass``: each start row's mass. The first frame is the
    opening's (t = 0): the positions the moved fraction is measured from."""
    if not frames or abs(frames[0].t) > 0.5 * dt:
        raise ValueError("no disc frame at the opening")
    open_at = {int(i): (x, y) for i, x, y in zip(frames[0].id, frames[0].x, frames[0].y)}
    rmean = float(np.mean(frames[0].r)) if len(frames[0].r) else 0.0
    surf0 = surfaces(frames[0], f)
    sink: list[float | None] = [None, None, None]
    rem_t = np.array([t for t, _ in removals], float)
    rem_m = np.array([mass[i] if i >= 0 else math.nan for _, i in removals], float)
    rows, moved_fraction = [FLOW_HEADER], 0.0
    for s in frames:
        inside = int(np.sum(s.y > f.floor))
        below = len(s.y) - inside
        out = rem_t <= s.t + 0.5 * dt
        removed = int(np.sum(out))
        x0 = np.array([open_at.get(int(i), (math.nan, math.nan)) for i in s.id], float).reshape(-1, 2)
        moved = int(np.sum(np.hypot(s.x - x0[:, 0], s.y - x0[:, 1]) >= s.r))
        moved_fraction = (moved + removed) / n_initial if n_initial else 0.0
        sf = surfaces(s, f)
        for c in range(3):
            if sink[c] is None and not sf[c] > surf0[c] - rmean:
                sink[c] = s.t
        ch = arch(s, f, resolved)
        crown = _f(float(np.max(s.y[ch]))) if ch else ""
        rows.append(f"{_f(s.t)},{inside},{below},{removed},{_f(float(np.sum(rem_m[out])))},{_f(moved_fraction)},"
                    f"{_f(sf[0])},{_f(sf[1])},{_f(sf[2])},{len(ch)},{crown}")
    return {"rows": rows, "sink": sink, "pattern": pattern(sink), "moved_fraction_end": moved_fraction}


def removal_ids(frames: list[Snapshot], times: list[float], dt: float) -> list[int]:
    """The disc of each removal time (in time order) where the code logs only a count (LAMMPS):
    the discs that vanished between two frames are the removals of that interval, the lowest at
    the earlier frame first; -1 where the frames do not tell (a removal after the last frame)."""
    ids = [-1] * len(times)
    order = sorted(range(len(times)), key=lambda k: times[k])
    k = 0
    for a, b in zip(frames, frames[1:]):
        gone = np.setdiff1d(a.id, b.id)
        gone = gone[np.argsort(a.y[np.searchsorted(a.id, gone)], kind="stable")]
        within = [m for m in order[k:] if times[m] <= b.t + 0.5 * dt]
        for m, i in zip(within, gone):
            ids[m] = int(i)
        k += len(within)
    return ids

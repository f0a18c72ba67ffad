"""compare/codes/frame_measures.py: the flow measures of a reference code's discharge, on hand-made frames
whose answers follow from the definitions (docs/outputs.md); each check next to a changed input
that must change its answer."""
from __future__ import annotations

import math

import numpy as np
import pytest

from dem.compare.cases.common import Snapshot
from dem.compare.codes.frame_measures import Frame, arch, flow, jams, pattern, removal_ids, surfaces

# a 10 cm wide floor at y = 0 with the slit [3, 7] (the gate), no points
RESOLVED = {"walls": [{"name": "left", "from": [0, 12], "to": [0, 0]},
                      {"name": "right", "from": [10, 12], "to": [10, 0]},
                      {"name": "bottom_left", "from": [0, 0], "to": [3, 0]},
                      {"name": "gate", "from": [3, 0], "to": [7, 0]},
                      {"name": "bottom_right", "from": [7, 0], "to": [10, 0]}],
            "points": [], "discharge": {"gate": "gate", "surface_column": 2.0}}
F = Frame(floor=0.0, slit_left=3.0, slit_right=7.0, x_left=0.0, x_right=10.0, column=2.0)


def frame(t, xy, ids=None, r=1.0) -> Snapshot:
    xy = np.array(xy, float).reshape(-1, 2)
    ids = np.arange(len(xy)) if ids is None else ids
    return Snapshot.from_columns(t, ids, x=xy[:, 0], y=xy[:, 1], r=np.full(len(xy), r))


# four discs over the slit: A and D rest on the floor within 2 r of the slit ends, each pair of
# neighbours overlaps (centre distances 1.93, 1.7, 1.84 < 2)
BRIDGE = [(2.5, 0.99), (4.2, 1.9), (5.9, 1.9), (7.5, 0.99)]


def test_the_arch_is_the_chain_of_overlapping_discs_from_slit_end_to_slit_end():
    s = frame(0.0, BRIDGE)
    assert sorted(arch(s, F, RESOLVED)) == [0, 1, 2, 3]
    lifted = frame(0.0, BRIDGE[:2] + [(5.9, 2.9)] + BRIDGE[3:])      # C-D 2.49 apart: no chain
    assert arch(lifted, F, RESOLVED) == []
    off_floor = frame(0.0, [(2.5, 1.2)] + BRIDGE[1:])                # A no longer a foot
    assert arch(off_floor, F, RESOLVED) == []


def test_surfaces_are_the_highest_disc_tops_in_the_columns():
    s = frame(0.0, [(1.0, 3.0), (5.0, 7.0), (9.5, 2.0), (5.0, -1.5)])
    assert surfaces(s, F) == [4.0, 8.0, 3.0]
    assert surfaces(frame(0.0, [(5.0, 7.0)]), F)[0] == -math.inf      # an empty column


def test_jams_are_gaps_longer_than_jam_time_while_discs_remain():
    inside = [frame(0.0, [(5.0, 5.0)]), frame(1.0, [(5.0, 5.0)])]
    # gaps 0-0.1, 0.1-0.2, 0.2-0.7 (a jam at the first step past 0.5), 0.7-end (1.01 > 1.0)
    assert jams([0.1, 0.2, 0.7], inside, F, 0.3, 1.0, 0.01) == (pytest.approx(0.51), 1)
    assert jams([0.1, 0.2, 0.7], inside, F, 0.6, 1.0, 0.01) == (None, 0)
    below = [frame(0.0, [(5.0, -2.0)]), frame(1.0, [(5.0, -2.0)])]   # nothing left above the floor
    assert jams([0.1, 0.2, 0.7], below, F, 0.3, 1.0, 0.01) == (None, 0)


def test_the_pattern_is_where_the_surface_sinks_first():
    assert pattern([0.1, 0.2, None]) == "funnel"
    assert pattern([0.3, 0.2, 0.3]) == "piping"
    assert pattern([None, None, None]) == "undetermined"


def test_flow_rows_count_every_disc_once():
    """Four discs, one in each wall column; disc 2 falls below the floor, then leaves (removed at
    0.015); disc 1 moves by more than its radius: moved fraction (1 moved + 1 removed) / 4 at the
    end, and the centre column's surface sinks first: piping."""
    f0 = frame(0.0, [(1.0, 3.0), (5.0, 3.0), (5.0, 1.0), (9.0, 3.0)])
    f1 = frame(0.01, [(1.0, 3.0), (5.0, 2.5), (5.0, -1.0), (9.0, 3.0)])
    f2 = frame(0.02, [(1.0, 3.0), (5.0, 1.5), (9.0, 3.0)], ids=[0, 1, 3])
    mass = np.array([1.0, 2.0, 3.0, 4.0])
    out = flow([f0, f1, f2], [(0.015, 2)], mass, 4, F, RESOLVED, 0.005)
    rows = [r.split(",") for r in out["rows"][1:]]
    assert [r[1:5] for r in rows] == [["4", "0", "0", "0"], ["3", "1", "0", "0"], ["3", "0", "1", "3"]]
    assert out["moved_fraction_end"] == pytest.approx(2 / 4)
    # the centre column's top fell from 4 to 2.5 by 0.02 (more than one mean radius); the walls' stay
    assert out["sink"] == [None, pytest.approx(0.02), None] and out["pattern"] == "piping"
    dropped = flow([f0, f1, f2], [], mass, 4, F, RESOLVED, 0.005)     # a removal log without the row
    assert dropped["rows"][-1].split(",")[3] == "0"


def test_removal_ids_from_frames_take_the_lowest_disc_first():
    a = frame(0.0, [(1.0, 3.0), (5.0, -3.9), (5.0, -2.0)])
    b = frame(0.01, [(1.0, 3.0)], ids=[0])
    assert removal_ids([a, b], [0.004, 0.008], 0.001) == [1, 2]
    assert removal_ids([a, b], [0.004, 0.008, 0.02], 0.001) == [1, 2, -1]   # after the last frame

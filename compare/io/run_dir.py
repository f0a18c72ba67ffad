"""The one reader of a ``dem run`` directory (docs/outputs.md).

``RunDir(path)`` gives:

- ``summary``: summary.json, checked: a JSON object whose ``disc_weight`` is a number >= 0 (0
  without gravity) and whose ``walls`` are a list of walls with ``from`` and ``to`` points; with
  ``strict=True`` (a run of the engine itself) also every key docs/outputs.md promises
  (SUMMARY_KEYS, WALL_KEYS, PROFILE_KEYS, and DISCHARGE_KEYS or SHEAR_KEYS for such runs);
- ``discs()``, ``contacts()``, ``profiles()``: discs.csv, contacts.csv, wall_profiles.csv;
- ``removals()``, ``flow_series()``, ``wall_series()``, ``wall_totals_series()``: a discharge's
  series; ``shear_series()``, ``shear_planes()``: a shear's; ``series(name)`` by file name;
- ``discharge_snapshots()``: the discharge snapshots indexed by discharge_discs.pvd (or, in a run
  without VTU files, discharge_snapshots.csv);
  ``shear_snapshots()``: snapshots/index.json of a shear run;

each CSV as a dict of numpy arrays keyed by column (text columns str, counters int, the rest
float). A file that is missing or malformed raises RunDirError, whose message starts with the
file's path and says what is wrong (the missing file, key or column, the bad line).

The same layout is written by compare/codes/shear_yade.py (a shear's series, snapshots and a
summary.json of its own keys), which is read without ``strict``.
"""
from __future__ import annotations

import csv
import json
import operator
import os
import re
import xml.etree.ElementTree as ET
from functools import cached_property
from pathlib import Path

import numpy as np

# Columns of the engine's CSV files (docs/outputs.md).
CONTACT_COLUMNS = ("kind", "i", "j", "x", "y", "nx", "ny", "e_n", "e_s", "f_n", "f_s")
DISC_COLUMNS = ("id", "x", "y", "r", "vx", "vy", "omega", "material")
PROFILE_COLUMNS = ("wall", "group", "bin", "s_lo", "s_hi", "x_mid", "y_mid", "depth_mid",
                   "normal", "shear", "contacts")
SNAPSHOT_DISC_COLUMNS = DISC_COLUMNS + ("dx", "dy")
REMOVAL_COLUMNS = ("t", "id", "mass", "vx", "vy", "how")
FLOW_COLUMNS = ("t", "discs_in_silo", "discs_below", "removed", "removed_mass", "moved_fraction",
                "surface_left", "surface_centre", "surface_right", "arch_discs", "arch_crown_y")
WALL_SERIES_COLUMNS = ("t", "wall", "bin", "s_mid", "x_mid", "y_mid", "depth_mid", "normal",
                       "shear")
WALL_TOTALS_COLUMNS = ("t", "name", "normal", "shear", "fx", "fy")
SHEAR_SERIES_COLUMNS = ("t", "strain", "angle", "sigma", "tau", "ratio", "sigma_check", "tau_check",
                        "sigma_inertia", "tau_inertia", "sigma_plate", "tau_plate", "plate_x",
                        "plate_y", "plate_vx", "plate_vy", "left_fx", "left_fy", "left_moment",
                        "right_fx", "right_fy", "right_moment", "floor_fx", "floor_fy", "contacts",
                        "sliding", "bond_strain", "kinetic_energy")
SHEAR_PLANE_COLUMNS = ("t", "strain", "plane", "y", "contacts", "sigma", "tau", "sigma_check",
                       "tau_check", "sigma_inertia", "tau_inertia")
# thermo.csv: these columns, then <group>_normal, <group>_shear per wall group of the run.
THERMO_COLUMNS = ("t", "step", "phase", "discs", "kinetic_energy", "contacts", "wall_contacts", "max_overlap")
TEXT_COLUMNS = {"kind", "j", "wall", "group", "material", "how", "name", "phase"}   # kept as str
INT_COLUMNS = {"i", "id", "bin", "contacts", "step", "wall_contacts"}                              # converted to int

# The files of a run and their columns; the series of a shear are read by their header (a
# YADE shear run writes the columns it has), the others need every column named here.
FILES = {
    "discs.csv": DISC_COLUMNS,
    "contacts.csv": CONTACT_COLUMNS,
    "wall_profiles.csv": PROFILE_COLUMNS,
    "removals.csv": REMOVAL_COLUMNS,
    "flow_series.csv": FLOW_COLUMNS,
    "wall_series.csv": WALL_SERIES_COLUMNS,
    "wall_totals_series.csv": WALL_TOTALS_COLUMNS,
    "shear_series.csv": SHEAR_SERIES_COLUMNS,
    "shear_planes.csv": SHEAR_PLANE_COLUMNS,
    "thermo.csv": THERMO_COLUMNS,
}

# The keys docs/outputs.md promises in summary.json.
SUMMARY_KEYS = ("engine", "scene", "status", "options", "n_discs", "steps", "time", "wall_time_s",
                "particle_steps_per_s", "rest", "weight", "disc_weight", "height", "width", "walls",
                "points", "groups", "balance", "derived", "stability")
SCENE_KEYS = ("name", "file", "description")
OPTION_KEYS = ("scheme", "dt", "dt_forced", "normal_spring", "no_tension", "friction_cap", "gravity")
REST_KEYS = ("reached", "time", "criterion", "mean_abs_du", "mean_abs_dv", "threshold")
WALL_KEYS = ("name", "group", "from", "to", "normal_total", "shear_total", "force", "contacts",
             "profile")
PROFILE_KEYS = ("s_lo", "s_hi", "depth_mid", "x_mid", "normal", "shear", "contacts")
POINT_KEYS = ("name", "force", "contacts")
GROUP_KEYS = ("normal_total", "shear_total", "force")
BALANCE_KEYS = ("weight", "walls_vertical", "residual_relative")
STABILITY_KEYS = ("dt_bound", "limited_by", "dt_single_contact", "dt_rotation_z4", "dt_rotation_z6",
                  "dt_clusters", "cluster_shapes", "clusters_not_examined")
DISCHARGE_KEYS = ("n_initial", "removed", "removed_by_hand", "discs_out_at_1s", "duration", "t_open",
                  "flow_rate_mass", "flow_rate_discs", "jammed", "jam_at", "jams", "peak_ratio_bottom",
                  "peak_ratio_side", "peak_ratio_bottom_windowed", "peak_ratio_side_windowed",
                  "pattern", "surface_sink_time", "dead_fraction_end")
SHEAR_KEYS = ("width", "rate", "max_strain", "plate_horizontal", "plate_mass", "plate_weight",
              "discs_weight", "rows", "planes", "bonds", "samples", "sigma_initial", "sigma_plate_load",
              "peak_ratio", "strain_at_peak", "peak_ratio_windowed", "strain_at_peak_windowed",
              "window_strain", "ratio_final", "strain_final", "check_static_max_relative",
              "check_with_inertia_max_relative", "plate_final", "bond_strain_final", "snapshots",
              "duration")
STATUSES = {"rest", "end_time", "unstable", "interrupted", "discharged", "jammed", "emptied", "sheared"}


class RunDirError(Exception):
    """A file of a run directory that is missing or malformed: ``path``, ``message``."""

    def __init__(self, path, message):
        super().__init__(f"{path}: {message}")
        self.path = str(path)
        self.message = message


# --------------------------------------------------------------------------- files

def read_csv(path, columns, empty=None, extra=False):
    """A CSV file with the given columns as a dict of numpy arrays.

    A header naming the columns (all of them, in any order, maybe with others: returned too with
    ``extra``, e.g. discs.csv's ``phi``) maps them by name; a file without a header holds
    exactly ``columns`` in order. Columns in TEXT_COLUMNS stay strings, INT_COLUMNS become int,
    the others float. An empty file (or a header alone) gives arrays of length 0. With ``empty``
    given (e.g. nan), an empty cell of a float column reads as that value (flow_series.csv leaves
    the arch columns empty when there is no arch); otherwise it is an error."""
    path = str(path)
    if not os.path.isfile(path):
        raise RunDirError(path, "file is missing")
    text = _plain_text(path)
    if text is not None:
        data = _numpy_columns(text, columns, extra)
        if data is not None:
            return data
    rows = None if text is None else [(n, line.split(",")) for n, line in enumerate(text.split("\n"), 1) if line]
    if rows is None:
        try:
            with open(path, newline="") as f:
                rows = [(n, [c.strip() for c in row]) for n, row in enumerate(csv.reader(f), 1) if row]
        except (OSError, UnicodeDecodeError, csv.Error) as err:
            raise RunDirError(path, f"cannot be read: {err}") from None
    layout = _layout(rows[0][1] if rows else [], columns, extra)
    if layout is None:
        first, names = rows[0][1], list(columns)
        missing = [c for c in names if c not in first]
        raise RunDirError(path, f"line 1: the header {','.join(first)} has no column "
                                f"{', '.join(repr(c) for c in missing)}")
    header, has_header, names_out = layout
    if has_header:
        rows = rows[1:]
    index = {name: k for k, name in enumerate(header)}
    if any(len(row) != len(header) for _, row in rows):
        line, row = next((line, row) for line, row in rows if len(row) != len(header))
        raise RunDirError(path, f"line {line}: expected {len(header)} fields "
                                f"({','.join(header)}), found {len(row)}")
    cells = list(zip(*(row for _, row in rows))) or [()] * len(header)   # one tuple a column
    data = {}
    for name in names_out:
        k = index[name]
        text, integer = name in TEXT_COLUMNS, name in INT_COLUMNS
        if not text:
            # The whole column at once (numpy converts each cell as int() or float() does); a cell
            # it refuses (empty, or not a number) is read again one by one below, for the message.
            try:
                data[name] = np.array(cells[k], dtype=int if integer else float)
                continue
            except ValueError:
                pass
        values = []
        for line, row in rows:
            cell = row[k]
            if not text and empty is not None and cell == "" and not integer:
                cell = empty
            elif not text:
                try:
                    cell = int(cell) if integer else float(cell)
                except ValueError:
                    raise RunDirError(path, f"line {line}: column '{name}' is not a number: {cell!r} "
                                            f"(expected header {','.join(header)})") from None
            values.append(cell)
        dtype = str if text else int if integer else float
        data[name] = np.array(values, dtype=dtype)
    return data


# The largest file read as plain text (16 MiB: a 10k-disc contacts.csv is about 2 MB).
PLAIN_MAX_BYTES = 16 << 20
# Characters that make a CSV file other than plain comma-separated cells: quotes, and the
# whitespace (other than the line feed) that str.strip would take off a cell, or a NUL.
_NOT_PLAIN = re.compile('[" \t\r\x00\x0b\x0c\x1c-\x1f]')


def _plain_text(path):
    """The text of a plain file (ASCII, no quotes, no whitespace but line feeds), whose rows are
    its lines split on commas: the same cells as csv.reader and str.strip give, without a Python
    call a cell. None for any other file (or one that cannot be read): read_csv reads it with
    csv.reader, and says what is wrong with it. A file over PLAIN_MAX_BYTES goes to csv.reader
    too: its text and lines held beside its cells would add to the peak memory (a 1M-disc
    contacts.csv)."""
    try:
        if os.path.getsize(path) > PLAIN_MAX_BYTES:
            return None
        with open(path, newline="") as f:
            text = f.read()
    except (OSError, UnicodeDecodeError):
        return None
    if not text.isascii() or _NOT_PLAIN.search(text):
        return None
    return text


def _layout(first, columns, extra):
    """(header, whether the first row is it, the columns returned) of a file whose first row is
    ``first``: a header naming every column asked for maps them by name (the others returned only
    with ``extra``); a first row of numbers, or of cells that are mostly not column names, is data
    and the file holds ``columns`` in order. None: a header without some column asked for."""
    names = list(columns)
    if first == names or (set(names) <= set(first) and not _numeric(first)):
        return first, True, (first if extra else names)
    if first and not _numeric(first) and 2 * len(set(first) & set(names)) >= len(first):
        return None
    return names, False, names


def _numpy_columns(text, columns, extra):
    """read_csv's arrays of a plain file, its numbers converted by numpy's C reader (np.loadtxt:
    4-8x faster than a Python split of every line, and the same doubles: both round correctly,
    tests/python/test_run_dir.py), or None where read_csv's own reading is needed: no data row, a
    header without a column asked for, rows of another number of fields, an empty cell or one
    that is not a number (read_csv then says what is wrong, on which line). Integer columns are
    converted from their text by int() as read_csv does (np.loadtxt would take 1.0 for 1)."""
    lines = [line for line in text.split("\n") if line]
    if not lines:
        return None
    layout = _layout(lines[0].split(","), columns, extra)
    if layout is None:                 # a header without a column asked for: read_csv's error
        return None
    header, has_header, names_out = layout
    body = lines[1:] if has_header else lines
    if not body or set(map(operator.methodcaller("count", ","), body)) != {len(header) - 1}:
        return None
    index = {name: k for k, name in enumerate(header)}
    floats = [n for n in names_out if n not in TEXT_COLUMNS and n not in INT_COLUMNS]
    texts = [n for n in names_out if n in TEXT_COLUMNS or n in INT_COLUMNS]
    data = {}
    try:
        if floats:
            table = np.loadtxt(body, dtype=float, delimiter=",", comments=None, ndmin=2,
                               usecols=[index[n] for n in floats])
            data.update((n, np.ascontiguousarray(table[:, k])) for k, n in enumerate(floats))
        if texts:
            table = np.loadtxt(body, dtype=str, delimiter=",", comments=None, ndmin=2,
                               usecols=[index[n] for n in texts])
            for k, n in enumerate(texts):
                cells = table[:, k]
                data[n] = cells.astype(int) if n in INT_COLUMNS else np.array(cells.tolist(), dtype=str)
    except ValueError:
        return None
    return {n: data[n] for n in names_out}


def _numeric(cells) -> bool:
    try:
        [float(c) for c in cells]
        return True
    except ValueError:
        return False


def read_header_csv(path, needed=()):
    """A CSV file of numbers with a header (a shear's series, as the engine or YADE writes
    them): a dict of float arrays, one per column the header names; ``needed`` columns must be
    among them."""
    path = str(path)
    if not os.path.isfile(path):
        raise RunDirError(path, "file is missing")
    with open(path) as f:
        head = f.readline().strip().split(",")
    for c in needed:
        if c not in head:
            raise RunDirError(path, f"no column '{c}' (header {','.join(head)})")
    try:
        data = np.genfromtxt(path, delimiter=",", skip_header=1, ndmin=2, invalid_raise=True)
    except ValueError as err:
        raise RunDirError(path, f"not a table of numbers: {err}") from None
    if data.size == 0:
        return {c: np.zeros(0) for c in head}
    if data.shape[1] != len(head):
        raise RunDirError(path, f"{data.shape[1]} columns, the header names {len(head)}")
    return {c: data[:, k] for k, c in enumerate(head)}


def read_json(path):
    """A JSON file's object; missing, unreadable or not an object raises RunDirError."""
    path = str(path)
    if not os.path.isfile(path):
        raise RunDirError(path, "file is missing")
    try:
        with open(path) as f:
            data = json.load(f)
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise RunDirError(path, f"not valid JSON: {err}") from None
    if not isinstance(data, dict):
        raise RunDirError(path, "expected a JSON object")
    return data


def _require(path, obj, keys, where):
    missing = [k for k in keys if k not in obj]
    if missing:
        raise RunDirError(path, f"{where} has no {', '.join(repr(k) for k in missing)} "
                                "(docs/outputs.md promises them)")


def check_summary(summary, path="summary.json", strict=False):
    """Checks a summary.json dict (see the module's docstring); returns it."""
    weight = summary.get("disc_weight")
    if not isinstance(weight, (int, float)) or isinstance(weight, bool) or not weight >= 0:
        raise RunDirError(path, f"'disc_weight' must be a number >= 0, found {weight!r}")
    walls = summary.get("walls")
    if not isinstance(walls, list):
        raise RunDirError(path, "'walls' must be a list")
    for w in walls:
        if not (isinstance(w, dict) and len(w.get("from", ())) == 2 and len(w.get("to", ())) == 2):
            raise RunDirError(path, f"wall without 'from'/'to' points: {w!r}")
    if not strict:
        return summary
    _require(path, summary, SUMMARY_KEYS, "the summary")
    if summary["status"] not in STATUSES:
        raise RunDirError(path, f"'status' {summary['status']!r} is none of {', '.join(sorted(STATUSES))}")
    for key, keys in (("scene", SCENE_KEYS), ("options", OPTION_KEYS), ("rest", REST_KEYS),
                      ("balance", BALANCE_KEYS), ("stability", STABILITY_KEYS)):
        if not isinstance(summary[key], dict):
            raise RunDirError(path, f"'{key}' must be an object")
        _require(path, summary[key], keys, f"'{key}'")
    for w in walls:
        _require(path, w, WALL_KEYS, f"wall {w.get('name')!r}")
        _require(path, w["profile"], PROFILE_KEYS, f"the profile of wall {w['name']!r}")
    for p in summary["points"]:
        _require(path, p, POINT_KEYS, f"point {p.get('name')!r}")
    for name, g in summary["groups"].items():
        _require(path, g, GROUP_KEYS, f"group {name!r}")
    if "discharge" in summary:
        _require(path, summary["discharge"], DISCHARGE_KEYS, "'discharge'")
    if "shear" in summary:
        _require(path, summary["shear"], SHEAR_KEYS, "'shear'")
    return summary


def read_summary(path, strict=False):
    """summary.json, checked (check_summary)."""
    return check_summary(read_json(path), str(path), strict)


def read_pvd(path):
    """The DataSets of a ParaView collection (.pvd) as (timestep, file) pairs sorted by time
    (stable: equal times keep their order in the file). ``file`` is as written (relative to
    the .pvd's folder)."""
    path = str(path)
    if not os.path.isfile(path):
        raise RunDirError(path, "file is missing")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as err:
        raise RunDirError(path, f"not valid XML: {err}") from None
    found = []
    for ds in root.iter("DataSet"):
        try:
            t = float(ds.get("timestep"))
        except (TypeError, ValueError):
            raise RunDirError(path, f"DataSet without a numeric timestep: {ds.attrib}") from None
        if not ds.get("file"):
            raise RunDirError(path, f"DataSet without a file: {ds.attrib}")
        found.append((t, ds.get("file")))
    return sorted(found, key=lambda pair: pair[0])


def _same_time(a, b):
    return abs(a - b) <= 1e-9 * max(1.0, abs(a), abs(b))


# --------------------------------------------------------------------------- the directory

class RunDir:
    """One run directory of ``dem run`` (or of a discharge's ensemble member)."""

    def __init__(self, path, strict=False):
        self.path = Path(path)
        self.strict = strict

    def __repr__(self):
        return f"RunDir({str(self.path)!r})"

    def file(self, name) -> Path:
        """The path of one of the run's files (whether or not it is there)."""
        return self.path / name

    def has(self, name) -> bool:
        return self.file(name).is_file()

    @cached_property
    def summary(self) -> dict:
        return read_summary(self.file("summary.json"), self.strict)

    @property
    def status(self) -> str:
        return self.summary.get("status", "")

    def is_discharge(self) -> bool:
        return isinstance(self.summary.get("discharge"), dict)

    def is_shear(self) -> bool:
        return isinstance(self.summary.get("shear"), dict)

    def csv(self, name, empty=None):
        """One of FILES as a dict of arrays (read_csv with its columns)."""
        if name not in FILES:
            raise KeyError(f"{name}: not a CSV file of a run directory ({', '.join(FILES)})")
        if name in ("shear_series.csv", "shear_planes.csv"):
            return read_header_csv(self.file(name), ("strain", "sigma", "tau") +
                                   (("ratio",) if name == "shear_series.csv" else ()))
        if name == "thermo.csv":  # its wall-group columns are the run's own
            return read_csv(self.file(name), THERMO_COLUMNS, extra=True)
        return read_csv(self.file(name), FILES[name], empty=empty, extra=(name == "discs.csv"))

    def discs(self):
        """discs.csv (with ``phi`` when the run integrated the rotation angle)."""
        return self.csv("discs.csv")

    def contacts(self):
        return self.csv("contacts.csv")

    def profiles(self):
        return self.csv("wall_profiles.csv")

    def removals(self):
        return self.csv("removals.csv")

    def flow_series(self):
        """flow_series.csv; the arch columns are NaN where there was no arch."""
        return self.csv("flow_series.csv", empty=float("nan"))

    def wall_series(self):
        return self.csv("wall_series.csv")

    def wall_totals_series(self):
        return self.csv("wall_totals_series.csv")

    def shear_series(self):
        return self.csv("shear_series.csv")

    def shear_planes(self):
        return self.csv("shear_planes.csv")

    def thermo(self):
        """thermo.csv: the run's global measures in every phase (``phase`` as str)."""
        return self.csv("thermo.csv")

    def series(self, name):
        """A series by its short name: removals, flow, wall, wall_totals, shear, shear_planes."""
        files = {"removals": "removals.csv", "flow": "flow_series.csv", "wall": "wall_series.csv",
                 "wall_totals": "wall_totals_series.csv", "shear": "shear_series.csv",
                 "shear_planes": "shear_planes.csv"}
        if name not in files:
            raise KeyError(f"no series {name!r} ({', '.join(files)})")
        return self.flow_series() if name == "flow" else self.csv(files[name])

    def discharge_snapshots(self):
        """The discharge snapshots: a list of {"t", "discs", "contacts"} sorted by t (paths).

        Times (since opening) come from discharge_discs.pvd's timestep attributes; each VTU file
        named there has a CSV twin of the same stem (snapshots/discs_NNNN.csv). The contacts CSV
        is the twin of discharge_contacts.pvd's file at the same time, or, without that .pvd or
        time, the discs file's name with 'discs_' replaced by 'contacts_'. A run without VTU files
        (`--no-vtu`, output.vtu = "none") lists them in discharge_snapshots.csv (t, discs,
        contacts: the CSV files, relative to the run), with the times the .pvd would give."""
        index = self.file("discharge_snapshots.csv")
        if not self.file("discharge_discs.pvd").is_file() and index.is_file():
            lines = index.read_text().splitlines()
            if not lines or lines[0] != "t,discs,contacts":
                raise RunDirError(index, "the header must be t,discs,contacts")
            snaps = []
            for n, line in enumerate(lines[1:], 2):
                cells = line.split(",")
                try:
                    snaps.append({"t": float(cells[0]), "discs": os.path.join(str(self.path), cells[1]),
                                  "contacts": os.path.join(str(self.path), cells[2])})
                except (ValueError, IndexError):
                    raise RunDirError(index, f"line {n}: expected t,discs,contacts, found {line!r}") from None
            return sorted(snaps, key=lambda s: s["t"])
        discs = read_pvd(self.file("discharge_discs.pvd"))
        contacts_pvd = self.file("discharge_contacts.pvd")
        contacts = read_pvd(contacts_pvd) if contacts_pvd.is_file() else []
        snaps = []
        for t, name in discs:
            match = [c for tc, c in contacts if _same_time(t, tc)]
            if match:
                cname = match[0]
            else:
                folder, base = os.path.split(name)
                cname = os.path.join(folder, base.replace("discs_", "contacts_", 1))
            snaps.append({"t": t,
                          "discs": os.path.join(str(self.path), os.path.splitext(name)[0] + ".csv"),
                          "contacts": os.path.join(str(self.path), os.path.splitext(cname)[0] + ".csv")})
        return snaps

    def shear_snapshots(self):
        """snapshots/index.json of a shear run: its list of snapshots (``strain``, ``t``, the
        ``discs`` and ``contacts`` file names in snapshots/, the walls at that moment)."""
        path = self.file(os.path.join("snapshots", "index.json"))
        index = read_json(path).get("snapshots")
        if not isinstance(index, list):
            raise RunDirError(path, "'snapshots' must be a list")
        return index

    def snapshot_csv(self, name, columns):
        """A snapshot's CSV file (a name relative to the run directory) with the given columns."""
        return read_csv(self.file(name), columns, extra=True)

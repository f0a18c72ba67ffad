"""The shear kind: paper 2's simple shear box (Sumita, Kiyama & Nishimura) as one comparison case.

A shear case (``Case.mode == "shear"``) is a scene with ``[shear_box]`` and ``[shear]`` (and
optionally ``[clusters]``): the discs (one jittered member) are compressed under the free plate
to rest (at most ``end.time``: the case's ``settle``), then both side walls turn about their lower
ends until gamma = tan(angle) reaches ``shear.max_strain``. Every code writes the engine's shear
outputs (docs/outputs.md, "Shear outputs": ``shear_series.csv``, ``summary.json``), read here
into ``Result.extra["shear"]``; the judge (compare/verdict/shear_judge.py) compares the
paper's outputs across codes.

What each backend takes from here: the box (plate height and reach for the case's own discs:
``box``), the engine's bond list (``bonds_of``, compare/cases/shear_stability.py), the stable dt of the shared scheme
(``stable_dt``, from the engine's bound), LIGGGHTS' refusal (``liggghts_refusal``) and the common reader
(``read_outputs``).
"""
from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from dem.compare.cases.common import SHARED_VARIANT, CaseError, stability
from dem.compare.cases.shear_stability import engine_bonds
from dem.compare.io.run_dir import RunDir

WINDOW = 0.011           # strain over which the windowed peak averages tau/sigma
BANDS = ((0.0, 0.02), (0.02, 0.05), (0.05, 0.10), (0.10, 0.15))   # strain bands of the curve
SERIES_COLUMNS = ("t", "strain", "sigma", "tau", "ratio", "plate_x", "plate_y", "sigma_plate", "tau_plate",
                  "kinetic_energy")
MEASURES = ("sigma0", "peak_windowed", "dilation")   # besides the bands
VV_SAFETY = 0.7          # dt at most this fraction of the velocity Verlet bound of the clusters

bonds_of = engine_bonds  # the engine's bond list (the backends' and the judge's name)


def is_shear(resolved: dict) -> bool:
    return "shear_box" in resolved and "shear" in resolved


def shear_time(resolved: dict) -> float:
    """[s] from the start of the shear to shear.max_strain."""
    sh = resolved["shear"]
    return math.atan(float(sh["max_strain"])) / float(sh["rate"])


def shared_bound(scene) -> float:
    """[s] The engine's time-step bound of the scene run with the shared scheme (velocity Verlet)
    and the shared contact law: its single contacts, a disc's rotation on 4 contacts and its
    clusters with their touching neighbours held (``dem resolve --stability``)."""
    sets = {"integrator.scheme": "velocity_verlet", **{f"contact.{k}": v for k, v in SHARED_VARIANT.items()}}
    return float(stability(scene, sets)["dt_bound"])


def stable_dt(scene, dt: float) -> float:
    """The scene's dt halved until it is at most VV_SAFETY x the engine's bound of the shared
    scheme (``shared_bound``): velocity Verlet's bound with bonds across a gap is about a third of
    paper 2's eq. (19)'s."""
    bound = shared_bound(scene)
    while dt > VV_SAFETY * bound:
        dt *= 0.5
    return dt


def box(resolved: dict, discs) -> dict:
    """The box for the case's own discs (x, y, r rows): the plate plate_gap above the highest
    disc (the gap of the scene's own start, as the engine places it) and reaching plate_overhang
    beyond each side wall; the side walls' and the floor's material."""
    b = resolved["shear_box"]
    walls = {w["name"]: w for w in resolved["walls"]}
    for name in ("left", "right", "floor", "plate"):
        if name not in walls:
            raise CaseError(f"shear_box: the resolved scene has no wall {name!r}")
    plate = walls["plate"]
    scene = np.asarray(resolved["discs"], float)
    d = np.asarray(discs, float)
    gap = float(b["plate_y"]) - float(np.max(scene[:, 1] + scene[:, 2]))
    width = float(b["width"])
    return {"width": width, "height": float(b["height"]), "wall_length": float(b["wall_length"]),
            "plate_y": float(np.max(d[:, 1] + d[:, 2])) + gap, "plate_gap": gap,
            "plate_mass": float(b["plate_mass"]), "plate_volume": float(b["plate_volume"]),
            "plate_density": float(b["plate_density"]),
            "plate_overhang": 0.5 * (float(plate["to"][0]) - float(plate["from"][0])) - 0.5 * width,
            "plate_horizontal": b["plate_horizontal"], "wall_material": walls["left"]["material"],
            "plate_material": b["plate_material"]}


def liggghts_refusal(resolved: dict) -> str:
    """Why LIGGGHTS-PUBLIC 3.8.0 (Debian's build, the one compared) cannot run a shear-box
    scene; checked against the binary: ``bond_style harmonic`` is its only bond style (with
    ``atom_style molecular``), and mesh walls move only by prescribed motion (``fix move/mesh``)
    or by a one-axis force servo (``mesh/surface/stress/servo``)."""
    why = []
    if "clusters" in resolved:
        why.append("clusters.bonds: paper 2's bonds carry a normal AND a shear spring with dashpots, act in "
                   "tension and turn the discs through their lever arms; LIGGGHTS-PUBLIC 3.8.0's only bond "
                   "style is `bond_style harmonic` (atom_style molecular), a central spring without shear "
                   "spring, torque or dashpot, and its rigid bodies (fix rigid, fix multisphere) are not elastic")
    b = resolved.get("shear_box")
    if b is not None:
        horiz = ("free horizontally as well" if b["plate_horizontal"] == "free"
                 else "horizontally tied to the side walls at its height (plate_horizontal = 'with_walls')")
        why.append(f"shear_box.plate_mass: the plate is a rigid wall of mass {b['plate_mass']!r} g moved "
                   f"vertically by gravity and the discs' forces, {horiz}; LIGGGHTS moves a mesh wall only by a "
                   "prescribed motion (fix move/mesh) or by a one-axis force servo without mass "
                   "(mesh/surface/stress/servo), and a plate of particles would not be a flat wall (the side "
                   "walls' turning alone is expressible: fix move/mesh rotate)")
    return "; ".join(why)


# ----------------------------------------------------------------------------- reading

def read_outputs(run_dir: Path) -> dict:
    """shear_series.csv and summary.json of a shear run (the engine's or the YADE script's) in
    the common form: {"series": {column: [values]} (SERIES_COLUMNS present in the file),
    "status", "rest_reached", "rest_time", "planes", "bonds", "plate_weight", "width"}."""
    run_dir = Path(run_dir)
    s = RunDir(run_dir).summary  # the engine's, or the YADE script's with the same keys
    with open(run_dir / "shear_series.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    cols = [c for c in SERIES_COLUMNS if rows and c in rows[0]]
    series = {c: [float(r[c]) for r in rows] for c in cols}
    sh = s.get("shear") or {}
    rest = s.get("rest") or {}
    return {"series": series, "status": s.get("status"), "rest_reached": bool(rest.get("reached")),
            "rest_time": rest.get("time"), "planes": sh.get("planes"), "bonds": sh.get("bonds"),
            "plate_weight": sh.get("plate_weight"), "width": sh.get("width")}


def windowed_peak(strain: np.ndarray, ratio: np.ndarray, window: float = WINDOW) -> float:
    """Largest centred moving average of tau/sigma over ``window`` of strain."""
    if len(ratio) == 0:
        return float("nan")
    step = float(np.median(np.diff(strain))) if len(strain) > 1 else window
    half = max(1, int(round(0.5 * window / step))) if step > 0 else 1
    return max(float(np.mean(ratio[max(0, q - half):q + half + 1])) for q in range(len(ratio)))


def bands(max_strain: float) -> list[tuple[float, float]]:
    """BANDS cut at the case's max_strain (a band with less than 0.005 of strain is left out)."""
    out = []
    for lo, hi in BANDS:
        hi = min(hi, max_strain)
        if hi - lo >= 0.005 - 1e-12:
            out.append((lo, hi))
    return out


def band_key(lo: float, hi: float) -> str:
    return f"ratio_{lo:g}_{hi:g}"


def measures(extra: dict, max_strain: float) -> dict:
    """One member's measures from read_outputs' dict."""
    s = {k: np.asarray(v, float) for k, v in extra["series"].items()}
    strain, ratio = s["strain"], s["ratio"]
    if len(strain) < 2 or not np.all(np.isfinite(ratio)):
        return {}
    k = int(np.argmax(ratio))
    out = {"sigma0": float(s["sigma"][0]), "peak_windowed": windowed_peak(strain, ratio),
           "peak_raw": float(ratio[k]), "strain_at_peak": float(strain[k]),
           "dilation": float(s["plate_y"][-1] - s["plate_y"][0]), "strain_end": float(strain[-1]),
           "rest_reached": bool(extra.get("rest_reached"))}
    for lo, hi in bands(max_strain):
        sel = (strain >= lo - 1e-9) & (strain < hi - 1e-9) if hi < max_strain - 1e-9 else (strain >= lo - 1e-9)
        out[band_key(lo, hi)] = float(np.mean(ratio[sel])) if np.any(sel) else float("nan")
    return out


def curve(extra: dict, grid: np.ndarray, column: str) -> np.ndarray:
    s = extra["series"]
    return np.interp(grid, np.asarray(s["strain"], float), np.asarray(s[column], float), right=np.nan)


# ----------------------------------------------------------------------------- judging

LABELS = {"sigma0": "initial normal stress sigma0 (start of the shear)",
          "peak_windowed": f"peak tau/sigma (windowed over {WINDOW:g} of strain)",
          "dilation": "dilation (plate rise over the shear) [cm]",
          "peak_raw": "raw peak tau/sigma (largest sample)", "strain_at_peak": "strain at the raw peak"}


def label(key: str) -> str:
    if key.startswith("ratio_"):
        lo, hi = key[len("ratio_"):].split("_")
        return f"mean tau/sigma for strain {lo} .. {hi}"
    return LABELS.get(key, key)

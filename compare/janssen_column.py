"""The Janssen column as an ensemble in any of the three codes.

A member is the column scene's loose start (reference_inputs/scenes/janssen_column.toml,
scripts/make_janssen_scene.py) with every disc moved by a seeded uniform jitter of +-JITTER cm
in x and y, run with the shared contact law in two stages in the same code:

1. fill: the grid falls and settles for FILL seconds;
2. the discs touching the floor (bottom within 0.05 cm of the floor plus the largest radius) are
   taken away, velocities zeroed, and the column drops onto the next layer and settles for
   RESETTLE seconds: the discs slide down along the walls, which is what mobilises the wall
   friction (member_record measures how much).

``member_record`` keeps what the Janssen analysis needs: the side-wall pressure per bin (mean of
both walls) against height, the packing fraction and surface, the weight, the floor force and
the wall friction (global balance), the mobilised wall friction (signed sum of shear over sum of
normal force on the side walls) in the upper part and overall, the largest overlap relative to
the radius and the wall time of the code.

    /usr/bin/python3 -m compare.janssen_column CODE MEMBERS OUT_DIR [FIRST]

runs members FIRST .. FIRST+MEMBERS-1 of CODE (native, liggghts or yade) and writes
OUT_DIR/CODE/member_NN.json (a member already written is kept);

    /usr/bin/python3 -m compare.janssen_column analyse OUT_DIR

fits every code's ensemble found there (``analyse``), compares each with native and writes
OUT_DIR/janssen_column.json and OUT_DIR/janssen_column.png.
"""
from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from . import janssen
from .common import ROOT, SHARED_VARIANT, Case, resolve, write_text_atomic

SCENE = ROOT / "reference_inputs" / "scenes" / "janssen_column.toml"
DT = 2e-5          # s
FILL = 1.2         # s, stage 1
RESETTLE = 0.6     # s, stage 2
JITTER = 0.04      # cm
FLOOR_GAP = 0.05   # cm: a disc whose bottom is below floor + r_max + FLOOR_GAP is in the floor layer
UPPER = 0.5        # the upper part: the top half of the fill


def resolved_scene(scene: Path = SCENE) -> dict:
    r = resolve(scene)
    r["contact"] = dict(SHARED_VARIANT)
    return r


def geometry(resolved: dict) -> dict:
    walls = resolved["walls"]
    xs = [c for w in walls for c in (w["from"][0], w["to"][0])]
    ys = [c for w in walls for c in (w["from"][1], w["to"][1])]
    rho = next(m["density"] for m in resolved["materials"] if m["density"] > 0)
    return {"width": max(xs) - min(xs), "floor": min(ys), "rho_s": rho,
            "g": float(np.linalg.norm(resolved["gravity"])),
            "mu_w": next(p["mu"] for p in resolved["pairs"] if "wall" in p["materials"])}


def member_start(resolved: dict, member: int, jitter: float = JITTER) -> np.ndarray:
    """(n, 6) start of one member: the loose start moved by a jitter seeded with the member."""
    d = np.array(resolved["discs"], float)
    rng = np.random.default_rng(7919 + member)
    xy = d[:, :2] + rng.uniform(-jitter, jitter, size=(len(d), 2))
    return np.column_stack([xy, d[:, 2], np.zeros((len(d), 3))])


def cut_floor_layer(discs: np.ndarray, floor: float) -> np.ndarray:
    d = np.array(discs, float)
    keep = d[:, 1] - d[:, 2] > floor + FLOOR_GAP + d[:, 2].max()
    out = d[keep]
    out[:, 3:] = 0.0
    return out


def max_overlap_ratio(discs: np.ndarray, width: float, floor: float) -> float:
    """Largest overlap (disc-disc or disc-wall) over the smaller radius."""
    d = np.asarray(discs, float)
    x, y, r = d[:, 0], d[:, 1], d[:, 2]
    worst = float(np.max(np.concatenate([(r - x) / r, (x + r - width) / r, (floor + r - y) / r])))
    tree = cKDTree(d[:, :2])
    pairs = tree.query_pairs(2 * r.max(), output_type="ndarray")
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        gap = np.hypot(x[i] - x[j], y[i] - y[j]) - r[i] - r[j]
        worst = max(worst, float(np.max(-gap / np.minimum(r[i], r[j]))))
    return max(worst, 0.0)


def member_record(resolved: dict, res, code: str, member: int, wall_time: float) -> dict:
    """The Janssen quantities of one settled member (``res``: the common Result of stage 2)."""
    geo = geometry(resolved)
    W, floor = geo["width"], geo["floor"]
    d = np.array(res.discs_end, float)
    surf = janssen.surface_height(d, W)
    phi = janssen.packing_fraction(d, W, floor, surf)
    prof = {w["name"]: w for w in resolved["walls"]}
    sides = [w["name"] for w in resolved["walls"] if w["group"].startswith("side")]
    lo = np.array(res.profiles[sides[0]]["s_lo"])
    hi = np.array(res.profiles[sides[0]]["s_hi"])
    top = prof[sides[0]]["from"][1]
    normal = np.mean([np.array(res.profiles[s]["normal"]) for s in sides], axis=0)
    shear = np.sum([np.array(res.profiles[s]["shear"]) for s in sides], axis=0)
    ntot = np.sum([np.array(res.profiles[s]["normal"]) for s in sides], axis=0)
    y_lo, y_hi = top - hi, top - lo
    upper = y_lo >= surf - UPPER * (surf - floor)
    weight = float(np.sum(geo["rho_s"] * math.pi * d[:, 2] ** 2) * geo["g"])
    bottom = [w["name"] for w in resolved["walls"] if not w["group"].startswith("side")]
    floor_force = float(sum(np.sum(res.profiles[b]["normal"]) for b in bottom))
    friction = float(np.sum(shear))
    return {"code": code, "member": member, "status": res.status, "reason": res.reason,
            "wall_time_s": wall_time, "n_discs": int(len(d)), "width": W, "floor": floor,
            "rho_s": geo["rho_s"], "g": geo["g"], "mu_w": geo["mu_w"],
            "surface": surf, "phi": phi, "weight": weight, "floor_force": floor_force,
            "wall_friction": friction, "balance": (floor_force + friction - weight) / weight,
            "mobilised_upper": float(shear[upper].sum() / ntot[upper].sum()),
            "mobilised_all": float(shear.sum() / ntot.sum()),
            "max_overlap_ratio": max_overlap_ratio(d, W, floor),
            "kinetic_energy_end": res.kinetic_energy_end,
            "y_lo": y_lo.tolist(), "y_hi": y_hi.tolist(), "p": (normal / (hi - lo)).tolist()}


def backend(code: str):
    if code == "native":
        from . import native_backend as b
    elif code == "liggghts":
        from . import liggghts_backend as b
    elif code == "yade":
        from . import yade_backend as b
    else:
        raise ValueError(f"unknown code {code!r}")
    return b


def run_member(code: str, member: int, out_dir: Path, resolved: dict | None = None,
               timeout: float = 3600) -> dict:
    """Both stages of one member in ``code``; the record (status 'failed' with the reason when a
    stage fails)."""
    r = resolved or resolved_scene()
    b = backend(code)
    out_dir = Path(out_dir)
    t0 = time.monotonic()
    case = Case(name=f"janssen_column_m{member}_fill", resolved=r, discs=member_start(r, member), dt=DT,
                duration=FILL, seed=member)
    res = b.run(case, out_dir / "fill", timeout)
    if not res.ok:
        return {"code": code, "member": member, "status": "failed", "reason": f"fill: {res.reason}"}
    cut = cut_floor_layer(np.array(res.discs_end, float), geometry(r)["floor"])
    case2 = Case(name=f"janssen_column_m{member}", resolved=r, discs=cut, dt=DT, duration=RESETTLE, seed=member)
    res = b.run(case2, out_dir / "resettle", timeout)
    if not res.ok:
        return {"code": code, "member": member, "status": "failed", "reason": f"resettle: {res.reason}"}
    return member_record(r, res, code, member, time.monotonic() - t0)


def run_ensemble(code: str, members: int, out_dir: Path, first: int = 0, timeout: float = 3600) -> list[dict]:
    r = resolved_scene()
    recs = []
    for m in range(first, first + members):
        path = Path(out_dir) / code / f"member_{m:02d}.json"
        if path.exists():
            recs.append(json.loads(path.read_text()))
            continue
        rec = run_member(code, m, Path(out_dir) / code / f"m{m:02d}", r, timeout)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(path, json.dumps(rec) + "\n")
        recs.append(rec)
        print(f"{code} member {m}: {rec['status']} {rec.get('reason', '')} "
              f"{rec.get('wall_time_s', float('nan')):.1f} s", flush=True)
    return recs


def load_members(out_dir: Path, code: str) -> list[dict]:
    return [json.loads(p.read_text()) for p in sorted((Path(out_dir) / code).glob("member_*.json"))]


MERGE = 3   # 2 cm profile bins joined three by three: 6 cm = 0.3 W per fitted point


def analyse(out_dir: Path, codes=("native", "liggghts", "yade"), merge: int = MERGE) -> dict:
    """Ensemble fit per code (members with status ok), comparison of each code with native,
    wall time per member; writes janssen_column.json and janssen_column.png in ``out_dir``."""
    from . import janssen_figure
    out_dir = Path(out_dir)
    fits, summary = {}, {"codes": {}, "comparisons": {}}
    for code in codes:
        recs = load_members(out_dir, code)
        ok = [m for m in recs if m.get("status") == "ok"]
        if len(ok) < 2:
            continue
        f = janssen.ensemble_fit(ok, merge)
        fits[code] = f
        summary["codes"][code] = {
            "members": len(ok), "failed": [m.get("reason", "") for m in recs if m.get("status") != "ok"],
            "wall_time_per_member_s": float(np.mean([m["wall_time_s"] for m in ok])),
            "n_discs_mean": float(np.mean([m["n_discs"] for m in ok])),
            "phi_mean": float(np.mean([m["phi"] for m in ok])),
            **{k: f[k] for k in janssen.FIT_KEYS}, "ci": f["ci"], "r2": f["r2"], "chi2_red": f["chi2_red"],
            "fit_counts": f["r2"] >= janssen.R2_MIN, "checks": f["checks"]}
    if "native" in fits:
        for code, f in fits.items():
            if code != "native":
                summary["comparisons"][f"{code} vs native"] = janssen.compare_fits(fits["native"], f)
    write_text_atomic(out_dir / "janssen_column.json", json.dumps(summary, indent=1) + "\n")
    if fits:
        janssen_figure.plot_ensemble_fits(fits, out_dir / "janssen_column.png")
    return summary


if __name__ == "__main__":
    a = sys.argv[1:]
    if len(a) == 2 and a[0] == "analyse":
        analyse(Path(a[1]))
        sys.exit(0)
    if len(a) not in (3, 4):
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    run_ensemble(a[0], int(a[1]), Path(a[2]), int(a[3]) if len(a) == 4 else 0)

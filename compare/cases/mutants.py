"""Mutants: deliberately wrong translations that the verdict must catch.

A mutant changes one constant of the scene that ONE reference code translates (the others, and
the constants the translation check expects, stay right), as a translation bug would. The run
with mutants passes only when the unmutated run passes and every mutant fails at least one
metric; the report lists which metrics caught each mutant and by how much, and whether a
physical metric (anything but the translation check) caught it too.
"""
from __future__ import annotations

import copy
import dataclasses
from pathlib import Path

import numpy as np

# (name, what, pairs, factor, scope): what = pair constant (kn, ks, eta_n, eta_s, mu) of the
# "disc-disc", "disc-wall" or "all" pairs, or "density" / "gravity", or "bonds" (clusters bonded
# only where their discs touch: the gap bonds of closed triangles dropped; changes only scenes whose
# [clusters] bond every pair), or "geometry" (pairs: "wall_right", the rightmost side wall moved
# outwards, or "points", each point moved away from the points' middle along x, with the wall ends
# at it; by factor x the smallest disc radius); scope "gravity" = only cases with gravity, "points"
# = only codes that build points (not LAMMPS: a static scene's points are joints of one plane).
SPECS = [
    ("kn_x1.05", "kn", "all", 1.05, "all"),
    ("ks_x0.5", "ks", "all", 0.5, "all"),
    ("eta_n_x1.2", "eta_n", "all", 1.2, "all"),
    ("mu_disc_disc_x0.9", "mu", "disc-disc", 0.9, "all"),
    ("mu_disc_wall_x0.9", "mu", "disc-wall", 0.9, "all"),
    ("mu_disc_wall_x0.9_gravity_cases", "mu", "disc-wall", 0.9, "gravity"),
    ("density_x1.01", "density", "", 1.01, "all"),
    ("gravity_x1.01", "gravity", "", 1.01, "all"),
    ("bonds_touching_only", "bonds", "", 1.0, "all"),
    ("wall_right_shift_0.01r", "geometry", "wall_right", 0.01, "all"),
    ("slit_ends_0.2r", "geometry", "points", 0.2, "points"),
]
# Run only when named (--mutant NAME): the statistical metrics' power checks (docs/compare.md,
# "Mutants"): the Janssen column's wall friction; on the designed discharge, a slit wider by two
# radii (the flow rate and the discs out, about +30 % by Beverloo's law in 2D) and denser discs
# (every wall load +25 %, the flow unchanged).
EXTRA_SPECS = [
    ("mu_disc_wall_x0.8", "mu", "disc-wall", 0.8, "all"),
    ("slit_ends_1r", "geometry", "points", 1.0, "points"),
    ("density_x1.25", "density", "", 1.25, "all"),
]
# The statistical metric kinds a power-check mutant must make disagree, where the run has such
# metrics: caught by the translation check alone, it proves nothing about the statistics.
PROVES = {"mu_disc_wall_x0.8": ("janssen",), "slit_ends_1r": ("flow_rate", "discs_out"),
          "density_x1.25": ("wall_load",)}


@dataclasses.dataclass
class Mutation:
    name: str
    code: str
    what: str
    pairs: str
    factor: float
    scope: str
    proves: tuple = ()          # statistical kinds it must make disagree (PROVES)

    def applies(self, code: str, case) -> bool:
        """For this code, in a case its scope covers, and changing something there (gravity x 1.01
        changes nothing without gravity)."""
        if code != self.code:
            return False
        if self.scope == "gravity" and not float(np.hypot(*case.resolved["gravity"])) > 0:
            return False
        if self.scope == "points" and code == "lammps":
            return False
        return self.apply(case.resolved) != case.resolved

    def apply(self, resolved: dict) -> dict:
        r = copy.deepcopy(resolved)
        if self.what == "gravity":
            r["gravity"] = [g * self.factor for g in r["gravity"]]
        elif self.what == "bonds":
            if "clusters" in r and r["clusters"].get("bonds") == "all":
                r["clusters"] = dict(r["clusters"], bonds="touching")
        elif self.what == "geometry":
            _move_geometry(r, self.pairs, self.factor)
        elif self.what == "density":
            for m in r["materials"]:
                m["density"] = m["density"] * self.factor
        else:
            solid = {m["name"] for m in r["materials"] if m["density"] > 0}
            for p in r["pairs"]:
                dd = all(m in solid for m in p["materials"])
                if self.pairs == "all" or (self.pairs == "disc-disc") == dd:
                    p[self.what] = p[self.what] * self.factor
        return r

    def folder(self, out: Path, code: str) -> Path:
        return Path(out) / "mutants" / self.name / code

    @property
    def label(self) -> str:
        return f"{self.code}: {self.name}"


def _move_geometry(r: dict, what: str, factor: float) -> None:
    """Moves, by factor x the smallest disc radius along x, the rightmost side wall (walls of a
    group "side*", outwards) or each point away from the points' middle (one point: to +x) with
    the wall ends at it; a scene without such a wall or points is left as it is."""
    radii = [float(d[2]) for d in r.get("discs", [])]
    if not radii:
        return
    step = factor * min(radii)
    if what == "wall_right":
        sides = [w for w in r["walls"] if w.get("active", True) and str(w.get("group", "")).startswith("side")]
        if sides:
            w = max(sides, key=lambda w: w["from"][0] + w["to"][0])
            w["from"] = [w["from"][0] + step, w["from"][1]]
            w["to"] = [w["to"][0] + step, w["to"][1]]
        return
    if what != "points":
        raise ValueError(f"mutant geometry {what!r}: not 'wall_right' or 'points'")
    pts = r["points"]
    mid = sum(p["at"][0] for p in pts) / len(pts) if pts else 0.0
    for p in pts:
        old = list(p["at"])
        dx = step if len(pts) == 1 or old[0] >= mid else -step
        p["at"] = [old[0] + dx, old[1]]
        for w in r["walls"]:
            for end in ("from", "to"):
                if abs(w[end][0] - old[0]) <= 1e-9 and abs(w[end][1] - old[1]) <= 1e-9:
                    w[end] = [w[end][0] + dx, w[end][1]]


def mutations(codes, names=None) -> list[Mutation]:
    """Every mutant of SPECS for every reference code among ``codes``; with ``names``, only those
    (a spec name of SPECS or EXTRA_SPECS for every reference code, or CODE_SPEC for one code;
    ValueError for a name that is neither)."""
    out = []
    for name, what, pairs, factor, scope in SPECS + EXTRA_SPECS:
        for c in codes:
            if c == "native":
                continue
            m = Mutation(f"{c}_{name}", c, what, pairs, factor, scope, PROVES.get(name, ()))
            if names is None and (name, what, pairs, factor, scope) in SPECS:
                out.append(m)
            elif names is not None and (name in names or m.name in names):
                out.append(m)
    if names is not None:
        known = {n for n, *_ in SPECS + EXTRA_SPECS} | {f"{c}_{n}" for n, *_ in SPECS + EXTRA_SPECS for c in codes
                                                           if c != "native"}
        bad = [n for n in names if n not in known]
        if bad:
            raise ValueError(f"unknown mutant {', '.join(bad)} (known: {', '.join(sorted(known))})")
    return out


def caught(baseline: dict, mutant_report: dict, proves: tuple = ()) -> dict:
    """The metrics that say disagree under the mutant where the baseline did not, with how far off
    they are; and the mutant's measured effect on every statistical metric (its estimate and
    interval against the margin), whatever its verdict. A power-check mutant (``proves``) is
    caught only when a statistical metric of each of those kinds that the run has disagrees."""
    base = {(m["scene"], m["metric"]): m for m in baseline["metrics"]}
    rows, effects = [], []
    for m in mutant_report["metrics"]:
        b = base.get((m["scene"], m["metric"]))
        if m["verdict"] == "disagree" and (b is None or b["verdict"] != "disagree"):
            rows.append({"scene": m["scene"], "metric": m["metric"], "by": margin(m), "note": m.get("note", ""),
                         "margin_kind": m.get("margin_kind")})
        if m.get("kind") == "statistical" and "stat" in m:
            effects.append({"scene": m["scene"], "metric": m["metric"], "verdict": m["verdict"],
                            "estimate": m["stat"].get("estimate"), "ci": m.get("ci"), "margin": m["margin"],
                            "relative": m.get("relative", True)})
    physical = [r for r in rows if not _read_back(r)]
    present = {m.get("margin_kind") for m in mutant_report["metrics"] if m.get("kind") == "statistical"}
    needed = [k for k in proves if k in present]
    proved = [k for k in needed if any(r["margin_kind"] == k for r in rows)]
    ok = bool(rows) and len(proved) == len(needed)
    return {"caught": ok, "caught_physically": bool(physical), "metrics": rows, "effects": effects,
            "verdict": mutant_report.get("verdict"), "proves": needed, "proved": proved}


def physical_catch(baseline: dict, metrics: list) -> str | None:
    """The first deterministic physical metric (not the translation read-back) among ``metrics``
    (not yet judged) that fails where the baseline did not: its scene and name, or None."""
    base = {(m["scene"], m["metric"]): m for m in baseline["metrics"]}
    for m in metrics:
        b = base.get((m["scene"], m["metric"]))
        if (m.get("kind", "deterministic") == "deterministic" and not m["pass"]
                and m.get("verdict") != "inconclusive" and not _read_back(m)
                and (b is None or b["verdict"] != "disagree")):
            return f"caught by {m['metric']} on {m['scene']}"
    return None


def _read_back(m: dict) -> bool:
    return m["metric"].startswith(("translation constants", "translation geometry"))


def margin(m: dict) -> float:
    """How many tolerances (or margins) the metric is off: value / tolerance, or for a statistical
    metric the distance of its interval's nearer end from zero over the margin."""
    if m.get("kind") == "statistical" and m.get("ci"):
        lo, hi = m["ci"]
        near = 0.0 if lo <= 0 <= hi else min(abs(lo), abs(hi))
        return near / m["margin"]
    v = m.get("values") or {}
    if "max_diff_over_critical" in v:
        return float(v["max_diff_over_critical"])
    if "max_diff_over_tolerance" in v:
        return float(v["max_diff_over_tolerance"])
    if "p" in v and v.get("p") is not None:
        return float("nan")
    for k in ("max_rel_diff", "max_rel", "rel_diff"):
        if k in v and isinstance(m.get("tolerance"), (int, float)) and m["tolerance"]:
            return float(v[k]) / float(m["tolerance"])
    return float("nan")

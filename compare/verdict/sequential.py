"""Decided, not sampled: members added in batches until every statistical metric is decided.

``dem compare ... --until-decided [--budget MINUTES] [--max-members N]`` runs each ensemble scene
with its first members (the profile's or --members), judges, and adds a batch of members (as many
as the first) to every scene that still has an inconclusive statistical metric, until each metric
agrees or disagrees, the scene reaches --max-members, or the budget ends. Earlier members are read
back, not run again (their inputs are unchanged). The error rates hold over the looks by a split
of the level over the planned looks (Bonferroni): with K looks, each look judges at alpha / K, so
that the chance of a false verdict at any look is at most alpha (compare/cases/stats.py Levels).
"""
from __future__ import annotations

import math
import time

from dem.compare.verdict import pipeline, verdict

DEFAULT_MAX_MEMBERS = 32


def planned_looks(first: int, batch: int, max_members: int) -> int:
    """Looks at first, first + batch, ... up to max_members (the last look at max_members)."""
    return 1 + max(0, math.ceil((max_members - first) / max(batch, 1)))


def undecided(report: dict, plans) -> list:
    """The ensemble plans with a statistical metric still inconclusive for lack of members (a failed
    run is not helped by more members: its scene is left as it is)."""
    out = []
    for p in plans:
        ms = [m for m in report["metrics"] if m["scene"] == p.name and m.get("kind") == "statistical"]
        if p.members > 1 and any(m["verdict"] == verdict.INCONCLUSIVE and "stat" in m and "reason" not in m["stat"]
                                 for m in ms):
            out.append(p)
    return out


def run(plans, out, codes, log, budget_min: float, max_members: int) -> dict:
    """Looks until decided; the report of the last look, with the looks' history in ``looks``."""
    t0 = time.monotonic()
    ens = [p for p in plans if p.members > 1]
    first = {p.name: p.members for p in ens}
    looks = max((planned_looks(first[p.name], first[p.name], max_members) for p in ens), default=1)
    history, last_cost = [], 0.0
    while True:
        t1 = time.monotonic()
        rep = pipeline.run([], out, codes, log=log, plans=plans, looks=looks)
        last_cost = time.monotonic() - t1
        todo = undecided(rep, plans)
        history.append({"members": {p.name: p.members for p in ens}, "elapsed_s": time.monotonic() - t0,
                        "undecided": [p.name for p in todo]})
        grow = [p for p in todo if p.members < max_members]
        spent = (time.monotonic() - t0) / 60
        if not grow or len(history) >= looks:
            break
        if spent + last_cost / 60 > budget_min:
            log(f"until-decided: budget {budget_min:g} min: {spent:.1f} min spent, the next look would take "
                f"about {last_cost / 60:.1f} min more; stopping")
            break
        for p in grow:
            p.members = min(p.members + first[p.name], max_members)
            p.entry.options.resume = True          # earlier members are read back
        log("until-decided: look " + str(len(history) + 1) + " of at most " + str(looks) + ": "
            + ", ".join(f"{p.name} {p.members} members" for p in grow))
    rep["looks"] = {"planned": looks, "done": len(history), "history": history, "budget_min": budget_min,
                    "max_members": max_members}
    return rep

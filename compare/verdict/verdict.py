"""The three-valued verdict: agree, disagree or inconclusive, per metric, per scene and overall.

Deterministic metrics (collisions, the frozen static silo, the translation read-back) agree or
disagree by their tolerances. Statistical metrics carry their statistic (compare/cases/stats.py) and
margin (compare/cases/margins.py) and are judged once the whole report is in, because the disagree
interval is split over all of the report's statistical metrics. A metric that could not be
judged (a failed run, too few members, a settle that did not reach rest) is inconclusive with its
reason, never disagree.
"""
from __future__ import annotations

from dem.compare.cases import margins, stats
from dem.compare.cases.stats import AGREE, DISAGREE, INCONCLUSIVE

EXIT = {AGREE: 0, DISAGREE: 1, INCONCLUSIVE: 3}   # 2: bad input, refused before any run
ORDER = (DISAGREE, INCONCLUSIVE, AGREE)           # what a scene or report says when metrics differ


def unjudged(name: str, scene: str, reason: str, kind: str = "deterministic") -> dict:
    """A metric that could not be judged (a run failed, no members): inconclusive, with why."""
    return {"metric": name, "scene": scene, "values": {}, "tolerance": "", "pass": False,
            "verdict": INCONCLUSIVE, "note": reason, "unit": "", "kind": kind}


def statistical(name: str, scene: str, stat: dict, margin_kind: str, options, values: dict | None = None,
                note: str = "") -> dict:
    """A statistical metric, judged later by ``finalize``. options: the entry's plan.Options
    (profile and --margin overrides)."""
    delta = margins.margin(margin_kind, options.profile, options.margins)
    rel = margins.MARGINS[margin_kind].relative
    why = stat.get("reason", "")
    return {"metric": name, "scene": scene, "values": values or {}, "kind": "statistical",
            "margin_kind": margin_kind, "margin": delta, "relative": rel, "stat": stat,
            "tolerance": f"margin ±{delta:.0%}" if rel else f"margin ±{delta:g}",
            "note": "; ".join(x for x in (note, why) if x), "unit": "", "pass": False, "verdict": INCONCLUSIVE}


def finalize(metrics: list, looks: int = 1, alpha: float = stats.FAMILY_ALPHA) -> list:
    """Judges every statistical metric of a report against its margin (the disagree level split
    over the report's statistical metrics and the planned looks); sets each metric's pass."""
    stat = [m for m in metrics if m.get("kind") == "statistical" and "stat" in m]
    levels = stats.Levels(alpha, max(len(stat), 1), looks)
    for m in stat:
        m.update(stats.judge(m["stat"], m["margin"], levels))
        m["members_to_decide"] = (stats.members_needed(m["stat"], m["margin"], levels)
                                  if m["verdict"] == INCONCLUSIVE else None)
        m["levels"] = {"agree": levels.agree, "disagree": levels.disagree}
    for m in metrics:
        m.setdefault("kind", "deterministic")
        m.setdefault("verdict", AGREE if m["pass"] else DISAGREE)
        m["pass"] = m["verdict"] == AGREE
    return metrics


def combine(verdicts) -> str:
    """disagree if any disagrees, else inconclusive if any is, else agree (nothing: inconclusive)."""
    vs = list(verdicts)
    if not vs:
        return INCONCLUSIVE
    return next(v for v in ORDER if v in vs)

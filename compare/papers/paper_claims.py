"""The paper's statements about its static silo (section 5(1) of Kiyama & Fujimura 1983), each
checked against a study's own runs.

Every check returns a row: the statement, what the paper says, what these runs show (numbers),
and whether they agree. Only runs that came to rest count; the others are named in the row.

- chains: force chains most horizontal in 11/12, most vertical in 18/19. Measured on what the
  paper draws, the elastic resultant F = e_n n + e_s t of each disc-disc contact (t = (-ny, nx)):
  its verticality sum |F| (F_y/|F|)^2 / sum |F| (0 horizontal, 1 vertical). The lattice sets the
  normals (every contact of an (s-1)/s lattice has the same |ny|); the shear forces turn the
  resultants, so the measure differs between schemes that rest differently.
- side_force: the side-wall normal force is largest for 11/12 and falls as s grows.
- depth: the side-wall normal force per contact row grows with depth in the upper half of the
  fill and drops in its lowest rows (below the largest row force).
- corner_friction: small negative wall friction (upward on the wall) near the bottom corners:
  some contact row in the lowest 10 % of the side-wall contacts' depth span has friction < 0.
"""
import numpy as np

from dem.compare.figures import figure_data as figures   # reading and side-wall profiles, no matplotlib

CORNER_SPAN = 0.10      # lowest share of the side-wall contacts' depth span: "near the bottom"


def verticality(contacts) -> float:
    """Force-weighted mean (F_y/|F|)^2 of the disc-disc contacts' elastic resultants
    F = e_n n + e_s t (0: all horizontal, 1: all vertical)."""
    dd = np.asarray(contacts["kind"]).astype(str) == "dd"
    nx, ny = (np.asarray(contacts[k], float)[dd] for k in ("nx", "ny"))
    e_n, e_s = (np.asarray(contacts[k], float)[dd] for k in ("e_n", "e_s"))
    fy = e_n * ny + e_s * nx
    f = np.hypot(e_n * nx - e_s * ny, fy)
    return float(np.sum(fy * fy / np.where(f > 0, f, 1.0)) / np.sum(f)) if f.sum() > 0 else float("nan")


FIRST, LAST = "11/12", "18/19"   # the paper's extreme arrangements


def _ranked(values: dict) -> str:
    missing = [k for k in (FIRST, LAST) if k not in values]
    note = f" ({' and '.join(missing)} not at rest: the extremes among the others)" if missing else ""
    return ", ".join(f"{k} {v:.3g}" for k, v in values.items()) + note


def chains(runs: dict) -> dict:
    """runs: {arrangement label: run dir}, in order of s."""
    v = {k: verticality(figures.load_run(d, parts=("contacts",))["contacts"]) for k, d in runs.items()}
    keys = list(v)
    ok = len(keys) >= 2 and min(v, key=v.get) == keys[0] and max(v, key=v.get) == keys[-1]
    return {"statement": "force chains", "paper": f"most horizontal in {FIRST}, most vertical in {LAST}",
            "shows": "verticality of the contact forces e_n n + e_s t: " + _ranked(v), "agrees": ok}


def side_force(records: list) -> dict:
    """records: the study's records of one scheme and dt at rest, in order of s."""
    v = {r["arrangement"]: r["side_mean"] for r in records}
    keys = list(v)
    vals = np.array(list(v.values()))
    falls = len(vals) >= 2 and bool(np.all(np.diff(vals) < 0))
    ok = len(vals) >= 2 and max(v, key=v.get) == keys[0]
    trend = "falls at every step" if falls else \
        f"{int(np.sum(np.diff(vals) < 0))} of {len(vals) - 1} steps fall" if len(vals) >= 2 else ""
    return {"statement": "side-wall normal force against s",
            "paper": f"largest for {FIRST}, falls as s grows",
            "shows": f"{_ranked(v)} disc weights; largest for {max(v, key=v.get) if v else '-'}; {trend}",
            "agrees": ok and (falls or np.corrcoef(np.arange(len(vals)), vals)[0, 1] < -0.8)}


def _rows(run_dir):
    run = figures.load_run(run_dir, parts=("contacts",))
    prof = figures.side_wall_contacts(run["summary"], run["contacts"])
    w = run["summary"]["disc_weight"]
    return (prof["depth"], prof["normal"] / w, prof["friction"] / w) if prof is not None else None


def depth(runs: dict) -> dict:
    """P_y per contact row against depth: grows in the upper half, drops in the lowest rows."""
    shown, good = [], []
    for k, d in runs.items():
        rows = _rows(d)
        if rows is None or len(rows[0]) < 4:
            shown.append(f"{k}: too few rows")
            good.append(False)
            continue
        z, fn, _ = rows
        upper = z <= z.min() + 0.5 * (z.max() - z.min())
        grows = np.corrcoef(z[upper], fn[upper])[0, 1] > 0 if upper.sum() >= 3 else False
        drop = fn[-1] < fn.max()
        good.append(bool(grows and drop))
        shown.append(f"{k}: {'grows' if grows else 'does not grow'} above mid-depth, lowest row "
                     f"{fn[-1]:.3g} vs largest {fn.max():.3g}")
    return {"statement": "side-wall force against depth",
            "paper": "grows with depth and levels off, drops near the bottom",
            "shows": "; ".join(shown), "agrees": bool(good) and all(good)}


def corner_friction(runs: dict) -> dict:
    """Negative (upward on the wall) friction in the lowest rows of each run."""
    shown, found = [], []
    for k, d in runs.items():
        rows = _rows(d)
        if rows is None:
            shown.append(f"{k}: no side-wall contacts")
            found.append(False)
            continue
        z, _, fr = rows
        low = z >= z.max() - CORNER_SPAN * (z.max() - z.min())
        top = z <= z.min() + CORNER_SPAN * (z.max() - z.min())
        neg = bool(np.any(fr[low] < 0))
        found.append(neg)
        shown.append(f"{k}: lowest rows {'have' if neg else 'have no'} negative friction "
                     f"(min {fr[low].min():.2g}), top rows min {fr[top].min():.2g}")
    return {"statement": "wall friction near the bottom corners",
            "paper": "small negative friction near the bottom corners",
            "shows": "; ".join(shown),
            "agrees": bool(found) and sum(found) > len(found) / 2}


def table(rows: list) -> list[str]:
    """Markdown lines: statement | paper says | these runs show | agrees?"""
    out = ["| statement | the paper says | these runs show | agrees? |", "|---|---|---|---|"]
    for r in rows:
        judged = r.get("judged") or ("yes" if r["agrees"] else "**no**")
        out.append(f"| {r['statement']} | {r['paper']} | {r['shows']} | {judged} |")
    return out


# ------------------------------------------------------------------------ discharge, section 5(2)

PEAK_FACTOR = 2.0   # "about 10x" holds within a factor of 2 (5x-20x)


def _mean(e, key):
    s = e.get(key) or {}
    return s.get("mean")


def discharge(ensembles: dict) -> list[dict]:
    """ensembles: {"17/18": ensemble.json dict, "11/12": ...} of the paper's scheme and dt.
    Rows for the flow patterns and the peak wall forces the paper reports."""
    rows = []
    for arr, want in (("17/18", "funnel"), ("11/12", "piping")):
        e = ensembles.get(arr)
        if not e:
            continue
        p = e.get("pattern", {})
        n = sum(p.get(k, 0) for k in ("funnel", "piping", "undetermined"))
        rows.append({"statement": f"{arr} flow pattern", "paper": f"{want} flow",
                     "shows": f"funnel {p.get('funnel', 0)}, piping {p.get('piping', 0)}, undetermined "
                              f"{p.get('undetermined', 0)} of {n} members",
                     "agrees": n > 0 and p.get(want, 0) > n / 2})
    e = ensembles.get("17/18")
    if e:
        rows.append(_peak_row("17/18 bottom wall, early discharge",
                              "largest wall force under an arch foot, about 10x its static value",
                              e, "bottom", 10 / PEAK_FACTOR, 10 * PEAK_FACTOR))
        rows.append(_peak_row("17/18 side walls, early discharge", "2-5x static", e, "side", 2, 5))
    e = ensembles.get("11/12")
    if e:
        rows.append(_peak_row("11/12 walls near the slit ends", "small arches, 2-3x static", e, "bottom", 2, 3))
    return rows


def _peak_row(statement: str, paper: str, e: dict, wall: str, lo: float, hi: float) -> dict:
    """A peak ratio the paper states, judged at both samplings the runs give: the raw peak (the
    series sampled every 5 ms) and the 50 ms moving average. The paper does not say how its
    forces were sampled, so a value inside its range at one sampling only is said so."""
    raw, win = _mean(e, f"peak_ratio_{wall}"), _mean(e, f"peak_ratio_{wall}_windowed")
    if raw is None or win is None:
        return {"statement": statement, "paper": paper, "shows": "no value", "agrees": False}
    inside = {"5 ms": lo <= raw <= hi, "50 ms average": lo <= win <= hi}
    only = [k for k, ok in inside.items() if ok]
    return {"statement": statement, "paper": paper,
            "shows": f"{wall} peak/static {raw:.3g} (sampled every 5 ms), {win:.3g} (50 ms average)",
            "agrees": len(only) == 2, "judged": None if len(only) != 1 else f"at {only[0]} only"}

"""One pipeline for every comparison: entries (scene + options) -> runs in every code -> metrics.

``dem compare`` (python3 -m dem.compare scene) and the studies (the list files under
reference_inputs/agreement/) both call ``run``. For each entry (compare/cases/plan.py) it
1. refuses what a reference code cannot express, before any run (PlanError, exit 2);
2. reads each reference code's effective constants back from the code itself and compares them
   with ``dem resolve`` (compare/verdict/probe.py), and its walls, points, radii and start positions after
   its setup against the case's (compare/verdict/geometry_probe.py): the translation check, metrics of
   every scene;
3. runs the members in every code (compare/verdict/study.py's runners and readers) and judges them:
   deterministic kinds against tolerances matched to the codes' measured agreement, ensembles
   by equivalence against declared margins: agree, disagree or inconclusive (compare/verdict/verdict.py).

A *mutation* (compare/cases/mutants.py) hands one reference code a deliberately wrong scene (one
constant changed) while the expected constants and every other code stay as they are; results
of unmutated runs are reused from the baseline's folders.
"""
from __future__ import annotations

import copy
import hashlib
import json
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from dem.compare.verdict import collision_judge, preflight, study, verdict, geometry_probe, probe, shear_judge
from dem.compare.cases import janssen, stats
from dem.compare.codes import native_backend
from dem.compare.codes.backends import refusals
from dem.compare.cases.common import Case, Result, scene_material_index, inward_normal, tangent
from dem.compare.cases.plan import Entry, Plan, PlanError, codes_of, jittered, make_plan, member_case, start_discs
from dem.compare.figures import janssen_figure
from dem.compare.io.job_pool import in_order

# Static cases from a frozen packing: tolerances at 10x the largest cross-code spread measured on
# the paper's eight frozen lattices (reference_inputs/agreement/static.list, docs/compare.md): the
# codes agree to 1e-12 .. 1e-4 in the wall normal totals, 1e-11 .. 9.5e-4 in the side-wall
# friction totals and 1e-12 .. 1.7e-4 in the cumulative profiles, the largest on 11/12 .. 13/14.
TOL_STATIC_TOTAL = 1e-3       # wall normal totals, relative
TOL_STATIC_SHEAR = 1e-2       # side-wall friction totals, relative
TOL_STATIC_CUMULATIVE = 2e-3  # cumulative normal profile / wall total


def _metric(name, scene, values, tol, passed, note="", kind="deterministic") -> dict:
    m = study.metric(name, scene, values, tol, passed, note)
    m["kind"] = kind
    return m


# ------------------------------------------------------------------------ running codes

def case_for(code: str, case: Case, plan: Plan, mutation) -> Case:
    """The case a code runs: the native side with the scene's own law when asked, then the
    mutation (a mutant's wrong constant, or an attribution's law switch) for the code it names."""
    if code == "native" and plan.options.native_law == "scene":
        r = copy.deepcopy(plan.resolved)
        r["integrator"] = dict(r["integrator"], scheme="velocity_verlet")
        case = _with_resolved(case, r)
    if mutation is not None and mutation.applies(code, case):
        case = _with_resolved(case, mutation.apply(case.resolved))
    return case


def _with_resolved(case: Case, r: dict) -> Case:
    c = copy.copy(case)
    c.resolved = r
    return c


def run_one(code: str, case: Case, plan: Plan, out: Path, mutation=None) -> Result:
    """One code's run of a case in ``out/code``; in a mutant or attribution run the code it names
    runs in its own folder and every other code reuses its baseline result."""
    mutated = mutation is not None and mutation.code == code
    d = mutation.folder(out, code) if mutated else out / code
    return study.run_code(code, case_for(code, case, plan, mutation), d, plan.options.timeout,
                          reuse=mutation is not None and not mutated, resume=plan.options.resume)


def run_all(codes, case: Case, plan: Plan, out: Path, mutation=None) -> dict:
    """Every code's run of one case."""
    return {c: run_one(c, case, plan, out, mutation) for c in codes}


# ------------------------------------------------------------------------ translation check

def translation_check(plan: Plan, codes, out: Path, mutation=None) -> list:
    """Each reference code's constants read back from the code (compare/verdict/probe.py) against
    ``dem resolve`` to 1e-9 relative, and its walls, points, radii and start positions read back
    after its setup (compare/verdict/geometry_probe.py) against the case's to 1e-9 of the scene's length."""
    codes = codes_of(plan, codes)
    metrics = []
    case = member_case(plan, 0, start_discs(plan.shared))
    expected = probe.expected_constants(plan.shared, case.discs, plan.dt, case.material_index())
    geometry = geometry_probe.expected_geometry(case)
    for c in codes:
        if c == "native":
            continue
        pcase = case_for(c, case, plan, mutation)
        pr = _probe_cached(probe, c, pcase, out, plan.options.timeout)
        if pr.get("status") != "ok":
            metrics.append(verdict.unjudged(f"translation constants read back ({c})", plan.name,
                                            f"probe failed: {pr.get('reason', '')}"))
        else:
            rows = probe.compare_constants(expected, pr)
            bad = [r for r in rows if not r["pass"]]
            worst = max((r["rel_diff"] for r in rows if math.isfinite(r["rel_diff"])), default=float("nan"))
            metrics.append(_metric(f"translation constants read back ({c})", plan.name,
                                   {"quantities": len(rows), "max_rel_diff": worst}, 1e-9, not bad,
                                   "; ".join(f"{r['quantity']}: {r['probed']!r} vs {r['expected']!r}"
                                             for r in bad[:4])))
        if plan.kind != "shear":     # the shear box's walls are boxes the shear script builds: not read
            metrics.append(_geometry_metric(geometry_probe, c, pcase, geometry, plan, out))
    return metrics


def _geometry_metric(geometry_probe, code: str, case: Case, expected: dict, plan: Plan, out: Path) -> dict:
    """One code's geometry read back against the (unmutated) case's: max deviation / length scale."""
    name = f"translation geometry read back ({code})"
    gr = _probe_cached(geometry_probe, code, case, out, plan.options.timeout, kind="geometry")
    if gr.get("status") != "ok":
        return verdict.unjudged(name, plan.name, f"geometry run failed: {gr.get('reason', '')}")
    rows = geometry_probe.compare_geometry(expected, gr["geometry"])
    s = geometry_probe.summary(rows)
    bad = [r for r in rows if not r["pass"]]
    note = "; ".join(f"{r['item']}: off by {r['deviation']:.3g} cm{' (' + r['note'] + ')' if r['note'] else ''}"
                     for r in sorted(bad, key=lambda r: -r["rel"])[:4])
    if gr["geometry"].get("points") is None and expected["points"]:
        note = (note + "; " if note else "") + "points: not read (the code has no point contact)"
    return _metric(name, plan.name, {"items": s["items"], "max_rel_diff": s["max_rel_diff"], "worst": s["worst"],
                                     "length_scale": expected["length"]}, geometry_probe.REL, not bad, note)


def input_key(write) -> str:
    """sha1 of the names and bytes of every file ``write(folder)`` writes into an empty folder."""
    h = hashlib.sha1()
    with tempfile.TemporaryDirectory() as t:
        write(Path(t))
        for f in sorted(p for p in Path(t).rglob("*") if p.is_file()):
            rel = f.relative_to(t).as_posix().encode()
            h.update(len(rel).to_bytes(8, "little") + rel)
            data = f.read_bytes()
            h.update(len(data).to_bytes(8, "little") + data)
    return h.hexdigest()[:16]


def probe_key(module, code: str, case: Case) -> str:
    """The cache key of a probe (``module``: dem.compare.verdict.probe or dem.compare.verdict.geometry_probe): the bytes of
    the inputs it runs, written by the backend's own translation; any change to the translation
    (a mutant, a backend bug) gets its own probe, and cases that translate alike share one."""
    writer = module.write_probe_inputs if hasattr(module, "write_probe_inputs") else module.write_inputs
    return input_key(lambda d: writer(code, case, d))


def _probe_cached(module, code: str, case: Case, out: Path, timeout: float, kind: str = "constants") -> dict:
    """A code's probe of a case's translation, kept under the run's folder ``out`` by the bytes of
    the probe's translated inputs (``probe_key``: a list of collisions whose probes translate to
    the same bytes probes once). A case the backend refuses is probed (and fails) anew."""
    try:
        h = probe_key(module, code, case)
    except (ValueError, KeyError, OSError):     # a refused translation (CaseError): the probe says why
        return module.probe(code, case, out / "probes" / code / kind / "refused", timeout)
    d = out / "probes" / code / kind / h
    cached = d / "probe.json"
    if cached.exists():
        return json.loads(cached.read_text())
    pr = module.probe(code, case, d, timeout)
    d.mkdir(parents=True, exist_ok=True)
    cached.write_text(json.dumps(pr, indent=1, default=float))
    return pr


# ------------------------------------------------------------------------ kinds

def collision(plan: Plan, codes, out: Path, mutation=None) -> tuple[list, dict]:
    case = member_case(plan, 0, start_discs(plan.shared))
    res = run_all(codes, case, plan, out, mutation)
    return collision_judge.judge(plan.name, case, res)


def fill_time(plan: Plan) -> float:
    """[s] the frozen packing's fill: static, --settle; discharge, the scene's end.time (its fall
    and rest: a discharge's --settle is each member's short settling after the jitter)."""
    return float(plan.shared["end"]["time"]) if plan.kind == "discharge" else plan.settle


def frozen_packing(plan: Plan, out: Path) -> np.ndarray:
    """The native engine fills the scene with the shared law for fill_time(plan) s, the gate of a
    discharge closed; velocities zeroed. How near rest the fill ended (its walls' load along
    gravity against its weight) is kept beside it, in rest.json, for the rest gate."""
    path = out / "frozen.npy"
    if path.exists() and (out / "rest.json").exists():
        return np.load(path)
    case = fill_case(plan, fill_time(plan))
    res = native_backend.run(case, out / "fill", 1800)
    if not res.ok:
        raise RuntimeError(f"frozen packing of {plan.name}: native fill failed: {res.reason}")
    end = np.array(res.discs_end, float)
    end[:, 3:] = 0.0
    out.mkdir(parents=True, exist_ok=True)
    (out / "rest.json").write_text(json.dumps({"settle": plan.settle, "rel": rest_of(plan, res, case)}))
    np.save(path, end)
    return end


def fill_case(plan: Plan, settle: float) -> Case:
    return Case(name="fill", resolved=plan.shared, discs=start_discs(plan.shared), dt=plan.dt, duration=settle,
                materials=scene_material_index(plan.shared))


def rest_of(plan: Plan, res: Result, case: Case) -> float:
    """|walls' load along gravity / weight - 1| of a native fill (0 without gravity: nothing to carry)."""
    if not res.ok:
        return math.inf
    if not np.linalg.norm(plan.shared["gravity"]) > 0:
        return 0.0
    return float(weight_metrics(plan.name, {"native": res}, case, plan.shared)[0]["values"]["rel_diff"])


REST_TOL = 1e-3   # the native fill rests when the walls carry its weight to this (relative) before the codes run
# A discharge's start: its metrics have margins of 5-10 % and members spread 2-5 %, so a packing
# whose walls carry its weight to 1 % is at rest for them (the designed silos' fills reach 0.4-0.7 %).
REST_TOL_DISCHARGE = 1e-2
REST_TRIES = (2, 4)  # longer fills tried (x --settle) to name the settle that reaches rest


def rest_gate(plan: Plan, out: Path) -> list:
    """Every code's start must rest before the codes are compared from it: a native fill that does
    not is reported inconclusive, with the fill that reaches rest (found by longer native fills),
    and no reference code runs (what would differ then is the packing's motion, not the codes).
    The fill is the frozen packing's (static: --settle s; discharge: the scene's end.time), or,
    for a discharge from the scene's own start, the --settle s each member fills before the
    opening."""
    if plan.kind == "discharge" and plan.options.start == "scene":
        seconds, knob = plan.settle, "--settle"
        case = fill_case(plan, seconds)
        rel = rest_of(plan, native_backend.run(case, out / "rest" / "fill_x1", 1800), case)
    else:
        seconds = fill_time(plan)
        knob = "--settle" if plan.kind != "discharge" else "--set end.time="
        frozen_packing(plan, out)
        rel = json.loads((out / "rest.json").read_text())["rel"]
    tol = REST_TOL_DISCHARGE if plan.kind == "discharge" else REST_TOL
    if rel <= tol:
        return []

    def rests(k):
        case = fill_case(plan, seconds * k)
        return rest_of(plan, native_backend.run(case, out / "rest" / f"fill_x{k}", 1800), case) <= tol
    sep = "" if knob.endswith("=") else " "
    hint = next((f"{knob}{sep}{seconds * k:g} reaches it" for k in REST_TRIES if rests(k)),
                f"{knob}{sep}{seconds * REST_TRIES[-1]:g} does not reach it either")
    return [verdict.unjudged("native fill at rest before the codes start from it", plan.name,
                             f"the native fill did not reach rest in {seconds:g} s ({knob}{sep}{seconds:g}; the walls "
                             f"carry the weight to {rel:.2g}, rest is {tol:g}); {hint}")]


def static_frozen(plan: Plan, codes, out: Path, mutation=None) -> tuple[list, dict]:
    unrested = rest_gate(plan, out)
    if unrested:
        return unrested, {"case": plan.name, "results": {}, "n_discs": len(plan.shared["discs"])}
    pack = frozen_packing(plan, out)
    case = Case(name=plan.name, resolved=plan.shared, discs=pack, dt=plan.dt, duration=plan.duration,
                materials=scene_material_index(plan.shared))     # the fill keeps the scene's order
    res = run_all(codes, case, plan, out, mutation)
    metrics, detail = study.static_compare(case, res, tolerances=(TOL_STATIC_TOTAL, TOL_STATIC_SHEAR,
                                                                  TOL_STATIC_CUMULATIVE))
    if np.linalg.norm(plan.shared["gravity"]) > 0:
        metrics += weight_metrics(plan.name, res, case, dict(plan.shared, discs=[list(r[:3]) + [m[3]] for r, m in
                                                                             zip(pack, plan.shared["discs"])]))
    if mutation is None:
        study.save_profiles(out / "profiles.json", case, res)
    return metrics, detail


def member_runs(plan: Plan, codes, out: Path, mutation=None, series_interval=None, start=None) -> list:
    """[(code -> Result, Case)] for members 0 .. plan.members - 1, in member order; up to
    ``plan.options.jobs`` members at once (each member in its own folder out/mK: the runs share
    nothing, so the order they finish in changes no result). ``start``: the discs every member
    jitters (default: the scene's start)."""
    def one(k):
        case = member_case(plan, k) if start is None else member_case(plan, k, jittered(start, k, plan.perturb))
        if series_interval is not None:
            case.series_interval = series_interval
        return run_all(codes, case, plan, out / f"m{k}", mutation), case
    return in_order(one, range(plan.members), plan.options.jobs)


def ensemble_runs(plan: Plan, codes, out: Path, mutation=None, start=None) -> dict:
    """code -> [(Result, Case)] over the members (``start``: as member_runs)."""
    per = {c: [] for c in codes}
    for res, case in member_runs(plan, codes, out, mutation, start=start):
        for c in codes:
            per[c].append((res[c], case))
    return per


def static_members(plan: Plan, codes, out: Path, mutation=None) -> tuple[list, dict]:
    """Independent dynamics: every code from the jittered scene start; each wall's normal total
    (and the side walls' friction) compared as ensemble means."""
    per = ensemble_runs(plan, codes, out, mutation)
    walls = [w for w in plan.shared["walls"] if w.get("active", True)]
    tots = {c: [_with_weight(study.wall_totals(r), walls, case) if r.ok else None for r, case in runs]
            for c, runs in per.items()}
    keys = [(w["name"], "normal") for w in walls] + \
           [(w["name"], "shear") for w in walls if w["group"].startswith("side")]
    metrics, summary = [], {}
    for c in codes:
        summary[c] = {f"{w}.{k}": stats.mean_se([t[w][k] for t in tots[c] if t]) for w, k in keys}
        summary[c]["failed"] = [r.reason for r, _ in per[c] if not r.ok]
    for c in codes:
        if c == "native":
            continue
        for w, k in keys:
            name = f"static {w} {k} total, members from the scene's start ({c} vs native)"
            if summary[c]["failed"] or summary["native"]["failed"]:
                metrics.append(verdict.unjudged(name, plan.name, "failed members: " + "; ".join(
                    (summary[c]["failed"] + summary["native"]["failed"])[:2]), "statistical"))
                continue
            kind = "wall_friction" if k == "shear" else "wall_load"
            if plan.options.metrics and kind not in plan.options.metrics:
                continue
            st = stats.difference([t[w][k] if t else None for t in tots["native"]],
                                  [t[w][k] if t else None for t in tots[c]], relative=True, paired=True)
            a, b = summary["native"][f"{w}.{k}"], summary[c][f"{w}.{k}"]
            metrics.append(verdict.statistical(name, plan.name, st, kind, plan.options,
                                               {"native": list(a[:2]), c: list(b[:2])}))
    if np.linalg.norm(plan.shared["gravity"]) > 0:       # every member at rest carries its weight
        for c in codes:
            worst = None
            for r, case in per[c]:
                m = weight_metrics(plan.name, {c: r}, case, plan.shared)[0]
                if worst is None or not m["pass"] or m["values"].get("rel_diff", 0) > worst["values"].get("rel_diff", 0):
                    worst = m
                if not m["pass"]:
                    break
            if worst is not None:
                worst["metric"] += f", worst of {plan.members} members"
                metrics.append(worst)
    return metrics, {"case": plan.name, "members": plan.members, "summary": summary}


def _with_weight(tot: dict, walls: list, case: Case) -> dict:
    """Adds the force the discs exert on all walls together along gravity: at rest, their weight
    (the least noisy static quantity of an ensemble: it sees density and gravity directly)."""
    g = np.array(case.resolved["gravity"], float)
    gn = np.linalg.norm(g)
    down = g / gn if gn > 0 else np.array([0.0, -1.0])
    w_sum = 0.0
    for w in walls:
        if w["name"] in tot:
            f = -tot[w["name"]]["normal"] * inward_normal(w, case.centre) + tot[w["name"]]["shear"] * tangent(w)
            w_sum += float(f @ down)
    return dict(tot, **{"all walls": {"weight": w_sum}})


TOL_WEIGHT = 1e-4   # walls' load along gravity against the weight, relative (rest residue after 0.3 s: 1e-5)


def weight_metrics(name: str, results: dict, case: Case, resolved: dict) -> list:
    """Each code at rest: the force on all walls along gravity against the discs' weight, sum of
    rho pi r^2 |g| (the scene's, unmutated: a code with a wrong density or gravity fails here)."""
    rho = {m["name"]: m["density"] for m in resolved["materials"]}
    names = [m["name"] for m in resolved["materials"]]
    d = np.array(resolved["discs"], float)
    weight = float(sum(rho[names[int(m)]] * math.pi * r * r for r, m in zip(d[:, 2], d[:, 3]))
                   * np.linalg.norm(resolved["gravity"]))
    walls = [w for w in resolved["walls"] if w.get("active", True)]
    out = []
    for c, r in results.items():
        mname = f"weight carried by the walls at rest ({c} vs rho pi r^2 g)"
        if not r.ok:
            out.append(verdict.unjudged(mname, name, f"run failed: {r.reason}"))
            continue
        got = _with_weight(study.wall_totals(r), walls, case)["all walls"]["weight"]
        rel = abs(got - weight) / weight if weight else float("nan")
        out.append(_metric(mname, name, {"walls": got, "weight": weight, "rel_diff": rel}, TOL_WEIGHT,
                           rel <= TOL_WEIGHT, "" if rel <= TOL_WEIGHT else "not at rest, or a wrong density or gravity"))
    return out


JANSSEN_SERIES = 0.05   # [s] wall-force samples of a Janssen member (the mobilisation before the lowering)
JANSSEN_MIN_POINTS = 8  # a fit counts only with this many points over the column's depth


def janssen_column(plan: Plan, codes, out: Path, mutation=None) -> tuple[list, dict]:
    """Members of a tall column in every code, each the jittered scene start run in one piece for
    the plan's duration (the scene's end.time unless --duration): the discs fall and settle, then
    the floor is lowered slowly by the scene's prescribed translation (walls[].velocity: a
    fraction of a disc diameter), so that the column slides down along the side walls and their
    friction is mobilised upward; the column then rests, or (a translation until the run's end)
    is measured while it slides. The ensemble-averaged side-wall pressure of each code (bins W
    tall) is fitted with Janssen's law (scipy curve_fit); a fit counts when its goodness of fit
    (janssen.goodness_of_fit) has p >= 0.01, with at least 8 points; janssen_metrics judges each code against the native engine, paired by
    member; floor force + wall friction = weight, each member's (a sliding column: the members'
    mean)."""
    records = {c: [] for c in codes}
    for k, (res, case) in enumerate(member_runs(plan, codes, out, mutation, JANSSEN_SERIES)):
        for c in codes:
            r = res[c]
            records[c].append(janssen.member_record(plan.shared, r, c, k, case.end_time) if r.ok else
                              {"status": "failed", "reason": r.reason})
    fits, metrics, table = {}, [], []
    sliding = any(w.get("motion") and float(w["motion"]["until"]) >= plan.duration - 1e-9 for w in plan.shared["walls"])
    for c in codes:
        ok = [m for m in records[c] if m.get("status") == "ok"]
        fails = [m["reason"] for m in records[c] if m.get("status") != "ok"]
        if fails or len(ok) < 2:
            metrics.append(verdict.unjudged(f"Janssen fit ({c})", plan.name,
                                            "failed members: " + "; ".join(fails[:2]) if fails else "fewer than 2 members"))
            continue
        fits[c] = f = janssen.ensemble_fit(ok)
        f["members"] = len(ok)
        chk = f["checks"]
        bal = max(abs(b) for b in chk["balance"])
        if sliding:      # the run ends while the column slides: each member's forces carry its stick-slip inertia
            metrics.append(_metric(f"Janssen column sliding: floor force + wall friction = weight, mean of the "
                                   f"members ({c})", plan.name, {"mean_rel": chk["balance_mean"], "max_rel": bal},
                                   0.01, chk["balance_mean_ok"]))
        else:
            metrics.append(_metric(f"Janssen column: floor force + wall friction = weight, every member ({c})",
                                   plan.name, {"max_rel": bal}, 0.01, chk["balance_ok"]))
        f["gof"] = g = janssen.goodness_of_fit(f)
        good = g["ok"] and f["n_points"] >= JANSSEN_MIN_POINTS
        gate = _metric(f"Janssen law fits the {len(ok)}-member mean profile: goodness of fit p >= "
                       f"{janssen.GOF_ALPHA} with >= {JANSSEN_MIN_POINTS} points ({c})", plan.name,
                       {"gof_p": g["p"], "chi2": g["chi2"], "dof": g["dof"], "r2": f["r2"],
                        "n_points": f["n_points"], "bin_width": f["bin_width"]},
                       f"p >= {janssen.GOF_ALPHA}", good,
                       "" if good else f"goodness of fit p {g['p']:.3g} (chi^2 {g['chi2']:.1f}, {g['dof']} dof) with "
                                       f"{f['n_points']} points of {f['bin_width']:g} cm: the fit cannot be judged")
        if not good:     # a profile the law does not fit cannot be judged: inconclusive, never disagree (docs/compare.md)
            gate["verdict"] = verdict.INCONCLUSIVE
        metrics.append(gate)
    if "native" in fits:
        for c, f in fits.items():
            if c != "native":
                metrics += janssen_metrics(plan, fits["native"], f, c, records["native"], records[c])
    table += ["| code | members | bin [cm] | points | chi², dof, goodness-of-fit p | r² | p_inf | lambda [cm] | K | mu_w,eff | "
              "mobilised F_t/(mu_w F_n): before lowering, after (all; top half) | balance (max) | wall time / member [s] |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for c, f in fits.items():
        ci = f["ci"]
        chk = f["checks"]
        mu = chk["mu_w"]
        ok = [m for m in records[c] if m.get("status") == "ok"]
        before = chk["mobilised_before_mean"]
        btxt = f"{before / mu:.2f} ± {1.96 * chk['mobilised_before_se'] / mu:.2f}" if math.isfinite(before) else "n/a"
        table.append(f"| {c} | {len(ok)} | {f['bin_width']:g} | {f['n_points']} | "
                     f"{f['gof']['chi2']:.1f}, {f['gof']['dof']}, {f['gof']['p']:.2f} | {f['r2']:.3f} | "
                     f"{f['p_inf']:.4g} ± {ci['p_inf']:.2g} | {f['lambda']:.3g} ± {ci['lambda']:.2g} | "
                     f"{f['K']:.3g} ± {ci['K']:.2g} | {f['mu_w_eff']:.3g} ± {ci['mu_w_eff']:.2g} | "
                     f"{btxt}; {chk['mobilised_all_mean'] / mu:.2f} ± {1.96 * chk['mobilised_all_se'] / mu:.2f}; "
                     f"{chk['mobilised_upper_mean'] / mu:.2f} (mu_w {mu:g}) | "
                     f"{max(abs(b) for b in chk['balance']):.2g} | "
                     f"{np.mean([m['wall_time_s'] for m in ok]):.0f} |")
    table += ["", "± are 95 % intervals (fit: scipy curve_fit covariance; mobilised: over the members)."]
    png = None
    if fits and mutation is None:
        png = f"janssen_{plan.name}.png"
        janssen_figure.plot_ensemble_fits(fits, out.parent.parent / png,
                                          f"{plan.name}: ensemble-averaged side-wall pressure, Janssen fits, 95 % bands")
    summary = {c: {**{k: f[k] for k in janssen.FIT_KEYS}, "ci": f["ci"], "r2": f["r2"], "n_points": f["n_points"],
                   "bin_width": f["bin_width"], "chi2_red": f["chi2_red"], "gof": f["gof"], "checks": f["checks"]}
               for c, f in fits.items()}
    return metrics, {"case": plan.name, "members": plan.members, "table": table, "png": png, "fits": summary}


JANSSEN_JUDGED = ("K", "lambda", "mu_w_eff")   # the fit's parameters with a margin (compare/cases/margins.py)


def janssen_metrics(plan: Plan, a: dict, b: dict, code: str, rec_a: list | None = None,
                    rec_b: list | None = None) -> list:
    """Each judged parameter of code's ensemble fit against the native fit, and mu_w,eff of the
    deep half member by member, all paired by member (members k of every code share their
    jittered start; ``rec_a``, ``rec_b``: the member records, None or a failed record where a
    member has none):

    - K, lambda, mu_w,eff: the relative difference b/a - 1 of the two ensemble fits, its standard
      error from the paired delete-one jackknife (member k left out of both ensembles;
      janssen.jackknife_fits), n - 1 degrees of freedom; a profile that the law does not fit on
      either side (janssen.goodness_of_fit p < GOF_ALPHA) leaves them inconclusive;
    - mu_w,eff of the deep half: every member's rho_b g W / (2 p_deep), p_deep its mean side-wall
      pressure over the fitted bins of the lower half of the profile (between the native members'
      mean surface and W/2 above the floor: the same bins in every code), where Janssen's pressure
      nears p_inf = rho_b g W / (2 mu_w,eff); the paired relative difference of the member means
      (stats.difference). It needs no fit, so a profile below the r^2 gate still judges it."""
    out = []
    unfit = not all(f.get("gof", {}).get("ok", False) for f in (a, b))
    why_unfit = (f"goodness of fit p {a.get('gof', {}).get('p', float('nan')):.3g} (native), "
              f"{b.get('gof', {}).get('p', float('nan')):.3g} ({code}): a fit counts only with p >= {janssen.GOF_ALPHA}")
    jack, jack_why = {}, ""
    if not unfit and rec_a is not None and rec_b is not None:
        try:
            jack = janssen.jackknife_fits(rec_a, rec_b, JANSSEN_JUDGED, a.get("merge"))
        except (RuntimeError, ValueError) as e:
            jack_why = f"paired jackknife: {e}"
    for k in JANSSEN_JUDGED:
        name = f"Janssen {k} ({code} vs native)"
        if unfit or k not in jack:
            out.append(verdict.unjudged(name, plan.name, why_unfit if unfit else
                                        (jack_why or "no member records to pair"), "statistical"))
            continue
        se, n = jack[k]
        st = {"type": "t", "relative": True, "n": [n, n], "estimate": b[k] / a[k] - 1, "se": se,
              "df": float(n - 1), "design": "paired", "mean": [a[k], b[k]]}
        out.append(verdict.statistical(name, plan.name, st, "janssen", plan.options,
                                       {"native": [a[k], a["se"][k]], code: [b[k], b["se"][k]]},
                                       "ensemble-averaged profile's fit; standard error: paired jackknife "
                                       "over the members"))
    name = f"Janssen mu_w_eff of the deep half, member by member ({code} vs native)"
    if rec_a is None or rec_b is None or not any(m and m.get("status") == "ok" for m in rec_a):
        out.append(verdict.unjudged(name, plan.name, "no member records to pair", "statistical"))
        return out
    y_top = janssen.deep_top(rec_a)
    merge = a.get("merge") or janssen.merge_for([next(m for m in rec_a if m and m.get("status") == "ok")])
    va, nbins = janssen.saturated_mu(rec_a, y_top, merge)
    vb, _ = janssen.saturated_mu(rec_b, y_top, merge)
    st = stats.difference(va, vb, relative=True, paired=True)
    if nbins < janssen.SAT_MIN_BINS:
        st = dict(st, reason=f"{nbins} fitted bins below y = {y_top:.1f} cm: no deep part to average")
    out.append(verdict.statistical(name, plan.name, st, "janssen", plan.options,
                                   {"native": list(stats.mean_se([v for v in va if v is not None])[:2]),
                                    code: list(stats.mean_se([v for v in vb if v is not None])[:2]),
                                    "y_top": y_top, "bins": nbins},
                                   f"rho_b g W / (2 p_deep) per member, p_deep the side-wall pressure over {nbins} "
                                   f"bins below y = {y_top:.1f} cm (the lower half of the native profile)"))
    return out


def discharge_start(plan: Plan, out: Path) -> np.ndarray | None:
    """The discs a discharge's members jitter: --start frozen, the native engine's rested packing
    (one fill for every member of every code, so member k starts alike in every code and settles
    only --settle s); --start scene, None (the scene's start, each code filling it itself)."""
    return frozen_packing(plan, out) if plan.options.start == "frozen" else None


def discharge(plan: Plan, codes, out: Path, mutation=None) -> tuple[list, dict]:
    unrested = rest_gate(plan, out)
    if unrested:
        return unrested, {}
    per = ensemble_runs(plan, codes, out, mutation, start=discharge_start(plan, out))
    per_code = {c: [(r, study.discharge_measures(r, case) if r.ok else {}) for r, case in runs]
                for c, runs in per.items()}
    metrics, summary = study.discharge_compare(plan.name, per_code, plan.options)
    if mutation is None:
        study.save_series(out / "series.json", per_code)
    return metrics, summary


KIND_RUNNERS = {"collision": collision, "janssen": janssen_column, "discharge": discharge}


def shear_box(plan: Plan, codes, out: Path, mutation=None) -> tuple[list, dict]:
    """Paper 2's shear box (compare/cases/shear.py, compare/verdict/shear_judge.py): jittered members compressed to rest and sheared in
    every code; sigma0, the windowed peak of tau/sigma, its mean in strain bands (the curve) and
    the dilation compared as ensemble means against the shear margin, every member at rest before
    the shear."""
    per = ensemble_runs(plan, codes, out, mutation)
    metrics, detail = shear_judge.judge(plan.name, {c: [r for r, _ in runs] for c, runs in per.items()},
                                  float(plan.shared["shear"]["max_strain"]),
                                  float(plan.shared["shear"]["sample_strain"]), plan.options)
    detail["dt"], detail["settle"] = plan.dt, plan.settle
    if mutation is None and detail["curves"]:
        detail["png"] = f"shear_{plan.name}.png"
        shear_judge.plot(detail, out.parent.parent / detail["png"])
    return metrics, detail


KIND_RUNNERS["shear"] = shear_box


def run_plan(plan: Plan, codes, out: Path, mutation=None) -> tuple[list, dict]:
    codes = codes_of(plan, codes)
    if plan.kind == "static":
        fn = static_frozen if plan.options.start == "frozen" else static_members
    else:
        fn = KIND_RUNNERS[plan.kind]
    return fn(plan, codes, out, mutation)


# ------------------------------------------------------------------------ the whole run

def plans_of(entries: list[Entry], codes) -> list[Plan]:
    """Every entry's plan, every refusal found before any run (PlanError lists them all)."""
    plans, refused, names = [], [], set()
    for e in entries:
        p = make_plan(e)
        base, k = p.name, 2
        while p.name in names:             # the same scene twice: its own folder and metrics
            p.name, k = f"{base}_{k}", k + 1
        names.add(p.name)
        plans.append(p)
        refused += refusals(p, codes_of(p, codes))
        if not refused:        # the engine's own refusal (dt above its bound), before any reference code
            why = preflight.refusal(p, member_case(p, 0))
            refused += [why] if why else []
    if refused:
        raise PlanError("\n".join(refused))
    return plans


def run(entries: list[Entry], out: Path, codes, log=print, mutation=None, plans=None,
        check_translation: bool = True, looks: int = 1, stop=None) -> dict:
    """Every plan run in every code and judged. ``stop(metrics)``, when given, is asked after each
    plan with that plan's metrics (not yet judged); a reason it returns ends the run there (a
    mutant caught by a physical metric needs no further scene)."""
    out.mkdir(parents=True, exist_ok=True)
    plans = plans if plans is not None else plans_of(entries, codes)
    report = {"codes": {}, "metrics": [], "scenes": [], "calibration": [], "static": [], "discharge": {},
              "janssen": []}
    for c in codes:
        be = study.backend(c)
        report["codes"][c] = be.version() if be.available() else "not installed"
    t0 = time.monotonic()
    for p in plans:
        where = out / p.kind / p.name
        log(f"{p.name}: {p.kind}{' (' + p.options.start + ')' if p.kind in ('static', 'discharge') else ''}, "
            f"{p.members} member(s), dt {p.dt:g} s, {p.duration:g} s"
            + (f" [mutant {mutation.name}]" if mutation else ""))
        t1 = time.monotonic()
        metrics = translation_check(p, codes, out, mutation) if check_translation else []
        m, detail = run_plan(p, codes, where, mutation)
        metrics += m
        report["metrics"] += metrics
        report["scenes"].append({"scene": str(p.entry.scene), "name": p.name, "kind": p.kind,
                                 "members": p.members, "dt": p.dt, "duration": p.duration,
                                 "native_law": p.options.native_law, "elapsed_s": time.monotonic() - t1})
        if p.kind == "collision":
            report["calibration"].append(detail)
        elif p.kind == "discharge":
            report["discharge"][p.name] = detail
        elif p.kind == "janssen":
            report["janssen"].append(detail)
        elif p.kind == "shear":
            report.setdefault("shear", []).append(detail)
        else:
            report["static"].append(detail)
        why = stop(metrics) if stop is not None else None
        if why:
            left = plans[plans.index(p) + 1:]
            if left:
                log(f"{why}: the remaining {len(left)} scene(s) not run")
            break
    report["elapsed_s"] = time.monotonic() - t0
    return judged(report, looks)


def judged(report: dict, looks: int = 1) -> dict:
    """Every metric judged (the statistical ones against their margins, the disagree level split
    over the report's statistical metrics and ``looks``), then each scene's and the report's verdict."""
    verdict.finalize(report["metrics"], looks)
    for sc in report["scenes"]:
        sc["verdict"] = verdict.combine(m["verdict"] for m in report["metrics"] if m["scene"] == sc["name"])
        sc["passed"] = sc["verdict"] == verdict.AGREE
    report["verdict"] = verdict.combine(m["verdict"] for m in report["metrics"])
    report["passed"] = report["verdict"] == verdict.AGREE
    return report

"""Janssen's law for a 2D slab of width W (validation.md):

    p_w(z) = p_inf (1 - exp(-(z - z0) / lambda)),  lambda = W / (2 K mu_w),
    p_inf = rho_b g W / (2 mu_w),

fitted by least squares to a side-wall pressure profile (force per bin / bin length against
depth z below the top surface), leaving out the lowest ~W/2 near the floor corners. For a fixed
lambda the model is linear in A = p_inf and B = -p_inf exp(z0 / lambda), so the fit is an exact
1D minimisation over lambda (golden section on log lambda, bracketed by a grid).

The ensemble test (``--kind janssen``, compare/verdict/pipeline.py ``janssen_column``) measures each
member's run with ``member_record`` and fits the members' mean profile with ``ensemble_fit``
(scipy's curve_fit, 95 % intervals from its covariance).
"""
from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.optimize import OptimizeWarning, curve_fit
from scipy.spatial import cKDTree

from dem.compare.cases.common import moved_wall


def _linear(z, p, lam):
    e = np.exp(-z / lam)
    M = np.column_stack([np.ones_like(z), e])
    coef, *_ = np.linalg.lstsq(M, p, rcond=None)
    res = p - M @ coef
    return coef, float(res @ res)


def fit(z: np.ndarray, p: np.ndarray, lam_range=(0.05, 1e4)) -> dict:
    """Least-squares p_inf, lambda, z0 of p = p_inf (1 - exp(-(z - z0)/lambda))."""
    z, p = np.asarray(z, float), np.asarray(p, float)
    ok = np.isfinite(z) & np.isfinite(p)
    z, p = z[ok], p[ok]
    if len(z) < 4:
        raise ValueError(f"Janssen fit needs at least 4 points, got {len(z)}")
    span = max(float(z.max() - z.min()), 1e-12)
    grid = np.geomspace(max(lam_range[0], span * 1e-3), min(lam_range[1], span * 1e3), 200)
    sse = [_linear(z, p, lam)[1] for lam in grid]
    k = int(np.argmin(sse))
    lo, hi = math.log(grid[max(k - 1, 0)]), math.log(grid[min(k + 1, len(grid) - 1)])
    g = (math.sqrt(5) - 1) / 2
    a, b = lo, hi
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = _linear(z, p, math.exp(c))[1], _linear(z, p, math.exp(d))[1]
    for _ in range(100):
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = _linear(z, p, math.exp(c))[1]
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = _linear(z, p, math.exp(d))[1]
    lam = math.exp((a + b) / 2)
    (A, B), sse = _linear(z, p, lam)
    z0 = lam * math.log(-B / A) if A > 0 and B < 0 else float("nan")
    ss_tot = float(((p - p.mean()) ** 2).sum())
    return {"p_inf": float(A), "lambda": float(lam), "z0": float(z0), "rmse": math.sqrt(sse / len(z)),
            "r2": 1 - sse / ss_tot if ss_tot > 0 else float("nan"), "n_points": int(len(z)),
            "lambda_at_grid_edge": bool(k in (0, len(grid) - 1))}


def model(z, p_inf, lam, z0):
    return p_inf * (1 - np.exp(-(np.asarray(z, float) - z0) / lam))


def derived(f: dict, rho_b: float, g: float, width: float) -> dict:
    """mu_w,eff = rho_b g W / (2 p_inf) and K = p_inf / (rho_b g lambda) (validation.md)."""
    p_inf, lam = f["p_inf"], f["lambda"]
    return {"mu_w_eff": rho_b * g * width / (2 * p_inf) if p_inf > 0 else float("nan"),
            "K": p_inf / (rho_b * g * lam) if lam > 0 else float("nan")}


def side_wall_pressure(profiles: dict, walls: list[dict], surface_y: float, floor_y: float,
                       width: float, names=("left", "right")) -> tuple[np.ndarray, np.ndarray]:
    """Depth below the surface and mean pressure of the side walls (bins above W/2 from the floor).

    ``profiles``: Result.profiles; the side walls run from top to bottom (``from`` is the top).
    """
    wall = {w["name"]: w for w in walls}
    zs, ps = [], []
    for name in names:
        prof = profiles[name]
        top = wall[name]["from"][1]
        s_lo, s_hi = np.array(prof["s_lo"]), np.array(prof["s_hi"])
        y_mid = top - 0.5 * (s_lo + s_hi)
        zs.append(surface_y - y_mid)
        ps.append(np.array(prof["normal"]) / (s_hi - s_lo))
    z = np.mean(zs, axis=0)
    p = np.mean(ps, axis=0)
    y_mid = surface_y - z
    keep = (z > 0) & (y_mid > floor_y + width / 2)
    return z[keep], p[keep]


def surface_height(discs: np.ndarray, width: float, columns: int = 5) -> float:
    """Mean over vertical columns of the highest disc top: the free surface [cm]."""
    d = np.asarray(discs, float)
    x0, x1 = d[:, 0].min() - d[:, 2].max(), d[:, 0].max() + d[:, 2].max()
    tops = []
    for k in range(columns):
        lo, hi = x0 + (x1 - x0) * k / columns, x0 + (x1 - x0) * (k + 1) / columns
        sel = (d[:, 0] >= lo) & (d[:, 0] < hi)
        if sel.any():
            tops.append(float((d[sel, 1] + d[sel, 2]).max()))
    return float(np.mean(tops))


def packing_fraction(discs: np.ndarray, width: float, floor_y: float, surface_y: float) -> float:
    """Disc area over the bin's area below the surface (discs' area above the surface is cut)."""
    d = np.asarray(discs, float)
    below = d[:, 1] <= surface_y
    return float(np.sum(math.pi * d[below, 2] ** 2) / (width * (surface_y - floor_y)))


# ---------------------------------------------------------------- ensembles with intervals

Z95 = 1.959963984540054   # two-sided 95 % quantile of the normal distribution
R2_MIN = 0.95             # a fit counts only with r^2 at least this
FIT_KEYS = ("p_inf", "lambda", "z0", "K", "mu_w_eff")


POOLED_BELOW = 8          # ensembles smaller than this use the pooled relative scatter


def ensemble_profile(members: list[dict], merge: int = 2, sigma: str = "auto") -> dict:
    """Mean side-wall pressure over members, bin by bin, and each bin's standard error ``se``.

    ``sigma``: "bin": each bin's own standard error (sample standard deviation over members /
    sqrt(n)); "pooled": the relative scatter (standard deviation over mean) pooled over the kept
    bins as an RMS, times each bin's mean, / sqrt(n) -- the force-chain scatter grows with the
    pressure, and with 2-4 members a bin's own standard deviation (1-3 degrees of freedom) can be
    near zero by chance and would dominate a weighted fit; "auto": "bin" from POOLED_BELOW
    members up, else "pooled".

    ``members``: records with the same bins (``y_lo``, ``y_hi``: height of each bin, ``p``: mean
    side-wall pressure there), ``surface``, ``floor``, ``width``. ``merge`` neighbouring bins are
    joined first (their pressures averaged). Depth z is measured below the members' mean surface;
    bins are kept when they lie wholly below the lowest member surface and more than W/2 above
    the floor (validation.md).
    """
    if len(members) < 2:
        raise ValueError("an ensemble profile needs at least 2 members")
    y_lo = np.array(members[0]["y_lo"], float)
    y_hi = np.array(members[0]["y_hi"], float)
    P = np.array([m["p"] for m in members], float)
    n = (len(y_lo) // merge) * merge
    y_lo = y_lo[:n].reshape(-1, merge).min(axis=1)
    y_hi = y_hi[:n].reshape(-1, merge).max(axis=1)
    P = P[:, :n].reshape(len(members), -1, merge).mean(axis=2)
    surface = float(np.mean([m["surface"] for m in members]))
    floor, width = float(members[0]["floor"]), float(members[0]["width"])
    keep = (y_hi <= min(m["surface"] for m in members)) & (y_lo >= floor + width / 2)
    y_mid = 0.5 * (y_lo + y_hi)
    n = len(members)
    mode = sigma if sigma != "auto" else ("bin" if n >= POOLED_BELOW else "pooled")
    mean, sd, se = _mean_sd_se(P[:, keep], mode)
    order = np.argsort(surface - y_mid[keep])
    return {"z": (surface - y_mid[keep])[order], "p": mean[order], "se": se[order], "sd": sd[order],
            "members": n, "surface": surface, "sigma": mode}


def _mean_sd_se(P: np.ndarray, mode: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each bin's mean over the members (rows of P), standard deviation and standard error by
    ``mode`` (ensemble_profile's ``sigma``: "bin" or "pooled")."""
    n = P.shape[0]
    mean, sd = P.mean(axis=0), P.std(axis=0, ddof=1)
    if mode == "bin":
        return mean, sd, sd / math.sqrt(n)
    if mode == "pooled":
        ok = mean > 0
        cv = math.sqrt(float(np.mean((sd[ok] / mean[ok]) ** 2)))
        return mean, sd, cv * np.abs(mean) / math.sqrt(n)
    raise ValueError(f"sigma: 'bin', 'pooled' or 'auto', not {mode!r}")


def fit_ci(z, p, sigma, level_z: float = Z95) -> dict:
    """Weighted least squares of p = p_inf (1 - exp(-(z - z0)/lambda)) (scipy curve_fit with
    ``sigma`` as absolute standard errors); 95 % half-widths ``ci`` = 1.96 x the standard errors
    from pcov, which is scaled by the reduced chi^2 when that exceeds 1 (scatter the given sigma
    does not explain widens the intervals, never narrows them). r^2 is the unweighted share of
    the profile's variance that the model explains."""
    z, p, sigma = (np.asarray(a, float) for a in (z, p, sigma))
    if len(z) < 4:
        raise ValueError(f"Janssen fit needs at least 4 points, got {len(z)}")
    sigma = np.where(sigma > 0, sigma, np.max(sigma[sigma > 0]) if np.any(sigma > 0) else 1.0)
    start = fit(z, p)
    p0 = [start["p_inf"], start["lambda"], start["z0"] if math.isfinite(start["z0"]) else 0.0]
    popt, pcov = curve_fit(model, z, p, p0=p0, sigma=sigma, absolute_sigma=True, maxfev=20000)
    res = p - model(z, *popt)
    dof = max(len(z) - 3, 1)
    chi2_red = float(np.sum((res / sigma) ** 2) / dof)
    pcov = pcov * max(1.0, chi2_red)
    se = np.sqrt(np.diag(pcov))
    ss_tot = float(np.sum((p - p.mean()) ** 2))
    names = ("p_inf", "lambda", "z0")
    return {**{k: float(v) for k, v in zip(names, popt)},
            "se": {k: float(s) for k, s in zip(names, se)},
            "ci": {k: float(level_z * s) for k, s in zip(names, se)},
            "cov": pcov.tolist(), "r2": 1 - float(res @ res) / ss_tot if ss_tot > 0 else float("nan"),
            "chi2_red": chi2_red, "n_points": int(len(z))}


GOF_ALPHA = 0.01          # a fit counts when its goodness-of-fit p-value is at least this
GOF_REPLICATES = 400      # parametric bootstrap replicates of that p-value


def _chi2(z, p, sigma, p0) -> float:
    """chi^2 of the weighted least-squares fit of Janssen's law started at p0 (fit_ci's weights)."""
    sigma = np.where(sigma > 0, sigma, np.max(sigma[sigma > 0]) if np.any(sigma > 0) else 1.0)
    try:
        with warnings.catch_warnings():       # only the residuals count here, not the covariance
            warnings.simplefilter("ignore", OptimizeWarning)
            popt, _ = curve_fit(model, z, p, p0=p0, sigma=sigma, absolute_sigma=True, maxfev=20000)
    except RuntimeError:            # no convergence: the profile is far from the law
        return math.inf
    return float(np.sum(((p - model(z, *popt)) / sigma) ** 2))


def goodness_of_fit(f: dict, replicates: int = GOF_REPLICATES, seed: int = 1) -> dict:
    """Is the ensemble profile Janssen's law, up to the members' scatter? The fit's chi^2 (each
    bin's residual over its standard error) against its distribution when it is: a parametric
    bootstrap that draws the members anew as the fitted law plus normal scatter of each bin's
    measured standard deviation, forms their mean and standard errors as the data's (the same
    ``sigma`` mode) and fits them again. The bootstrap, not the chi^2 table: a bin's standard
    error from a few members is itself uncertain, which makes chi^2 larger than the table's (by
    (n - 1)/(n - 3) in the mean for n members). p = (1 + replicates at or above the observed
    chi^2) / (1 + replicates); the fit counts (``ok``) when p >= GOF_ALPHA. r^2 is no gate: in a
    column several lambda deep the profile is flat over most of its depth, so scatter that the
    law explains leaves r^2 low (measured: r^2 0.93 with chi^2 / dof 1.0-1.2)."""
    prof = f["profile"]
    z, p, se, sd = (np.asarray(prof[k], float) for k in ("z", "p", "se", "sd"))
    n, mode = int(prof["members"]), prof["sigma"]
    p0 = (f["p_inf"], f["lambda"], f["z0"])
    observed = _chi2(z, p, se, p0)
    truth = model(z, *p0)
    rng = np.random.default_rng(seed)
    reps = np.empty(replicates)
    for k in range(replicates):
        mean, _, s = _mean_sd_se(truth + rng.standard_normal((n, len(z))) * sd, mode)
        reps[k] = _chi2(z, mean, s, p0)
    pval = float((1 + np.sum(reps >= observed)) / (1 + replicates))
    dof = len(z) - 3
    return {"chi2": observed, "dof": dof, "p": pval, "replicates": replicates, "alpha": GOF_ALPHA,
            "ok": bool(pval >= GOF_ALPHA), "chi2_replicates_median": float(np.median(reps))}


def derived_ci(f: dict, rho_b: float, rho_b_se: float, g: float, width: float, level_z: float = Z95) -> dict:
    """mu_w,eff = rho_b g W / (2 p_inf) and K = p_inf / (rho_b g lambda) with standard errors
    propagated to first order from the fit's covariance of (p_inf, lambda) and rho_b's standard
    error (independent of the fit); adds them to ``f`` and returns it."""
    p_inf, lam = f["p_inf"], f["lambda"]
    cov = np.array(f["cov"], float)
    vp, vl, cpl = cov[0, 0], cov[1, 1], cov[0, 1]
    vr = (rho_b_se / rho_b) ** 2
    mu = rho_b * g * width / (2 * p_inf)
    K = p_inf / (rho_b * g * lam)
    mu_se = abs(mu) * math.sqrt(vp / p_inf ** 2 + vr)
    K_se = abs(K) * math.sqrt(max(vp / p_inf ** 2 + vl / lam ** 2 - 2 * cpl / (p_inf * lam) + vr, 0.0))
    f.update({"mu_w_eff": mu, "K": K, "rho_b": rho_b})
    f["se"].update({"mu_w_eff": mu_se, "K": K_se, "rho_b": rho_b_se})
    f["ci"].update({"mu_w_eff": level_z * mu_se, "K": level_z * K_se, "rho_b": level_z * rho_b_se})
    return f


def ensemble_fit(members: list[dict], merge: int | None = None, sigma: str = "auto") -> dict:
    """The fit of the ensemble-averaged profile with derived K and mu_w,eff (rho_b from the
    members' packing fractions: mean and standard error), and the per-member cross-checks.
    ``merge``: profile bins joined per fitted bin (None: ``merge_for``, bins W tall)."""
    if merge is None:
        merge = merge_for(members)
    prof = ensemble_profile(members, merge, sigma)
    f = fit_ci(prof["z"], prof["p"], prof["se"])
    phi = np.array([m["phi"] for m in members], float)
    rho_s = float(members[0]["rho_s"])
    derived_ci(f, rho_s * phi.mean(), rho_s * phi.std(ddof=1) / math.sqrt(len(phi)),
               float(members[0]["g"]), float(members[0]["width"]))
    f["profile"] = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in prof.items()}
    f["bin_width"] = float(np.median(np.subtract(members[0]["y_hi"], members[0]["y_lo"]))) * merge
    f["merge"] = int(merge)
    f["checks"] = member_checks(members)
    return f


def member_checks(members: list[dict], balance_tol: float = 0.01) -> dict:
    """Per member: global balance (floor force + wall friction - weight) / weight within
    ``balance_tol`` (``balance_ok``; ``balance_mean_ok``: the members' mean within it, the check
    of a column that ends sliding, whose members' forces each carry the inertia of its
    stick-slip); mobilised wall friction (signed shear over normal on the side walls) in the
    upper half and overall at the end, and overall before the floor is lowered (codes with a
    wall-force series), to be read against the Coulomb coefficient mu_w."""
    bal = [m["balance"] for m in members]
    up = np.array([m["mobilised_upper"] for m in members], float)
    al = np.array([m["mobilised_all"] for m in members], float)
    bf = np.array([m.get("mobilised_before", float("nan")) for m in members], float)
    se = lambda v: float(v.std(ddof=1) / math.sqrt(len(v))) if len(v) > 1 else float("nan")  # noqa: E731
    return {"balance": bal, "balance_ok": bool(all(abs(b) <= balance_tol for b in bal)),
            "balance_mean": float(np.mean(bal)), "balance_mean_ok": bool(abs(float(np.mean(bal))) <= balance_tol),
            "mobilised_upper": up.tolist(), "mobilised_upper_mean": float(up.mean()),
            "mobilised_upper_se": se(up),
            "mobilised_all_mean": float(al.mean()), "mobilised_all_se": se(al),
            "mobilised_before_mean": float(bf.mean()) if np.all(np.isfinite(bf)) else float("nan"),
            "mobilised_before_se": se(bf) if np.all(np.isfinite(bf)) else float("nan"),
            "mu_w": float(members[0]["mu_w"]),
            "max_overlap_ratio": float(max(m["max_overlap_ratio"] for m in members))}


def compare_fits(a: dict, b: dict, keys=FIT_KEYS, r2_min: float = R2_MIN, level_z: float = Z95) -> dict:
    """Two fits agree when both have r^2 >= r2_min and, for every parameter, the difference lies
    within the combined interval level_z sqrt(se_a^2 + se_b^2)."""
    out, ok = {}, a["r2"] >= r2_min and b["r2"] >= r2_min
    for k in keys:
        diff = b[k] - a[k]
        tol = level_z * math.hypot(a["se"][k], b["se"][k])
        agree = bool(abs(diff) <= tol)
        out[k] = {"a": a[k], "b": b[k], "diff": diff, "tol": tol, "agree": agree}
        ok = ok and agree
    return {"params": out, "r2": [a["r2"], b["r2"]], "r2_ok": bool(a["r2"] >= r2_min and b["r2"] >= r2_min),
            "agree": bool(ok)}


def band(f: dict, z, level_z: float = Z95) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Model and its pointwise confidence band (first-order, from the fit's covariance)."""
    z = np.asarray(z, float)
    p_inf, lam, z0 = f["p_inf"], f["lambda"], f["z0"]
    e = np.exp(-(z - z0) / lam)
    J = np.column_stack([1 - e, -p_inf * e * (z - z0) / lam ** 2, -p_inf * e / lam])
    cov = np.array(f["cov"], float)
    s = np.sqrt(np.einsum("ij,jk,ik->i", J, cov, J))
    m = model(z, p_inf, lam, z0)
    return m, m - level_z * s, m + level_z * s


# ---------------------------------------------------------------- one member's measurements

UPPER = 0.5          # the upper part of the fill: its top half
BIN_WIDTHS = 1.0     # the fitted bins are BIN_WIDTHS x W tall (8 cm in the column: docs/compare.md)


def geometry(resolved: dict, t: float) -> dict:
    """Width W between the side walls, the floor's height at time ``t`` of the run (the bottom
    walls where their prescribed translation has taken them), the discs' density, |g| and the
    disc-wall friction coefficient mu_w of the side walls."""
    walls = resolved["walls"]
    sides = [w for w in walls if w["group"].startswith("side")]
    bottom = [moved_wall(w, t) for w in walls if not w["group"].startswith("side")]
    xs = [c for w in sides for c in (w["from"][0], w["to"][0])]
    rho = next(m["density"] for m in resolved["materials"] if m["density"] > 0)
    mat = sides[0]["material"]
    mu_w = next(p["mu"] for p in resolved["pairs"] if mat in p["materials"])
    return {"width": max(xs) - min(xs), "floor": max(max(w["from"][1], w["to"][1]) for w in bottom),
            "rho_s": rho, "g": float(np.linalg.norm(resolved["gravity"])), "mu_w": mu_w}


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


def _mobilised(sides: list, normal_of, shear_of, keep=None) -> float:
    """Sum of the side walls' friction over the sum of their normal force, per bin given by
    ``normal_of(wall)``, ``shear_of(wall)`` (signed: positive is friction holding the discs up;
    the side walls run top -> bottom)."""
    sh = np.sum([np.asarray(shear_of(s), float) for s in sides], axis=0)
    nn = np.sum([np.asarray(normal_of(s), float) for s in sides], axis=0)
    if keep is not None:
        sh, nn = sh[keep], nn[keep]
    return float(sh.sum() / nn.sum()) if nn.sum() > 0 else float("nan")


def lowering_start(resolved: dict) -> float | None:
    """[s] when the first prescribed wall translation starts (None without one)."""
    t = [float(w["motion"]["from"]) for w in resolved["walls"] if w.get("motion")]
    return min(t) if t else None


def member_record(resolved: dict, res, code: str, member: int, end_time: float) -> dict:
    """The Janssen quantities of one member's run (``res``: the common Result; ``end_time``: the
    run's simulated time): the side-wall pressure per bin (mean of both walls) against height,
    the packing fraction and surface, the weight, floor force and wall friction (global
    balance), the mobilised wall friction (sum of shear over sum of normal force on the side
    walls, a fraction of mu_w once divided by it) in the top half of the fill and overall, and
    overall just before the floor is lowered when the code records a wall-force series, the
    largest overlap relative to the radius and the code's wall time."""
    geo = geometry(resolved, end_time)
    W, floor = geo["width"], geo["floor"]
    d = np.array(res.discs_end, float)
    surf = surface_height(d, W)
    phi = packing_fraction(d, W, floor, surf)
    by_name = {w["name"]: w for w in resolved["walls"]}
    sides = [w["name"] for w in resolved["walls"] if w["group"].startswith("side")]
    lo = np.array(res.profiles[sides[0]]["s_lo"])
    hi = np.array(res.profiles[sides[0]]["s_hi"])
    top = moved_wall(by_name[sides[0]], end_time)["from"][1]     # the profile's bins run along the wall where it is
    normal = np.mean([np.array(res.profiles[s]["normal"]) for s in sides], axis=0)
    y_lo, y_hi = top - hi, top - lo
    upper = y_lo >= surf - UPPER * (surf - floor)
    prof = lambda key: (lambda s: res.profiles[s][key])  # noqa: E731
    weight = float(np.sum(geo["rho_s"] * math.pi * d[:, 2] ** 2) * geo["g"])
    bottom = [w["name"] for w in resolved["walls"] if not w["group"].startswith("side")]
    floor_force = float(sum(np.sum(res.profiles[b]["normal"]) for b in bottom))
    friction = float(sum(np.sum(res.profiles[s]["shear"]) for s in sides))
    before = float("nan")
    t0 = lowering_start(resolved)
    ser = res.series or {}
    if t0 is not None and ser.get("t"):
        ts = np.array(ser["t"], float)
        k = np.flatnonzero(ts <= t0 + 1e-9)
        if len(k):
            i = int(k[-1])
            w = ser["walls"]
            before = _mobilised(sides, lambda s: w[s]["normal"][i], lambda s: w[s]["shear"][i])
    return {"code": code, "member": member, "status": res.status, "reason": res.reason,
            "wall_time_s": res.wall_time_s, "n_discs": int(len(d)), "width": W, "floor": floor,
            "rho_s": geo["rho_s"], "g": geo["g"], "mu_w": geo["mu_w"],
            "surface": surf, "phi": phi, "weight": weight, "floor_force": floor_force,
            "wall_friction": friction, "balance": (floor_force + friction - weight) / weight,
            "mobilised_upper": _mobilised(sides, prof("normal"), prof("shear"), upper),
            "mobilised_all": _mobilised(sides, prof("normal"), prof("shear")),
            "mobilised_before": before,
            "max_overlap_ratio": max_overlap_ratio(d, W, floor),
            "kinetic_energy_end": res.kinetic_energy_end,
            "y_lo": y_lo.tolist(), "y_hi": y_hi.tolist(), "p": (normal / (hi - lo)).tolist()}


def merge_for(members: list[dict], widths: float = BIN_WIDTHS) -> int:
    """How many of the members' profile bins make one fitted bin of ``widths`` x W."""
    m = members[0]
    dy = float(np.median(np.subtract(m["y_hi"], m["y_lo"])))
    return max(1, int(round(widths * float(m["width"]) / dy)))


# ---------------------------------------------------------------- paired member statistics

DEEP_FRACTION = 0.5  # the deep part: the lower half of the fitted profile (W/2 above the floor .. the surface)
SAT_MIN_BINS = 2     # fitted bins the deep part must hold


def _merged(m: dict, merge: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A member's bins joined ``merge`` at a time, as ensemble_profile joins them: y_lo, y_hi, p."""
    y_lo, y_hi, p = (np.asarray(m[k], float) for k in ("y_lo", "y_hi", "p"))
    n = (len(y_lo) // merge) * merge
    return (y_lo[:n].reshape(-1, merge).min(axis=1), y_hi[:n].reshape(-1, merge).max(axis=1),
            p[:n].reshape(-1, merge).mean(axis=1))


def deep_top(members: list, fraction: float = DEEP_FRACTION) -> float:
    """[cm] the height below which the profile is its deep part: ``fraction`` of the way down from
    the members' mean surface to W/2 above the floor (``members``: the reference code's records;
    None or failed ones are skipped)."""
    ok = [m for m in members if m and m.get("status", "ok") == "ok"]
    surface = float(np.mean([m["surface"] for m in ok]))
    low = float(ok[0]["floor"]) + float(ok[0]["width"]) / 2
    return surface - fraction * (surface - low)


def saturated_mu(members: list, y_top: float, merge: int) -> tuple[list, int]:
    """Each member's mu_w,eff from its deep side-wall pressure: rho_s phi g W / (2 p_sat), p_sat
    the mean pressure of the fitted bins (``merge`` profile bins each) wholly below ``y_top`` and
    at least W/2 above the floor (Janssen's saturated pressure p_inf = rho_b g W / (2 mu_w,eff)).
    ``members``: records, or None for a member without one (its value None). Returns the values
    and the number of bins averaged."""
    out, bins = [], 0
    for m in members:
        if not m or m.get("status", "ok") != "ok":
            out.append(None)
            continue
        y_lo, y_hi, p = _merged(m, merge)
        keep = (y_hi <= y_top) & (y_lo >= float(m["floor"]) + float(m["width"]) / 2)
        bins = max(bins, int(keep.sum()))
        p_sat = float(p[keep].mean()) if keep.sum() >= SAT_MIN_BINS else float("nan")
        out.append(float(m["rho_s"]) * float(m["phi"]) * float(m["g"]) * float(m["width"]) / (2 * p_sat)
                   if p_sat > 0 else None)
    return out, bins


def jackknife_fits(a: list, b: list, keys=FIT_KEYS, merge: int | None = None) -> dict:
    """Paired delete-one jackknife of the relative difference b/a - 1 of each ensemble-fit
    parameter: member k left out of both codes' ensembles (members k of every code share their
    start), the fits repeated; se^2 = (n - 1)/n sum_k (R_(-k) - mean R)^2, n - 1 degrees of
    freedom. ``a``, ``b``: the two codes' member records, paired by position (None: no record;
    only members with a record in both codes count). Returns {key: (se, n)}; raises RuntimeError
    when a leave-one-out fit fails."""
    pairs = [(x, y) for x, y in zip(a, b) if x and y and x.get("status", "ok") == "ok" and y.get("status", "ok") == "ok"]
    n = len(pairs)
    if n < 3:
        raise RuntimeError(f"the paired jackknife needs 3 members with a record in both codes, has {n}")
    if merge is None:
        merge = merge_for([pairs[0][0]])
    R = {k: [] for k in keys}
    for j in range(n):
        ra = [x for i, (x, _) in enumerate(pairs) if i != j]
        rb = [y for i, (_, y) in enumerate(pairs) if i != j]
        fa, fb = ensemble_fit(ra, merge), ensemble_fit(rb, merge)
        for k in keys:
            R[k].append(fb[k] / fa[k] - 1.0)
    return {k: (float(math.sqrt((n - 1) / n * np.sum((np.array(v) - np.mean(v)) ** 2))), n) for k, v in R.items()}

"""Janssen's law for a 2D slab of width W (validation.md):

    p_w(z) = p_inf (1 - exp(-(z - z0) / lambda)),  lambda = W / (2 K mu_w),
    p_inf = rho_b g W / (2 mu_w),

fitted by least squares to a side-wall pressure profile (force per bin / bin length against
depth z below the top surface), leaving out the lowest ~W/2 near the floor corners. For a fixed
lambda the model is linear in A = p_inf and B = -p_inf exp(z0 / lambda), so the fit is an exact
1D minimisation over lambda (golden section on log lambda, bracketed by a grid).
"""
from __future__ import annotations

import math

import numpy as np


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

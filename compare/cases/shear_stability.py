"""Time-step bounds of paper 2's clusters: the spectral radius of one step of each scheme on a
whole cluster (its discs' x, y and rotation, its bonds, and the contacts to its touching
neighbours, which are held fixed), linearised with every contact sticking. This is the
multi-degree-of-freedom version of the one-contact bounds. The engine computes the same bound
for its own scheme (engine/src/physics/stability.cpp, cluster_dt_bound: printed in the run header,
`stability.dt_clusters` in summary.json, and enforced); this module, written apart in numpy,
gives it for every scheme and checks the engine's (tests/python/test_shear.py). It is not a
safe bound for the whole assembly (neighbours that move can raise the frequencies), but it
shows what bonds across a gap do: their lever arms (R0/2 > r) stiffen the coupled rotation
modes.

    /usr/bin/python3 -m dem.compare.cases.shear_stability SCENE.toml [SCENE.toml ...] [--dem build/dem]
"""
import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
SCHEMES = ("paper_eq18", "paper_eq19", "velocity_verlet")
TOUCH = 0.01  # [cm] neighbours within this gap hold the cluster (the lattice gap is 0.004 cm)


def _pair(resolved, a, b):
    for p in resolved["pairs"]:
        if sorted(p["materials"]) == sorted([a, b]):
            return p
    raise KeyError((a, b))


def cluster_system(resolved, members, bonds):
    """Stiffness K, damping C and inverse mass of one cluster (3 dof per disc)."""
    discs = resolved["discs"]
    mats = resolved["materials"]
    idx = {d: k for k, d in enumerate(members)}
    n = 3 * len(members)
    K = np.zeros((n, n))
    C = np.zeros((n, n))
    minv = np.zeros(n)
    for d, k in idx.items():
        x, y, r, m = discs[d]
        mass = mats[m]["density"] * math.pi * r * r
        minv[3 * k:3 * k + 3] = (1 / mass, 1 / mass, 2 / (mass * r * r))

    def add(i, j, nvec, ai, aj, p):
        t = (-nvec[1], nvec[0])
        bn = np.zeros(n)
        bs = np.zeros(n)
        bn[3 * i:3 * i + 2] = nvec
        bs[3 * i:3 * i + 2] = t
        bs[3 * i + 2] = ai
        if j is not None:
            bn[3 * j:3 * j + 2] = -np.asarray(nvec)
            bs[3 * j:3 * j + 2] = -np.asarray(t)
            bs[3 * j + 2] = aj
        K[:] += p["kn"] * np.outer(bn, bn) + p["ks"] * np.outer(bs, bs)
        C[:] += p["eta_n"] * np.outer(bn, bn) + p["eta_s"] * np.outer(bs, bs)

    bonded = {tuple(sorted(b)) for b in bonds}
    for i, j in bonded:
        xi, yi, ri, mi = discs[i]
        xj, yj, rj, mj = discs[j]
        R = math.hypot(xj - xi, yj - yi)
        stretch = max(1.0, R / (ri + rj))
        add(idx[i], idx[j], ((xj - xi) / R, (yj - yi) / R), ri * stretch, rj * stretch,
            _pair(resolved, mats[mi]["name"], mats[mj]["name"]))
    # touching neighbours outside the bonds: fixed partners
    for d in members:
        xi, yi, ri, mi = discs[d]
        for e, (xj, yj, rj, mj) in enumerate(discs):
            if e == d or tuple(sorted((d, e))) in bonded or (e in idx and e < d):
                continue  # a contact inside the cluster is met from both discs: counted once
            R = math.hypot(xj - xi, yj - yi)
            if R - ri - rj <= TOUCH:
                add(idx[d], idx.get(e) if e in idx else None, ((xj - xi) / R, (yj - yi) / R), ri, rj,
                    _pair(resolved, mats[mi]["name"], mats[mj]["name"]))
        for w in resolved["walls"]:
            (ax, ay), (bx, by) = w["from"], w["to"]
            ex, ey = bx - ax, by - ay
            u = ((xi - ax) * ex + (yi - ay) * ey) / (ex * ex + ey * ey)
            if not 0 <= u <= 1:
                continue
            px, py = ax + u * ex, ay + u * ey
            dist = math.hypot(px - xi, py - yi)
            if dist - ri <= TOUCH and dist > 0:
                add(idx[d], None, ((px - xi) / dist, (py - yi) / dist), ri, 0,
                    _pair(resolved, mats[mi]["name"], w["material"]))
    return K, C, minv


def spectral_radius(K, C, minv, dt, scheme):
    n = K.shape[0]
    A = np.zeros((3 * n, 3 * n))
    for col in range(3 * n):
        s = np.zeros(3 * n)
        s[col] = 1
        x, v, du = s[:n].copy(), s[n:2 * n].copy(), s[2 * n:].copy()

        def acc(x, du):
            return minv * (-K @ x - C @ du / dt)
        if scheme == "velocity_verlet":
            v = v + 0.5 * dt * acc(x, du)
            du = v * dt
            x = x + du
            v = v + 0.5 * dt * acc(x, du)
        else:
            v = v + dt * acc(x, du)
            du = v * dt if scheme == "paper_eq18" else 0.5 * (du + v * dt)
            x = x + du
        A[:, col] = np.concatenate([x, v, du])
    return float(np.max(np.abs(np.linalg.eigvals(A))))


def dt_bound(K, C, minv, scheme, tol=1e-9):
    lo = hi = 1e-6
    while spectral_radius(K, C, minv, hi, scheme) <= 1 + tol:
        lo, hi = hi, hi * 1.2
        if hi > 1:
            return math.inf
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if spectral_radius(K, C, minv, mid, scheme) <= 1 + tol:
            lo = mid
        else:
            hi = mid
    return lo


def engine_bonds(discs, clusters) -> list[list[int]]:
    """The engine's bond list (engine/src/clusters.cpp): every pair of a cluster, or the pairs
    whose gap is at most touch_tolerance (``bonds = "touching"``), sorted."""
    out = []
    for members in clusters["members"]:
        for a in range(len(members)):
            for b in range(a + 1, len(members)):
                i, j = sorted((members[a], members[b]))
                (xi, yi, ri), (xj, yj, rj) = discs[i][:3], discs[j][:3]
                gap = math.hypot(xj - xi, yj - yi) - ri - rj
                if clusters["bonds"] == "touching" and gap > clusters["touch_tolerance"]:
                    continue
                out.append([i, j])
    return sorted(out)


def bonds_of(resolved):
    return engine_bonds(resolved["discs"], resolved["clusters"])


def scene_bounds(resolved):
    """{scheme: smallest bound over the distinct cluster shapes} (or over single discs when the
    scene has no clusters), plus the number of shapes examined."""
    if "clusters" in resolved:
        groups = resolved["clusters"]["members"]
        bonds = bonds_of(resolved)
    else:
        groups = [[k] for k in range(len(resolved["discs"]))]
        bonds = []
    seen = {}
    for members in groups:
        K, C, minv = cluster_system(resolved, members, [b for b in bonds if b[0] in members and b[1] in members])
        key = (np.round(K / max(1.0, np.abs(K).max()), 9).tobytes(), minv.tobytes())
        if key not in seen:
            seen[key] = (K, C, minv)
    out = {s: min(dt_bound(K, C, m, s) for K, C, m in seen.values()) for s in SCHEMES}
    out["shapes"] = len(seen)
    return out


def resolve(scene, dem):
    proc = subprocess.run([str(dem), "resolve", str(scene)], capture_output=True, text=True, check=True)
    return json.loads(proc.stdout)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="dem.compare.cases.shear_stability", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--dem", default=os.environ.get("DEM_BINARY", str(REPO / "build" / "dem")))
    a = ap.parse_args(argv)
    for s in a.scenes:
        b = scene_bounds(resolve(s, a.dem))
        print(f"{s}: " + ", ".join(f"{k} {b[k]:.3e} s" for k in SCHEMES) + f" ({b['shapes']} distinct shapes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Paper 2's simple shear test in YADE 2023.02a from a scene file: the YADE backend's shear path
(compare/codes/yade_backend.py, ``shear_case_data`` and compare/codes/shear_yade_template.py), the same
translation ``dem compare`` runs for a shear-box scene.

    /usr/bin/python3 -m dem.compare.codes.shear_yade SCENE.toml --out DIR [--clusters bonds|clumps]
                     [--dt S] [--dem build/dem] [--timeout S]

The scene is resolved by the engine itself (``dem resolve``: discs, constants, box, clusters) and
becomes one shear case: the scene's own start, YADE's law (the shared contact variant:
compare/cases/common.py SHARED_VARIANT; the paper's incremental spring and elastic-force rules are not
expressible in YADE), leapfrog at ``--dt`` (default 5e-5 s: at the paper's 1e-4 s YADE's
near-critical dashpots are unstable, reference-codes.md), the compression to rest for at most the
scene's ``end.time``. The backend writes DIR/shear_series.csv, shear_planes.csv, summary.json and
snapshots/ in the engine's formats (docs/outputs.md, "Shear outputs"), at full precision.

Clusters (``--clusters``): ``bonds`` (default) every bonded pair of the scene (the engine's own
bond list) an elastic, unbreakable CohFrictPhys bond without dashpots; ``clumps`` rigid YADE
clumps. A scene without clusters runs free discs.
"""
import argparse
import copy
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from dem.compare.io.run_dir import RunDir
from dem.compare.cases import shear
from dem.compare.cases.common import SHARED_VARIANT, Case
from dem.compare.cases.plan import start_discs
from dem.compare.codes import yade_backend

REPO = Path(__file__).resolve().parents[2]


def resolve(scene, dem):
    proc = subprocess.run([str(dem), "resolve", str(scene)], capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"shear_yade: dem resolve {scene}: {proc.stderr.strip()}")
    return json.loads(proc.stdout)


def make_case(resolved, clusters="bonds", dt=5e-5):
    """The scene's own start as the YADE backend's shear case (the shared contact variant)."""
    if not shear.is_shear(resolved):
        raise SystemExit("shear_yade: the scene has no [shear_box] and [shear]")
    if clusters == "clumps" and "clusters" not in resolved:
        raise SystemExit("shear_yade: --clusters clumps needs a scene with [clusters]")
    r = copy.deepcopy(resolved)
    r["contact"] = dict(SHARED_VARIANT)
    return Case(name=r["name"], resolved=r, discs=start_discs(r), dt=dt, duration=shear.shear_time(r),
                mode="shear", settle=float(r["end"]["time"]), clusters=clusters,
                materials=np.asarray(r["discs"], float)[:, 3].astype(int))


def run(scene, out_dir, clusters="bonds", dt=5e-5, dem=None, timeout=1800):
    """Runs YADE on the scene through the backend; returns summary.json's dict (raises SystemExit
    on failure)."""
    dem = dem or os.environ.get("DEM_BINARY", REPO / "build" / "dem")
    out = Path(out_dir).resolve()
    case = make_case(resolve(scene, dem), clusters, dt)
    res = yade_backend.run(case, out, timeout=timeout)
    if not res.ok:
        raise SystemExit(f"shear_yade: yade failed on {scene}: {res.reason}")
    return RunDir(out).summary


def main(argv=None):
    ap = argparse.ArgumentParser(prog="dem.compare.codes.shear_yade", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--out", required=True)
    ap.add_argument("--clusters", choices=("bonds", "clumps"), default="bonds")
    ap.add_argument("--dt", type=float, default=5e-5)
    ap.add_argument("--dem", default=None, help="the engine (default $DEM_BINARY or build/dem)")
    ap.add_argument("--timeout", type=float, default=1800)
    a = ap.parse_args(argv)
    s = run(a.scene, a.out, a.clusters, a.dt, a.dem, a.timeout)
    sh = s["shear"]
    print(f"{a.scene}: yade {s['clusters']}: peak tau/sigma {sh['peak_ratio']:.4f} at strain {sh['strain_at_peak']:.4f}; "
          f"rest {'reached' if s['rest']['reached'] else 'NOT reached'}; {s['wall_time_s']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

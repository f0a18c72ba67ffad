"""Paper 2's simple shear test in YADE 2023.02a, from the same scene files as the engine.

    /usr/bin/python3 -m compare.shear_yade SCENE.toml --out DIR [--clusters scene|none|bonds|clumps]
                     [--dt S] [--dem build/dem] [--timeout S]

The scene is resolved by the engine itself (``dem resolve``: discs, constants, box, clusters), so
both codes run the same discs, clusters, plate and constants. The YADE script is
compare/shear_yade_template.py; it writes DIR/shear_series.csv, shear_planes.csv, summary.json
and snapshots/ in the engine's formats (docs/outputs.md, "Shear outputs"), at full precision.

Clusters in YADE (``--clusters``; ``scene`` = ``bonds`` when the scene has clusters, else ``none``):

- ``bonds``: each bonded pair of the scene (the engine's own bond list: all pairs of a cluster or
  the touching ones) is a YADE interaction made at the start with a CohFrictPhys of the
  disc-disc kn, ks and normal/shear adhesion 1e30: elastic, in tension, no Coulomb cap, never
  broken, as paper 2's clusters; but WITHOUT the dashpots paper 2 keeps inside clusters (YADE's
  cohesive law has none), with the normal spring on the distance change since bonding (the
  engine: incremental), and YADE rotates the stored shear force with the contact frame;
- ``clumps``: YADE clumps, RIGID clusters (paper 2's are elastic, with the paper's stiffness);
- ``none``: free discs.

Everything else is the translation of compare/yade_backend.py (reference-codes.md): ViscElMat with
the disc material = 2 x the disc-disc pair (series combination) and a wall material of zeros
(the disc-wall contact then takes 2 x disc-disc: the paper's walls); the law's total-force
no-tension clamp and Coulomb cap on the total normal force (the paper: on the elastic force); the
overlap spring (the paper: incremental); leapfrog integration at a dt of its own (the paper's
1e-4 s is unstable in YADE with these dashpots; default 5e-5 s). Walls and plate are boxes; the
side walls are turned about their lower inner corners by RotationEngines.
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
TEMPLATE = Path(__file__).resolve().parent / "shear_yade_template.py"


def resolve(scene, dem):
    proc = subprocess.run([str(dem), "resolve", str(scene)], capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"shear_yade: dem resolve {scene}: {proc.stderr.strip()}")
    return json.loads(proc.stdout)


def bonds_of(discs, clusters):
    """The engine's bond list (engine/src/physics/clusters.cpp): every pair of a cluster, or the pairs
    whose gap is at most touch_tolerance."""
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


def pair_of(resolved, a, b):
    for p in resolved["pairs"]:
        if sorted(p["materials"]) == sorted([a, b]):
            return {k: p[k] for k in ("kn", "ks", "eta_n", "eta_s", "mu")}
    raise SystemExit(f"shear_yade: no pair {a}-{b} in the scene")


def make_case(resolved, out_dir, clusters="scene", dt=5e-5):
    if "shear_box" not in resolved or "shear" not in resolved:
        raise SystemExit("shear_yade: the scene has no [shear_box] and [shear]")
    mats = resolved["materials"]
    disc_mats = {d[3] for d in resolved["discs"]}
    if len(disc_mats) != 1:
        raise SystemExit("shear_yade: one disc material only")
    dm = mats[disc_mats.pop()]
    box = resolved["shear_box"]
    walls = {w["name"]: w for w in resolved["walls"]}
    plate = walls["plate"]
    mode = clusters
    if mode == "scene":
        mode = "bonds" if "clusters" in resolved else "none"
    if mode in ("bonds", "clumps") and "clusters" not in resolved:
        raise SystemExit(f"shear_yade: --clusters {mode} needs a scene with [clusters]")
    cl = {"mode": mode}
    if mode == "bonds":
        cl["bonds"] = bonds_of(resolved["discs"], resolved["clusters"])
        cl["bond_set"] = resolved["clusters"]["bonds"]
    if mode == "clumps":
        cl["members"] = resolved["clusters"]["members"]
    return {
        "scene": resolved["name"],
        "out_dir": str(Path(out_dir).resolve()),
        "dt": dt,
        "gravity": resolved["gravity"],
        "density": dm["density"],
        "discs": [[d[0], d[1], d[2]] for d in resolved["discs"]],
        "pair_dd": pair_of(resolved, dm["name"], dm["name"]),
        "pair_dw": pair_of(resolved, dm["name"], box["plate_material"]),
        "box": {"width": box["width"], "wall_length": box["wall_length"], "plate_y": box["plate_y"],
                "plate_mass": box["plate_mass"], "plate_overhang": 0.5 * (plate["to"][0] - plate["from"][0]) - 0.5 * box["width"]},
        "shear": resolved["shear"],
        "compress": {"max_time": resolved["end"]["time"], "rest_factor": resolved["end"]["rest_factor"]},
        "clusters": cl,
    }


def run(scene, out_dir, clusters="scene", dt=5e-5, dem=None, timeout=1800):
    """Runs YADE on the scene; returns summary.json's dict (raises SystemExit on failure)."""
    dem = dem or os.environ.get("DEM_BINARY", REPO / "build" / "dem")
    out = Path(out_dir).resolve()  # yade runs in it: every path absolute
    out.mkdir(parents=True, exist_ok=True)
    case = make_case(resolve(scene, dem), out, clusters, dt)
    if case["shear"].get("rate", 0) <= 0:
        raise SystemExit("shear_yade: shear.rate must be > 0")
    (out / "yade_case.json").write_text(json.dumps(case, indent=1))
    shutil.copy(TEMPLATE, out / "shear_yade_script.py")
    t0 = time.time()
    with open(out / "yade.log", "w") as log:
        proc = subprocess.run(["yade", "-n", "-j1", "-x", str(out / "shear_yade_script.py"), str(out / "yade_case.json")],
                              stdout=log, stderr=subprocess.STDOUT, timeout=timeout, cwd=out)
    (out / "yade_process.json").write_text(json.dumps({"exit": proc.returncode, "wall_s": time.time() - t0}))
    if proc.returncode != 0 or not (out / "summary.json").is_file():
        tail = (out / "yade.log").read_text()[-2000:]
        raise SystemExit(f"shear_yade: yade failed (exit {proc.returncode}) on {scene}:\n{tail}")
    return json.loads((out / "summary.json").read_text())


def main(argv=None):
    ap = argparse.ArgumentParser(prog="compare.shear_yade", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--out", required=True)
    ap.add_argument("--clusters", choices=("scene", "none", "bonds", "clumps"), default="scene")
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

#!/usr/bin/python3
"""Stability limit of velocity_verlet_onset beside velocity Verlet on the paper's silos.

    /usr/bin/python3 benchmarks/onset_stability.py --out out/onset_stability [--silos 18,19] [--quick]

The onset scheme needs the overlap spring, so both schemes run the paper's law on it
(contact.normal_spring = "overlap", the paper's constants otherwise). The criterion and the search
are stability_study.py's (fill from the lattice for T with stop_at_rest off and --force-dt; the
largest dt at rest and the first dt the engine stops as unstable, scan then bisection).
Outputs DIR/results.json and DIR/report.md.
"""
from __future__ import annotations

import argparse
import concurrent.futures as cf
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common_study as cs  # noqa: E402
import stability_study as st  # noqa: E402

SCHEMES = ("velocity_verlet", "velocity_verlet_onset")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/onset_stability")
    ap.add_argument("--dem", default=None)
    ap.add_argument("--silos", default="18,19", help="s of the (s-1)/s silos")
    ap.add_argument("--quick", action="store_true", help="T = 1 s, coarse bisection (stability_study's quick)")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args(argv)
    out = Path(args.out)
    (out / "scenes").mkdir(parents=True, exist_ok=True)
    dem = cs.setup_binary(args.dem)
    cfg = st.PROFILES["quick" if args.quick else "full"]
    t0 = time.monotonic()
    cases = []
    for s in (int(x) for x in args.silos.split(",")):
        name = f"silo_{s - 1}_{s}"
        scene = cs.scene_with(cs.SCENES / f"{name}.toml", out / "scenes" / f"{name}_overlap.toml",
                              {"end.time": cfg["T"], "end.stop_at_rest": False, "contact.normal_spring": "overlap"})
        cases.append({"name": f"{name}_overlap", "group": "paper silo", "scene": scene,
                      "what": f"({s - 1})/{s} silo, the paper's law on the overlap spring"})
    tasks = [(c, s) for c in cases for s in SCHEMES]
    with cf.ThreadPoolExecutor(max_workers=args.jobs) as ex:
        results = list(ex.map(lambda t: st.search(t[0], t[1], cfg, out), tasks))
    res = {"engine": cs.engine_version(), "dem": str(dem), "config": cfg,
           "command": " ".join(["/usr/bin/python3", "benchmarks/onset_stability.py"] + (argv if argv is not None else sys.argv[1:])),
           "results": results, "elapsed_s": time.monotonic() - t0}
    cs.write_json(out / "results.json", res)
    rows = [[r["case"], r["scheme"], cs.g(r["bounds"].get("enforced")), cs.g(r["max_rest"]), cs.g(r.get("first_not_rest")),
             cs.g(r.get("max_no_blowup")), cs.g(r.get("first_blowup")), len(r["runs"])] for r in results]
    text = ["# Stability limit: velocity_verlet_onset beside velocity Verlet", "",
            f"Command: `{res['command']}`; {res['elapsed_s']:.0f} s; T = {cfg['T']} s, scan x{cfg['scan']}, "
            f"bisection to {cfg['tol']:.0%}.", "",
            cs.md_table(["silo", "scheme", "engine's bound [s]", "largest dt at rest [s]", "first dt not at rest [s]",
                         "largest dt without blow-up [s]", "first blow-up [s]", "runs"], rows), ""]
    cs.write_text(out / "report.md", "\n".join(text) + "\n")
    print("\n".join(text))
    return 0


if __name__ == "__main__":
    sys.exit(main())

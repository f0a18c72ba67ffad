"""python3 -m compare report --out DIR [--full] [--codes native,liggghts,yade]
python3 -m compare translate [--check]

Runs the agreement study (compare/study.py) and writes DIR/report.md, DIR/agreement.json and
the PNG plots. Exit 0 when every metric is within tolerance, 1 when any fails (a failed
reference run counts as a failure), 2 for bad arguments.
"""
import argparse
import sys
from pathlib import Path

from . import report, study


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python3 -m compare")
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("report", help="run the agreement study and write the report")
    r.add_argument("--out", required=True, type=Path)
    r.add_argument("--full", action="store_true", help="the whole study (all lattices, 8-member ensembles, MPI)")
    r.add_argument("--codes", default=",".join(study.CODES), help="comma-separated subset of native,liggghts,yade")
    r.add_argument("--timeout", type=float, default=900, help="seconds per reference run (default 900)")
    t = sub.add_parser("translate", help="write reference_inputs/liggghts/ and reference_inputs/yade/ for the paper's scenes")
    t.add_argument("--check", action="store_true", help="exit 1 when the committed inputs differ from the generator's")
    a = ap.parse_args(argv)
    if a.cmd == "translate":
        from . import translate
        return translate.main(a.check)
    codes = [c.strip() for c in a.codes.split(",") if c.strip()]
    bad = [c for c in codes if c not in study.CODES]
    if bad or "native" not in codes:
        print(f"--codes: unknown {bad}" if bad else "--codes: native is the reference and must be included",
              file=sys.stderr)
        return 2
    rep = study.run_study(a.out, "full" if a.full else "quick", codes, a.timeout,
                          log=lambda m: print(m, flush=True))
    report.write(rep, a.out)
    n_fail = sum(not m["pass"] for m in rep["metrics"])
    print(f"{a.out / 'report.md'}: {'PASS' if rep['passed'] else 'FAIL'} "
          f"({len(rep['metrics']) - n_fail} of {len(rep['metrics'])} metrics within tolerance)")
    return 0 if rep["passed"] else 1


if __name__ == "__main__":
    sys.exit(main())

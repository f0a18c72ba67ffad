#!/usr/bin/env python3
"""The README's figures of the paper's silo, read from the main job's output.

    /usr/bin/python3 scripts/readme_figures.py OUT              # print the README's block
    /usr/bin/python3 scripts/readme_figures.py OUT --check README.md

OUT is the main job's folder (`bash scripts/paper_silo.sh` writes out/paper_silo): its
study.json (the static study) and discharge/discharge.json (the discharge ensembles). The block
stands in README.md between the two marker lines below; `--check` exits 1 when the README's
block differs from what OUT gives, naming the first line that differs. Only the paper's scheme
(eq. 19 at dt = 1e-4 s) and the two schemes that blow up there are quoted, so a study run on
those cases alone gives the same block (tests/python/test_readme_figures.py does that).
"""
import argparse
import json
import sys
from pathlib import Path

BEGIN = "<!-- figures of the main job: scripts/readme_figures.py out/paper_silo -->"
END = "<!-- end of the main job's figures -->"
PAPER = ("paper_eq19", 1e-4)


def _static(records: list) -> list[str]:
    paper = sorted((r for r in records if (r["scheme"], r["dt"]) == PAPER), key=lambda r: r["s"])
    at_rest = [r for r in paper if r["rest"]]
    others = {}
    for r in records:
        if r["dt"] == PAPER[1] and r["scheme"] != PAPER[0]:
            others.setdefault(r["scheme"], []).append(r["exit"] == 3)
    blown = ", ".join(f"{s} {sum(v)} of {len(v)}" for s, v in sorted(others.items()))
    first, last = paper[0], paper[-1]
    side = [r["side_mean"] for r in paper]
    trend = "at every step of s" if all(a > b for a, b in zip(side, side[1:])) else "not at every step of s"
    return [
        f"- At the paper's dt = 1e-4 s, eq. (19) brings {len(at_rest)} of {len(paper)} arrangements to rest; "
        f"the other schemes blow up there ({blown}).",
        f"- Side-wall normal force at rest (eq. 19): {first['side_mean']:.1f} disc weights in {first['arrangement']} "
        f"to {last['side_mean']:.1f} in {last['arrangement']}, falling {trend}: "
        + ", ".join(f"{r['side_mean']:.1f}" for r in paper) + ".",
    ]


def _mean(e: dict, key: str) -> str:
    v = e[key]
    return f"{v['mean']:.3g}" if v.get("n") else "-"


def _discharge(records: list) -> list[str]:
    by = {r["tag"]: r["ensemble"] for r in records if "ensemble" in r}
    lines = []
    for tag, arr in (("17_18_eq19_1e-4", "17/18"), ("11_12_eq19_1e-4", "11/12")):
        e = by[tag]
        p, fr = e["pattern"], e["flow_rate_discs"]
        lines.append(
            f"- {arr} discharge (eq. 19, {e['members']} members): funnel {p['funnel']}, piping {p['piping']}; "
            f"flow {fr['mean']:.1f} +- {fr['stderr']:.1f} discs/s; peak/static bottom {_mean(e, 'peak_ratio_bottom')} "
            f"(5 ms) / {_mean(e, 'peak_ratio_bottom_windowed')} (50 ms), side {_mean(e, 'peak_ratio_side')} / "
            f"{_mean(e, 'peak_ratio_side_windowed')}.")
    return lines


def block(out: Path) -> list[str]:
    static = json.loads((out / "study.json").read_text())
    discharge = json.loads((out / "discharge" / "discharge.json").read_text())
    return [BEGIN, *_static(static), *_discharge(discharge), END]


def readme_block(readme: Path) -> list[str]:
    lines = readme.read_text().splitlines()
    if BEGIN not in lines or END not in lines:
        raise SystemExit(f"{readme}: no block between '{BEGIN}' and '{END}'")
    return lines[lines.index(BEGIN):lines.index(END) + 1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", type=Path, help="the main job's folder (out/paper_silo)")
    ap.add_argument("--check", type=Path, metavar="README", help="compare with this README's block")
    a = ap.parse_args(argv)
    want = block(a.out)
    if not a.check:
        print("\n".join(want))
        return 0
    have = readme_block(a.check)
    for i, (w, h) in enumerate(zip(want, have)):
        if w != h:
            print(f"{a.check}: the main job's figures differ at line {i + 1} of the block:\n  README: {h}\n  "
                  f"job:    {w}", file=sys.stderr)
            return 1
    if len(want) != len(have):
        print(f"{a.check}: the block has {len(have)} lines, the job gives {len(want)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

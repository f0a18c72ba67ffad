#!/usr/bin/python3
"""The shape of the engine's source (engine/src, or another tree): include floors, unit circles
and the longest functions -- the measures docs/architecture.md quotes.

    /usr/bin/python3 scripts/engine_shape.py [SRC_DIR] [--top N]

- floors: the longest chain of #include "..." from any file (a file including nothing of the
  engine is floor 1);
- circles: units (NAME.hpp + NAME.cpp) that reach themselves through the includes of either
  file (scene.cpp including shear_scene.hpp whose header includes scene.hpp is one);
- longest functions: lines from a definition's opening brace at column 0 to its closing brace at
  column 0 (the project's formatting), top N.
"""
import argparse
import re
from pathlib import Path

INCLUDE = re.compile(r'^#include "([^"]+)"', re.M)


def files(src: Path):
    return sorted(p for p in src.rglob("*") if p.suffix in (".hpp", ".cpp"))


def resolve(src: Path, here: Path, name: str):
    for cand in (src / name, here.parent / name):
        if cand.exists():
            return cand.resolve()
    return None


def graph(src: Path):
    g = {}
    for f in files(src):
        g[f.resolve()] = [t for t in (resolve(src, f, n) for n in INCLUDE.findall(f.read_text())) if t]
    return g


def floors(g):
    memo = {}

    def depth(f, stack=()):
        if f in memo:
            return memo[f]
        if f in stack:
            return 0
        d = 1 + max((depth(t, stack + (f,)) for t in g.get(f, [])), default=0)
        memo[f] = d
        return d

    return max(depth(f) for f in g), memo


def circles(g):
    unit = lambda p: p.with_suffix("")
    ug = {}
    for f, ts in g.items():
        ug.setdefault(unit(f), set()).update(unit(t) for t in ts if unit(t) != unit(f))
    found = set()
    for start in ug:
        stack, seen = [(start, (start,))], set()
        while stack:
            u, path = stack.pop()
            for v in ug.get(u, ()):
                if v == start:
                    found.add(tuple(sorted(p.name for p in path)))
                elif v not in seen:
                    seen.add(v)
                    stack.append((v, path + (v,)))
    return sorted(found)


def functions(src: Path):
    out = []
    for f in files(src):
        lines = f.read_text().splitlines()
        start = None
        for k, line in enumerate(lines):
            if start is None and line.endswith("{") and re.match(r"^[A-Za-z].*\)\s*(const\s*)?(override\s*)?\{$", line):
                start = k
            elif start is not None and line == "}":
                out.append((k - start + 1, f"{f.relative_to(src)}:{start + 1}", lines[start][:90]))
                start = None
    return sorted(out, reverse=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("src", nargs="?", default=str(Path(__file__).resolve().parents[1] / "engine" / "src"))
    ap.add_argument("--top", type=int, default=5)
    a = ap.parse_args()
    src = Path(a.src).resolve()
    g = graph(src)
    n, _ = floors(g)
    print(f"files: {len(g)}, include floors: {n}")
    cs = circles(g)
    print(f"unit circles: {len(cs)}" + "".join(f"\n  {' <-> '.join(c)}" for c in cs[:10]))
    print("longest functions:")
    for length, where, head in functions(src)[:a.top]:
        print(f"  {length:4d} lines  {where}  {head}")


if __name__ == "__main__":
    main()

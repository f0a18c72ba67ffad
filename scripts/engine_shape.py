#!/usr/bin/python3
"""The shape of the engine's source (engine/src, or another tree): include floors, unit circles
and the longest functions -- the measures docs/architecture.md quotes; with --compare, the same
measures of the Python comparison layer (compare/, or another package) from its imports.

    /usr/bin/python3 scripts/engine_shape.py [SRC_DIR] [--top N]
    /usr/bin/python3 scripts/engine_shape.py --compare [PACKAGE_DIR] [--top N]
    /usr/bin/python3 scripts/engine_shape.py --markdown            # docs/architecture.md's figures
    /usr/bin/python3 scripts/engine_shape.py --check docs/architecture.md

- floors: the longest chain of #include "..." from any file (a file including nothing of the
  engine is floor 1);
- circles: units (NAME.hpp + NAME.cpp) that reach themselves through the includes of either
  file (scene.cpp including shear_scene.hpp whose header includes scene.hpp is one);
- longest functions: lines from a definition's opening brace at column 0 to its closing brace at
  column 0 (the project's formatting), top N.

--compare (a Python package, its imports read with ast; absolute ``dem.compare.x`` and relative ones):
- folder floors: the longest chain of imports between the package's folders (the package's own
  top folder is one; a folder importing no other folder is floor 1);
- circles: modules that reach themselves through their imports (each strongly connected set of
  modules once), and the same between folders;
- in-function imports: import statements inside a function's body (those of the package and the
  others alike), by module;
- functions over 100 lines (def to its last line), and the longest N.
"""
import argparse
import ast
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
            elif start is not None and line in ("}", "};"):  # a function, or a lambda at namespace scope
                out.append((k - start + 1, f"{f.relative_to(src)}:{start + 1}", lines[start][:90]))
                start = None
    return sorted(out, reverse=True)


# --------------------------------------------------------------------------- the Python package


def py_modules(pkg: Path):
    """{dotted name: path} of every module of the package (pkg's name first; __init__ is the
    package itself). Files that are not importable Python (YADE's scripts) still parse."""
    out = {}
    for f in sorted(pkg.rglob("*.py")):
        parts = [pkg.name, *f.relative_to(pkg).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = f
    return out


def _target(mods, name):
    """The module that an imported dotted name is, or lies in (longest known prefix)."""
    while name and name not in mods:
        name = name.rpartition(".")[0]
    return name or None


def _is_package(mods, name):
    return mods[name].name == "__init__.py"


def py_imports(mods, name, tree):
    """[(imported module of the package, line, inside a function)] of one module."""
    out = []
    base = name if _is_package(mods, name) else name.rpartition(".")[0]

    def visit(node, in_function):
        for child in ast.iter_child_nodes(node):
            inner = in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
            if isinstance(child, ast.Import):
                for alias in child.names:
                    out.append((alias.name.removeprefix("dem."), child.lineno, in_function))
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    head = base.rsplit(".", child.level - 1)[0] if child.level > 1 else base
                    mod = f"{head}.{child.module}" if child.module else head
                else:
                    mod = (child.module or "").removeprefix("dem.")     # compare/ is imported as dem.compare
                for alias in child.names:
                    full = f"{mod}.{alias.name}"
                    out.append((full if full in mods else mod, child.lineno, in_function))
            visit(child, inner)

    visit(tree, False)
    return out


def py_graph(pkg: Path):
    mods = py_modules(pkg)
    g, in_function, long_functions = {}, [], []
    for name, f in mods.items():
        tree = ast.parse(f.read_text(), str(f))
        g[name] = set()
        for imported, line, inside in py_imports(mods, name, tree):
            if inside:
                in_function.append((f"{f.relative_to(pkg.parent)}:{line}", imported))
            target = _target(mods, imported) if imported.split(".")[0] == pkg.name else None
            if target and target != name:
                g[name].add(target)
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                long_functions.append((node.end_lineno - node.lineno + 1,
                                       f"{f.relative_to(pkg.parent)}:{node.lineno}", node.name))
    return mods, g, in_function, sorted(long_functions, reverse=True)


def strongly_connected(g):
    """Tarjan's sets of nodes that reach each other, those of more than one node, sorted."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def connect(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(g.get(v, ())):
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                out.append(sorted(group))

    for v in sorted(g):
        if v not in index:
            connect(v)
    return sorted(out)


def folder_of(mods, name):
    """The folder a module lies in, as a dotted package name."""
    return name if _is_package(mods, name) else name.rpartition(".")[0]


def folder_graph(mods, g):
    fg = {}
    for name, targets in g.items():
        a = folder_of(mods, name)
        fg.setdefault(a, set()).update(b for b in (folder_of(mods, t) for t in targets) if b != a)
    return fg


def folder_floors(fg):
    """{folder: floor}: 1 + the highest floor it imports (a folder in a circle counts its circle once)."""
    memo = {}

    def floor(v, stack=()):
        if v in memo:
            return memo[v]
        if v in stack:
            return 0
        memo[v] = 1 + max((floor(w, stack + (v,)) for w in fg.get(v, ())), default=0)
        return memo[v]

    return {v: floor(v) for v in fg}


def python_shape(pkg: Path, top: int):
    mods, g, in_function, long_functions = py_graph(pkg)
    fg = folder_graph(mods, g)
    floors_ = folder_floors(fg)
    print(f"python modules: {sum(1 for f in mods.values() if f.name != '__init__.py')} "
          f"in {len(fg)} folders, folder floors: {max(floors_.values())}")
    for v in sorted(floors_, key=lambda v: (floors_[v], v)):
        print(f"  {floors_[v]}  {v}")
    cs = strongly_connected(g)
    print(f"module circles: {len(cs)}" + "".join(f"\n  {' <-> '.join(c)}" for c in cs))
    fcs = strongly_connected(fg)
    print(f"folder circles: {len(fcs)}" + "".join(f"\n  {' <-> '.join(c)}" for c in fcs))
    print(f"in-function imports: {len(in_function)}" + "".join(f"\n  {w}  {m}" for w, m in in_function))
    over = [x for x in long_functions if x[0] > 100]
    print(f"functions over 100 lines: {len(over)}; longest functions:")
    for length, where, fname in long_functions[:max(top, len(over))]:
        print(f"  {length:4d} lines  {where}  {fname}")


BEGIN = "<!-- measured by /usr/bin/python3 scripts/engine_shape.py --markdown (checked by the tests) -->"
END = "<!-- end of the measured shape -->"


def markdown(root: Path) -> list[str]:
    """docs/architecture.md's block of figures, both layers, as measured now."""
    src = root / "engine" / "src"
    g = graph(src)
    n, _ = floors(g)
    fns = functions(src)
    over = [f for f in fns if f[0] > 100]
    def name(head):  # a function's name, or a lambda's (`auto f = [](...) {`)
        return (head.split("=")[0] if "= [" in head else head.split("(")[0]).split()[-1]
    longest = ", ".join(f"`{name(head)}` {length} ({where.split(':')[0]})" for length, where, head in fns[:3])
    mods, pg, in_function, long_py = py_graph(root / "compare")
    fg = folder_graph(mods, pg)
    modules = sum(1 for f in mods.values() if f.name != "__init__.py")
    over_py = [x for x in long_py if x[0] > 100]
    longest_py = ", ".join(f"`{name}` {length} ({where.split(':')[0]})" for length, where, name in long_py[:3])
    return [BEGIN,
            f"- engine/src: {len(g)} files, {n} include floors, {len(circles(g))} unit circles; "
            f"{len(over)} functions over 100 lines; the longest {longest}.",
            f"- compare/: {modules} modules in {len(fg)} folders, {max(folder_floors(fg).values())} folder floors, "
            f"{len(strongly_connected(pg))} circles between modules and {len(strongly_connected(fg))} between "
            f"folders, {len(in_function)} imports inside functions; {len(over_py)} functions over 100 lines; "
            f"the longest {longest_py}.",
            END]


def check(doc: Path, root: Path) -> int:
    lines = doc.read_text().splitlines()
    if BEGIN not in lines or END not in lines:
        print(f"{doc}: no block between '{BEGIN}' and '{END}'")
        return 1
    have, want = lines[lines.index(BEGIN):lines.index(END) + 1], markdown(root)
    if have != want:
        print(f"{doc}: its measured figures are stale; now:\n" + "\n".join(want))
        return 1
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("src", nargs="?", default=None)
    ap.add_argument("--top", type=int, default=5)
    ap.add_argument("--compare", action="store_true", help="measure a Python package (default compare/)")
    ap.add_argument("--markdown", action="store_true", help="the figures docs/architecture.md quotes")
    ap.add_argument("--check", type=Path, metavar="DOC", help="exit 1 when DOC's figures differ from the measure")
    a = ap.parse_args()
    root = Path(__file__).resolve().parents[1]
    if a.markdown:
        print("\n".join(markdown(root)))
        return 0
    if a.check:
        return check(a.check, root)
    if a.compare:
        python_shape(Path(a.src or root / "compare").resolve(), a.top)
        return
    src = Path(a.src or root / "engine" / "src").resolve()
    g = graph(src)
    n, _ = floors(g)
    print(f"files: {len(g)}, include floors: {n}")
    cs = circles(g)
    print(f"unit circles: {len(cs)}" + "".join(f"\n  {' <-> '.join(c)}" for c in cs[:10]))
    print("longest functions:")
    for length, where, head in functions(src)[:a.top]:
        print(f"  {length:4d} lines  {where}  {head}")


if __name__ == "__main__":
    raise SystemExit(main())

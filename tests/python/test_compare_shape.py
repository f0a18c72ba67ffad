"""The shape of compare/ as docs/architecture.md states it, measured from its imports by
scripts/engine_shape.py --compare: at most 6 folder floors, no circle between modules or
folders, imports at a module's top but the deferred ones named there, no function over 100 lines."""
import importlib.util
import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("engine_shape", REPO / "scripts" / "engine_shape.py")
shape = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(shape)

DEFERRED = {("compare/papers/paper_static.py", "compare.figures.runs"),
            ("compare/papers/paper_discharge.py", "compare.figures.runs"),
            ("compare/codes/yade_template.py", "yade.config")}


def test_compare_keeps_its_shape():
    mods, g, in_function, long_functions = shape.py_graph(REPO / "compare")
    fg = shape.folder_graph(mods, g)
    assert max(shape.folder_floors(fg).values()) <= 6
    assert shape.strongly_connected(g) == []
    assert shape.strongly_connected(fg) == []
    assert {(where.rsplit(":", 1)[0], m) for where, m in in_function} <= DEFERRED, in_function
    assert [f for f in long_functions if f[0] > 100] == []


def test_the_measure_sees_a_circle_and_an_import_in_a_function(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "a").mkdir(parents=True)
    (pkg / "b").mkdir()
    for d in (pkg, pkg / "a", pkg / "b"):
        (d / "__init__.py").write_text("")
    (pkg / "a" / "x.py").write_text("from pkg.b import y\n")
    (pkg / "b" / "y.py").write_text("def f():\n    from pkg.a import x\n    return x\n")
    mods, g, in_function, _ = shape.py_graph(pkg)
    assert shape.strongly_connected(g) == [["pkg.a.x", "pkg.b.y"]]
    assert shape.strongly_connected(shape.folder_graph(mods, g)) == [["pkg.a", "pkg.b"]]
    assert [m for _, m in in_function] == ["pkg.a.x"]


def test_architecture_doc_quotes_the_measured_shape_and_no_engine_function_passes_100_lines(tmp_path, capsys):
    """docs/architecture.md's figures are engine_shape.py's, measured now; a changed figure is
    found; engine/src has no function over 100 lines."""
    doc = REPO / "docs" / "architecture.md"
    assert shape.check(doc, REPO) == 0, capsys.readouterr().out
    assert [f for f in shape.functions(REPO / "engine" / "src") if f[0] > 100] == []
    stale = tmp_path / "architecture.md"
    # One figure changed, whatever it is now.
    stale.write_text(re.sub(r" (\d+) include floors", lambda m: f" {int(m.group(1)) + 1} include floors",
                            doc.read_text(), count=1))
    assert shape.check(stale, REPO) == 1 and "stale" in capsys.readouterr().out

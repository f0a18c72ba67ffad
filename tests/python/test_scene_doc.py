"""docs/scene.md has a row for every key the engine reads from a scene table: the reader's
tables (`Tab t(..., "NAME", ...)` up to its `t.finish()`) are read from the engine's source."""
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SOURCES = [REPO / "engine" / "src" / "scene" / n for n in ("scene.cpp", "shear_scene.cpp")]
READ = re.compile(r'\bt\.(?:num|positive|non_negative|integer|boolean|str|choice|vec2|bounded|numbers|node|table|'
                  r'array_of_tables)\("(\w+)"')


def engine_keys():
    keys = set()
    for src in SOURCES:
        text = src.read_text()
        for m in re.finditer(r'Tab t\([^;]*?"(\w+)"(?: \+ [^,]+)?, s\.file\);(.*?)t\.finish\(\);', text, re.S):
            table = m.group(1)
            for k in READ.findall(m.group(2)):
                keys.add(f"{table}.{k}")
    return keys


def documented(key, doc):
    table, name = key.split(".", 1)
    if table in ("pairs", "walls", "points", "materials"):
        return f"`{name}`" in doc or name in doc
    return f"`{key}`" in doc or re.search(rf"`{re.escape(table)}\.[^`]*\b{re.escape(name)}\b", doc) is not None


def test_every_scene_key_has_a_row():
    doc = (REPO / "docs" / "scene.md").read_text()
    keys = engine_keys()
    assert len(keys) > 50, sorted(keys)  # the reader was found
    missing = sorted(k for k in keys if not documented(k, doc))
    assert not missing, f"docs/scene.md has no row for {missing}"


@pytest.mark.release_only  # Python's side: the sanitized engine's runs are the other tests'
def test_the_example_scene_is_the_one_documented_and_it_discharges(tmp_path):
    """docs/scene.md opens with examples/flat_silo.toml verbatim; the engine settles it to rest and
    discharges it without a jam (its slit is five diameters wide), and --pictures draws its five
    pictures although no disc touches a side wall at its end."""
    import json
    import os
    import subprocess
    doc = (REPO / "docs" / "scene.md").read_text()
    example = (REPO / "examples" / "flat_silo.toml").read_text()
    block = re.search(r"```toml\n(.*?)```", doc, re.S)
    assert block and block.group(1) == example
    dem = os.environ.get("DEM_BINARY", str(REPO / "build" / "dem"))
    proc = subprocess.run([dem, "run", str(REPO / "examples" / "flat_silo.toml"), "--out", str(tmp_path / "r"),
                           "--quiet", "--pictures"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert sorted(p.name for p in (tmp_path / "r").glob("*.png")) == \
        ["flow.png", "frames.png", "network.png", "side_walls.png", "wall_ratios.png"]
    d = summary["discharge"]
    assert summary["rest"]["reached"] and not d["jammed"] and d["removed"] > 20, d["status"]

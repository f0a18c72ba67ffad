"""dem.compare.io.scene_toml, the one TOML writer: values, documents that tomllib reads back equal
(every committed scene), edits that refuse keys the scene does not have, relative file paths
rebased, and the scene generators that write through it."""
import json
import math
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from dem.compare.io import scene_toml as st

REPO = Path(__file__).resolve().parents[2]
SCENES = REPO / "reference_inputs" / "scenes"
COMMITTED = sorted(SCENES.glob("*.toml")) + sorted((REPO / "reference_inputs" / "agreement").rglob("*.toml"))
SILO = SCENES / "silo_17_18.toml"
CALIBRATION = REPO / "reference_inputs" / "agreement" / "calibration" / "head_on_disc_disc.toml"


def resolve(dem_binary, scene):
    p = subprocess.run([str(dem_binary), "resolve", str(scene)], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


# --------------------------------------------------------------------------- values

def test_values():
    assert st.value(True) == "true" and st.value(False) == "false"
    assert st.value(3) == "3" and st.value(-2 ** 63) == str(-2 ** 63)
    assert st.value(0.1) == "0.1" and st.value(1e-4) == "0.0001" and st.value(1e16) == "1e+16"
    assert st.value(2.0) == "2.0"
    assert st.value(np.float64(0.25)) == "0.25" and st.value(np.int64(7)) == "7" and st.value(np.bool_(True)) == "true"
    assert st.value(np.float32(0.5)) == "0.5" and st.value(np.array([[1.0, 2.0]])) == "[[1.0, 2.0]]"
    assert st.value("a\"b\\c\n\t\x01\x7fé") == '"a\\"b\\\\c\\n\\t\\u0001\\u007fé"'
    assert st.value([1, [2.5, "x"], (True,)]) == '[1, [2.5, "x"], [true]]'
    assert st.value({"a b": 1, "c": [0.5]}) == '{"a b" = 1, c = [0.5]}'
    for v in (1e-4, 0.1 + 0.2, 1 / 3, 5e-324, 1.7976931348623157e308, -0.0):
        assert tomllib.loads(f"x = {st.value(v)}")["x"] == v          # repr: the same double back


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, np.float64("nan"), [1.0, math.inf]])
def test_non_finite_values_are_refused(bad):
    with pytest.raises(ValueError, match="non-finite"):
        st.value(bad)


def test_values_without_a_toml_form():
    with pytest.raises(ValueError, match="64 bits"):
        st.value(2 ** 63)
    with pytest.raises(TypeError, match="no TOML form"):
        st.value(None)
    with pytest.raises(TypeError, match="no TOML form"):
        st.value(object())


# --------------------------------------------------------------------------- documents

@pytest.mark.parametrize("path", COMMITTED, ids=[str(p.relative_to(REPO)) for p in COMMITTED])
def test_every_committed_scene_round_trips(path):
    doc = st.load(path)
    text = st.dumps(doc)
    assert tomllib.loads(text) == doc
    assert st.dumps(tomllib.loads(text)) == text          # and writing it again changes nothing


def test_dumps_layout_and_comments():
    doc = {"scene": {"name": "x"},
           "materials": {"sand": {"density": 2.65}, "wall": {}},
           "pairs": [{"materials": ["sand", "sand"], "mu": 0.5}, {"materials": ["sand", "wall"], "mu": 0.2}],
           "fill": {"type": "list", "discs": [[1.0, 2.0, 0.5], [3.0, 2.0, 0.5]]},
           "odd key": {"a.b": 1, "sub": {"deep": {"x": 1}}}}
    text = st.dumps(doc, header="first line\nsecond", comments={"pairs[1]": "the wall", "pairs[0].mu": "tan",
                                                                "materials.wall": "no density"})
    assert tomllib.loads(text) == doc
    lines = text.splitlines()
    assert lines[:3] == ["# first line", "# second", "[scene]"]
    assert "[materials]" not in lines and "[materials.sand]" in lines
    assert "[materials.wall]                 # no density" in lines       # empty table: its header
    assert lines.count("[[pairs]]") == 1 and "[[pairs]]                        # the wall" in lines
    assert "mu = 0.5                         # tan" in lines
    assert "discs = [" in lines and "  [1.0, 2.0, 0.5]," in lines          # an array of arrays: a row a line
    assert '["odd key"]' in lines and '"a.b" = 1' in lines and '["odd key".sub.deep]' in lines


def test_dumps_refuses_comments_on_keys_it_does_not_have():
    with pytest.raises(KeyError, match="end.tim"):
        st.dumps({"end": {"time": 1.0}}, comments={"end.tim": "s"})


def test_dumps_round_trips_awkward_strings():
    doc = {"scene": {"name": "q\"uote\\ back", "description": "line\nbreak \t tab \x00 nul \x7f del ☃ \U0001F600"},
           "end": {"time": 1e-300, "big": 2 ** 62, "neg": -1.5e300}}
    assert tomllib.loads(st.dumps(doc)) == doc


# --------------------------------------------------------------------------- edits

def test_with_changes_changes_adds_and_removes_by_path():
    doc = st.load(SILO)
    new = st.with_changes(doc, {"end.time": 0.5, "pairs[1].mu": 0.3, "fill.s": 12},
                          add={"output.progress": False, "discharge": {"time": 1.0, "gate": "gate"}},
                          remove=["fill.gap"])
    assert new["end"]["time"] == 0.5 and new["pairs"][1]["mu"] == 0.3 and new["fill"]["s"] == 12
    assert new["output"]["progress"] is False and new["discharge"] == {"time": 1.0, "gate": "gate"}
    assert "gap" not in new["fill"]
    assert doc == st.load(SILO)                                       # the original is untouched
    assert st.get(new, "pairs[-1].mu") == 0.3 and st.has(new, "discharge.gate") and not st.has(new, "x.y")
    assert st.with_changes(doc, {"fill": {"type": "file", "file": "a.csv", "material": "sand"}})["fill"] == \
        {"type": "file", "file": "a.csv", "material": "sand"}         # a whole table for another
    assert len(st.with_changes(doc, remove=["pairs[0]"])["pairs"]) == 1


@pytest.mark.parametrize("kwargs,error,fragment", [
    ({"changes": {"end.tim": 1.0}}, KeyError, "'end.tim'"),
    ({"changes": {"ends.time": 1.0}}, KeyError, "'ends'"),
    ({"changes": {"pairs[2].mu": 1.0}}, KeyError, "'pairs[2]'"),
    ({"changes": {"pairs.mu": 1.0}}, ValueError, "'pairs' is a"),
    ({"changes": {"end.time.x": 1.0}}, ValueError, "'end.time' is a number"),
    ({"changes": {"end.time": "long"}}, ValueError, "'end.time' from a number"),
    ({"changes": {"end.stop_at_rest": 1}}, ValueError, "'end.stop_at_rest' from a bool"),
    ({"changes": {"end": 5.0}}, ValueError, "'end' from a table"),
    ({"add": {"end.time": 1.0}}, ValueError, "already has it"),
    ({"add": {"pairs[0]": {}}}, ValueError, "cannot add 'pairs[0]'"),
    ({"remove": ["fill.radiu"]}, KeyError, "'fill.radiu'"),
    ({"changes": {"": 1}}, ValueError, "key path"),
])
def test_an_edit_of_a_key_the_scene_does_not_have_raises_naming_it(kwargs, error, fragment):
    with pytest.raises(error) as e:
        st.with_changes(st.load(SILO), **kwargs)
    assert fragment in str(e.value)


def test_edit_of_a_missing_key_writes_nothing(tmp_path):
    out = tmp_path / "x.toml"
    with pytest.raises(KeyError, match="contact.normal_sprng"):
        st.edit(SILO, {"contact.normal_sprng": "overlap"}, out)
    assert not out.exists() and not list(tmp_path.iterdir())


def test_edit_rewrites_relative_paths_for_the_new_folder(tmp_path, dem_binary):
    """fill.file (and start.from) are read relative to the scene's folder: a scene written
    elsewhere still names the same files; a path given in the changes is written as given."""
    (tmp_path / "a" / "b").mkdir(parents=True)
    out = st.edit(CALIBRATION, {"end.time": 0.001}, tmp_path / "a" / "b" / "moved.toml")
    moved = st.load(out)
    assert moved["fill"]["file"] != "head_on_disc_disc.csv" and not Path(moved["fill"]["file"]).is_absolute()
    assert (out.parent / moved["fill"]["file"]).resolve() == (CALIBRATION.parent / "head_on_disc_disc.csv").resolve()
    a, b = resolve(dem_binary, CALIBRATION), resolve(dem_binary, out)
    assert a["discs"] == b["discs"]                       # the same disc file, read from the new folder
    (tmp_path / "mine.csv").write_text("x,y,r\n0.0,0.0,1.0\n")
    given = st.load(st.edit(CALIBRATION, {"fill.file": "mine.csv", "fill.count": 1}, tmp_path / "given.toml"))
    assert given["fill"]["file"] == "mine.csv"
    # start.from: relative to the scene's folder too; absolute paths stay
    doc = st.with_changes(st.load(SILO), add={"start.from": "state.bin"})
    rebased = st.rebase_paths(doc, tmp_path / "x", tmp_path / "y")
    assert rebased["start"]["from"] == str(Path("..") / "x" / "state.bin")
    absolute = st.with_changes(doc, {"start.from": "/data/state.bin"})
    assert st.rebase_paths(absolute, tmp_path / "x", tmp_path / "y")["start"]["from"] == "/data/state.bin"
    assert st.rebase_paths(doc, tmp_path, tmp_path) == doc


def test_every_committed_scene_is_tested():
    assert len(COMMITTED) >= 40 and SILO in COMMITTED and CALIBRATION in COMMITTED  # the globs find the scenes


# One test a scene: the test workers share them out. The benchmark scenes of 100k and 1M discs
# are bench_silo_10k's tables with larger numbers (their text round-trips above): resolving their
# discs (3-40 s) would test nothing the 10k scene does not.
RESOLVED = [p for p in COMMITTED if p.name not in ("bench_silo_100k.toml", "bench_silo_1m.toml")]


@pytest.mark.parametrize("path", RESOLVED, ids=[str(p.relative_to(REPO / "reference_inputs")) for p in RESOLVED])
def test_written_scenes_resolve_as_the_originals(tmp_path, dem_binary, path):
    """Every committed scene, loaded and written elsewhere, is the same scene to the engine."""
    copy = st.edit(path, None, tmp_path / path.name)
    a, b = resolve(dem_binary, path), resolve(dem_binary, copy)
    a.pop("file"), b.pop("file")
    assert a == b, path


def test_load_names_the_file_of_a_syntax_error(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[end\ntime = 1\n")
    with pytest.raises(ValueError, match="bad.toml.*TOML syntax"):
        st.load(bad)
    with pytest.raises(FileNotFoundError, match="missing.toml"):
        st.load(tmp_path / "missing.toml")


# --------------------------------------------------------------------------- generators

@pytest.mark.parametrize("script", ["make_paper_scenes.py", "make_calibration_scenes.py", "make_janssen_scene.py",
                                    "make_shear_scenes.py"])
def test_generated_scenes_are_up_to_date(script):
    p = subprocess.run([sys.executable, str(REPO / "scripts" / script), "--check"], capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stderr

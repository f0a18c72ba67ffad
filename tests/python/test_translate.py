"""The committed translations hold each case's data once: YADE's folders carry yade_case.json and
no copy of the one script template; `compare translate --out DIR` writes folders that run as
they are (the template beside each case)."""
from pathlib import Path

import pytest

from dem.compare.codes import yade_backend
from dem.compare.verdict import translate

REPO = Path(__file__).resolve().parents[2]


def test_committed_yade_inputs_have_no_script_copies():
    folders = sorted((REPO / "reference_inputs" / "yade").iterdir())
    assert len(folders) == len(translate.cases()) == 10
    for f in folders:
        assert sorted(p.name for p in f.iterdir()) == ["yade_case.json"], f


@pytest.mark.release_only  # Python's side: the sanitized engine's runs are the other tests'
def test_translate_out_writes_runnable_folders(tmp_path, dem_binary):
    assert translate.main(False, tmp_path) == 0
    for case in ("silo_17_18", "discharge_11_12"):
        d = tmp_path / "yade" / case
        assert (d / "yade_script.py").read_text() == yade_backend.TEMPLATE.read_text()
        assert (d / "yade_case.json").read_bytes() == (REPO / "reference_inputs" / "yade" / case / "yade_case.json").read_bytes()
        assert (tmp_path / "liggghts" / case / "in.liggghts").is_file() and (tmp_path / "lammps" / case / "in.lammps").is_file()

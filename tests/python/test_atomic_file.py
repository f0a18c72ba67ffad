"""dem.compare.io.atomic_file: a file is written whole or left as it was."""
import pytest

from dem.compare.io import atomic_file


def test_written_whole_in_a_new_folder(tmp_path):
    path = tmp_path / "a" / "b" / "out.txt"
    assert atomic_file.write_text(path, "one\ntwo\n") == path
    assert path.read_text() == "one\ntwo\n"
    atomic_file.write_bytes(path, b"\x89PNG")
    assert path.read_bytes() == b"\x89PNG"
    assert sorted(p.name for p in path.parent.iterdir()) == ["out.txt"]


def test_an_error_while_writing_leaves_the_old_file_and_no_temporary(tmp_path):
    path = tmp_path / "out.vtu"
    path.write_text("old")
    with pytest.raises(RuntimeError, match="half-way"):
        with atomic_file.replacing(path) as tmp:
            with open(tmp, "w") as f:
                f.write("half a fi")
            raise RuntimeError("killed half-way")
    assert path.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.vtu"]


def test_nothing_is_left_where_there_was_nothing(tmp_path):
    path = tmp_path / "new.png"
    with pytest.raises(ValueError):
        with atomic_file.replacing(path) as tmp:
            open(tmp, "wb").close()
            raise ValueError("no picture")
    assert list(tmp_path.iterdir()) == []

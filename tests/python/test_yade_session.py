"""A kept YADE process runs scripts as `yade -x` would: each in its folder, its output in its own
log, no name of an earlier script left, a failed script's process not reused, a timeout reported."""
import os
import shutil

import pytest

from dem.compare.codes import yade_session

pytestmark = [pytest.mark.reference_codes,
              pytest.mark.skipif(shutil.which("yade") is None and os.environ.get("CI") != "true",
                                 reason="yade not installed (CI installs it)")]


def _script(folder, name, text):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_text(text)
    return name


def test_scripts_share_a_process_but_not_their_names_or_scene(tmp_path):
    yade_session.close_all()
    first = _script(tmp_path / "a", "s.py", "import os\nleft = 1\nO.bodies.append(sphere((0, 0, 0), 1))\n"
                    "O.dt = 1e-3\nprint('pid', os.getpid(), 'cwd', os.getcwd(), 'name', __name__)\n")
    second = _script(tmp_path / "b", "s.py", "import os\nprint('pid', os.getpid(), 'cwd', os.getcwd(), "
                     "'left' in globals(), len(O.bodies), O.iter, O.time, 'O' in globals())\n")
    assert yade_session.run(first, tmp_path / "a", tmp_path / "a" / "log", 60) == 0
    assert yade_session.run(second, tmp_path / "b", tmp_path / "b" / "log", 60) == 0
    a = (tmp_path / "a" / "log").read_text().split()
    b = (tmp_path / "b" / "log").read_text().split()
    assert a[a.index("pid") + 1] == b[b.index("pid") + 1]          # one process
    assert a[a.index("cwd") + 1] == str(tmp_path / "a") and b[b.index("cwd") + 1] == str(tmp_path / "b")
    assert a[a.index("name") + 1] == "__main__"
    assert b[b.index("cwd") + 2:] == ["False", "0", "0", "0.0", "True"]   # no name, body or time left


def test_a_failed_script_ends_its_process_and_the_next_starts_afresh(tmp_path):
    yade_session.close_all()
    pid = "import os\nprint('pid', os.getpid())\n"
    before = _script(tmp_path / "a", "s.py", pid)
    broken = _script(tmp_path / "b", "s.py", pid + "raise ValueError('boom')\n")
    exits = _script(tmp_path / "c", "s.py", pid + "import sys\nsys.exit(5)\n")
    after = _script(tmp_path / "d", "s.py", pid)
    assert yade_session.run(before, tmp_path / "a", tmp_path / "a" / "log", 60) == 0
    assert yade_session.run(broken, tmp_path / "b", tmp_path / "b" / "log", 60) == 1
    assert "ValueError: boom" in (tmp_path / "b" / "log").read_text()
    assert yade_session.run(exits, tmp_path / "c", tmp_path / "c" / "log", 60) == 5
    assert yade_session.run(after, tmp_path / "d", tmp_path / "d" / "log", 60) == 0
    pids = [(tmp_path / k / "log").read_text().split()[1] for k in "abcd"]
    assert pids[0] == pids[1] and len(set(pids)) == 3                 # b ran in a's process; c, d each anew


def test_a_script_past_its_timeout_is_reported_and_its_process_ended(tmp_path):
    yade_session.close_all()
    slow = _script(tmp_path / "a", "s.py", "import time\ntime.sleep(30)\n")
    quick = _script(tmp_path / "b", "s.py", "print('ok')\n")
    assert yade_session.run(slow, tmp_path / "a", tmp_path / "a" / "log", 3) is None
    assert yade_session.run(quick, tmp_path / "b", tmp_path / "b" / "log", 60) == 0
    assert (tmp_path / "b" / "log").read_text().strip() == "ok"

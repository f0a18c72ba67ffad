"""Replays the corpus of malformed scenes (tests/corpus/scenes/*.toml, also the fuzzer's seeds,
scripts/fuzz.sh): each is refused before any step with exit code 2 and a message naming the
field, within a time limit, without a crash, a sanitizer report or an output directory. The
fragments the message must contain are the file's `# expect:` lines."""
import os
import re
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
CORPUS = sorted((REPO / "tests" / "corpus" / "scenes").glob("*.toml"))


def expectations(path):
    head = path.read_bytes()[:4096].decode("utf-8", "replace")
    return re.findall(r"(?m)^# expect: (.+)$", head)


def test_corpus_is_there():
    assert len(CORPUS) >= 30
    for path in CORPUS:
        assert expectations(path), f"{path.name}: no '# expect:' line"


@pytest.mark.parametrize("path", CORPUS, ids=[p.stem for p in CORPUS])
def test_malformed_scene_is_refused(tmp_path, dem_binary, path):
    out = tmp_path / "out"
    # A limit on the address space catches a scene that allocates without bound (the sanitizer
    # build reserves terabytes of shadow memory, so it gets no limit and relies on the timeout).
    sanitized = "asan" in str(dem_binary)
    limit = None if sanitized else (lambda: __import__("resource").setrlimit(
        __import__("resource").RLIMIT_AS, (4 << 30, 4 << 30)))
    proc = subprocess.run([str(dem_binary), "run", str(path), "--out", str(out), "--quiet"],
                          capture_output=True, text=True, errors="replace", timeout=60, stdin=subprocess.DEVNULL,
                          preexec_fn=limit)
    assert proc.returncode == 2, f"exit {proc.returncode}\n{proc.stdout}\n{proc.stderr}"
    assert "Sanitizer" not in proc.stderr and "runtime error" not in proc.stderr, proc.stderr
    assert str(path) in proc.stderr, proc.stderr
    for fragment in expectations(path):
        assert fragment in proc.stderr, f"{fragment!r} not in: {proc.stderr}"
    assert not out.exists(), "output directory left behind"


def test_tiny_discs_in_a_huge_box_run(tmp_path, run_dem):
    """The valid twin of the corpus's tiny_discs_huge_box: the cell grid stays small (at most
    4 n + 64 cells) and the run completes."""
    text = (REPO / "tests" / "corpus" / "scenes" / "tiny_discs_huge_box.toml").read_text()
    text = text.replace("[1.0000015, 1.0, 1e-6]", "[1.0000025, 1.0, 1e-6]").replace("time = 5.0", "time = 0.001")
    scene = tmp_path / "sparse.toml"
    scene.write_text(text)
    proc = run_dem("run", scene, "--out", tmp_path / "out", "--quiet", "--force-dt", timeout=60)
    assert proc.returncode == 0, proc.stderr
    import json
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["n_discs"] == 4 and summary["steps"] == 10

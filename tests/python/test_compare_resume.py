"""`dem compare --resume`: a finished run whose translated inputs are byte for byte the same is
read back; a failed run, a changed case or changed inputs on disk run again."""
import types
from pathlib import Path

from dem.compare.verdict import study
from dem.compare.cases.common import Result


def _fake_backend(calls):
    def write_inputs(case, out_dir, threads=1):
        Path(out_dir).mkdir(parents=True, exist_ok=True)
        (Path(out_dir) / "deck.in").write_text(f"k_n {case.kn}\n")

    def run(case, out_dir, timeout=0, threads=1):
        write_inputs(case, out_dir, threads)
        calls.append(case.kn)
        return Result(code="fake", case="c", status="ok" if case.kn > 0 else "failed", wall_time_s=1.0)
    return types.SimpleNamespace(available=lambda: True, write_inputs=write_inputs, run=run)


def test_resume_reads_back_only_unchanged_finished_runs(monkeypatch, tmp_path):
    calls = []
    monkeypatch.setattr(study, "backend", lambda code: _fake_backend(calls))
    case = types.SimpleNamespace(name="c", kn=2.0)
    d = tmp_path / "fake"
    study.run_code("fake", case, d, 10)
    study.run_code("fake", case, d, 10, resume=True)
    assert calls == [2.0]                                   # read back, not run
    study.run_code("fake", case, d, 10)
    assert calls == [2.0, 2.0]                              # without --resume: runs
    changed = types.SimpleNamespace(name="c", kn=3.0)
    study.run_code("fake", changed, d, 10, resume=True)
    assert calls == [2.0, 2.0, 3.0]                         # another translation: runs
    (d / "deck.in").write_text("k_n 4.0\n")
    study.run_code("fake", changed, d, 10, resume=True)
    assert calls == [2.0, 2.0, 3.0, 3.0]                    # inputs on disk differ: runs


def test_resume_runs_a_failed_run_again(monkeypatch, tmp_path):
    calls = []
    monkeypatch.setattr(study, "backend", lambda code: _fake_backend(calls))
    case = types.SimpleNamespace(name="c", kn=-1.0)         # the fake fails on k_n <= 0
    d = tmp_path / "fake"
    assert not study.run_code("fake", case, d, 10).ok
    study.run_code("fake", case, d, 10, resume=True)
    assert calls == [-1.0, -1.0]

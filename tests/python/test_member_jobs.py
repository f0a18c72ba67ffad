"""`dem compare --jobs N`: ensemble members run N at once, in their own folders, and come back in
member order whatever order they finish in."""
import subprocess
import threading
import time
import types
from pathlib import Path

from dem.compare.verdict import pipeline

ROOT = Path(__file__).resolve().parents[2]


def _fake_members(monkeypatch, members, jobs):
    """A plan of ``members`` members whose runs sleep (later members shorter, so they finish first)
    and record how many run at once."""
    state = {"now": 0, "most": 0, "lock": threading.Lock()}

    def fake_case(plan, k):
        return types.SimpleNamespace(k=k, series_interval=None)

    def fake_run_all(codes, case, plan, out, mutation=None):
        with state["lock"]:
            state["now"] += 1
            state["most"] = max(state["most"], state["now"])
        time.sleep(0.05 * (members - case.k))
        with state["lock"]:
            state["now"] -= 1
        return {c: (c, case.k, out.name, case.series_interval) for c in codes}

    monkeypatch.setattr(pipeline, "member_case", fake_case)
    monkeypatch.setattr(pipeline, "run_all", fake_run_all)
    plan = types.SimpleNamespace(members=members, options=types.SimpleNamespace(jobs=jobs))
    return plan, state


def test_members_come_back_in_member_order_with_parallel_jobs(monkeypatch, tmp_path):
    plan, state = _fake_members(monkeypatch, 4, 2)
    got = pipeline.member_runs(plan, ("native", "yade"), tmp_path, series_interval=0.05)
    assert [case.k for _, case in got] == [0, 1, 2, 3]
    assert [res["yade"] for res, _ in got] == [("yade", k, f"m{k}", 0.05) for k in range(4)]
    assert state["most"] == 2


def test_one_job_runs_members_one_after_another(monkeypatch, tmp_path):
    plan, state = _fake_members(monkeypatch, 3, 1)
    got = pipeline.member_runs(plan, ("native",), tmp_path)
    assert [case.k for _, case in got] == [0, 1, 2] and state["most"] == 1


def test_jobs_below_one_is_refused(dem_binary, tmp_path):
    p = subprocess.run([str(dem_binary), "compare", str(ROOT / "reference_inputs" / "scenes" / "discharge_17_18.toml"),
                        "--jobs", "0", "--out", str(tmp_path / "out")], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "--jobs" in p.stderr, p.stderr
    assert not (tmp_path / "out").exists()

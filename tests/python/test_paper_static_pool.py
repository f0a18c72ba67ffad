"""The static study draws its pictured cases' figures in figure processes while other runs go on:
the PNGs are those dem.compare.figures draws in this process from the same runs, byte for byte, and
the report shows them."""
from dem.compare.figures import runs as figures
import pytest

from dem.compare.papers import paper_static

# The pool is Python's; the engine runs it starts are the release build's (sanitizer: release only).
pytestmark = pytest.mark.release_only


def test_figures_of_the_pool_are_those_drawn_here(tmp_path, dem_binary, monkeypatch):
    monkeypatch.setattr(paper_static, "ARRANGEMENTS", [18])
    monkeypatch.setattr(paper_static, "SCHEMES", ["paper_eq19", "velocity_verlet"])
    out = tmp_path / "study"
    assert paper_static.main(["--out", str(out), "--dem", str(dem_binary), "--jobs", "2"]) == 0
    report = (out / "report.md").read_text()
    for scheme, dt in (paper_static.PAPER, paper_static.REFERENCE):
        tag = f"{scheme}_dt{dt:g}"
        run = out / "runs" / tag / "silo_17_18"
        here = tmp_path / "here"
        figures.plot_network_grid([run], here / f"network_{tag}.png", labels=["17/18"])
        figures.plot_side_profiles([run], here / f"fig7_{tag}.png", labels=["17/18"])
        for name in (f"network_{tag}.png", f"fig7_{tag}.png"):
            assert (out / name).read_bytes() == (here / name).read_bytes(), name
            assert f"({name})" in report

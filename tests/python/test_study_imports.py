"""The studies' own processes import no matplotlib: they start their runs at once, and only the
figure processes (a fork server that preloads dem.compare.figures) draw."""
import subprocess
import sys
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]


def test_study_processes_import_no_matplotlib():
    code = ("import sys; import dem.compare.papers.paper_static, dem.compare.papers.paper_discharge, dem.compare.papers.paper_claims, "
            "dem.compare.figures.figure_data; print(sorted(m for m in sys.modules if m.split('.')[0] == 'matplotlib'))")
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO_ROOT, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_figures_reexports_the_data_functions():
    from dem.compare.figures import figure_data, runs as figures
    for name in ("load_run", "read_csv", "read_summary", "network_segments", "side_wall_contacts",
                 "run_caption", "common_caption", "PAPER_LAW", "SHARED_LAW", "DIAMETER_IN_DISC_WEIGHTS"):
        assert getattr(figures, name) is getattr(figure_data, name), name

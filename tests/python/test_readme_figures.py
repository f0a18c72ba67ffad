"""The README's figures of the paper's silo are the main job's: the static study and the two
discharge ensembles the README quotes (eq. 19 at the paper's dt, and the schemes that blow up
there) are run as the main job runs them, and scripts/readme_figures.py finds the README's block
equal to what they give."""
import importlib.util
from pathlib import Path

import pytest

from dem.compare.papers import paper_discharge, paper_static

REPO = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("readme_figures", REPO / "scripts" / "readme_figures.py")
readme_figures = importlib.util.module_from_spec(spec)
spec.loader.exec_module(readme_figures)


@pytest.mark.release_only
def test_readme_quotes_the_main_job(tmp_path, dem_binary, monkeypatch):
    out = tmp_path / "paper_silo"
    monkeypatch.setattr(paper_static, "STEPS", [1e-4])
    assert paper_static.main(["--out", str(out), "--dem", str(dem_binary), "--jobs", "2"]) == 0
    quoted = [c for c in paper_discharge.CONFIGS if c[0] in ("17_18_eq19_1e-4", "11_12_eq19_1e-4")]
    assert len(quoted) == 2
    monkeypatch.setattr(paper_discharge, "CONFIGS", quoted)
    assert paper_discharge.main(["--out", str(out / "discharge"), "--dem", str(dem_binary), "--jobs", "2"]) == 0
    assert readme_figures.main([str(out), "--check", str(REPO / "README.md")]) == 0


def test_a_changed_figure_is_found(tmp_path, capsys):
    import json
    out = tmp_path / "job"
    (out / "discharge").mkdir(parents=True)
    static = [{"s": s, "arrangement": f"{s - 1}/{s}", "scheme": sc, "dt": 1e-4, "rest": sc == "paper_eq19",
               "exit": 0 if sc == "paper_eq19" else 3, "side_mean": 300.0 - 30 * s}
              for s in (12, 19) for sc in ("paper_eq18", "paper_eq19")]
    stat = {"n": 8, "mean": 10.0, "stderr": 1.0}
    ens = {"members": 8, "pattern": {"funnel": 8, "piping": 0}, "flow_rate_discs": stat, "peak_ratio_bottom": stat,
           "peak_ratio_bottom_windowed": stat, "peak_ratio_side": stat, "peak_ratio_side_windowed": stat}
    (out / "study.json").write_text(json.dumps(static))
    (out / "discharge" / "discharge.json").write_text(json.dumps(
        [{"tag": t, "ensemble": ens} for t in ("17_18_eq19_1e-4", "11_12_eq19_1e-4")]))
    block = readme_figures.block(out)
    assert "2 of 2 arrangements to rest" in block[1] and "falling at every step of s" in block[2]
    readme = tmp_path / "README.md"
    readme.write_text("\n".join(["intro", *block, "more"]))
    assert readme_figures.main([str(out), "--check", str(readme)]) == 0
    readme.write_text("\n".join(["intro", *block, "more"]).replace("2 of 2 arrangements", "1 of 2 arrangements"))
    assert readme_figures.main([str(out), "--check", str(readme)]) == 1
    assert "differ at line 2" in capsys.readouterr().err


def test_the_paper_is_cited_with_one_year():
    """README, docs, figures, reports and the engine's help cite Kiyama & Fujimura with the year of
    CITATION.cff."""
    import re
    year = re.search(r"year: (\d{4})", (REPO / "CITATION.cff").read_text()).group(1)
    files = [REPO / "README.md", *(REPO / "docs").glob("*.md"), *(REPO / "compare").rglob("*.py"),
             *(REPO / "engine" / "src").rglob("*.cpp")]
    cited = {(f.name, y) for f in files for y in re.findall(r"Kiyama (?:&|and) Fujimura[^0-9\n]{0,20}(\d{4})", f.read_text())}
    assert cited and all(y == year for _, y in cited), sorted(c for c in cited if c[1] != year)

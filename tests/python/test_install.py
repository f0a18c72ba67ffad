"""`cmake --install` gives a dem that runs with the source tree gone: the comparison layer is
installed beside the scenes (PREFIX/share/dem/compare) and the installed dem's Python processes
(`dem compare`, `dem run --pictures`) import that copy, not the checkout's; compare/ is put on no
Python's path but theirs."""
import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
MARK = 'import os; os.environ.get("DEM_MARK") and print("compare imported from", __file__)\n'


@pytest.mark.release_only
def test_the_installed_dem_runs_its_own_comparison_layer(tmp_path, dem_binary):
    prefix = tmp_path / "prefix"
    p = subprocess.run(["cmake", "--install", str(Path(dem_binary).parent), "--prefix", str(prefix)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    share = prefix / "share" / "dem"
    assert (share / "compare" / "__main__.py").is_file() and (share / "reference_inputs" / "scenes").is_dir()
    with open(share / "compare" / "__init__.py", "a") as f:
        f.write(MARK)          # the installed copy says when it is the one imported
    env = {**os.environ, "DEM_MARK": "1"}
    env.pop("PYTHONPATH", None)
    dem = prefix / "bin" / "dem"
    h = subprocess.run([str(dem), "compare", "--help"], capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120)
    assert h.returncode == 0 and f"compare imported from {share / 'compare' / '__init__.py'}" in h.stdout, h.stdout + h.stderr
    r = subprocess.run([str(dem), "run", str(REPO / "examples" / "flat_silo.toml"), "--out", str(tmp_path / "run"),
                        "--quiet", "--pictures", "--set", "discharge.time=0.1"],
                       capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
    assert r.returncode == 0, r.stderr
    assert str(share / "compare") in r.stdout + r.stderr and (tmp_path / "run" / "frames.png").is_file()
    # the checkout's build keeps its own checkout's layer
    b = subprocess.run([str(dem_binary), "compare", "--help"], capture_output=True, text=True, env=env, timeout=120)
    assert b.returncode == 0 and "compare imported from" not in b.stdout

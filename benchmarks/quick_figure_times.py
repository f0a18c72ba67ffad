"""CPU seconds of one run's pictures drawn with PIL (compare/quick_figures.py), by phase.

    /usr/bin/python3 benchmarks/quick_figure_times.py RUN_DIR [--repeats 3]

RUN_DIR is a discharge run (`build/dem run reference_inputs/scenes/discharge_17_18.toml --out
RUN_DIR --quiet`). Each repeat is a fresh process, as `compare.figures run DIR --renderer pil`
starts (one OpenBLAS thread): `time.process_time` of importing numpy and PIL, then compare's
modules, and for each of the five pictures its reading (compare.figure_data's functions), drawing
and PNG encoding (written into a temporary folder). Prints one line a picture and the sums.
"""
import argparse
import os
import subprocess
import sys
import tempfile

CHILD = r"""
import os, sys, time
t0 = time.process_time()
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import numpy
from PIL import Image, ImageDraw, ImageFont
t1 = time.process_time()
from compare.figures import figure_data, quick_figures as q
t2 = time.process_time()
run, out = sys.argv[1], sys.argv[2]
reading = [0.0]
def timed(fn):
    def wrap(*args, **kwargs):
        t = time.process_time()
        try:
            return fn(*args, **kwargs)
        finally:
            reading[0] += time.process_time() - t
    return wrap
for name in ("discharge_frames", "flow_data", "wall_ratio_data", "load_run"):
    setattr(q, name, timed(getattr(figure_data, name)))
sums = [0.0, 0.0, 0.0]
lines = [f"import numpy+PIL {t1 - t0:.3f} compare {t2 - t1:.3f}"]
for name in ("network", "side_walls", "frames", "wall_ratios", "flow"):
    before, t = reading[0], time.process_time()
    fig = getattr(q, name)(run)
    t_drawn = time.process_time()
    fig.save(f"{out}/{name}.png")
    t_saved = time.process_time()
    read = reading[0] - before
    parts = (read, t_drawn - t - read, t_saved - t_drawn)
    sums = [a + b for a, b in zip(sums, parts)]
    lines.append(f"{name:12s} read {parts[0]:.3f} draw {parts[1]:.3f} encode {parts[2]:.3f}")
lines.append(f"sums: read {sums[0]:.3f} draw {sums[1]:.3f} encode {sums[2]:.3f}; "
             f"all {time.process_time() - t0:.3f} s CPU")
print("\n".join(lines), flush=True)
"""


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run_dir")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = dict(os.environ, PYTHONPATH=repo)
    with tempfile.TemporaryDirectory() as out:
        for r in range(args.repeats):
            print(f"[{r}]", flush=True)
            subprocess.run([sys.executable, "-c", CHILD, os.path.abspath(args.run_dir), out], env=env,
                           cwd=repo, check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

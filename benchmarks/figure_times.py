"""CPU seconds of one run's pictures, each on its own, in one process.

    /usr/bin/python3 benchmarks/figure_times.py RUN_DIR [--checkout DIR] [--out DIR] [--repeats 3]

RUN_DIR is a discharge run (`build/dem run reference_inputs/scenes/discharge_17_18.toml --out
RUN_DIR --quiet`); --checkout is the checkout whose compare/ draws (default this one; an older
one to compare with), the folder the drawing process runs in. Each repeat is a fresh process: `time.process_time` around importing
dem.compare.figures and around each of the five pictures of `dem.compare.figures run` (written into DIR,
default a temporary folder). Prints one line a repeat.
"""
import argparse
import os
import subprocess
import sys
import tempfile

CHILD = r"""
import sys, time
t0 = time.process_time()
from dem.compare.figures import runs as f
t1 = time.process_time()
run, out = sys.argv[1], sys.argv[2]
parts = [("network", lambda: f.plot_network(run, f"{out}/network.png")),
         ("side_walls", lambda: f.plot_side_profiles([run], f"{out}/side_walls.png")),
         ("frames", lambda: f.plot_discharge_frames(run, f"{out}/frames.png")),
         ("wall_ratios", lambda: f.plot_wall_ratios(run, f"{out}/wall_ratios.png")),
         ("flow", lambda: f.plot_flow(run, f"{out}/flow.png"))]
line = [f"import {t1 - t0:.2f}"]
for name, draw in parts:
    t = time.process_time()
    draw()
    line.append(f"{name} {time.process_time() - t:.2f}")
print(" ".join(line) + f"  all {time.process_time() - t0:.2f} s CPU", flush=True)
"""


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run_dir")
    ap.add_argument("--out")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--checkout", default=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    args = ap.parse_args(argv)
    out = args.out or tempfile.mkdtemp(prefix="figure_times_")
    os.makedirs(out, exist_ok=True)
    for _ in range(args.repeats):
        # the checkout's own package dem (its build/python), not the one a .pth file names
        subprocess.run([sys.executable, "-c", CHILD, os.path.abspath(args.run_dir), os.path.abspath(out)],
                       cwd=args.checkout, env=dict(os.environ, PYTHONPATH=os.path.join(os.path.abspath(args.checkout), "build", "python")),
                       check=True)
    print(f"load average (1 min) {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

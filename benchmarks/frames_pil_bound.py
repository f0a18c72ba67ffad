"""A lower bound of the frames picture drawn without matplotlib: CPU seconds of PIL alone.

    /usr/bin/python3 benchmarks/frames_pil_bound.py RUN_DIR [--out frames_pil.png]

RUN_DIR is a discharge run (`build/dem run reference_inputs/scenes/discharge_17_18.toml --out
RUN_DIR --quiet`). Draws its first ten discharge snapshots as `compare.figures`' frames.png does
in size (2595 x 1266 pixels, 10 panels): each disc an outlined circle, each contact a short
segment at its point, a frame and a time per panel; no axes, ticks, colour bar or antialiasing,
so it is a bound, not a picture to use. Prints `time.process_time` of importing numpy and PIL,
reading the snapshots (compare.run_dir, which imports no matplotlib), drawing and encoding (PNG,
zlib level 3).
"""
import sys
import time

t0 = time.process_time()
import numpy as np  # noqa: E402
from PIL import Image, ImageDraw, ImageFont  # noqa: E402
t1 = time.process_time()

from compare.io.run_dir import CONTACT_COLUMNS, SNAPSHOT_DISC_COLUMNS, RunDir, read_csv  # noqa: E402


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    run, out = argv[0], (argv[2] if len(argv) > 2 and argv[1] == "--out" else "frames_pil.png")
    t2 = time.process_time()
    snaps = RunDir(run).discharge_snapshots()[:10]
    frames = [(s["t"], read_csv(s["discs"], SNAPSHOT_DISC_COLUMNS), read_csv(s["contacts"], CONTACT_COLUMNS))
              for s in snaps]
    t3 = time.process_time()
    image = Image.new("RGB", (2595, 1266), "white")
    pen = ImageDraw.Draw(image)
    font = ImageFont.load_default()
    width, height, scale = 500, 560, 12.0           # panel size [px], px per cm
    for k, (t, discs, contacts) in enumerate(frames):
        ox, oy = 40 + (k % 5) * 510, 80 + (k // 5) * 600
        pen.rectangle([ox, oy, ox + width, oy + height], outline="black")
        px, py = ox + 10 + discs["x"] * scale, oy + height - 60 - discs["y"] * scale
        for x, y, r in zip(px, py, discs["r"] * scale):
            pen.ellipse([x - r, y - r, x + r, y + r], fill=(250, 180, 80), outline=(128, 128, 128))
        cx, cy = ox + 10 + contacts["x"] * scale, oy + height - 60 - contacts["y"] * scale
        for x, y in zip(cx, cy):
            pen.line([x - 5, y - 3, x + 5, y + 3], fill="black", width=2)
        pen.text((ox + width // 2 - 30, oy - 20), f"t = {t:.2f} s", fill="black", font=font)
    t4 = time.process_time()
    image.save(out, format="png", compress_level=3)
    t5 = time.process_time()
    print(f"import {t1 - t0:.3f} read {t3 - t2:.3f} draw {t4 - t3:.3f} encode {t5 - t4:.3f} "
          f"all {t5 - t0:.3f} s CPU ({len(frames)} panels, {np.mean([len(d['r']) for _, d, _ in frames]):.0f} discs)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

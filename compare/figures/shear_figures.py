"""Figures of paper 2's simple shear test (Sumita, Kiyama & Nishimura), from `dem run`
directories of shear scenes (docs/outputs.md, "Shear outputs") and from the YADE runs of
compare/codes/shear_yade.py (same file layout for the series).

- ``ratio``:   tau/sigma against shear strain, one panel per alpha, one curve per variant (with
  and without clusters, native and YADE): the analogue of the paper's Fig. 7;
- ``network``: contact forces of snapshots (the paper's Figs. 5 and 6): discs, cluster bonds as
  light lines between centres, every contact as a segment centred on its contact point along
  the elastic resultant e_n n + e_s t; tensile bonds in blue.

Usage, from the repository root::

    /usr/bin/python3 -m dem.compare.figures.shear_figures ratio --runs A:LABEL:DIR ... --out fig7.png
    /usr/bin/python3 -m dem.compare.figures.shear_figures network DIR:K[:TITLE] ... --out fig6.png
"""

import argparse
import math
import os

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402

from dem.compare.figures.runs import _draw_discs, _fail, _reading, _save  # noqa: E402
from dem.compare.io.run_dir import CONTACT_COLUMNS, DISC_COLUMNS, RunDir, read_header_csv  # noqa: E402

SERIES_NEEDED = ("strain", "sigma", "tau", "ratio")
STYLES = {"free": ("0.2", "-"), "clusters": ("tab:red", "-"), "touching": ("tab:orange", "--"),
          "clumps": ("tab:purple", "-."), "bonds": ("tab:red", ":")}


def read_series(path):
    """shear_series.csv as a dict of float arrays (the columns its header names;
    dem.compare.io.run_dir.read_header_csv)."""
    return _reading(read_header_csv, path, SERIES_NEEDED)


def peak(series, window=0.011):
    """(raw peak of tau/sigma, strain there, windowed peak): the windowed peak is the largest
    centred moving average over `window` of strain."""
    s, r = series["strain"], series["ratio"]
    if len(r) == 0:
        return float("nan"), float("nan"), float("nan")
    k = int(np.argmax(r))
    step = np.median(np.diff(s)) if len(s) > 1 else window
    half = max(1, int(round(0.5 * window / step))) if step > 0 else 1
    best = -np.inf
    for q in range(len(r)):
        best = max(best, float(np.mean(r[max(0, q - half):q + half + 1])))
    return float(r[k]), float(s[k]), best


def plot_ratio(runs, out_png, title=None):
    """runs: list of (alpha, label, series dict). One panel per alpha, one curve per label."""
    alphas = []
    for a, _, _ in runs:
        if a not in alphas:
            alphas.append(a)
    fig, axes = plt.subplots(1, len(alphas), figsize=(4.6 * len(alphas), 4.2), sharey=True, squeeze=False)
    for ax, a in zip(axes[0], alphas):
        for a2, label, s in runs:
            if a2 != a:
                continue
            base = label.split()[0]
            colour, ls = STYLES.get(base, ("tab:blue", "-"))
            if "yade" in label.lower():
                ls = ":" if ls == "-" else "-."
            ax.plot(100 * s["strain"], s["ratio"], color=colour, linestyle=ls, linewidth=1.3, label=label)
        ax.set_title(f"alpha = {a} deg")
        ax.set_xlabel("shear strain gamma_xy [%]")
        ax.grid(alpha=0.3)
        ax.axhline(0, color="0.6", linewidth=0.6)
        ax.legend(fontsize=7, loc="lower right")
    axes[0][0].set_ylabel("tau_xy / sigma_x (mean over the planes)")
    fig.suptitle(title or "Stress ratio against shear strain (paper 2, Fig. 7 analogue)", fontsize=11)
    fig.tight_layout()
    return _save(fig, out_png)


def load_snapshot(run_dir, k):
    """Snapshot k of a shear run: (entry of snapshots/index.json, contacts, discs, summary)."""
    rd = RunDir(run_dir)
    index = _reading(rd.shear_snapshots)
    if not 0 <= k < len(index):
        _fail(rd.file(os.path.join("snapshots", "index.json")), f"no snapshot {k} (there are {len(index)})")
    entry = index[k]
    contacts = _reading(rd.snapshot_csv, os.path.join("snapshots", entry["contacts"]), CONTACT_COLUMNS)
    discs = _reading(rd.snapshot_csv, os.path.join("snapshots", entry["discs"]), DISC_COLUMNS)
    summary = _reading(lambda: rd.summary)
    return entry, contacts, discs, summary


def force_scale(summary):
    """Force drawn as one disc diameter: the plate's weight shared by one row (b / 2r discs)."""
    shear = summary.get("shear") or {}
    width = float(shear.get("width", 40.0))
    return float(shear.get("plate_weight", 1.0)) / (width / 2.0)


def draw_snapshot(ax, entry, contacts, discs, f_ref, linewidth=1.0):
    """Discs, walls, bonds and contact forces of one snapshot on an Axes."""
    r = discs["r"]
    _draw_discs(ax, discs, "none", "0.65", 0.4 * linewidth)
    pos = {int(i): (x, y) for i, x, y in zip(discs["id"], discs["x"], discs["y"])}
    kind = contacts["kind"]
    bond = kind == "db"
    if bond.any():
        segs = []
        for i, j in zip(contacts["i"][bond], contacts["j"][bond]):
            if int(i) in pos and int(j) in pos:
                segs.append([pos[int(i)], pos[int(j)]])
        ax.add_collection(LineCollection(segs, colors="tab:green", linewidths=0.6 * linewidth, alpha=0.6))
    r_ref = float(np.median(r)) if len(r) else 1.0
    x, y, nx, ny, en, es = (np.asarray(contacts[c], dtype=float) for c in ("x", "y", "nx", "ny", "e_n", "e_s"))
    half = r_ref / f_ref      # one diameter = f_ref
    fx = en * nx - es * ny
    fy = en * ny + es * nx
    centre = np.stack([x, y], axis=-1)
    d = half * np.stack([fx, fy], axis=-1)
    segs = np.stack([centre - d, centre + d], axis=1)
    tension = bond & (en < 0)
    colours = np.where(tension, "tab:blue", "darkred")
    ax.add_collection(LineCollection(segs, colors=list(colours), linewidths=1.1 * linewidth))
    for w in entry["walls"]:
        ax.plot([w["from"][0], w["to"][0]], [w["from"][1], w["to"][1]], color="black", linewidth=2.5 * linewidth)
    xs = [c for w in entry["walls"] for c in (w["from"][0], w["to"][0])]
    ys = [w["from"][1] for w in entry["walls"] if w["name"] == "plate"]
    top = max(ys) if ys else float(np.max(discs["y"] + r))
    ax.set_xlim(min(xs) - 1, max(xs) + 1)
    ax.set_ylim(-1.5, top + 2)
    ax.set_aspect("equal")


def plot_networks(items, out_png, ncols=2):
    """items: list of (run_dir, snapshot index, title). One panel each. Compressed states (strain
    0) share one force scale (one disc diameter = the plate's weight shared by one row); sheared
    states share another (one diameter = a quarter of the largest force among them), so that
    panels of one kind compare directly, as the paper's Figs. 5 and 6."""
    n = len(items)
    ncols = min(ncols, n)
    nrows = int(math.ceil(n / ncols))
    loaded = [load_snapshot(run_dir, k) for run_dir, k, _ in items]
    f0 = force_scale(loaded[0][3])
    biggest = 0.0
    for entry, contacts, _, _ in loaded:
        if entry["strain"] > 1e-9 and len(contacts["e_n"]):
            biggest = max(biggest, float(np.max(np.hypot(contacts["e_n"], contacts["e_s"]))))
    f1 = biggest / 4 if biggest > 0 else f0
    fig, axes = plt.subplots(nrows, ncols, figsize=(6.2 * ncols, 3.9 * nrows), squeeze=False)
    for ax, (run_dir, k, title), (entry, contacts, discs, summary) in zip(axes.flat, items, loaded):
        f_ref = f1 if entry["strain"] > 1e-9 else f0
        draw_snapshot(ax, entry, contacts, discs, f_ref, linewidth=0.8)
        ax.set_title(f"{title}\nshear strain {100 * entry['strain']:.1f} %; one diameter = {f_ref:.3g} dyn/cm",
                     fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    fig.suptitle("Contact forces e_n n + e_s t (segments centred on the contact points); blue: bonds in tension; "
                 "green: cluster bonds", fontsize=9)
    fig.tight_layout()
    return _save(fig, out_png)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="dem.compare.figures.shear_figures", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("ratio", help="tau/sigma against strain (Fig. 7 analogue)")
    r.add_argument("--runs", nargs="+", required=True, help="ALPHA:LABEL:DIR (DIR holds shear_series.csv)")
    r.add_argument("--out", required=True)
    nw = sub.add_parser("network", help="contact-force networks of snapshots (Figs. 5, 6)")
    nw.add_argument("items", nargs="+", help="RUN_DIR:K[:TITLE]")
    nw.add_argument("--out", required=True)
    nw.add_argument("--ncols", type=int, default=2)
    a = ap.parse_args(argv)
    if a.cmd == "ratio":
        runs = []
        for item in a.runs:
            alpha, label, folder = item.split(":", 2)
            runs.append((alpha, label, read_series(os.path.join(folder, "shear_series.csv"))))
        print(plot_ratio(runs, a.out))
    else:
        items = []
        for item in a.items:
            parts = item.split(":", 2)
            items.append((parts[0], int(parts[1]), parts[2] if len(parts) > 2 else os.path.basename(parts[0])))
        print(plot_networks(items, a.out, a.ncols))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

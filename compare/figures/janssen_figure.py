"""Figure of the Janssen column ensembles: each code's ensemble-averaged side-wall pressure
against depth with the bins' 95 % error bars, its Janssen fit and the fit's 95 % confidence band.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from dem.compare.cases import janssen  # noqa: E402

COLORS = {"native": "tab:blue", "liggghts": "tab:orange", "yade": "tab:green"}


def plot_ensemble_fits(fits: dict, png: Path, title: str = "") -> Path:
    """``fits``: code -> janssen.ensemble_fit result (with its ``profile``); writes ``png``."""
    fig, ax = plt.subplots(figsize=(6.4, 6.0))
    zmax = max(max(f["profile"]["z"]) for f in fits.values())
    zz = np.linspace(0.0, zmax, 200)
    for i, (code, f) in enumerate(fits.items()):
        c = COLORS.get(code, f"C{i}")
        pr = f["profile"]
        ax.errorbar(np.array(pr["p"]) / 1e3, pr["z"], xerr=janssen.Z95 * np.array(pr["se"]) / 1e3, fmt="o",
                    ms=3, color=c, capsize=2,
                    label=f"{code}: mean of {pr['members']} members, bins {f.get('bin_width', float('nan')):g} cm "
                          f"(95 % error bars)")
        m, lo, hi = janssen.band(f, zz)
        ax.plot(m / 1e3, zz, "-", color=c,
                label=(f"{code} fit: " + (f"goodness of fit p = {f['gof']['p']:.2f}, " if "gof" in f else "")
                       + f"K = {f['K']:.2f}$\\pm${f['ci']['K']:.2f}, "
                       f"$\\lambda$ = {f['lambda']:.0f}$\\pm${f['ci']['lambda']:.0f} cm, "
                       f"$\\mu_{{w,eff}}$ = {f['mu_w_eff']:.3f}$\\pm${f['ci']['mu_w_eff']:.3f}"))
        ax.fill_betweenx(zz, lo / 1e3, hi / 1e3, color=c, alpha=0.2, lw=0)
    ax.invert_yaxis()
    ax.set_xlabel("side-wall pressure p_w [10$^3$ dyn/cm per cm of thickness]")
    ax.set_ylabel("depth z below the mean surface [cm]")
    ax.set_title(title or "Janssen column: ensemble-averaged side-wall pressure, fits and 95 % bands",
                 fontsize=9)
    ax.legend(fontsize=6, loc="upper right")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    png = Path(png)
    tmp = png.with_name(png.stem + ".tmp.png")
    fig.savefig(tmp, dpi=120)
    plt.close(fig)
    tmp.replace(png)
    return png

"""The margins of agreement: the difference between two codes that still counts as agreement.

A statistical metric agrees when the interval of its difference lies inside [-margin, margin]
(compare/cases/stats.py). Every metric kind has one default per profile; `--margin KIND=DELTA` (on the
command line or a list line) overrides it for the scenes it applies to. Relative margins are
fractions of the reference code's (the native engine's) mean; the jam fraction's is absolute.
docs/compare.md ("Margins") gives the reason for each size.
"""
from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True)
class Margin:
    quick: float
    full: float
    relative: bool
    what: str


MARGINS = {
    # The mean flow rate over the steady window and the discs out: the silo's main result.
    "flow_rate": Margin(0.10, 0.05, True, "mean flow rate over the steady window"),
    "discs_out": Margin(0.10, 0.05, True, "discs out at the end of the flow"),
    # Time-averaged wall loads (during flow; static members' wall totals at rest).
    "wall_load": Margin(0.10, 0.05, True, "time-averaged wall load (a wall group's total)"),
    # Side-wall friction totals (during flow; static members at rest): friction at rest is
    # statically indeterminate, so its member-to-member spread is several times a normal load's.
    "wall_friction": Margin(0.10, 0.05, True, "side-wall friction total (a wall's or the group's)"),
    # Each point of a cumulative time-averaged wall profile, relative to the wall's total.
    "wall_profile": Margin(0.10, 0.05, True, "cumulative wall profile, each point / the wall total"),
    # Windowed peaks: the largest 0.05 s average, a maximum over a noisy series.
    "peak": Margin(0.10, 0.10, True, "windowed peak wall load / its value at the opening"),
    # A jam is all or nothing a member: 0.2 is one member in five jamming differently.
    "jam_fraction": Margin(0.20, 0.20, False, "fraction of members that jam (absolute)"),
    # Janssen's K, lambda and mu_w,eff from the ensemble-averaged profile's fit; mu_w,eff of the
    # deep half of the profile, member by member.
    "janssen": Margin(0.10, 0.10, True, "Janssen fit parameter (K, lambda, mu_w,eff); mu_w,eff of the deep half"),
    # The shear box's sigma0, peak and band means of tau/sigma, dilation.
    "shear": Margin(0.10, 0.10, True, "shear-box ensemble mean"),
}


def parse(items) -> dict:
    """``--margin KIND=DELTA`` items -> {kind: delta}; ValueError names the item and why."""
    out = {}
    for item in items or ():
        key, sep, val = str(item).partition("=")
        key = key.strip()
        if not sep or key not in MARGINS:
            raise ValueError(f"--margin {item!r}: give KIND=DELTA with KIND one of {', '.join(MARGINS)}")
        try:
            delta = float(val)
        except ValueError:
            raise ValueError(f"--margin {item!r}: {val!r} is not a number") from None
        if not 0 < delta <= 1:
            raise ValueError(f"--margin {item!r}: a margin is a fraction in (0, 1]"
                             + (" of the reference's mean" if MARGINS[key].relative else ""))
        out[key] = delta
    return out


def margin(kind: str, profile: str, overrides: dict | None = None) -> float:
    """The margin of a metric kind in a profile (quick or full), unless overridden."""
    if overrides and kind in overrides:
        return float(overrides[kind])
    m = MARGINS[kind]
    return m.full if profile == "full" else m.quick

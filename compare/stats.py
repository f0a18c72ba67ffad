"""The statistics of the verdict: two-sample tests whose power is stated.

Every ensemble metric is judged by a two-sided Welch test of the two codes' means; the level of
each test is the family level divided by the number of statistical tests in the report
(Bonferroni), so that the report as a whole fails a true agreement with probability at most
FAMILY_ALPHA. Each metric also states the smallest difference it detects: the difference at which
the same test rejects with probability POWER (validation.md: about 2.8 combined standard errors
at 95 % / 80 % for many members; more with few members, through Student's t).

Proportions (the jam fraction) use Fisher's exact test (few members per code) and Wilson score
intervals. Heavy-tailed quantities (peak ratios) are summarised by the ensemble median of each
member's windowed maximum with a percentile-bootstrap interval.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats as sps

FAMILY_ALPHA = 0.05   # probability that a report of true agreement shows any statistical failure
POWER = 0.80          # power at which the detectable difference is stated


def mean_se(values) -> tuple[float, float, int]:
    """Mean, standard error and count of the finite values."""
    v = np.array([x for x in values if x is not None and math.isfinite(x)], float)
    if len(v) == 0:
        return float("nan"), float("nan"), 0
    se = float(np.std(v, ddof=1) / math.sqrt(len(v))) if len(v) > 1 else float("nan")
    return float(np.mean(v)), se, len(v)


def welch_df(se_a: float, n_a: int, se_b: float, n_b: int) -> float:
    """Welch-Satterthwaite degrees of freedom of the difference of two means."""
    va, vb = se_a ** 2, se_b ** 2
    den = (va ** 2 / (n_a - 1) if n_a > 1 else 0.0) + (vb ** 2 / (n_b - 1) if n_b > 1 else 0.0)
    if den <= 0:
        return float(max(n_a + n_b - 2, 1))
    return max((va + vb) ** 2 / den, 1.0)


def detectable(se_comb: float, df: float, alpha: float, power: float = POWER) -> float:
    """Smallest true difference that a two-sided t test at level alpha rejects with the given power
    (normal-shift approximation with Student's quantiles: (t_{1-alpha/2} + t_{power}) x s.e.)."""
    return float((sps.t.ppf(1 - alpha / 2, df) + sps.t.ppf(power, df)) * se_comb)


def compare_means(a: tuple, b: tuple, alpha: float) -> dict:
    """Welch test of two ensemble means. a, b: (mean, se, n). Returns the difference, the combined
    standard error, df, the p value, the critical difference (|diff| above it fails), the smallest
    detectable difference, both also relative to |mean of a|, and pass."""
    (ma, sa, na), (mb, sb, nb) = a, b
    if na < 2 or nb < 2 or not (math.isfinite(sa) and math.isfinite(sb)):
        return {"diff": mb - ma, "pass": False, "reason": f"needs at least 2 members in each code (have {na}, {nb})"}
    comb = math.hypot(sa, sb)
    df = welch_df(sa, na, sb, nb)
    diff = mb - ma
    if comb == 0:
        p = 1.0 if diff == 0 else 0.0
        crit = 0.0
    else:
        p = float(2 * sps.t.sf(abs(diff) / comb, df))
        crit = float(sps.t.ppf(1 - alpha / 2, df) * comb)
    mde = detectable(comb, df, alpha)
    scale = abs(ma) if ma else float("nan")
    return {"diff": diff, "se_comb": comb, "df": df, "p": p, "alpha": alpha, "critical": crit,
            "detectable": mde, "detectable_rel": mde / scale, "diff_rel": diff / scale,
            "pass": bool(p >= alpha)}


def wilson(k: int, n: int, conf: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of a proportion k / n."""
    if n == 0:
        return float("nan"), float("nan")
    z = sps.norm.ppf(1 - (1 - conf) / 2)
    p = k / n
    den = 1 + z * z / n
    mid = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return max(0.0, mid - half), min(1.0, mid + half)


def compare_proportions(ka: int, na: int, kb: int, nb: int, alpha: float) -> dict:
    """Fisher's exact two-sided test of two proportions, with Wilson intervals and the smallest
    difference from p_a that the test detects with POWER (exact, over the binomial outcomes)."""
    if na == 0 or nb == 0:
        return {"pass": False, "reason": "no members"}
    p = float(sps.fisher_exact([[ka, na - ka], [kb, nb - kb]])[1])
    pa = ka / na
    mde = float("nan")
    for d in np.linspace(0.01, 1.0, 100):      # smallest |p_b - p_a| with power >= POWER
        pw = 0.0
        for q in (pa + d, pa - d):
            if not 0 <= q <= 1:
                continue
            pmf = sps.binom.pmf(np.arange(nb + 1), nb, q)
            rej = [sps.fisher_exact([[ka, na - ka], [j, nb - j]])[1] < alpha for j in range(nb + 1)]
            pw = max(pw, float(np.sum(pmf[rej])))
        if pw >= POWER:
            mde = float(d)
            break
    return {"a": pa, "b": kb / nb, "ci_a": wilson(ka, na), "ci_b": wilson(kb, nb), "p": p, "alpha": alpha,
            "detectable": mde, "pass": bool(p >= alpha)}


def bootstrap_median(values, conf: float = 0.95, n_boot: int = 4000, seed: int = 0) -> tuple[float, float, float]:
    """Median and its percentile-bootstrap interval (seeded: the same data give the same interval)."""
    v = np.array([x for x in values if x is not None and math.isfinite(x)], float)
    if len(v) == 0:
        return float("nan"), float("nan"), float("nan")
    rng = np.random.default_rng(seed)
    meds = np.median(rng.choice(v, size=(n_boot, len(v)), replace=True), axis=1)
    lo, hi = np.quantile(meds, [(1 - conf) / 2, 1 - (1 - conf) / 2])
    return float(np.median(v)), float(lo), float(hi)


def members_for(rel_diff: float, cv: float, alpha: float, power: float = POWER) -> int:
    """Members per code for a two-sample test of equal size to detect a relative difference
    ``rel_diff`` when one member's coefficient of variation is ``cv``."""
    for n in range(2, 10_000):
        se = cv * math.sqrt(2.0 / n)
        if detectable(se, 2 * n - 2, alpha, power) <= rel_diff:
            return n
    return 10_000
